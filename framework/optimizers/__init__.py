"""Robot-independent population optimizers (metaheuristics): ``minimize(cost, box, solver=..., rng=...)`` over a
population cost, with the ask/tell contract, bound handling and their own registry.

Every algorithm is one module registered by name; adding one is a new module plus its name in the import list
below (importing a module registers its algorithm).
"""

from . import (  # noqa: F401
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
from .base import Algorithm, Box, OptimizeResult, minimize, repair
from .registry import ALGORITHMS, available_solvers, get_solver, register

__all__ = ["ALGORITHMS", "Algorithm", "Box", "OptimizeResult", "available_solvers", "get_solver", "minimize",
           "register", "repair"]
