"""Trajectories as data: ``K`` waypoints of a frame, positions [m] and optional orientations, in the world frame.

A :class:`Trajectory` is an immutable value. Build one from the papers' paths, from your own arrays or files,
and compose them in code::

    from framework import trajectory as tr

    circle = tr.circle(centre=(0.5, 0.25, 0.45), radius=0.05, points=200)        # paper 000, circular
    tool_down = tr.circle((0.3, 0.2, 0.5), 0.05, points=32, orientation=tr.Ry(np.pi / 2))
    path = tr.line((0.5, 0.2, 0.4), circle.positions[0], points=20).then(circle)
    path = path.offset((0.0, -0.1, 0.0))                                         # move it 10 cm
    path.to_csv("path.csv"); same = tr.Trajectory.from_file("path.csv")

Plane curves (circle, lemniscate, rose, sinusoid) are drawn in a plane through their centre spanned by two
world axes, ``plane="yz"`` by default: the first letter is the curve's horizontal coordinate ``u``, the second
its vertical ``v`` (paper 000 draws every path in the plane ``x = 0.5``; paper 002's single-pose targets put
its circles in the plane ``x = C_x`` too). Closed curves sample their parameter on ``[0, 2π]`` *inclusive*, so
the last waypoint repeats the first (as ``θ_k ∈ [0, 2π]`` in paper 000).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import TaskError

ArrayLike = Sequence[float] | np.ndarray

_AXES = {"x": 0, "y": 1, "z": 2}
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

    Raises:
        TaskError: wrong shapes, NaN/inf, fewer than one waypoint, or matrices that are not rotations.
    """

    positions: np.ndarray
    rotations: np.ndarray | None = None
    name: str = field(default="path", compare=False)

    def __post_init__(self) -> None:
        P = np.array(self.positions, dtype=float)
        if P.ndim != 2 or P.shape[1] != 3 or P.shape[0] < 1:
            raise TaskError(
                f"trajectory {self.name!r}: positions must have shape (K, 3) with K >= 1; got {P.shape}"
            )
        _check_finite(P, f"trajectory {self.name!r}: positions")
        P.flags.writeable = False
        object.__setattr__(self, "positions", P)
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

    def rotation(self, k: int) -> np.ndarray | None:
        """``(3, 3)`` rotation of waypoint ``k``, or ``None`` for a position-only trajectory."""
        return None if self.rotations is None else self.rotations[k]

    def __getitem__(self, index: int | slice | Sequence[int] | np.ndarray) -> Trajectory:
        """A sub-trajectory (``path[::4]``, ``path[:10]``, ``path[[0, 5, 9]]``); an int keeps one waypoint."""
        idx = [index] if isinstance(index, (int, np.integer)) else index
        P = self.positions[idx]
        R = None if self.rotations is None else self.rotations[idx]
        return Trajectory(P, R, self.name)

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
        return Trajectory(self.positions + _vector(delta, "offset"), self.rotations, self.name)

    def transformed(
        self, rotation: np.ndarray | None = None, translation: ArrayLike = (0.0, 0.0, 0.0)
    ) -> Trajectory:
        """The path moved rigidly: ``p' = R p + t`` and ``R_k' = R R_k`` (rotation about the world origin)."""
        R = np.eye(3) if rotation is None else _rotation(rotation, "rotation")
        P = self.positions @ R.T + _vector(translation, "translation")
        rotations = None if self.rotations is None else np.einsum("ij,kjl->kil", R, self.rotations)
        return Trajectory(P, rotations, self.name)

    def with_orientation(self, rotation: np.ndarray | None) -> Trajectory:
        """The same positions with orientation ``rotation`` (``(3, 3)`` for all waypoints or ``(K, 3, 3)``);
        ``None`` drops the orientation."""
        return Trajectory(self.positions, rotation, self.name)

    def reversed(self) -> Trajectory:
        """The waypoints in reverse order."""
        return self[::-1]

    def then(self, *others: Trajectory) -> Trajectory:
        """This path followed by ``others`` (see :func:`concatenate`)."""
        return concatenate(self, *others, name=self.name)

    def renamed(self, name: str) -> Trajectory:
        return Trajectory(self.positions, self.rotations, name)

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


