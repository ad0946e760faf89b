"""``metaik run TASK``: an IK task's cases, a tracking task's paths, a reach or placement task; tables, CSV,
recording."""


from __future__ import annotations

import sys
from contextlib import contextmanager, nullcontext
from pathlib import Path

import numpy as np
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from ..errors import EXIT_INTERRUPTED, EXIT_MISSED, EXIT_OK, TaskError
from ..interrupts import graceful_interrupt
from ..io.placement import PlacementTask
from .reach import run_placement
from ..io.recording import Recorder
from ..solvers.settings import DEFAULTS
from ..io.taskfile import resolve_task


def run_command(args, console: Console) -> int:
    from ..solvers.solve import solve
    from ..io.taskfile import load_task

    task = load_task(resolve_task(args.task), points=getattr(args, "points", None))
    if isinstance(task, PlacementTask):  # where a mobile base should stand
        return run_placement(args, console, task)
    settings = dict(task.solver)
    overrides = {"name": args.solver, "seed": args.seed, "max_iterations": args.iterations,
                 "population": args.population}
    if args.solver is not None and args.solver != settings.get("name", DEFAULTS.solver) and "options" in settings:
        console.print(f"the file's [solver.options] are {settings.get('name', DEFAULTS.solver)}'s: "
                      f"{args.solver} runs with its own defaults")
        del settings["options"]
    settings.update({k: v for k, v in overrides.items() if v is not None})
    solver = settings.get("name", DEFAULTS.solver)
    if task.is_tracking:
        return _run_tracking(args, console, task, settings, solver)
    cases = [c for c in task.cases if not args.case or c.name in args.case]
    if not cases:
        raise TaskError(f"no case named {args.case}; cases: {[c.name for c in task.cases]}")
    console.print(f"[bold]{task.name}[/] on {task.robot.name} ({task.robot.n} DOF) with {solver}: {task.description}")

    names = cases[0].problem.names
    solve_settings = asked(settings)
    table = Table(title=f"{task.name}: {solver}, seed {solve_settings['seed']} (unweighted terms)")
    table.add_column("")
    rows: dict[str, list[str]] = {n: [] for n in (*names, "cost", "task error", "success", "iterations",
                                                   "evaluations", "time (s)")}
    all_ok, interrupted, solved, missed = True, False, None, []
    header = ["case", "success", "task_error", "cost", *task.robot.coordinate_names]
    with console.status("solving") as status, _recorder(args, task, settings) as recorder, \
            _csv_rows(args.output, header) as csv_row:
        for case in cases:
            status.update(f"solving {case.name}")
            try:
                result = solve(case.problem, solver, **solve_settings,
                               callback=recorder.term_logger(case.problem, case.name) if recorder else None)
            except KeyboardInterrupt:  # a second Ctrl-C, or one while the solver's code compiled: no result
                interrupted = True
                break
            solved = (case, result)
            csv_row(case.name, result.success, f"{result.task_error:.6e}", f"{result.cost:.17g}",
                    *(f"{v:.17g}" for v in result.configuration))
            if recorder:
                recorder.log_case(case, result)
            interrupted = result.stop_reason == "interrupted"
            all_ok &= result.success
            if not result.success:
                missed.append(f"{case.name}: {result.reason}")
            table.add_column(case.name, justify="right")
            for n in names:
                rows[n].append(f"{result.terms[n]:.3e}")
            rows["cost"].append(f"{result.cost:.6g}")
            rows["task error"].append(f"{result.task_error:.2e}")
            rows["success"].append("yes" if result.success else "[red]no[/]")
            rows["iterations"].append(str(result.iterations))
            rows["evaluations"].append(str(result.evaluations))
            rows["time (s)"].append(f"{result.wall_time:.3f}")
            if interrupted:  # Ctrl-C: the cases done so far are shown, the others are not started
                break
    for label, cells in rows.items():
        table.add_row(escape(label), *cells)
    console.print(table)
    for line in missed:  # why each failed case failed, in one line
        console.print(f"[red]missed[/] {escape(line)}")
    if solved is not None:
        x = solved[1].configuration
        groups = task.robot.groups or {"all": np.arange(task.robot.n)}
        console.print(f"configuration of {solved[0].name}: " + "; ".join(
            f"{g} {np.array2string(x[idx], precision=4, suppress_small=True)}" for g, idx in groups.items()))
    _recorded(args, console)
    if args.output is not None:
        console.print(f"wrote {args.output}")
    if interrupted:
        Console(stderr=True).print(f"interrupted during {case.name!r}: {len(table.columns) - 1} of {len(cases)} "
                                   "cases shown", highlight=False)
        return EXIT_INTERRUPTED
    return EXIT_OK if all_ok else EXIT_MISSED


