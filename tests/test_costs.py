"""Cost terms on batches against independent computations (Pinocchio FK, scipy Rotation)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from scipy.spatial.transform import Rotation

import framework as fw
from framework.costs import JointLimitPenalty, Motion, Orientation, Position, Program, RelativePosition
from framework.engine import objective_derivatives_at, residuals
from framework.costs.problem import Problem


@pytest.fixture(scope="module")
def robot() -> fw.Robot:
    return fw.load_robot("youbot_dual_mobile")


def reference_placements(robot, X, frame):
    return [robot.frame_placement(x, frame) for x in X]


def test_position_equals_pinocchio_distance(robot, rng):
    X = robot.random_configurations(rng, 200)
    target = np.array([0.5, -0.2, 0.45])
    term = Position("arm2_ee", target)
    values = Problem(robot, term).values(X)[:, 0]
    expected = [np.linalg.norm(M.translation - target) for M in reference_placements(robot, X, "arm2_ee")]
    np.testing.assert_allclose(values, expected, rtol=0, atol=1e-12)


def test_task_errors_of_a_population_are_pinocchio_s(robot, rng):
    """Each task block's error for a population (the rows Deb's ranking compares with the tolerances): the
    position distance and the rotation angle from Pinocchio's placements, each row equal to the single call."""
    X = robot.random_configurations(rng, 50)
    target = pin.SE3(Rotation.from_rotvec([0.3, -0.2, 0.5]).as_matrix(), np.array([0.5, -0.2, 0.45]))
    problem = Problem(robot, fw.Pose("arm2_ee", target) + 0.1 * Motion("all", robot.middle))
    errors = problem.program.task_errors(X)
    assert errors.shape == (50, 2) and problem.program.task_angular == (False, True)
    placements = reference_placements(robot, X, "arm2_ee")
    np.testing.assert_allclose(errors[:, 0], [np.linalg.norm(M.translation - target.translation)
                                              for M in placements], atol=1e-12)
    np.testing.assert_allclose(errors[:, 1], [np.linalg.norm(pin.log3(target.rotation.T @ M.rotation))
                                              for M in placements], atol=1e-9)
    for x, row in zip(X, errors):
        np.testing.assert_array_equal(problem.program.task_errors(x), row)
    np.testing.assert_array_equal(problem.program.limits(1e-3, 2e-3), [1e-3, 2e-3])


def test_values_and_errors_in_one_pass_equal_the_population_kernels(robot, rng):
    """One configuration's term values and task errors in one pass (a solve's answer found without its collision
    terms) equal the population kernels' (each block evaluated on its own), with contact rows in and out of contact."""
    shape = fw.RobotShape(robot)
    target = pin.SE3(Rotation.from_rotvec([0.3, -0.2, 0.5]).as_matrix(), np.array([0.5, -0.2, 0.45]))
    problem = Problem(robot, fw.Pose("arm2_ee", target) + 0.1 * Motion("all", robot.middle)
                      + fw.SelfCollision(shape, margin=0.01) + fw.Obstacles(shape, [fw.Sphere([0.3, 0.0, 0.4], 0.2)]))
    X = robot.random_configurations(rng, 60)
    program = problem.program
    in_contact = 0
    for x in X:
        values, errors = program.values_and_errors(x)
        np.testing.assert_allclose(values, problem.values(x[None])[0], rtol=1e-13, atol=1e-15)
        np.testing.assert_allclose(errors, program.task_errors(x), rtol=1e-13, atol=1e-15)
        in_contact += values[2] > 0
    assert 0 < in_contact < len(X)


def test_relative_position_against_pinocchio(robot, rng):
    X = robot.random_configurations(rng, 100)
    offset = np.array([0.2, -0.3, -0.2])
    values = Problem(robot, RelativePosition("arm1_ee", "arm2_ee", offset)).values(X)[:, 0]
    a = reference_placements(robot, X, "arm1_ee")
    b = reference_placements(robot, X, "arm2_ee")
    expected = [np.linalg.norm(mb.translation - ma.translation - offset) for ma, mb in zip(a, b)]
    np.testing.assert_allclose(values, expected, atol=1e-12)


