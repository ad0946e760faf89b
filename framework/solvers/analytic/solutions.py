"""Closed-form inverse kinematics where the arm's axes allow it: which family a frame's chain belongs to, read
from the Pinocchio model (:func:`closed_form`), every solution of a pose (:func:`analytic_ik`), and a batch of
poses (:func:`analytic_ik_batch`).

The chain is the solved joints that move the frame; other joints keep the reference configuration's values. Its
axes are read at the zero configuration in the world frame (tool offset and locked joints included, whatever the
URDF names its frames) and recognised by :mod:`~framework.solvers.analytic.forms`: a spherical wrist (axes 4, 5,
6 meeting) with axes 2 ∥ 3 or with axes 1, 2 meeting, or axes 2 ∥ 3 ∥ 4 with axes 5, 6 meeting — read from the
base or from the tool back; a 7R chain with one joint searched.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ...costs.pose import pose_parameters
from ...errors import TaskError
from ...model.joints import JointKind
from ...model.robot import Robot
from .families import MOST, exact_solutions, nearest_solutions
from .forms import ClosedForm, five_joints, form_of, homogeneous, with_free_joint
from .free_joint import STEP


@dataclass(slots=True)
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


class AnalyticIK:
    """Every solution of one frame's poses on one robot, prepared once: ``ik = AnalyticIK(robot, frame)``, then
    ``ik(pose)`` (what :func:`analytic_ik` calls; a call takes microseconds). A :class:`TaskError` says why when
    the frame's chain has no closed form.

    Attributes:
        robot, frame: what it solves; form: the chain's :class:`ClosedForm`.
    """

    def __init__(self, robot: Robot, frame: str):
        form = closed_form(robot, frame)
        if not form.exists:
            raise TaskError(f"{frame!r} of {robot.name} has no closed form here: {form.reason}")
        self.robot, self.frame, self.form = robot, frame, form
        self._middle = np.array(robot.middle, dtype=float)  # the default reference (never written)
        self._exact = (form.code, form.tables[0], form.coordinates) if not form.free.size else None

    def __call__(self, pose, *, reference: np.ndarray | None = None, quaternion: str | None = None,
                 tolerance: float = 1e-10) -> AnalyticSolutions:
        """Every solution reaching ``pose`` (``pinocchio.SE3``, 4x4 matrix or ``(position, rotation)``; 4 numbers
        need ``quaternion``) within the joint limits, nearest to ``reference`` ``(n,)`` first (default: the middle
        of the bounds)."""
        x_ref = self._middle if reference is None else _reference(self.robot, reference)
        if self._exact is not None:  # a 6R chain: the pose's transform straight to the compiled call (it checks it)
            T = pose.homogeneous if type(pose) is pin.SE3 else pose if _plain_matrix(pose) else \
                homogeneous(_packed(pose, self.frame, quaternion))
            code, table, coordinates = self._exact
            X = exact_solutions(code, table, coordinates, T, x_ref, float(tolerance))
            if len(X):
                return AnalyticSolutions(X, self.form.family)
        return self._searched_or_none(pose, x_ref, quaternion, tolerance)

    def _searched_or_none(self, pose, x_ref: np.ndarray, quaternion: str | None,
                          tolerance: float) -> AnalyticSolutions:
        """A 7R chain's solutions (its joint searched), or none and why."""
        form = self.form
        packed = _packed(pose, self.frame, quaternion)  # (a pose that is no transform says why here)
        if form.free.size:
            X = form.solutions(packed, x_ref, tolerance)
            if len(X):
                return AnalyticSolutions(X, form.family)
            reason = (f"no value of the searched joint, in steps of {STEP} rad from the reference's, has a solution "
                      "within the limits (the pose may be beyond reach, or reachable between two steps)")
            return AnalyticSolutions(X, form.family, reason)
        reason = ("every solution of the pose is outside the joint limits"
                  if len(form.solutions(packed, x_ref, tolerance, limits=False)) else
                  "the pose is beyond the arm's reach (no exact solution" +
                  ("; a five-joint arm takes only some orientations at a point)" if form.first else ")"))
        return AnalyticSolutions(np.zeros((0, self.robot.n)), form.family, reason)

    def __repr__(self) -> str:
        return f"AnalyticIK({self.robot.name!r}, {self.frame!r}, {self.form.family})"


