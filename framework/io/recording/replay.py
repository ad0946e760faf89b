"""Opening recordings in the rerun viewer, and ``metaik replay``."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from ...errors import RecordingError
from .reader import read_recording, repair_recording


# ---------------------------------------------------------------------------------------------- replay
def replay_command_line(path: str | Path) -> list[str]:
    """The command that opens ``path`` in the rerun viewer (the viewer binary ships with rerun-sdk)."""
    return [sys.executable, "-m", "rerun", str(path)]


#: Seconds a viewer that fails at once (no display, a broken install) takes to exit: one still running then started.
START_WAIT = 5.0


def replay(path: str | Path, *, wait: bool = False) -> subprocess.Popen:
    """Open a recording in the rerun viewer (a separate process); ``wait=True`` blocks until it closes. A viewer
    that exits with an error within :data:`START_WAIT` seconds (no display, ...) is a :class:`RecordingError`
    holding its last line.

    A torn recording opens as its intact part (a repaired copy in the temporary folder)."""
    path = Path(path)
    if not path.is_file():
        raise RecordingError(f"recording {path} does not exist")
    if read_recording(path).torn:
        import tempfile

        repaired = Path(tempfile.mkdtemp(prefix="metaik-")) / path.name
        repair_recording(path, repaired)
        path = repaired
    import tempfile

    log = tempfile.TemporaryFile()
    try:
        process = subprocess.Popen(replay_command_line(path), stdout=log, stderr=subprocess.STDOUT)
    except OSError as err:
        raise RecordingError(f"cannot start the rerun viewer: {err}") from err
    try:
        code = process.wait(timeout=START_WAIT)
    except subprocess.TimeoutExpired:
        code = None
    if code:
        log.seek(0)
        lines = [line for line in log.read().decode(errors="replace").splitlines() if line.strip()]
        raise RecordingError(f"the rerun viewer did not start (exit {code}): {lines[-1] if lines else 'no output'}")
    if wait:
        process.wait()
    return process
