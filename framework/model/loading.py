"""Loading robots: from the shipped index by name, or from any URDF / xacro file or URDF text.

``load_robot("youbot_dual_mobile")`` reads ``robots/index.toml``; ``load_robot("path/arm.urdf")`` or
``load_robot("arm.urdf.xacro", xacro_args={"l1": "0.5"})`` reads a file nobody here wrote;
:func:`robot_from_urdf` builds from URDF text (e.g. written in a notebook). Joints not chosen for the search
(``joints=...``) are locked at their ``locked`` values (default: 0, or the centre of their limits if 0 is
outside them) and folded into fixed placements by Pinocchio's ``buildReducedModel``.
"""

from __future__ import annotations

import re
import sys
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import LimitsError, RobotFileError, UnknownFrameError, UnknownJointError, UnknownRobotError
from ..resources import data_dir
from .xacro_files import package_folders
from .roles import gripper_groups, mobile_base, segment_names
from .floating import expand as expand_floating, floating_joints, with_floating_joints
from .bounds import default_bounds, override_bounds
from .joints import JointKind, build_joints
from .robot import Robot
from ..validate import names, table

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


def robot_index() -> dict[str, dict]:
    """The shipped robots: name -> entry (``file``, ``description``, ``end_effectors``, ``groups``, ...)."""
    path = data_dir("robots") / "index.toml"
    try:
        with path.open("rb") as fh:
            return tomllib.load(fh)
    except (OSError, tomllib.TOMLDecodeError) as err:
        raise RobotFileError(f"cannot read the robot index {path}: {err}") from err


def load_robot(
    source: str | Path,
    *,
    joints: Sequence[str] | None = None,
    locked: Mapping[str, float] | None = None,
    end_effectors: Sequence[str] | None = None,
    groups: Mapping[str, Sequence[str]] | None = None,
    bounds: Mapping[str, tuple[float, float]] | None = None,
    xacro_args: Mapping[str, str] | None = None,
    unbounded_translation: float = 2.0,
    package_dirs: Sequence[str | Path] | Mapping[str, str | Path] = (),
    trusted: bool = False,
    floating_base: bool = False,
    quaternion: str | None = None,
) -> Robot:
    """Load a robot by index name or from a ``.urdf`` / ``.xacro`` file.

    Args:
        source: a name from ``robots/index.toml`` or a path to a URDF or xacro file.
        joints: joints to solve for (default: every movable joint); the others are locked.
        locked: values of locked joints in joint coordinates [rad or m] (default 0 or mid-range).
        end_effectors: end-effector frame names (default: the index entry, else the tip of every leaf chain).
        groups: joint-group name -> joint names (default: the index entry, else derived from the chains).
        bounds: search bounds to override, coordinate or joint name -> (lower, upper).
        xacro_args: xacro arguments, for ``.xacro`` files.
        unbounded_translation: half-width [m] of the search box of unbounded translations (planar bases).
        package_dirs: folders holding ROS packages (or ``{package name: folder}`` for packages named unlike their
            folders), relative to the working folder: for ``$(find pkg)`` in xacro files and ``package://`` meshes
            (``ROS_PACKAGE_PATH`` and ``AMENT_PREFIX_PATH`` are searched after them).
        trusted: let xacro read environment variables and YAML files and evaluate ``$(eval)`` (robot files are
            data by default: see :mod:`framework.model.xacro_files`).
        floating_base: add a free-flyer above the root link, solved as six coordinates (``root_joint_x`` ...
            ``root_joint_roll``; see :mod:`framework.model.floating`); a URDF ``floating`` joint always is. Lock one at a
            pose with ``locked={"root_joint": pose}``: a ``pinocchio.SE3``, a 4x4 matrix, a ``(position, rotation)``
            pair, or 7 numbers ``(x, y, z, q, q, q, q)`` with ``quaternion=`` naming the order of the last four.
        quaternion: ``"xyzw"`` or ``"wxyz"``: the order of a locked floating joint's quaternion given as numbers.
    """
    path, entry = resolve_robot(source)
    name = str(source) if entry else path.name.split(".")[0]
    package_dirs = package_folders(package_dirs)
    text = read_robot_file(path, xacro_args=xacro_args, package_dirs=package_dirs, trusted=trusted)
    return robot_from_urdf(
        text,
        name=name,
        joints=joints,
        locked=locked,
        end_effectors=end_effectors if end_effectors is not None else entry.get("end_effectors"),
        groups=groups if groups is not None else entry.get("groups"),
        bounds=bounds,
        unbounded_translation=unbounded_translation,
        source=str(path),
        strict_groups=groups is not None,  # the index's groups shrink to the joints a user chose to solve
        floating_base=floating_base,
        quaternion=quaternion,
        package_dirs=package_dirs,
    )


