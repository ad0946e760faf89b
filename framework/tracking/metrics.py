"""Results of a tracked path: :class:`TrackingResult`, per-waypoint errors, smoothness (joint steps)."""


from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..costs.program import wrapping_coordinates
from ..model.robot import Robot
from ..solvers.solve import IKResult
from .trajectory import Trajectory


# ---------------------------------------------------------------------------------------------- smoothness
@dataclass(frozen=True)
class Smoothness:
    """Joint steps between consecutive waypoints, per joint group, as numbers.

    The step of group ``g`` at waypoint ``k >= 1`` is ``‖q_g,k − q_g,k−1‖∞`` (the largest single joint move)
    [rad, or m for prismatic/planar translations]; angles of continuous joints and planar headings are wrapped.

    Attributes:
        max_step, mean_step: group -> largest / mean step along the path (``k = 1 .. K−1``).
        worst_point: group -> waypoint ``k`` of the largest step (where the motion jumps).
        approach: group -> step from the initial configuration to the first waypoint (not part of the path).
        steps: group -> ``(K − 1,)`` the steps themselves.
    """

    max_step: dict[str, float]
    mean_step: dict[str, float]
    worst_point: dict[str, int]
    approach: dict[str, float]
    steps: dict[str, np.ndarray] = field(repr=False)


def joint_steps(robot: Robot, Q: np.ndarray, initial: np.ndarray | None = None) -> Smoothness:
    """Smoothness of a joint path ``Q`` ``(K, n)`` per group of ``robot`` (and ``"all"``)."""
    Q = robot.check_population(Q, "joint path")
    start = Q[0] if initial is None else robot.check_population(initial, "initial configuration")[0]
    D = np.diff(np.vstack([start, Q]), axis=0)
    wrap = wrapping_coordinates(robot)
    D[:, wrap] = (D[:, wrap] + np.pi) % (2 * np.pi) - np.pi
    groups = {"all": np.arange(robot.n), **{g: np.asarray(i) for g, i in robot.groups.items()}}
    max_step, mean_step, worst, approach, steps = {}, {}, {}, {}, {}
    for name, idx in groups.items():
        s = np.abs(D[:, idx]).max(axis=1)
        approach[name] = float(s[0])
        path = s[1:]
        steps[name] = path
        max_step[name] = float(path.max()) if path.size else 0.0
        mean_step[name] = float(path.mean()) if path.size else 0.0
        worst[name] = int(np.argmax(path)) + 1 if path.size else 0
    return Smoothness(max_step, mean_step, worst, approach, steps)


# ---------------------------------------------------------------------------------------------- result
@dataclass(frozen=True)
class TrackingResult:
    """What tracking a trajectory produced, one entry per waypoint done (``len(result)`` of them).

    Attributes:
        trajectory: the desired path (all ``K`` waypoints, even if stopped early).
        configurations: ``Q`` ``(k, n)`` joint coordinates per waypoint [rad / m].
        initial: ``(n,)`` the configuration before the first waypoint (``q_prev`` of the first solve).
        position_error: ``(k,)`` sum of the unweighted position terms [m] (with a follower: ``e_t1 + e_t2``).
        orientation_error: ``(k,)`` sum of the orientation terms (``|sin(φ/2)|``; zeros without orientation).
        motion_error: ``(k,)`` sum of the unweighted motion terms (each in its own norm).
        task_error, cost: ``(k,)`` task error (decides success) and objective value per waypoint.
        terms: term name -> ``(k,)`` unweighted values.
        iterations, evaluations: ``(k,)`` per waypoint; times: ``(k,)`` seconds per waypoint.
        success: ``(k,)`` ``task_error <= tolerance``.
        stop_reason: ``"completed"``, ``"interrupted"`` (Ctrl-C) or ``"callback"``.
        solver, settings: what ran, with every setting.
        wall_time, cpu_time: seconds for the whole run (wall clock, and CPU time of this process).
        reason: what went wrong, in one line: the waypoints missed (and the first one's
            :attr:`~framework.solvers.solve.IKResult.reason`), those the joint limits held back, those not solved;
            ``""`` when every waypoint was.
        lagging: ``(k,)`` the waypoints whose configuration the joint velocity or acceleration limits held short of
            their solution (``track(..., velocity_scale=...)`` on a timed path).
    """

    trajectory: Trajectory
    configurations: np.ndarray
    initial: np.ndarray
    position_error: np.ndarray
    orientation_error: np.ndarray
    motion_error: np.ndarray
    task_error: np.ndarray
    cost: np.ndarray
    terms: dict[str, np.ndarray] = field(repr=False)
    iterations: np.ndarray = field(repr=False)
    evaluations: np.ndarray = field(repr=False)
    times: np.ndarray = field(repr=False)
    success: np.ndarray = field(repr=False)
    stop_reason: str = "completed"
    solver: str = ""
    settings: dict[str, Any] = field(default_factory=dict, repr=False)
    wall_time: float = 0.0
    cpu_time: float = 0.0
    reason: str = ""
    lagging: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool), repr=False)

    def __len__(self) -> int:
        return self.configurations.shape[0]

    @property
    def completed(self) -> bool:
        """True when every waypoint of the trajectory was solved."""
        return len(self) == self.trajectory.K

    @property
    def all_success(self) -> bool:
        return self.completed and bool(self.success.all())

    def frame_positions(self, robot: Robot, frames: Sequence[str] | str | None = None) -> np.ndarray:
        """World positions of ``frames`` along the joint path: ``(k, len(frames), 3)`` [m]."""
        return robot.frame_poses(self.configurations, frames).positions

    def smoothness(self, robot: Robot) -> Smoothness:
        """Joint steps per group (see :func:`joint_steps`)."""
        return joint_steps(robot, self.configurations, self.initial)

    def summary(self, robot: Robot | None = None) -> dict[str, float]:
        """Mean / max errors, totals and (with ``robot``) the largest joint step along the path."""
        out = {
            "points": float(len(self)),
            "position_mean": _mean(self.position_error),
            "position_max": _max(self.position_error),
            "orientation_mean": _mean(self.orientation_error),
            "orientation_max": _max(self.orientation_error),
            "motion_mean": _mean(self.motion_error),
            "motion_max": _max(self.motion_error),
            "success_rate": _mean(self.success.astype(float)),
            "evaluations": float(self.evaluations.sum()),
            "time": self.wall_time,
            "cpu_time": self.cpu_time,
        }
        if robot is not None and len(self):
            smooth = self.smoothness(robot)
            out["max_step"] = smooth.max_step["all"]
            out["mean_step"] = smooth.mean_step["all"]
        return out


