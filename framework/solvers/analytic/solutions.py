"""Closed-form inverse kinematics where the arm's axes allow it: which family a frame's chain belongs to, read
from the Pinocchio model (:func:`closed_form`), and every solution of a pose (:func:`analytic_ik`).

The chain is the solved joints that move the frame; other joints keep the reference configuration's values. Its
axes are read at the zero configuration in the world frame (tool offset and locked joints included, whatever the
URDF names its frames), axes that are parallel but opposite are turned to one direction (the solution's sign
turned back), and the families of :mod:`~framework.solvers.analytic.families` are recognised from the geometry
alone: a spherical wrist (axes 4, 5, 6 meeting) with axes 2 ∥ 3 or with axes 1, 2 meeting, or axes 2 ∥ 3 ∥ 4 with
axes 5, 6 meeting.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ...costs.pose import pose_parameters
from ...errors import TaskError
from ...model.joints import JointKind
from ...model.robot import Robot
from .families import (MOST, THREE_PARALLEL, WRIST_CROSSING, WRIST_PARALLEL, exact_solutions, nearest_configurations,
                       nearest_solutions, table)

#: Two axes closer than this [rad of direction, m of distance] are taken as parallel / meeting.
GEOMETRY = 1e-9
#: Family names by code.
FAMILIES = {WRIST_PARALLEL: "spherical wrist, axes 2 ∥ 3", WRIST_CROSSING: "spherical wrist, axes 1 and 2 meet",
            THREE_PARALLEL: "axes 2 ∥ 3 ∥ 4, axes 5 and 6 meet"}


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

    @property
    def exists(self) -> bool:
        return self.family is not None

    def nearest(self, pose: np.ndarray, x_ref: np.ndarray, tolerance: float = 1e-10) -> np.ndarray:
        """``(k, n)`` each exact solution of the world pose ``(12,)`` once, as its 2π copy within the limits nearest
        ``x_ref`` ``(n,)`` (the others keep its values), nearest first."""
        # (one array type for each argument: a read-only or non-contiguous one is another compiled signature)
        return nearest_configurations(self.code, self.tables[0], self.coordinates, _writable(pose),
                                      _writable(x_ref), float(tolerance))

    def solutions(self, pose: np.ndarray, x_ref: np.ndarray, tolerance: float = 1e-10, *,
                  limits: bool = True) -> np.ndarray:
        """``(k, n)`` every exact solution of the world pose ``(12,)`` (position [m], row-major rotation), the
        chain's coordinates set in ``x_ref`` ``(n,)``, within the joint limits (or each once in [-π, π] without
        ``limits``), nearest to ``x_ref`` first."""
        return exact_solutions(self.code, self.tables[0 if limits else 1], self.coordinates, _writable(pose),
                               _writable(x_ref), float(tolerance))


def _writable(a) -> np.ndarray:
    """``a`` as a writable C-contiguous float array (itself when it is one)."""
    if type(a) is np.ndarray and a.dtype == np.float64 and a.flags.c_contiguous and a.flags.writeable:
        return a
    return np.array(a, dtype=float)


@dataclass(frozen=True)
class AnalyticSolutions:
    """Every solution of one pose.

    Attributes:
        configurations: ``(k, n)`` joint vectors of the robot, each meeting the pose exactly (forward kinematics
            within ``tolerance``) and within the joint limits, 2π copies included, nearest to ``reference`` first;
            the joints off the chain keep the reference's values.
        family: the closed form used.
        reason: ``""``, or why there is none: the pose is beyond reach, or every solution is outside the limits.
    """

    configurations: np.ndarray
    family: str
    reason: str = ""

    def __len__(self) -> int:
        return len(self.configurations)

    @property
    def reachable(self) -> bool:
        return len(self.configurations) > 0


def closed_form(robot: Robot, frame: str) -> ClosedForm:
    """The closed form of ``frame``'s chain on ``robot``, if its axes allow one (read once per robot and frame)."""
    robot.frame_id(frame)  # an unknown frame names the close ones
    return robot.derived(_detect, frame)


def analytic_ik(robot: Robot, frame: str, pose, *, reference: np.ndarray | None = None,
                quaternion: str | None = None, tolerance: float = 1e-10) -> AnalyticSolutions:
    """Every solution of ``frame`` reaching ``pose`` (``pinocchio.SE3``, 4x4 matrix or ``(position, rotation)``; 4
    numbers need ``quaternion``), within the joint limits, nearest to ``reference`` ``(n,)`` first (default: the
    middle of the bounds). A :class:`TaskError` says why when the chain has no closed form."""
    form = closed_form(robot, frame)
    if not form.exists:
        raise TaskError(f"{frame!r} of {robot.name} has no closed form here: {form.reason}")
    x_ref = robot.middle if reference is None else _reference(robot, reference)
    packed = pose_parameters(pose, lambda: f"pose of {frame!r}", quaternion)
    X = form.solutions(packed, x_ref, tolerance)
    if len(X):
        return AnalyticSolutions(X, form.family)
    reason = ("every solution of the pose is outside the joint limits"
              if len(form.solutions(packed, x_ref, tolerance, limits=False)) else
              "the pose is beyond the arm's reach (no exact solution)")
    return AnalyticSolutions(X, form.family, reason)


