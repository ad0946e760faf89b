"""How to solve: the settings every entry point takes — :func:`~framework.solve`, :func:`~framework.solve_batch`,
:func:`~framework.tracking.track` and the reach functions — with their defaults defined once, here.

Each entry point takes them as keywords (``solver=``, ``tolerance=``, ``time_budget=``, ``seed=``, ``options=``,
...) and checks them where they enter (:func:`~framework.solvers.solve.make_request`, the solver's options by its
own class): a bad one is a :class:`~framework.errors.SolverError` that names it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any


@dataclass(frozen=True)
class Settings:
    """What a solve is asked for, apart from the problem, its start and its seed.

    Attributes:
        solver: an IK solver's name (``metaik solvers``).
        seed: the seed of the solve's randomness (a batch's item ``i``: ``seed + i``).
        tolerance: success threshold of every position-like task term [m].
        angle_tolerance: success threshold of every orientation [rad] (``None``: ``tolerance``).
        time_budget: seconds per solve (``None``: no limit).
        max_iterations: iteration budget per solve (``None``: the solver's own default).
        population: candidates per iteration (metaheuristics, the hybrid's global phase).
        stop_at_tolerance: metaheuristics stop once the task is within tolerance.
        options: the solver's options (``None``: its defaults).
    """

    solver: str = "hybrid"
    seed: int = 0
    tolerance: float = 1e-6
    angle_tolerance: float | None = None
    time_budget: float | None = None
    max_iterations: int | None = None
    population: int = 30
    stop_at_tolerance: bool = False
    options: Mapping[str, Any] | None = None


#: The defaults of ``solve``, ``solve_batch`` and ``track``.
DEFAULTS = Settings()
#: The defaults of capability maps: most of their targets are out of reach, and the engine's restarts alone answer
#: those quickly (the hybrid would search each globally first); a voxel is reached within 0.1 mm (and 0.1 mrad).
MAPS = Settings(solver="multistart_lm", tolerance=1e-4, max_iterations=300)
#: The defaults of base placement: as :data:`MAPS`, with a larger budget per candidate (a whole robot, two hands).
PLACEMENT = replace(MAPS, max_iterations=1500)
