"""Denavit–Hartenberg tables: the forward-kinematics reference and the generator of the shipped URDFs.

Standard DH (paper 000 eq. 5): the transform from frame j-1 to frame j is

    A_j = Rz(θ_j) Tz(d_j) Tx(a_j) Rx(α_j),

with θ_j = theta + q_j for a revolute joint and d_j = d + q_j for a prismatic one. The chain is the
product A_1 ... A_n (eq. 6-7). :func:`dh_chain` computes it with numpy for a batch of configurations;
it is the independent reference the tests compare Pinocchio against.

:func:`chain_elements` writes one DH table as URDF so that link ``{prefix}link{k}`` *is* DH frame k and
every number in the file is a literal of the table: for row j,

    link{j-1} --joint{j} (axis z, origin Rz(theta) [Tz(d) if prismatic])--> link{j}_z
              --dh{j} (fixed, origin Tx(a) [Tz(d) if revolute] Rx(alpha))--> link{j}

and a fixed joint from the last link to ``{prefix}ee``, the end-effector frame. :func:`mobile_base_elements`
writes the planar base of paper 000 eq. 2 (prismatic x, prismatic y, revolute θ).

``python -m framework.model.dh`` reads ``robots/dh_tables.toml`` and rewrites the URDF files in ``robots/``
(``--check`` only compares).
"""

from __future__ import annotations

import argparse
import math
import sys
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import ConfigurationError, LimitsError, MetaikError, RobotFileError
from ..resources import data_dir

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

KINDS = ("revolute", "prismatic")
EFFORT = "100"
VELOCITY = "2"


@dataclass(frozen=True)
class DHJoint:
    """One row of a standard DH table.

    Attributes:
        a: link length [m]. alpha: link twist [rad]. d: link offset [m]. theta: joint-angle offset [rad].
        kind: ``"revolute"`` (the joint variable adds to theta) or ``"prismatic"`` (it adds to d).
        lower, upper: joint limits of the variable q [rad for revolute, m for prismatic].
        name: optional label of the row (not used in the URDF; joints are named ``{prefix}joint{j}``).
        radius: radius of the link's collision capsules [m] (``None``: no collision geometry), see
            :func:`link_collisions`.
    """

    a: float
    alpha: float
    d: float
    theta: float = 0.0
    kind: str = "revolute"
    lower: float = -math.pi
    upper: float = math.pi
    name: str | None = None
    radius: float | None = None

    def __post_init__(self) -> None:
        label = self.name or "DH row"
        if self.radius is not None and not (math.isfinite(self.radius) and self.radius > 0):
            raise RobotFileError(f"{label}: collision radius {self.radius} must be a number > 0 [m]")
        if self.kind not in KINDS:
            raise RobotFileError(f"{label}: joint kind {self.kind!r} is not one of {', '.join(KINDS)}")
        for field in ("a", "alpha", "d", "theta"):
            if not math.isfinite(getattr(self, field)):
                raise RobotFileError(f"{label}: {field} = {getattr(self, field)} is not finite")
        check_limits(self.lower, self.upper, label)


def check_limits(lower: float, upper: float, what: str) -> None:
    """Raise :class:`LimitsError` unless ``lower <= upper`` and both are finite."""
    if not (math.isfinite(lower) and math.isfinite(upper)):
        raise LimitsError(f"{what}: limits [{lower}, {upper}] must be finite")
    if lower > upper:
        raise LimitsError(f"{what}: lower limit {lower} is above upper limit {upper}; swap them")


# --------------------------------------------------------------------------- numpy reference


def dh_transform(a, alpha, d, theta) -> np.ndarray:
    """A = Rz(theta) Tz(d) Tx(a) Rx(alpha) (paper 000 eq. 5), broadcast over the arguments' shapes.

    Returns an array of shape ``(..., 4, 4)``; lengths in m, angles in rad.
    """
    a, alpha, d, theta = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (a, alpha, d, theta)))
    ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
    A = np.zeros(theta.shape + (4, 4))
    A[..., 0, 0], A[..., 0, 1], A[..., 0, 2], A[..., 0, 3] = ct, -st * ca, st * sa, a * ct
    A[..., 1, 0], A[..., 1, 1], A[..., 1, 2], A[..., 1, 3] = st, ct * ca, -ct * sa, a * st
    A[..., 2, 1], A[..., 2, 2], A[..., 2, 3] = sa, ca, d
    A[..., 3, 3] = 1.0
    return A


