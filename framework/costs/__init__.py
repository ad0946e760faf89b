"""Cost terms (the task layer): each maps a population ``(pop, n)`` to ``(pop,)``; they compose with weights."""

from .base import Linearization, LocalKinematics, Objective, Term, stacked_residuals
from .limits import JointLimitPenalty
from .motion import Motion
from .orientation import Orientation, quaternion_error
from .position import Position
from .relative import RelativePosition

__all__ = [
    "JointLimitPenalty",
    "Linearization",
    "LocalKinematics",
    "Motion",
    "Objective",
    "Orientation",
    "Position",
    "RelativePosition",
    "Term",
    "quaternion_error",
    "stacked_residuals",
]
