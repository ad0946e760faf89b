"""Trajectories as data: ``K`` waypoints of a frame, positions [m] and optional orientations, in the world frame.

A :class:`Trajectory` is an immutable value: build one from your own arrays or files, or from the papers' paths
and plane curves (:mod:`~framework.tracking.paths`), and compose them in code::

    from framework.tracking import paths, trajectory as tr

    circle = paths.circle(centre=(0.5, 0.25, 0.45), radius=0.05, points=200)     # paper 000, circular
    path = paths.line((0.5, 0.2, 0.4), circle.positions[0], points=20).then(circle)
    path = path.offset((0.0, -0.1, 0.0))                                         # move it 10 cm
    path.to_csv("path.csv"); same = tr.Trajectory.from_file("path.csv")
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import TaskError

ArrayLike = Sequence[float] | np.ndarray

#: Column names of the CSV format: positions [m], then an optional ``(x, y, z, w)`` quaternion (scalar last).
CSV_COLUMNS = ("x", "y", "z", "qx", "qy", "qz", "qw")


# ---------------------------------------------------------------------------------------------- rotations
def Rx(angle: float) -> np.ndarray:
    """Rotation about the world x-axis by ``angle`` [rad], ``(3, 3)``."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def Ry(angle: float) -> np.ndarray:
    """Rotation about the world y-axis by ``angle`` [rad], ``(3, 3)``; paper 002's ``R_d = Ry(π/2)``."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def Rz(angle: float) -> np.ndarray:
    """Rotation about the world z-axis by ``angle`` [rad], ``(3, 3)``."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _matrices_from_quaternions(Q: np.ndarray) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    return Rotation.from_quat(Q).as_matrix()


def _quaternions_from_matrices(R: np.ndarray) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    return Rotation.from_matrix(R).as_quat()


