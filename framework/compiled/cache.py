"""numba's on-disk cache of the package's compiled code, keyed by content, in the user's cache folder.

numba keys a cached function on its own source file's time stamp and keeps it beside the file: every reinstall,
every fresh clone and a read-only install compiled everything again, and an edit to a callee left its callers'
cached machine code running the old definition (numba links a callee's code into each caller). Here each module's
compiled code lives in a folder named after the module and a hash of its *sources*: the module's own and every
module of the package it imports, transitively (its callees' code is in there). An edit recompiles the modules
that import the edited one, nothing else; the same sources installed anywhere — another venv, a wheel, a
read-only site-packages — find the same folder. The hash also covers numba's version and the code-generation
settings numba's own index ignores (``NUMBA_OPT``, ``NUMBA_BOUNDSCHECK``, ...: a run under
``NUMBA_ENABLE_PROFILING=1`` once cached code 1.9x slower that later runs loaded); numba keys each entry by the
CPU and the Python version itself.

The folder is ``platformdirs.user_cache_dir("metaik")`` (``~/.cache/metaik`` on Linux), or ``$METAIK_CACHE_DIR``.
Where it cannot be written, numba's own places are used (beside the package, or its user-wide folder).
"""

from __future__ import annotations

import hashlib
import os
import re
import sys
import threading
import time
from functools import cache
from pathlib import Path

import numba
from numba.core import caching
from numba.core import config as numba_config
from numba.core import event as numba_event

from ..interrupts import held_interrupt

PACKAGE = Path(__file__).resolve().parents[1]
#: numba's settings that change the machine code it caches (``numba.core.config`` attributes).
CODEGEN_SETTINGS = ("OPT", "BOUNDSCHECK", "DEBUGINFO_DEFAULT", "ENABLE_PROFILING", "FASTMATH", "CPU_NAME",
                    "CPU_FEATURES")
#: The environment variable naming the cache folder.
ENVIRONMENT = "METAIK_CACHE_DIR"

_FROM = re.compile(r"^\s*from\s+(\.*)([\w.]*)\s+import\s+(.*)$")
_PLAIN = re.compile(r"^\s*import\s+([\w.]+)")


def cache_root() -> Path:
    """The folder of the package's compiled code: ``$METAIK_CACHE_DIR``, else the user's cache folder."""
    given = os.environ.get(ENVIRONMENT)
    if given:
        return Path(given).expanduser().resolve()
    import platformdirs

    return Path(platformdirs.user_cache_dir("metaik"))