def _vector(value: ArrayLike, what: str) -> np.ndarray:
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

    Either all have orientations or none. A waypoint repeated at a junction (the end of one piece equal to the
    start of the next, within 1e-12 m) is kept once.
    """
    if not trajectories:
        raise TaskError("concatenate needs at least one trajectory")
    oriented = {t.has_orientation for t in trajectories}
    if len(oriented) != 1:
        raise TaskError(
            "cannot concatenate trajectories with and without orientation; use with_orientation()"
        )
    P, R = [trajectories[0].positions], [trajectories[0].rotations]
    for t in trajectories[1:]:
        start = 1 if np.linalg.norm(t.positions[0] - P[-1][-1]) < 1e-12 else 0
        P.append(t.positions[start:])
        R.append(None if t.rotations is None else t.rotations[start:])
    rotations = np.concatenate(R) if oriented == {True} else None
    return Trajectory(np.concatenate(P), rotations, name or "+".join(t.name for t in trajectories))


# ---------------------------------------------------------------------------------------------- shapes
def _plane(plane: str | tuple[ArrayLike, ArrayLike]) -> tuple[np.ndarray, np.ndarray]:
    """Unit vectors ``(u, v)`` of a plane: ``"yz"``, ``"xz"``, ``"xy"`` (any two axes) or two orthonormal vectors."""
    if isinstance(plane, str):
        if len(plane) != 2 or plane[0] not in _AXES or plane[1] not in _AXES or plane[0] == plane[1]:
            raise TaskError(f"plane must name two different axes such as 'yz' or 'xz'; got {plane!r}")
        u, v = np.zeros(3), np.zeros(3)
        u[_AXES[plane[0]]], v[_AXES[plane[1]]] = 1.0, 1.0
        return u, v
    u, v = (_vector(w, "plane vector") for w in plane)
    if abs(np.linalg.norm(u) - 1) > 1e-9 or abs(np.linalg.norm(v) - 1) > 1e-9 or abs(u @ v) > 1e-9:
        raise TaskError("plane vectors must be orthonormal")
    return u, v


#: Most waypoints a parametric path is sampled at (each is one IK solve; beyond this is a typo, not a path).
MAX_POINTS = 1_000_000


def point_count(points: int) -> int:
    if isinstance(points, bool) or not isinstance(points, (int, float, np.integer, np.floating)) \
            or not np.isfinite(points) or int(points) != points or not 2 <= points <= MAX_POINTS:
        raise TaskError(f"a trajectory needs an integer number of points in [2, {MAX_POINTS:,}]; got {points!r}")
    return int(points)


def _positive(value: float, what: str) -> float:
    value = float(value)
    if not np.isfinite(value) or value <= 0:
        raise TaskError(f"{what} must be a positive number [m]; got {value!r}")
    return value


def plane_curve(
    centre: ArrayLike,
    u: np.ndarray,
    v: np.ndarray,
    *,
    plane: str | tuple[ArrayLike, ArrayLike] = "yz",
    orientation: np.ndarray | None = None,
    name: str = "curve",
) -> Trajectory:
    """Waypoints ``centre + u_k e_u + v_k e_v`` for in-plane coordinates ``u``, ``v`` ``(K,)`` [m]."""
    e_u, e_v = _plane(plane)
    u, v = np.asarray(u, dtype=float), np.asarray(v, dtype=float)
    P = _vector(centre, "centre") + u[:, None] * e_u + v[:, None] * e_v
    return Trajectory(P, orientation, name)


def circle(
    centre: ArrayLike,
    radius: float,
    points: int = 200,
    *,
    plane: str | tuple[ArrayLike, ArrayLike] = "yz",
    start_angle: float = 0.0,
    turns: float = 1.0,
    orientation: np.ndarray | None = None,
    name: str = "circle",
) -> Trajectory:
    """Circle ``centre + r (cos θ e_u + sin θ e_v)``, ``θ = start_angle + linspace(0, 2π turns, points)``."""
    theta = start_angle + np.linspace(0.0, 2 * np.pi * turns, point_count(points))
    r = _positive(radius, "circle radius")
    return plane_curve(
        centre, r * np.cos(theta), r * np.sin(theta), plane=plane, orientation=orientation, name=name
    )


def lemniscate(
    centre: ArrayLike,
    a: float,
    points: int = 200,
    *,
    plane: str | tuple[ArrayLike, ArrayLike] = "yz",
    orientation: np.ndarray | None = None,
    name: str = "lemniscate",
) -> Trajectory:
    """Lemniscate of Bernoulli ``r² = a² cos 2φ`` (figure eight, lobes along ``e_u``, half-width ``a`` [m]).

    Parametrized by ``t = linspace(0, 2π, points)``: ``u = a cos t / (1 + sin² t)``,
    ``v = a sin t cos t / (1 + sin² t)``; it starts at the tip of the ``+e_u`` lobe and crosses the centre
    twice. Paper 002 gives only "r = a cos(θ)" and the parameter ``a``; this is our reading of it.
    """
    t = np.linspace(0.0, 2 * np.pi, point_count(points))
    a = _positive(a, "lemniscate parameter a")
    d = 1.0 + np.sin(t) ** 2
    return plane_curve(
        centre,
        a * np.cos(t) / d,
        a * np.sin(t) * np.cos(t) / d,
        plane=plane,
        orientation=orientation,
        name=name,
    )


def rose(
    centre: ArrayLike,
    radius: float,
    amplitude: float,
    points: int = 200,
    *,
    petals: int = 3,
    plane: str | tuple[ArrayLike, ArrayLike] = "yz",
    orientation: np.ndarray | None = None,
    name: str = "rose",
) -> Trajectory:
    """Rose curve: ``r = radius + amplitude cos(petals θ)``, ``u = r cos θ``, ``v = r sin θ``, ``θ ∈ [0, 2π]``."""
    theta = np.linspace(0.0, 2 * np.pi, point_count(points))
    r = _positive(radius, "rose radius") + float(amplitude) * np.cos(petals * theta)
    return plane_curve(
        centre, r * np.cos(theta), r * np.sin(theta), plane=plane, orientation=orientation, name=name
    )


def line(
    start: ArrayLike,
    stop: ArrayLike,
    points: int = 200,
    *,
    orientation: np.ndarray | None = None,
    name: str = "line",
) -> Trajectory:
    """Evenly spaced waypoints from ``start`` to ``stop`` (both included) [m]."""
    s = np.linspace(0.0, 1.0, point_count(points))[:, None]
    a, b = _vector(start, "line start"), _vector(stop, "line stop")
    return Trajectory(a + s * (b - a), orientation, name)


def sinusoid(
    start: ArrayLike,
    stop: ArrayLike,
    amplitude: float,
    wavenumber: float,
    points: int = 200,
    *,
    axis: ArrayLike = (0.0, 0.0, 1.0),
    phase: float = 0.0,
    saturation: float | None = None,
    orientation: np.ndarray | None = None,
    name: str = "sinusoid",
) -> Trajectory:
    """A sine wave along the segment ``start → stop``: ``p(s) = start + s d + w(s) axis``, ``s`` = distance [m].

    ``w(s) = amplitude sin(wavenumber s + phase)`` [m] (``wavenumber`` in rad/m); with ``saturation`` the wave is
    clipped to ``±saturation`` [m], which turns it into a trapezoidal wave (paper 000's trapezoidal path).
    """
    a, b = _vector(start, "sinusoid start"), _vector(stop, "sinusoid stop")
    length = float(np.linalg.norm(b - a))
    if length == 0:
        raise TaskError("a sinusoid needs start != stop")
    s = np.linspace(0.0, length, point_count(points))
    w = float(amplitude) * np.sin(float(wavenumber) * s + float(phase))
    if saturation is not None:
        w = np.clip(w, -_positive(saturation, "saturation"), saturation)
    direction = _vector(axis, "sinusoid axis")
    direction = direction / np.linalg.norm(direction)
    P = a + s[:, None] * (b - a) / length + w[:, None] * direction
    return Trajectory(P, orientation, name)


# ---------------------------------------------------------------------------------------------- papers
def paper000(path: str, points: int = 200) -> Trajectory:
    """Paper 000's paths for end-effector 1 (section 4, ``K = 200``), all in the plane ``x = 0.5`` m.

    - ``"sinusoidal"``: ``z = 0.4 + 0.05 sin(30 y)``, ``y ∈ [-0.25, 0.75]``
    - ``"circular"``: ``y = 0.25 + 0.05 cos θ``, ``z = 0.45 + 0.05 sin θ``, ``θ ∈ [0, 2π]``
    - ``"trapezoidal"``: ``r = 0.45 + 0.1 sin(30 y)``, ``z = 0.5`` if ``r > 0.5``, ``0.4`` if ``r < 0.4``, else
      ``r``, ``y ∈ [-0.25, 0.75]``
    - ``"rose"``: ``r = 0.035 + 0.015 cos 3θ``, ``y = 0.25 + r cos θ``, ``z = 0.35 + r sin θ``, ``θ ∈ [0, 2π]``
    """
    y0, y1 = -0.25, 0.75
    if path == "sinusoidal":
        return sinusoid((0.5, y0, 0.4), (0.5, y1, 0.4), 0.05, 30.0, points, phase=30.0 * y0, name=path)
    if path == "circular":
        return circle((0.5, 0.25, 0.45), 0.05, points, name=path)
    if path == "trapezoidal":
        return sinusoid(
            (0.5, y0, 0.45), (0.5, y1, 0.45), 0.1, 30.0, points, phase=30.0 * y0, saturation=0.05, name=path
        )
    if path == "rose":
        return rose((0.5, 0.25, 0.35), 0.035, 0.015, points, petals=3, name=path)
    raise TaskError(f"paper 000 has no path {path!r}; paths: {list(PAPER000_PATHS)}")


PAPER000_PATHS = ("sinusoidal", "circular", "trapezoidal", "rose")

#: Paper 002 (section 5): circle centre C [m], radius r [m] (and lemniscate parameter a = r) per robot.
PAPER002_PATHS: dict[str, tuple[tuple[float, float, float], float]] = {
    "youbot_arm": ((0.3, 0.2, 0.5), 0.05),
    "puma560": ((0.5, 0.0, 0.4), 0.3),
    "fanuc_am120ib": ((1.4, 0.0, 0.25), 0.5),
    "baxter_arm": ((0.6, 0.6, 0.5), 0.3),
}


def paper002(robot: str, path: str, points: int = 50) -> Trajectory:
    """Paper 002's ``"circle"`` or ``"lemniscate"`` for ``robot`` (a key of :data:`PAPER002_PATHS`), with the
    orientation ``R_d = Ry(π/2)`` at every waypoint, in the plane ``x = C_x``.

    The paper's sign tests count 32 circle and 73 lemniscate poses; ``points`` is our choice (default 50).
    """
    if robot not in PAPER002_PATHS:
        raise TaskError(f"paper 002 has no path for robot {robot!r}; robots: {list(PAPER002_PATHS)}")
    centre, size = PAPER002_PATHS[robot]
    if path == "circle":
        return circle(centre, size, points, orientation=Ry(np.pi / 2), name=f"{robot} circle")
    if path == "lemniscate":
        return lemniscate(centre, size, points, orientation=Ry(np.pi / 2), name=f"{robot} lemniscate")
    raise TaskError(f"paper 002 has no path {path!r}; paths: 'circle', 'lemniscate'")
