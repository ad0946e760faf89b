"""SelfCollision and Obstacles: hinges on sphere distances, against a closed form and coal's exact check."""

from __future__ import annotations

import warnings
from pathlib import Path

import numba
import numpy as np
import pinocchio as pin
import pytest

import framework as fw
from framework.engine import residuals
from framework.errors import TaskError
from tests.test_collision import L, R


def test_motion_towards_a_collision_stops_at_the_margin(sphere_arm):
    """Motion towards (0, 0) puts the two spheres on each other; kept apart, the optimum splits the angle
    θ* = 2 asin((2R + margin) / 2L) equally between the joints (closed form), found by DE ranked by Deb's rules (the default with priorities)."""
    robot, shape, exact = sphere_arm
    margin = 0.01
    free = fw.solve(fw.Problem(robot, 1.0 * fw.Motion("all", [0.0, 0.0])), initial=np.array([1.0, 0.5]))
    assert shape.check(free.configuration).colliding
    problem = fw.Problem(robot, fw.SelfCollision(shape, margin=margin, cover=exact) + fw.Motion("all", [0.0, 0.0]))
    result = fw.solve(problem, "de", seed=0, max_iterations=300, tolerance=1e-6)
    half = np.arcsin((2 * R + margin) / (2 * L))
    assert result.success
    np.testing.assert_allclose(np.abs(result.configuration), [half, half], atol=1e-3)
    assert not shape.check(result.configuration, margin=margin - 1e-5).colliding


def test_the_local_engine_leaves_a_collision(sphere_arm):
    robot, shape, exact = sphere_arm
    start = np.array([0.05, 0.02])
    assert shape.check(start).colliding
    result = fw.solve(fw.Problem(robot, fw.SelfCollision(shape, cover=exact) + 0.1 * fw.Motion("all", start)),
                      initial=start, tolerance=1e-9)
    assert result.success and not shape.check(result.configuration).colliding


def test_panda_reaches_targets_without_self_collision(erd):
    """Position targets from random starts with the automatic sphere cover: every answer collision-free by coal
    on the exact meshes (the spheres are larger than the links, so this holds with a margin)."""
    robot = fw.load_robot(erd / "panda_description" / "urdf" / "panda.urdf",
                          joints=[f"panda_joint{i}" for i in range(1, 8)], end_effectors=["panda_hand"])
    shape = fw.RobotShape(robot, srdf=erd / "panda_description" / "srdf" / "panda.srdf")
    problem = fw.Problem(robot, fw.Position("panda_hand", [0.3, 0.0, 0.2]) + fw.SelfCollision(shape))
    rng = np.random.default_rng(0)
    for k in range(8):
        result = fw.solve(problem, seed=k, tolerance=1e-6, initial=robot.random_configurations(rng, 1)[0])
        assert result.success and not shape.check(result.configuration).colliding


def test_sphere_obstacles_are_kept_clear(sphere_arm):
    robot, shape, exact = sphere_arm
    obstacle = np.array([0.0, L, 0.0])  # on the forearm sphere's circle, at θ1 + θ2 = π/2
    problem = fw.Problem(robot, fw.Obstacles(shape, [fw.Sphere(obstacle, 0.05)], margin=0.01, cover=exact)
                         + fw.Motion("all", [np.pi / 4, np.pi / 4]))
    result = fw.solve(problem, "de", seed=0, max_iterations=300, tolerance=1e-6)
    world = exact.world_centers(shape, result.configuration)[1]
    assert result.success and np.linalg.norm(world - obstacle) >= R + 0.05 + 0.01 - 1e-6
    with pytest.raises(TaskError, match="no obstacle"):
        fw.Obstacles(shape, [])
    with pytest.raises(TaskError, match="margin"):
        fw.SelfCollision(shape, margin=-1.0, cover=exact)


