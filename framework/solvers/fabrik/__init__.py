"""FABRIK and M-FABRIK (paper 003), for chains read from the Pinocchio model.

Layout, in the order data flows: :mod:`~.chain` (which chains, their plane geometry) → :mod:`~.reach` (where the
arm reaches) → :mod:`~.passes` (forward / backward reaching) → :mod:`~.fabrik` (fixed base) → :mod:`~.mobile`,
:mod:`~.environment`, :mod:`~.regions` (base, obstacles, admissible area) → :mod:`~.mfabrik` (Algorithm 1) →
:mod:`~.steps` (Algorithm 2, also along a path tracked by :func:`framework.tracking.track`); :mod:`~.solver`
registers the solver ``mfabrik`` behind :func:`framework.solve` and :func:`framework.tracking.track`: it reads the
robot's model (its planar chain and base derived from it), the :class:`~framework.costs.Obstacles` term's scene
(the floor shadows of :meth:`Environment.from_scene`) and task files through the one reader, and returns the
common result. FABRIK and M-FABRIK's own :class:`ReachResult` (with the base's path) stays inside; the Jacobian
baselines of paper 003 are the solvers ``pinv`` and ``dls`` (:mod:`framework.solvers.baselines`).
"""

from .chain import PlanarChain
from .environment import Environment
from .errors import UnsupportedBaseError, UnsupportedChainError
from .fabrik import Fabrik
from .mfabrik import MFabrik
from .mobile import BaseOrientation, MobileArm
from .reach import ReachTable
from .regions import BaseReach
from .result import ReachResult
from .steps import Steps, algorithm2, intermediate_configurations, shortest_free_path

__all__ = [
    "BaseOrientation",
    "BaseReach",
    "Environment",
    "Fabrik",
    "MFabrik",
    "MobileArm",
    "PlanarChain",
    "ReachResult",
    "ReachTable",
    "Steps",
    "UnsupportedBaseError",
    "UnsupportedChainError",
    "algorithm2",
    "intermediate_configurations",
    "shortest_free_path",
]
