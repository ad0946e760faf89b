"""Xacro files as data: expanded without running code, with ROS packages found without ROS.

xacro evaluates ``${...}`` with Python's ``eval`` (a few names hidden), and ``$(eval ...)``, ``$(env ...)`` and
``xacro.load_yaml`` reach the interpreter, the environment and any file. A robot file travels like a document,
so :func:`expand_xacro` evaluates it with our own evaluator instead: an expression may only use numbers, strings,
lists, dicts, arithmetic, comparisons, conditionals, the properties and arguments of the file, ``math``'s
functions and a few pure builtins (``min``, ``max``, ``abs``, ``round``, ``len``, ...); no attribute of any other
object, no name or attribute starting with ``_``. ``$(env)``, ``$(optenv)``, ``$(eval)`` and
``xacro.load_yaml`` need ``trusted=True``. ``$(find pkg)`` resolves in ``package_dirs`` (a package is a folder
named like it, or holding a ``package.xml`` naming it), then ``ROS_PACKAGE_PATH`` / ``AMENT_PREFIX_PATH`` when set.
An argument given that the files do not declare (``<xacro:arg name=...>``) is an error.
"""

from __future__ import annotations

import ast
import math
import os
import re
import threading
from collections.abc import Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from ..errors import RobotFileError

#: Builtins an expression may call (pure functions of their arguments).
SAFE_BUILTINS = {name: getattr(__builtins__, name, None) if not isinstance(__builtins__, dict)
                 else __builtins__[name] for name in (
                     "abs", "all", "any", "bool", "dict", "divmod", "enumerate", "float", "int", "len", "list",
                     "map", "max", "min", "range", "reversed", "round", "sorted", "str", "sum", "tuple", "zip")}
SAFE_MATH = {k: v for k, v in math.__dict__.items() if not k.startswith("_")}
_NODES = (ast.Expression, ast.Constant, ast.Name, ast.Load, ast.BinOp, ast.UnaryOp, ast.BoolOp, ast.Compare,
          ast.IfExp, ast.Call, ast.Attribute, ast.Subscript, ast.Slice, ast.List, ast.Tuple, ast.Dict,
          ast.operator, ast.unaryop, ast.boolop, ast.cmpop, ast.keyword)
_NAMESPACES = {"math", "python", "xacro"}
_TRUSTED_ONLY = {"load_yaml", "abs_filename", "dotify"}
_LOCK = threading.Lock()  # xacro keeps its state in module globals: one expansion at a time


class XacroEvaluator:
    """Evaluates one ``${...}`` expression against xacro's symbol table, refusing anything but data."""

    def __init__(self, trusted: bool):
        self.trusted = trusted

    def check(self, tree: ast.AST, expression: str) -> None:
        for node in ast.walk(tree):
            if not isinstance(node, _NODES):
                raise RobotFileError(f"xacro expression {expression!r}: {type(node).__name__} is not allowed "
                                     "in a robot file")
            name = node.id if isinstance(node, ast.Name) else node.attr if isinstance(node, ast.Attribute) else None
            if name is not None and name.startswith("_"):
                raise RobotFileError(f"xacro expression {expression!r}: names starting with '_' are not allowed")
            if isinstance(node, ast.Attribute):
                if not (isinstance(node.value, ast.Name) and node.value.id in _NAMESPACES):
                    raise RobotFileError(f"xacro expression {expression!r}: attribute access is allowed on math, "
                                         "python and xacro only")
                if node.value.id == "python" and node.attr not in SAFE_BUILTINS:
                    raise RobotFileError(f"xacro expression {expression!r}: python.{node.attr} is not allowed")
                if node.value.id == "xacro" and node.attr in _TRUSTED_ONLY and not self.trusted:
                    raise RobotFileError(f"xacro expression {expression!r}: xacro.{node.attr} reads files; load "
                                         "the robot with trusted=True to allow it")
            if isinstance(node, ast.Name) and node.id in _TRUSTED_ONLY and not self.trusted:
                raise RobotFileError(f"xacro expression {expression!r}: {node.id} reads files; load the robot "
                                     "with trusted=True to allow it")

    def __call__(self, expression: str, symbols: Any, locals_: Any = None) -> Any:
        text = expression.strip()
        try:
            tree = ast.parse(text, mode="eval")
        except SyntaxError as err:
            raise RobotFileError(f"xacro expression {text!r} is not valid: {err.msg}") from None
        self.check(tree, text)
        names = _Names(symbols)
        return eval(compile(tree, "<xacro expression>", "eval"), {"__builtins__": {}}, names)  # noqa: S307