def test_orientation_is_the_quaternion_vector_norm_from_scipy(robot, rng):
    X = robot.random_configurations(rng, 200)
    target_quat = Rotation.random(random_state=3).as_quat()  # (x, y, z, w)
    values = Problem(robot, Orientation("arm1_ee", target_quat, quaternion="xyzw")).values(X)[:, 0]
    for value, M in zip(values, reference_placements(robot, X, "arm1_ee")):
        relative = Rotation.from_quat(target_quat).inv() * Rotation.from_matrix(M.rotation)
        assert value == pytest.approx(np.linalg.norm(relative.as_quat()[:3]), abs=1e-12)


@pytest.mark.parametrize("phi", [0.0, 1e-9, 1e-4, 0.3, 1.5, 2.0, np.pi - 1e-6, np.pi])
def test_orientation_residual_is_the_rotation_vector_and_the_value_sin_half_angle(phi):
    """Residual log(R_tᵀR) against scipy's rotation vector (its norm is the angle, up to π), value sin(φ/2)."""
    robot = fw.load_robot("youbot_arm")
    x = robot.middle
    R = robot.frame_placement(x, "ee").rotation
    axis = np.array([1.0, 2.0, -0.5]) / np.linalg.norm([1.0, 2.0, -0.5])
    R_target = R @ Rotation.from_rotvec(-phi * axis).as_matrix()  # R_targetᵀ R = exp(φ axis)
    term = Orientation("ee", R_target)
    r, _ = residuals(Program(robot, 1.0 * term), x)
    assert np.linalg.norm(r) == pytest.approx(phi, rel=1e-9, abs=1e-12)
    if phi < np.pi - 1e-3:  # at π the axis sign is a convention
        np.testing.assert_allclose(r, Rotation.from_matrix(R_target.T @ R).as_rotvec(), atol=1e-9)
    assert Problem(robot, term).values(x)[0, 0] == pytest.approx(np.sin(phi / 2), rel=1e-9, abs=1e-15)


def test_orientation_target_as_matrix_or_quaternion_agree(robot, rng):
    X = robot.random_configurations(rng, 20)
    rot = Rotation.from_euler("y", np.pi / 2)
    a = Problem(robot, Orientation("arm1_ee", rot.as_matrix())).values(X)
    b = Problem(robot, Orientation("arm1_ee", rot.as_quat(), quaternion="xyzw")).values(X)
    np.testing.assert_allclose(a, b, atol=1e-14)


def test_motion_l2_and_normalized_l1(robot, rng):
    X = robot.random_configurations(rng, 50)
    prev = robot.random_configurations(rng, 1)[0]
    idx = robot.group("arm2")
    l2 = Problem(robot, Motion("arm2", prev)).values(X)[:, 0]
    l1 = Problem(robot, Motion("arm2", prev[idx], norm="l1")).values(X)[:, 0]
    np.testing.assert_allclose(l2, np.sqrt(((X[:, idx] - prev[idx]) ** 2).sum(axis=1)), atol=1e-14)
    np.testing.assert_allclose(l1, np.abs(X[:, idx] - prev[idx]).sum(axis=1) / (5 * np.pi), atol=1e-14)


def test_joint_limit_penalty(robot):
    X = np.tile(robot.middle, (3, 1))
    X[1, 4] = robot.upper[4] + 0.25
    X[2, 0] = robot.lower[0] - 0.5
    X[2, 12] = robot.upper[12] + 0.125
    values = Problem(robot, JointLimitPenalty(1000.0)).values(X)[:, 0]
    np.testing.assert_allclose(values, [0.0, 250.0, 625.0])