def _recorder(args, task, settings: dict):
    """A :class:`Recorder` of this run when ``--record FILE`` was given, else a context yielding None."""
    if getattr(args, "record", None) is None:
        return nullcontext()
    return Recorder.for_task(args.record, task, settings={**settings, "command": " ".join(sys.argv)})


def _recorded(args, console: Console) -> None:
    if getattr(args, "record", None) is not None:
        console.print(f"recorded the run to {args.record} (open it with `metaik replay {args.record}`)")


def _run_tracking(args, console: Console, task, settings: dict, solver: str) -> int:
    """``metaik run`` of a tracking task: track every case's trajectory, then one summary table."""
    cases = [c for c in task.cases if not args.case or c.name in args.case]
    if not cases:
        raise TaskError(f"no case named {args.case}; cases: {[c.name for c in task.cases]}")
    solve_settings = asked(settings)
    results: list = []
    try:
        with _recorder(args, task, settings) as recorder, _waypoint_csv(args.output, task.robot) as csv_row:
            console.print(f"[bold]{task.name}[/] on {task.robot.name} ({task.robot.n} DOF), tracking with {solver} "
                          f"({solve_settings['max_iterations'] or 'default'} iterations per point): {task.description}")
            interrupted = _track_cases(args, task, cases, settings, solver, solve_settings, recorder, results,
                                       csv_row)
    except KeyboardInterrupt:  # before the tracking loop took over Ctrl-C (files opening, the problem's code
        interrupted = True  # compiling): what was done is in the table, the CSV and the recording
    console.print(tracking_table(task, results, solver, solve_settings["seed"], solve_settings["tolerance"]))
    for case, result in results:  # why a path missed waypoints, in one line
        if result.reason:
            console.print(f"[red]missed[/] {escape(case.name)}: {escape(result.reason)}")
    if args.output is not None:
        console.print(f"wrote {args.output}")
    _recorded(args, console)
    if interrupted:
        done = sum(len(result) for _, result in results)
        total = sum(case.trajectory.K for case in cases)
        Console(stderr=True).print(f"interrupted: {done} of {total} waypoints solved (the table shows them)",
                                   highlight=False)
        return EXIT_INTERRUPTED
    return EXIT_OK if all(r.all_success for _, r in results) else EXIT_MISSED


def _track_cases(args, task, cases, settings, solver, solve_settings, recorder, results: list, csv_row) -> bool:
    """Track each case in turn (``solve_settings``: :func:`asked`), appending ``(case, result)`` to ``results`` (and to the recording, if any) and
    each waypoint to the CSV as soon as it is solved; returns True when Ctrl-C stopped the run."""
    from ..tracking import track, waypoint_errors

    for case in cases:
        kinds = case.problem.program.term_kinds  # the same terms at every waypoint of the case

        def solved(k: int, result, case=case, kinds=kinds) -> None:
            with graceful_interrupt() as interrupt:  # a Ctrl-C waits for the waypoint's CSV row and recording
                csv_row(case.name, k, result.configuration, waypoint_errors(result, kinds))
                if recorder:
                    recorder.log_waypoint(result.configuration)
            if interrupt.requested:  # then stops the run, this waypoint done
                raise KeyboardInterrupt

        result = track(
            task.robot, case.trajectory, case.builder,
            solver=solver,
            **solve_settings,
            initial=case.initial,
            warm_start=settings.get("warm_start", True),
            predict=settings.get("predict"),
            velocity_scale=settings.get("velocity_scale"),
            acceleration=settings.get("acceleration"),
            retime=settings.get("retime", False),
            bounds=settings.get("bounds", "resample"),
            priorities=task.priorities,
            progress=False if args.no_progress else None,
            callback=solved,
        )
        results.append((case, result))
        if recorder:
            recorder.log_case(case, result)
        if result.stop_reason == "interrupted":
            return True
    return False