def resolve_robot(source: str | Path) -> tuple[Path, Mapping]:
    """The file of a robot given by index name or path, and its index entry (empty for a plain file)."""
    path = Path(source)
    if path.is_file():
        return path, {}
    if path.is_dir():
        files = sorted(p.name for p in path.iterdir() if p.name.endswith((".urdf", ".xacro")))
        raise RobotFileError(f"{path} is a folder: give the URDF or xacro file of the robot"
                             + (f" (it holds {', '.join(files[:8])}{', ...' if len(files) > 8 else ''})"
                                if files else " (it holds no .urdf or .xacro file)"))
    index = robot_index()
    if str(source) in index:
        return data_dir("robots") / index[str(source)]["file"], index[str(source)]
    if path.suffix:
        raise RobotFileError(f"robot file {path} does not exist")
    raise UnknownRobotError(
        f"unknown robot {str(source)!r}: not in the robot index ({', '.join(sorted(index))}) and not a file path"
    )


def read_robot_file(path: Path, *, xacro_args: Mapping[str, str] | None = None,
                    package_dirs: Sequence[str | Path] | Mapping[str, str | Path] = (), trusted: bool = False) -> str:
    """URDF text of a ``.urdf`` file or an expanded ``.xacro`` file (see :mod:`framework.model.xacro_files`: robot
    files are data unless ``trusted``; ``$(find pkg)`` resolves in ``package_dirs``)."""
    path = Path(path)
    if not path.is_file():
        raise RobotFileError(f"robot file {path} does not exist")
    if path.suffix == ".xacro":
        from .xacro_files import expand_xacro

        return expand_xacro(path, xacro_args=xacro_args, package_dirs=package_dirs, trusted=trusted)
    if xacro_args:
        raise RobotFileError(f"xacro arguments given for {path}, which is not a .xacro file")
    try:
        return path.read_text()
    except (OSError, UnicodeDecodeError) as err:
        raise RobotFileError(f"cannot read robot file {path}: {err}") from err


#: The xacro namespace as ElementTree spells the tags in it.
XACRO_NAMESPACE = "{http://www.ros.org/wiki/xacro}"


def parse_urdf(text: str, what: str = "URDF") -> ET.Element:
    """The ``<robot>`` element of URDF text; raises :class:`RobotFileError` on malformed XML."""
    try:
        root = ET.fromstring(text)
    except ET.ParseError as err:
        raise RobotFileError(f"malformed XML in {what}: {err}") from err
    if root.tag != "robot":
        raise RobotFileError(f"{what} is not a URDF: root element is <{root.tag}>, expected <robot>")
    if any(str(e.tag).startswith(XACRO_NAMESPACE) for e in root.iter()):
        raise RobotFileError(f"{what} holds xacro (xacro: elements): name the file .urdf.xacro (or .xacro) to have "
                             "it expanded")
    substituted = next((v for e in root.iter() for v in e.attrib.values() if "$(" in v or "${" in v), None)
    if substituted is not None:
        raise RobotFileError(f"{what} holds xacro substitutions ({substituted[:40]!r}): name the file .urdf.xacro to "
                             "have it expanded ($(env), $(optenv) and $(eval) also need trusted=True)")
    if root.find("link") is None:
        raise RobotFileError(f"{what} has no <link>")
    _check_tree(root, what)
    return root