def dh_chain(table: Sequence[DHJoint], q) -> np.ndarray:
    """Pose of the last DH frame in frame 0, A_1(q_1) ... A_n(q_n) (paper 000 eq. 6-7).

    Args:
        table: the n DH rows.
        q: joint values, shape ``(..., n)`` [rad or m].
    Returns:
        Homogeneous transforms, shape ``(..., 4, 4)``.
    """
    q = np.asarray(q, dtype=float)
    if q.ndim == 0 or q.shape[-1] != len(table):
        n = len(table)
        raise ConfigurationError(f"q has shape {q.shape}; the DH table has {n} joints, expected (..., {n})")
    T = np.broadcast_to(np.eye(4), q.shape[:-1] + (4, 4))
    for j, row in enumerate(table):
        qj = q[..., j]
        if row.kind == "revolute":
            A = dh_transform(row.a, row.alpha, row.d, row.theta + qj)
        else:
            A = dh_transform(row.a, row.alpha, row.d + qj, row.theta)
        T = T @ A
    return T


def planar_transform(q0) -> np.ndarray:
    """wTp(q0) of a planar base, q0 = (x [m], y [m], θ [rad]) of shape ``(..., 3)`` (paper 000 eq. 2)."""
    q0 = np.asarray(q0, dtype=float)
    c, s = np.cos(q0[..., 2]), np.sin(q0[..., 2])
    T = np.zeros(q0.shape[:-1] + (4, 4))
    T[..., 0, 0], T[..., 0, 1], T[..., 1, 0], T[..., 1, 1] = c, -s, s, c
    T[..., 0, 3], T[..., 1, 3], T[..., 2, 2], T[..., 3, 3] = q0[..., 0], q0[..., 1], 1.0, 1.0
    return T


