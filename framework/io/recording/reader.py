"""Reading recordings back: :func:`read_recording` -> :class:`Recording` (entities, timelines, logged values),
with rerun's own reader; a torn file (a run killed while writing) is read up to its last complete message."""

from __future__ import annotations

import dataclasses
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...errors import RecordingError


# ---------------------------------------------------------------------------------------------- reading
@dataclass(frozen=True)
class Recording:
    """A recording read back with rerun's own reader (:class:`rerun.chunk.RrdReader`).

    Attributes:
        path: the file.
        complete: False when the file has no footer (its writer did not close it, e.g. it crashed).
        entities: entity paths holding data (``"/world/robot/skeleton"``, ...).
        timelines: every timeline of the recording (``"solution"``, ``"iteration"``, ``"waypoint"``).
        torn: ``None``, or where a torn file stops (its writer was killed mid-message): what was recovered is
            every message before that point.
    """

    path: Path
    complete: bool
    entities: tuple[str, ...]
    timelines: frozenset[str]
    torn: str | None = None
    _batches: dict[str, list] = field(repr=False, default_factory=dict)

    def _rows(self, entity: str) -> list:
        entity = entity if entity.startswith("/") else f"/{entity}"
        if entity not in self._batches:
            raise RecordingError(
                f"{self.path} has no entity {entity!r}; entities: {', '.join(self.entities)}"
            )
        return self._batches[entity]

    def components(self, entity: str) -> tuple[str, ...]:
        """Component columns logged at ``entity`` (``"Scalars:scalars"``, ``"LineStrips3D:strips"``, ...)."""
        names = {n for batch in self._rows(entity) for n in batch.schema.names}
        return tuple(sorted(n for n in names if ":" in n and not n.startswith("rerun.")))

    def values(self, entity: str, component: str, timeline: str | None = None) -> tuple[np.ndarray, list]:
        """Times on ``timeline`` and logged values of one component, sorted by time.

        With ``timeline=None`` only static values are returned (times are then all ``-1``).
        """
        times, values = [], []
        for batch in self._rows(entity):
            names = batch.schema.names
            if component not in names:
                continue
            if timeline is None:
                if any(n in self.timelines for n in names):
                    continue
                t = np.full(batch.num_rows, -1)
            elif timeline in names:
                t = np.asarray(batch.column(timeline).to_pylist())
            else:
                continue
            times.append(t)
            values += batch.column(component).to_pylist()
        if not times:
            return np.zeros(0, dtype=int), []
        t = np.concatenate(times)
        order = np.argsort(t, kind="stable")
        return t[order], [values[i] for i in order]

    def scalars(self, entity: str, timeline: str) -> tuple[np.ndarray, np.ndarray]:
        """``(times, values)`` of a scalar series (one scalar per row) on ``timeline``."""
        t, v = self.values(entity, "Scalars:scalars", timeline)
        return t, np.array([row[0] for row in v], dtype=float)

    def count(self, entity: str, timeline: str, component: str | None = None) -> int:
        """Number of rows logged at ``entity`` on ``timeline`` (e.g. the number of poses of the robot)."""
        component = component or self.components(entity)[0]
        return len(self.values(entity, component, timeline)[0])

    def configurations(self, timeline: str) -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
        """``(times, X (K, n), coordinate names)``: the joint values recorded on ``timeline`` (``"solution"`` or
        ``"waypoint"``), as solved — to replay them on the model, reload or continue a run."""
        entity = "/world/robot/configuration"
        _, names = self.values(entity, "coordinate_names")
        if not names:
            raise RecordingError(f"{self.path} holds no joint values (recorded before they were)")
        times, rows = self.values(entity, "joint_values", timeline)
        X = np.array(rows, dtype=float).reshape(len(rows), len(names[-1]))
        return times, X, tuple(names[-1])

    def text(self, entity: str) -> str:
        """The (last) text of a static TextDocument."""
        _, values = self.values(entity, "TextDocument:text")
        if not values:
            raise RecordingError(f"{entity} holds no text document")
        return values[-1][0]


