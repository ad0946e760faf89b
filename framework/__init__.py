"""metaik: inverse kinematics by optimization for any robot described by URDF/xacro.

The data flow follows the package layout: robot model (:mod:`~framework.model.robot`, :mod:`~framework.model.loading`,
:mod:`~framework.model.compose`) → population kinematics (:mod:`~framework.model.kinematics`) → cost terms → solvers →
tracking → results and recordings.
"""

from .model.compose import Mount, mount, mount_urdf, planar_base_urdf
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
from .model.kinematics import FramePoses
from .model.loading import load_robot, robot_from_urdf, robot_index
from .costs.problem import Evaluation, Problem
from .model.joints import Joint, JointKind
from .model.robot import Robot
from .solvers.solve import IKResult, solve
from .solvers.batch import BatchResult, solve_batch
from .geometry.collision import CollisionReport, Contact, RobotShape
from .geometry.scene import Box, Capsule, Mesh, Plane, Prism, Scene, Sphere
from .solvers import solver_names
from .solvers.analytic import AnalyticBatch, AnalyticIK, AnalyticSolutions, ClosedForm, analytic_ik, analytic_ik_batch, closed_form

__version__ = "0.1.0"

__all__ = [
    "AnalyticSolutions",
    "ClosedForm",
    "analytic_ik",
    "analytic_ik_batch",
    "AnalyticBatch",
    "AnalyticIK",
    "closed_form",
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
    "Prism",
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
