"""``closed_form``: the exact solution of a pose on an arm solved in closed form, as a solver of the framework.

``solve(problem, "closed_form")`` takes a problem whose task fixes one frame's pose (a pose term, or a position and
an orientation term of that frame) on a 6R chain with a closed form (:func:`~.solutions.closed_form`), and returns
its solution that costs least over every 2π copy within the limits — with a motion term to the previous waypoint,
the one nearest it: tracking a path never flips a branch —, the nearest to the start among equals. Other terms
are weighed, not solved: a second arm keeps its start. A pose beyond reach (or outside the limits) ends with the
start and the stop reason ``unreachable``.
"""

from __future__ import annotations

import numpy as np

from ...errors import SolverError
from ..ik import IKSolver, Outcome, Request
from ..multistart import start_configuration
from ..registry import register_ik
from .seeding import TIE, load_every, pose_task


@register_ik("closed_form")
class ClosedFormSolver(IKSolver):
    """Every solution of the pose by the Paden-Kahan subproblems; the least costly one."""

    kind = "closed form (6R families)"
    reference = "Paden 1985 and Kahan (subproblems); Pieper 1968 (spherical wrist); IKFast (Diankov 2010)"

    def prepare(self, problem) -> None:
        """The closed form's compiled code (every solution: the least costly is chosen among them)."""
        task = pose_task(problem)
        if task is not None:
            problem.robot.derived(load_every, task.frame)

    def solve(self, problem, request: Request) -> Outcome:
        task = pose_task(problem)
        if task is None:
            raise SolverError("closed_form solves problems whose task fixes one frame's pose (a pose term, or a "
                              "position and an orientation term of it) on a 6R arm with a closed form (metaik show "
                              "ROBOT names them)")
        x0, start = start_configuration(problem, request, True, closed_form=False)
        X = task.form.solutions(task.pose, x0)
        settings = {"start": start, "family": task.form.family, "solutions": len(X)}
        if not len(X):
            return Outcome(np.array(x0, dtype=float), "unreachable", 0, 0, None, settings)
        cost = problem.cost(X) if len(X) > 1 else np.zeros(1)
        x = X[int(np.argmax(cost <= cost.min() + TIE))]
        return Outcome(x, "tolerance", 1, len(X), None, settings)
