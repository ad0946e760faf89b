"""``metaik bench``: parse, plan, run (resuming), report."""


from __future__ import annotations

import shlex
from pathlib import Path

from ..bench.grid import GRID_LIMIT, GROUP_BY, plan
from ..bench.report import doc_figures, grid_markdown, report_markdown, write_doc, write_report
from ..bench.runner import run_grid
from ..bench.store import drop_runs, grid_records
from ..errors import EXIT_INTERRUPTED, EXIT_OK, MetaikError, TaskError
from ..bench.stats import (
    sci,
    summary_rows,
)
from ..io.taskfile import resolve_task


# ---------------------------------------------------------------------------------------------- command line
def add_bench_command(subparsers) -> None:
    """Add ``metaik bench`` to an argparse subparsers object (its handler is :func:`bench_command`)."""
    p = subparsers.add_parser(
        "bench", help="benchmark solvers on task files: parallel, resumable, tables + figures"
    )
    p.add_argument("tasks", nargs="+", help="task files (.toml) or shipped task names")
    p.add_argument("--solvers", help="comma-separated solvers (default: the task's [bench] solvers)")
    p.add_argument("--runs", type=int, help="independent runs per (case, solver)")
    p.add_argument("--seed", type=int, help="first seed (runs use seed .. seed + runs - 1)")
    p.add_argument("--iterations", type=int, help="override max_iterations")
    p.add_argument("--population", type=int, help="override the population size")
    p.add_argument("--tolerance", type=float, help="success threshold on the task error")
    p.add_argument("--case", action="append", help="only these cases or systems (by name); repeatable")
    p.add_argument("--reference", help="solver compared against every other by the sign test")
    p.add_argument("--group-by", choices=GROUP_BY, help="tables and figures per case or per system")
    p.add_argument("--jobs", "-j", type=int, help="worker processes (default: all cores)")
    p.add_argument("--scheduler", metavar="tcp://HOST:PORT|local",
                   help="run on a Dask cluster (an address, or 'local': a local cluster of --jobs processes)")
    p.add_argument("--out", help="output folder (default: results/bench/<task name>, git-ignored)")
    p.add_argument("--max-runs", type=int, help="stop after this many new runs (re-run to continue)")
    p.add_argument("--grid-limit", type=int, default=GRID_LIMIT,
                   help=f"refuse grids of more runs than this (default {GRID_LIMIT:,})")
    p.add_argument("--report-only", action="store_true", help="do not run; report the results file")
    p.add_argument(
        "--rerun", action="store_true", help="drop this grid's runs from the results file, run them again"
    )
    p.add_argument("--no-figures", action="store_true", help="skip the PNG figures")
    p.add_argument(
        "--doc", help="also write one Markdown results document here (figures in <its folder>/figures/bench)"
    )
    p.add_argument("--title", help="title of the --doc document")
    p.set_defaults(handler=bench_command)


