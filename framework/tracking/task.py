"""What is tracked: the declarative :class:`TrackingTask` (terms per waypoint, targets moved in place) and the
constants of the loop's warm starts."""


from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from ..costs import JointLimitPenalty, Motion, Objective, Orientation, Position, RelativePosition
from ..solvers.batch import item_parameters
from ..costs.base import Term, check_weight
from ..costs.motion import motion_name
from ..errors import TaskError
from ..costs.problem import Problem
from ..model.robot import Robot
from ..solvers.solve import IKResult
from .trajectory import Trajectory

#: ``builder(k, position (3,), rotation (3, 3) or None, previous (n,)) -> Objective`` for waypoint ``k``.
TaskBuilder = Callable[[int, np.ndarray, "np.ndarray | None", np.ndarray], Objective]
#: ``callback(k, result)`` after each waypoint; returning True stops the tracking (points done are kept).
TrackingCallback = Callable[[int, IKResult], "bool | None"]

#: Generations of the global phase of a solver that has one (the hybrid) at the first waypoint, whose start may
#: be far from the path: the branch it settles on is kept along the whole path (with none, the Puma circle
#: under paper 002's weights settles on a branch from which point 2's optimum does not reach).
FIRST_GLOBAL_ITERATIONS = 30
COORDINATIONS = ("target", "relative")
#: The names of the terms a :class:`TrackingTask` builds at every waypoint (its motion terms are named by
#: :func:`~framework.costs.motion.motion_name`): what :meth:`TrackingTask.objective` names them, :meth:`update`
#: and :meth:`targets` find them by, and ``extra`` terms may not be named.
POSITION, ORIENTATION, FOLLOWER, LIMITS = "position", "orientation", "follower", "joint_limits"

#: Step size [rad / m] of a CMA-ES that continues from the previous waypoint's search distribution (solvers with
#: a ``covariance`` option; the shape: :func:`continued`): its mean starts at the Jacobian prediction, already on
#: the task, and the optimum is about this far from it. Paper 000's paths, 40 points: mean error 1e-12 to 2e-11 m
#: at 1e-4 (1e-3: 2e-10, 0.02: 4e-7); a fresh identity covariance gives 1e-8 to 4e-8 m whatever the step.
CONTINUED_SIGMA0 = 1e-4

#: The first waypoint of such a solver has no previous distribution: its mean starts at the Jacobian prediction,
#: its covariance is :func:`task_covariance` (the task's null space wide, its row space narrowed by
#: ``TASK_SPACE_RATIO``) and its step ``FIRST_SIGMA0`` [rad / m]. Paper 000's four paths from the paper's q_prev,
#: 4 seeds: first-point error 1e-9 to 3e-9 m (identity covariance: 1e-6 to 4e-6 m whatever the step).
FIRST_SIGMA0, TASK_SPACE_RATIO = 0.1, 1e-4


