"""Two-hand tasks on example-robot-data's robots, loaded as they are (other joints locked, mimic grippers, a
floating base): both hands at full poses reachable by construction, motion minimized second; every pose checked
with Pinocchio's FK of the full model (the URDF built by Pinocchio itself, locked joints at their values)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import framework as fw
from tests.conftest import pinocchio_placements

ARM7 = [f"arm_{{side}}_{k}_joint" for k in range(1, 8)]
ROBOTS = {
    "pr2": ("pr2_description/urdf/pr2.urdf", ["torso_lift_joint"] + [
        f"{s}_{j}_joint" for s in "lr" for j in ("shoulder_pan", "shoulder_lift", "upper_arm_roll", "elbow_flex",
                                                   "forearm_roll", "wrist_flex", "wrist_roll")],
            ("l_gripper_tool_frame", "r_gripper_tool_frame")),
    "tiago_dual": ("tiago_description/robots/tiago_dual.urdf",
                   ["torso_lift_joint"] + [j.format(side=s) for s in ("left", "right") for j in ARM7],
                   ("arm_left_tool_link", "arm_right_tool_link")),
    "baxter": ("baxter_description/urdf/baxter.urdf",
               [f"{s}_{j}" for s in ("left", "right") for j in ("s0", "s1", "e0", "e1", "w0", "w1", "w2")],
               ("left_gripper", "right_gripper")),
    "talos": ("talos_data/robots/talos_reduced.urdf",
              ["torso_1_joint", "torso_2_joint"] + [j.format(side=s) for s in ("left", "right") for j in ARM7],
              ("wrist_left_ft_tool_link", "wrist_right_ft_tool_link")),
}


@pytest.mark.parametrize("name", list(ROBOTS))
def test_two_hands_at_full_poses_with_motion_second(erd, name):
    path, joints, hands = ROBOTS[name]
    robot = fw.load_robot(erd / path, joints=joints, end_effectors=list(hands))
    rng = np.random.default_rng(3)
    start = robot.middle.copy()
    x_goal = robot.random_configurations(rng, 1)[0]
    targets = {hand: robot.frame_placement(x_goal, hand) for hand in hands}
    objective = [(2.0, fw.Pose(hand, M)) for hand, M in targets.items()] + [(0.1, fw.Motion("all", start))]
    result = fw.solve(fw.Problem(robot, objective), seed=0, tolerance=1e-9)
    assert result.success, result.errors
    # Pinocchio's own model of the whole URDF: solved joints from the answer, locked ones at their values,
    # mimic joints from their leaders
    reached = pinocchio_placements(robot, result.configuration, targets)
    for hand, M in targets.items():
        error = pin.log6(M.inverse() * reached[hand])
        assert np.linalg.norm(error.linear) <= 1e-9 and np.linalg.norm(error.angular) <= 1e-9, (hand, error)
    # motion second: no more motion than the configuration the targets came from, which reaches them too
    goal_motion = fw.Problem(robot, fw.Motion("all", start)).values(x_goal[None])[0, 0]
    assert result.terms["motion[all]"] <= goal_motion + 1e-9


@pytest.mark.parametrize("name, expected", [
    ("pr2", ("l_gripper_tool_frame", "r_gripper_tool_frame")),
    ("tiago_dual", ("hand_left_grasping_frame", "hand_right_grasping_frame")),
    ("baxter", ("left_gripper", "right_gripper")),
])
def test_default_end_effectors_are_the_tools_of_the_solved_chains(erd, name, expected):
    path, joints, _ = ROBOTS[name]
    assert fw.load_robot(erd / path, joints=joints).end_effectors == expected


@pytest.mark.parametrize("path", ["pr2_description/urdf/pr2.urdf", "tiago_description/robots/tiago_dual.urdf",
                                  "talos_data/robots/talos_reduced.urdf",
                                  "alexander_description/urdf/alexander_v1.lowerBodyOnly.urdf"])
def test_default_end_effectors_of_a_full_urdf_are_not_sensors(erd, path):
    from framework.model.loading import SENSOR_NAMES

    robot = fw.load_robot(erd / path)
    assert robot.end_effectors and not [f for f in robot.end_effectors if SENSOR_NAMES.search(f)]
    assert not [f for f in robot.end_effectors if "caster" in f]
    assert not [f for f in robot.end_effectors if any(w in f.lower() for w in ("imu", "camera", "laser"))]  # any case


@pytest.mark.parametrize("path, hands, groups", [
    ("pr2_description/urdf/pr2.urdf", ("l_gripper_tool_frame", "r_gripper_tool_frame"),
     {"torso": 1, "head": 2, "left_arm": 7, "right_arm": 7, "left_gripper": 1, "right_gripper": 1}),
    ("tiago_description/robots/tiago_dual.urdf", ("hand_left_grasping_frame", "hand_right_grasping_frame"),
     {"torso": 1, "left_arm": 7, "right_arm": 7, "head": 2, "left_gripper": 36, "right_gripper": 36}),
    ("baxter_description/urdf/baxter.urdf", ("left_gripper", "right_gripper"),
     {"head": 1, "left_arm": 7, "right_arm": 7, "left_gripper": 1, "right_gripper": 1}),
])
def test_a_full_urdf_gives_hands_not_fingers_and_disjoint_groups(erd, path, hands, groups):
    """Every joint of the URDF solved: a hand's fingers (TIAGo: 5 chains per hand; PR2, Baxter: a gripper jaw) give
    the hand's tool frame once, wheels give none; groups are the joints on the same chains — the torso shared by
    the arms and the head, each arm, the head, the fingers on no hand's chain (grippers) — disjoint, named by role
    and side."""
    robot = fw.load_robot(erd / path)
    assert set(hands) <= set(robot.end_effectors)
    assert not [f for f in robot.end_effectors if "finger" in f or "wheel" in f or "thumb" in f]
    assert {name: len(idx) for name, idx in robot.groups.items()} == groups
    members = np.concatenate(list(robot.groups.values()))
    assert len(set(members.tolist())) == members.size  # disjoint
    model = robot.model
    for hand in hands:  # each hand's group is the chain from the shared torso to that hand (independently: the tree)
        jid, chain = model.frames[robot.frame_id(hand)].parentJoint, []
        while jid > 0:
            chain.append(model.names[jid])
            jid = model.parents[jid]
        arm = next(idx for idx in robot.groups.values() if len(idx) == 7 and
                   robot.coordinate_names[idx[-1]] in chain)
        assert {robot.coordinate_names[i] for i in arm} <= set(chain)


def test_a_free_flyer_without_joints_is_solved_as_a_floating_base(erd):
    """Hector's quadrotor has no movable joint: loading it says so and how to solve it; with a floating base its six
    coordinates are the group "base" (as on Talos, where the legs, torso, arms and head keep their own groups)."""
    path = erd / "hector_description" / "robots" / "quadrotor_base.urdf"
    with pytest.raises(fw.UnknownJointError, match="no movable joint.*floating_base=True"):
        fw.load_robot(path)
    drone = fw.load_robot(path, floating_base=True)
    assert {name: len(idx) for name, idx in drone.groups.items()} == {"base": 6}
    target = drone.frame_placement(drone.middle + 0.1, "base_link")
    assert fw.solve(fw.Problem(drone, fw.Pose("base_link", target)), seed=0).success
    talos = fw.load_robot(erd / "talos_data" / "robots" / "talos_reduced.urdf", floating_base=True)
    assert {name: len(idx) for name, idx in talos.groups.items()} == {
        "base": 6, "left_leg": 6, "right_leg": 6, "torso": 2, "left_arm": 8, "right_arm": 8, "head": 2}


def _solve_full_poses(robot, tips, count: int, seed: int, within: float, label: str = "",
                      time_budget: float | None = None) -> None:
    """Full poses of the frames ``tips`` at once, from the FK of ``count`` random configurations (numpy seed
    ``seed``), each solved with seed ``k`` (within ``time_budget`` s if given): a success, and every pose within
    ``within`` m and rad by Pinocchio's FK."""
    for k, x in enumerate(robot.random_configurations(np.random.default_rng(seed), count)):
        targets = {tip: robot.frame_placement(x, tip) for tip in tips}
        result = fw.solve(fw.Problem(robot, [(1.0, fw.Pose(tip, M)) for tip, M in targets.items()]), seed=k,
                          time_budget=time_budget)
        assert result.success, (label, k, result.errors)
        for tip, M in targets.items():
            error = pin.log6(M.inverse() * robot.frame_placement(result.configuration, tip))
            assert np.linalg.norm(error.linear) <= within and np.linalg.norm(error.angular) <= within, \
                (label, k, tip, error)


