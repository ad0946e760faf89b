"""Paths a :class:`~framework.tracking.trajectory.Trajectory` is made from: plane curves, lines, sinusoids and the
papers' paths (000: sinusoidal, circular, trapezoidal, rose; 002: circle and lemniscate per robot)::

    from framework.tracking import paths

    circle = paths.circle(centre=(0.5, 0.25, 0.45), radius=0.05, points=200)     # paper 000, circular
    tool_down = paths.circle((0.3, 0.2, 0.5), 0.05, points=32, orientation=Ry(np.pi / 2))

Plane curves (circle, lemniscate, rose, sinusoid) are drawn in a plane through their centre spanned by two
world axes, ``plane="yz"`` by default: the first letter is the curve's horizontal coordinate ``u``, the second
its vertical ``v`` (paper 000 draws every path in the plane ``x = 0.5``; paper 002's single-pose targets put
its circles in the plane ``x = C_x`` too). Closed curves sample their parameter on ``[0, 2π]`` *inclusive*, so
the last waypoint repeats the first (as ``θ_k ∈ [0, 2π]`` in paper 000).
"""
from __future__ import annotations

import numpy as np

from ..errors import TaskError
from .trajectory import ArrayLike, Ry, Trajectory, point3

_AXES = {"x": 0, "y": 1, "z": 2}


def _plane(plane: str | tuple[ArrayLike, ArrayLike]) -> tuple[np.ndarray, np.ndarray]:
    """Unit vectors ``(u, v)`` of a plane: ``"yz"``, ``"xz"``, ``"xy"`` (any two axes) or two orthonormal vectors."""
    if isinstance(plane, str):
        if len(plane) != 2 or plane[0] not in _AXES or plane[1] not in _AXES or plane[0] == plane[1]:
            raise TaskError(f"plane must name two different axes such as 'yz' or 'xz'; got {plane!r}")
        u, v = np.zeros(3), np.zeros(3)
        u[_AXES[plane[0]]], v[_AXES[plane[1]]] = 1.0, 1.0
        return u, v
    u, v = (point3(w, "plane vector") for w in plane)
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
    P = point3(centre, "centre") + u[:, None] * e_u + v[:, None] * e_v
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
    a, b = point3(start, "line start"), point3(stop, "line stop")
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
    a, b = point3(start, "sinusoid start"), point3(stop, "sinusoid stop")
    length = float(np.linalg.norm(b - a))
    if length == 0:
        raise TaskError("a sinusoid needs start != stop")
    s = np.linspace(0.0, length, point_count(points))
    w = float(amplitude) * np.sin(float(wavenumber) * s + float(phase))
    if saturation is not None:
        w = np.clip(w, -_positive(saturation, "saturation"), saturation)
    direction = point3(axis, "sinusoid axis")
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