def test_composition_adds_weighted_terms_exactly(robot, rng):
    X = robot.random_configurations(rng, 64)
    prev = robot.middle
    t1 = Position("arm1_ee", [0.5, -0.2, 0.45])
    t2 = Position("arm2_ee", [0.7, -0.5, 0.25])
    m0, m1 = Motion("base", prev), Motion("arm1", prev)
    objective = 1.2 * t1 + 1.2 * t2 + 0.1 * m0 + 0.4 * m1
    problem = Problem(robot, objective)
    parts = [Problem(robot, t).values(X)[:, 0] for t in (t1, t2, m0, m1)]
    expected = 1.2 * parts[0] + 1.2 * parts[1] + 0.1 * parts[2] + 0.4 * parts[3]
    np.testing.assert_allclose(problem.cost(X), expected, rtol=1e-15, atol=0)
    evaluation = problem.evaluate(X)
    assert evaluation.names == ("position[arm1_ee]", "position[arm2_ee]", "motion[base]", "motion[arm1]")
    np.testing.assert_array_equal(evaluation.task_error, parts[0] + parts[1])
    assert sum([t1, t2]).terms == (1.0 * t1 + t2).terms  # sum() works as well
    assert [w for w, _ in 2 * (t1 + 0.5 * t2)] == [2.0, 1.0]

    program = Program(robot, problem.objective)
    assert program.terms == (t1, t2, m0, m1) and program.weight_list == (1.2, 1.2, 0.1, 0.4)
    empty = Program(robot, fw.Objective(()))  # what is left of a task of collision terms alone (hull steps)
    assert empty.terms == () and empty.task_rows == 0


def all_terms(robot, rotation_seed: int) -> list:
    """One term of every standard kind (task terms, L2 and L1 motion, the limit penalty)."""
    prev = robot.middle
    return [
        Position("arm1_ee", [0.5, -0.2, 0.45]),
        RelativePosition("arm1_ee", "arm2_ee", [0.2, -0.3, -0.2]),
        Orientation("arm2_ee", Rotation.random(random_state=rotation_seed).as_matrix()),
        Motion("arm2", prev),
        Motion("base", prev, norm="l1"),
        JointLimitPenalty(lower=robot.lower + 0.5, upper=robot.upper - 0.5),
    ]


def rho(term, r: np.ndarray, robot) -> float:
    """A term's value from its residual, written out here (the definition each term's docstring gives)."""
    if isinstance(term, Orientation):
        return float(np.sin(min(np.linalg.norm(r), np.pi) / 2))
    if isinstance(term, Motion) and term.norm == "l1":
        return float(np.abs(r).sum() / (len(r) * np.pi))
    if isinstance(term, JointLimitPenalty):
        return float(term.weight * np.abs(r).sum())
    return float(np.linalg.norm(r))


def test_residual_jacobians_match_finite_differences(robot, rng):
    """Every block's Jacobian (compiled) against central differences of its residual (compiled)."""
    h = 1e-7
    for x in robot.random_configurations(rng, 3):
        for term in all_terms(robot, 1)[:5]:
            program = Program(robot, 1.0 * term)
            _, J = residuals(program, x, -1)
            fd = np.column_stack([(residuals(program, x + e, -1)[0] - residuals(program, x - e, -1)[0]) / (2 * h)
                                  for e in np.eye(robot.n) * h])
            np.testing.assert_allclose(J, fd, atol=2e-6, err_msg=term.name)


