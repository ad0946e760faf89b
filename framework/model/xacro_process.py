"""The xacro expansion of :mod:`framework.model.xacro_files`, run in a process of its own.

xacro keeps its evaluator and its substitution commands in module globals, so evaluating a file with our own
evaluator (data only) and finding ``$(find pkg)`` in ``package_dirs`` means replacing them: this module does that in
a child process, never in the user's. It imports nothing of the package (the child starts in ~40 ms): run as
``python xacro_process.py`` with a JSON request ``{"path", "args", "package_dirs", "trusted"}`` on stdin, it writes
``{"urdf", "includes"}`` or ``{"error"}`` as JSON on stdout.
"""

from __future__ import annotations

import ast
import json
import math
import os
import re
import sys
from collections.abc import Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any


class RobotFileError(Exception):
    """A robot file the child cannot expand (the parent raises the package's own error with its message)."""


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


def find_package(name: str, package_dirs: Sequence | Mapping[str, str | Path]) -> Path:
    """The folder of ROS package ``name``: given by name in ``package_dirs`` (``{package: folder}`` mappings or
    ``[package, folder]`` pairs), or found in its folders (each a package itself, or holding packages, to any
    depth), then in the folders of ``ROS_PACKAGE_PATH`` and ``AMENT_PREFIX_PATH/share``. Not found: an error listing the folders searched and the
    package names seen closest to ``name``."""
    named: dict[str, Path] = {}
    roots: list[Path] = []
    for item in ([package_dirs] if isinstance(package_dirs, Mapping) else package_dirs):
        if isinstance(item, Mapping):
            named.update({k: Path(v) for k, v in item.items()})
        elif isinstance(item, (list, tuple)):  # a (package name, folder) pair
            named[str(item[0])] = Path(item[1])
        else:
            roots.append(Path(item))
    if name in named:
        if named[name].is_dir():
            return named[name]
        raise RobotFileError(f"ROS package {name!r}: its folder {named[name]} (package_dirs) does not exist")
    roots += [p.parent for p in named.values()]
    roots += [Path(p) for p in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep) if p]
    roots += [Path(p) / "share" for p in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p]
    seen: set[str] = set(named)
    for root in roots:
        if not root.is_dir():
            continue
        if _is_package(root, name):
            return root
        for manifest in sorted(root.rglob("package.xml")):
            if _is_package(manifest.parent, name):
                return manifest.parent
            seen.add(_package_name(manifest) or manifest.parent.name)
        candidate = root / name
        if candidate.is_dir():
            return candidate
        seen.update(child.name for child in root.iterdir() if child.is_dir())
    searched = ", ".join(str(r) for r in roots) or "nothing (give package_dirs=[folder, ...])"
    import difflib

    close = difflib.get_close_matches(name, sorted(seen), n=3, cutoff=0.5)
    hint = (f"; closest package names seen: {', '.join(close)} (a package named unlike its folder: "
            f"package_dirs={{{name!r}: folder}})") if close else ""
    raise RobotFileError(f"ROS package {name!r} not found; searched {searched}{hint}")


def _package_name(manifest: Path) -> str | None:
    match = re.search(r"<name>\s*([^<\s]+)\s*</name>", manifest.read_text(errors="replace"))
    return match.group(1) if match else None


def _is_package(folder: Path, name: str) -> bool:
    manifest = folder / "package.xml"
    return manifest.is_file() and _package_name(manifest) == name


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
    if True:  # (this process expands one file)
        xacro.safe_eval = XacroEvaluator(trusted)
        sa._eval_find = lambda pkg: str(find_package(pkg, package_dirs))
        if not trusted:
            sa._eval_env, sa._eval_optenv, sa._eval = refuse("env"), refuse("optenv"), refuse("eval")
        try:
            yield xacro
        finally:
            xacro.safe_eval, sa._eval_find, sa._eval_env, sa._eval_optenv, sa._eval = saved


def expand(path: str, args: Mapping[str, str], package_dirs: Sequence[str], trusted: bool) -> dict[str, Any]:
    """``{"urdf": text, "includes": [files]}`` of the xacro file ``path``, or ``{"error": message}``."""
    with _patched(trusted, package_dirs) as xacro:
        try:
            doc = xacro.process_file(path, mappings=dict(args))
        except RobotFileError as err:
            return {"error": str(err)}
        except Exception as err:  # XacroException, NameError, KeyError, ...
            cause = err
            while getattr(cause, "exc", None) is not None:  # xacro wraps the error that stopped it
                cause = cause.exc
            if isinstance(cause, RobotFileError):
                return {"error": f"{path}: {cause}"}
            return {"error": f"xacro failed on {path}: {err}"}
        return {"urdf": doc.toprettyxml(indent="  "), "includes": [str(p) for p in getattr(xacro, "all_includes", [])]}


if __name__ == "__main__":
    request = json.load(sys.stdin)
    json.dump(expand(request["path"], request["args"], request["package_dirs"], request["trusted"]), sys.stdout)
