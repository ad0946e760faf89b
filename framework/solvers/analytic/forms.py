"""A chain's closed form read from its geometry: the family of its axes (:func:`form_of`), a 7R chain's searched
joint (:func:`with_free_joint`), and what the compiled solver reads of them (:class:`ClosedForm`).

Axes are read at the zero configuration in the world frame; axes that are parallel but opposite are turned to one
direction (the solution's sign turned back); a chain that is no family read from its base may be one read from the
tool back (``M T⁻¹ = e^{-ξ6 q6} ... e^{-ξ1 q1}``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from .families import (FIVE_PARALLEL, THREE_PARALLEL, WRIST_CROSSING, WRIST_PARALLEL, exact_solutions,
                       nearest_configurations, table)
from .free_joint import STEP, free_solutions

#: Two axes closer than this [rad of direction, m of distance] are taken as parallel / meeting.
GEOMETRY = 1e-9
#: Family names by code.
FAMILIES = {WRIST_PARALLEL: "spherical wrist, axes 2 ∥ 3", WRIST_CROSSING: "spherical wrist, axes 1 and 2 meet",
            THREE_PARALLEL: "axes 2 ∥ 3 ∥ 4, axes 5 and 6 meet",
            FIVE_PARALLEL: "five joints, axes 2 ∥ 3 ∥ 4 (the orientations the arm can take)"}


@dataclass(frozen=True)
class ClosedForm:
    """Whether (and how) a frame's chain has a closed-form inverse kinematics.

    Attributes:
        frame: the end-effector frame.
        family: the family's name (:data:`FAMILIES`), or ``None`` when there is no closed form here.
        reason: why there is none (``""`` when there is).
        coordinates: ``(6,)`` the chain's coordinates in the robot's joint vector, base to tip.
        code, signs, axes, points, centre, M, Minv, lower, upper: the solver's data (family code; ±1 per joint
            turning opposite parallel axes to one direction; unit axes and a point on each ``(6, 3)`` [m] at the zero
            configuration; the meeting point of the wrist axes [m]; the frame's placement at zero ``(4, 4)`` and its
            inverse; the chain's joint limits turned by ``signs``).
    """

    frame: str
    family: str | None
    reason: str = ""
    coordinates: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int), repr=False)
    code: int = 0
    signs: np.ndarray = field(default_factory=lambda: np.ones(6), repr=False)
    axes: np.ndarray = field(default_factory=lambda: np.zeros((6, 3)), repr=False)
    points: np.ndarray = field(default_factory=lambda: np.zeros((6, 3)), repr=False)
    centre: np.ndarray = field(default_factory=lambda: np.zeros(3), repr=False)
    M: np.ndarray = field(default_factory=lambda: np.eye(4), repr=False)
    Minv: np.ndarray = field(default_factory=lambda: np.eye(4), repr=False)
    lower: np.ndarray = field(default_factory=lambda: np.zeros(6), repr=False)
    upper: np.ndarray = field(default_factory=lambda: np.zeros(6), repr=False)
    #: the data above in one array for the compiled solver, within the limits and anywhere in [-π, π]
    tables: tuple[np.ndarray, np.ndarray] = field(default=(np.zeros(0), np.zeros(0)), repr=False)
    #: a 7R chain's searched joint (:mod:`~framework.solvers.analytic.free_joint`), empty for a 6R chain
    free: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    #: the first of the six slots that is a joint (1 for a five-joint chain: slot 0 holds none, and its coordinate
    #: repeats slot 1's, written first)
    first: int = 0

    @property
    def exists(self) -> bool:
        return self.family is not None

    def nearest(self, pose: np.ndarray, x_ref: np.ndarray, tolerance: float = 1e-10) -> np.ndarray:
        """``(k, n)`` each exact solution of the world pose ``(12,)`` once, as its 2π copy within the limits nearest
        ``x_ref`` ``(n,)`` (the others keep its values), nearest first."""
        # (one array type for each argument: a read-only or non-contiguous one is another compiled signature)
        if self.free.size:
            return free_solutions(self.code, self.tables[0], self.free, self.coordinates, _writable(pose),
                                  _writable(x_ref), float(tolerance), False)
        return nearest_configurations(self.code, self.tables[0], self.coordinates, _writable(pose),
                                      _writable(x_ref), float(tolerance))

    def solutions(self, pose: np.ndarray, x_ref: np.ndarray, tolerance: float = 1e-10, *,
                  limits: bool = True) -> np.ndarray:
        """``(k, n)`` every exact solution of the world pose ``(12,)`` (position [m], row-major rotation), the
        chain's coordinates set in ``x_ref`` ``(n,)``, within the joint limits (or each once in [-π, π] without
        ``limits``), nearest to ``x_ref`` first."""
        if self.free.size:
            return free_solutions(self.code, self.tables[0 if limits else 1], self.free, self.coordinates,
                                  _writable(pose), _writable(x_ref), float(tolerance), True)
        return exact_solutions(self.code, self.tables[0 if limits else 1], self.coordinates, homogeneous(pose),
                               _writable(x_ref), float(tolerance))


def homogeneous(pose: np.ndarray) -> np.ndarray:
    """The 4x4 homogeneous transform of a pose ``(12,)`` (position [m], row-major rotation)."""
    T = np.eye(4)
    T[:3, 3] = pose[:3]
    T[:3, :3] = np.reshape(pose[3:], (3, 3))
    return T


def _writable(a) -> np.ndarray:
    """``a`` as a writable C-contiguous float array (itself when it is one)."""
    if type(a) is np.ndarray and a.dtype == np.float64 and a.flags.c_contiguous and a.flags.writeable:
        return a
    return np.array(a, dtype=float)


def form_of(frame: str, H: np.ndarray, P: np.ndarray, M: np.ndarray, coordinates: np.ndarray, lower_all: np.ndarray,
            upper_all: np.ndarray) -> ClosedForm:
    """The closed form of a 6R chain: axes ``H`` and points ``P`` ``(6, 3)`` at zero in the world, the frame's
    placement ``M`` ``(4, 4)``, its ``coordinates`` in the joint vector and the robot's limits."""
    H, signs = _oriented(H)
    code, centre, P, reason = _family(H, P)
    tool = None
    if code == 0:  # read from the tool back: M T⁻¹ = e^{-ξ6 q6} ... e^{-ξ1 q1}, a chain with axes -h6 .. -h1
        Hr, signs_r = _oriented(-H[::-1] * signs[::-1, None])
        code_r, centre_r, P_r, _ = _family(Hr, P[::-1].copy())
        if code_r == 0:
            return ClosedForm(frame, None, reason, coordinates)
        code, centre, P, H, signs, tool = code_r, centre_r, P_r, Hr, signs_r, M
        coordinates = coordinates[::-1].copy()
    limits = lower_all[coordinates], upper_all[coordinates]
    lower, upper = np.where(signs > 0, limits[0], -limits[1]), np.where(signs > 0, limits[1], -limits[0])
    pose_M = M if tool is None else np.eye(4)
    Minv = np.linalg.inv(pose_M)
    tables = tuple(table(H, P, centre, pose_M, Minv, lo, hi, signs, tool)
                   for lo, hi in ((lower, upper), (np.full(6, -np.pi), np.full(6, np.pi))))
    family = FAMILIES[code] + ("" if tool is None else " (read from the tool back)")
    return ClosedForm(frame, family, "", coordinates, code, signs, H, P, centre, M, Minv, lower, upper, tables)