def test_collision_blocks_are_built_once_per_shape_cover_scene_and_margin(sphere_arm):
    """A tracking task makes its terms anew at every waypoint: their blocks come from the shape, built once for each
    cover, margin (and scene), and the same as a first build's."""
    robot, shape, exact = sphere_arm
    first = fw.SelfCollision(shape, margin=0.01, cover=exact).blocks(robot)
    assert fw.SelfCollision(shape, margin=0.01, cover=exact).blocks(robot) is first
    other = fw.SelfCollision(shape, margin=0.02, cover=exact).blocks(robot)
    assert not all(np.array_equal(a.params, b.params) for a, b in zip(other, first))  # the margin is a parameter
    fresh = fw.SelfCollision(fw.RobotShape(robot), margin=0.01, cover=exact).blocks(robot)  # another shape: built anew
    assert [b.signature() for b in fresh] == [b.signature() for b in first]
    assert all(np.array_equal(a.params, b.params) for a, b in zip(fresh, first))
    scene = fw.Scene((fw.Sphere([0.0, L, 0.0], 0.05),))
    blocks = fw.Obstacles(shape, scene, margin=0.01, cover=exact).blocks(robot)
    assert fw.Obstacles(shape, scene, margin=0.01, cover=exact).blocks(robot) is blocks
    moved = fw.Obstacles(shape, [fw.Sphere([0.0, -L, 0.0], 0.05)], margin=0.01, cover=exact).blocks(robot)
    assert not np.array_equal(moved[0].params, blocks[0].params)  # another scene: its own blocks
    for make in (lambda: fw.SelfCollision(shape, margin=0.01, cover=exact),
                 lambda: fw.Obstacles(shape, scene, margin=0.01, cover=exact)):
        # their packing too (signature and parameters), equal to the blocks' own and read-only
        a, b = make(), make()
        assert a.parameters(robot) is b.parameters(robot) and not a.parameters(robot).flags.writeable
        assert a.packed(robot)[1] == tuple(block.signature() for block in a.blocks(robot))
        np.testing.assert_array_equal(a.parameters(robot), np.concatenate([k.params for k in a.blocks(robot)]))


def test_pairs_whose_covers_never_separate_are_left_to_the_exact_check(erd):
    """PR2's shoulder pans never meet (coal: apart in every sampled configuration) but their sphere covers overlap
    in every one: a sphere row for them would make every problem infeasible. SelfCollision leaves that pair (and
    only pairs like it) out of its rows with a warning; coal's exact check, which decides success, still holds
    every pair, and a two-hand solve with self-collision succeeds."""
    joints = ["torso_lift_joint"] + [f"{s}_{j}" for s in "lr" for j in (
        "shoulder_pan_joint", "shoulder_lift_joint", "upper_arm_roll_joint", "elbow_flex_joint", "forearm_roll_joint",
        "wrist_flex_joint", "wrist_roll_joint")]
    robot = fw.load_robot(erd / "pr2_description" / "urdf" / "pr2.urdf", joints=joints)
    shape = fw.RobotShape(robot, srdf=erd / "pr2_description" / "srdf" / "pr2.srdf")
    cover = shape.cover()
    shoulders = ("l_shoulder_pan_link_0", "r_shoulder_pan_link_0")
    assert shape.inseparable(cover) == {shoulders}
    assert shape.inseparable(cover) is shape.inseparable(cover)  # computed once
    rng = np.random.default_rng(5)
    left, right = ([k for k, g in enumerate(cover.geometries) if g == name] for name in shoulders)
    for x in robot.random_configurations(rng, 5):  # the covers overlap, the meshes do not (independently: coal)
        c = cover.world_centers(shape, x)
        gap = np.linalg.norm(c[left][:, None] - c[right][None], axis=2) - cover.radii[left][:, None] \
            - cover.radii[right][None]
        assert gap.min() < -0.05
        assert all({c.a, c.b} != set(shoulders) for c in shape.check(x).contacts)
    term = fw.SelfCollision(shape)
    with pytest.warns(UserWarning, match="left to the exact check.*shoulder_pan_link"):
        blocks = term.blocks(robot)
    bodies = {b.frames for b in blocks}
    assert ("body[l_shoulder_pan_joint]", "body[r_shoulder_pan_joint]") not in bodies
    assert ("body[l_forearm_roll_joint]", "body[r_forearm_roll_joint]") in bodies  # the arms still kept apart
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # said once: the shape builds the blocks of a cover and margin once
        rows = fw.Problem(robot, fw.SelfCollision(shape)).program  # the term's rows alone
    assert fw.SelfCollision(shape).blocks(robot) is blocks
    x = robot.random_configurations(rng, 1)[0]
    while shape.check(x, distances=False).colliding or residuals(rows, x)[0].min() < 0:
        x = robot.random_configurations(rng, 1)[0]  # a target whose configuration the sphere model calls clear
    hands = ("l_gripper_tool_frame", "r_gripper_tool_frame")
    objective = fw.Pose(hands[0], robot.frame_placement(x, hands[0])) \
        + fw.Pose(hands[1], robot.frame_placement(x, hands[1]))
    result = fw.solve(fw.Problem(robot, objective + term), seed=0, time_budget=5.0)  # the term packed: no new warning
    assert result.success and not shape.check(result.configuration).colliding  # coal, on the exact meshes