def _module_name(path: Path, package: Path) -> str:
    parts = list(path.relative_to(package.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _imports(text: str, here: list[str], package: str) -> list[tuple[str, list[str]]]:
    """``(module, names)`` of every import statement of the package in a module's ``text`` (``here``: the package
    it is in, as parts), those inside functions too; not those for type checkers only (``if TYPE_CHECKING:``)."""
    found = []
    lines = text.splitlines()
    typing_only = None  # the indentation of an ``if TYPE_CHECKING:`` block being skipped
    for k, line in enumerate(lines):
        indent = len(line) - len(line.lstrip())
        if typing_only is not None:
            if not line.strip() or indent > typing_only:
                continue
            typing_only = None
        if line.lstrip().startswith("if TYPE_CHECKING"):
            typing_only = indent
            continue
        match = _FROM.match(line)
        if match:
            dots, target, rest = match.groups()
            while "(" in rest and ")" not in rest and k + 1 < len(lines):  # a parenthesized list goes on
                k += 1
                rest += " " + lines[k]
            if dots:
                parts = here[: len(here) - len(dots) + 1] + ([target] if target else [])
                base = ".".join(parts)
            elif target == package or target.startswith(package + "."):
                base = target
            else:
                continue
            names = [n.split(" as ")[0].strip() for n in re.split(r"[,()]", rest.split("#")[0])]
            found.append((base, [n for n in names if n]))
            continue
        match = _PLAIN.match(line)
        if match and (match.group(1) == package or match.group(1).startswith(package + ".")):
            found.append((match.group(1), []))
    return found


@cache
def _modules(package: Path = PACKAGE) -> dict[str, tuple[str, frozenset[str]]]:
    """Every module of the package: name -> (SHA-256 of its source, the package's modules it imports)."""
    files = {_module_name(p, package): p for p in package.rglob("*.py")}
    modules = {}
    for name, path in files.items():
        text = path.read_bytes()
        here = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
        imported = set()
        for base, names in _imports(text.decode(), here, package.name):
            submodules = [f"{base}.{item}" for item in names if f"{base}.{item}" in files]
            imported.update(submodules)  # ``from . import x``: the submodule x (not the package's __init__)
            if not names or len(submodules) < len(names):  # a name defined by the module (or package) itself
                imported.add(base)
        modules[name] = (hashlib.sha256(text).hexdigest(), frozenset(m for m in imported if m in files))
    return modules


@cache
def sources_hash(module: str, package: Path = PACKAGE) -> str:
    """SHA-256 over the sources of ``module`` and of every module of the package it imports, transitively, and
    over numba's version and code-generation settings (:data:`CODEGEN_SETTINGS`)."""
    modules = _modules(package)
    closure, todo = set(), [module]
    while todo:
        name = todo.pop()
        if name in closure or name not in modules:
            continue
        closure.add(name)
        todo.extend(modules[name][1])
    digest = hashlib.sha256()
    for name in sorted(closure):
        digest.update(f"{name}:{modules[name][0]}\n".encode())
    digest.update(f"numba {numba.__version__} {sys.implementation.cache_tag}\n".encode())
    for setting in CODEGEN_SETTINGS:
        digest.update(f"{setting}={getattr(numba_config, setting, None)!r}\n".encode())
    return digest.hexdigest()


def module_folder(module: str) -> Path:
    """Where the compiled code of ``module`` (a dotted name in the package) is cached for its current sources."""
    return cache_root() / f"numba-{numba.__version__}" / f"{module}-{sources_hash(module)[:16]}"


class ContentLocator(caching._CacheLocator):
    """numba's cache locator for the package's functions: :func:`module_folder`, stamped with :func:`sources_hash`."""

    def __init__(self, py_func, module: str):
        self._lineno = py_func.__code__.co_firstlineno
        self._module = module
        self._path = module_folder(module)

    def get_cache_path(self) -> str:
        return str(self._path)

    def get_source_stamp(self) -> str:
        return sources_hash(self._module)

    def get_disambiguator(self) -> str:
        return str(self._lineno)

    @classmethod
    def from_function(cls, py_func, py_file):
        try:
            path = Path(py_file).resolve()
            path.relative_to(PACKAGE)
        except (ValueError, OSError):
            return None
        self = cls(py_func, _module_name(path, PACKAGE))
        try:
            self.ensure_cache_path()
        except OSError:  # not writable: numba's own locators
            return None
        return self


class _ContentImpl(caching.CompileResultCacheImpl):
    _locator_classes = [ContentLocator, *caching.CompileResultCacheImpl._locator_classes]


class ContentCache(caching.FunctionCache):
    """numba's function cache with :class:`ContentLocator` first."""

    _impl_class = _ContentImpl


class _LinkedImpl(_ContentImpl):
    """The cache of a linked-only function (:mod:`framework.compiled.linked`): its library is bitcode, read back without
    machine code (numba's own ``CompileResult._rebuild``, with :func:`framework.compiled.linked.unserialize`)."""

    def rebuild(self, target_context, payload):
        from numba.core.compiler import CompileResult

        from . import linked

        libdata, fndesc, env, signature, objectmode, lifted, typeann, reload_init, referenced_envs = payload
        library = linked.unserialize(target_context.codegen(), libdata)
        return CompileResult(target_context=target_context, typing_context=target_context.typing_context,
                             library=library, environment=env,
                             entry_point=target_context.get_executable(library, fndesc, env), fndesc=fndesc,
                             type_annotation=typeann, signature=signature, objectmode=objectmode, lifted=lifted,
                             typing_error=None, call_helper=None, metadata=None, reload_init=reload_init,
                             referenced_envs=referenced_envs)


class LinkedCache(ContentCache):
    """:class:`ContentCache` for linked-only functions."""

    _impl_class = _LinkedImpl


def cached(dispatcher, *, linked_only: bool = False):
    """``dispatcher`` (a numba function or C callback made without ``cache=True``) cached by :class:`ContentCache`
    (``linked_only``: a function of :data:`framework.compiled.linked.PIPELINE`, by :class:`LinkedCache`)."""
    function = getattr(dispatcher, "py_func", None) or dispatcher._pyfunc
    dispatcher._cache = (LinkedCache if linked_only else ContentCache)(function)
    return dispatcher


def is_cached(dispatcher) -> bool:
    """Whether ``dispatcher`` has compiled code in the cache for its current sources (any signature)."""
    cache_ = getattr(dispatcher, "_cache", None)
    if not isinstance(cache_, ContentCache):
        return False
    index = Path(cache_.cache_path) / f"{cache_._impl.filename_base}.nbi"
    return index.is_file() and bool(cache_._cache_file._load_index())


def has_signature(dispatcher, signature: tuple) -> bool:
    """Whether ``dispatcher`` has compiled code for the argument types ``signature`` in the cache (for its current
    sources and this machine)."""
    cache_ = getattr(dispatcher, "_cache", None)
    if not isinstance(cache_, ContentCache):
        return False
    key = cache_._index_key(signature, dispatcher.targetctx.codegen())
    return key in cache_._cache_file._load_index()


class CompileNotice:
    """Says on stderr when the package's code compiles — a first use after an install or an edit: the process
    waits seconds then — and how long it took; :attr:`seconds` sums those waits.

    A compile the package starts (one of its functions, with the others it calls) that is still running after
    :attr:`after` seconds is one line: ``metaik: compiling engine.reach.reach for this machine (first use, cached
    afterwards) ... 12.3 s``; quicker ones (a kernel loaded from the cache, a small function) say nothing, until
    the silent ones add up to :attr:`after` seconds: the next compile then says so as it begins (a wait made of
    many small compiles is announced too). Quiet with ``METAIK_COMPILE_NOTICE=0``.
    """

    def __init__(self, stream=None, after: float = 1.0):
        self.stream = stream
        self.after = after
        self.seconds = 0.0
        self._depth = 0
        self._start = 0.0
        self._timer: threading.Timer | None = None
        self._said = False
        self._quiet = 0.0  # seconds of compiles that said nothing since the last that did
        self._held = None
        self.interrupt = None

    def start(self, name: str, where: str = "") -> None:
        """A compile of ``name`` begins (nested compiles are part of the outermost one); ``where``: where it runs,
        if not in this process."""
        self._depth += 1
        if self._depth == 1:
            self._held = held_interrupt()  # a Ctrl-C stops the compile at its next function (numba's events)
            self.interrupt = self._held.__enter__()
            self._start = time.perf_counter()
            self._said = False
            if os.environ.get("METAIK_COMPILE_NOTICE", "1") != "0":
                self._timer = threading.Timer(max(0.0, self.after - self._quiet), self._say, (name, where))
                self._timer.daemon = True
                self._timer.start()

    def end(self) -> None:
        """The compile begun last ends."""
        self._depth -= 1
        if self._depth == 0:
            held, self._held, self.interrupt = self._held, None, None
            elapsed = time.perf_counter() - self._start
            self.seconds += elapsed
            if self._timer is not None:
                self._timer.cancel()
                self._timer.join()
                self._timer = None
            if self._said:
                self._write(f"{elapsed:.1f} s\n")
                self._quiet = 0.0
            else:
                self._quiet += elapsed
            held.__exit__(None, None, None)  # raises KeyboardInterrupt if one was held

    def _say(self, name: str, where: str) -> None:
        self._said = True
        self._write(f"metaik: compiling {name} for this machine (first use, cached afterwards"
                    f"{'; ' + where if where else ''}) ... ")

    def _write(self, text: str) -> None:
        stream = self.stream or sys.stderr
        stream.write(text)
        stream.flush()


class _Listener(numba_event.Listener):
    """numba's compile events of the package's functions, to :data:`NOTICE`."""

    def on_start(self, event) -> None:
        name = package_name(event.data.get("dispatcher"))
        if name:
            NOTICE.start(name)

    def on_end(self, event) -> None:
        if package_name(event.data.get("dispatcher")):
            NOTICE.end()
            _stop_if_asked()


def _stop_if_asked() -> None:
    """A safe point of a compile (a function's compile ended): a Ctrl-C held since stops it here."""
    if NOTICE.interrupt is not None and NOTICE.interrupt.requested:
        raise KeyboardInterrupt


def package_name(dispatcher) -> str | None:
    """``module.function`` of a dispatcher of the package (without the package's name), else ``None``."""
    function = getattr(dispatcher, "py_func", None)
    module = getattr(function, "__module__", "") or ""
    if not module.startswith(PACKAGE.name + "."):
        return None
    return f"{module[len(PACKAGE.name) + 1:]}.{function.__qualname__}"


#: The process's compile notice.
NOTICE = CompileNotice()
numba_event.register("numba:compile", _Listener())
