"""The engine's last steps on convex hulls: a target the sphere model cannot reach (a thin plate a few millimetres
above a table) reached without contact by coal's exact check; hull rows' Jacobians against finite differences of
coal's distances; success decided by the exact check, not by the sphere rows."""

from __future__ import annotations

import numba
import numpy as np
import pytest

import framework as fw
from framework.engine.hull_reach import BUFFER, HullRows

HALF = 0.01  # the plate's half thickness [m]
PLATE = f"""<robot name="plate">
  <link name="base"/>
  <link name="carriage"/>
  <link name="plate"><collision><geometry><box size="0.2 0.2 {2 * HALF}"/></geometry></collision></link>
  <joint name="lift" type="prismatic"><parent link="base"/><child link="carriage"/><axis xyz="0 0 1"/>
    <limit lower="-0.5" upper="0.5" effort="1" velocity="1"/></joint>
  <joint name="tilt" type="revolute"><parent link="carriage"/><child link="plate"/><axis xyz="1 0 0"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>"""
TABLE = fw.Box([0.0, 0.0, -0.05], [1.0, 1.0, 0.1], name="table")  # top at z = 0


@pytest.fixture(scope="module")
def plate():
    robot = fw.robot_from_urdf(PLATE)
    return robot, fw.RobotShape(robot)


def test_a_plate_just_above_a_table_is_reached_on_hulls(plate):
    """Target: the plate's centre 3 mm above its contact height, with a motion term pulling the plate to a 0.3 rad
    tilt (its edge 3 cm into the table: the answer without the collision term is in contact). Its sphere cover
    sticks out of the 2 cm plate by centimetres, so the sphere model keeps it higher (multistart_lm, which has no
    hull steps, misses); the hybrid reaches it on the plate's own box, coal finds no contact and the distance to
    the table is the closed form's (plate bottom at z − HALF cos θ − 0.1 |sin θ|, table top at 0)."""
    robot, shape = plate
    cover = shape.cover()
    assert cover.radii.max() > 0.03  # the reason the spheres cannot get there (a trivial check of the premise)
    target = np.array([0.0, 0.0, HALF + 0.003])
    objective = fw.Position("plate", target) + fw.Obstacles(shape, [TABLE]) + 0.1 * fw.Motion("all", [0.0, 0.3])
    problem = fw.Problem(robot, objective)
    free = fw.solve(problem.without_collision_terms, seed=0, tolerance=1e-6)
    assert free.success and shape.check(free.configuration, scene=fw.Scene((TABLE,)), distances=False).colliding
    spheres_only = fw.solve(problem, "multistart_lm", seed=0, tolerance=1e-6)
    assert not spheres_only.success
    assert np.linalg.norm(robot.frame_placement(spheres_only.configuration, "plate").translation - target) > 0.005
    result = fw.solve(problem, seed=0, tolerance=1e-6)
    assert result.success and not result.collisions.colliding
    assert result.settings["on_hulls"] and not result.settings["clear_first"]
    reached = robot.frame_placement(result.configuration, "plate")
    assert np.linalg.norm(reached.translation - target) <= 1e-6
    assert result.errors["obstacles"] > 0.005  # the sphere rows still overlap the table: they did not decide
    report = shape.check(result.configuration, scene=fw.Scene((TABLE,)), self_pairs=False)
    half_height = HALF * np.cos(result.configuration[1]) + 0.1 * abs(np.sin(result.configuration[1]))
    assert report.min_distance == pytest.approx(target[2] - half_height, abs=1e-6)
    assert report.min_distance >= BUFFER - 1e-9


def test_a_target_inside_the_table_is_no_success(plate):
    """The hull steps never trade contact for the task: a target 5 mm into the table is missed, and the
    configuration returned is clear."""
    robot, shape = plate
    problem = fw.Problem(robot, fw.Position("plate", [0.0, 0.0, HALF - 0.005]) + fw.Obstacles(shape, [TABLE]))
    result = fw.solve(problem, seed=0, tolerance=1e-6)
    assert not result.success and not result.collisions.colliding