@dataclass(frozen=True)
class AnalyticBatch:
    """The solutions of a batch of poses, each once: as its 2π copy within the limits nearest the reference.

    Attributes:
        chain: ``(B, 8, 6)`` the chain's coordinates of each pose's solutions, nearest to the reference first (rows
            past ``counts[b]`` are NaN).
        counts: ``(B,)`` how many each pose has (0: beyond reach, or every one outside the limits).
        coordinates: ``(6,)`` the chain's coordinates in the robot's joint vector.
        reference: ``(n,)`` the reference configuration (the joints off the chain keep its values).
    """

    chain: np.ndarray
    counts: np.ndarray
    coordinates: np.ndarray
    reference: np.ndarray

    def __len__(self) -> int:
        return len(self.counts)

    def configurations(self, b: int) -> np.ndarray:
        """``(counts[b], n)`` the robot configurations of pose ``b``'s solutions, nearest first."""
        X = np.repeat(self.reference[None], self.counts[b], axis=0)
        X[:, self.coordinates] = self.chain[b, : self.counts[b]]
        return X

    @property
    def nearest(self) -> np.ndarray:
        """``(B, n)`` each pose's solution nearest to the reference (a NaN row for a pose without any)."""
        X = np.repeat(self.reference[None], len(self.counts), axis=0)
        X[:, self.coordinates] = self.chain[:, 0]
        return X


def analytic_ik_batch(robot: Robot, frame: str, poses, *, reference: np.ndarray | None = None,
                      tolerance: float = 1e-10, workers: int | None = None) -> AnalyticBatch:
    """:func:`analytic_ik` over a batch of poses (``(B, 4, 4)`` homogeneous matrices, or a sequence of any form a
    :class:`~framework.costs.Pose` takes), in one compiled loop on ``workers`` threads (default: every core); each
    solution once, as its 2π copy nearest ``reference`` (default: the middle of the bounds)."""
    from ...costs import Pose
    from ...engine.batch import in_chunks

    form = closed_form(robot, frame)
    if not form.exists:
        raise TaskError(f"{frame!r} of {robot.name} has no closed form here: {form.reason}")
    x_ref = np.array(robot.middle if reference is None else _reference(robot, reference), dtype=float)
    packed = np.ascontiguousarray(Pose(frame, pin.SE3.Identity()).target_parameters(robot, poses))
    chain = np.full((len(packed), MOST, 6), np.nan)
    counts = np.zeros(len(packed), dtype=np.int64)

    def work(items: np.ndarray) -> None:
        a, b = int(items[0]), int(items[-1]) + 1
        nearest_solutions(form.code, form.tables[0], form.coordinates, packed[a:b], x_ref, tolerance, chain[a:b],
                          counts[a:b])

    in_chunks(work, len(packed), workers=workers)
    return AnalyticBatch(chain, counts, form.coordinates, x_ref)


def _reference(robot: Robot, reference) -> np.ndarray:
    """The reference configuration ``(n,)`` as a float array, checked."""
    x = np.asarray(reference, dtype=float)
    if x.shape != (robot.n,) or not np.isfinite(x).all():
        raise TaskError(f"reference must be {robot.n} finite joint coordinates of {robot.name}; got {reference!r}")
    return x


# ---------------------------------------------------------------------------------------------- detection
def _detect(robot: Robot, frame: str) -> ClosedForm:
    model = robot.model
    fid = robot.frame_id(frame)
    support = set(model.supports[model.frames[fid].parentJoint])
    chain = [j for j in robot.joints if j.pin_id in support]
    if any(m.pin_id in support for m in robot.mimics):
        return ClosedForm(frame, None, "a mimic joint moves the frame")
    if any(j.kind not in (JointKind.REVOLUTE, JointKind.CONTINUOUS) for j in chain):
        return ClosedForm(frame, None, "its chain holds joints other than revolute ones: "
                                       f"{[j.name for j in chain if j.kind not in (JointKind.REVOLUTE, JointKind.CONTINUOUS)]}")
    if len(chain) != 6:
        return ClosedForm(frame, None, f"its chain has {len(chain)} joints, not 6 (lock the extra ones, "
                                       "load_robot(..., locked={...}))")
    data = model.createData()
    pin.framesForwardKinematics(model, data, robot.to_pinocchio(np.zeros(robot.n)))
    H = np.array([data.oMi[j.pin_id].rotation @ j.axis for j in chain])
    P = np.array([data.oMi[j.pin_id].translation for j in chain])
    M = data.oMf[fid].homogeneous.copy()
    signs = np.ones(6)
    for i in range(1, 6):  # parallel axes turned to the direction of the first of them
        for k in range(i):
            if np.linalg.norm(np.cross(H[i], H[k])) < GEOMETRY and H[i] @ H[k] < 0:
                H[i], signs[i] = -H[i], -1.0
                break
    coordinates = np.array([j.index for j in chain], dtype=np.int64)
    code, centre, P, reason = _family(H, P)
    if code == 0:
        return ClosedForm(frame, None, reason, coordinates)
    limits = robot.lower[coordinates], robot.upper[coordinates]
    lower, upper = np.where(signs > 0, limits[0], -limits[1]), np.where(signs > 0, limits[1], -limits[0])
    Minv = np.linalg.inv(M)
    tables = (table(H, P, centre, M, Minv, lower, upper, signs),
              table(H, P, centre, M, Minv, np.full(6, -np.pi), np.full(6, np.pi), signs))
    return ClosedForm(frame, FAMILIES[code], "", coordinates, code, signs, H, P, centre, M, Minv, lower, upper, tables)


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