def test_contact_rows_cost_nothing_where_the_descent_stays_clear(rng):
    """The engine descends without the contact rows first (they are evaluated when the rest is met): where that
    descent ends clear of them (paper 000's four targets from its q_prev), the descent with a SelfCollision
    term is step for step that of the problem whose only contact rows can never be violated (an obstacle 50 m
    away: a problem with contact rows, as the engine's damping rule sees it; the same iterations and
    configuration, up to the last polishing step's rounding); where that answer is in contact (random targets
    from random starts: the dual youBot's arms are close), the engine goes on and ends with every row within
    tolerance. A trivial method — the answer without the term — is in contact there."""
    from framework.engine import LocalSettings, solve_local
    from framework.io.taskfile import load_task

    task = load_task(Path(fw.__file__).resolve().parents[1] / "tasks" / "youbot_dual_coordinated_ik.toml")
    robot = task.robot
    shape = fw.RobotShape(robot)
    settings = LocalSettings(tolerance=1e-9, restarts=False, regularize=False, max_iterations=200)
    far = fw.Obstacles(shape, [fw.Sphere([50.0, 50.0, 50.0], 0.05)], margin=0.005)
    starts = [(c.problem.previous, [t.target for _, t in c.problem.objective if t.is_task]) for c in task.cases]
    for _ in range(10):
        x = robot.random_configurations(rng, 2)
        starts.append((x[1], [robot.frame_placement(x[0], f).translation for f in ("arm1_ee", "arm2_ee")]))
    same = contact = 0
    for x0, (t1, t2) in starts:
        objective = fw.Position("arm1_ee", t1) + fw.Position("arm2_ee", t2)
        free = fw.Problem(robot, objective + far)
        whole = fw.Problem(robot, objective + fw.SelfCollision(shape, margin=0.005))
        a = solve_local(free.program, x0, 0, settings)
        b = solve_local(whole.program, x0, 0, settings)
        if not a.reached:
            continue
        rows = whole.program.task_errors(a.x)[2:]  # the collision term's rows at the free answer
        if np.all(rows <= 1e-9):
            np.testing.assert_allclose(b.x, a.x, rtol=0, atol=1e-9)  # the polish sees the (zero) contact rows
            assert b.iterations == a.iterations
            same += 1
        elif b.reached:
            assert np.all(whole.program.task_errors(b.x) <= 1e-9)
            contact += 1
    assert same >= 3 and contact >= 1


