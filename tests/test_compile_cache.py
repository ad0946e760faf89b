"""The compiled code's disk cache, keyed by content: what an edit invalidates, what a reinstall reuses, and the
notice a compile gives."""

from __future__ import annotations

import io
import os
import shutil
import stat
import subprocess
import sys
import textwrap
from pathlib import Path

import numba
import pytest

from framework.compiled import cache as compile_cache

ROOT = Path(__file__).resolve().parents[1]


def _package(folder: Path, sources: dict[str, str]) -> Path:
    package = folder / "pkg"
    package.mkdir(parents=True)
    (package / "__init__.py").write_text("")
    for name, text in sources.items():
        (package / f"{name}.py").write_text(textwrap.dedent(text))
    return package


def test_an_edit_changes_the_key_of_the_modules_that_import_the_edited_one_only(tmp_path, monkeypatch):
    """A module's key covers its own source and those of the modules it imports, transitively (absolute and
    relative, in functions too), numba's version and its code-generation settings; not the modules it does not
    import."""
    package = _package(tmp_path, {"a": "from .b import f\n", "b": "def f():\n    from . import c\n",
                                  "c": "X = 1\n", "d": "import pkg.c\n", "e": "Y = 2\n"})

    def keys():
        compile_cache._modules.cache_clear()
        compile_cache.sources_hash.cache_clear()
        return {m: compile_cache.sources_hash(f"pkg.{m}", package) for m in "abcde"}

    before = keys()
    assert len(set(before.values())) == 5
    (package / "c.py").write_text("X = 2\n")
    after = keys()
    assert {m for m in "abcde" if after[m] != before[m]} == {"a", "b", "c", "d"}  # e does not import c
    monkeypatch.setattr(compile_cache.numba_config, "OPT", 0)
    assert all(v != after[m] for m, v in keys().items())  # NUMBA_OPT changes the machine code: every key
    monkeypatch.undo()
    compile_cache._modules.cache_clear()
    compile_cache.sources_hash.cache_clear()


_PROBE = """
import sys
sys.path.insert(0, sys.argv[1])
import numpy as np
from framework.engine import draws
from framework.compiled.cache import is_cached
cached = is_cached(draws.draws)
draws.draws(draws.stream(1), np.zeros(2), np.ones(2), 3)
print(cached, draws.draws.stats.cache_hits and 1 or 0, draws.__file__)
"""


def _probe(root: Path, cache: Path) -> tuple[bool, str]:
    environment = {**os.environ, "METAIK_CACHE_DIR": str(cache), "METAIK_COMPILE_NOTICE": "0"}
    out = subprocess.run([sys.executable, "-c", _PROBE, str(root)], check=True, capture_output=True, text=True,
                         env=environment, cwd=root).stdout.split()
    return out[0] == "True", out[2]


def test_the_same_sources_installed_elsewhere_or_read_only_load_the_cached_code(tmp_path):
    """Compiled in one copy of the package, loaded (not compiled) by another copy of the same sources — another
    venv, a reinstall — and by a read-only one; compiled again after an edit of its module, not after an edit of
    a module it does not import."""
    cache = tmp_path / "cache"
    copies = []
    for name in ("first", "second"):
        shutil.copytree(ROOT / "framework", tmp_path / name / "framework",
                        ignore=shutil.ignore_patterns("__pycache__"))
        copies.append(tmp_path / name)
    cached, where = _probe(copies[0], cache)
    assert not cached and where.startswith(str(copies[0]))
    for path in (copies[1] / "framework").rglob("*"):  # the second copy read-only
        path.chmod(path.stat().st_mode & ~(stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH))
    try:
        cached, where = _probe(copies[1], cache)
        assert cached and where.startswith(str(copies[1]))
    finally:
        for path in (copies[1] / "framework").rglob("*"):
            path.chmod(path.stat().st_mode | stat.S_IWUSR)
    (copies[1] / "framework" / "cli" / "replay.py").write_text("# edited\n", encoding="utf-8")  # not imported
    assert _probe(copies[1], cache)[0]
    draws = copies[1] / "framework" / "engine" / "draws.py"
    draws.write_text(draws.read_text(encoding="utf-8") + "\n# edited\n", encoding="utf-8")
    assert not _probe(copies[1], cache)[0]


def test_a_compile_of_the_package_says_so_while_it_waits_and_a_compiled_call_does_not(monkeypatch):
    """numba's compile events of the package's functions: one line per outermost compile that lasts (here: any),
    begun while the compile runs and ended with its time; nothing for a call that is compiled already, nor for
    code outside the package."""
    stream = io.StringIO()
    monkeypatch.setattr(compile_cache.NOTICE, "stream", stream)
    monkeypatch.setattr(compile_cache.NOTICE, "after", 0.0)
    monkeypatch.delenv("METAIK_COMPILE_NOTICE", raising=False)

    def add_one(x):
        return x + 1.0

    def twice(x):
        return inner(inner(x))

    add_one.__module__ = twice.__module__ = "framework.probe"
    inner = numba.njit(add_one)
    outer = numba.njit(twice)
    seconds = compile_cache.NOTICE.seconds
    assert outer(1.0) == 3.0
    lines = stream.getvalue().splitlines()
    assert len(lines) == 1 and lines[0].startswith("metaik: compiling probe.") and lines[0].endswith(" s")
    assert "twice" in lines[0]  # the outermost compile (its callee's compile is inside it)
    assert compile_cache.NOTICE.seconds > seconds
    outer(2.0)
    numba.njit(lambda x: x * 2.0)(1.0)  # not the package's
    assert len(stream.getvalue().splitlines()) == 1


def test_the_notice_can_be_quiet(monkeypatch):
    stream = io.StringIO()
    monkeypatch.setattr(compile_cache.NOTICE, "stream", stream)
    monkeypatch.setattr(compile_cache.NOTICE, "after", 0.0)
    monkeypatch.setenv("METAIK_COMPILE_NOTICE", "0")

    def add_two(x):
        return x + 2.0

    add_two.__module__ = "framework.probe"
    assert numba.njit(add_two)(1.0) == 3.0
    assert stream.getvalue() == ""


def test_many_small_compiles_are_announced_once_they_add_up():
    """Compiles quicker than the notice's delay say nothing, until their silent time adds up to it: the next one
    then says so as it begins (a first solve made of many small compiles is not a silent wait)."""
    import io
    import time

    from framework.compiled.cache import CompileNotice

    out = io.StringIO()
    notice = CompileNotice(stream=out, after=0.3)
    for k in range(3):
        notice.start(f"probe.f{k}")
        time.sleep(0.16)
        notice.end()
    said = out.getvalue()
    assert "probe.f0" not in said  # 0.16 s: below the delay
    assert said.startswith("metaik: compiling probe.f1") and said.rstrip().endswith(" s")  # 0.32 s in all
    assert "probe.f2" not in said  # counting starts again after a notice
    assert notice.seconds == pytest.approx(0.48, abs=0.1)