def test_position_residual_and_jacobian_are_pinocchio_s(robot, rng):
    """Position residual p − t and its Jacobian against Pinocchio's frame placement and LOCAL_WORLD_ALIGNED
    Jacobian (times dv/dx for the planar base)."""
    target = np.array([0.3, -0.1, 0.2])
    program = Program(robot, 1.0 * Position("arm2_ee", target))
    data = robot.model.createData()
    fid = robot.frame_id("arm2_ee")
    for x in robot.random_configurations(rng, 5):
        r, J = residuals(program, x)
        J_pin = pin.computeFrameJacobian(robot.model, data, robot.to_pinocchio(x), fid, pin.LOCAL_WORLD_ALIGNED)
        np.testing.assert_allclose(r, data.oMf[fid].translation - target, atol=1e-13)
        np.testing.assert_allclose(J, (J_pin @ robot.coordinate_jacobian(x))[:3], atol=1e-12)


def test_values_are_rho_of_the_residuals_in_both_views(robot, rng):
    """value = ρ(r) for every term; the population kernel and the single-configuration residuals agree."""
    X = robot.random_configurations(rng, 6)
    X[0, -1] = robot.upper[-1] + 0.7  # one member outside the limits (the penalty is not zero there)
    for term in all_terms(robot, 3):
        program = Program(robot, 1.0 * term)
        values = Problem(robot, term).values(X)[:, 0]
        for x, value in zip(X, values):
            r, _ = residuals(program, x, 0 if isinstance(term, JointLimitPenalty) else -1)
            assert value == pytest.approx(rho(term, r, robot), rel=1e-12, abs=1e-14), term.name


def test_value_gradients_and_hessians_match_finite_differences(robot, rng):
    """The Newton phases' gradient against differences of the population values, and their Hessian (second-order
    kinematics included) against differences of that gradient — for every smooth term."""
    h = 1e-6
    for x in robot.random_configurations(rng, 3):
        for term in all_terms(robot, 2)[:4]:
            program = Program(robot, 2.0 * term)
            problem = Problem(robot, 2.0 * term)
            _, g, H = objective_derivatives_at(program, x)
            E = np.eye(robot.n) * h
            fd = (problem.cost(x + E) - problem.cost(x - E)) / (2 * h)
            np.testing.assert_allclose(g, fd, atol=1e-6, err_msg=term.name)
            if isinstance(term, Orientation):
                continue  # its second order is exact on the target only (below)
            fdH = np.column_stack([(objective_derivatives_at(program, x + e)[1] - objective_derivatives_at(
                program, x - e)[1]) / (2 * h) for e in E])
            np.testing.assert_allclose(H, fdH, atol=2e-5, err_msg=term.name)


def test_lagrangian_curvature_of_a_task_on_its_target(robot, rng):
    """Σ μ·∇²r of position, relative position and orientation blocks (from the product of exponentials) against
    differences of Jᵀμ, at configurations where the orientation is on its target."""
    h = 1e-6
    for x in robot.random_configurations(rng, 3):
        R = robot.frame_placement(x, "arm2_ee").rotation
        for term in (Position("arm1_ee", [0.5, -0.2, 0.45]), RelativePosition("arm1_ee", "arm2_ee", [0.2, 0, 0]),
                     Orientation("arm2_ee", R)):
            program = Program(robot, 1.0 * term)
            mu = rng.standard_normal(3)
            _, J = residuals(program, x)
            curvature = _curvature(program, x, mu)
            fd = np.column_stack([(residuals(program, x + e)[1].T @ mu - residuals(program, x - e)[1].T @ mu)
                                  / (2 * h) for e in np.eye(robot.n) * h])
            np.testing.assert_allclose(curvature, fd, atol=1e-6, err_msg=term.name)


def _curvature(program, x, mu):
    from tests.compiled import curvature_at

    return curvature_at(x, program.packed, np.int64(1), np.int64(0), np.int64(0), mu)