def test_a_loose_cover_keeps_the_answer_without_the_terms_when_coal_finds_it_clear(erd):
    """PR2's meshes are covered by spheres fatter than the links: where the problem without its collision
    terms has an answer coal finds clear (by the terms' margin), the hybrid returns that answer (the same
    configuration as solving that problem), a success whose exact check is the one it made; its collision
    term's sphere rows may overlap there, and the task error leaves them out."""
    robot = fw.load_robot(erd / "pr2_description" / "urdf" / "pr2.urdf",
                          joints=["torso_lift_joint"] + [f"{s}_{j}" for s in "lr" for j in
                                                         ("shoulder_pan_joint", "shoulder_lift_joint",
                                                          "upper_arm_roll_joint", "elbow_flex_joint")])
    shape = fw.RobotShape(robot, srdf=erd / "pr2_description" / "srdf" / "pr2.srdf")
    rng = np.random.default_rng(3)
    kept = 0
    for seed in range(20):
        x = robot.random_configurations(rng, 1)[0]
        if shape.check(x, distances=False).colliding:
            continue
        hands = [robot.frame_placement(x, f).translation for f in robot.end_effectors[:2]]
        objective = fw.Position(robot.end_effectors[0], hands[0]) + fw.Position(robot.end_effectors[1], hands[1]) \
            + 0.1 * fw.Motion("all", robot.middle)
        problem = fw.Problem(robot, objective + fw.SelfCollision(shape, margin=0.01))
        result = fw.solve(problem, seed=seed, tolerance=1e-9)
        if not result.settings["clear_first"]:
            continue
        free = fw.solve(problem.without_collision_terms, seed=seed, tolerance=1e-9)
        np.testing.assert_array_equal(result.configuration, free.configuration)
        assert result.success and not result.collisions.colliding
        assert shape.check(result.configuration).min_distance >= 0.01  # the margin, by coal's distances
        assert result.task_error == pytest.approx(free.task_error, abs=1e-15)
        kept += 1
    assert kept >= 3


def test_a_loose_cover_tries_other_drawn_starts_without_the_terms_before_the_sphere_rows(pr2_table):
    """A PR2 two-hand pose over a table (benchmarks/collisions.py's target 33, seed 33) whose first answers without
    the collision terms touch the table or the robot, and which the sphere rows' engine never meets (its spheres
    are fatter than the links: 1,700 restarts missed): another drawn start without the terms gives an answer coal
    finds clear. Success and clearance are checked here by Pinocchio FK and coal."""
    robot, shape, scene = pr2_table
    poses = {"l_gripper_tool_frame": [0.6341914987592463, -0.461850130079126, 1.2527543663617564,
                                      0.4948193036205476, 0.8674107038673525, -0.05246453641099369,
                                      -0.8443236955996358, 0.4941777036020543, 0.20713738028558132,
                                      0.20559998495488674, -0.05819852299624405, 0.9769040782531345],
             "r_gripper_tool_frame": [0.6638783666271535, 0.029684499404211744, 0.9052835716355594,
                                      0.9580969637586652, -0.15053467975516427, -0.24369964757347798,
                                      -0.2763496543388752, -0.7096311684613702, -0.648116095537624,
                                      -0.07537291677526758, 0.6883043766671548, -0.7214956746077056]}
    objective = 0.1 * fw.Motion("all", robot.middle)
    for frame, p in poses.items():
        objective = objective + fw.Pose(frame, (np.array(p[:3]), np.array(p[3:]).reshape(3, 3)))
    problem = fw.Problem(robot, objective + fw.SelfCollision(shape) + fw.Obstacles(shape, scene))
    result = fw.solve(problem, seed=33, tolerance=1e-6)
    assert result.success and result.settings["clear_first"]
    for frame, p in poses.items():
        M = robot.frame_placement(result.configuration, frame)
        assert np.linalg.norm(M.translation - p[:3]) <= 1e-6
    assert not shape.check(result.configuration, scene=scene, distances=False).colliding


