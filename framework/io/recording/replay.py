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


def replay(path: str | Path, *, wait: bool = False) -> subprocess.Popen:
    """Open a recording in the rerun viewer (a separate process); ``wait=True`` blocks until it closes.

    A torn recording opens as its intact part (a repaired copy in the temporary folder)."""
    path = Path(path)
    if not path.is_file():
        raise RecordingError(f"recording {path} does not exist")
    if read_recording(path).torn:
        import tempfile

        repaired = Path(tempfile.mkdtemp(prefix="metaik-")) / path.name
        repair_recording(path, repaired)
        path = repaired
    try:
        process = subprocess.Popen(replay_command_line(path))
    except OSError as err:
        raise RecordingError(f"cannot start the rerun viewer: {err}") from err
    if wait:
        process.wait()
    return process
