"""The shipped URDFs against the papers' DH tables: Pinocchio FK == DH product (paper 000 eq. 2-7).

For independence, the DH tables, limits and mounts of the papers' robots are typed here again from
SPEC.md / the papers, not read from robots/dh_tables.toml; only the textbook Stanford and SCARA tables
(our documented choice of values) are read from that file.
"""

from __future__ import annotations

import math
import sys
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from framework.model import dh
from framework.model.dh import DHJoint, dh_chain, dh_transform
from framework.errors import LimitsError, MetaikError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

ROBOTS = Path(__file__).resolve().parent.parent / "robots"
PI = np.pi
N_CONFIGURATIONS = 1000
TOL = 1e-12  # [m] and [rad]

# (a [m], alpha [rad], d [m]) and limits [deg]: typed from SPEC.md (papers 000 Table 2, 002 Tables 2-4).
YOUBOT = [(0.033, PI / 2, 0.147), (0.155, 0, 0), (0.135, 0, 0), (0, PI / 2, 0), (0, 0, 0.2175)]
YOUBOT_LIMITS = ([-169, -65, -150, -102.5, -167.5], [169, 90, 146, 102.5, 167.5])
PUMA = [
    (0, PI / 2, 0), (0.4318, 0, 0), (0.0203, -PI / 2, 0.15), (0, PI / 2, 0.4318), (0, -PI / 2, 0), (0, 0, 0),
]  # fmt: skip
PUMA_LIMITS = ([-160, -45, -225, -110, -100, -266], [160, 225, 45, 170, 100, 266])
BAXTER = [
    (0.069, -PI / 2, 0.270), (0, PI / 2, 0), (0.069, -PI / 2, 0.364), (0, PI / 2, 0),
    (0.01, -PI / 2, 0.374), (0.01, PI / 2, 0), (0.01, 0, 0.28),
]  # fmt: skip
BAXTER_LIMITS = ([-141, -123, -173, -3, -175, -90, -175], [51, 60, 173, 150, 175, 120, 175])
FANUC = [
    (0.1, -PI / 2, 0), (0.7, PI, 0), (0.1, -PI / 2, 0), (0, PI / 2, -0.96), (0, -PI / 2, 0), (0, 0, -0.1),
]  # fmt: skip
FANUC_LIMITS = ([-185, -100, -185, -200, -140, -270], [185, 160, 273, 200, 140, 270])


def revolute_table(rows, limits_deg) -> tuple[DHJoint, ...]:
    lower, upper = np.deg2rad(limits_deg[0]), np.deg2rad(limits_deg[1])
    rows = zip(rows, lower, upper, strict=True)
    return tuple(DHJoint(a, alpha, d, 0.0, "revolute", lo, hi) for (a, alpha, d), lo, hi in rows)


def toml_table(name: str) -> tuple[DHJoint, ...]:
    """Textbook tables (Stanford, SCARA): our choice of values lives only in dh_tables.toml."""
    tables, _ = dh.load_tables(ROBOTS / "dh_tables.toml")
    return tables[name]


def translation(x, y, z, R: np.ndarray | None = None) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = np.eye(3) if R is None else R, (x, y, z)
    return T