def test_a_drawn_start_keeps_the_point_reaching_the_task_when_the_regularizers_pull_it_into_contact(pr2_table):
    """PR2's two grippers at the poses of a collision-free configuration with the left fingers beside the right
    forearm: the motion regularizer pulls every answer without the collision terms (the warm start's and those of
    drawn starts) to one place with the fingers in the forearm, and the sphere rows (fatter than the links) never
    fit there; the point that first reached the task from a drawn start is clear on some of them. The solve
    answers clear of contact (Pinocchio FK and coal check it here) instead of failing after its whole budget."""
    robot, shape, scene = pr2_table
    source = np.array([0.17721061665995014, 0.18655195718074313, -0.30313623782171073, 2.1723478647637684,
                       -1.0137374239803085, -0.16171354177002062, -0.5858484990566715, -0.21779402708558226,
                       0.05216780209242966, 0.030376558368432893, -2.3610944316588753, -0.20349193782955943,
                       0.4966309227130976, -0.09432849104394858, -2.755372271378169])
    assert not shape.check(source, scene=scene, distances=False).colliding
    frames = ("l_gripper_tool_frame", "r_gripper_tool_frame")
    poses = {frame: robot.frame_placement(source, frame) for frame in frames}
    objective = 0.1 * fw.Motion("all", robot.middle)
    for frame, M in poses.items():
        objective = objective + fw.Pose(frame, M)
    problem = fw.Problem(robot, objective + fw.SelfCollision(shape) + fw.Obstacles(shape, scene))
    free = problem.without_collision_terms
    rng = np.random.default_rng(0)
    for k in range(4):  # the premise: regularized answers without the terms are in contact, from any start
        answer = fw.solve(free, seed=k, initial=robot.random_configurations(rng, 1)[0], tolerance=1e-6)
        assert answer.success and shape.check(answer.configuration, scene=scene, distances=False).colliding
    for seed in range(3):
        result = fw.solve(problem, seed=seed, tolerance=1e-6)
        assert result.success and result.settings["clear_first"] and result.settings["restart_count"] > 0
        for frame, M in poses.items():
            reached = robot.frame_placement(result.configuration, frame)
            assert np.linalg.norm(reached.translation - M.translation) <= 1e-6
            assert np.linalg.norm(pin.log3(M.rotation.T @ reached.rotation)) <= 1e-6
        assert not shape.check(result.configuration, scene=scene, distances=False).colliding


def test_the_fast_check_with_a_margin_finds_the_pairs_closer_than_it(erd, rng):
    """``check(x, margin, distances=False)`` (coal's security margin) flags exactly the pairs whose distance
    (coal's distance computation on every pair) is below the margin, on PR2's meshes (tested on their convex hulls
    first) and the youBot's spheres."""
    pr2 = fw.load_robot(erd / "pr2_description" / "urdf" / "pr2.urdf",
                        joints=["torso_lift_joint", "l_shoulder_pan_joint", "l_elbow_flex_joint",
                                "r_shoulder_pan_joint", "r_elbow_flex_joint"])
    for robot in (pr2, fw.load_robot("youbot_dual_mobile")):
        shape = fw.RobotShape(robot)
        assert (shape._hull_model(shape.geometry) is not None) == (robot is pr2)  # the hulls' pass: meshes only
        for x in robot.random_configurations(rng, 15):
            for margin in (0.0, 0.02, 0.05):
                fast = shape.check(x, margin, distances=False)
                full = shape.check(x, margin)
                assert {(c.a, c.b) for c in fast.contacts} == {(c.a, c.b) for c in full.contacts}
    with pytest.raises(TaskError, match="margin"):
        shape.check(robot.middle, -0.01, distances=False)


