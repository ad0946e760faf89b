"""Process checks read from ``/proc`` (Linux): a process's running children, which of some processes still run.
Used by the kill tests and ``benchmarks/reliability.py``."""

from __future__ import annotations

from pathlib import Path


def _state_and_parent(stat: Path) -> tuple[str, int] | None:
    try:
        fields = stat.read_text().rsplit(")", 1)[1].split()
    except OSError:  # the process ended meanwhile
        return None
    return fields[0], int(fields[1])


def children(pid: int) -> list[int]:
    """Process ids of ``pid``'s children that are not zombies."""
    found = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        read = _state_and_parent(stat)
        if read is not None and read[1] == pid and read[0] != "Z":
            found.append(int(stat.parent.name))
    return found


def alive(pids: list[int]) -> list[int]:
    """Those of ``pids`` still running (not ended, not zombies)."""
    out = []
    for pid in pids:
        read = _state_and_parent(Path(f"/proc/{pid}/stat"))
        if read is not None and read[0] != "Z":
            out.append(pid)
    return out
