"""Reports of a grid's records: tables, CSVs, sign tests and figures (:func:`write_report`), and results
documents written whole by their command (:func:`write_doc`)."""


from __future__ import annotations

import csv
import json
import os
import sys
import time
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

from ..errors import MetaikError
from .stats import (
    group_records,
    sign_markdown,
    sign_rows,
    summary_markdown,
    summary_rows,
    terms_markdown,
)
from .grid import Grid
from .record import RunRecord


# ---------------------------------------------------------------------------------------------- report
def _write_csv(path: Path, header: Sequence[str], rows: Iterable[Sequence[Any]]) -> Path:
    with path.open("w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(header)
        writer.writerows(rows)
    return path


def write_report(
    records: Sequence[RunRecord],
    out_dir: str | Path,
    *,
    tolerance: float = 1e-4,
    reference: str | None = None,
    group_by: str = "case",
    figures: bool = True,
    max_iteration: int | None = None,
) -> list[Path]:
    """Write summary tables (``summary.md``, ``summary.csv``), sign tests (``sign_test.md``/``.csv``, if a
    reference solver is given) and figures (``figures/boxplots_<group>.png``, ``figures/convergence_<group>.png``).

    Returns the written paths.
    """
    from . import plots

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    if not records:
        raise MetaikError(f"no results to report in {out}")
    rows = summary_rows(records, group_by=group_by, tolerance=tolerance)
    written = []
    md = [
        "# Benchmark summary",
        "",
        (
            f"Task error (sum of unweighted task terms): mean, sample std (ddof = 1), best, "
            f"worst, median; success = task error ≤ {tolerance:g}."
        ),
        "",
        summary_markdown(rows, tolerance),
        "## Every term (mean ± std)",
        "",
        terms_markdown(rows),
    ]
    (out / "summary.md").write_text("\n".join(md))
    written.append(out / "summary.md")
    metrics = list(dict.fromkeys(m for r in rows for m in r.stats))
    header = ["group", "solver", "runs", "success_rate"] + [
        f"{m}_{s}" for m in metrics for s in ("mean", "std", "best", "worst", "median")
    ]
    written.append(
        _write_csv(
            out / "summary.csv",
            header,
            (
                [r.group, r.solver, r.runs, r.success_rate]
                + [
                    getattr(r.stats[m], s) if m in r.stats else ""
                    for m in metrics
                    for s in ("mean", "std", "best", "worst", "median")
                ]
                for r in rows
            ),
        )
    )
    if reference:
        signs = sign_rows(records, reference, group_by=group_by)
        (out / "sign_test.md").write_text("# Sign tests\n\n" + sign_markdown(signs))
        written.append(out / "sign_test.md")
        written.append(
            _write_csv(
                out / "sign_test.csv",
                ["group", "metric", "reference", "other", "wins", "losses", "ties", "p_value"],
                (
                    [
                        s.group,
                        s.metric,
                        s.reference,
                        s.other,
                        s.test.wins,
                        s.test.losses,
                        s.test.ties,
                        s.test.p_value,
                    ]
                    for s in signs
                ),
            )
        )
    if figures:
        written += plots.report_figures(
            records, out / "figures", group_by=group_by, max_iteration=max_iteration
        )
    return written


NOTES_MARKER = "<!-- notes: hand-written text below this line is kept when this file is regenerated -->"


def machine() -> str:
    """One line about the machine: cores, CPU model, Python and the load average when the report was written."""
    cpu = ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    load = (
        ", load average {:.1f} / {:.1f} / {:.1f} (1 / 5 / 15 min)".format(*os.getloadavg())
        if hasattr(os, "getloadavg")
        else ""
    )
    return f"{os.cpu_count()} cores{f' ({cpu})' if cpu else ''}, Python {sys.version.split()[0]}{load}"


def grid_markdown(grid: Grid) -> str:
    """Markdown list of a grid's settings: solvers, runs, budget, cases."""
    lines = []
    for task in grid.tasks:
        specs = [s for s in grid.specs if s.task == task.name]
        budget = json.loads(specs[0].budget)
        systems = list(dict.fromkeys(s.system for s in specs))
        lines += [
            (
                f"- task `{task.name}` ({task.path.name}): {len({(s.system, s.case) for s in specs})} case(s) on "
                f"{', '.join(systems)}"
            ),
            (
                f"- solvers: {', '.join(dict.fromkeys(s.solver for s in specs))}; "
                f"{len({s.seed for s in specs})} run(s) per case and solver (seeds {min(s.seed for s in specs)}.."
                f"{max(s.seed for s in specs)})"
            ),
            (
                f"- population {budget['population']}, {budget['max_iterations']} iterations, tolerance "
                f"{budget['tolerance']:g}, stop at tolerance: {budget['stop_at_tolerance']}"
            ),
        ]
    return "\n".join(lines)


def report_markdown(
    records: Sequence[RunRecord],
    *,
    tolerance: float,
    reference: str | None,
    group_by: str,
    figures: Mapping[str, Sequence[Path]] | None = None,
    relative_to: Path | None = None,
) -> str:
    """The body of a results document: per group the task-error table and its figures, then every term and the
    sign tests. ``figures``: group -> PNG paths, linked relative to ``relative_to``."""
    rows = summary_rows(records, group_by=group_by, tolerance=tolerance)
    parts = [
        (
            f"Task error = sum of the unweighted task terms; mean, sample std (ddof = 1), best, worst, median over the "
            f"runs; success = task error ≤ {tolerance:g}; time = wall time of one solve."
        ),
        "",
    ]
    for block in summary_markdown(rows, tolerance).split("### ")[1:]:
        group = block.split("\n", 1)[0]
        parts.append("### " + block.rstrip("\n") + "\n")
        for png in (figures or {}).get(group, ()):
            link = os.path.relpath(png, relative_to) if relative_to else str(png)
            parts.append(f"![{png.stem}]({Path(link).as_posix()})\n")
    parts += ["## Every term (mean ± std)", "", terms_markdown(rows)]
    if reference:
        parts += ["## Sign tests", "", sign_markdown(sign_rows(records, reference, group_by=group_by))]
    return "\n".join(parts)


def write_doc(path: str | Path, title: str, command: str, body: str) -> Path:
    """Write a generated results document: title, the command that made it, the machine, then ``body``.

    Text after :data:`NOTES_MARKER` in an existing file is kept (the hand-written analysis).
    """
    path = Path(path)
    notes = ""
    if path.is_file() and NOTES_MARKER in path.read_text():
        notes = path.read_text().split(NOTES_MARKER, 1)[1]
    header = [
        f"# {title}",
        "",
        f"Generated by `{command}` on {time.strftime('%Y-%m-%d')}; machine: {machine()}.",
        "",
    ]
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(header) + "\n" + body.rstrip("\n") + "\n\n" + NOTES_MARKER + (notes or "\n"))
    return path


def doc_figures(records: Sequence[RunRecord], doc: Path, *, group_by: str, max_iteration: int | None = None):
    """Figures of a results document, in ``<doc folder>/figures/bench/<doc name>_*.png``; group -> paths."""
    from . import plots

    out = doc.parent / "figures" / "bench"
    prefix = doc.stem + "_"
    plots.report_figures(records, out, group_by=group_by, max_iteration=max_iteration, prefix=prefix)
    return {
        group: [out / f"{prefix}{kind}_{plots.slug(group)}.png" for kind in ("boxplots", "convergence")]
        for group in group_records(records, group_by)
    }