# ---------------------------------------------------------------------------------------------- the value
@dataclass(frozen=True, eq=False)
class Trajectory:
    """``K`` waypoints for one frame, in the world frame.

    Attributes:
        positions: ``(K, 3)`` waypoint positions [m].
        rotations: ``(K, 3, 3)`` world-from-frame rotations of the waypoints, or ``None`` (position only).
        name: label for reports and plots.
        times: ``(K,)`` when each waypoint is to be met [s], strictly increasing, or ``None`` (untimed: waypoints
            only); :meth:`timed` gives a path times from a rate or a duration.

    Raises:
        TaskError: wrong shapes, NaN/inf, fewer than one waypoint, or matrices that are not rotations.
    """

    positions: np.ndarray
    rotations: np.ndarray | None = None
    name: str = field(default="path", compare=False)
    times: np.ndarray | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        P = np.array(self.positions, dtype=float)
        if P.ndim != 2 or P.shape[1] != 3 or P.shape[0] < 1:
            raise TaskError(
                f"trajectory {self.name!r}: positions must have shape (K, 3) with K >= 1; got {P.shape}"
            )
        _check_finite(P, f"trajectory {self.name!r}: positions")
        P.flags.writeable = False
        object.__setattr__(self, "positions", P)
        if self.times is not None:
            t = np.array(self.times, dtype=float)
            if t.shape != (P.shape[0],) or not np.isfinite(t).all() or (np.diff(t) <= 0).any():
                raise TaskError(f"trajectory {self.name!r}: times must be {P.shape[0]} finite, strictly increasing "
                                f"seconds (one per waypoint); got {np.asarray(self.times).tolist()}")
            t.flags.writeable = False
            object.__setattr__(self, "times", t)
        if self.rotations is None:
            return
        R = np.array(self.rotations, dtype=float)
        if R.shape == (3, 3):
            R = np.broadcast_to(R, (P.shape[0], 3, 3)).copy()
        if R.shape != (P.shape[0], 3, 3):
            raise TaskError(
                f"trajectory {self.name!r}: rotations must have shape ({P.shape[0]}, 3, 3) or (3, 3); got {R.shape}"
            )
        _check_finite(R, f"trajectory {self.name!r}: rotations")
        error = np.abs(np.einsum("kji,kjl->kil", R, R) - np.eye(3)).max(axis=(1, 2))
        bad = np.flatnonzero((error > 1e-6) | (np.linalg.det(R) < 0))
        if bad.size:
            raise TaskError(
                f"trajectory {self.name!r}: rotations of waypoints {bad[:5].tolist()} are not rotation matrices"
            )
        R.flags.writeable = False
        object.__setattr__(self, "rotations", R)

    # ------------------------------------------------------------------ sizes and access
    def __len__(self) -> int:
        return self.positions.shape[0]

    @property
    def K(self) -> int:
        """Number of waypoints."""
        return self.positions.shape[0]

    @property
    def has_orientation(self) -> bool:
        return self.rotations is not None

    @property
    def is_timed(self) -> bool:
        return self.times is not None

    def timed(self, *, rate: float | None = None, duration: float | None = None,
              times: ArrayLike | None = None) -> Trajectory:
        """The same waypoints met at ``rate`` [Hz] from ``t = 0``, spread evenly over ``duration`` [s], or at
        ``times`` ``(K,)`` [s] (exactly one of them)."""
        given = [v for v in (rate, duration, times) if v is not None]
        if len(given) != 1:
            raise TaskError("timed() takes exactly one of rate [Hz], duration [s] or times (K,) [s]")
        if rate is not None:
            if not (isinstance(rate, (int, float)) and 0 < rate < np.inf):
                raise TaskError(f"rate must be a frequency > 0 [Hz]; got {rate!r}")
            times = np.arange(self.K) / float(rate)
        elif duration is not None:
            if not (isinstance(duration, (int, float)) and 0 < duration < np.inf) or self.K < 2:
                raise TaskError(f"duration must be > 0 [s] for a path of two or more waypoints; got {duration!r}")
            times = np.linspace(0.0, float(duration), self.K)
        return Trajectory(self.positions, self.rotations, self.name, times)

    @property
    def intervals(self) -> np.ndarray:
        """``(K - 1,)`` seconds between consecutive waypoints (a timed path)."""
        if self.times is None:
            raise TaskError(f"trajectory {self.name!r} has no times: Trajectory.timed(rate=..., duration=...)")
        return np.diff(self.times)

    def rotation(self, k: int) -> np.ndarray | None:
        """``(3, 3)`` rotation of waypoint ``k``, or ``None`` for a position-only trajectory."""
        return None if self.rotations is None else self.rotations[k]

    def __getitem__(self, index: int | slice | Sequence[int] | np.ndarray) -> Trajectory:
        """A sub-trajectory (``path[::4]``, ``path[:10]``, ``path[[0, 5, 9]]``); an int keeps one waypoint."""
        idx = [index] if isinstance(index, (int, np.integer)) else index
        P = self.positions[idx]
        R = None if self.rotations is None else self.rotations[idx]
        return Trajectory(P, R, self.name, None if self.times is None else self.times[idx])

    @property
    def length(self) -> float:
        """Length of the polyline through the waypoints [m]."""
        return float(np.linalg.norm(np.diff(self.positions, axis=0), axis=1).sum())

    @property
    def spacing(self) -> np.ndarray:
        """``(K - 1,)`` distances between consecutive waypoints [m]."""
        return np.linalg.norm(np.diff(self.positions, axis=0), axis=1)

    # ------------------------------------------------------------------ composition
    def offset(self, delta: ArrayLike) -> Trajectory:
        """The same path translated by ``delta`` ``(3,)`` [m] (world axes); orientations unchanged."""
        return Trajectory(self.positions + point3(delta, "offset"), self.rotations, self.name, self.times)

    def transformed(
        self, rotation: np.ndarray | None = None, translation: ArrayLike = (0.0, 0.0, 0.0)
    ) -> Trajectory:
        """The path moved rigidly: ``p' = R p + t`` and ``R_k' = R R_k`` (rotation about the world origin)."""
        R = np.eye(3) if rotation is None else _rotation(rotation, "rotation")
        P = self.positions @ R.T + point3(translation, "translation")
        rotations = None if self.rotations is None else np.einsum("ij,kjl->kil", R, self.rotations)
        return Trajectory(P, rotations, self.name, self.times)

    def with_orientation(self, rotation: np.ndarray | None) -> Trajectory:
        """The same positions with orientation ``rotation`` (``(3, 3)`` for all waypoints or ``(K, 3, 3)``);
        ``None`` drops the orientation."""
        return Trajectory(self.positions, rotation, self.name, self.times)

    def reversed(self) -> Trajectory:
        """The waypoints in reverse order (a timed path: the same intervals, in reverse)."""
        times = None if self.times is None else self.times[-1] - self.times[::-1]
        return Trajectory(self.positions[::-1], None if self.rotations is None else self.rotations[::-1], self.name,
                          times)

    def then(self, *others: Trajectory) -> Trajectory:
        """This path followed by ``others`` (see :func:`concatenate`)."""
        return concatenate(self, *others, name=self.name)

    def renamed(self, name: str) -> Trajectory:
        return Trajectory(self.positions, self.rotations, name, self.times)

    # ------------------------------------------------------------------ files
    def to_array(self) -> np.ndarray:
        """``(K, 3)`` positions, or ``(K, 7)`` positions and ``(x, y, z, w)`` quaternions."""
        if self.rotations is None:
            return self.positions.copy()
        return np.hstack([self.positions, _quaternions_from_matrices(self.rotations)])

    @classmethod
    def from_array(cls, array: np.ndarray, name: str = "path") -> Trajectory:
        """From ``(K, 3)`` positions, ``(K, 7)`` positions + ``(x, y, z, w)`` quaternions, or ``(K, 12)``
        positions + row-major rotation matrices."""
        A = np.array(array, dtype=float)
        if A.ndim != 2 or A.shape[1] not in (3, 7, 12):
            raise TaskError(
                f"trajectory {name!r}: an array of waypoints must have shape (K, 3), (K, 7) or (K, 12); got {A.shape}"
            )
        _check_finite(A, f"trajectory {name!r}")
        if A.shape[1] == 3:
            return cls(A, None, name)
        if A.shape[1] == 12:
            return cls(A[:, :3], A[:, 3:].reshape(-1, 3, 3), name)
        norms = np.linalg.norm(A[:, 3:], axis=1)
        if np.any(norms < 1e-9):
            raise TaskError(
                f"trajectory {name!r}: zero quaternion at waypoints {np.flatnonzero(norms < 1e-9)[:5].tolist()}"
            )
        return cls(A[:, :3], _matrices_from_quaternions(A[:, 3:] / norms[:, None]), name)

    def to_csv(self, path: str | Path) -> None:
        """Write ``x,y,z[,qx,qy,qz,qw]`` with a header line, full precision."""
        A = self.to_array()
        header = ",".join(CSV_COLUMNS[: A.shape[1]])
        np.savetxt(Path(path), A, delimiter=",", header=header, comments="", fmt="%.17g")

    def save(self, path: str | Path) -> None:
        """Write ``.csv`` (:meth:`to_csv`), ``.npy`` (:meth:`to_array`) or ``.npz`` (``positions``, ``rotations``)."""
        path = Path(path)
        if path.suffix == ".csv":
            self.to_csv(path)
        elif path.suffix == ".npy":
            np.save(path, self.to_array())
        elif path.suffix == ".npz":
            arrays = {"positions": self.positions}
            if self.rotations is not None:
                arrays["rotations"] = self.rotations
            np.savez(path, **arrays)
        else:
            raise TaskError(f"cannot save a trajectory as {path.name}: use .csv, .npy or .npz")

    @classmethod
    def from_file(cls, path: str | Path, name: str | None = None) -> Trajectory:
        """Read a ``.csv`` (header ``x,y,z[,qx,qy,qz,qw]`` optional), ``.npy`` or ``.npz`` file."""
        path = Path(path)
        name = name or path.stem
        if not path.is_file():
            raise TaskError(f"trajectory file {path} does not exist")
        try:
            if path.suffix == ".csv":
                A = _read_csv(path)
            elif path.suffix == ".npy":
                A = np.load(path, allow_pickle=False)
            elif path.suffix == ".npz":
                with np.load(path, allow_pickle=False) as data:
                    if "positions" not in data:
                        raise TaskError(f"{path}: an .npz trajectory needs a 'positions' array")
                    rotations = data.get("rotations", None)
                    return cls(data["positions"], rotations, name)
            else:
                raise TaskError(f"cannot read a trajectory from {path.name}: use .csv, .npy or .npz")
        except (ValueError, OSError) as err:
            raise TaskError(f"{path}: not a readable trajectory file: {err}") from err
        try:
            return cls.from_array(A, name)
        except TaskError as err:
            raise TaskError(f"{path}: {err}") from None