def five_joints(frame: str, H: np.ndarray, P: np.ndarray, M: np.ndarray, coordinates: np.ndarray,
                lower_all: np.ndarray, upper_all: np.ndarray):
    """The closed form of a 5R chain (axes 2 ∥ 3 ∥ 4, :data:`~.families.FIVE_PARALLEL`) held in slots 1-5 of the
    six, slot 0 a joint fixed at 0; or a form saying there is none."""
    H, signs = _oriented(H)

    def parallel(a: int, b: int) -> bool:
        return bool(np.linalg.norm(np.cross(H[a], H[b])) < GEOMETRY)

    if not (parallel(1, 2) and parallel(2, 3)) or parallel(0, 1) or parallel(4, 1):
        return ClosedForm(frame, None, "a 5-joint chain, but not with axes 2 ∥ 3 ∥ 4 (the family solved in closed "
                                       "form)", coordinates)
    coordinates = np.concatenate([coordinates[:1], coordinates]).astype(np.int64)
    H, P, signs = np.vstack([np.zeros(3), H]), np.vstack([P[:1], P]), np.concatenate([[1.0], signs])
    limits = lower_all[coordinates], upper_all[coordinates]
    lower, upper = np.where(signs > 0, limits[0], -limits[1]), np.where(signs > 0, limits[1], -limits[0])
    lower[0] = upper[0] = 0.0
    Minv = np.linalg.inv(M)
    wide = np.concatenate([[0.0], np.full(5, np.pi)])
    tables = (table(H, P, np.zeros(3), M, Minv, lower, upper, signs),
              table(H, P, np.zeros(3), M, Minv, -wide, wide, signs))
    return ClosedForm(frame, FAMILIES[FIVE_PARALLEL], "", coordinates, FIVE_PARALLEL, signs, H, P, np.zeros(3), M,
                      Minv, lower, upper, tables, first=1)


