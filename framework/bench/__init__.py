"""Benchmark harness: a grid of (task file, system, case, solver, seed) IK runs, in parallel, resumable.

The grid comes from task files (a top-level ``[bench]`` table) and command-line overrides::

    [bench]
    solvers = ["cmaes", "de", "sde"]     # default: [solver].name
    runs = 100                           # independent runs per (case, solver); seeds seed .. seed + runs - 1
    seed = 0
    reference = "de"                     # the sign test compares it against every other solver
    group_by = "case"                    # tables and figures per "case" or per "system" (cases pooled)
    random_reachable = 50                # optional: generated cases, targets = FK of random configurations
    case_seed = 1                        #   drawn uniformly within the limits by default_rng([case_seed, system])
    history_points = 200                 # best cost per iteration kept per run (downsampled); 0 keeps all
    [bench.options.de]                   # optional solver parameters by solver
    F = 0.6
    [[bench.systems]]                    # optional: the same task on other robots (default: the task's robot)
    robot = "baxter_dual"                # end-effector frames and joint groups of the task's robot are mapped
                                         # by position onto this robot's (index order)
    cases = [{ name = "p", t = [0.6, 0.6, 0.8] }]   # optional: this system's own cases

Generated cases (``random_reachable``) define, for every end-effector ``i`` (1-based, index order), the variables
``t_ee{i}`` (world position [m]) and ``R_ee{i}`` (world rotation), and ``q_ref`` (the sampled configuration).

Every finished run is appended to a JSON-lines results file as soon as it ends (so Ctrl-C or a crash loses at
most the runs in flight); re-running the same grid skips the runs already in the file. :func:`write_report`
then writes the summary tables (Markdown, CSV), the sign tests, boxplots and convergence curves.
"""

from .grid import (BENCH_KEYS, GRID_LIMIT, GROUP_BY, HISTORY_POINTS, ROBOT_OPTIONS, BenchCase, BenchTask, Grid,
                   RunSpec, RunSpecs, expand_task, plan, problem_fingerprint, random_reachable_cases)
from .record import RunRecord, downsample, execute
from .report import (NOTES_MARKER, doc_figures, grid_markdown, machine, report_markdown, write_doc,
                     write_report)
from .runner import RunReport, run_grid
from .store import drop_runs, grid_records, read_results

__all__ = ["BENCH_KEYS", "GRID_LIMIT", "GROUP_BY", "HISTORY_POINTS", "NOTES_MARKER", "ROBOT_OPTIONS", "BenchCase",
           "BenchTask", "Grid", "RunRecord", "RunReport", "RunSpec", "RunSpecs", "doc_figures", "downsample",
           "drop_runs", "execute", "expand_task",
           "grid_markdown", "grid_records", "machine", "plan", "problem_fingerprint", "random_reachable_cases",
           "read_results", "report_markdown", "run_grid", "write_doc", "write_report"]