def _check_tree(root: ET.Element, what: str) -> None:
    """The links and joints form one tree (urdfdom only prints its reason to stderr): every joint names a parent
    and a child that exist, no link has two parents, one root link."""
    links = [link.get("name") for link in root.findall("link")]
    seen: set[str] = set()
    parent_of: dict[str, str] = {}
    for link in links:
        if not link:
            raise RobotFileError(f"{what}: a <link> has no name")
        if link in seen:
            raise RobotFileError(f"{what}: link {link!r} is defined twice")
        seen.add(link)
    for joint in root.findall("joint"):
        name = joint.get("name")
        ends = {}
        for end in ("parent", "child"):
            element = joint.find(end)
            ends[end] = None if element is None else element.get("link")
            if ends[end] not in seen:
                raise RobotFileError(f"{what}: joint {name!r} has {end} link {ends[end]!r}, which is not a <link>")
        child = ends["child"]
        if child in parent_of:
            raise RobotFileError(f"{what}: link {child!r} is the child of two joints ({parent_of[child]!r} and {name!r})")
        parent_of[child] = name
    roots = [link for link in links if link not in parent_of]
    if len(roots) != 1:
        raise RobotFileError(f"{what}: the links form {'no tree (a loop)' if not roots else 'several trees'}; "
                             f"root links: {roots}")


def robot_from_urdf(
    text: str,
    *,
    name: str | None = None,
    joints: Sequence[str] | None = None,
    locked: Mapping[str, float] | None = None,
    end_effectors: Sequence[str] | None = None,
    groups: Mapping[str, Sequence[str]] | None = None,
    bounds: Mapping[str, tuple[float, float]] | None = None,
    unbounded_translation: float = 2.0,
    source: str | None = None,
    strict_groups: bool = True,
    floating_base: bool = False,
    quaternion: str | None = None,
    package_dirs: Sequence[str | Path] | Mapping[str, str | Path] = (),
) -> Robot:
    """Build a :class:`Robot` from URDF text. Arguments as :func:`load_robot` (``strict_groups``: every member of
    ``groups`` must be a solved joint)."""
    what = source or "URDF text"
    joints = None if joints is None else names(joints, "joints", UnknownJointError)
    locked = None if locked is None else table(locked, "locked", LimitsError)
    end_effectors = None if end_effectors is None else names(end_effectors, "end_effectors", UnknownFrameError)
    if groups is not None:
        groups = {g: names(m, f"group {g!r}", UnknownJointError) for g, m in table(groups, "groups").items()}
    bounds = None if bounds is None else table(bounds, "bounds", LimitsError)
    root = parse_urdf(text, what)
    name = name or root.get("name") or "robot"
    if not isinstance(floating_base, bool):
        raise RobotFileError(f"floating_base must be true or false; got {floating_base!r}")
    if floating_base or any(j.get("type") == "floating" for j in root.findall("joint")):
        root, floating = with_floating_joints(root, add_root=floating_base, translation=unbounded_translation)
        text = ET.tostring(root, encoding="unicode")
        joints, locked = expand_floating(floating, joints, locked or {}, quaternion)
    try:
        full = pin.buildModelFromXML(text)
    except Exception as err:  # Pinocchio raises ValueError / RuntimeError on inconsistent trees
        raise RobotFileError(f"Pinocchio cannot build a model from {what}: {err}") from err

    mimic = mimic_joints(root, what)
    model, locked_values = _reduce(full, joints, locked or {}, mimic)
    robot_joints, mimics = build_joints(model, mimic)
    if not robot_joints:
        raise UnknownJointError(f"{what} has no movable joint: there is nothing to solve (a free-flying body is "
                                "solved with floating_base=True)")
    lower, upper = default_bounds(model, robot_joints, translation=unbounded_translation)
    if bounds:  # before the robot checks them: an override may be what makes a URDF's empty range usable
        lower, upper = override_bounds(lower, upper, bounds, robot_joints, name)
    if end_effectors is None:
        end_effectors = _leaf_frames(model, robot_joints)
    robot = Robot(
        name=name,
        model=model,
        joints=robot_joints,
        lower=lower,
        upper=upper,
        end_effectors=tuple(end_effectors),
        groups={},
        urdf=text,
        locked=locked_values,
        source=source,
        mimics=mimics,
        package_dirs=package_folders(package_dirs),
    )
    robot = _with_groups(robot, groups, strict=strict_groups)
    return robot