def test_hull_rows_match_differences_of_coal_distances(rng):
    """Each active hull row's Jacobian against central differences of coal's distance of its pair (youBot arms
    against each other and a box), on configurations where the pair stays the same within ±h."""
    robot = fw.load_robot("youbot_dual")
    shape = fw.RobotShape(robot)
    box = fw.Box([0.3, 0.0, 0.35], [0.3, 0.6, 0.1])
    program = fw.Problem(robot, fw.SelfCollision(shape, margin=0.05) + fw.Obstacles(shape, [box], margin=0.05)).program
    rows = HullRows(program, program.hull_pairs)
    h, checked = 1e-6, 0
    for x in robot.random_configurations(rng, 40):
        _, _, R, t, near = rows._near(x)
        for k in near:
            value = rows._height(k, R, t)
            if value >= 0 or value < -0.04:  # deep overlaps: EPA's witness points jump between faces
                continue
            single = rows.subset([k])
            _, values, gradients = single.measure(x, robot.n)
            numeric = np.empty(robot.n)
            for i in range(robot.n):
                e = np.zeros(robot.n)
                e[i] = h
                numeric[i] = (single.measure(x + e, robot.n)[0] - single.measure(x - e, robot.n)[0]) / (2 * h)
            np.testing.assert_allclose(gradients[0], numeric, atol=1e-5)
            checked += 1
    assert checked >= 10


def test_hull_rows_measure_every_pair_within_reach(pr2_table, rng):
    """The pairs a hull row measures (those the exact check's broad phase and the rows' own bounding spheres keep)
    hold every pair whose hulls coal finds within its margin plus REACH (PR2's meshes with a table, random
    configurations), and leave most of the others out (each measured pair is a coal distance, ~7 µs)."""
    from framework.engine.hull_reach import REACH

    robot, shape, scene = pr2_table
    program = fw.Problem(robot, fw.SelfCollision(shape) + fw.Obstacles(shape, scene, margin=0.01)).program
    rows = HullRows(program, program.hull_pairs)
    within = kept = 0
    for x in robot.random_configurations(rng, 12):
        near = rows._near(x)[4]
        poses, _ = robot.frame_jacobians(x[None], rows.frames)  # every pair placed, to measure them all
        R, t = rows._placements(poses.positions[0], poses.rotations[0], np.arange(len(rows.pairs)))
        close = {k for k in range(len(rows.pairs)) if rows._height(k, R, t) + BUFFER < REACH}
        assert close <= set(near), sorted(close - set(near))
        within, kept = within + len(close), kept + len(near)
    assert within > 0 and kept < 0.1 * 12 * len(rows.pairs)  # 6 % (the rows' bounding spheres alone keep 18 %)


def test_hull_steps_only_where_the_spheres_are_looser(plate, erd):
    """Where the sphere model is exact (the youBot's sphere links, a sphere against its platform's box used whole)
    no pair is loose and the hull steps never run; PR2's meshes and the plate's box covered by spheres are."""
    youbot = fw.load_robot("youbot_dual_mobile")
    pairs = fw.SelfCollision(fw.RobotShape(youbot)).hull_pairs(youbot)
    assert len(pairs) > 100 and not any(p.loose for p in pairs)
    robot, shape = plate
    assert all(p.loose for p in fw.Obstacles(shape, [TABLE]).hull_pairs(robot))
    pr2 = fw.load_robot(erd / "pr2_description" / "urdf" / "pr2.urdf",
                        joints=["torso_lift_joint", "l_shoulder_pan_joint", "r_shoulder_pan_joint"])
    pr2_pairs = fw.SelfCollision(fw.RobotShape(pr2)).hull_pairs(pr2)
    assert pr2_pairs and all(p.loose for p in pr2_pairs)


