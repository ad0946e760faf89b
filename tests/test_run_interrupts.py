"""Ctrl-C at any moment of ``metaik run``: exit 130, one line saying what was done, and files that hold exactly
that (a CSV with its header and the waypoints solved, a recording that reads back with the robot and those
waypoints). Each signal is sent after an event the run shows (a line on stdout or stderr, rows in the CSV), not
after a fixed sleep."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

from tests.conftest import same_framework_env

TASK = "paper000_circular"


def _waypoints() -> int:
    from framework.io.taskfile import load_task, resolve_task

    return load_task(resolve_task(TASK)).cases[0].trajectory.K


WAYPOINTS = _waypoints()


def _default_sigint() -> None:
    """Ctrl-C's default action in the child, as in a terminal (a test run started in the background of a
    non-interactive shell ignores SIGINT, and a child would inherit that)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


class _Run:
    """A ``metaik run`` subprocess whose stdout and stderr are read as they come."""

    def __init__(self, folder: Path, *arguments: str, **environment: str):
        env = same_framework_env(PYTHONUNBUFFERED="1", **environment)
        self.process = subprocess.Popen(
            [sys.executable, "-m", "framework.cli", "run", TASK, "--record", "r.rrd", "--output", "r.csv",
             "--no-progress", *arguments], stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=folder, env=env,
            preexec_fn=_default_sigint)
        self.folder = folder
        self.out, self.err = bytearray(), bytearray()
        self._readers = [threading.Thread(target=self._read, args=(s, b), daemon=True)
                         for s, b in ((self.process.stdout, self.out), (self.process.stderr, self.err))]
        for reader in self._readers:
            reader.start()

    @staticmethod
    def _read(stream, into: bytearray) -> None:
        while chunk := os.read(stream.fileno(), 4096):
            into.extend(chunk)

    def wait_for(self, seen, what: str, timeout: float = 240.0) -> None:
        start = time.monotonic()
        while not seen():
            if self.process.poll() is not None or time.monotonic() - start > timeout:
                self.process.kill()
                raise AssertionError(f"never saw {what}; stdout: {self.out.decode()[-2000:]}\n"
                                     f"stderr: {self.err.decode()[-2000:]}")
            time.sleep(0.05)

    def interrupt(self, timeout: float = 60.0) -> tuple[int, str, str]:
        self.process.send_signal(signal.SIGINT)
        try:
            code = self.process.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.process.kill()
            raise AssertionError(f"SIGINT did not stop the run within {timeout} s: {self.err.decode()[-2000:]}")
        for reader in self._readers:
            reader.join(timeout=10)
        return code, self.out.decode(), self.err.decode()

    def csv_rows(self) -> int:
        path = self.folder / "r.csv"
        return max(len(path.read_text().splitlines()) - 1, 0) if path.exists() else 0


def _check_files(folder: Path, solved: int) -> None:
    """The CSV holds its header and ``solved`` rows; the recording reads back (robot, ``solved`` waypoints) and
    ``metaik replay --summary`` reads it."""
    from framework.io.recording import read_recording

    lines = (folder / "r.csv").read_text().splitlines()
    assert lines[0].startswith("case,k,") and len(lines) == 1 + solved
    recording = read_recording(folder / "r.rrd")
    assert any(e.startswith("/world/robot") for e in recording.entities)
    _, X, _ = recording.configurations("waypoint") if solved else (None, [], None)
    assert len(X) == solved
    summary = subprocess.run([sys.executable, "-m", "framework.cli", "replay", "r.rrd", "--summary"],
                             capture_output=True, text=True, cwd=folder, env=same_framework_env())
    assert summary.returncode == 0 and "Traceback" not in summary.stderr, summary.stderr


def _last_line(err: str) -> str:
    """The one line that says the run was interrupted (stderr also holds compile notices)."""
    lines = [line for line in err.splitlines() if line.startswith("interrupted")]
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


def test_ctrl_c_before_the_first_waypoint(tmp_path):
    """As the first waypoint's solve starts (its header printed just before; its 100,000 generations would take
    minutes): no waypoint done, an empty table, the CSV's header, a recording with the robot and no waypoint."""
    run = _Run(tmp_path, "--solver", "cmaes", "--iterations", "100000")  # pycma: Ctrl-C read each generation
    run.wait_for(lambda: TASK.encode() in run.out, "the run's header")
    code, out, err = run.interrupt()
    assert code == 130, (out, err)
    assert _last_line(err) == f"interrupted: 0 of {WAYPOINTS} waypoints solved (the table shows them)"
    assert "tracking with cmaes" in out  # the table (empty, or its case at 0 waypoints)
    _check_files(tmp_path, 0)


def test_ctrl_c_between_waypoints(tmp_path):
    """After a few waypoints (rows in the CSV): the line, the CSV and the recording agree on how many."""
    run = _Run(tmp_path, "--solver", "cmaes_fast")
    run.wait_for(lambda: run.csv_rows() >= 3, "three waypoints in the CSV")
    code, out, err = run.interrupt()
    assert code == 130, (out, err)
    last = _last_line(err)
    assert last.startswith("interrupted: ") and last.endswith(f" of {WAYPOINTS} waypoints solved (the table shows them)")
    solved = int(last.split()[1])
    assert 3 <= solved < WAYPOINTS
    _check_files(tmp_path, solved)


def test_ctrl_c_while_the_code_compiles(tmp_path):
    """With an empty compile cache, as soon as a compile is announced: the run stops at once (not after the
    compile), one line, and whatever files it had begun read back with nothing solved."""
    run = _Run(tmp_path, "--solver", "hybrid", METAIK_CACHE_DIR=str(tmp_path / "cache"))
    run.wait_for(lambda: b"metaik: compiling" in run.err, "a compile notice")
    code, out, err = run.interrupt(timeout=30.0)
    assert code == 130, (out, err)
    assert "interrupted" in _last_line(err)
    if (tmp_path / "r.csv").exists():
        _check_files(tmp_path, 0)
