"""FABRIK and M-FABRIK (paper 003), for chains read from the Pinocchio model.

Layout, in the order data flows: :mod:`~.chain` (which chains, their plane geometry) → :mod:`~.reach` (where the
arm reaches) → :mod:`~.passes` (forward / backward reaching) → :mod:`~.fabrik` (fixed base) → :mod:`~.mobile`,
:mod:`~.environment`, :mod:`~.regions` (base, obstacles, admissible area) → :mod:`~.mfabrik` (Algorithm 1) →
:mod:`~.steps` (Algorithm 2, also along a path tracked by :func:`framework.tracking.track`); :mod:`~.solver`
registers the solver ``mfabrik`` behind :func:`framework.solve`. FABRIK and M-FABRIK return their own
:class:`ReachResult` (with the base's path), which ``mfabrik`` turns into the common result; the Jacobian
baselines of paper 003 are the solvers ``pinv`` and ``dls`` (:mod:`framework.solvers.baselines`).
"""

from .chain import PlanarChain
from .environment import Circle, Environment, Polygon, Rectangle
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
    "Circle",
    "Environment",
    "Fabrik",
    "MFabrik",
    "MobileArm",
    "PlanarChain",
    "Polygon",
    "ReachResult",
    "ReachTable",
    "Rectangle",
    "Steps",
    "UnsupportedBaseError",
    "UnsupportedChainError",
    "algorithm2",
    "intermediate_configurations",
    "shortest_free_path",
]