def test_a_workspace_pair_is_two_disjoint_workspaces_each_linearizing_as_one_alone(robot, rng):
    """The engine's point and trial workspaces, carved from one allocation: the views of a lone workspace's shapes,
    no byte shared between the two, and each gives a lone workspace's residuals and Jacobians (bit for bit) while the
    other is written."""
    from framework.costs.kernels import COMPUTE, TASK, YES
    from framework.costs.workspace import WORKSPACE
    from tests.compiled import linearize_in, make_workspaces, rows_in

    program = Program(robot, fw.Objective(tuple((1.0, t) for t in all_terms(robot, 3))))
    (lone_buffer, _), lone = make_workspaces(program.packed, robot.n, 1)
    (buffer, records), pair = make_workspaces(program.packed, robot.n, 2)
    assert buffer.size == 2 * lone_buffer.size and np.shares_memory(records, pair)
    arrays = [name for name in WORKSPACE.names if name in ("poses", "placements", "jacobians", "residuals",
                                                           "residual_jacobian", "scratch", "need")]
    first, second = ([pair[i][name] for name in arrays] for i in (0, 1))  # their arrays' addresses, in order
    assert first == sorted(first) and second == sorted(second) and first[0] < second[0]
    start, end = buffer.ctypes.data, buffer.ctypes.data + buffer.nbytes
    assert start <= first[0] and second[0] == start + buffer.nbytes // 2 and second[-1] < end  # disjoint halves
    x, y = rng.uniform(robot.lower, robot.upper, size=(2, robot.n))
    rows = linearize_in(lone, 0, x, TASK, YES, COMPUTE)
    assert linearize_in(pair, 0, x, TASK, YES, COMPUTE) == rows
    linearize_in(pair, 1, y, TASK, YES, COMPUTE)  # the other one written at another configuration
    alone, one, other = rows_in(lone, 0, rows), rows_in(pair, 0, rows), rows_in(pair, 1, rows)
    for a, b in zip(one, alone):  # residual rows, their Jacobian, poses, frame Jacobians
        np.testing.assert_array_equal(a, b)
    assert rows > 0 and not np.array_equal(one[0], other[0])


# ---------------------------------------------------------------------- bad input


@pytest.mark.parametrize("target", [[np.nan, 0, 0], [0, 0], [[0, 0, 0]], [0, np.inf, 0]])
def test_bad_position_target(target):
    with pytest.raises(fw.TaskError):
        Position("arm1_ee", target)


@pytest.mark.parametrize("target", [np.full((3, 3), np.nan), np.zeros(4), np.ones((2, 2)), 2 * np.eye(3), np.diag([1, 1, -1.0])])
def test_bad_orientation_target(target):
    with pytest.raises(fw.TaskError):
        Orientation("arm1_ee", target)


def test_unknown_frame_in_a_task(robot):
    with pytest.raises(fw.UnknownFrameError, match="arm3_ee"):
        Problem(robot, Position("arm3_ee", [0, 0, 0]))


def test_unknown_group_and_wrong_previous_shape(robot):
    with pytest.raises(fw.UnknownJointError):
        Problem(robot, Motion("legs", np.zeros(13)))
    with pytest.raises(fw.TaskError, match="previous configuration of group .arm1. must have 5 \\(the group.s\\) or "
                                         "13 \\(the robot.s\\) values; got 7"):
        Problem(robot, Motion("arm1", np.zeros(7)))


@pytest.mark.parametrize("weight", [-1.0, np.nan, np.inf])
def test_invalid_weights(weight):
    with pytest.raises(fw.TaskError, match="weight"):
        weight * Position("arm1_ee", [0, 0, 0])


def test_wrong_population_shape_in_cost(robot):
    problem = Problem(robot, Position("arm1_ee", [0, 0, 0]))
    with pytest.raises(fw.ConfigurationError):
        problem.cost(np.zeros((4, 12)))
    with pytest.raises(fw.ConfigurationError):
        problem.cost(np.full((4, 13), np.nan))