def rz(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


# Paper 000 eq. 3, as printed.
P_T_B1 = np.array([[1, 0, 0, 0.15], [0, 1, 0, 0], [0, 0, 1, 0.14], [0, 0, 0, 1]], dtype=float)
P_T_B2 = np.array([[-1, 0, 0, -0.15], [0, -1, 0, 0], [0, 0, 1, 0.14], [0, 0, 0, 1]], dtype=float)


@dataclass(frozen=True)
class Arm:
    prefix: str
    table: tuple[DHJoint, ...]
    mount: np.ndarray  # pose of the arm's DH frame 0 in the platform (mobile) or the world


@dataclass(frozen=True)
class Expected:
    arms: tuple[Arm, ...]
    mobile: bool = False  # planar base wTp(x, y, θ) of paper 000 eq. 2 under the mounts


def expected_robots() -> dict[str, Expected]:
    youbot = revolute_table(YOUBOT, YOUBOT_LIMITS)
    puma = revolute_table(PUMA, PUMA_LIMITS)
    baxter = revolute_table(BAXTER, BAXTER_LIMITS)
    fanuc = revolute_table(FANUC, FANUC_LIMITS)
    stanford, scara = toml_table("stanford_arm"), toml_table("scara")
    eye = np.eye(4)
    return {
        "youbot_arm": Expected((Arm("", youbot, eye),)),
        "puma560": Expected((Arm("", puma, eye),)),
        "baxter_arm": Expected((Arm("", baxter, eye),)),
        "fanuc_am120ib": Expected((Arm("", fanuc, eye),)),
        "stanford_arm": Expected((Arm("", stanford, eye),)),
        "scara": Expected((Arm("", scara, eye),)),
        "youbot_dual_mobile": Expected(
            (Arm("arm1_", youbot, P_T_B1), Arm("arm2_", youbot, P_T_B2)), mobile=True
        ),
        "youbot_mobile": Expected((Arm("arm_", youbot, P_T_B1),), mobile=True),
        "youbot_dual": Expected((Arm("arm1_", youbot, P_T_B1), Arm("arm2_", youbot, P_T_B2))),
        # Mounts below are our choices (documented in dh_tables.toml), typed again here.
        "baxter_dual": Expected(
            (
                Arm("left_", baxter, translation(0.064, 0.259, 0.13, rz(PI / 4))),
                Arm("right_", baxter, translation(0.064, -0.259, 0.13, rz(-PI / 4))),
            )
        ),
        "stanford_dual": Expected(
            (Arm("arm1_", stanford, translation(0, 0.5, 0)), Arm("arm2_", stanford, translation(0, -0.5, 0)))
        ),
        "puma_scara": Expected(
            (
                Arm("puma_", puma, translation(0, 0.4, 0.672)),
                Arm("scara_", scara, translation(0, -0.4, 0.387)),
            )
        ),
    }


EXPECTED = expected_robots()
with (ROBOTS / "index.toml").open("rb") as _fh:
    INDEX = tomllib.load(_fh)


def planar(x, y, theta) -> np.ndarray:
    """wTp(q0), paper 000 eq. 2, for arrays of base poses: (B, 4, 4)."""
    c, s = np.cos(theta), np.sin(theta)
    T = np.zeros(np.shape(x) + (4, 4))
    T[..., 0, 0], T[..., 0, 1], T[..., 0, 3] = c, -s, x
    T[..., 1, 0], T[..., 1, 1], T[..., 1, 3] = s, c, y
    T[..., 2, 2] = T[..., 3, 3] = 1.0
    return T


def rotation_angle(R_a: np.ndarray, R_b: np.ndarray) -> np.ndarray:
    """Angle [rad] of R_a^T R_b, accurate near 0 (atan2 of the skew and symmetric parts)."""
    E = np.swapaxes(R_a, -1, -2) @ R_b
    skew = np.stack(
        [E[..., 2, 1] - E[..., 1, 2], E[..., 0, 2] - E[..., 2, 0], E[..., 1, 0] - E[..., 0, 1]], axis=-1
    )
    return np.arctan2(0.5 * np.linalg.norm(skew, axis=-1), 0.5 * (np.trace(E, axis1=-2, axis2=-1) - 1.0))


def q_index(model: pin.Model, joint: str) -> int:
    assert model.existJointName(joint), f"no joint {joint!r} in the model"
    return model.joints[model.getJointId(joint)].idx_q


# --------------------------------------------------------------------------- the DH reference itself


def test_dh_transform_is_eq5_elementwise():
    rng = np.random.default_rng(0)
    a, alpha, d, theta = rng.uniform(-2, 2, (4, 50))
    A = dh_transform(a, alpha, d, theta)
    ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
    z, o = np.zeros(50), np.ones(50)
    expected = np.stack(
        [
            np.stack([ct, -st * ca, st * sa, a * ct], -1),
            np.stack([st, ct * ca, -ct * sa, a * st], -1),
            np.stack([z, sa, ca, d], -1),
            np.stack([z, z, z, o], -1),
        ],
        -2,
    )
    assert A.shape == (50, 4, 4)
    np.testing.assert_allclose(A, expected, rtol=0, atol=1e-15)
    assert dh_transform(0.1, 0.2, 0.3, np.zeros((3, 2))).shape == (3, 2, 4, 4)


def test_dh_chain_matches_paper_000_youbot_matrices():
    """0T1 and 4T5 as printed in paper 000 (after eq. 5), and the chain as their product (eq. 6)."""
    youbot = revolute_table(YOUBOT, YOUBOT_LIMITS)
    rng = np.random.default_rng(1)
    q = rng.uniform(-PI, PI, (20, 5))
    c1, s1, c5, s5 = np.cos(q[:, 0]), np.sin(q[:, 0]), np.cos(q[:, 4]), np.sin(q[:, 4])
    z, o = np.zeros(20), np.ones(20)
    T01 = np.stack([np.stack(r, -1) for r in ([c1, z, s1, 0.033 * c1], [s1, z, -c1, 0.033 * s1],
                                              [z, o, z, 0.147 * o], [z, z, z, o])], -2)  # fmt: skip
    T45 = np.stack([np.stack(r, -1) for r in ([c5, -s5, z, z], [s5, c5, z, z], [z, z, o, 0.2175 * o],
                                              [z, z, z, o])], -2)  # fmt: skip
    np.testing.assert_allclose(dh_chain(youbot[:1], q[:, :1]), T01, atol=1e-15)
    np.testing.assert_allclose(dh_chain(youbot[4:], q[:, 4:]), T45, atol=1e-15)
    middle = dh_chain(youbot[1:4], q[:, 1:4])
    np.testing.assert_allclose(dh_chain(youbot, q), T01 @ middle @ T45, atol=1e-14)


def test_prismatic_row_moves_along_z():
    row = DHJoint(a=0.2, alpha=0.3, d=0.1, theta=0.4, kind="prismatic", lower=0.0, upper=1.0)
    T0, T1 = dh_chain([row], [[0.0]]), dh_chain([row], [[0.5]])
    np.testing.assert_allclose(T1[0, :3, 3] - T0[0, :3, 3], [0, 0, 0.5], atol=1e-15)
    np.testing.assert_allclose(T1[0, :3, :3], T0[0, :3, :3], atol=0)


# --------------------------------------------------------------------------- shipped URDFs == DH product


def test_index_lists_exactly_the_checked_robots():
    assert set(INDEX) == set(EXPECTED)


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_pinocchio_fk_equals_dh_product(name: str):
    entry, expected = INDEX[name], EXPECTED[name]
    model = pin.buildModelFromUrdf(str(ROBOTS / entry["file"]))
    data = model.createData()
    assert model.nq == model.nv == model.njoints - 1  # only 1-DOF joints
    rng = np.random.default_rng(zlib.crc32(name.encode()))
    Q = rng.uniform(model.lowerPositionLimit, model.upperPositionLimit, (N_CONFIGURATIONS, model.nq))

    frames = [model.getFrameId(f"{arm.prefix}ee") for arm in expected.arms]
    assert all(f < model.nframes for f in frames)
    pin_T = np.empty((len(frames), N_CONFIGURATIONS, 4, 4))
    for k, q in enumerate(Q):
        pin.forwardKinematics(model, data, q)
        pin.updateFramePlacements(model, data)
        for i, f in enumerate(frames):
            pin_T[i, k] = data.oMf[f].homogeneous

    world_T_platform = np.eye(4)
    if expected.mobile:
        x, y, theta = (Q[:, q_index(model, j)] for j in ("base_x", "base_y", "base_theta"))
        world_T_platform = planar(x, y, theta)
    for i, arm in enumerate(expected.arms):
        cols = [q_index(model, f"{arm.prefix}joint{j}") for j in range(1, len(arm.table) + 1)]
        dh_T = world_T_platform @ arm.mount @ dh_chain(arm.table, Q[:, cols])  # eq. 7: wTp pTb bTe
        position_error = np.linalg.norm(pin_T[i, :, :3, 3] - dh_T[:, :3, 3], axis=-1)
        angle_error = rotation_angle(pin_T[i, :, :3, :3], dh_T[:, :3, :3])
        assert position_error.max() < TOL, f"{arm.prefix}ee position error {position_error.max():.3e} m"
        assert angle_error.max() < TOL, f"{arm.prefix}ee rotation error {angle_error.max():.3e} rad"


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_joint_limits_are_the_papers(name: str):
    expected = EXPECTED[name]
    model = pin.buildModelFromUrdf(str(ROBOTS / INDEX[name]["file"]))
    for arm in expected.arms:
        for j, row in enumerate(arm.table, start=1):
            k = q_index(model, f"{arm.prefix}joint{j}")
            assert model.lowerPositionLimit[k] == pytest.approx(row.lower, abs=1e-15)
            assert model.upperPositionLimit[k] == pytest.approx(row.upper, abs=1e-15)
    if expected.mobile:  # paper 000: x, y in [-1.5, 1.5] m, θ in [-π, π]
        for joint, bound in (("base_x", 1.5), ("base_y", 1.5), ("base_theta", PI)):
            k = q_index(model, joint)
            assert (model.lowerPositionLimit[k], model.upperPositionLimit[k]) == (-bound, bound)


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_index_entry_matches_model(name: str):
    entry = INDEX[name]
    assert {"file", "description", "end_effectors", "source", "groups"} <= set(entry)
    model = pin.buildModelFromUrdf(str(ROBOTS / entry["file"]))
    for frame in entry["end_effectors"]:
        assert model.existFrame(frame), frame
    assert entry["end_effectors"] == [f"{arm.prefix}ee" for arm in EXPECTED[name].arms]
    grouped = [joint for members in entry["groups"].values() for joint in members]
    assert sorted(grouped) == sorted(model.names[1:])  # every joint in exactly one group
    if len(EXPECTED[name].arms) == 1 and not EXPECTED[name].mobile:
        assert list(entry["groups"]) == ["arm"]


# --------------------------------------------------------------------------- generator and validation


def test_committed_urdfs_equal_generated():
    generated = dh.build_urdfs(ROBOTS / "dh_tables.toml")
    assert set(generated) == {entry["file"] for entry in INDEX.values()}
    for file, text in generated.items():
        assert (ROBOTS / file).read_text() == text, f"robots/{file} is stale: run `python -m framework.model.dh`"
    assert dh.main(["--check"]) == 0


def test_urdf_numbers_are_table_literals():
    """The youBot file holds the table's numbers as written (shortest repr), e.g. d5 = 0.2175."""
    text = (ROBOTS / "youbot_arm.urdf").read_text()
    assert 'xyz="0.0 0.0 0.2175"' in text and 'xyz="0.033 0.0 0.147" rpy="1.5707963267948966 0.0 0.0"' in text


def test_inverted_limits_raise():
    with pytest.raises(LimitsError):
        DHJoint(0.1, 0.0, 0.0, lower=1.0, upper=-1.0)
    with pytest.raises(LimitsError):
        DHJoint(0.1, 0.0, 0.0, lower=float("nan"), upper=1.0)
    with pytest.raises(LimitsError):
        dh.mobile_base_elements(x_limits=(1.5, -1.5))


def test_inverted_limits_in_tables_file_raise(tmp_path: Path):
    bad = tmp_path / "dh_tables.toml"
    bad.write_text(
        "[tables.arm]\n"
        'joints = [{ a = 0.1, alpha = 0, d = 0.0, kind = "revolute", lower = 90, upper = -90 }]\n'
        '[robots.arm]\nfile = "arm.urdf"\narms = [{ table = "arm" }]\n'
    )
    with pytest.raises(LimitsError, match="arm joint 1"):
        dh.build_urdfs(bad)
    assert dh.main(["--tables", str(bad)]) == 2
    assert not (tmp_path / "arm.urdf").exists()


def test_bad_kind_raises():
    with pytest.raises(MetaikError, match="spherical"):
        DHJoint(0.1, 0.0, 0.0, kind="spherical")


def test_dh_chain_rejects_wrong_width():
    with pytest.raises(MetaikError):
        dh_chain(revolute_table(YOUBOT, YOUBOT_LIMITS), np.zeros((3, 4)))


def test_dh_to_urdf_single_arm_on_base_link():
    table = (DHJoint(0.3, 0.0, 0.0), DHJoint(0.2, 0.0, 0.1, kind="prismatic", lower=0.0, upper=0.5))
    mount = translation(0.1, -0.2, 0.3, rz(0.7))
    model = pin.buildModelFromXML(dh.dh_to_urdf(table, "toy", prefix="t_", base_link="stand", origin=mount))
    data = model.createData()
    q = np.array([0.4, 0.25])
    pin.framesForwardKinematics(model, data, q)
    ee = data.oMf[model.getFrameId("t_ee")].homogeneous
    np.testing.assert_allclose(ee, mount @ dh_chain(table, q), atol=1e-14)


# --------------------------------------------------------------------------- xacro example


def test_xacro_example_expands_and_loads():
    import xacro

    path = ROBOTS / "examples" / "two_link.urdf.xacro"
    q = np.array([0.3, -0.8])

    def tool_position(**mappings: str) -> np.ndarray:
        text = xacro.process_file(str(path), mappings=mappings).toxml()
        model = pin.buildModelFromXML(text)
        data = model.createData()
        pin.framesForwardKinematics(model, data, q)
        return data.oMf[model.getFrameId("tool")].translation

    def planar_2r(l1: float, l2: float) -> np.ndarray:
        q12 = q.sum()
        return np.array([l1 * np.cos(q[0]) + l2 * np.cos(q12), l1 * np.sin(q[0]) + l2 * np.sin(q12), 0.0])

    np.testing.assert_allclose(tool_position(), planar_2r(0.5, 0.4), atol=1e-14)
    np.testing.assert_allclose(tool_position(l1="0.7", l2="0.2"), planar_2r(0.7, 0.2), atol=1e-14)
