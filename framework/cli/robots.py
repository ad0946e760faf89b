"""How the command line loads a robot: an index name or a file, with the options :func:`framework.load_robot`
takes (``--package-dir``, ``--trusted``, ``--xacro-arg``), as task files and Python give them."""

from __future__ import annotations

import argparse

from ..errors import RobotFileError, TaskError


def add_robot_options(parser: argparse.ArgumentParser) -> None:
    """The robot-loading options of a command that takes a ``robot`` argument."""
    parser.add_argument("--package-dir", action="append", default=[], metavar="FOLDER|PKG=FOLDER",
                        help="where ROS packages are ($(find pkg), package:// meshes): a folder holding packages, "
                             "or PKG=FOLDER for a package named unlike its folder (repeatable)")
    parser.add_argument("--trusted", action="store_true",
                        help="let xacro read environment variables and YAML files and run $(eval)")
    parser.add_argument("--xacro-arg", action="append", default=[], metavar="NAME=VALUE",
                        help="a xacro argument (repeatable)")


def load_robot_of(args: argparse.Namespace):
    """The robot ``args.robot`` loaded with the options of :func:`add_robot_options`."""
    from ..model.loading import load_robot

    package_dirs = [dict([_pair(v, "--package-dir")]) if "=" in v else v for v in args.package_dir]
    xacro_args = dict(_pair(v, "--xacro-arg") for v in args.xacro_arg)
    try:
        return load_robot(args.robot, package_dirs=package_dirs, trusted=args.trusted, xacro_args=xacro_args or None)
    except RobotFileError as err:
        if "package_dirs" not in str(err):
            raise
        raise RobotFileError(f"{err} (on the command line: --package-dir FOLDER, or --package-dir PKG=FOLDER)") \
            from None


def _pair(text: str, flag: str) -> tuple[str, str]:
    key, sep, value = text.partition("=")
    if not sep or not key or not value:
        raise TaskError(f"{flag} takes NAME=VALUE; got {text!r}")
    return key, value
