"""Following a path of end-effector set-points, each solve warm-started from the previous solution.

With M-FABRIK and a step ``ρ``, Algorithm 2 (:mod:`framework.fabrik.steps`) inserts intermediate configurations
wherever consecutive base positions are more than ``ρ`` apart.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .mfabrik import MFabrik
from .steps import Steps, intermediate_configurations

#: ``solve(target, x0, tolerance=..., max_iterations=...)``, e.g. ``MFabrik(...).solve`` (a :class:`ReachResult`) or
#: a call of :func:`framework.solve` (an :class:`~framework.solve.IKResult`): a result with ``configuration``,
#: ``iterations``, ``wall_time`` and ``success``.
Solve = Callable[..., Any]


@dataclass(frozen=True)
class Tracking:
    """The outcome of following a path.

    Attributes:
        results: one result per set-point (:class:`ReachResult` or :class:`~framework.solve.IKResult`).
        steps: per set-point, Algorithm 2's intermediate configurations before it (None without a step).
    """

    results: tuple[Any, ...]
    steps: tuple[Steps | None, ...] = field(repr=False)

    @property
    def configurations(self) -> np.ndarray:
        """``(m, n)`` the configuration reached at each set-point."""
        return np.array([r.configuration for r in self.results])

    @property
    def iterations(self) -> np.ndarray:
        """``(m,)`` iterations per set-point."""
        return np.array([r.iterations for r in self.results])

    @property
    def wall_times(self) -> np.ndarray:
        """``(m,)`` seconds per set-point (solves only, not Algorithm 2)."""
        return np.array([r.wall_time for r in self.results])

    @property
    def success(self) -> bool:
        """Every set-point reached and every base transition planned."""
        return all(r.success for r in self.results) and all(s is None or s.success for s in self.steps)


def track(
    solve: Solve,
    targets: np.ndarray,
    x0: np.ndarray,
    *,
    tolerance: float = 1e-3,
    max_iterations: int = 1000,
    step: float | None = None,
    planner: MFabrik | None = None,
) -> Tracking:
    """Solve for each set-point of ``targets`` ``(m, 3)`` [m] in turn, starting from ``x0`` ``(n,)``.

    Args:
        solve: a solver's ``solve`` method.
        targets: set-points in the world frame [m].
        x0: start configuration; each later solve starts from the previous solution.
        tolerance, max_iterations: passed to every solve.
        step: Algorithm 2's ``ρ`` [m]; requires ``planner`` (the M-FABRIK solver that plans the steps).
        planner: the M-FABRIK solver for Algorithm 2.
    """
    if step is not None and planner is None:
        raise ValueError("a step ρ needs the M-FABRIK solver that plans it (planner=...)")
    results, steps, x = [], [], np.asarray(x0, dtype=float)
    for target in np.asarray(targets, dtype=float):
        result = solve(target, x, tolerance=tolerance, max_iterations=max_iterations)
        if step is not None and planner is not None:
            steps.append(intermediate_configurations(planner, x, result.configuration, target, step))
        else:
            steps.append(None)
        results.append(result)
        x = result.configuration
    return Tracking(tuple(results), tuple(steps))