def test_problem_previous_is_where_the_motion_terms_measure_from(robot, rng):
    q_prev = robot.random_configurations(rng, 1)[0]
    problem = Problem(robot, Position("arm1_ee", [0.5, 0, 0.4]) + Motion("arm1", q_prev) + Motion("base", q_prev))
    expected = robot.middle.copy()
    for group in ("arm1", "base"):
        expected[robot.group(group)] = q_prev[robot.group(group)]
    np.testing.assert_array_equal(problem.previous, expected)
    assert Problem(robot, Position("arm1_ee", [0.5, 0, 0.4])).previous is None


def test_motion_reads_each_robot_s_group_and_keeps_it_read_only(robot, rng):
    """A Motion term remembers its group's coordinates per robot: used with a second robot whose group differs
    (the fixed-platform youBot: no base), its values are that robot's (against numpy on the group's slice)."""
    fixed = fw.load_robot("youbot_dual")
    term = Motion("arm2", np.zeros(5))
    for r in (robot, fixed, robot):
        X = r.random_configurations(rng, 20)
        np.testing.assert_allclose(Problem(r, term).values(X)[:, 0], np.linalg.norm(X[:, r.group("arm2")], axis=1),
                                   rtol=0, atol=1e-12)
        assert not term.indices(r).flags.writeable
    assert not np.array_equal(term.indices(robot), term.indices(fixed))


def test_jacobians_on_a_real_robot_with_continuous_joints(erd, rng):
    """PR2 from example-robot-data (torso + both arms, continuous forearm and wrist rolls): every block's Jacobian
    against central differences of its residual, and a pose's position residual against Pinocchio."""
    joints = ["torso_lift_joint"] + [f"{s}_{j}_joint" for s in "lr" for j in (
        "shoulder_pan", "shoulder_lift", "upper_arm_roll", "elbow_flex", "forearm_roll", "wrist_flex", "wrist_roll")]
    pr2 = fw.load_robot(erd / "pr2_description" / "urdf" / "pr2.urdf", joints=joints)
    hands = ("l_gripper_tool_frame", "r_gripper_tool_frame")
    target = pr2.frame_placement(pr2.random_configurations(rng, 1)[0], hands[0])
    terms = [fw.Pose(hands[0], target), RelativePosition(hands[0], hands[1], [0.0, -0.3, 0.0]),
             Motion("all", pr2.middle)]
    h = 1e-7
    for x in pr2.random_configurations(rng, 3):
        for term in terms:
            program = Program(pr2, 1.0 * term)
            r, J = residuals(program, x, -1)
            fd = np.column_stack([(residuals(program, x + e, -1)[0] - residuals(program, x - e, -1)[0]) / (2 * h)
                                  for e in np.eye(pr2.n) * h])
            np.testing.assert_allclose(J, fd, atol=2e-6, err_msg=term.name)
        r, _ = residuals(Program(pr2, 1.0 * terms[0]), x)
        np.testing.assert_allclose(r[:3], pr2.frame_placement(x, hands[0]).translation - target.translation,
                                   atol=1e-13)