@dataclass(frozen=True)
class TrackingTask:
    """The per-waypoint task, declaratively: which frames follow the path and how terms are weighted.

    Attributes:
        frame: frame that follows the trajectory (default: the robot's first end-effector).
        position_weight: weight of ``‖p_frame − t_k‖`` [m] (α of paper 000, κ of paper 002).
        orientation_weight: weight of the orientation error ``|sin(φ/2)|`` (λ of paper 002); used only when
            the trajectory has orientations.
        motion: joint group -> weight of its motion ``‖q_g − q_g^prev‖`` (β, γ of paper 000, μ of paper 002);
            a single number weights the group ``"all"``; an empty mapping turns motion off.
        motion_norm: ``"l2"`` (paper 000 eq. 10) or ``"l1"`` (paper 002 eq. 16, ``‖·‖₁ / (n π)``).
        follower: second frame of a coordinated dual-arm task, or ``None``.
        offset: ``t_r`` ``(3,)`` [m], world axes: the follower's target is ``t_k + t_r``.
        follower_weight: weight of the follower's term (default: ``position_weight``).
        coordination: ``"target"``: ``‖p_follower − (t_k + t_r)‖`` (paper 000 eq. 8); ``"relative"``:
            ``‖p_follower − (p_frame + t_r)‖`` (paper 001's relative-position error).
        joint_limits: weight δ of a joint-limit penalty (paper 001), or ``None`` for none.
        extra: terms added at every waypoint as they are, with their weights (a :class:`~framework.costs.Term`
            or an :class:`~framework.costs.Objective`): collision terms (``SelfCollision``, ``Obstacles``), a
            posture, ...; their names must differ from the path's own terms'.
    """

    frame: str | None = None
    position_weight: float = 1.0
    orientation_weight: float = 1.0
    motion: Mapping[str, float] | float = field(default_factory=lambda: {"all": 0.1})
    motion_norm: str = "l2"
    follower: str | None = None
    offset: Sequence[float] | None = None
    follower_weight: float | None = None
    coordination: str = "target"
    joint_limits: float | None = None
    extra: Objective | Term | None = None

    def __post_init__(self) -> None:
        check_weight(self.position_weight)
        check_weight(self.orientation_weight)
        motion = {"all": self.motion} if isinstance(self.motion, (int, float)) else dict(self.motion)
        for weight in motion.values():
            check_weight(weight)
        object.__setattr__(self, "motion", motion)
        if self.coordination not in COORDINATIONS:
            raise TaskError(f"coordination must be one of {COORDINATIONS}; got {self.coordination!r}")
        if (self.follower is None) != (self.offset is None):
            raise TaskError("a coordinated task needs both a follower frame and an offset t_r (or neither)")
        if self.offset is not None:
            offset = np.asarray(self.offset, dtype=float)
            if offset.shape != (3,) or not np.all(np.isfinite(offset)):
                raise TaskError(f"the relative offset t_r must be 3 finite numbers [m]; got {self.offset!r}")
            object.__setattr__(self, "offset", offset)
        if self.extra is not None:
            extra = Objective.of(self.extra)
            own = {POSITION, ORIENTATION, FOLLOWER, LIMITS} | {motion_name(g) for g in motion}
            clash = sorted(own & {term.name for _, term in extra})
            if clash:
                raise TaskError(f"extra terms need names other than the path's own terms; got {clash}")
            object.__setattr__(self, "extra", extra)

    def frame_of(self, robot: Robot) -> str:
        return self.frame or robot.end_effectors[0]

    def objective(
        self, robot: Robot, k: int, position: np.ndarray, rotation: np.ndarray | None, previous: np.ndarray
    ) -> Objective:
        """The weighted terms of waypoint ``k``: position, [orientation], [follower], motion, [limits]."""
        frame = self.frame_of(robot)
        objective = self.position_weight * Position(frame, position, name=POSITION)
        if rotation is not None and self.orientation_weight > 0:
            objective = objective + self.orientation_weight * Orientation(frame, rotation, name=ORIENTATION)
        if self.follower is not None:
            weight = self.position_weight if self.follower_weight is None else self.follower_weight
            if self.coordination == "target":
                term = Position(self.follower, position + self.offset, name=FOLLOWER)
            else:
                term = RelativePosition(frame, self.follower, self.offset, name=FOLLOWER)
            objective = objective + weight * term
        for group, weight in self.motion.items():
            objective = objective + weight * Motion(
                group, previous, norm=self.motion_norm, name=motion_name(group)
            )
        if self.joint_limits is not None:
            objective = objective + JointLimitPenalty(self.joint_limits, name=LIMITS)
        if self.extra is not None:
            objective = objective + self.extra
        return objective

    def update(self, objective: Objective, position: np.ndarray, rotation: np.ndarray | None,
               previous: np.ndarray) -> bool:
        """Move the targets of an objective built by :meth:`objective` to the next waypoint, in place.

        Returns False when the objective does not have the shape this waypoint needs (it must be rebuilt).
        """
        terms = {t.name: t for _, t in objective}
        if (ORIENTATION in terms) != (rotation is not None and self.orientation_weight > 0):
            return False
        for name, target in self.targets(position, rotation).items():
            terms[name].set_target(target)
        for group in self.motion:
            terms[motion_name(group)].set_target(previous)
        return True

    def targets(self, positions: np.ndarray, rotations: np.ndarray | None) -> dict[str, np.ndarray]:
        """The targets the path sets, by term name, of one waypoint (``(3,)``, ``(3, 3)`` or ``None``) or of
        many (``(K, 3)``, ``(K, 3, 3)``): position, [orientation], [follower]; the motion terms' reference is the
        previous solution, not part of the path."""
        targets = {POSITION: positions}
        if rotations is not None and self.orientation_weight > 0:
            targets[ORIENTATION] = rotations
        if self.follower is not None and self.coordination == "target":
            targets[FOLLOWER] = positions + self.offset
        return targets

    def path_parameters(self, problem: Problem,
                        trajectory: Trajectory) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray]]:
        """``(P, follows)``: the parameters ``P (K, p)`` of ``problem`` (built by :meth:`objective`) at every
        waypoint of ``trajectory``, the targets moved as :meth:`update` moves them, and the parameters that follow
        the previous solution (the motion terms' reference: slots and coordinates, written as the path is solved;
        an extra term's own reference stays)."""
        P, _ = item_parameters(problem, self.targets(trajectory.positions, trajectory.rotations))
        motion = [problem.names.index(motion_name(group)) for group in self.motion]
        return P, problem.program.layout.references_of(motion)

    def frames(self, robot: Robot) -> tuple[str, ...]:
        """The frames that track: the main frame and, if any, the follower."""
        return (self.frame_of(robot),) + ((self.follower,) if self.follower else ())


