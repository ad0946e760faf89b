"""IK solvers on a :class:`~framework.costs.problem.Problem`: the interface (``Request`` -> ``Outcome``), their
registry, the engine-based solvers (``hybrid``, ``multistart_lm``), every optimizer as an IK solver, the Jacobian
baselines, M-FABRIK and the closed form of 6R arms; ``solve`` and ``solve_batch``.

Adding a solver is one new module registered with ``@register_ik("name")`` plus its import line below.
"""

from .. import optimizers  # noqa: F401  (registers the algorithms every IK solver name may also be)
from . import hybrid, multistart  # noqa: F401  (IK solvers on the local engine)
from .baselines import solver as _jacobian_solvers  # noqa: F401  registers "pinv" and "dls" (papers 001, 003)
from .fabrik import solver as _mfabrik_solver  # noqa: F401  registers "mfabrik" (paper 003)
from .analytic import solver as _closed_form_solver  # noqa: F401  registers "closed_form" (6R arms)
from ..optimizers import Algorithm, Box, OptimizeResult, available_solvers, get_solver, minimize, register, repair
from ..optimizers.registry import ALGORITHMS
from .ik import IKSolver, Outcome, Request
from .registry import IK_SOLVERS, ik_solver, register_ik, solver_names

__all__ = [
    "ALGORITHMS",
    "IKSolver",
    "IK_SOLVERS",
    "Outcome",
    "Request",
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