def test_jacobians_of_the_frames_a_call_needs_equal_every_frames(rng):
    """The engine computes frame Jacobians only for the frames its rows read: after a poses-only call, the
    Jacobians from those poses (frames of clear contact rows skipped) and the descent without the contact rows
    (their frames skipped) give the same residuals and Jacobian rows as one call computing every frame's
    Jacobian — itself checked against finite differences in tests/test_costs.py. Dual youBot with SelfCollision,
    at random configurations (most of them in contact) and at configurations clear of contact."""
    from framework.costs.kernels import COMPUTE, JACOBIANS_FROM_POSES, NO, TASK, YES
    from framework.engine.tables import without_contacts
    from framework.io.taskfile import load_task
    from tests.compiled import linearize_in, make_workspaces, python_callable, rows_in, use_table

    task = load_task(Path(fw.__file__).resolve().parents[1] / "tasks" / "youbot_dual_coordinated_ik.toml")
    robot = task.robot
    problem = fw.Problem(robot, fw.Position("arm1_ee", [0.5, 0.2, 0.4]) + fw.Position("arm2_ee", [0.5, -0.2, 0.4])
                         + fw.SelfCollision(fw.RobotShape(robot), margin=0.005) + 0.1 * fw.Motion("all", np.zeros(13)))
    packed = problem.program.packed
    lazy, contacts = python_callable(without_contacts)(packed.blocks)
    assert contacts and lazy is not packed.blocks
    owners, records = make_workspaces(packed, robot.n, 3)
    WHOLE, SPLIT, PART = 0, 1, 2
    use_table(records, PART, lazy)
    active = clear = 0
    for x in robot.random_configurations(rng, 120):
        m = linearize_in(records, WHOLE, x, TASK, YES, COMPUTE)
        assert linearize_in(records, SPLIT, x, TASK, NO, COMPUTE) == m
        linearize_in(records, SPLIT, x, TASK, YES, JACOBIANS_FROM_POSES)
        (r_whole, J_whole, *_), (r_split, J_split, *_) = rows_in(records, WHOLE, m), rows_in(records, SPLIT, m)
        np.testing.assert_array_equal(r_split, r_whole)
        np.testing.assert_array_equal(J_split, J_whole)
        contact = np.any(r_whole[6:] != 0.0)
        active += contact
        clear += not contact
        k = linearize_in(records, PART, x, TASK, YES, COMPUTE)  # the position rows only
        assert k == 6
        np.testing.assert_array_equal(rows_in(records, PART, k)[1], J_whole[:k])
    assert active >= 10 and clear >= 3


def test_restoring_steps_see_the_rows_in_contact_as_the_kernel_stacks_them(rng):
    """The Newton phase's restoring steps leave out the contact rows clear where they start (no Jacobian there;
    their evaluation was most of a step's cost): the rows kept in place, moved up, are the residuals and Jacobian
    rows that the kernel stacks for the block table with the clear ones set aside — exactly the rows of the whole
    task that are not clear, in order. Dual youBot with SelfCollision at random configurations (most in contact,
    a trivial compaction — none set aside — would leave 40 zero rows in)."""
    from framework.costs.kernels import COMPUTE, TASK, YES
    from framework.costs.workspace import views
    from framework.engine.tables import set_aside_clear
    from framework.io.taskfile import load_task
    from tests.compiled import linearize_in, make_workspaces, rows_in, use_table

    @numba.njit
    def set_aside(records, i, near):
        v = views(records[i])
        return set_aside_clear(v.blocks, v.r, v.J, near)

    task = load_task(Path(fw.__file__).resolve().parents[1] / "tasks" / "youbot_dual_coordinated_ik.toml")
    robot = task.robot
    problem = fw.Problem(robot, fw.Position("arm1_ee", [0.5, 0.2, 0.4]) + fw.Position("arm2_ee", [0.5, -0.2, 0.4])
                         + fw.SelfCollision(fw.RobotShape(robot), margin=0.005) + 0.1 * fw.Motion("all", np.zeros(13)))
    packed = problem.program.packed
    owners, records = make_workspaces(packed, robot.n, 2)
    WHOLE, KEPT = 0, 1
    near = packed.blocks.copy()
    use_table(records, KEPT, near)
    compacted = 0
    for x in robot.random_configurations(rng, 60):
        m = linearize_in(records, WHOLE, x, TASK, YES, COMPUTE)
        r, J = rows_in(records, WHOLE, m)[:2]
        nonzero = (r != 0.0) | np.any(J != 0.0, axis=1)
        mn = set_aside(records, WHOLE, near)
        assert linearize_in(records, KEPT, x, TASK, YES, COMPUTE) == mn
        (r_whole, J_whole, *_), (r_kept, J_kept, *_) = rows_in(records, WHOLE, mn), rows_in(records, KEPT, mn)
        np.testing.assert_array_equal(r_whole, r_kept)
        np.testing.assert_array_equal(J_whole, J_kept)
        np.testing.assert_array_equal(r_whole[6:], r[6:][nonzero[6:]])  # one row per contact block
        assert mn == 6 + nonzero[6:].sum()
        compacted += mn < m
    assert compacted >= 50