def _read_csv(path: Path) -> np.ndarray:
    lines = [
        line for line in path.read_text().splitlines() if line.strip() and not line.lstrip().startswith("#")
    ]
    if not lines:
        raise TaskError(f"{path}: the file holds no waypoints")
    first = [c.strip().lower() for c in lines[0].split(",")]
    if first and not _is_number(first[0]):
        expected = list(CSV_COLUMNS[: len(first)])
        if first != expected:
            raise TaskError(
                f"{path}: header must be {','.join(expected)} (positions [m], quaternion x,y,z,w); got {lines[0]!r}"
            )
        lines = lines[1:]
    rows = []
    for i, line in enumerate(lines):
        try:
            rows.append([float(c) for c in line.split(",")])
        except ValueError:
            raise TaskError(f"{path}: line {i + 2} is not a row of numbers: {line!r}") from None
    widths = {len(r) for r in rows}
    if len(widths) != 1:
        raise TaskError(f"{path}: rows have different numbers of columns {sorted(widths)}")
    return np.array(rows, dtype=float)


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _check_finite(A: np.ndarray, what: str) -> None:
    if not np.all(np.isfinite(A)):
        rows = np.unique(np.nonzero(~np.isfinite(A.reshape(A.shape[0], -1)))[0])
        raise TaskError(f"{what} hold NaN or inf (waypoints {rows[:5].tolist()})")