def test_a_batch_reaches_the_plate_targets_as_single_solves_do(plate):
    """``solve_batch`` over plate targets just above the table: the items the compiled engine leaves short (the
    sphere rows) are solved as ``solve`` solves them (item ``i`` with seed ``i``: the problem without its
    collision term first, its answer kept when coal finds it clear), and count as successes by the exact check
    like the single solves: the same configurations."""
    robot, shape = plate
    targets = [[0.0, 0.0, HALF + h] for h in (0.002, 0.004, 0.006)]
    problem = fw.Problem(robot, fw.Position("plate", targets[0]) + fw.Obstacles(shape, [TABLE]))
    batch = fw.solve_batch(problem, targets, seed=0, tolerance=1e-6)
    assert batch.success.all()
    for i, target in enumerate(targets):
        single = fw.solve(fw.Problem(robot, fw.Position("plate", target) + fw.Obstacles(shape, [TABLE])), seed=i,
                          tolerance=1e-6)
        assert single.success and single.settings["clear_first"]
        np.testing.assert_array_equal(batch.configurations[i], single.configuration)
        reached = robot.frame_placement(batch.configurations[i], "plate").translation
        assert np.linalg.norm(reached - target) <= 1e-6


def test_restarts_tell_a_start_in_contact_by_its_hinge_rows(rng):
    """The engine redraws a restart that begins in contact (``CLEAR_DRAWS``): its test, no one-sided task row
    violated (stopping at the first one that is), agrees with the collision term's value (positive exactly when a
    pair is closer than the margin) over random youBot configurations, most of which are in contact; a draw ends
    at the first clear one, within the box."""
    from framework.costs.kernels import hinges_clear
    from tests.compiled import make_workspaces
    from framework.engine.draws import stream
    from framework.engine.local import LocalSettings, solve_local
    from framework.engine.reach import CLEAR_DRAWS

    robot = fw.load_robot("youbot_dual_mobile")
    problem = fw.Problem(robot, fw.Position("arm1_ee", [0.5, 0.0, 0.4]) + fw.SelfCollision(fw.RobotShape(robot)))
    program = problem.program
    X = robot.random_configurations(rng, 60)
    values = problem.values(X)[:, 1]
    owners, records = make_workspaces(program.packed, robot.n, 1)

    @numba.njit
    def clear_at(x, records):
        return hinges_clear(x, records[0])

    clear = [clear_at(x, records) for x in X]
    assert clear == [bool(v == 0) for v in values.tolist()]
    assert 0 < sum(clear) < len(clear)
    draws, drawn = stream(3), LocalSettings(max_iterations=0, restarts=False, regularize=False)
    for _ in range(20):  # a drawn start (x0 None), no iteration: the draw itself
        result = solve_local(program, None, draws, drawn)
        x, count = result.x, result.evaluations - 1
        assert 1 <= count <= CLEAR_DRAWS and np.all((robot.lower <= x) & (x <= robot.upper))
        assert problem.values(x[None])[0, 1] == 0 or count == CLEAR_DRAWS  # clear, or every draw in contact


def test_the_hull_steps_tables_are_built_once_per_program(plate):
    """The hull steps' tables (the other task terms' program, every hull pair's rows) are kept by the program: a
    second run of the steps reads the same ones and answers the same (each run keeps its own pairs: the first
    one's dropped pairs do not carry over)."""
    from framework.engine.hull_reach import _hull_setup, hull_reach

    robot, shape = plate
    objective = fw.Position("plate", [0.0, 0.0, HALF + 0.003]) + fw.Obstacles(shape, [TABLE]) \
        + 0.1 * fw.Motion("all", [0.0, 0.3])
    program = fw.Problem(robot, objective).program
    start = np.array([0.1, 0.3])
    first = hull_reach(program, start)
    kept = program.memo(_hull_setup)
    again = hull_reach(program, start)
    assert program.memo(_hull_setup) is kept and first.reached
    np.testing.assert_array_equal(first.x, again.x)
    assert len(kept[1].pairs) == len(program.hull_pairs)
    assert not kept[1]._unmapped.any()  # every hull pair is one of the exact check's broad phase (measured by it)