def rpy_matrix(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """R = Rz(yaw) Ry(pitch) Rx(roll), the URDF convention; angles in rad."""
    cr, sr, cp, sp, cy, sy = (f(v) for v in (roll, pitch, yaw) for f in (math.cos, math.sin))
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def transform(xyz: Sequence[float] = (0.0, 0.0, 0.0), rpy: Sequence[float] = (0.0, 0.0, 0.0)) -> np.ndarray:
    """4x4 transform with translation ``xyz`` [m] and rotation Rz(y) Ry(p) Rx(r), ``rpy`` [rad]."""
    T = np.eye(4)
    T[:3, :3] = rpy_matrix(*rpy)
    T[:3, 3] = xyz
    return T


def rpy_from_matrix(R: np.ndarray) -> tuple[float, float, float]:
    """(roll, pitch, yaw) [rad] with R = Rz(yaw) Ry(pitch) Rx(roll); checked to round-trip to 1e-12."""
    R = np.asarray(R, dtype=float)
    if R.shape != (3, 3) or not np.allclose(R.T @ R, np.eye(3), atol=1e-12) or np.linalg.det(R) < 0:
        raise RobotFileError(f"not a rotation matrix:\n{R}")
    cos_pitch = math.hypot(R[0, 0], R[1, 0])
    pitch = math.atan2(-R[2, 0], cos_pitch)
    if cos_pitch > 1e-9:
        roll, yaw = math.atan2(R[2, 1], R[2, 2]), math.atan2(R[1, 0], R[0, 0])
    else:  # gimbal lock: only roll ± yaw is defined; put it all in yaw
        roll, yaw = 0.0, math.atan2(-R[0, 1], R[1, 1])
    if not np.allclose(rpy_matrix(roll, pitch, yaw), R, rtol=0.0, atol=1e-12):  # pragma: no cover
        raise RobotFileError(f"cannot express the rotation as URDF rpy:\n{R}")
    return roll, pitch, yaw


# --------------------------------------------------------------------------- URDF elements


def _num(*values: float) -> str:
    """Floats as the shortest text that reads back to the same double (no -0.0)."""
    return " ".join(repr(float(v) + 0.0) for v in values)


def _link(name: str) -> ET.Element:
    return ET.Element("link", name=name)


def _joint(name, kind, parent, child, xyz=(0.0, 0.0, 0.0), rpy=(0.0, 0.0, 0.0), axis=None, limits=None):
    joint = ET.Element("joint", name=name, type=kind)
    ET.SubElement(joint, "origin", xyz=_num(*xyz), rpy=_num(*rpy))
    ET.SubElement(joint, "parent", link=parent)
    ET.SubElement(joint, "child", link=child)
    if axis is not None:
        ET.SubElement(joint, "axis", xyz=_num(*axis))
    if limits is not None:
        lower, upper = _num(limits[0]), _num(limits[1])
        ET.SubElement(joint, "limit", lower=lower, upper=upper, effort=EFFORT, velocity=VELOCITY)
    return joint


def _collision(link: ET.Element, geometry: str, dims: dict[str, str], xyz=(0.0, 0.0, 0.0),
               rpy=(0.0, 0.0, 0.0)) -> None:
    collision = ET.SubElement(link, "collision")
    ET.SubElement(collision, "origin", xyz=_num(*xyz), rpy=_num(*rpy))
    ET.SubElement(ET.SubElement(collision, "geometry"), geometry, **dims)


def link_collisions(link: ET.Element, row: DHJoint) -> None:
    """Collision geometry of DH row ``row`` on ``link{j}_z`` (the body joint j moves): spheres of ``row.radius``
    ``r`` every ``r`` (at most) along each of the row's offsets — ``d`` along z (a prismatic row: its shortest
    stroke, behind the joint), then ``a`` along x — ends included. Their union holds the capsule of radius
    ``r √3/2`` around the segments (URDF has no capsule element; spheres are also what the fast distance
    kernel uses, so the exact check and the kernel see the same shape)."""
    r = row.radius
    if r is None:
        return
    revolute = row.kind == "revolute"
    dz = row.d if revolute else -max(row.lower, 0.0)
    z_end = dz if revolute else 0.0
    points = [(0.0, 0.0, t * dz) for t in np.linspace(0.0, 1.0, int(math.ceil(abs(dz) / r)) + 1)]
    points += [(t * row.a, 0.0, z_end) for t in np.linspace(0.0, 1.0, int(math.ceil(abs(row.a) / r)) + 1)[1:]]
    for xyz in points:
        _collision(link, "sphere", {"radius": _num(r)}, xyz)


def chain_elements(
    table: Sequence[DHJoint],
    prefix: str = "",
    parent_link: str | None = None,
    origin: np.ndarray | None = None,
) -> list[ET.Element]:
    """URDF links and joints of one DH arm (layout in the module docstring).

    Args:
        table: the DH rows.
        prefix: prepended to every link and joint name (``"arm1_"``).
        parent_link: link the arm base ``{prefix}link0`` is fixed to by joint ``{prefix}mount``
            (``None``: ``{prefix}link0`` is the root of the tree).
        origin: pose of ``{prefix}link0`` in ``parent_link``, 4x4 (default identity).
    """
    if not table:
        raise RobotFileError(f"the DH table of arm {prefix!r} has no rows")
    elements = [_link(f"{prefix}link0")]
    if parent_link is not None:
        T = np.eye(4) if origin is None else np.asarray(origin, dtype=float)
        rpy = rpy_from_matrix(T[:3, :3])
        elements.append(_joint(f"{prefix}mount", "fixed", parent_link, f"{prefix}link0", T[:3, 3], rpy))
    elif origin is not None:
        raise RobotFileError(f"arm {prefix!r}: an origin needs a parent_link to be relative to")
    for j, row in enumerate(table, start=1):
        prev, z_link, link = f"{prefix}link{j - 1}", f"{prefix}link{j}_z", f"{prefix}link{j}"
        revolute = row.kind == "revolute"
        joint_xyz = (0.0, 0.0, 0.0) if revolute else (0.0, 0.0, row.d)
        dh_xyz = (row.a, 0.0, row.d) if revolute else (row.a, 0.0, 0.0)
        moving = _link(z_link)
        link_collisions(moving, row)
        elements += [
            _joint(f"{prefix}joint{j}", row.kind, prev, z_link, joint_xyz, (0.0, 0.0, row.theta),
                   axis=(0.0, 0.0, 1.0), limits=(row.lower, row.upper)),
            moving,
            _joint(f"{prefix}dh{j}", "fixed", z_link, link, dh_xyz, (row.alpha, 0.0, 0.0)),
            _link(link),
        ]  # fmt: skip
    last = f"{prefix}link{len(table)}"
    elements += [_joint(f"{prefix}ee_joint", "fixed", last, f"{prefix}ee"), _link(f"{prefix}ee")]
    return elements


def mobile_base_elements(
    x_limits: tuple[float, float] = (-1.5, 1.5),
    y_limits: tuple[float, float] = (-1.5, 1.5),
    theta_limits: tuple[float, float] = (-math.pi, math.pi),
    *,
    world_link: str = "world",
    platform_link: str = "platform",
) -> list[ET.Element]:
    """Planar base wTp(x, y, θ) = Tx(x) Ty(y) Rz(θ) (paper 000 eq. 2) as three URDF joints.

    Joints ``base_x`` (prismatic, axis x) -> ``base_y`` (prismatic, axis y) -> ``base_theta`` (revolute,
    axis z), links ``world_link`` -> ``base_x_link`` -> ``base_y_link`` -> ``platform_link``.
    Limits [m, m, rad]; the defaults are the search box of paper 000.
    """
    for joint, (lo, hi) in zip(
        ("base_x", "base_y", "base_theta"), (x_limits, y_limits, theta_limits), strict=True
    ):
        check_limits(lo, hi, joint)
    return [
        _link(world_link),
        _joint("base_x", "prismatic", world_link, "base_x_link", axis=(1.0, 0.0, 0.0), limits=x_limits),
        _link("base_x_link"),
        _joint("base_y", "prismatic", "base_x_link", "base_y_link", axis=(0.0, 1.0, 0.0), limits=y_limits),
        _link("base_y_link"),
        _joint(
            "base_theta", "revolute", "base_y_link", platform_link, axis=(0.0, 0.0, 1.0), limits=theta_limits
        ),
        _link(platform_link),
    ]


def urdf_text(name: str, elements: Sequence[ET.Element], note: str | None = None) -> str:
    """A ``<robot>`` document holding ``elements``, indented, with an optional leading comment."""
    robot = ET.Element("robot", name=name)
    robot.extend(elements)
    ET.indent(robot, space="  ")
    head = '<?xml version="1.0"?>\n' + (f"<!-- {note} -->\n" if note else "")
    return head + ET.tostring(robot, encoding="unicode") + "\n"


def dh_to_urdf(
    table: Sequence[DHJoint],
    name: str,
    *,
    prefix: str = "",
    base_link: str | None = None,
    origin: np.ndarray | None = None,
    note: str | None = None,
) -> str:
    """URDF text of a single DH arm; with ``base_link``, the arm is fixed to that root link at ``origin``."""
    elements = [_link(base_link)] if base_link is not None else []
    return urdf_text(name, elements + chain_elements(table, prefix, base_link, origin), note)


# --------------------------------------------------------------------------- robots/dh_tables.toml


def _table(name: str, spec: Mapping) -> tuple[DHJoint, ...]:
    """DH rows from the file: a, d [m]; alpha, theta [deg]; limits [deg] (revolute) or [m] (prismatic)."""
    rows = []
    for j, row in enumerate(spec.get("joints", []), start=1):
        try:
            kind = row.get("kind", "revolute")
            to_q = math.radians if kind == "revolute" else float
            rows.append(
                DHJoint(
                    a=float(row["a"]),
                    alpha=math.radians(row["alpha"]),
                    d=float(row["d"]),
                    theta=math.radians(row.get("theta", 0.0)),
                    kind=kind,
                    lower=to_q(row["lower"]),
                    upper=to_q(row["upper"]),
                    name=f"{name} joint {j}",
                    radius=row.get("radius", spec.get("radius")),
                )
            )
        except (KeyError, TypeError, ValueError) as err:
            raise RobotFileError(f"DH table {name!r}, row {j}: missing or bad field {err}") from err
    if not rows:
        raise RobotFileError(f"DH table {name!r} has no joints")
    return tuple(rows)


def load_tables(path: str | Path | None = None) -> tuple[dict[str, tuple[DHJoint, ...]], dict]:
    """The DH tables (name -> rows, in SI units) and the robot assemblies of a ``dh_tables.toml`` file (by
    default the shipped one)."""
    path = Path(path) if path is not None else shipped_tables()
    try:
        with path.open("rb") as fh:
            data = tomllib.load(fh)
    except (OSError, tomllib.TOMLDecodeError) as err:
        raise RobotFileError(f"cannot read DH tables {path}: {err}") from err
    tables = {name: _table(name, spec) for name, spec in data.get("tables", {}).items()}
    return tables, data.get("robots", {})


def robot_urdf(
    name: str, spec: Mapping, tables: Mapping[str, Sequence[DHJoint]], note: str | None = None
) -> str:
    """URDF text of one robot assembly of ``dh_tables.toml`` (optional planar base, one or more arms)."""
    elements: list[ET.Element] = []
    root = spec.get("root")
    parent = root
    if "base" in spec:
        b = spec["base"]
        theta = tuple(math.radians(v) for v in b.get("theta", (-180.0, 180.0)))
        elements += mobile_base_elements(
            tuple(b.get("x", (-1.5, 1.5))), tuple(b.get("y", (-1.5, 1.5))), theta,
            world_link=root or "world", platform_link=b.get("platform", "platform"),
        )  # fmt: skip
        parent = b.get("platform", "platform")
        if "body" in b:  # the platform's collision box: size [m], centre xyz [m]
            platform = next(e for e in elements if e.tag == "link" and e.get("name") == parent)
            _collision(platform, "box", {"size": _num(*b["body"]["size"])}, tuple(b["body"].get("xyz", (0, 0, 0))))
    elif root is not None:
        elements.append(_link(root))
    arms = spec.get("arms", [])
    if not arms:
        raise RobotFileError(f"robot {name!r} has no arms")
    for arm in arms:
        if arm.get("table") not in tables:
            known = ", ".join(tables)
            raise RobotFileError(f"robot {name!r}: unknown DH table {arm.get('table')!r}; known: {known}")
        origin = None
        if parent is None and ("xyz" in arm or "rpy" in arm):
            raise RobotFileError(f"robot {name!r}: a mount (xyz, rpy) needs a root link or a base")
        if parent is not None:
            rpy = [math.radians(v) for v in arm.get("rpy", (0.0, 0.0, 0.0))]
            origin = transform(arm.get("xyz", (0.0, 0.0, 0.0)), rpy)
        if len(arms) > 1 or parent is not None:
            elements.append(ET.Comment(f" {arm.get('prefix', '')}: DH table {arm['table']} "))
        elements += chain_elements(tables[arm["table"]], arm.get("prefix", ""), parent, origin)
    return urdf_text(name, elements, note)


def shipped_tables() -> Path:
    """The ``dh_tables.toml`` shipped with the robot files."""
    return data_dir("robots") / "dh_tables.toml"


def build_urdfs(path: str | Path | None = None) -> dict[str, str]:
    """File name -> URDF text of every robot in ``dh_tables.toml`` (by default the shipped one), as the generator
    writes them."""
    path = Path(path) if path is not None else shipped_tables()
    tables, robots = load_tables(path)
    note = f"Generated by `python -m framework.model.dh` from {path.name}; do not edit by hand."
    return {spec.get("file", f"{n}.urdf"): robot_urdf(n, spec, tables, note) for n, spec in robots.items()}


def main(argv: Sequence[str] | None = None) -> int:
    """Rewrite the URDF files next to ``dh_tables.toml`` (``--check``: only report the stale ones)."""
    parser = argparse.ArgumentParser(prog="python -m framework.model.dh", description=main.__doc__)
    parser.add_argument("--tables", type=Path, default=None, help="DH tables file (default: the shipped one)")
    parser.add_argument("--check", action="store_true", help="exit 1 if a URDF differs from the tables")
    args = parser.parse_args(argv)
    try:
        urdfs = build_urdfs(args.tables)
    except MetaikError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    stale = []
    for file, text in urdfs.items():
        target = (args.tables or shipped_tables()).parent / file
        if target.is_file() and target.read_text() == text:
            continue
        stale.append(target)
        if not args.check:
            target.write_text(text)
    verb = "stale" if args.check else "wrote"
    for target in stale:
        print(f"{verb} {target}")
    return 1 if args.check and stale else 0


if __name__ == "__main__":
    sys.exit(main())
