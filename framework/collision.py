"""Collisions on the exact geometry: the URDF's ``<collision>`` elements (boxes, cylinders, spheres, meshes) as
Pinocchio's geometry model, distances by coal.

Pairs checked: every two geometries on bodies that can move relative to each other (links merged into one body by
fixed or locked joints never are), except adjacent bodies (a joint between them) and the pairs an SRDF disables.
Locked joints' links are part of the shape (a locked torso still collides)::

    shape = RobotShape(robot, srdf="robot.srdf")
    report = shape.check(x)            # CollisionReport: contacts closer than the margin, the smallest distance
    report.colliding, report.contacts  # [Contact("l_forearm", "r_forearm", -0.012), ...]

Meshes are found from ``package://`` paths in ``package_dirs`` and in every folder above the robot file (an
installed ``example-robot-data`` resolves so).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from .errors import RobotFileError
from .robot import Robot


@dataclass(frozen=True)
class Contact:
    """Two geometries closer than the margin: their names and the distance between them [m] (negative: depth of
    penetration, as coal reports it)."""

    a: str
    b: str
    distance: float


@dataclass(frozen=True)
class CollisionReport:
    """The pairs closer than ``margin`` [m] at a configuration, closest first, and the smallest distance of all
    pairs checked."""

    contacts: tuple[Contact, ...]
    min_distance: float
    margin: float

    @property
    def colliding(self) -> bool:
        """Whether any pair is closer than the margin (penetrating, with the default margin 0)."""
        return bool(self.contacts)


class RobotShape:
    """The collision geometry of a robot and the pairs to check (see the module docstring).

    Args:
        robot: the robot; its URDF's ``<collision>`` elements are read against its Pinocchio model.
        srdf: an SRDF file whose ``<disable_collisions>`` pairs are not checked.
        package_dirs: folders holding ROS packages, for ``package://`` mesh paths.
    """

    def __init__(self, robot: Robot, *, srdf: str | Path | None = None, package_dirs: Sequence[str | Path] = ()):
        self.robot = robot
        folders = [str(p) for p in package_dirs]
        if robot.source:
            folders += [str(p) for p in Path(robot.source).resolve().parents]
        try:
            geometry = pin.buildGeomFromUrdfString(robot.model, robot.urdf, pin.GeometryType.COLLISION,
                                                   package_dirs=folders)
        except (ValueError, RuntimeError) as err:
            raise RobotFileError(f"cannot read the collision geometry of {robot.name!r}: {err}") from None
        if geometry.ngeoms == 0:
            raise RobotFileError(f"robot {robot.name!r} has no <collision> geometry")
        model = robot.model
        objects = geometry.geometryObjects
        for i in range(geometry.ngeoms):
            for j in range(i + 1, geometry.ngeoms):
                a, b = objects[i].parentJoint, objects[j].parentJoint
                if a != b and model.parents[a] != b and model.parents[b] != a:
                    geometry.addCollisionPair(pin.CollisionPair(i, j))
        if srdf is not None:
            if not Path(srdf).is_file():
                raise RobotFileError(f"SRDF file {srdf} does not exist")
            pin.removeCollisionPairs(model, geometry, str(srdf))
        self.geometry = geometry
        self._data = model.createData()
        self._geometry_data = geometry.createData()

    @property
    def pairs(self) -> tuple[tuple[str, str], ...]:
        """The geometry pairs checked, by name."""
        objects = self.geometry.geometryObjects
        return tuple((objects[p.first].name, objects[p.second].name) for p in self.geometry.collisionPairs)

    def check(self, x: np.ndarray, margin: float = 0.0) -> CollisionReport:
        """Distances of every pair at joint coordinates ``x`` ``(n,)``; pairs closer than ``margin`` [m] are
        contacts."""
        q = self.robot.to_pinocchio(np.asarray(x, dtype=float))
        pin.computeDistances(self.robot.model, self._data, self.geometry, self._geometry_data, q)
        objects = self.geometry.geometryObjects
        distances = [r.min_distance for r in self._geometry_data.distanceResults]
        contacts = sorted(
            (Contact(objects[p.first].name, objects[p.second].name, float(d))
             for p, d in zip(self.geometry.collisionPairs, distances) if d < margin),
            key=lambda c: c.distance,
        )
        return CollisionReport(tuple(contacts), float(min(distances, default=np.inf)), float(margin))