def _deepest_body_frames(model: pin.Model, roots: int, count: int) -> list[str]:
    """Body frames at the ends of the ``count`` longest joint chains of distinct limbs (a limb: the first joint
    after the ``roots`` joints of a floating base), longest first."""
    ends: dict[int, tuple[int, str]] = {}
    for frame in model.frames:
        if frame.type != pin.FrameType.BODY:
            continue
        chain, jid = [], frame.parentJoint
        while jid > 0:
            chain.append(jid)
            jid = model.parents[jid]
        if len(chain) <= roots:
            continue
        limb = chain[-(roots + 1)]
        if len(chain) > ends.get(limb, (0, ""))[0]:
            ends[limb] = (len(chain), frame.name)
    return [name for _, name in sorted(ends.values(), key=lambda e: -e[0])[:count]]


def test_every_example_robot_data_urdf_loads_and_solves_or_is_refused_by_name(erd):
    """Every URDF example-robot-data ships, as a user would load it: either it loads and a full pose of the body
    frame at the end of its longest chain is solved (3 poses, Pinocchio's FK of random configurations; the answer
    checked with Pinocchio's FK), or loading raises one of the framework's own errors saying what is wrong — never
    another exception. The legged and humanoid robots are solved again on a floating base, every limb's end at a
    full pose at once (up to four: feet and a hand). Measured with example-robot-data 6.0: 61 of 69 files load (the
    others: a <limit> without bounds, a <mimic> of a missing joint, no <link>, a free-flyer without joints), all
    183 poses strict; the hybrid without its restarts (``options={"restarts": False}``) meets 178."""
    paths = sorted(erd.rglob("*.urdf"))
    assert len(paths) >= 60
    loaded = 0
    for path in paths:
        try:
            robot = fw.load_robot(path)
        except fw.MetaikError as error:
            assert str(error), path  # a named refusal
            continue
        loaded += 1
        (tip,) = _deepest_body_frames(robot.model, 0, 1)
        rng = np.random.default_rng(7)
        for k, x in enumerate(robot.random_configurations(rng, 3)):
            target = robot.frame_placement(x, tip)
            result = fw.solve(fw.Problem(robot, fw.Pose(tip, target)), seed=k, time_budget=0.5)
            error = pin.log6(target.inverse() * robot.frame_placement(result.configuration, tip))
            assert result.success and np.linalg.norm(error.linear) <= 1e-6 and np.linalg.norm(error.angular) <= 1e-6, \
                (path.name, tip, k, result.stop_reason, error)
    assert loaded >= 60
    for name in ("talos_data/robots/talos_reduced.urdf", "anymal_c_simple_description/urdf/anymal.urdf",
                 "go2_description/urdf/go2.urdf", "g1_description/urdf/g1_29dof_rev_1_0.urdf",
                 "human_description/robots/human.urdf", "solo_description/robots/solo12.urdf"):
        robot = fw.load_robot(erd / name, floating_base=True)
        tips = _deepest_body_frames(robot.model, 6, 4)
        assert len(tips) >= 3, (name, tips)
        _solve_full_poses(robot, tips, 1, 8, 1e-6, name, time_budget=0.5)


