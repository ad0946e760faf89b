"""Closed-form solutions inside solves: where a problem's task fixes a frame's pose (a pose term, or a position and
an orientation term of one frame) on an arm solved in closed form, the solve starts from the solution that costs
least (the numeric engine then has nothing left to do for the pose alone, and the rest — regularizers over other
joints, collision terms, a second arm — from the right branch); the ``closed_form`` solver answers with it.

Only the first frame whose pose the task fixes is used; without one, nothing changes (a lookup per solve). A 7R
arm's closed form (a searched joint, :mod:`~.free_joint`) does not seed: the numeric engine alone was faster there
(benchmarks/closed_form.py).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .forms import ClosedForm
from .solutions import closed_form

#: Solutions whose cost is within this of the least are ties: the one nearest the start among them is taken.
TIE = 1e-12


class PoseTask(NamedTuple):
    """A frame whose pose a problem's task terms fix, its closed form, and how many terms fix it."""

    frame: str
    pose: np.ndarray  # (12,) position [m] and row-major rotation
    form: ClosedForm
    terms: int


def pose_task(problem) -> PoseTask | None:
    """The first frame whose position and rotation ``problem``'s task terms fix together
    (:attr:`~framework.costs.problem.Problem.fixed_frames`), if its chain has a closed form (and no searched
    joint); else ``None``."""
    for frame, (placing, turning), count in problem.fixed_frames:
        form = closed_form(problem.robot, frame)
        if form.exists and not form.free.size:
            if placing is turning:  # a pose term: its target as one array
                pose = placing.pose_vector()
            else:
                pose = np.concatenate((placing.frame_target()[1], turning.frame_target()[2].ravel()))
            return PoseTask(frame, pose, form, count)
    return None


def closed_form_start(problem, x0: np.ndarray) -> np.ndarray | None:
    """The exact solution of ``problem``'s pose task whose cost is least — the one nearest ``x0`` ``(n,)`` among
    equals —, the other joints at ``x0``; ``None`` when the problem fixes no pose on a closed-form chain, or the
    pose has no solution within the limits."""
    task = pose_task(problem)
    if task is None:
        return None
    if settles(problem):  # the pose alone: every solution costs 0, the nearest is taken
        X = task.form.nearest(task.pose, x0)
        return X[0] if len(X) else None
    X = task.form.solutions(task.pose, x0)  # every 2π copy: the other terms may prefer any
    if len(X) <= 1:
        return X[0] if len(X) else None
    cost = problem.cost(X)
    return X[int(np.argmax(cost <= cost.min() + TIE))]


def settles(problem) -> bool:
    """Whether a closed-form start (:func:`closed_form_start`) is ``problem``'s answer as it is: its objective is the
    terms fixing the pose alone (nothing else to weigh, nothing to check), so the engine has nothing to add."""
    fixed = problem.fixed_frames  # (a collision term fixes no frame: with one, the count falls short)
    return bool(fixed) and len(problem.objective) == fixed[0][2]


def prepare(problem) -> None:
    """Load the closed form's compiled code that ``problem``'s solve will call, if its task fixes a pose on a
    closed-form arm (before a time budget starts: :meth:`~framework.solvers.ik.IKSolver.prepare`; once per robot,
    frame and entry point — a pose alone needs only the nearest solutions, other terms every solution —: a prepared
    solve pays a lookup)."""
    task = pose_task(problem)
    if task is not None:
        problem.robot.derived(_load_nearest if settles(problem) else load_every, task.frame)


def _load_nearest(robot, frame: str) -> bool:
    """Call the closed form's nearest solutions of ``frame`` once (loaded from the cache, or compiled)."""
    form = closed_form(robot, frame)
    form.nearest(_home(form), robot.middle)
    return True


def load_every(robot, frame: str) -> bool:
    """Call the closed form's every solution of ``frame`` once (loaded from the cache, or compiled)."""
    form = closed_form(robot, frame)
    form.solutions(_home(form), robot.middle)
    return True


def _home(form: ClosedForm) -> np.ndarray:
    """``(12,)`` the frame's pose at the zero configuration (a pose the arm reaches)."""
    return np.concatenate([form.M[:3, 3], form.M[:3, :3].ravel()])
