"""What to draw of a robot (:class:`RobotDrawing`), shared by the meshcat viewer (:mod:`framework.viz.viewer`) and
the rerun recordings (:mod:`framework.io.recording`).

:class:`RobotDrawing` turns a configuration into world-frame geometry with Pinocchio: every frame origin joined
to its parent frame's origin (the links as segments, fixed and locked joints included), the joint origins,
axes for chosen frames, and the URDF's ``<visual>`` meshes and primitives where their files resolve locally
(``package://`` paths are looked up next to the URDF, in ``ROS_PACKAGE_PATH`` and in installed ``cmeel`` data
such as example-robot-data; nothing is downloaded).
"""

from __future__ import annotations

import os
import sysconfig
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from ..errors import RobotFileError
from ..model.xacro_files import find_package

if TYPE_CHECKING:  # pragma: no cover
    from ..model.robot import Robot

#: Colours (RGB 0-255) used by the recordings and the meshcat viewer.
LINK_COLOR = (255, 127, 14)
JOINT_COLOR = (40, 40, 40)
TARGET_COLOR = (214, 39, 40)
DESIRED_COLOR = (31, 119, 180)
TRACKED_COLOR = (44, 160, 44)
VISUAL_COLOR = (190, 190, 190)


@dataclass(frozen=True)
class Visual:
    """One ``<visual>`` of the URDF, attached to a link.

    Attributes:
        link: the link (a body frame of the model).
        frame_id: its Pinocchio frame index.
        origin: ``(4, 4)`` placement of the geometry in the link frame.
        kind: ``"mesh"``, ``"box"``, ``"cylinder"`` (along its z axis) or ``"sphere"``.
        size: mesh scale ``(3,)``; box edge lengths ``(3,)`` [m]; cylinder ``(radius, length)`` [m]; sphere
            ``(radius,)`` [m].
        path: the resolved mesh file (meshes only).
        rgba: colour from the URDF material, each in ``[0, 1]``, if it has one.
    """

    link: str
    frame_id: int
    origin: np.ndarray = field(repr=False)
    kind: str
    size: np.ndarray = field(repr=False)
    path: Path | None = None
    rgba: tuple[float, float, float, float] | None = None


class RobotDrawing:
    """What a viewer draws of a robot: links as segments between frame origins, joints, frames, visuals.

    Computed with Pinocchio from ``robot.model`` (locked joints already folded in), so composed and reduced
    robots draw like any other. Shared by the rerun recordings and the meshcat viewer.

    Args:
        robot: the robot.
        frames: frames drawn as axes (default: the end-effectors).
    """

    def __init__(self, robot: Robot, frames: Sequence[str] | None = None):
        self.robot = robot
        self.frames = tuple(robot.end_effectors if frames is None else frames)
        self.frame_ids = np.array([robot.frame_id(f) for f in self.frames], dtype=int)
        model = robot.model
        self._data = model.createData()
        self.joint_frame_ids = np.array(
            [i for i, f in enumerate(model.frames) if f.type == pin.FrameType.JOINT], dtype=int
        )
        self.segment_frame_ids = self._segments()
        self.visuals, self.missing = robot_visuals(robot)

    def _segments(self) -> np.ndarray:
        """``(m, 2)`` (parent frame, frame) pairs whose origins are apart in some sampled configuration."""
        model = self.robot.model
        pairs = np.array([(f.parentFrame, i) for i, f in enumerate(model.frames) if i > 0], dtype=int)
        if pairs.size == 0:
            return pairs.reshape(0, 2)
        rng = np.random.default_rng(0)
        samples = np.vstack([self.robot.middle, self.robot.random_configurations(rng, 3)])
        M = self.world_frames(samples)
        origins = M[..., :3, 3]
        length = np.linalg.norm(origins[:, pairs[:, 0]] - origins[:, pairs[:, 1]], axis=-1)
        return pairs[(length > 1e-9).any(axis=0)]

    def world_frames(self, X: np.ndarray) -> np.ndarray:
        """``(pop, nframes, 4, 4)`` world placement of every frame of the model for ``X`` ``(pop, n)``."""
        X = self.robot.check_population(X)
        model = self.robot.model
        if len(self._data.oMf) != model.nframes:  # frames added since (Robot.add_frame): Pinocchio sizes Data once
            self._data = model.createData()
        data = self._data
        out = np.empty((X.shape[0], model.nframes, 4, 4))
        for k, q in enumerate(self.robot.to_pinocchio(X)):
            pin.framesForwardKinematics(model, data, q)
            for i in range(model.nframes):
                out[k, i] = data.oMf[i].homogeneous
        return out

    def segments(self, M: np.ndarray) -> np.ndarray:
        """``(pop, m, 2, 3)`` link segments [m] from :meth:`world_frames` ``M``."""
        ids = self.segment_frame_ids
        origins = M[..., :3, 3]
        return np.stack([origins[:, ids[:, 0]], origins[:, ids[:, 1]]], axis=2)

    def joint_origins(self, M: np.ndarray) -> np.ndarray:
        """``(pop, j, 3)`` world positions of the joints [m]."""
        return M[:, self.joint_frame_ids][..., :3, 3]

    def frame_placements(self, M: np.ndarray) -> np.ndarray:
        """``(pop, k, 4, 4)`` world placements of :attr:`frames`."""
        return M[:, self.frame_ids]

    def visual_placements(self, M: np.ndarray) -> np.ndarray:
        """``(pop, v, 4, 4)`` world placements of :attr:`visuals` (without the mesh scale)."""
        if not self.visuals:
            return np.zeros((M.shape[0], 0, 4, 4))
        ids = np.array([v.frame_id for v in self.visuals])
        origins = np.stack([v.origin for v in self.visuals])
        return M[:, ids] @ origins


