"""``metaik robots``, ``show ROBOT``, ``tasks``, ``solvers``: what is shipped and what a robot is."""


from __future__ import annotations

from rich.console import Console
from rich.markup import escape
from rich.table import Table

from ..errors import EXIT_OK


def robots_command(args, console: Console) -> int:
    from ..model.loading import load_robot, robot_index

    table = Table(title="Shipped robots (robots/index.toml)")
    for column in ("name", "DOF", "end-effectors", "groups"):
        table.add_column(column, no_wrap=True)
    table.add_column("description", overflow="fold")
    for name, entry in robot_index().items():
        robot = load_robot(name)
        groups = ", ".join(f"{g} ({len(i)})" for g, i in robot.groups.items())
        table.add_row(name, str(robot.n), ", ".join(robot.end_effectors), groups, entry.get("description", ""))
    console.print(table)
    return EXIT_OK


def solvers_command(args, console: Console) -> int:
    from ..solvers import ALGORITHMS, IK_SOLVERS, ik_solver

    table = Table(title="Solvers: solve(problem, name, options={...}); metaik run TASK --solver NAME")
    for column in ("name", "kind", "options (defaults)", "reference"):
        table.add_column(column, overflow="fold")
    for name in [*sorted(IK_SOLVERS), *sorted(ALGORITHMS)]:
        solver = ik_solver(name)
        defaults = ", ".join(f"{k}={v!r}" for k, v in solver.defaults().items()) or "—"
        reference = solver.reference or (ALGORITHMS[name].__doc__ or "").strip().splitlines()[0]
        table.add_row(name, solver.kind, escape(defaults), escape(reference))
    console.print(table)
    return EXIT_OK


def show_command(args, console: Console) -> int:
    import pinocchio as pin

    from ..solvers.analytic import closed_form
    from .robots import load_robot_of

    robot = load_robot_of(args)
    console.print(f"[bold]{robot.name}[/]: {robot.n} joint coordinates, end-effectors {list(robot.end_effectors)}")
    table = Table()
    for column in ("#", "coordinate", "kind", "lower", "upper", "group"):
        table.add_column(column)
    group_of = {int(i): g for g, idx in robot.groups.items() for i in idx}
    for joint in robot.joints:
        for i in joint.coordinates:
            table.add_row(
                str(i), robot.coordinate_names[i], joint.kind.value,
                f"{robot.lower[i]:.4g}", f"{robot.upper[i]:.4g}", group_of.get(i, ""),
            )
    console.print(table)
    if robot.locked:
        console.print("locked: " + ", ".join(f"{k}={v:.4g}" for k, v in robot.locked.items()))
    console.print("groups: " + ("; ".join(
        f"{g} ({', '.join(robot.coordinate_names[i] for i in idx)})" for g, idx in robot.groups.items()) or "none"),
        highlight=False)
    console.print(f"end-effectors: {', '.join(robot.end_effectors) or 'none'}", highlight=False)
    for frame in robot.end_effectors:  # which ones inverse kinematics solves in closed form, and why not
        form = closed_form(robot, frame)
        console.print(f"closed form of {frame}: " + (form.family if form.exists else f"none ({form.reason})"),
                      highlight=False)
    frames = [f.name for f in robot.model.frames
              if f.type in (pin.FrameType.BODY, pin.FrameType.OP_FRAME) and f.name != "universe"]
    console.print(f"frames ({len(frames)}): {', '.join(frames)}", highlight=False)
    return EXIT_OK


def tasks_command(args, console: Console) -> int:
    from ..resources import data_dir

    table = Table(title="Shipped tasks (metaik run NAME)")
    table.add_column("name", no_wrap=True)
    table.add_column("first line", overflow="fold")
    for path in sorted(data_dir("tasks").glob("*.toml")):
        first = path.read_text().splitlines()[0].lstrip("# ") if path.stat().st_size else ""
        table.add_row(path.stem, first)
    console.print(table)
    return EXIT_OK


