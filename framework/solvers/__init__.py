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
from framework.solvers import hybrid, multistart  # noqa: F401  (IK solvers on the local engine)
from framework.solvers.base import Algorithm, Box, OptimizeResult, minimize, repair
from framework.solvers.ik import IKSolver, Outcome, Request
from framework.solvers.registry import (
    IK_SOLVERS,
    SOLVERS,
    available_solvers,
    get_solver,
    ik_solver,
    register,
    register_ik,
    solver_names,
)

__all__ = [
    "IKSolver",
    "IK_SOLVERS",
    "Outcome",
    "Request",
    "SOLVERS",
    "ik_solver",
    "register_ik",
    "solver_names",
    "Algorithm",
    "Box",
    "OptimizeResult",
    "available_solvers",
    "get_solver",
    "minimize",
    "register",
    "repair",
]