#: An ``.rrd`` file: a 12-byte stream header (``RRF2``, version, options), then messages, each a 16-byte header
#: (kind, payload length: two little-endian u64) and its payload; kind 0 ends the stream (a footer follows).
RRD_MAGIC, STREAM_HEADER, MESSAGE_HEADER = b"RRF2", 12, 16


def intact_messages(data: bytes) -> tuple[int, int, str | None]:
    """``(end, messages, torn)``: the byte offset after the last complete message of an ``.rrd`` stream, how many
    messages precede it, and ``None`` if the stream is whole up to its end marker, else where and how it is cut."""
    if data[:4] != RRD_MAGIC or len(data) < STREAM_HEADER:
        raise RecordingError("not a rerun recording (no RRF2 stream header)")
    offset, count = STREAM_HEADER, 0
    while offset + MESSAGE_HEADER <= len(data):
        kind = int.from_bytes(data[offset:offset + 8], "little")
        length = int.from_bytes(data[offset + 8:offset + 16], "little")
        if kind == 0:
            if offset + MESSAGE_HEADER + length <= len(data):
                return offset, count, None
            return offset, count, f"cut in its footer, after all {count} messages"
        if offset + MESSAGE_HEADER + length > len(data):
            break
        offset += MESSAGE_HEADER + length
        count += 1
    if offset == len(data):
        return offset, count, f"ends after {count} complete messages, without an end marker (its writer was stopped)"
    return offset, count, (f"cut at byte {len(data):,} of message {count + 1} (starting at byte {offset:,}); "
                           f"{count} complete messages recovered")


def read_recording(path: str | Path) -> Recording:
    """Read a ``.rrd`` file back: its entities, timelines and every logged value (see :class:`Recording`).

    A torn file (its writer killed while writing) is read up to its last complete message; ``torn`` says where
    it stops."""
    path = Path(path)
    if not path.is_file():
        raise RecordingError(f"recording {path} does not exist")
    if path.stat().st_size == 0:
        raise RecordingError(f"recording {path} is empty: its writer stopped before writing anything")
    try:
        recording = _read(path, path)
        if recording.complete:
            return recording
        _, count, torn = intact_messages(path.read_bytes())
        return dataclasses.replace(recording, torn=torn or f"all {count} messages whole; its footer is cut")
    except RecordingError as err:
        data = path.read_bytes()
        try:
            end, count, torn = intact_messages(data)
        except RecordingError:
            raise err from None
        if torn is None or count == 0:
            raise
    import tempfile

    with tempfile.TemporaryDirectory() as folder:
        intact = Path(folder) / path.name
        intact.write_bytes(data[:end])
        recording = _read(intact, path)
    return Recording(path, False, recording.entities, recording.timelines, torn, recording._batches)


def repair_recording(path: str | Path, out: str | Path) -> str | None:
    """Write the intact part of a torn recording ``path`` to ``out`` (the whole file if it is not torn); returns
    where it was cut (``None``: not torn)."""
    torn = read_recording(path).torn
    data = Path(path).read_bytes()
    Path(out).write_bytes(data if torn is None else data[:intact_messages(data)[0]])
    return torn


def _read(file: Path, path: Path) -> Recording:
    from rerun.chunk import RrdReader

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            chunks = RrdReader(file).stream().to_chunks()
        except Exception as err:  # rerun raises ValueError / OSError on files that are not recordings
            raise RecordingError(f"{path} is not a readable rerun recording: {err}") from err
    complete = not any("footer" in str(w.message) for w in caught)
    batches: dict[str, list] = {}
    timelines: set[str] = set()
    for chunk in chunks:
        if chunk.entity_path.startswith("/__"):
            continue
        batches.setdefault(chunk.entity_path, []).append(chunk.to_record_batch())
        timelines.update(chunk.timeline_names)
    return Recording(path, complete, tuple(sorted(batches)), frozenset(timelines), None, batches)
