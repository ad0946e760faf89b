"""The ``metaik`` command line: ``robots``, ``show ROBOT``, ``tasks``, ``solvers``, ``run TASK``, ``bench TASK...``,
``reach ROBOT``, ``replay FILE``.

Exit codes: 0 success; 1 the run finished but some case missed its tolerance; 2 bad input (missing file,
bad TOML, unknown robot/solver/frame, invalid weights: one clear line, no traceback); 130 interrupted.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path

from rich.console import Console
from rich.markup import escape

from ..compiled import cache as compile_cache
from ..errors import EXIT_INPUT, EXIT_INTERRUPTED, EXIT_MISSED, EXIT_OK, MetaikError
from ..io.taskfile import resolve_task
from .bench import add_bench_command, bench_command
from .robots import add_robot_options
from .info import robots_command, show_command, solvers_command, tasks_command
from .reach import add_reach_command, reach_command
from .replay import add_replay_command, replay_command
from .run import run_command

__all__ = ["EXIT_INPUT", "EXIT_INTERRUPTED", "EXIT_MISSED", "EXIT_OK", "build_parser", "main", "resolve_task"]


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of every ``metaik`` command."""
    parser = argparse.ArgumentParser(
        prog="metaik", description="Inverse kinematics by optimization for any URDF robot."
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    sub.add_parser("robots", help="list the shipped robots (DOF, end-effectors, groups)")

    show = sub.add_parser("show", help="describe a robot: joints, bounds, frames, groups")
    show.add_argument("robot", help="robot index name or URDF/xacro path")
    add_robot_options(show)

    run = sub.add_parser("run", help="solve a task file (a path, or the name of a shipped task)")
    run.add_argument("task", help="task file (.toml) or shipped task name, e.g. youbot_dual_coordinated_ik")
    run.add_argument("--solver", help="override the task's solver (e.g. hybrid, cmaes, de, sde)")
    run.add_argument("--seed", type=int, help="override the seed")
    run.add_argument("--iterations", type=int, help="override max_iterations")
    run.add_argument("--population", type=int, help="override the population size")
    run.add_argument("--case", action="append", help="only these cases (by name); repeatable")
    run.add_argument("--points", type=int, help="tracking tasks: number of waypoints (re-samples the path)")
    run.add_argument("--no-progress", action="store_true", help="tracking and reach tasks: no progress bar")
    run.add_argument("--output", type=Path, help="tracking tasks: write the joint path and errors per waypoint (.csv)")
    run.add_argument("--record", type=Path, metavar="FILE.rrd",
                     help="write a rerun recording of the run (open it with `metaik replay FILE.rrd`)")

    sub.add_parser("tasks", help="list the shipped task files")
    sub.add_parser("solvers", help="list the solvers with their options, defaults and references")
    add_bench_command(sub)
    add_reach_command(sub)
    add_replay_command(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    console = Console()
    compiled_before = compile_cache.NOTICE.seconds  # each compile says so on stderr as it begins (NOTICE)
    try:
        commands = {"robots": robots_command, "show": show_command, "run": run_command, "tasks": tasks_command,
                    "solvers": solvers_command,
                    "bench": bench_command, "reach": reach_command, "replay": replay_command}
        code = commands[args.command](args, console)
        compiling = compile_cache.NOTICE.seconds - compiled_before
        if compiling >= 1.0 and code != EXIT_INTERRUPTED:  # its time would be read as the solver's
            Console(stderr=True).print(f"(the times above include {compiling:.0f} s of compiling, once per install)",
                                       highlight=False)
        return code
    except MetaikError as err:
        Console(stderr=True).print(f"[bold red]error:[/] {escape(str(err))}", highlight=False, markup=True,
                                   soft_wrap=True)
        return EXIT_INPUT
    except KeyboardInterrupt:
        Console(stderr=True).print("interrupted before any result")
        return EXIT_INTERRUPTED


