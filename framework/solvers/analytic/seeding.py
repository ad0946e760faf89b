"""Closed-form solutions as the engine's start: where a problem's pose task falls on an arm solved in closed form,
its solve starts from the solution that costs least (the numeric engine then has nothing left to do for a pose
alone, and the rest — regularizers over other joints, collision terms, a second arm — from the right branch).

Only the first pose task term with a closed form is used; without one, nothing changes (a lookup per solve). A 7R
arm's closed form (a searched joint, :mod:`~.free_joint`) does not seed: the numeric engine alone was faster there
(benchmarks/closed_form.py).
"""

from __future__ import annotations

import numpy as np

from .solutions import closed_form

#: Solutions whose cost is within this of the least are ties: the one nearest the start among them is taken.
TIE = 1e-12


def closed_form_start(problem, x0: np.ndarray) -> np.ndarray | None:
    """The exact solution of ``problem``'s pose task (from :func:`~.solutions.closed_form`) whose cost is least —
    the one nearest ``x0`` ``(n,)`` among equals —, the other joints at ``x0``; ``None`` when the problem has no
    pose task on a closed-form chain, or the pose has no solution within the limits."""
    robot = problem.robot
    for _, term in problem.objective:
        target = term.pose_target() if term.is_task else None
        if target is None:
            continue
        form = closed_form(robot, target[0])
        if not form.exists or form.free.size:
            continue
        if len(problem.objective) == 1:  # the pose alone: every solution costs 0, the nearest is taken
            X = form.nearest(target[1], x0)
            return X[0] if len(X) else None
        X = form.solutions(target[1], x0)  # every 2π copy: the other terms may prefer any
        if len(X) <= 1:
            return X[0] if len(X) else None
        cost = problem.cost(X)
        return X[int(np.argmax(cost <= cost.min() + TIE))]
    return None


def settles(problem) -> bool:
    """Whether a closed-form start is ``problem``'s answer as it is: its objective is the pose term alone (nothing
    else to weigh, nothing to check), so the engine has nothing to add."""
    return len(problem.objective) == 1 and not problem.checks_collisions


def prepare(problem) -> None:
    """Load the closed form's compiled code for ``problem``'s pose task, if it has one (before a time budget starts:
    :meth:`~framework.solvers.ik.IKSolver.prepare`; once per robot and frame: a prepared solve pays a lookup)."""
    for _, term in problem.objective:
        target = term.pose_target() if term.is_task else None
        form = None if target is None else closed_form(problem.robot, target[0])
        if form is not None and form.exists and not form.free.size:
            problem.robot.derived(_load, target[0])
            return


def _load(robot, frame: str) -> bool:
    """Call the closed form of ``frame`` once (its compiled code loaded from the cache, or compiled)."""
    form = closed_form(robot, frame)
    form.nearest(form.M[:3, 3].tolist() + form.M[:3, :3].ravel().tolist(), robot.middle)
    return True
