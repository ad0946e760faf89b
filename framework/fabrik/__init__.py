"""FABRIK and M-FABRIK (paper 003) with their Jacobian baselines, for chains read from the Pinocchio model.

Layout, in the order data flows: :mod:`~.chain` (which chains, their plane geometry) → :mod:`~.reach` (where the
arm reaches) → :mod:`~.passes` (forward / backward reaching) → :mod:`~.fabrik` (fixed base) → :mod:`~.mobile`,
:mod:`~.environment`, :mod:`~.regions` (base, obstacles, admissible area) → :mod:`~.mfabrik` (Algorithm 1) →
:mod:`~.steps` (Algorithm 2) → :mod:`~.tracking` (paths); :mod:`~.jacobian` holds the pseudo-inverse and damped
least-squares baselines. Every solver returns a :class:`ReachResult`.
"""

from .chain import PlanarChain
from .environment import Circle, Environment, Polygon, Rectangle
from .errors import UnsupportedBaseError, UnsupportedChainError
from .fabrik import Fabrik
from .jacobian import JacobianIK, JacobianSettings, damped_least_squares_ik, pseudo_inverse_ik
from .mfabrik import MFabrik
from .mobile import BaseOrientation, MobileArm
from .reach import ReachTable
from .regions import BaseReach
from .result import ReachResult
from .steps import Steps, intermediate_configurations, shortest_free_path
from .tracking import Tracking, track

__all__ = [
    "BaseOrientation",
    "BaseReach",
    "Circle",
    "Environment",
    "Fabrik",
    "JacobianIK",
    "JacobianSettings",
    "MFabrik",
    "MobileArm",
    "PlanarChain",
    "Polygon",
    "ReachResult",
    "ReachTable",
    "Rectangle",
    "Steps",
    "Tracking",
    "UnsupportedBaseError",
    "UnsupportedChainError",
    "damped_least_squares_ik",
    "intermediate_configurations",
    "pseudo_inverse_ik",
    "shortest_free_path",
    "track",
]
