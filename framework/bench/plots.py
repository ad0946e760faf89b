"""Benchmark figures (matplotlib, Agg backend, PNG): boxplots per solver and convergence curves.

:func:`boxplots` and :func:`convergence` take plain arrays keyed by solver name and write one PNG;
:func:`report_figures` draws both for every group of a set of runs. matplotlib is imported lazily.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from .stats import Run, by_solver, convergence_curves, group_records

#: Smallest value drawn on a log axis (exact zeros, e.g. a motion error of 0, are drawn here).
LOG_FLOOR = 1e-18


def _pyplot():
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def boxplots(
    panels: Mapping[str, Mapping[str, np.ndarray]],
    path: str | Path,
    *,
    title: str = "",
    log: Sequence[str] = (),
) -> Path:
    """One boxplot panel per metric, one box per solver; saves a PNG.

    Args:
        panels: metric label (e.g. ``"position error [m]"``) -> solver -> values ``(runs,)``.
        path: the PNG to write (parent folders are created).
        title: figure title.
        log: metric labels drawn on a log axis (values below :data:`LOG_FLOOR` are drawn at the floor).
    """
    plt = _pyplot()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig, axes = plt.subplots(1, len(panels), figsize=(4.2 * len(panels), 3.8), squeeze=False)
    for ax, (label, values) in zip(axes[0], panels.items()):
        names = list(values)
        data = [np.asarray(values[s], dtype=float) for s in names]
        if label in log:
            data = [np.maximum(d, LOG_FLOOR) for d in data]
            ax.set_yscale("log")
        ax.boxplot(data, showfliers=True)
        ax.set_xticks(range(1, len(names) + 1), names, rotation=45, ha="right")
        ax.set_title(label, fontsize=10)
        ax.grid(True, axis="y", alpha=0.3)
    if title:
        fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def convergence(
    curves: Mapping[str, tuple[np.ndarray, np.ndarray]],
    path: str | Path,
    *,
    title: str = "",
    ylabel: str = "best cost",
    max_iteration: int | None = None,
) -> Path:
    """Convergence curves on a log axis (paper 000 Fig. 6, paper 002 Fig. 12); saves a PNG.

    Args:
        curves: solver -> (iterations ``(k,)`` 1-based, values ``(k,)``); values below :data:`LOG_FLOOR` are
            drawn at the floor.
        path: the PNG to write.
        title, ylabel: labels.
        max_iteration: draw only up to this iteration (paper 000 shows the first 300).
    """
    plt = _pyplot()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for name, (iterations, values) in curves.items():
        it = np.asarray(iterations, dtype=float)
        v = np.maximum(np.asarray(values, dtype=float), LOG_FLOOR)
        if max_iteration is not None:
            keep = it <= max_iteration
            it, v = it[keep], v[keep]
        ax.plot(it, v, label=name, linewidth=1.4)
    ax.set_yscale("log")
    ax.set_xlabel("iteration")
    ax.set_ylabel(ylabel)
    ax.grid(True, which="both", alpha=0.25)
    ax.legend(fontsize=8, ncol=2)
    if title:
        ax.set_title(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def slug(text: str) -> str:
    """A file-name fragment for a group label."""
    return "".join(c if c.isalnum() else "_" for c in text).strip("_").lower() or "all"


def report_figures(
    records: Sequence[Run],
    out_dir: str | Path,
    *,
    group_by: str = "case",
    max_iteration: int | None = None,
    prefix: str = "",
) -> list[Path]:
    """Boxplots (position / orientation / motion error, CPU or wall time) and convergence curves, one PNG each per
    group."""
    out = Path(out_dir)
    written = []
    panels_of = (
        ("position_error", "position error [m]"),
        ("orientation_error", "orientation error"),
        ("motion_error", "motion error"),
        ("cpu_time", "CPU time per solve [s]"),
        ("wall_time", "wall time per solve [s]"),
    )
    for group, members in group_records(records, group_by).items():
        solvers = by_solver(members)
        panels = {}
        for metric, label in panels_of:
            if metric == "wall_time" and "CPU time per solve [s]" in panels:
                continue  # CPU time when every run has it: robust to other load on the machine
            if not any(np.isnan(r.metric(metric)) for r in members):
                panels[label] = {s: np.array([r.metric(metric) for r in runs]) for s, runs in solvers.items()}
        log = [
            label
            for label, values in panels.items()
            if label != "motion error"
            and all(np.all(v > 0) for v in values.values())
            or label == "position error [m]"
        ]
        written.append(boxplots(panels, out / f"{prefix}boxplots_{slug(group)}.png", title=group, log=log))
    for group, curves in convergence_curves(records, group_by).items():
        written.append(
            convergence(
                curves,
                out / f"{prefix}convergence_{slug(group)}.png",
                title=f"{group}: best run of each solver",
                ylabel="best cost − f* (f* = lowest final cost of the case)",
                max_iteration=max_iteration,
            )
        )
    return written
