"""Every term type a task file can name: one import line per term class (its module holds all the rest: the term,
its block kinds' kernels, its task-file type and keys, its report category)."""

from __future__ import annotations

from .base import Term
from .collision import Obstacles, SelfCollision  # noqa: F401
from .com import CenterOfMass  # noqa: F401
from .cone import Cone  # noqa: F401
from .direction import Direction  # noqa: F401
from .distance import Distance  # noqa: F401
from .limits import JointLimitPenalty  # noqa: F401
from .look_at import LookAt  # noqa: F401
from .motion import JointTarget, Motion  # noqa: F401
from .orientation import Orientation  # noqa: F401
from .point_on_line import PointOnLine  # noqa: F401
from .point_on_plane import PointOnPlane  # noqa: F401
from .pose import Pose  # noqa: F401
from .position import Position  # noqa: F401
from .relative_pose import RelativePose  # noqa: F401
from .relative_position import RelativePosition  # noqa: F401

#: The term classes imported above, in that order.
TERM_CLASSES: tuple[type[Term], ...] = tuple(
    value for value in dict(globals()).values() if isinstance(value, type) and issubclass(value, Term)
    and value.task_type is not None)
#: ``type`` -> term class.
TERM_TYPES: dict[str, type[Term]] = {cls.task_type: cls for cls in TERM_CLASSES}