def mimic_joints(root: ET.Element, what: str = "URDF") -> dict[str, tuple[str, float, float]]:
    """The URDF's ``<mimic>`` couplings: joint name -> (leader, multiplier, offset); chains of mimics resolve
    to the first leader."""
    mimic: dict[str, tuple[str, float, float]] = {}
    for joint in root.findall("joint"):
        element = joint.find("mimic")
        if element is None or joint.get("type") in ("fixed", None):
            continue
        try:
            multiplier = float(element.get("multiplier", 1.0))
            offset = float(element.get("offset", 0.0))
        except ValueError:
            raise RobotFileError(f"{what}: joint {joint.get('name')!r} has a <mimic> with a non-numeric value") from None
        if not (np.isfinite(multiplier) and np.isfinite(offset)) or not element.get("joint"):
            raise RobotFileError(f"{what}: joint {joint.get('name')!r} has an invalid <mimic>")
        mimic[joint.get("name")] = (element.get("joint"), multiplier, offset)
    for name in list(mimic):
        leader, multiplier, offset = mimic[name]
        seen = {name}
        while leader in mimic:
            if leader in seen:
                raise RobotFileError(f"{what}: mimic joints {sorted(seen)} mimic each other in a loop")
            seen.add(leader)
            leader, m, o = mimic[leader][0], multiplier * mimic[leader][1], multiplier * mimic[leader][2] + offset
            multiplier, offset = m, o
        mimic[name] = (leader, multiplier, offset)
    return mimic


def _reduce(
    full: pin.Model, joints: Sequence[str] | None, locked: Mapping[str, float],
    mimic: Mapping[str, tuple[str, float, float]] | None = None,
) -> tuple[pin.Model, dict[str, float]]:
    """Lock every joint not in ``joints`` (and every joint in ``locked``) with Pinocchio's reduced model; a mimic
    joint is kept when its leader is solved and locked with it otherwise (one whose leader the model does not move
    only where ``locked`` gives its value)."""
    mimic = dict(mimic or {})
    names = list(full.names)[1:]
    # a coupling to a joint the model does not move (a name the file lacks, a fixed joint) cannot be kept: such a
    # follower loads only locked at a value the user gives (the file as it is, its broken couplings named)
    broken = {name: leader for name, (leader, _, _) in mimic.items() if leader not in names}
    unlocked = [name for name in broken if name not in locked]
    if unlocked:
        listed = ", ".join(f"{name!r} mimics {broken[name]!r}" for name in unlocked)
        raise RobotFileError(f"{len(unlocked)} joint{'s' if len(unlocked) > 1 else ''} mimic a joint that is not a "
                             f"movable joint of the model: {listed}; lock {'them' if len(unlocked) > 1 else 'it'} "
                             "(locked={name: value}) to load the file as it is")
    for name in broken:
        del mimic[name]
    fixed = {f.name for f in full.frames if f.type == pin.FrameType.FIXED_JOINT}
    for joint in [*(joints or []), *locked]:
        if joint in fixed:
            raise UnknownJointError(f"joint {joint!r} is a fixed joint: there is nothing to solve or lock")
        if joint not in names:
            raise UnknownJointError(f"the model has no joint {joint!r}; joints: {', '.join(names)}")
        if joint in mimic:
            raise UnknownJointError(f"joint {joint!r} mimics {mimic[joint][0]!r}: solve or lock {mimic[joint][0]!r}")
    if joints is not None:
        if not list(joints):
            raise UnknownJointError(f"joints=[] leaves nothing to solve; joints: {', '.join(names)}")
        both = sorted(set(joints) & set(locked))
        if both:
            raise UnknownJointError(f"joints {both} are both solved (joints=) and locked (locked=); choose one")
    keep = set(names if joints is None else joints) - set(locked)
    keep = {n for n in keep if n not in mimic} | {n for n, (leader, _, _) in mimic.items() if leader in keep}
    to_lock = [n for n in names if n not in keep and n not in mimic]
    to_lock += [n for n in names if n in mimic and n not in keep]  # after their leaders: they take their values
    if not to_lock:
        return full, {}
    q_ref = pin.neutral(full)
    values: dict[str, float] = {}
    for joint_name in to_lock:
        jid = full.getJointId(joint_name)
        jm = full.joints[jid]
        k, lo, hi = jm.idx_q, full.lowerPositionLimit[jm.idx_q], full.upperPositionLimit[jm.idx_q]
        if joint_name in locked:
            value = _locked_value(locked[joint_name], joint_name, lo, hi, bounded=jm.nq == 1)
        elif joint_name in mimic:  # follows its locked leader
            leader, multiplier, offset = mimic[joint_name]
            value = multiplier * values[leader] + offset
        else:
            value = 0.0 if (jm.nq != 1 or lo <= 0.0 <= hi) else 0.5 * (lo + hi)
        if jm.nq == 1:
            q_ref[k] = value
        elif jm.nq == 2:  # continuous: (cos, sin)
            q_ref[k : k + 2] = np.cos(value), np.sin(value)
        elif joint_name in locked:
            raise UnknownJointError(f"joint {joint_name!r} has {jm.nq} coordinates; lock it at its neutral value")
        values[joint_name] = value
    ids = [full.getJointId(n) for n in to_lock]
    return pin.buildReducedModel(full, ids, q_ref), values


