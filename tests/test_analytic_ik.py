"""Closed-form IK (framework.solvers.analytic): the family read from the model, every solution exact by Pinocchio's
forward kinematics and within the limits, and none missing — against the numeric solver from many starts."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import framework as fw
from framework.errors import TaskError
from tests.conftest import example_robot_data_dir

ERD = example_robot_data_dir()


def _kr6() -> fw.Robot:
    rtbdata = pytest.importorskip("rtbdata")
    kuka = Path(rtbdata.__path__[0]) / "xacro" / "kuka_description"
    return fw.load_robot(kuka / "kuka_kr6" / "urdf" / "kr6r700sixx.xacro",
                         package_dirs={"kuka_kr6_support": kuka / "kuka_kr6", "kuka_resources": kuka / "kuka_resources"})


def _pybullet(path: str, **options) -> fw.Robot:
    pybullet_data = pytest.importorskip("pybullet_data")
    return fw.load_robot(Path(pybullet_data.getDataPath()) / path, **options)


#: robot, frame, the family expected
ARMS = {
    "panda_locked": (lambda: fw.load_robot(ERD / "panda_description" / "urdf" / "panda.urdf",
                                           locked={"panda_joint7": 0.3, "panda_finger_joint1": 0.0}),
                     "panda_hand_tcp", "spherical wrist, axes 1 and 2 meet (read from the tool back)"),
    "iiwa_locked": (lambda: _pybullet("kuka_iiwa/model.urdf", locked={"lbr_iiwa_joint_3": 0.4}), "lbr_iiwa_link_7",
                    "spherical wrist, axes 1 and 2 meet"),
    "ur5": (lambda: fw.load_robot(ERD / "ur_description" / "urdf" / "ur5_robot.urdf"), "tool0", "axes 2 ∥ 3 ∥ 4"),
    "ur10": (lambda: fw.load_robot(ERD / "ur_description" / "urdf" / "ur10_robot.urdf"), "tool0", "axes 2 ∥ 3 ∥ 4"),
    "puma560": (lambda: fw.load_robot("puma560"), "ee", "spherical wrist, axes 2 ∥ 3"),
    "youbot_arm": (lambda: fw.load_robot("youbot_arm"), "ee", "five joints, axes 2 ∥ 3 ∥ 4"),
    "fanuc": (lambda: fw.load_robot("fanuc_am120ib"), "ee", "spherical wrist, axes 2 ∥ 3"),
    "kr6": (_kr6, "tool0", "spherical wrist, axes 2 ∥ 3"),
}


@pytest.fixture(scope="module", params=sorted(ARMS))
def arm(request):
    make, frame, family = ARMS[request.param]
    return make(), frame, family


def _pose_error(robot: fw.Robot, x: np.ndarray, frame: str, target: pin.SE3) -> float:
    reached = robot.frame_placement(x, frame)
    return max(float(np.linalg.norm(reached.translation - target.translation)),
               float(np.linalg.norm(pin.log3(reached.rotation.T @ target.rotation))))


def test_every_solution_is_exact_within_the_limits_and_the_sampled_one_is_first(arm):
    """Poses of random configurations: each solution meets the pose to 1e-10 (m, rad) by Pinocchio's FK, lies in
    the limits, none twice; with the sampled configuration as reference it comes first (distance 0: a solver
    missing the sample's own branch would fail here); the others follow by distance."""
    robot, frame, family = arm
    form = fw.closed_form(robot, frame)
    assert form.family is not None and form.family.startswith(family)
    rng = np.random.default_rng(7)
    counts = []
    for x in robot.random_configurations(rng, 40):
        target = robot.frame_placement(x, frame)
        found = fw.analytic_ik(robot, frame, target, reference=x)
        X = found.configurations
        counts.append(len(X))
        assert found.reachable and found.reason == ""
        np.testing.assert_allclose(X[0], x, atol=1e-8)
        assert max(_pose_error(robot, q, frame, target) for q in X) <= 1e-10
        assert np.all(X >= robot.lower - 1e-12) and np.all(X <= robot.upper + 1e-12)
        distances = np.linalg.norm(X - x, axis=1)
        assert np.all(np.diff(distances) >= -1e-12)
        apart = np.abs(X[:, None] - X[None]).max(axis=2) + np.eye(len(X))
        assert apart.min() > 1e-6
    assert np.mean(counts) >= (1.2 if form.first else 2)  # 2-8 solutions per pose of a 6R arm, 1-4 of a 5R


def test_no_solution_is_missing(arm):
    """For a few poses, the numeric solver from 60 random starts: every configuration it finds (pose within 1e-9)
    is one of the closed form's (a brute-force search for the solution set, which a missed branch fails)."""
    robot, frame, _ = arm
    rng = np.random.default_rng(3)
    found = 0
    for x in robot.random_configurations(rng, 3):
        target = robot.frame_placement(x, frame)
        X = fw.analytic_ik(robot, frame, target).configurations
        problem = fw.Problem(robot, fw.Pose(frame, target))
        for start in robot.random_configurations(rng, 60):
            result = fw.solve(problem, "multistart_lm", initial=start, seed=0, tolerance=1e-12,
                              options={"closed_form": False})  # the numeric engine alone
            if _pose_error(robot, result.configuration, frame, target) <= 1e-9:
                assert np.abs(X - result.configuration).max(axis=1).min() <= 1e-6
                found += 1
    assert found >= 60  # most numeric solves converge: the check is not vacuous


def test_a_pose_beyond_reach_or_limits_says_so():
    """Beyond reach: no solution and the reason; within reach but every solution's joint 1 outside a narrowed
    range: none, and that reason."""
    robot = fw.load_robot("puma560")
    found = fw.analytic_ik(robot, "ee", pin.SE3(np.eye(3), np.array([5.0, 0.0, 0.0])))
    assert not found.reachable and len(found) == 0 and "beyond the arm's reach" in found.reason
    x = robot.random_configurations(np.random.default_rng(1), 1)[0]
    target = robot.frame_placement(x, "ee")
    q1 = np.sort(fw.analytic_ik(robot, "ee", target).configurations[:, 0])
    gaps = np.diff(np.concatenate([[robot.lower[0]], q1, [robot.upper[0]]]))
    k = int(np.argmax(gaps))  # the widest stretch of joint 1's range holding no solution
    low = robot.lower[0] if k == 0 else q1[k - 1]
    narrow = robot.with_bounds({robot.joints[0].name: (low + 0.01, low + gaps[k] - 0.01)})
    hidden = fw.analytic_ik(narrow, "ee", target)
    assert len(hidden) == 0 and "outside the joint limits" in hidden.reason


def test_every_form_of_a_pose_gives_the_same_solutions_and_a_bad_one_says_what_is_wrong():
    """An SE3, its 4x4 matrix and its (position, rotation) pair give the same solutions (the SE3 goes straight to
    the compiled call, the others are checked first); a matrix that is no transform raises, it does not read as
    beyond reach."""
    robot = fw.load_robot("puma560")
    target = robot.frame_placement(robot.random_configurations(np.random.default_rng(4), 1)[0], "ee")
    X = fw.analytic_ik(robot, "ee", target).configurations
    assert len(X) > 0
    for same in (target.homogeneous, (target.translation, target.rotation)):
        assert np.array_equal(fw.analytic_ik(robot, "ee", same).configurations, X)
    assert np.array_equal(fw.AnalyticIK(robot, "ee")(target).configurations, X)  # prepared: the same call
    sheared = target.homogeneous
    sheared[0, 1] += 0.1
    with pytest.raises(TaskError, match="not a rotation matrix"):
        fw.analytic_ik(robot, "ee", sheared)
    bad = pin.SE3(target)
    bad.rotation = 1.1 * target.rotation  # pin stores it as given
    with pytest.raises(TaskError, match="not a rotation matrix"):
        fw.analytic_ik(robot, "ee", bad)


def test_chains_without_a_closed_form_say_why():
    cases = {"baxter_arm": "a 7R chain, but no joint", "stanford_arm": "other than revolute"}
    for name, why in cases.items():
        robot = fw.load_robot(name)
        form = fw.closed_form(robot, robot.end_effectors[0])
        assert form.family is None and why in form.reason
        with pytest.raises(TaskError, match="no closed form"):
            fw.analytic_ik(robot, robot.end_effectors[0], pin.SE3.Identity())
        with pytest.raises(TaskError, match="no closed form"):
            fw.AnalyticIK(robot, robot.end_effectors[0])


def test_continuous_joints_get_their_2pi_copies():
    """UR5's joints span ±2π: every base solution comes with each 2π copy of each joint within the limits."""
    robot = fw.load_robot(ERD / "ur_description" / "urdf" / "ur5_robot.urdf")
    x = robot.random_configurations(np.random.default_rng(0), 1)[0]
    target = robot.frame_placement(x, "tool0")
    X = fw.analytic_ik(robot, "tool0", target).configurations
    bases = np.unique(np.round(np.mod(X + np.pi, 2 * np.pi) - np.pi, 8), axis=0)
    shifts = 2 * np.pi * np.arange(-3, 4)
    copies = [np.prod([np.sum((robot.lower[i] <= b[i] + shifts) & (b[i] + shifts <= robot.upper[i])) for i in range(6)])
              for b in bases]
    assert len(bases) >= 2 and len(X) == sum(copies) > len(bases)


def test_show_prints_the_closed_form_of_each_end_effector(capsys):
    from framework.cli import EXIT_OK, main

    assert main(["show", "puma560"]) == EXIT_OK
    assert "closed form of ee: spherical wrist, axes 2 ∥ 3" in capsys.readouterr().out
    assert main(["show", "baxter_arm"]) == EXIT_OK
    assert "closed form of ee: none (a 7R chain, but no joint" in capsys.readouterr().out.replace("\n", " ")


def test_a_pose_solve_starts_from_the_closed_form():
    """fw.solve on a pose of a closed-form arm starts from its exact solution (the engine has nothing left to do);
    with a motion regularizer, from the solution it prefers (the least cost: checked against every solution's
    cost); a baseline solver is not seeded."""
    robot = fw.load_robot("puma560")
    rng = np.random.default_rng(5)
    x, start = robot.random_configurations(rng, 2)
    target = robot.frame_placement(x, "ee")
    result = fw.solve(fw.Problem(robot, fw.Pose("ee", target)), initial=start)
    assert result.settings["start"] == "closed form" and result.success and result.iterations <= 1
    X = fw.analytic_ik(robot, "ee", target, reference=start).configurations
    np.testing.assert_allclose(result.configuration, X[0], atol=1e-9)
    far = X[-1]  # a motion term pulling towards the farthest solution: that one costs least
    problem = fw.Problem(robot, fw.Pose("ee", target) + 0.1 * fw.Motion("all", far))
    result = fw.solve(problem, initial=start)
    costs = problem.cost(X)
    np.testing.assert_allclose(result.configuration, X[np.argmin(costs)], atol=1e-6)
    assert fw.solve(fw.Problem(robot, fw.Pose("ee", target)), "dls", initial=start).settings["start"] == "initial"


@pytest.mark.parametrize("arm7", ["panda", "iiwa"])
def test_a_7r_arm_searches_one_joint(arm7):
    """Panda (joint 7 searched, the chain read from the tool back) and iiwa: every solution found is exact by
    Pinocchio's FK and within the limits; a pose of a random configuration is found at least 98 % of the time (the
    search steps 0.05 rad: a pose reachable only between two steps is missed, and says so)."""
    robot, frame = ((fw.load_robot(ERD / "panda_description" / "urdf" / "panda.urdf",
                                   locked={"panda_finger_joint1": 0.0}), "panda_hand_tcp") if arm7 == "panda"
                    else (_pybullet("kuka_iiwa/model.urdf"), "lbr_iiwa_link_7"))
    form = fw.closed_form(robot, frame)
    assert form.exists and "searched" in form.family
    found = 0
    X = robot.random_configurations(np.random.default_rng(2), 100)
    for x in X:
        target = robot.frame_placement(x, frame)
        solutions = fw.analytic_ik(robot, frame, target)
        found += solutions.reachable
        assert solutions.reachable or "searched joint" in solutions.reason
        for q in solutions.configurations:
            assert _pose_error(robot, q, frame, target) <= 1e-10
            assert np.all(q >= robot.lower - 1e-12) and np.all(q <= robot.upper + 1e-12)
    assert found >= 98


def test_tracking_with_the_closed_form_takes_the_least_motion_at_every_waypoint():
    """Paper 002's Puma circle (position, orientation and an L1 motion term to the previous waypoint) tracked by the
    ``closed_form`` solver: every waypoint exact (1e-12), and its configuration the one of least L1 motion from the
    previous among all the pose's solutions (a brute force over fw.analytic_ik's set): no branch flips that a
    nearer solution would avoid."""
    from framework.io.taskfile import load_task
    from framework.resources import data_dir
    from framework.tracking import track

    task = load_task(data_dir("tasks") / "paper002_puma_circle.toml")
    case = task.cases[0]
    result = track(task.robot, case.trajectory, case.builder, solver="closed_form", initial=case.initial,
                   progress=False)
    assert result.position_error.max() <= 1e-12 and result.orientation_error.max() <= 1e-12
    previous = case.initial
    for k, x in enumerate(result.configurations):
        target = pin.SE3(case.trajectory.rotation(k), case.trajectory.positions[k])
        X = fw.analytic_ik(task.robot, "ee", target, reference=previous).configurations
        motion = np.abs(X - previous).sum(axis=1)
        assert np.abs(x - previous).sum() <= motion.min() + 1e-9
        previous = x


def test_a_five_joint_arm_says_which_orientations_it_cannot_take():
    """The youBot arm (5 joints) reaches a pose only with orientations its axes allow: a pose of a random
    configuration is solved (the sample among the solutions), the same position with a turned orientation says
    why it has none; a batch gives each pose's solutions over the five coordinates, exact by Pinocchio's FK."""
    robot = fw.load_robot("youbot_arm")
    x = robot.random_configurations(np.random.default_rng(4), 1)[0]
    target = robot.frame_placement(x, "ee")
    assert np.abs(fw.analytic_ik(robot, "ee", target).configurations - x).max(axis=1).min() <= 1e-8
    # its reachable orientations keep axis 5's angle to axis 2 (both turned by joint 1 only): turning the hand about
    # their common normal by 0.5 rad leaves them
    data = robot.model.createData()
    pin.forwardKinematics(robot.model, data, robot.to_pinocchio(x))
    axes = [data.oMi[j.pin_id].rotation @ j.axis for j in robot.joints]
    normal = np.cross(axes[4], axes[1])
    turn = pin.exp3(0.5 * normal / np.linalg.norm(normal))
    turned = pin.SE3(turn @ target.rotation, target.translation)
    found = fw.analytic_ik(robot, "ee", turned)
    assert len(found) == 0 and "five-joint arm takes only some orientations" in found.reason
    X = robot.random_configurations(np.random.default_rng(5), 50)
    batch = fw.analytic_ik_batch(robot, "ee", [robot.frame_placement(q, "ee") for q in X])
    assert batch.chain.shape == (50, 8, 5) and batch.counts.min() >= 1
    for q, nearest in zip(X, batch.nearest):
        assert _pose_error(robot, nearest, "ee", robot.frame_placement(q, "ee")) <= 1e-10