def test_the_newton_phase_stops_on_an_obstacle_it_starts_clear_of(sphere_arm):
    """Motion towards a configuration whose forearm sphere is inside a sphere obstacle, from starts clear of it:
    the forearm's centre turns on a circle with θ1 + θ2, so the obstacle (kept ``margin`` away) allows
    θ1 + θ2 <= s_b = φ − 2 asin((R + ρ + margin) / 2L) on the starts' side, and the closest allowed configuration to
    the motion target q is q's projection on θ1 + θ2 = s_b (closed form). The Newton phase's steps towards q
    enter the obstacle's row, clear where they start. The motion target itself (the trivial answer) is in it.
    (The rows hold ``CLEARANCE`` beyond the margin: an answer on the boundary is clear by coal.)"""
    from framework.costs.sphere_rows import CLEARANCE

    robot, shape, exact = sphere_arm
    margin, phi, rho = 0.01, 1.5, 0.05
    obstacle = fw.Sphere([L * np.cos(phi), L * np.sin(phi), 0.0], rho)
    bound = phi - 2 * np.arcsin((R + rho + margin + CLEARANCE) / (2 * L))
    for q in ([0.7, 0.6], [0.2, 1.1], [1.0, 0.25]):
        q = np.array(q)
        assert shape.check(q, scene=fw.Scene([obstacle]), self_pairs=False).colliding
        expected = q + (bound - q.sum()) / 2
        problem = fw.Problem(robot, fw.Obstacles(shape, [obstacle], margin=margin, cover=exact) + fw.Motion("all", q))
        for start in ([0.3, 0.2], [0.1, 0.5], [0.6, -0.1]):
            result = fw.solve(problem, initial=np.array(start), tolerance=1e-9)
            assert result.success
            np.testing.assert_allclose(result.configuration, expected, atol=1e-7)


def test_within_leaves_the_contact_rows_to_the_exact_check_only_when_told(rng):
    """``Program.within`` against a direct reading of its rule: every task block within its tolerance (angular
    for orientations), the collision blocks skipped only when the exact check has the last word."""
    robot = fw.load_robot("youbot_dual")
    shape = fw.RobotShape(robot)
    program = fw.Problem(robot, fw.Pose("arm1_ee", np.eye(4)) + fw.SelfCollision(shape, margin=0.005)).program
    exact, angular = np.array(program.task_checked_exactly), np.array(program.task_angular)
    assert exact.sum() >= 30 and angular.sum() == 1 and (~exact).sum() == 2  # a position, a rotation, the pairs
    limits = np.where(angular, 1e-4, 1e-6)
    seen = set()
    for _ in range(300):
        errors = np.zeros(exact.size)
        hit = rng.choice(exact.size, size=rng.integers(0, 3), replace=False)
        errors[hit] = rng.choice([1e-7, 1e-5, 1e-3], size=hit.size)
        plain, checked = bool(np.all(errors <= limits)), bool(np.all((errors <= limits) | exact))
        assert program.within(errors.tolist(), 1e-6, 1e-4) == plain
        assert program.within(errors, 1e-6, 1e-4, exact_checked=True) == checked
        seen.add((plain, checked))
    assert seen == {(True, True), (False, True), (False, False)}


