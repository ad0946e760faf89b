"""Composing robots in code: mount arm URDFs on a base (fixed or mobile) at given transforms.

This is how a user builds a new dual-arm or mobile system from parts::

    robot = mount(planar_base_urdf(), [
        Mount("youbot_arm", parent="platform", xyz=(0.15, 0, 0.14), prefix="arm1_"),
        Mount("youbot_arm", parent="platform", xyz=(-0.15, 0, 0.14), rpy=(0, 0, np.pi), prefix="arm2_"),
    ])

Each arm's links and joints are renamed with its prefix; the arm's joints form the group named after the
prefix (``"arm1"``), the base's movable joints the group ``"base"``.
"""

from __future__ import annotations

import copy
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import RobotFileError
from .loading import parse_urdf, read_robot_file, resolve_robot, robot_from_urdf
from .robot import Robot


@dataclass(frozen=True)
class Mount:
    """One arm to mount: its source, the base link it hangs from, its placement and its name prefix.

    Attributes:
        source: robot index name, path to a URDF/xacro file, or URDF text.
        parent: base link the arm's root link is fixed to.
        xyz: translation of the arm's root in the parent link [m].
        rpy: rotation of the arm's root in the parent link, URDF roll-pitch-yaw [rad].
        prefix: prepended to every link and joint name of the arm (also names its group, without ``_``).
        end_effectors: end-effector frames of the arm, unprefixed (default: the index entry or leaf frames).
        xacro_args: arguments for a xacro source.
    """

    source: str | Path
    parent: str
    xyz: Sequence[float] = (0.0, 0.0, 0.0)
    rpy: Sequence[float] = (0.0, 0.0, 0.0)
    prefix: str = ""
    end_effectors: Sequence[str] | None = None
    xacro_args: Mapping[str, str] = field(default_factory=dict)

    @property
    def group(self) -> str:
        return self.prefix.rstrip("_") or "arm"


def planar_base_urdf(
    name: str = "mobile_base",
    *,
    x: tuple[float, float] = (-1.5, 1.5),
    y: tuple[float, float] = (-1.5, 1.5),
    theta: tuple[float, float] = (-np.pi, np.pi),
) -> str:
    """URDF of an omnidirectional base: prismatic ``base_x``, ``base_y`` and revolute ``base_theta``.

    Links ``world -> base_x_link -> base_y_link -> platform``; the platform frame is the paper's {p} (000 eq. 2).
    Default bounds are paper 000's workspace: x, y in [-1.5, 1.5] m, θ in [-π, π].
    """

    def joint(jname: str, kind: str, parent: str, child: str, axis: str, lim: tuple[float, float]) -> str:
        return (
            f'  <joint name="{jname}" type="{kind}">\n'
            f'    <parent link="{parent}"/>\n    <child link="{child}"/>\n'
            f'    <origin xyz="0 0 0" rpy="0 0 0"/>\n    <axis xyz="{axis}"/>\n'
            f'    <limit lower="{lim[0]!r}" upper="{lim[1]!r}" effort="100" velocity="1"/>\n  </joint>\n'
        )

    links = "".join(f'  <link name="{n}"/>\n' for n in ("world", "base_x_link", "base_y_link", "platform"))
    return (
        f'<?xml version="1.0"?>\n<robot name="{name}">\n{links}'
        + joint("base_x", "prismatic", "world", "base_x_link", "1 0 0", x)
        + joint("base_y", "prismatic", "base_x_link", "base_y_link", "0 1 0", y)
        + joint("base_theta", "revolute", "base_y_link", "platform", "0 0 1", theta)
        + "</robot>\n"
    )


def mount_urdf(base: str | Path, mounts: Sequence[Mount], *, name: str | None = None,
               package_dirs: Sequence[str | Path] | Mapping[str, str | Path] = (), trusted: bool = False) -> str:
    """URDF text of ``base`` with every arm of ``mounts`` attached (see :class:`Mount`; ``package_dirs``,
    ``trusted``: as :func:`framework.load_robot` takes them)."""
    base_root, _ = _read(base, package_dirs=package_dirs, trusted=trusted)
    base_root = copy.deepcopy(base_root)
    if name:
        base_root.set("name", name)
    links = {link.get("name") for link in base_root.findall("link")}
    joints = {joint.get("name") for joint in base_root.findall("joint")}
    for mount in mounts:
        if mount.parent not in links:
            raise RobotFileError(f"cannot mount {mount.source!s:.60}: the base has no link {mount.parent!r}")
        arm_root, directory = _read(mount.source, mount.xacro_args, package_dirs=package_dirs, trusted=trusted)
        arm = _prefixed(arm_root, mount.prefix, directory)
        arm_links = [link.get("name") for link in arm.findall("link")]
        arm_joints = [joint.get("name") for joint in arm.findall("joint")]
        clash = (links & set(arm_links)) | (joints & set(arm_joints))
        if clash:
            raise RobotFileError(f"names {sorted(clash)[:5]} already exist; give the mount a distinct prefix")
        children = {j.find("child").get("link") for j in arm.findall("joint")}
        roots = [link for link in arm_links if link not in children]
        if len(roots) != 1:
            raise RobotFileError(f"arm {mount.source!s:.60} must have one root link; found {roots}")
        for element in arm:
            if element.tag in ("link", "joint"):
                base_root.append(element)
            elif element.tag == "material" and element.get("name") not in {
                m.get("name") for m in base_root.findall("material")
            }:
                base_root.append(element)
        fixed = ET.SubElement(base_root, "joint", name=f"{mount.prefix}mount", type="fixed")
        ET.SubElement(fixed, "parent", link=mount.parent)
        ET.SubElement(fixed, "child", link=roots[0])
        ET.SubElement(fixed, "origin", xyz=_floats(mount.xyz), rpy=_floats(mount.rpy))
        links |= set(arm_links)
        joints |= {*arm_joints, f"{mount.prefix}mount"}
    ET.indent(base_root)
    return ET.tostring(base_root, encoding="unicode")