def point3(value: ArrayLike, what: str) -> np.ndarray:
    v = np.asarray(value, dtype=float)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise TaskError(f"{what} must be 3 finite numbers [m]; got {value!r}")
    return v


def _rotation(value: np.ndarray, what: str) -> np.ndarray:
    R = np.asarray(value, dtype=float)
    if R.shape != (3, 3) or not np.all(np.isfinite(R)) or not np.allclose(R.T @ R, np.eye(3), atol=1e-6):
        raise TaskError(f"{what} must be a (3, 3) rotation matrix")
    return R


def concatenate(*trajectories: Trajectory, name: str | None = None) -> Trajectory:
    """One trajectory through all waypoints of ``trajectories`` in order.

    Either all have orientations or none; either all are timed or none (each timed piece then follows the last
    one's end, its first interval kept before its first waypoint). A waypoint repeated at a junction (the end of one
    piece equal to the start of the next, within 1e-12 m) is kept once (at the earlier time).
    """
    if not trajectories:
        raise TaskError("concatenate needs at least one trajectory")
    oriented = {t.has_orientation for t in trajectories}
    if len(oriented) != 1:
        raise TaskError(
            "cannot concatenate trajectories with and without orientation; use with_orientation()"
        )
    timed = {t.is_timed for t in trajectories}
    if len(timed) != 1:
        raise TaskError("cannot concatenate timed and untimed trajectories; time them all (timed()) or none")
    P, R = [trajectories[0].positions], [trajectories[0].rotations]
    T = [trajectories[0].times]
    for t in trajectories[1:]:
        start = 1 if np.linalg.norm(t.positions[0] - P[-1][-1]) < 1e-12 else 0
        P.append(t.positions[start:])
        R.append(None if t.rotations is None else t.rotations[start:])
        if timed == {True}:
            gap = t.times[1] - t.times[0] if t.K > 1 else 1.0
            shift = T[-1][-1] - t.times[0] + (0.0 if start else gap)
            T.append(t.times[start:] + shift)
    rotations = np.concatenate(R) if oriented == {True} else None
    times = np.concatenate(T) if timed == {True} else None
    return Trajectory(np.concatenate(P), rotations, name or "+".join(t.name for t in trajectories), times)


# ---------------------------------------------------------------------------------------------- shapes