def with_free_joint(frame: str, H: np.ndarray, P: np.ndarray, M: np.ndarray, coordinates: np.ndarray,
                    lower_all: np.ndarray, upper_all: np.ndarray, names: list[str]):
    """The closed form of a 7R chain with one joint searched (the first that leaves a closed-form 6R chain at every
    value), or a form saying there is none."""
    for f in range(7):
        others = [i for i in range(7) if i != f]
        base = form_of(frame, H[others], P[others], M, coordinates[others], lower_all, upper_all)
        if not base.exists:
            continue
        after = set(coordinates[f + 1:].tolist())
        moves = np.array([c in after for c in base.coordinates], dtype=float)
        centre_moves = _centre_moves(frame, H, P, M, coordinates, lower_all, upper_all, f, base)
        if centre_moves is None:
            continue
        free = np.concatenate([H[f], P[f], [lower_all[coordinates[f]], upper_all[coordinates[f]], STEP,
                                            float(centre_moves)], moves, [coordinates[f]]])
        return ClosedForm(frame, f"{base.family}, {names[f]} searched", "", base.coordinates, base.code, base.signs,
                          base.axes, base.points, base.centre, base.M, base.Minv, base.lower, base.upper, base.tables,
                          free)
    return ClosedForm(frame, None, "a 7R chain, but no joint leaves a closed-form 6R chain when fixed", coordinates)


def _centre_moves(frame, H, P, M, coordinates, lower_all, upper_all, f, base) -> bool | None:
    """Whether the family's centre moves with free joint ``f`` (it lies on the joints after it), checked at a
    second value of the joint: the 6R chain there must be of the same family; None if not."""
    theta = 0.7
    R = pin.exp3(theta * H[f])
    others = [i for i in range(7) if i != f]
    after = np.array([i > f for i in others])
    Ht = np.where(after[:, None], H[others] @ R.T, H[others])
    Pt = np.where(after[:, None], (P[others] - P[f]) @ R.T + P[f], P[others])
    Mt = M.copy()
    Mt[:3, :3], Mt[:3, 3] = R @ M[:3, :3], R @ (M[:3, 3] - P[f]) + P[f]
    moved = form_of(frame, Ht, Pt, Mt, coordinates[others], lower_all, upper_all)
    if moved.code != base.code:
        return None
    if np.allclose(moved.centre, R @ (base.centre - P[f]) + P[f], atol=1e-9):
        return True
    return False if np.allclose(moved.centre, base.centre, atol=1e-9) else None


def _oriented(H: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(axes, signs)``: parallel axes turned to the direction of the first of them (±1 per axis)."""
    H, signs = H.copy(), np.ones(len(H))
    for i in range(1, len(H)):
        for k in range(i):
            if np.linalg.norm(np.cross(H[i], H[k])) < GEOMETRY and H[i] @ H[k] < 0:
                H[i], signs[i] = -H[i], -1.0
                break
    return H, signs


def _family(H: np.ndarray, P: np.ndarray) -> tuple[int, np.ndarray, np.ndarray, str]:
    """``(code, meeting point, points, reason)``: the family of the axes ``(H, P)`` (code 0: none)."""
    def parallel(a: int, b: int) -> bool:
        return bool(np.linalg.norm(np.cross(H[a], H[b])) < GEOMETRY)

    wrist = _meet(H, P, 3, 4)
    if wrist is not None and _meet(H, P, 4, 5) is not None and _off(H, P, 5, wrist) < 1e-7:
        if parallel(1, 2) and not parallel(0, 1):
            return WRIST_PARALLEL, wrist, P, ""
        shoulder = _meet(H, P, 0, 1)
        if shoulder is not None:
            P = P.copy()
            P[0] = P[1] = shoulder
            return WRIST_CROSSING, wrist, P, ""
        return 0, wrist, P, "a spherical wrist, but axes 1-3 are neither 2 ∥ 3 nor 1 and 2 meeting"
    hand = _meet(H, P, 4, 5)
    if parallel(1, 2) and parallel(2, 3) and hand is not None and not parallel(0, 1) and not parallel(4, 1):
        return THREE_PARALLEL, hand, P, ""
    return 0, np.zeros(3), P, "no spherical wrist and no three parallel axes (the families solved in closed form)"


def _off(H: np.ndarray, P: np.ndarray, a: int, point: np.ndarray) -> float:
    """Distance [m] of ``point`` from axis ``a``."""
    d = point - P[a]
    return float(np.linalg.norm(d - (d @ H[a]) * H[a]))


def _meet(H: np.ndarray, P: np.ndarray, a: int, b: int) -> np.ndarray | None:
    """The point where axes ``a`` and ``b`` meet, or None (parallel, or apart by more than 1e-7 m)."""
    n = np.cross(H[a], H[b])
    if np.linalg.norm(n) < GEOMETRY:
        return None
    d = P[b] - P[a]
    if abs(d @ n) / np.linalg.norm(n) > 1e-7:
        return None
    # P[a] + s H[a] = P[b] + t H[b]: least squares in (s, t)
    A = np.column_stack([H[a], -H[b]])
    s, t = np.linalg.lstsq(A, d, rcond=None)[0]
    return 0.5 * (P[a] + s * H[a] + P[b] + t * H[b])
