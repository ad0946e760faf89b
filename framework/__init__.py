"""metaik: inverse kinematics by optimization for any robot described by URDF/xacro.

The data flow follows the package layout: robot model (:mod:`~framework.robot`, :mod:`~framework.loading`,
:mod:`~framework.compose`) → population kinematics (:mod:`~framework.kinematics`) → cost terms → solvers →
tracking → results and recordings.
"""

from .compose import Mount, mount, mount_urdf, planar_base_urdf
from .costs import (CenterOfMass, SelfCollision, Obstacles, Cone, Direction, Distance, JointLimitPenalty, JointTarget, LookAt, Motion, Objective, Orientation, PointOnLine, PointOnPlane, Pose, Position,
                    RelativePose, RelativePosition, Term)
from .errors import (
    ConfigurationError,
    LimitsError,
    MetaikError,
    ResourceError,
    RobotFileError,
    SolverError,
    TaskError,
    UnknownFrameError,
    UnknownJointError,
    UnknownRobotError,
    UnsupportedJointError,
)
from .kinematics import FramePoses
from .loading import load_robot, robot_from_urdf, robot_index
from .problem import Evaluation, Problem
from .robot import Joint, JointKind, Robot
from .solve import IKResult, solve
from .batch import BatchResult, solve_batch
from .collision import CollisionReport, Contact, RobotShape
from .scene import Box, Capsule, Mesh, Plane, Scene, Sphere
from .solvers import solver_names
from .fabrik import solver as _mfabrik_solver  # noqa: F401  registers "mfabrik" (paper 003) with the solvers
from .baselines import solver as _jacobian_solvers  # noqa: F401  registers "pinv" and "dls" (papers 001, 003)

__version__ = "0.1.0"

__all__ = [
    "ConfigurationError",
    "Evaluation",
    "IKResult",
    "CenterOfMass",
    "CollisionReport",
    "Contact",
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
    "Problem",
    "RelativePose",
    "RelativePosition",
    "Term",
    "solver_names",
    "solve",
    "solve_batch",
    "BatchResult",
    "FramePoses",
    "Joint",
    "JointKind",
    "LimitsError",
    "MetaikError",
    "Mount",
    "ResourceError",
    "Robot",
    "SelfCollision",
    "Obstacles",
    "RobotShape",
    "Scene",
    "Sphere",
    "Box",
    "Capsule",
    "Plane",
    "Mesh",
    "RobotFileError",
    "SolverError",
    "TaskError",
    "UnknownFrameError",
    "UnknownJointError",
    "UnknownRobotError",
    "UnsupportedJointError",
    "load_robot",
    "mount",
    "mount_urdf",
    "planar_base_urdf",
    "robot_from_urdf",
    "robot_index",
]