def test_widened_margins_read_the_gap_of_clear_rows_near_contact(rng):
    """``widen_margins``, which the Newton phase reads to linearize blocking contact rows at x: the collision
    blocks with their margins widened by b read, row for row, what a SelfCollision term built with margin m + b
    reads (dual youBot, 60 random configurations); a row clear at m but within b of it reads its gap − b, and its
    Jacobian is the gap's (central finite differences). A copy that left the margins as they are would read 0
    on those rows, with no Jacobian."""
    from framework.costs.kernels import residuals_at, widen_margins
    from framework.engine.local import residual_arrays
    from tests.compiled import python_callable

    widen_margins = python_callable(widen_margins)
    from framework.io.taskfile import load_task

    task = load_task(Path(fw.__file__).resolve().parents[1] / "tasks" / "youbot_dual_coordinated_ik.toml")
    robot = task.robot
    shape = fw.RobotShape(robot)
    margin, band = 0.005, 0.05
    narrow = fw.Problem(robot, fw.SelfCollision(shape, margin=margin)).program
    wide = fw.Problem(robot, fw.SelfCollision(shape, margin=margin + band)).program
    params = np.empty_like(narrow.packed.params)
    widen_margins(narrow.packed.blocks, narrow.packed.params, band, params)
    widened = narrow.packed._replace(params=params)
    (r, J), (rw, Jw), (re, Je) = residual_arrays(narrow), residual_arrays(narrow), residual_arrays(wide)
    near, h = 0, 1e-7
    for x in robot.random_configurations(rng, 60):
        m = residuals_at(x, -1, narrow.packed, r, J)
        assert residuals_at(x, -1, widened, rw, Jw) == m
        residuals_at(x, -1, wide.packed, re, Je)
        np.testing.assert_allclose(rw[:m], re[:m], atol=1e-15)
        np.testing.assert_allclose(Jw[:m], Je[:m], atol=1e-14)
        for a in np.flatnonzero((r[:m] == 0.0) & (rw[:m] < -1e-4)):  # clear at m, within the band
            near += 1
            assert 0.0 < rw[a] + band < band
            fd = np.empty(robot.n)
            for i in range(robot.n):
                e = np.zeros(robot.n)
                e[i] = h
                residuals_at(x + e, -1, widened, re, Je)
                plus = re[a]
                residuals_at(x - e, -1, widened, re, Je)
                fd[i] = (plus - re[a]) / (2 * h)
            residuals_at(x, -1, widened, rw, Jw)
            np.testing.assert_allclose(Jw[a], fd, atol=1e-6)
    assert near >= 10


def test_answers_held_on_a_contact_at_margin_zero_are_clear_by_the_exact_check():
    """With the default margin 0, an answer whose collision row is active sits on the contact: the rows hold
    ``CLEARANCE`` beyond it, so coal finds it clear (held exactly at 0 it read as touching: 2 of these 20 failed)."""
    from framework.costs.sphere_rows import CLEARANCE

    robot = fw.load_robot("youbot_dual_mobile")
    shape = fw.RobotShape(robot)
    X = [x for x in robot.random_configurations(np.random.default_rng(7), 400)
         if not shape.check(x, distances=False).colliding][:20]
    P1 = np.array([robot.frame_placement(x, "arm1_ee").translation for x in X])
    P2 = np.array([robot.frame_placement(x, "arm2_ee").translation for x in X])
    problem = fw.Problem(robot, fw.Position("arm1_ee", P1[0], name="h1") + fw.Position("arm2_ee", P2[0], name="h2")
                         + fw.SelfCollision(shape))
    batch = fw.solve_batch(problem, {"h1": P1, "h2": P2}, progress=False)
    assert batch.success.all()
    gaps = np.array([shape.check(x, distances=True).min_distance for x in batch.configurations])
    assert (gaps >= CLEARANCE - 1e-9).all()
    assert (gaps <= 2 * CLEARANCE).sum() >= 2  # answers held on a contact: the case this is about
