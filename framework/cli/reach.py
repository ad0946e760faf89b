"""``metaik reach ROBOT``: a capability map of a frame, or (``--place``) ranked base poses of a mobile robot."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from .robots import add_robot_options, load_robot_of
from ..errors import EXIT_OK, TaskError


def add_reach_command(sub: argparse._SubParsersAction) -> None:
    reach = sub.add_parser("reach", help="capability map of a frame (.npz, PNG slice, rerun), or base placement")
    reach.add_argument("robot", help="robot index name or URDF/xacro path")
    add_robot_options(reach)
    reach.add_argument("--frame", help="the frame to map (default: the robot's first end-effector)")
    reach.add_argument("--voxel", type=float, default=0.1, help="voxel edge [m] (default 0.1)")
    reach.add_argument("--orientations", type=int, default=0,
                       help="random orientations tried per voxel (default 0: the position alone)")
    reach.add_argument("--self-collision", action="store_true",
                       help="reach only without contact between the robot's own links (coal decides)")
    reach.add_argument("--out", type=Path, help="write the map (.npz)")
    reach.add_argument("--png", type=Path, help="draw the horizontal slice that reaches most (.png)")
    reach.add_argument("--record", type=Path, metavar="FILE.rrd", help="the map as a rerun point cloud")
    reach.add_argument("--place", action="append", metavar="FRAME=X,Y,Z",
                       help="base placement: a hand target [m, world]; repeatable (one per hand)")
    reach.add_argument("--radius", type=float, default=1.0, help="base placement: search radius [m]")
    reach.add_argument("--step", type=float, default=0.1, help="base placement: grid step [m]")
    reach.add_argument("--headings", type=int, default=12, help="base placement: headings per position")
    reach.add_argument("--seed", type=int, default=0)
    reach.add_argument("--scheduler", metavar="tcp://HOST:PORT|local", help="compute the map on a Dask cluster")
    reach.add_argument("--no-progress", action="store_true", help="no progress bar")


def _targets(entries: list[str]) -> dict[str, np.ndarray]:
    targets = {}
    for entry in entries:
        frame, _, numbers = entry.partition("=")
        try:
            point = np.array([float(v) for v in numbers.split(",")])
        except ValueError:
            point = np.zeros(0)
        if not frame or point.shape != (3,) or not np.isfinite(point).all():
            raise TaskError(f"--place takes FRAME=X,Y,Z (three numbers, metres); got {entry!r}")
        targets[frame] = point
    return targets


def _print_ranking(console: Console, placements) -> None:
    ranking = placements.ranking
    console.print(f"{len(placements.candidates)} base poses tried, {len(ranking)} reach every target")
    table = Table(title="Best base poses (smallest hand manipulability, highest first)")
    for column in ("rank", "x (m)", "y (m)", "θ (deg)", "manipulability"):
        table.add_column(column, justify="right")
    for rank, k in enumerate(ranking[:5], 1):
        x, y, theta = placements.candidates[k]
        table.add_row(str(rank), f"{x:.3f}", f"{y:.3f}", f"{np.degrees(theta):.1f}", f"{placements.score[k]:.4f}")
    console.print(table)


def run_placement(args, console: Console, task) -> int:
    """``metaik run`` of a base-placement task file: rank the base poses, solve the whole robot from the best one
    (both hands, motion minimized on the task), print it and, with ``--record``, record it."""
    from ..errors import EXIT_MISSED
    from ..reach.capability import base_placements, solve_from_base

    console.print(f"[bold]{escape(task.name)}[/] on {escape(task.robot.name)}: {escape(task.description)}")
    settings = {**task.settings, **({"seed": args.seed} if args.seed is not None else {})}
    placements = base_placements(task.robot, task.targets, progress=False if args.no_progress else None,
                                 **settings)
    _print_ranking(console, placements)
    if not placements.ranking.size:
        return EXIT_MISSED
    problem, result = solve_from_base(task.robot, task.targets, placements.best[1])
    console.print(f"whole robot from the best base pose: success {result.success}, errors "
                  + escape(", ".join(f"{k} {v:.1e}" for k, v in result.errors.items())))
    if args.record:
        from ..io.recording import Recorder

        with Recorder(args.record, task.robot, description=f"# {task.name}\n\n{task.description}") as recorder:
            recorder.log_solution(result, problem=problem, name="placed")
        console.print(f"recording written to {args.record}")
    return EXIT_OK if result.success else EXIT_MISSED


def reach_command(args, console: Console) -> int:
    from ..reach.capability import base_placements, reachability_map

    robot = load_robot_of(args)
    progress = False if args.no_progress else None
    if args.place:
        placements = base_placements(robot, _targets(args.place), radius=args.radius, step=args.step,
                                     headings=args.headings, seed=args.seed, progress=progress)
        _print_ranking(console, placements)
        return EXIT_OK
    frame = args.frame or robot.end_effectors[0]
    collisions = None
    if args.self_collision:
        from ..costs import SelfCollision
        from ..geometry.collision import RobotShape

        collisions = SelfCollision(RobotShape(robot))
    result = reachability_map(robot, frame, voxel=args.voxel, orientations=args.orientations, seed=args.seed,
                              progress=progress, scheduler=args.scheduler, collisions=collisions)
    reached = result.fraction > 0
    what = f"{robot.name}, frame {frame}{' clear of itself' if collisions else ''}"
    console.print(f"{what}: {len(result.centers)} voxels of {args.voxel:g} m, {reached.sum()} reach something, "
                  f"mean fraction {result.fraction[reached].mean():.3f} there" if reached.any() else
                  f"{what}: no voxel of {len(result.centers)} reached" + (
                      f" ({args.orientations} random orientations each: a {robot.n}-joint arm may take none of "
                      "them; try --orientations 0)" if args.orientations and robot.n < 6 else ""))
    if args.out:
        console.print(f"map written to {result.save(args.out)}")
    if args.png:
        console.print(f"slice drawn to {result.slice_png(args.png)}")
    if args.record:
        import rerun as rr

        recording = rr.RecordingStream("metaik reach")
        recording.save(str(args.record))
        result.log_rerun(recording)
        console.print(f"recording written to {args.record}")
    return EXIT_OK
