"""Cost terms (the task layer): each is defined once by its residual blocks; they compose with weights."""

from ..rotations import rotation_from
from .base import LEVELS, Objective, Term, check_weight
from .collision import Obstacles, SelfCollision
from .com import CenterOfMass
from .direction import Cone, Direction, LookAt
from .distance import Distance
from .limits import JointLimitPenalty
from .motion import JointTarget, Motion
from .orientation import Orientation
from .pose import Pose, pose_from
from .position import Position
from .program import Block, Program
from .relative import RelativePose, RelativePosition

__all__ = [
    "LEVELS",
    "Block",
    "CenterOfMass",
    "Cone",
    "LookAt",
    "Direction",
    "Distance",
    "JointLimitPenalty",
    "JointTarget",
    "Motion",
    "Objective",
    "Orientation",
    "Pose",
    "Position",
    "SelfCollision",
    "Obstacles",
    "Program",
    "RelativePose",
    "RelativePosition",
    "Term",
    "check_weight",
    "pose_from",
    "rotation_from",
]