def bench_command(args, console) -> int:
    """Handler of ``metaik bench``: plan, run (resuming), then write and print the report. Exit code 0 or 130."""
    from rich.table import Table

    paths = [resolve_task(t) for t in args.tasks]
    grid = plan(
        paths,
        solvers=[s.strip() for s in args.solvers.split(",") if s.strip()] if args.solvers else None,
        runs=args.runs,
        seed=args.seed,
        population=args.population,
        max_iterations=args.iterations,
        tolerance=args.tolerance,
        cases=args.case,
        reference=args.reference,
        group_by=args.group_by,
        grid_limit=args.grid_limit,
    )
    for flag, value in (("--jobs", args.jobs), ("--max-runs", args.max_runs)):
        if value is not None and value < 1:
            raise TaskError(f"{flag} must be an integer >= 1; got {value}")
    out = Path(args.out) if args.out else Path("results") / "bench" / grid.name
    _writable_folder(out, "--out")
    if args.doc:
        _writable_folder(Path(args.doc).parent, "--doc's folder")
    results = out / "results.jsonl"
    console.print(f"[bold]{grid.name}[/]: {len(grid.specs)} runs → {results}")
    if args.rerun and not args.report_only:
        console.print(f"dropped {drop_runs(results, grid.keys)} earlier runs of this grid")
    if not args.report_only:
        report = run_grid(grid, results, jobs=args.jobs, max_runs=args.max_runs, console=console,
                          scheduler=args.scheduler)
        console.print(
            f"{report.completed} runs done in {report.wall_time:.1f} s, {report.skipped} already in the "
            f"results file"
        )
        if report.interrupted and args.max_runs is None:
            console.print("interrupted: re-run the same command to resume")
            return EXIT_INTERRUPTED
    records = grid_records(grid, results)
    if not records:
        raise MetaikError(f"{results} holds no run of this grid yet")
    written = write_report(
        records,
        out,
        tolerance=grid.tolerance,
        reference=grid.reference,
        group_by=grid.group_by,
        figures=not args.no_figures,
    )
    if args.doc:
        doc = Path(args.doc)
        figures = None if args.no_figures else doc_figures(records, doc, group_by=grid.group_by)
        body = "## Settings\n\n" + grid_markdown(grid) + f"\n\n## Results ({len(records)} runs)\n\n"
        body += report_markdown(
            records,
            tolerance=grid.tolerance,
            reference=grid.reference,
            group_by=grid.group_by,
            figures=figures,
            relative_to=doc.parent,
        )
        written.append(write_doc(doc, args.title or f"Benchmark: {grid.name}", command_line(args), body))
    table = Table(title=f"{grid.name}: task error over {len(records)}/{len(grid.specs)} runs")
    for column in ("group", "solver", "runs", "mean", "std", "best", "worst", "success", "median time (s)"):
        table.add_column(column, justify="left" if column in ("group", "solver") else "right")
    for r in summary_rows(records, group_by=grid.group_by, tolerance=grid.tolerance):
        e = r.stats["task_error"]
        table.add_row(
            r.group,
            r.solver,
            str(r.runs),
            sci(e.mean),
            sci(e.std),
            sci(e.best),
            sci(e.worst),
            f"{r.successes}/{r.runs}",
            f"{r.stats['wall_time'].median:.3f}",
        )
    console.print(table)
    console.print(
        "wrote "
        + ", ".join(str(p) for p in written[:4])
        + (f" and {len(written) - 4} more" if len(written) > 4 else "")
    )
    return EXIT_OK


def command_line(args) -> str:
    """The ``metaik bench`` command line of parsed arguments (for the header of generated documents)."""
    words = ["metaik", "bench", *map(_portable, args.tasks)]
    for key, value in sorted(vars(args).items()):
        if key in ("tasks", "command", "handler") or value in (None, False):
            continue
        flag = "--" + key.replace("_", "-")
        values = value if isinstance(value, list) else [value]
        for v in values:
            words += [flag] if v is True else [flag, _portable(str(v))]
    return shlex.join(words)


def _portable(value: str) -> str:
    """An absolute path as a reader could type it: relative to the working folder, or ``…/name`` outside it (a
    document names no machine's folders); anything else as it is."""
    if not value.startswith("/"):
        return value
    try:
        return str(Path(value).resolve().relative_to(Path.cwd().resolve()))
    except ValueError:
        return f"…/{Path(value).name}"


def _writable_folder(folder: Path, what: str) -> None:
    """``folder`` made if it does not exist; a file in its place (or above it), or a folder that cannot be made,
    is a :class:`TaskError` naming ``what`` before any run starts."""
    for above in (folder, *folder.parents):
        if above.exists() and not above.is_dir():
            raise TaskError(f"{what} {folder}: {above} is a file, not a folder")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise TaskError(f"{what} {folder}: cannot make the folder ({err.strerror})") from None