def test_quaternion_order_is_named():
    """Every form of a rotation gives scipy's matrix: 4 numbers with quaternion="xyzw" or "wxyz", a
    pinocchio.Quaternion (built w first), a scipy Rotation, a matrix, an SE3, a 4x4; the order is kept for the targets
    a term is moved to; 4 numbers without an order are refused, saying how (read in the other order they would be
    another rotation, 2.6 rad away here)."""
    rot = Rotation.from_euler("zyx", [0.3, -0.7, 1.1])
    x, y, z, w = rot.as_quat()
    R = rot.as_matrix()
    forms = [Orientation("arm1_ee", [x, y, z, w], quaternion="xyzw"), Orientation("arm1_ee", [w, x, y, z], quaternion="wxyz"),
             Orientation("arm1_ee", pin.Quaternion(w, x, y, z)), Orientation("arm1_ee", rot), Orientation("arm1_ee", R),
             Orientation("arm1_ee", pin.SE3(R, np.ones(3))), Orientation("arm1_ee", pin.SE3(R, np.ones(3)).homogeneous),
             fw.Pose("arm1_ee", (np.zeros(3), [w, x, y, z]), quaternion="wxyz")]
    for term in forms:
        np.testing.assert_allclose(term.target if isinstance(term, Orientation) else term.rotation, R, atol=1e-12)
    wrong = Rotation.from_quat([w, x, y, z]).as_matrix()  # the same numbers read in the other order
    assert np.arccos((np.trace(wrong.T @ R) - 1) / 2) > 1.0
    moved = Orientation("arm1_ee", [0, 0, 0, 1], quaternion="wxyz")  # w = 0: a half turn about z
    moved.set_target([w, x, y, z])
    np.testing.assert_allclose(moved.target, R, atol=1e-12)
    for make in (lambda: Orientation("arm1_ee", [x, y, z, w]), lambda: fw.Pose("arm1_ee", (np.zeros(3), [x, y, z, w])),
                 lambda: fw.RelativePose("arm1_ee", "arm2_ee", (np.zeros(3), [x, y, z, w]))):
        with pytest.raises(fw.TaskError, match='name their order, quaternion "xyzw".* or "wxyz"'):
            make()
    with pytest.raises(fw.TaskError, match="names the order of 4 numbers"):
        Orientation("arm1_ee", R, quaternion="wxyz")
    with pytest.raises(fw.TaskError, match="quaternion must be 'xyzw' or 'wxyz'"):
        Orientation("arm1_ee", [x, y, z, w], quaternion="xyz")


def test_a_locked_floating_base_names_its_quaternion_order():
    """7 numbers locking a floating base need their quaternion order; in either order, and as an SE3 or a
    (position, pinocchio.Quaternion) pair, the base stands at the same pose."""
    rot = Rotation.from_euler("zyx", [0.4, 0.2, -0.3])
    x, y, z, w = rot.as_quat()
    p = [0.1, -0.2, 0.3]
    text = ('<robot name="f"><link name="body"/><link name="tip"/><joint name="j" type="revolute"><parent link="body"/>'
            '<child link="tip"/><origin xyz="0 0 0.5"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" '
            'velocity="1"/></joint></robot>')
    poses = []
    for locked, order in (([*p, x, y, z, w], "xyzw"), ([*p, w, x, y, z], "wxyz"), (pin.SE3(rot.as_matrix(), np.array(p)), None),
                          ((p, pin.Quaternion(w, x, y, z)), None)):
        robot = fw.robot_from_urdf(text, floating_base=True, locked={"root_joint": locked}, quaternion=order)
        poses.append(robot.frame_placement(robot.middle, "body"))
    for pose in poses:
        np.testing.assert_allclose(pose.translation, p, atol=1e-12)
        np.testing.assert_allclose(pose.rotation, rot.as_matrix(), atol=1e-12)
    with pytest.raises(fw.LimitsError, match='name their order, quaternion "xyzw"'):
        fw.robot_from_urdf(text, floating_base=True, locked={"root_joint": [*p, x, y, z, w]})


