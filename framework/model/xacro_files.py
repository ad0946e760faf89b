"""Xacro files as data: expanded without running code, with ROS packages found without ROS.

xacro evaluates ``${...}`` with Python's ``eval`` (a few names hidden), and ``$(eval ...)``, ``$(env ...)`` and
``xacro.load_yaml`` reach the interpreter, the environment and any file. A robot file travels like a document,
so :func:`expand_xacro` evaluates it with our own evaluator instead: an expression may only use numbers, strings,
lists, dicts, arithmetic, comparisons, conditionals, the properties and arguments of the file, ``math``'s
functions and a few pure builtins (``min``, ``max``, ``abs``, ``round``, ``len``, ...); no attribute of any other
object, no name or attribute starting with ``_``. ``$(env)``, ``$(optenv)``, ``$(eval)`` and
``xacro.load_yaml`` need ``trusted=True``. ``$(find pkg)`` resolves in ``package_dirs`` (a package is a folder
named like it, or holding a ``package.xml`` naming it; or ``{package name: folder}``), then ``ROS_PACKAGE_PATH`` / ``AMENT_PREFIX_PATH`` when set.
An argument given that the files do not declare (``<xacro:arg name=...>``) is an error.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from ..errors import RobotFileError
from . import xacro_process


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
                 package_dirs: Sequence[str | Path] | Mapping[str, str | Path] = (), trusted: bool = False) -> str:
    """URDF text of the xacro file ``path`` (see the module docstring for what an expression may do), expanded
    in a process of its own (:mod:`~framework.model.xacro_process`: xacro's globals are replaced there, not here)."""
    args = {k: str(v) for k, v in (xacro_args or {}).items()}
    request = {"path": str(path), "args": args, "trusted": bool(trusted),
               "package_dirs": [[e[0], str(e[1])] if isinstance(e, tuple) else str(e)
                                for e in package_folders(package_dirs)]}
    done = subprocess.run([sys.executable, xacro_process.__file__], input=json.dumps(request), capture_output=True,
                          text=True, check=False)
    try:
        answer = json.loads(done.stdout)
    except ValueError:
        raise RobotFileError(f"xacro failed on {path}: {done.stderr.strip()[-2000:] or 'no answer'}") from None
    if "error" in answer:
        raise RobotFileError(answer["error"])
    included = [Path(p) for p in answer["includes"]]
    unknown = sorted(set(args) - declared_arguments([Path(path), *included]))
    if unknown:
        raise RobotFileError(f"{path}: xacro arguments {unknown} are not declared by the file "
                             f"(declared: {sorted(declared_arguments([Path(path), *included]))})")
    return answer["urdf"]


def package_folders(package_dirs: Any) -> tuple[Path | tuple[str, Path], ...]:
    """``package_dirs`` checked and made absolute (relative paths against the working folder): folders holding
    packages, ``{package name: its folder}`` for packages named unlike their folders, or a list mixing both;
    anything else is a :class:`RobotFileError`. Each entry is a folder or a ``(package name, folder)`` pair."""
    if isinstance(package_dirs, (str, Path, Mapping)):
        package_dirs = [package_dirs]
    entries: list[Path | tuple[str, Path]] = []
    try:
        for item in package_dirs:
            if isinstance(item, Mapping):
                if not all(isinstance(k, str) and isinstance(v, (str, Path)) for k, v in item.items()):
                    raise TypeError
                entries += [(k, Path(v).resolve()) for k, v in item.items()]
            elif isinstance(item, tuple) and len(item) == 2 and isinstance(item[0], str) \
                    and isinstance(item[1], Path):
                entries.append((item[0], item[1].resolve()))  # an entry of this function's own result
            elif isinstance(item, (str, Path)):
                entries.append(Path(item).resolve())
            else:
                raise TypeError
    except TypeError:
        raise RobotFileError(f"package_dirs must be folders, {{package name: folder}}, or a list of both; got "
                             f"{package_dirs!r}") from None
    return tuple(entries)


def find_package(name: str, package_dirs: Any) -> Path:
    """The folder of ROS package ``name`` (:func:`framework.model.xacro_process.find_package`), or a
    :class:`RobotFileError`."""
    try:
        return xacro_process.find_package(name, package_folders(package_dirs))
    except xacro_process.RobotFileError as err:
        raise RobotFileError(str(err)) from None