def analytic_ik(robot: Robot, frame: str, pose, *, reference: np.ndarray | None = None,
                quaternion: str | None = None, tolerance: float = 1e-10) -> AnalyticSolutions:
    """Every solution of ``frame`` reaching ``pose``: :class:`AnalyticIK` ``(robot, frame)`` (made once per robot
    and frame) called on it."""
    return robot.derived(AnalyticIK, frame)(pose, reference=reference, quaternion=quaternion, tolerance=tolerance)


def _plain_matrix(pose) -> bool:
    """Whether ``pose`` is a 4x4 C-contiguous float array (the compiled call's own type: it checks the values)."""
    return type(pose) is np.ndarray and pose.shape == (4, 4) and pose.dtype == np.float64 and pose.flags.c_contiguous


def _packed(pose, frame: str, quaternion: str | None) -> np.ndarray:
    """The pose ``(12,)`` (position, row-major rotation), checked: a :class:`TaskError` names what is wrong."""
    return pose_parameters(pose, lambda: f"pose of {frame!r}", quaternion)


@dataclass(frozen=True)
class AnalyticBatch:
    """The solutions of a batch of poses, each once: as its 2π copy within the limits nearest the reference.

    Attributes:
        chain: ``(B, 8, k)`` the chain's ``k`` coordinates of each pose's solutions, nearest to the reference first (rows
            past ``counts[b]`` are NaN).
        counts: ``(B,)`` how many each pose has (0: beyond reach, or every one outside the limits).
        coordinates: ``(k,)`` the chain's coordinates in the robot's joint vector.
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

    form = robot.derived(AnalyticIK, frame).form
    if form.free.size:
        raise TaskError(f"{frame!r} of {robot.name} is a 7R chain with a searched joint: solve its poses one by one "
                        "(analytic_ik), or lock the joint (load_robot(..., locked={...}))")
    x_ref = np.array(robot.middle if reference is None else _reference(robot, reference), dtype=float)
    packed = np.ascontiguousarray(Pose(frame, pin.SE3.Identity()).target_parameters(robot, poses))
    chain = np.full((len(packed), MOST, 6), np.nan)
    counts = np.zeros(len(packed), dtype=np.int64)

    def work(items: np.ndarray) -> None:
        a, b = int(items[0]), int(items[-1]) + 1
        nearest_solutions(form.code, form.tables[0], form.coordinates, packed[a:b], x_ref, tolerance, chain[a:b],
                          counts[a:b])

    in_chunks(work, len(packed), workers=workers)
    return AnalyticBatch(chain[:, :, form.first:], counts, form.coordinates[form.first:], x_ref)


def _reference(robot: Robot, reference) -> np.ndarray:
    """The reference configuration ``(n,)`` as a writable float array of its own, checked."""
    x = np.array(reference, dtype=float)
    if x.shape != (robot.n,) or not math.isfinite(x.dot(x)):  # (xᵀx: inf or NaN with any such entry; 0.3 µs)
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
    if len(chain) not in (5, 6, 7):
        return ClosedForm(frame, None, f"its chain has {len(chain)} joints, not 6 (or 5, or 7 with one searched; "
                                       "lock the extra ones, load_robot(..., locked={...}))")
    data = model.createData()
    pin.framesForwardKinematics(model, data, robot.to_pinocchio(np.zeros(robot.n)))
    H = np.array([data.oMi[j.pin_id].rotation @ j.axis for j in chain])
    P = np.array([data.oMi[j.pin_id].translation for j in chain])
    M = data.oMf[fid].homogeneous.copy()
    coordinates = np.array([j.index for j in chain], dtype=np.int64)
    if len(chain) == 6:
        return form_of(frame, H, P, M, coordinates, robot.lower, robot.upper)
    if len(chain) == 5:
        return five_joints(frame, H, P, M, coordinates, robot.lower, robot.upper)
    return with_free_joint(frame, H, P, M, coordinates, robot.lower, robot.upper, [j.name for j in chain])