def test_a_full_pose_of_one_leg_of_a_whole_quadruped_is_solved_to_machine_precision(erd):
    """Go1 loaded whole (12 joints), a full pose of one calf (six rows that three joints move): the damped steps
    are solved over the moving columns, where ``J Jᵀ`` is singular, so the polish reaches rounding level — by
    Pinocchio's FK, every answer within 1e-12 m and rad (before, 8 of these 10 ended between 6e-12 and 6e-7:
    within the tolerance, the polish lost to rounding)."""
    _solve_full_poses(fw.load_robot(erd / "go1_description" / "urdf" / "go1.urdf"), ("FL_calf",), 10, 7, 1e-12)


def test_poses_whose_columns_are_dependent_are_polished_to_machine_precision(erd):
    """TIAGo on a floating base, full poses of its arm's end and of both wheels at once (18 rows, 16 moving
    columns of rank 13: the wheels and the base turn about shared axes): a polishing step that fails on the
    singular ``JᵀJ`` is taken again damped at a floor (``reach.POLISH_FLOOR``), so every answer is within 1e-12 m
    and rad by Pinocchio's FK (before, all 8 of these ended between 1e-11 and 6e-7: within the tolerance, the
    polish lost to rounding)."""
    robot = fw.load_robot(erd / "tiago_description" / "robots" / "tiago_no_hand.urdf", floating_base=True)
    _solve_full_poses(robot, ("arm_7_link", "wheel_left_link", "wheel_right_link"), 8, 2, 1e-12)


def test_whole_body_poses_near_joint_limits_are_polished_to_machine_precision(erd):
    """The human model on a floating base (42 coordinates), full poses of the left hand and both feet: answers
    with many coordinates at their bounds. A polishing step that carries coordinates through their bounds moves
    them onto the bounds and solves the rest again (``reach.projected_step``) instead of being clipped, so every
    answer is within 1e-12 m and rad by Pinocchio's FK (before, 2 of these 12 ended at 1.2e-7 and 6.6e-9: a
    clipped step converges linearly, and three polish steps were not enough)."""
    robot = fw.load_robot(erd / "human_description" / "robots" / "human.urdf", floating_base=True)
    _solve_full_poses(robot, ("left_hand", "left_foot", "right_foot"), 12, 2, 1e-12)