def tracking_table(task, results: list, solver: str, seed: int, tolerance: float) -> Table:
    """Mean/max position, orientation and motion error, smoothness and time of each tracked case."""
    table = Table(title=f"{task.name}: tracking with {solver}, seed {seed} (errors per waypoint)")
    table.add_column("")
    for case, _ in results:
        table.add_column(case.name, justify="right")
    rows = {label: [] for label in (
        "waypoints", "position error, mean [m]", "position error, max [m]", "orientation error, mean",
        "orientation error, max", "motion error, mean", "motion error, max", "max joint step", "mean joint step",
        "worst step at waypoint", f"within tolerance {tolerance:g}", "held back by joint limits", "path duration (s)",
        "evaluations", "time (s)")}
    for case, result in results:
        smooth = result.smoothness(task.robot) if len(result) else None
        oriented = case.trajectory.has_orientation
        cells = [
            f"{len(result)}/{case.trajectory.K}",
            f"{_mean(result.position_error):.2e}", f"{_max(result.position_error):.2e}",
            f"{_mean(result.orientation_error):.2e}" if oriented else "-",
            f"{_max(result.orientation_error):.2e}" if oriented else "-",
            f"{_mean(result.motion_error):.2e}", f"{_max(result.motion_error):.2e}",
            f"{smooth.max_step['all']:.4f}" if smooth else "-",
            f"{smooth.mean_step['all']:.4f}" if smooth else "-",
            str(smooth.worst_point["all"]) if smooth else "-",
            ("" if result.all_success else "[red]") + f"{int(result.success.sum())}/{case.trajectory.K}",
            str(int(result.lagging.sum())),
            f"{result.trajectory.times[-1] - result.trajectory.times[0]:.3f}" if result.trajectory.is_timed else "-",
            str(int(result.evaluations.sum())),
            f"{result.wall_time:.2f}",
        ]
        for label, cell in zip(rows, cells):
            rows[label].append(cell)
    for label, cells in rows.items():
        table.add_row(escape(label), *cells)
    return table


def asked(settings: dict) -> dict:
    """The solve settings of a task file's ``[solver]`` table (with the command line's overrides), each one not
    given taken from :data:`~framework.solvers.settings.DEFAULTS` (checked where the file was read)."""
    return {"seed": settings.get("seed", DEFAULTS.seed), "tolerance": settings.get("tolerance", DEFAULTS.tolerance),
            "max_iterations": settings.get("max_iterations", DEFAULTS.max_iterations),
            "population": settings.get("population", DEFAULTS.population),
            "stop_at_tolerance": settings.get("stop_at_tolerance", DEFAULTS.stop_at_tolerance),
            "options": settings.get("options", DEFAULTS.options)}


@contextmanager
def _waypoint_csv(path: Path | None, robot):
    """A writer of one CSV row per solved waypoint (case, k, joint coordinates, position / orientation / motion
    error), flushed at once so a killed run keeps every finished waypoint; a no-op without ``path``."""
    header = ["case", "k", *robot.coordinate_names, "position_error", "orientation_error", "motion_error"]
    with _csv_rows(path, header) as row:
        yield lambda case, k, q, errors: row(case, k, *(f"{v:.17g}" for v in q), *(f"{e:.6e}" for e in errors))


@contextmanager
def _csv_rows(path: Path | None, header: list[str]):
    """A writer of CSV rows under ``header`` to ``--output`` ``path`` (its folder made), each flushed at once; a
    no-op without ``path``; a path that cannot be written is a :class:`TaskError` before anything runs."""
    import csv

    if path is None:
        yield lambda *row: None
        return
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        handle = open(path, "w", newline="")
    except OSError as err:
        raise TaskError(f"cannot write --output {path}: {err.strerror}") from None
    with handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        handle.flush()

        def row(*values) -> None:
            writer.writerow(values)
            handle.flush()

        yield row


def _mean(a: np.ndarray) -> float:
    return float(a.mean()) if a.size else float("nan")


def _max(a: np.ndarray) -> float:
    return float(a.max()) if a.size else float("nan")


