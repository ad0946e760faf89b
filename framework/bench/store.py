"""The results file: JSON lines, one finished run each, read back by run key; torn tails dropped."""


from __future__ import annotations

import json
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from ..errors import MetaikError
from .grid import Grid
from .record import RunRecord


# ---------------------------------------------------------------------------------------------- the results file
def read_results(path: str | Path, keys: set[tuple] | None = None) -> list[RunRecord]:
    """Records of a results file (only those whose key is in ``keys``, if given); a torn last line is skipped."""
    path = Path(path)
    if not path.is_file():
        return []
    records, seen = [], set()
    with path.open() as f:
        for line in f:
            try:
                record = RunRecord.from_json(line)
            except (json.JSONDecodeError, TypeError):
                continue  # a line torn by a crash: that run is simply run again
            if (keys is None or record.key in keys) and record.key not in seen:
                seen.add(record.key)  # a run written twice (by a bench of an older version) counts once
                records.append(record)
    return records


def grid_records(grid: Grid, results: str | Path) -> list[RunRecord]:
    """The records of ``grid``'s runs found in ``results``, in grid order (so tables list solvers as given)."""
    order = {spec.key: i for i, spec in enumerate(grid.specs)}
    return sorted(read_results(results, set(order)), key=lambda r: order[r.key])


def drop_runs(results: str | Path, keys: set[tuple]) -> int:
    """Remove the records with these keys from a results file (e.g. to re-run them after a code change).

    Returns how many were removed; the file is rewritten through a temporary file and an atomic rename, under
    the file's lock (no bench may be writing it meanwhile).
    """
    results = Path(results)
    if not results.is_file():
        return 0
    with exclusive(results):
        return _drop_runs(results, keys)


def _drop_runs(results: Path, keys: set[tuple]) -> int:
    kept, removed = [], 0
    for line in results.read_text().splitlines(keepends=True):
        try:
            drop = RunRecord.from_json(line).key in keys
        except (json.JSONDecodeError, TypeError):
            drop = False
        removed += drop
        if not drop:
            kept.append(line)
    tmp = results.with_name(results.name + ".tmp")
    tmp.write_text("".join(kept))
    os.replace(tmp, results)
    return removed


def drop_torn_tail(path: Path) -> None:
    """Cut a results file after its last complete line (a crash may have torn the last one)."""
    if not path.is_file() or path.stat().st_size == 0:
        return
    data = path.read_bytes()
    if not data.endswith(b"\n"):
        path.write_bytes(data[: data.rfind(b"\n") + 1])


@contextmanager
def exclusive(results: Path) -> Iterator[None]:
    """Hold the results file's lock (``<file>.lock``) for the whole run: a second bench on the same file is an
    error, not a second writer of the same runs."""
    import fcntl

    lock = results.with_name(results.name + ".lock").open("a")
    try:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        lock.close()
        raise MetaikError(f"another bench is writing {results}; wait for it, or give another --out") from None
    try:
        yield
    finally:
        fcntl.flock(lock, fcntl.LOCK_UN)
        lock.close()
