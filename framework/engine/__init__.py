"""The one local solver: compiled Levenberg-Marquardt to reach the task, Newton steps to regularize on it.

Layers: :mod:`~framework.engine.clock` (a clock compiled code can read), :mod:`~framework.engine.draws`
(seeded uniform draws for the restarts), :mod:`~framework.engine.linalg` (small dense solves),
:mod:`~framework.engine.reach` (Levenberg-Marquardt with restarts), :mod:`~framework.engine.newton`
(regularizers on the task; weighted sums), :mod:`~framework.engine.local` (the Python face). Every local method
of the framework — the hybrid's refinement, multi-start, the tracking predictor, the Jacobian baselines — calls
:func:`solve_local` or its phases.
"""

from .local import (
    LocalResult,
    LocalSettings,
    minimize_sum,
    minimize_weighted,
    objective_derivatives_at,
    prepare,
    reaching_is_optimal,
    residual_arrays,
    residuals,
    search_box,
    solve_local,
)

__all__ = [
    "LocalResult",
    "LocalSettings",
    "minimize_sum",
    "minimize_weighted",
    "objective_derivatives_at",
    "prepare",
    "reaching_is_optimal",
    "residual_arrays",
    "residuals",
    "search_box",
    "solve_local",
]