def _mean(a: np.ndarray) -> float:
    return float(a.mean()) if a.size else float("nan")


def _max(a: np.ndarray) -> float:
    return float(a.max()) if a.size else float("nan")


def waypoint_errors(result: IKResult, kinds: Sequence[str]) -> tuple[float, float, float]:
    """A waypoint's position, orientation and motion errors: the sums of its unweighted terms of each kind
    (``kinds``: :attr:`~framework.costs.program.Program.term_kinds` of its problem)."""
    totals = {"position": 0.0, "orientation": 0.0, "motion": 0.0}
    errors = None
    for (name, value), kind in zip(result.terms.items(), kinds):
        if kind in totals:
            totals[kind] += value
        elif kind == "other":  # a term of both (a pose): its distance [m] and its angle as sin(φ/2)
            errors = result.errors if errors is None else errors
            totals["position"] += errors.get(f"{name}.distance", 0.0)
            totals["orientation"] += float(np.sin(0.5 * errors.get(f"{name}.angle", 0.0)))
    return totals["position"], totals["orientation"], totals["motion"]


def path_reason(results: Sequence, K: int, stop_reason: str, lagging: Sequence[bool] = ()) -> str:
    """:attr:`TrackingResult.reason` of the waypoint results ``results`` (``IKResult``) of a path of ``K``
    (``lagging``: those the joint limits held back)."""
    missed = [k for k, r in enumerate(results) if not r.success]
    parts = []
    if missed:
        parts.append(f"{len(missed)} of {len(results)} waypoints missed (k = {spans(missed)}); waypoint {missed[0]}: "
                     f"{results[missed[0]].reason}")
    held = [k for k, lag in enumerate(lagging) if lag]
    if held:
        parts.append(f"the joint velocity / acceleration limits held {len(held)} waypoints back (k = {spans(held)}): "
                     "the path is faster than the robot may move; retime=True (or a slower timed path) meets it")
    if len(results) < K:
        parts.append(f"stopped ({stop_reason}) after {len(results)} of {K} waypoints")
    return "; ".join(parts)


def spans(ks: Sequence[int], shown: int = 6) -> str:
    """``"3-7, 12, 20-21"``: runs of consecutive integers (the first ``shown`` runs, then ``...``)."""
    runs: list[list[int]] = []
    for k in ks:
        if runs and k == runs[-1][1] + 1:
            runs[-1][1] = k
        else:
            runs.append([k, k])
    text = ", ".join(f"{a}" if a == b else f"{a}-{b}" for a, b in runs[:shown])
    return text + (", ..." if len(runs) > shown else "")
