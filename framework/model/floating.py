"""Floating bases as six solved coordinates: a free-flyer becomes a chain of three prismatic joints (x, y, z in the
parent frame [m]) and three revolute joints (yaw about z, pitch about y, roll about x [rad]: ``R = Rz Ry Rx``), so
every kernel, the local engine and the metaheuristics treat it as they treat any other joint.

A URDF ``floating`` joint is rewritten this way; ``load_robot(..., floating_base=True)`` adds one above the root link
(named ``root_joint``, as Pinocchio names its free-flyer). The six joints are ``<name>_x``, ``_y``, ``_z``, ``_yaw``,
``_pitch``, ``_roll``; their bounds are ``±translation`` [m], yaw and roll one turn (continuous), pitch
``[−π/2, π/2]`` (the parametrization is singular at its ends), and can be set like any other bound. A floating
joint can be locked at a full pose: a ``pinocchio.SE3``, a 4x4 matrix, a ``(position, rotation)`` pair, or 7 numbers
``(x, y, z, q, q, q, q)`` whose quaternion order is named (``quaternion="xyzw"``, Pinocchio's configuration order, or
``"wxyz"``; :mod:`framework.model.rotations`).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence

import numpy as np
import pinocchio as pin

from ..errors import LimitsError, RobotFileError, TaskError
from .rotations import rotation_from

#: Pinocchio's name for a free-flyer root joint; the name of the one ``floating_base=True`` adds.
ROOT_JOINT = "root_joint"
AXES = (("x", "prismatic", "1 0 0"), ("y", "prismatic", "0 1 0"), ("z", "prismatic", "0 0 1"),
        ("yaw", "continuous", "0 0 1"), ("pitch", "revolute", "0 1 0"), ("roll", "continuous", "1 0 0"))


def coordinate_joints(name: str) -> tuple[str, ...]:
    """The six joints a floating joint ``name`` becomes."""
    return tuple(f"{name}_{axis}" for axis, _, _ in AXES)


def floating_joints(joint_names: Sequence[str]) -> set[str]:
    """Of ``joint_names``, the six joints of every floating joint they hold (all six solved)."""
    names = set(joint_names)
    prefixes = {n[: -len("_x")] for n in names if n.endswith("_x")}
    return {j for prefix in prefixes if set(coordinate_joints(prefix)) <= names for j in coordinate_joints(prefix)}


def _chain(name: str, parent: str, child: str, origin: ET.Element | None, translation: float) -> list[ET.Element]:
    """Links and joints from ``parent`` to ``child`` replacing a floating joint ``name``."""
    elements, previous = [], parent
    for k, (axis, kind, xyz) in enumerate(AXES):
        link = child if k == len(AXES) - 1 else f"{name}_{axis}_link"
        if link != child:
            elements.append(ET.Element("link", name=link))
        joint = ET.Element("joint", name=f"{name}_{axis}", type=kind)
        ET.SubElement(joint, "parent", link=previous)
        ET.SubElement(joint, "child", link=link)
        if k == 0 and origin is not None:
            joint.append(origin)
        ET.SubElement(joint, "axis", xyz=xyz)
        if kind == "prismatic":
            ET.SubElement(joint, "limit", lower=f"{-translation}", upper=f"{translation}", effort="0", velocity="0")
        elif kind == "revolute":
            ET.SubElement(joint, "limit", lower=f"{-np.pi / 2}", upper=f"{np.pi / 2}", effort="0", velocity="0")
        elements.append(joint)
        previous = link
    return elements


def with_floating_joints(root: ET.Element, *, add_root: bool, translation: float) -> tuple[ET.Element, tuple[str, ...]]:
    """``root`` (a parsed URDF) with every ``floating`` joint as six joints, and (``add_root``) a floating joint
    added above the root link; returns the new tree and the names of the floating joints."""
    root = ET.fromstring(ET.tostring(root))
    names = []
    for joint in list(root.findall("joint")):
        if joint.get("type") != "floating":
            continue
        name = joint.get("name")
        parent, child = joint.find("parent").get("link"), joint.find("child").get("link")
        root.remove(joint)
        root.extend(_chain(name, parent, child, joint.find("origin"), translation))
        names.append(name)
    if add_root:
        children = {j.find("child").get("link") for j in root.findall("joint")}
        roots = [link.get("name") for link in root.findall("link") if link.get("name") not in children]
        if len(roots) != 1:
            raise RobotFileError(f"floating_base=True needs one root link; found {roots}")
        world = f"{ROOT_JOINT}_world"
        root.insert(0, ET.Element("link", name=world))
        root.extend(_chain(ROOT_JOINT, world, roots[0], None, translation))
        names.append(ROOT_JOINT)
    return root, tuple(names)


def pose_coordinates(value, name: str, quaternion: str | None = None) -> dict[str, float]:
    """The six joint values of a floating joint ``name`` locked at a pose: a ``pinocchio.SE3``, a 4x4 homogeneous
    matrix, a ``(position, rotation)`` pair, or 7 numbers ``(x, y, z, q, q, q, q)`` in the ``quaternion`` order."""
    what = f"floating joint {name!r} locked at a pose"
    try:
        if isinstance(value, pin.SE3):
            p, R = np.array(value.translation), rotation_from(value, what)
        elif isinstance(value, tuple) and len(value) == 2:
            p, R = np.asarray(value[0], dtype=float), rotation_from(value[1], f"{what}: rotation", quaternion)
        else:
            array = np.array(value, dtype=float)
            if array.shape == (7,):
                p, R = array[:3], rotation_from(array[3:], f"{what}: its quaternion", quaternion)
            elif array.shape == (4, 4):
                p, R = array[:3, 3], rotation_from(array, what)
            else:
                raise TaskError(f"{what}: give a pinocchio.SE3, a 4x4 matrix, a (position, rotation) pair or 7 "
                                f"numbers (x, y, z and a quaternion, its order named); got {value!r}")
    except (TypeError, ValueError):
        raise LimitsError(f"{what}: give a pinocchio.SE3, a 4x4 matrix, a (position, rotation) pair or 7 numbers; "
                          f"got {value!r}") from None
    except TaskError as err:
        raise LimitsError(str(err)) from None
    if p.shape != (3,) or not np.isfinite(p).all():
        raise LimitsError(f"{what}: its position must be 3 finite numbers [m]; got {p!r}")
    roll, pitch, yaw = pin.rpy.matrixToRpy(R)
    values = (*p, yaw, pitch, roll)
    return dict(zip(coordinate_joints(name), map(float, values)))


def expand(names: tuple[str, ...], joints, locked: Mapping, quaternion: str | None = None,
           ) -> tuple[list[str] | None, dict]:
    """``joints=`` and ``locked=`` with floating joint names replaced by their six joints (``locked``: the pose
    as six values; ``quaternion``: the order of a pose's quaternion given as numbers)."""
    if joints is not None:
        joints = [j for name in joints for j in (coordinate_joints(name) if name in names else (name,))]
    out = {}
    for key, value in locked.items():
        out.update(pose_coordinates(value, key, quaternion) if key in names else {key: value})
    return joints, out