def _locked_value(value, joint: str, lo: float, hi: float, *, bounded: bool) -> float:
    """A locked joint's value as a finite number within the joint's limits (bounded joints)."""
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise LimitsError(f"locked value of joint {joint!r} must be a number; got {value!r}") from None
    if not np.isfinite(value):
        raise LimitsError(f"locked value of joint {joint!r} must be finite; got {value!r}")
    if bounded and np.isfinite(lo) and np.isfinite(hi) and lo < hi and not lo - 1e-12 <= value <= hi + 1e-12:
        raise LimitsError(f"locked value {value} of joint {joint!r} is outside its limits [{lo:.6g}, {hi:.6g}]")
    return value


#: Frame names that say "sensor" (any case), never a default end-effector.
SENSOR_NAMES = re.compile(r"camera|optical|rgb|depth|laser|lidar|sonar|imu|kinect|xtion|microphone|sensor|(^|_)ft(_|$)",
                          re.IGNORECASE)
#: Frame names of wheels: a chain ending in a continuous joint that carries one is no end-effector.
WHEEL_NAMES = re.compile(r"wheel|caster", re.IGNORECASE)
#: Frame names that say "tool", best first: the default end-effector of a chain is the first frame matching the
#: first pattern that any of its frames matches, else its last body frame.
TOOL_NAMES = tuple(re.compile(p, re.IGNORECASE) for p in (r"tcp|tool_frame|end_?effector|grasp", r"tool",
                                                           r"(gripper|hand)$", r"palm"))


def _leaf_frames(model: pin.Model, joints: Sequence) -> list[str]:
    """Default end-effectors: for each solved joint without a solved descendant (a chain's end; wheels and
    casters — chains of one or two continuous joints only, or a continuous end carrying a wheel frame — left out), its tool
    frame by name (:data:`TOOL_NAMES`); a chain end without one (a finger, a gripper jaw) gives the tool frame of
    its nearest solved ancestor that has one, looking up to the first joint where chains branch (a hand's fingers
    all give the hand's grasp frame, once); else the chain end's last body frame. Sensor frames never."""
    solved = {j.pin_id: j for j in joints}
    ancestors = {jid: [] for jid in solved}  # nearest first
    for jid in solved:
        parent = model.parents[jid]
        while parent > 0:
            ancestors[jid].append(parent)
            parent = model.parents[parent]
    has_solved_child = {a for jid in solved for a in ancestors[jid]}
    ends = []
    for jid, joint in solved.items():
        if jid in has_solved_child:
            continue
        chain = [solved[a] for a in ancestors[jid] if a in solved] + [joint]
        if all(j.kind is JointKind.CONTINUOUS for j in chain) and len(chain) <= 2:
            continue  # a wheel or a caster: one or two continuous joints from the root (a leg has more)
        if joint.kind is JointKind.CONTINUOUS and any(WHEEL_NAMES.search(f.name) for f in _frames_on(model, jid)):
            continue  # a wheel on a suspension
        ends.append(jid)
    below = {}  # solved joint -> chain ends beneath it
    for jid in ends:
        for a in ancestors[jid]:
            below[a] = below.get(a, 0) + 1
    leaves: list[str] = []
    for jid in ends:
        frames = _frames_on(model, jid)
        chosen = _tool(frames)
        for a in ancestors[jid] if chosen is None else ():
            if a in solved:
                chosen = _tool(_frames_on(model, a))
                if chosen is not None or below.get(a, 0) > 1:
                    break
        bodies = [f.name for f in frames if f.type == pin.FrameType.BODY]
        name = chosen or (bodies[-1] if bodies else None)
        if name is not None and name not in leaves:
            leaves.append(name)
    return leaves