def mount(
    base: str | Path,
    mounts: Sequence[Mount],
    *,
    name: str | None = None,
    **load_options,
) -> Robot:
    """A :class:`Robot` of ``base`` with the arms of ``mounts`` attached.

    Groups: ``"base"`` holds the base's movable joints, and each mount's joints form the group
    ``mount.group`` (its prefix without the trailing underscore). End-effectors are the arms' end-effectors,
    prefixed. ``package_dirs`` and ``trusted`` are read as :func:`framework.load_robot` reads them, for the base and
    every arm; the other ``load_options`` go to :func:`framework.robot_from_urdf` (``joints``, ``locked``, ...).
    """
    files = {k: load_options.pop(k) for k in ("package_dirs", "trusted") if k in load_options}
    text = mount_urdf(base, mounts, name=name, **files)
    base_root, _ = _read(base, **files)
    groups: dict[str, list[str]] = {}
    base_joints = [j.get("name") for j in base_root.findall("joint") if j.get("type") not in ("fixed", None)]
    if base_joints:
        groups["base"] = base_joints
    end_effectors: list[str] = []
    for m in mounts:
        arm_root, _ = _read(m.source, m.xacro_args, **files)
        groups[m.group] = [m.prefix + j.get("name") for j in arm_root.findall("joint") if j.get("type") != "fixed"]
        if m.end_effectors is not None:
            ees = list(m.end_effectors)
        elif isinstance(m.source, str) and "<robot" in m.source:
            ees = []
        else:
            ees = list(resolve_robot(m.source)[1].get("end_effectors", []))
        end_effectors += [m.prefix + e for e in ees]
    if "groups" not in load_options:  # the groups made up here keep the members a user chose to solve
        load_options.update(groups=groups, strict_groups=False)
    load_options.setdefault("end_effectors", end_effectors or None)
    return robot_from_urdf(text, name=name or base_root.get("name"), package_dirs=files.get("package_dirs", ()),
                           **load_options)


def _read(source: str | Path, xacro_args: Mapping[str, str] | None = None, *,
          package_dirs: Sequence[str | Path] | Mapping[str, str | Path] = (),
          trusted: bool = False) -> tuple[ET.Element, Path | None]:
    """Parse an index name, a file path or URDF text; also return the file's directory (for mesh paths)."""
    if isinstance(source, str) and "<robot" in source:
        return parse_urdf(source), None
    path, _ = resolve_robot(source)
    text = read_robot_file(path, xacro_args=xacro_args, package_dirs=package_dirs, trusted=trusted)
    return parse_urdf(text, str(path)), path.parent


def _prefixed(root: ET.Element, prefix: str, directory: Path | None) -> ET.Element:
    """A copy of a URDF tree with ``prefix`` on link/joint names and relative mesh paths made absolute."""
    root = copy.deepcopy(root)
    for link in root.findall("link"):
        link.set("name", prefix + link.get("name"))
    for joint in root.findall("joint"):
        joint.set("name", prefix + joint.get("name"))
        for tag in ("parent", "child"):
            joint.find(tag).set("link", prefix + joint.find(tag).get("link"))
        mimic = joint.find("mimic")
        if mimic is not None:
            mimic.set("joint", prefix + mimic.get("joint"))
    for mesh in root.iter("mesh"):
        filename = mesh.get("filename", "")
        if directory is not None and "://" not in filename and not Path(filename).is_absolute():
            mesh.set("filename", str((directory / filename).resolve()))
    return root


def _floats(values: Sequence[float]) -> str:
    values = np.asarray(values, dtype=float)
    if values.shape != (3,) or not np.all(np.isfinite(values)):
        raise RobotFileError(f"a mount placement needs 3 finite numbers; got {values.tolist()}")
    return " ".join(repr(float(v)) for v in values)
