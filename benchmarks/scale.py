"""Scaling over workers: a benchmark grid and a reachability map on 1 and 2 workers of this machine.

Grid: ``metaik bench``'s runner (``framework.bench.run_grid``) on a grid of the shipped task
``youbot_dual_coordinated_ik`` (4 cases × CMA-ES and DE × 10 seeds, 1000 generations of 30), with the local process
pool (``-j``) and on a local Dask cluster (``--scheduler local``: worker processes started for the run; their start
is part of the time). Map: ``reachability_map`` of the youBot arm's end-effector (voxels of 4 cm over its
workspace, positions), with the compiled batch loop on 1 and 2 threads, and split over a local Dask cluster of
1 and 2 worker processes. Every configuration runs twice, alternated; the better time counts.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import report  # noqa: E402

import framework as fw  # noqa: E402
from framework.bench import plan, run_grid  # noqa: E402
from framework.reach.capability import reachability_map  # noqa: E402
from framework.io.taskfile import resolve_task  # noqa: E402

OUT = report.ROOT / "docs" / "results" / "scale.md"
REPEATS = 2


def grid_seconds(grid, **how) -> float:
    with tempfile.TemporaryDirectory() as folder:
        start = time.perf_counter()
        report_ = run_grid(grid, Path(folder) / "results.jsonl", progress=False, **how)
        assert report_.completed == len(grid.specs)
        return time.perf_counter() - start


def map_seconds(robot, **how) -> tuple[float, int]:
    start = time.perf_counter()
    result = reachability_map(robot, "ee", voxel=0.04, progress=False, **how)
    return time.perf_counter() - start, len(result.centers)


def main() -> None:
    before = report.load()
    grid = plan([resolve_task("youbot_dual_coordinated_ik")], solvers=["cmaes", "de"], runs=10, max_iterations=1000)
    arm = fw.load_robot("youbot_arm")
    map_seconds(arm, workers=1)  # load the compiled code
    variants = {
        ("grid", "process pool", 1): lambda: grid_seconds(grid, jobs=1),
        ("grid", "process pool", 2): lambda: grid_seconds(grid, jobs=2),
        ("grid", "local Dask cluster", 1): lambda: grid_seconds(grid, jobs=1, scheduler="local"),
        ("grid", "local Dask cluster", 2): lambda: grid_seconds(grid, jobs=2, scheduler="local"),
        ("map", "compiled batch, threads", 1): lambda: map_seconds(arm, workers=1)[0],
        ("map", "compiled batch, threads", 2): lambda: map_seconds(arm, workers=2)[0],
        ("map", "local Dask cluster", 1): lambda: map_seconds(arm, workers=1, scheduler="local")[0],
        ("map", "local Dask cluster", 2): lambda: map_seconds(arm, workers=2, scheduler="local")[0],
    }
    times: dict[tuple, list[float]] = {key: [] for key in variants}
    for _ in range(REPEATS):
        for key, run in variants.items():
            times[key].append(run())
            print(key, f"{times[key][-1]:.2f} s", flush=True)
    voxels = map_seconds(arm, workers=2)[1]
    after = report.load()
    lines = [__doc__.split("\n\n", 1)[1].strip(), "",
             f"Grid: {len(grid.specs)} runs. Map: {voxels} voxels.", "",
             "| job | how | workers | seconds | speed-up over 1 worker |", "|---|---|---:|---:|---:|"]
    for (job, how, workers), values in times.items():
        one = min(times[(job, how, 1)])
        lines.append(f"| {job} | {how} | {workers} | {min(values):.2f} | {one / min(values):.2f}x |")
    report.write(OUT, "Scaling over workers: grids and maps on 1 and 2 workers", "\n".join(lines),
                 loads=(before, after))
    print(OUT.read_text())


if __name__ == "__main__":
    main()
