"""Grids and batches on a real Dask cluster: a scheduler and two worker processes on 127.0.0.1."""

from __future__ import annotations

import dataclasses
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import distributed
import numpy as np
import pytest

import framework as fw
from framework.bench import plan, read_results, run_grid
from framework.solvers.cluster import ClusterError, cluster_client

from tests.test_bench import SMALL



def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _worker(address: str, name: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", address, "--nthreads", "1",
                             "--no-nanny", "--no-dashboard", "--name", name, "--host", "127.0.0.1"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


@pytest.fixture(scope="module")
def cluster():
    """``(address, {name: worker process})``: a scheduler and two single-thread workers, killed at the end."""
    address = f"tcp://127.0.0.1:{_free_port()}"
    scheduler = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
                                  "--port", address.rsplit(":", 1)[1], "--no-dashboard"],
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    workers = {name: _worker(address, name) for name in ("w1", "w2")}
    try:
        with distributed.Client(address, timeout="60s") as client:
            client.wait_for_workers(2, timeout=120)
        yield address, workers
    finally:
        for process in [*workers.values(), scheduler]:
            process.kill()
            process.wait()


def _without_time(record) -> dict:
    return {k: v for k, v in dataclasses.asdict(record).items() if k not in ("wall_time", "cpu_time")}


def _grid(tmp_path: Path, runs: int, iterations: int):
    path = tmp_path / "small.toml"
    path.write_text(SMALL)
    return plan([path], runs=runs, max_iterations=iterations)


def test_a_grid_on_the_cluster_gives_the_local_rows(cluster, tmp_path):
    address, _ = cluster
    grid = _grid(tmp_path, runs=3, iterations=40)
    local, remote = tmp_path / "local.jsonl", tmp_path / "remote.jsonl"
    run_grid(grid, local, jobs=1, progress=False)
    report = run_grid(grid, remote, scheduler=address, chunk_size=2, progress=False)
    assert report.completed == len(grid.specs) == 12
    ours = {r.key: _without_time(r) for r in read_results(local)}
    theirs = {r.key: _without_time(r) for r in read_results(remote)}
    assert ours == theirs


def test_a_batch_split_over_the_workers_equals_the_local_batch(cluster):
    address, _ = cluster
    robot = fw.load_robot("puma560")
    rng = np.random.default_rng(4)
    Q = robot.lower + (robot.upper - robot.lower) * rng.random((120, robot.n))
    T = np.array([robot.frame_placement(q, "ee").homogeneous for q in Q])
    problem = fw.Problem(robot, fw.Pose("ee", T[0]))
    here = fw.solve_batch(problem, T, seed=9, progress=False)
    there = fw.solve_batch(problem, T, seed=9, scheduler=address)
    np.testing.assert_array_equal(there.configurations, here.configurations)
    np.testing.assert_array_equal(there.success, here.success)
    np.testing.assert_array_equal(there.errors, here.errors)
    assert there.success.all()


def test_killing_a_worker_mid_grid_loses_and_duplicates_nothing(cluster, tmp_path):
    """Runs last in this module: it kills worker w2 for good (no nanny restarts it)."""
    address, workers = cluster
    grid = _grid(tmp_path, runs=12, iterations=1500)
    results = tmp_path / "remote.jsonl"
    at_kill: list[int] = []

    def kill_when_started() -> None:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            done = len(results.read_text().splitlines()) if results.exists() else 0
            if done >= 6:
                os.kill(workers["w2"].pid, signal.SIGKILL)
                at_kill.append(done)
                return
            time.sleep(0.02)

    killer = threading.Thread(target=kill_when_started)
    killer.start()
    report = run_grid(grid, results, scheduler=address, chunk_size=2, progress=False)
    killer.join()
    assert workers["w2"].poll() is not None and at_kill[0] < 40  # killed while most of the grid was to run
    keys = [r.key for r in read_results(results)]
    assert report.completed == len(keys) == len(set(keys)) == len(grid.specs) == 48
    local = tmp_path / "local.jsonl"
    run_grid(grid, local, jobs=1, progress=False)
    assert {r.key: _without_time(r) for r in read_results(local)} == {
        r.key: _without_time(r) for r in read_results(results)}


def test_unreachable_scheduler_is_a_named_error():
    with pytest.raises(ClusterError, match="cannot reach"):
        with cluster_client(f"tcp://127.0.0.1:{_free_port()}"):
            pass
    with pytest.raises(ClusterError, match="tcp://HOST:PORT"):
        with cluster_client("127.0.0.1:8786"):
            pass
