"""Cost terms (the task layer): each is defined once by its residual blocks; they compose with weights."""

from ..model.rotations import rotation_from
from .base import LEVELS, Objective, Term, check_weight
from .collision import Obstacles, SelfCollision
from .com import CenterOfMass
from .cone import Cone
from .direction import Direction
from .distance import Distance
from .limits import JointLimitPenalty
from .look_at import LookAt
from .motion import JointTarget, Motion
from .orientation import Orientation
from .point_on_line import PointOnLine
from .point_on_plane import PointOnPlane
from .pose import Pose, pose_from
from .position import Position
from .program import Block, Program
from .relative_pose import RelativePose
from .relative_position import RelativePosition
from .registry import TERM_CLASSES, TERM_TYPES

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
    "PointOnLine",
    "PointOnPlane",
    "Pose",
    "Position",
    "SelfCollision",
    "Obstacles",
    "Program",
    "RelativePose",
    "RelativePosition",
    "TERM_CLASSES",
    "TERM_TYPES",
    "Term",
    "check_weight",
    "pose_from",
    "rotation_from",
]
