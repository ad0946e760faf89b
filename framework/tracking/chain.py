"""Stretches of a path solved in one compiled call, while the solver's engine phase answers every waypoint.

Along a path, a Jacobian solver warm-started from the previous solution solves waypoint ``k`` as: the targets
moved to the waypoint, the motion terms' reference moved to the previous solution, the local engine from that
solution (its :meth:`~framework.solvers.IKSolver.batch_plan`); most waypoints end there. A :class:`Chain` runs
that for a stretch of waypoints in one compiled call (:func:`~framework.engine.batch.follow_items`), without a
Python solve, its checks and its result per waypoint (about half a waypoint's time on paper 000's paths). It stops
at the first waypoint the engine misses; the tracking loop solves that one with the solver itself (its global
phase), then goes on chained.

Each waypoint's answer is the one :func:`~framework.solvers.solve.solve` gives it (the same compiled descent from the same
start and parameters), and the seed generator advances as one solve per waypoint advances it, so the waypoints a
solve falls back to draw what they would have drawn: a path's answers do not depend on where the stretches break.
"""

from __future__ import annotations

import time

import numpy as np

from ..engine.batch import CHUNK, BatchState, follow_items
from ..engine.local import regularized_status
from ..costs.problem import Problem
from ..solvers.solve import IKResult, result_of
from ..solvers import IKSolver, Outcome, Request


class Chain:
    """The waypoints of one path and problem, ready to be solved in compiled stretches (see module).

    Made by :meth:`of`, which says whether the solver's plan allows it; :meth:`run` solves a stretch.
    """

    def __init__(self, problem: Problem, P: np.ndarray, follows: tuple[np.ndarray, np.ndarray], plan,
                 request: Request, solver: str):
        self.problem, self.P, self.follows, self.plan, self.request = problem, P, follows, plan, request
        self.solver = solver
        self.state = BatchState.start(problem.program, np.zeros((P.shape[0], problem.robot.n)))
        self.streams = np.zeros(P.shape[0], dtype=np.uint64)
        self.watch()

    @classmethod
    def of(cls, problem: Problem, planned: tuple[np.ndarray, tuple[np.ndarray, np.ndarray]], method: IKSolver,
           request: Request) -> Chain | None:
        """The chain of ``problem`` at a task's ``path_parameters``: ``(P, follows)``, each waypoint's parameters
        ``P (K, p)`` and the slots that follow the previous solution (the motion terms' reference, written as the
        path is solved), solved by ``method`` with ``request``'s tolerances and budgets, or ``None`` when a waypoint's
        solve is not the engine alone (no plan: a global phase first, a weighted sum that decides, collision terms
        solved first without them) or reads what the compiled loop does not (terms without a compiled form)."""
        program = problem.program
        plan = method.batch_plan(problem, request)
        if plan is None or plan.clear_first or not program.task_rows or program.layout.generic:
            return None
        P, follows = planned
        return cls(problem, np.ascontiguousarray(P, dtype=float), follows, plan, request, method.name)

    def run(self, k: int, previous: np.ndarray, rng: np.random.Generator) -> tuple[list[IKResult], bool]:
        """Solve waypoints ``k, k + 1, ...`` (at most :data:`~framework.engine.batch.CHUNK`) from ``previous``
        ``(n,)``, each with the seed its solve would draw from ``rng`` (left as it was: :meth:`spend` advances it
        by the waypoints kept); returns their results and whether the stretch stopped at a waypoint the engine
        missed (the next one, left to the solver)."""
        items = np.arange(k, min(k + CHUNK, self.P.shape[0]), dtype=np.int64)
        state = self.state
        state.X[k] = previous
        saved = rng.bit_generator.state
        self.streams[items] = rng.integers(0, 2**63, size=items.size).astype(np.uint64)
        rng.bit_generator.state = saved
        done = follow_items(self.problem.program, self.P, state, items, self.plan.first, self.streams, self.follows)
        return [self._result(int(i)) for i in items[:done]], done < items.size

    def watch(self) -> None:
        """Remember the terms' versions (after the tracking loop moved targets itself, or at the start)."""
        self._versions = [t.version for t in self.problem.program.terms]

    def changed(self) -> bool:
        """Whether a term changed since :meth:`watch` (a callback moved one, e.g. an extra term's target): the
        stretch's later waypoints were solved with the old one, and the chain's parameters are stale."""
        return any(t.version != v for t, v in zip(self.problem.program.terms, self._versions))

    @staticmethod
    def spend(rng: np.random.Generator, count: int) -> None:
        """Advance ``rng`` as ``count`` solves advance it (one seed each): the waypoints of a stretch kept."""
        rng.integers(0, 2**63, size=count)

    def _result(self, i: int) -> IKResult:
        """Waypoint ``i``'s result (the engine reached its task), as :func:`~framework.solvers.solve.solve` makes it (the
        exact collision check included, when the problem has collision terms)."""
        state = self.state
        settings = {**self.plan.report, "restart_count": int(state.counts[i, 2]),
                    "regularized": regularized_status(int(state.regularized[i]))}
        outcome = Outcome(state.X[i], "tolerance", int(state.counts[i, 0]), int(state.counts[i, 1]), None, settings,
                          task_errors=state.E[i], values=state.V[i])  # (result_of copies x, reads the rows once)
        start = time.perf_counter() - 1e-9 * state.spent_ns[i]  # the wall time counts the compiled solve
        return result_of(self.problem, outcome, self.solver, self.request, start)
