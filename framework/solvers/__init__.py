"""Robot-independent optimizers: ``minimize(cost, box, solver=..., rng=...)`` over a population cost.

Every solver is one module registered by name; adding one is a new module plus its name in the
import list below (importing a module registers its solver).
"""

from framework.solvers import (  # noqa: F401
    cmaes,
    cmaes_fast,
    cpabc,
    cs,
    de,
    dempso,
    hbbo,
    ica,
    impso,
    itlbo,
    pso,
    qpso,
    sca,
    sde,
    tlbo,
    woa,
)
from framework.solvers.base import Algorithm, Box, OptimizeResult, minimize, repair
from framework.solvers.registry import SOLVERS, available_solvers, get_solver, register

__all__ = [
    "SOLVERS",
    "Algorithm",
    "Box",
    "OptimizeResult",
    "available_solvers",
    "get_solver",
    "minimize",
    "register",
    "repair",
]