def robot_visuals(robot: Robot) -> tuple[tuple[Visual, ...], tuple[str, ...]]:
    """The URDF's ``<visual>`` elements whose geometry can be drawn, and the mesh files that did not resolve."""
    if not robot.urdf:
        return (), ()
    try:
        root = ET.fromstring(robot.urdf)
    except ET.ParseError:
        return (), ()
    base_dir = Path(robot.source).parent if robot.source else None
    materials = {m.get("name"): _rgba(m) for m in root.findall("material")}
    visuals, missing = [], []
    for link in root.findall("link"):
        name = link.get("name")
        if not robot.model.existFrame(name, pin.FrameType.BODY):
            continue
        frame_id = robot.model.getFrameId(name, pin.FrameType.BODY)
        for element in link.findall("visual"):
            geometry = element.find("geometry")
            if geometry is None or len(geometry) == 0:
                continue
            shape = geometry[0]
            origin = _origin(element.find("origin"))
            material = element.find("material")
            rgba = None
            if material is not None:
                rgba = _rgba(material) or materials.get(material.get("name"))
            if shape.tag == "mesh":
                path = resolve_mesh(shape.get("filename", ""), base_dir, robot.package_dirs)
                if path is None:
                    missing.append(shape.get("filename", ""))
                    continue
                scale = np.array(_floats(shape.get("scale", "1 1 1"), 3))
                visuals.append(Visual(name, frame_id, origin, "mesh", scale, path, rgba))
            elif shape.tag == "box":
                visuals.append(
                    Visual(name, frame_id, origin, "box", np.array(_floats(shape.get("size"), 3)), None, rgba)
                )
            elif shape.tag == "cylinder":
                size = np.array([float(shape.get("radius", 0)), float(shape.get("length", 0))])
                visuals.append(Visual(name, frame_id, origin, "cylinder", size, None, rgba))
            elif shape.tag == "sphere":
                visuals.append(
                    Visual(
                        name,
                        frame_id,
                        origin,
                        "sphere",
                        np.array([float(shape.get("radius", 0))]),
                        None,
                        rgba,
                    )
                )
    return tuple(visuals), tuple(dict.fromkeys(missing))


def resolve_mesh(filename: str, base_dir: Path | None = None, package_dirs: Any = ()) -> Path | None:
    """A local file for a URDF mesh path (absolute, relative, ``file://`` or ``package://``), or None; a package is
    looked for in ``package_dirs`` first (as the robot's xacro includes were), then beside the file and in the ROS
    environment."""
    filename = filename.removeprefix("file://")
    if filename.startswith("package://"):
        package, _, rest = filename[len("package://") :].partition("/")
        candidates = []
        if package_dirs:
            try:
                candidates.append(find_package(package, package_dirs) / rest)
            except RobotFileError:
                pass
        if base_dir is not None:
            for ancestor in [base_dir, *base_dir.parents]:
                if ancestor.name == package:
                    candidates.append(ancestor / rest)
                candidates.append(ancestor / package / rest)
        candidates += [Path(root) / package / rest for root in _package_roots()]
    elif "://" in filename:
        return None  # http:// and friends: never downloaded
    else:
        path = Path(filename)
        candidates = [path] if path.is_absolute() else ([base_dir / path] if base_dir is not None else [])
    return next((c.resolve() for c in candidates if c.is_file()), None)


def _package_roots() -> list[str]:
    roots = [p for p in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep) if p]
    roots += [str(Path(p) / "share") for p in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p]
    for key in ("purelib", "platlib"):
        share = Path(sysconfig.get_paths()[key]) / "cmeel.prefix" / "share"
        if share.is_dir():
            roots.append(str(share))
    return list(dict.fromkeys(roots))


def _floats(text: str | None, size: int) -> list[float]:
    values = [float(v) for v in (text or "").split()]
    return values if len(values) == size else [0.0] * size


def _origin(element: ET.Element | None) -> np.ndarray:
    if element is None:
        return np.eye(4)
    M = np.eye(4)
    M[:3, :3] = pin.rpy.rpyToMatrix(*_floats(element.get("rpy", "0 0 0"), 3))
    M[:3, 3] = _floats(element.get("xyz", "0 0 0"), 3)
    return M


def _rgba(material: ET.Element) -> tuple[float, float, float, float] | None:
    color = material.find("color")
    if color is None or not color.get("rgba"):
        return None
    values = _floats(color.get("rgba"), 4)
    return tuple(values)  # type: ignore[return-value]