def test_a_target_moved_in_place_packs_as_a_problem_built_with_it(robot, rng):
    """Moving targets of a problem's terms (``set_target``, re-packed on the next refresh from each term's
    ``parameters``) gives the parameters and costs of a problem built afresh with those targets, and a term's
    ``parameters`` are its blocks' concatenated."""
    X = robot.random_configurations(rng, 4)

    def terms(k):
        y = X[k]
        return [fw.Position("arm2_ee", robot.frame_placement(y, "arm2_ee").translation),
                fw.Pose("arm1_ee", robot.frame_placement(y, "arm1_ee")),
                Orientation("arm2_ee", robot.frame_placement(y, "arm2_ee").rotation),
                fw.RelativePose("arm1_ee", "arm2_ee", robot.frame_placement(y, "arm1_ee").actInv(
                    robot.frame_placement(y, "arm2_ee"))),
                Motion("base", y[:3]), Motion("arm1", y, norm="l1"), fw.JointTarget("arm2", y)]

    moved = terms(1)
    problem = Problem(robot, sum(moved[1:], moved[0]))
    problem.cost(X)  # packed with the first targets
    fresh = terms(2)
    for term, new in zip(moved, fresh):
        target = {fw.Position: lambda t: t.target, fw.Pose: lambda t: t.target, Orientation: lambda t: t.target,
                  fw.RelativePose: lambda t: (t.position, t.rotation), Motion: lambda t: t.previous,
                  fw.JointTarget: lambda t: t.previous}[type(new)](new)
        term.set_target(target)
    built = Problem(robot, sum(fresh[1:], fresh[0]))
    np.testing.assert_array_equal(problem.cost(X), built.cost(X))
    np.testing.assert_array_equal(problem.program.packed.params, built.program.packed.params)
    assert not np.array_equal(problem.program.packed.params, Problem(robot, sum(terms(1)[1:], terms(1)[0])).program.packed.params)
    for term in fresh:
        blocks = term.blocks(robot)
        np.testing.assert_array_equal(term.parameters(robot), np.concatenate([b.params for b in blocks]))
    # a term of a fixed layout (its class and frames decide it) packs blocks of one signature whatever its target:
    # the problem built afresh found the moved one's layout without building its blocks
    assert built.program.layout is problem.program.layout
    for term, new in zip(moved, fresh):
        assert term.packed(robot)[1] == new.packed(robot)[1]
        if new.fixed_layout:
            assert new.layout_key(robot) == (type(new), new.frames)
    assert not Motion("base", X[0, :3]).fixed_layout  # its layout depends on its coordinates


def test_named_errors_report_the_worst_block_of_a_name(robot, rng):
    """Blocks sharing a name (here two terms named alike, one between them named otherwise: not contiguous) report
    their largest error; a name of one block its own."""
    x = robot.random_configurations(rng, 1)[0]
    a, b = robot.frame_placement(x, "arm1_ee").translation, robot.frame_placement(x, "arm2_ee").translation
    problem = Problem(robot, Position("arm1_ee", a + [0.1, 0, 0], name="p") + Position("arm2_ee", b, name="q")
                      + Position("arm2_ee", b + [0, 0.3, 0], name="p"))
    errors = problem.program.task_errors(x).tolist()
    assert errors == pytest.approx([0.1, 0.0, 0.3], abs=1e-12)
    assert problem.program.named_errors(errors) == {"p": errors[2], "q": errors[1]}


def test_a_task_file_names_the_order_of_its_quaternions(tmp_path):
    """``quaternion = "wxyz"`` beside 4 numbers in a [[terms]] entry (pose or orientation) reads them in that order;
    without it the file is refused with a message that says how."""
    from framework.io.taskfile import load_task

    rot = Rotation.from_euler("zyx", [0.3, -0.7, 1.1])
    x, y, z, w = rot.as_quat()
    text = f"""
[task]
name = "q"
robot = "puma560"
[[terms]]
type = "pose"
frame = "ee"
position = [0.4, 0.1, 0.3]
rotation = [{w}, {x}, {y}, {z}]
quaternion = "wxyz"
[[terms]]
type = "orientation"
frame = "ee"
target = [{x}, {y}, {z}, {w}]
quaternion = "xyzw"
"""
    path = tmp_path / "q.toml"
    path.write_text(text)
    pose, orientation = load_task(path).cases[0].problem.objective.terms
    np.testing.assert_allclose(pose[1].rotation, rot.as_matrix(), atol=1e-12)
    np.testing.assert_allclose(orientation[1].target, rot.as_matrix(), atol=1e-12)
    path.write_text(text.replace('quaternion = "wxyz"\n', ""))
    with pytest.raises(fw.TaskError, match='name their order, quaternion "xyzw"'):
        load_task(path)