def _frames_on(model: pin.Model, jid: int) -> list:
    """The body and operational frames moving with joint ``jid`` (sensor frames left out)."""
    return [f for f in model.frames if f.parentJoint == jid and f.type in (pin.FrameType.BODY, pin.FrameType.OP_FRAME)
            and not SENSOR_NAMES.search(f.name)]


def _tool(frames: list) -> str | None:
    """The first of ``frames`` matching the best :data:`TOOL_NAMES` pattern any of them matches."""
    return next((f.name for pattern in TOOL_NAMES for f in frames if pattern.search(f.name)), None)


def _with_groups(robot: Robot, groups: Mapping[str, Sequence[str]] | None, strict: bool = True) -> Robot:
    """Attach joint groups: given by name lists, or derived from the end-effector chains.

    Given groups must name solved joints (``strict``; a robot index's groups keep the members that are solved).

    Derived groups (:mod:`framework.model.roles`): a mobile base (a planar joint, a floating base's six joints, or
    horizontal prismatic joints with a vertical turn, leading every chain) is ``"base"``; the other joints on the
    same set of end-effector chains form one group — the joints several chains share (``"torso"``), and each
    chain's own joints, named by role and side (``"arm"``, ``"left_arm"``, ``"head"``, ``"front_left_leg"``, ...).
    """
    from dataclasses import replace

    result: dict[str, np.ndarray] = {}
    solved = set(robot.joint_names)
    if groups:
        for group, members in groups.items():
            kept = [m for m in members if m in solved]
            missing = [m for m in members if m not in solved]
            if strict and missing:
                raise UnknownJointError(f"group {group!r} names {missing}, which {'is' if len(missing) == 1 else 'are'}"
                                        f" not solved (solved joints: {', '.join(robot.joint_names)})")
            if kept:
                result[group] = _coords(robot, kept)
    else:
        model = robot.model
        chains = []
        for frame in robot.end_effectors:
            jid, chain = model.frames[robot.frame_id(frame)].parentJoint, []
            while jid > 0:
                if model.names[jid] in solved:  # not the mimic joints (they follow a solved one)
                    chain.append(model.names[jid])
                jid = model.parents[jid]
            chains.append(chain[::-1])
        floating = floating_joints(robot.joint_names)
        base = mobile_base(robot, chains, floating)
        if base:  # a mobile base is one group, whatever the chains
            result["base"] = _coords(robot, base)
        owners: dict[str, frozenset[int]] = {}  # joint -> the chains it is on
        for k, chain in enumerate(chains):
            for joint in chain:
                owners[joint] = owners.get(joint, frozenset()) | {k}
        segments: dict[frozenset[int], list[str]] = {}  # joints on the same chains form one group, in chain order
        for k, chain in enumerate(chains):
            for joint in chain:
                members = segments.setdefault(owners[joint], [])
                if joint not in members and joint not in base:
                    members.append(joint)
        segments = {keys: members for keys, members in segments.items() if members}
        names = segment_names(robot, chains, list(segments))
        for (keys, members), name in zip(segments.items(), names):
            result[name] = _coords(robot, members)
        grouped = {j for members in segments.values() for j in members} | set(base)
        for name, members in gripper_groups(robot, grouped).items():
            result[name] = _coords(robot, members)
    return replace(robot, groups=result)


def _coords(robot: Robot, joint_names: Sequence[str]) -> np.ndarray:
    return np.concatenate([np.asarray(robot.joint(j).coordinates) for j in joint_names]).astype(int)