class _Names(dict):
    """Name lookup of an expression: xacro's symbols (properties, arguments), then math and the safe builtins."""

    def __init__(self, symbols: Any):
        super().__init__()
        self.symbols = symbols

    def __missing__(self, key: str) -> Any:
        if key == "python":
            return _Namespace(SAFE_BUILTINS)
        if key == "math":
            return _Namespace(SAFE_MATH)
        try:
            return self.symbols[key]
        except KeyError:
            pass
        if key in SAFE_MATH:
            return SAFE_MATH[key]
        if key in SAFE_BUILTINS:
            return SAFE_BUILTINS[key]
        raise NameError(f"name {key!r} is not defined")


class _Namespace:
    def __init__(self, members: Mapping[str, Any]):
        self.__dict__.update(members)


def find_package(name: str, package_dirs: Sequence[str | Path]) -> Path:
    """The folder of ROS package ``name``: in ``package_dirs`` (each a package itself, or holding packages, to any
    depth), then the folders of ``ROS_PACKAGE_PATH`` and ``AMENT_PREFIX_PATH/share``."""
    roots = [Path(p) for p in package_dirs]
    roots += [Path(p) for p in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep) if p]
    roots += [Path(p) / "share" for p in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p]
    for root in roots:
        if not root.is_dir():
            continue
        if _is_package(root, name):
            return root
        for manifest in sorted(root.rglob("package.xml")):
            if _is_package(manifest.parent, name):
                return manifest.parent
        candidate = root / name
        if candidate.is_dir():
            return candidate
    searched = ", ".join(str(r) for r in roots) or "nothing (give package_dirs=[...])"
    raise RobotFileError(f"ROS package {name!r} not found; searched {searched}")


def _is_package(folder: Path, name: str) -> bool:
    manifest = folder / "package.xml"
    if manifest.is_file():
        match = re.search(r"<name>\s*([^<\s]+)\s*</name>", manifest.read_text(errors="replace"))
        return bool(match) and match.group(1) == name
    return False


@contextmanager
def _patched(trusted: bool, package_dirs: Sequence[str | Path]):
    """xacro's evaluator and substitution commands replaced by ours while a file expands."""
    import xacro
    from xacro import substitution_args as sa

    def refuse(command: str):
        def call(*args, **kwargs):
            raise RobotFileError(f"$({command} ...) reads the environment or runs code; load the robot with "
                                 "trusted=True to allow it")

        return call

    saved = (xacro.safe_eval, sa._eval_find, sa._eval_env, sa._eval_optenv, sa._eval)
    with _LOCK:
        xacro.safe_eval = XacroEvaluator(trusted)
        sa._eval_find = lambda pkg: str(find_package(pkg, package_dirs))
        if not trusted:
            sa._eval_env, sa._eval_optenv, sa._eval = refuse("env"), refuse("optenv"), refuse("eval")
        try:
            yield xacro
        finally:
            xacro.safe_eval, sa._eval_find, sa._eval_env, sa._eval_optenv, sa._eval = saved


def declared_arguments(paths: Sequence[Path]) -> set[str]:
    """Names of the ``<xacro:arg name="...">`` declared in the files ``paths``."""
    names = set()
    for path in paths:
        try:
            text = Path(path).read_text(errors="replace")
        except OSError:
            continue
        names.update(re.findall(r"<\s*xacro:arg\b[^>]*\bname\s*=\s*[\"']([^\"']+)[\"']", text))
    return names


def expand_xacro(path: Path, *, xacro_args: Mapping[str, Any] | None = None,
                 package_dirs: Sequence[str | Path] = (), trusted: bool = False) -> str:
    """URDF text of the xacro file ``path`` (see the module docstring for what an expression may do)."""
    args = {k: str(v) for k, v in (xacro_args or {}).items()}
    with _patched(trusted, package_dirs) as xacro:
        first = len(getattr(xacro, "all_includes", []))
        try:
            doc = xacro.process_file(str(path), mappings=args)
        except RobotFileError:
            raise
        except Exception as err:  # XacroException, NameError, KeyError, ...
            cause = err
            while getattr(cause, "exc", None) is not None:  # xacro wraps the error that stopped it
                cause = cause.exc
            if isinstance(cause, RobotFileError):
                raise RobotFileError(f"{path}: {cause}") from None
            raise RobotFileError(f"xacro failed on {path}: {err}") from err
        included = [Path(p) for p in getattr(xacro, "all_includes", [])[first:]]
    unknown = sorted(set(args) - declared_arguments([Path(path), *included]))
    if unknown:
        raise RobotFileError(f"{path}: xacro arguments {unknown} are not declared by the file "
                             f"(declared: {sorted(declared_arguments([Path(path), *included]))})")
    return doc.toprettyxml(indent="  ")
