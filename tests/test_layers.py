"""docs/architecture.md is the map: each folder of the package is one layer, listed bottom to top; every import of
the package — absolute or relative, inside functions or for type checkers only — goes to the module's own layer or
one below it, and no chain of imports comes back to where it started."""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "framework"


def layers() -> tuple[list[str], dict[str, int]]:
    """The layers' folders bottom to top, and each module of the package's root named there -> layer 0."""
    text = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    table = text[text.index("## Layers"):text.index("## Modules over")]
    rows = [line.split("|") for line in table.splitlines() if line.startswith("| ") and not line.startswith("| layer")]
    folders = [row[1].strip().strip("`") for row in rows]
    root = {path: 0 for path in re.findall(r"`([\w]+\.py)`", rows[0][2])}
    return folders, root


FOLDERS, ROOT_MODULES = layers()


def layer_of(path: str) -> int | None:
    """The layer of a module path relative to the package: its folder's row; a module of the root its own."""
    if "/" not in path:
        return ROOT_MODULES.get(path)
    folder = path.split("/")[0] + "/"
    return FOLDERS.index(folder) if folder in FOLDERS else None


def modules() -> list[str]:
    return [p.relative_to(PACKAGE).as_posix() for p in sorted(PACKAGE.rglob("*.py"))
            if p.relative_to(PACKAGE).as_posix() not in ("__init__.py", "__main__.py")]


def _module_file(dotted: Path) -> list[Path]:
    return [c for c in (dotted.with_suffix(".py"), dotted / "__init__.py") if c.is_file()]


def imports(path: str, text: str | None = None) -> set[str]:
    """Every package module ``path`` imports (absolute and relative, at any depth of the code, those under
    ``if TYPE_CHECKING:`` included), as paths relative to the package; a package's ``__init__.py`` when a name is
    taken from it. ``text``: the module's source in place of the file's."""
    source = PACKAGE / path
    tree = ast.parse(text if text is not None else source.read_text(encoding="utf-8"))
    found = set()
    for node in ast.walk(tree):
        targets: list[Path] = []
        if isinstance(node, ast.Import):
            targets = [c for a in node.names if a.name.split(".")[0] == "framework"
                       for c in _module_file(ROOT / a.name.replace(".", "/"))]
        elif isinstance(node, ast.ImportFrom):
            if node.level == 0:
                if (node.module or "").split(".")[0] != "framework":
                    continue
                base = ROOT / node.module.replace(".", "/")
            else:
                base = source.parent
                for _ in range(node.level - 1):
                    base = base.parent
                base = base / (node.module or "").replace(".", "/")
            for a in node.names:  # ``from . import blocks``: the module itself; else the names' module
                submodule = _module_file(base / a.name)
                targets += submodule or _module_file(base)
        found |= {t.relative_to(PACKAGE).as_posix() for t in targets}
    found.discard(path)
    return found


def test_the_map_has_every_module():
    """Every folder of the package is a layer, and the root holds only the modules the map names (and the
    package's ``__init__``)."""
    assert len(FOLDERS) >= 10 and FOLDERS[0] == "framework/"
    assert [m for m in modules() if layer_of(m) is None] == []


def test_no_module_imports_a_higher_layer():
    wrong = []
    for module in modules():
        mine = layer_of(module)
        for other in imports(module):
            theirs = layer_of(other) if other != "__init__.py" else len(FOLDERS)
            if theirs > mine:
                wrong.append(f"{module} ({FOLDERS[mine]}) imports {other} ({FOLDERS[min(theirs, len(FOLDERS) - 1)]})")
    assert wrong == []


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_no_import_cycle():
    graph = {m: imports(m) for m in [*modules(), "__init__.py"]}
    assert _cycles(graph) == []


def test_the_checks_see_what_they_must(tmp_path):
    """The checks are real: a lazy import, an absolute one and one for type checkers are found, and a cycle is."""
    lazy = imports("solvers/batch.py")
    assert "solvers/cluster.py" in lazy  # imported inside solve_batch (the Dask path)
    assert "geometry/hulls.py" in imports("costs/program.py")  # under ``if TYPE_CHECKING:``
    written = "def f():\n    import framework.model.robot\n    from framework.geometry import scene\n" \
              "    from framework.costs.base import Term\n    from ..solvers import ik_solver\n"
    assert imports("costs/x.py", written) == {"model/robot.py", "geometry/scene.py", "costs/base.py",
                                                "solvers/__init__.py"}
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert layer_of("cli/run.py") > layer_of("solvers/solve.py") > layer_of("model/robot.py") > layer_of("errors.py")


def test_the_root_holds_only_what_every_layer_uses():
    """The package's root: its ``__init__`` and the few modules the map names there."""
    assert sorted(p.name for p in PACKAGE.glob("*.py")) == sorted(["__init__.py", *ROOT_MODULES])
    assert len(ROOT_MODULES) <= 5


def _functions(tree: ast.AST):
    return [n for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))]


def test_modules_do_one_job():
    """No module over 500 lines; no function over 100 lines outside ``engine/`` (whose compiled functions are held
    to the same length below). A module over 400 lines is named, with its reason, under "Modules over 400 lines"
    on the map; one named there that is short again (350) is dropped from it."""
    text = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    section = text[text.index("## Modules over"):text.index("## A solve")]
    named = set(re.findall(r"`([\w/]+\.py)`", section))
    sources = {m: (PACKAGE / m).read_text(encoding="utf-8") for m in modules()}
    lengths = {m: len(source.splitlines()) for m, source in sources.items()}
    assert [f"{m} ({n} lines)" for m, n in lengths.items() if n > 500] == []
    assert [m for m, n in lengths.items() if n > 400 and m not in named] == []
    assert [m for m in named if lengths.get(m, 0) <= 350] == []
    long = [f"{m}:{f.name} ({f.end_lineno - f.lineno + 1} lines)" for m, source in sources.items()
            if not m.startswith("engine/") for f in _functions(ast.parse(source)) if f.end_lineno - f.lineno + 1 > 100]
    assert long == []


def _compiled_functions():
    """``(module, function node)`` of every compiled function of the package: decorated with ``compiled`` or
    ``internal`` (:mod:`framework.compiled.native`), or a block kind's kernel (a function of one workspace record ``ws``)."""
    for path in modules():
        tree = ast.parse((PACKAGE / path).read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if not isinstance(node, ast.FunctionDef):
                continue
            decorators = [ast.unparse(d).split("(")[0] for d in node.decorator_list]
            kernel = [a.arg for a in node.args.args] == ["ws"]
            if kernel or any(d in ("compiled", "internal") for d in decorators):
                yield path, node


def test_compiled_functions_are_short_and_take_few_parameters():
    """The engine and the kernels read in one sitting: no compiled function over 100 lines (its docstring
    included) or 12 parameters (grouped data travels as named tuples or records)."""
    found = list(_compiled_functions())
    assert len(found) > 150  # the scan finds them (the engine, the kernels, the kinematics, ...)
    long = [f"{path}:{node.name} ({node.end_lineno - node.lineno + 1} lines)" for path, node in found
            if node.end_lineno - node.lineno + 1 > 100]
    wide = [f"{path}:{node.name} ({len(node.args.args)} parameters)" for path, node in found
            if len(node.args.args) + len(node.args.kwonlyargs) > 12]
    assert long == [] and wide == []
