"""solve_batch: every item as `solve` solves it (bit for bit without a time budget), checked by Pinocchio FK."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import framework as fw
from framework.errors import SolverError, TaskError


def _poses(robot: fw.Robot, frame: str, count: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """FK-sampled reachable poses ``(count, 4, 4)`` and the configurations they come from."""
    rng = np.random.default_rng(seed)
    Q = robot.lower + (robot.upper - robot.lower) * rng.random((count, robot.n))
    return np.array([robot.frame_placement(q, frame).homogeneous for q in Q]), Q


@pytest.fixture(scope="module")
def puma():
    robot = fw.load_robot("puma560")
    T, _ = _poses(robot, "ee", 80, 7)
    return robot, T


@pytest.mark.parametrize("solver", ["hybrid", "multistart_lm"])
def test_batch_items_equal_one_by_one_solves(puma, solver):
    robot, T = puma
    problem = fw.Problem(robot, fw.Pose("ee", T[0]))
    batch = fw.solve_batch(problem, T, solver, seed=11, tolerance=1e-7)
    assert batch.compiled.mean() > 0.9  # most items in the compiled loop (else this test checks nothing new)
    for i in range(len(T)):
        one = fw.solve(fw.Problem(robot, fw.Pose("ee", T[i])), solver, seed=11 + i, tolerance=1e-7,
                       options={"closed_form": False})  # the batch's engine alone: the same descent
        np.testing.assert_array_equal(batch.configurations[i], one.configuration)
        assert batch.success[i] == one.success
        assert batch.costs[i] == pytest.approx(one.cost, abs=1e-15)
        assert batch.errors[i].tolist() == [one.errors[name] for name in batch.error_names]
    assert batch.success.all()  # FK-sampled poses are reachable: a trivial method (the start) reaches none


def test_successes_hold_by_pinocchio_fk(puma):
    robot, T = puma
    batch = fw.solve_batch(fw.Problem(robot, fw.Pose("ee", T[0])), T, tolerance=1e-9)
    model = robot.model
    data = model.createData()
    frame = model.getFrameId("ee")
    for x, target, ok in zip(batch.configurations, T, batch.success):
        pin.framesForwardKinematics(model, data, robot.to_pinocchio(x[None])[0])
        M = data.oMf[frame]
        position = np.linalg.norm(M.translation - target[:3, 3])
        angle = np.linalg.norm(pin.log3(target[:3, :3].T @ M.rotation))
        assert ok == (position <= 1e-9 and angle <= 1e-9)
    assert batch.success_rate == 1.0


def test_two_terms_regularized_and_targets_restored():
    """Two hands moved per item ({term: targets}), motion minimized on the task: as solve, and the problem's own
    targets are where they were afterwards."""
    robot = fw.load_robot("youbot_dual_mobile")
    rng = np.random.default_rng(3)
    Q = robot.lower + (robot.upper - robot.lower) * rng.random((12, robot.n))
    P1 = np.array([robot.frame_placement(q, "arm1_ee").translation for q in Q])
    P2 = np.array([robot.frame_placement(q, "arm2_ee").translation for q in Q])
    hand1, hand2 = fw.Position("arm1_ee", [0.3, 0.0, 0.4]), fw.Position("arm2_ee", [0.3, 0.2, 0.4])
    problem = fw.Problem(robot, hand1 + hand2 + 0.1 * fw.Motion("base", robot.middle) + 0.4 * fw.Motion(
        "arm1", robot.middle) + 0.4 * fw.Motion("arm2", robot.middle))
    batch = fw.solve_batch(problem, {hand1.name: P1, hand2.name: P2}, seed=5, tolerance=1e-8)
    assert hand1.target.tolist() == [0.3, 0.0, 0.4] and hand2.target.tolist() == [0.3, 0.2, 0.4]
    for i in range(len(Q)):
        one = fw.solve(fw.Problem(robot, fw.Position("arm1_ee", P1[i]) + fw.Position("arm2_ee", P2[i])
                                  + 0.1 * fw.Motion("base", robot.middle) + 0.4 * fw.Motion("arm1", robot.middle)
                                  + 0.4 * fw.Motion("arm2", robot.middle)), seed=5 + i, tolerance=1e-8)
        np.testing.assert_array_equal(batch.configurations[i], one.configuration)
        assert batch.costs[i] == pytest.approx(one.cost, rel=1e-12, abs=1e-15)
    assert batch.success.all()
    after = fw.solve(problem, seed=0, tolerance=1e-8)  # the problem solves its own targets again
    assert np.linalg.norm(robot.frame_placement(after.configuration, "arm1_ee").translation - [0.3, 0, 0.4]) < 1e-8


def test_warm_starts_threads_and_other_solvers(puma):
    robot, T = puma
    problem = fw.Problem(robot, fw.Pose("ee", T[0]))
    _, Q = _poses(robot, "ee", 20, 7)
    near = Q + 0.05  # a warm start near each pose's own configuration
    one_thread = fw.solve_batch(problem, T[:20], initial=near, seed=3, workers=1)
    two = fw.solve_batch(problem, T[:20], initial=near, seed=3, workers=2)
    np.testing.assert_array_equal(one_thread.configurations, two.configurations)
    first = fw.solve(fw.Problem(robot, fw.Pose("ee", T[0])), seed=3, initial=near[0], options={"closed_form": False})
    np.testing.assert_array_equal(one_thread.configurations[0], first.configuration)
    # a metaheuristic has no compiled batch plan: item by item through solve, same answers
    de = fw.solve_batch(problem, T[:3], "de", seed=2, max_iterations=20)
    assert not de.compiled.any()
    for i in range(3):
        one = fw.solve(fw.Problem(robot, fw.Pose("ee", T[i])), "de", seed=2 + i, max_iterations=20)
        np.testing.assert_array_equal(de.configurations[i], one.configuration)


def test_bad_batches_are_named_errors(puma):
    robot, T = puma
    problem = fw.Problem(robot, fw.Pose("ee", T[0]))
    bad = T[:3].copy()
    bad[1, :3, :3] *= 2.0
    with pytest.raises(TaskError, match="item 1 is not a homogeneous transform"):
        fw.solve_batch(problem, bad)
    with pytest.raises(TaskError, match="shape"):
        fw.solve_batch(fw.Problem(robot, fw.Position("ee", [0.3, 0, 0.3])), np.zeros((4, 2)))
    with pytest.raises(TaskError, match="item 2 holds NaN"):
        fw.solve_batch(fw.Problem(robot, fw.Position("ee", [0.3, 0, 0.3])), [[0, 0, 0]] * 2 + [[np.nan, 0, 0]])
    with pytest.raises(TaskError, match="does not have"):
        fw.solve_batch(problem, {"nope": T[:2]})
    with pytest.raises(SolverError, match="one per item"):
        fw.solve_batch(problem, T[:3], seed=[1, 2])
    with pytest.raises(SolverError, match="2 configurations for 3 targets"):
        fw.solve_batch(problem, T[:3], initial=np.tile(robot.middle, (2, 1)))
    two = fw.Problem(robot, fw.Position("ee", [0.3, 0, 0.3]) + fw.Orientation("ee", [0, 0, 0, 1], quaternion="xyzw"))
    with pytest.raises(TaskError, match="2 task terms with a target"):
        fw.solve_batch(two, T[:2])
    with pytest.raises(TaskError, match="one target per item"):
        fw.solve_batch(two, {two.names[0]: T[:2, :3, 3], two.names[1]: T[:3, :3, :3]})


def test_misses_are_the_engines_best_miss_as_in_solve():
    """Unreachable and hard targets under a small budget: multistart_lm keeps the engine's best miss over its
    restart rounds — the batch keeps the same one, in the compiled loop (no item handed to solve)."""
    arm = fw.load_robot("youbot_arm")
    rng = np.random.default_rng(8)
    points = rng.uniform([-0.8, -0.8, -0.3], [0.8, 0.8, 0.8], (40, 3))  # many out of reach
    problem = fw.Problem(arm, fw.Position("ee", points[0]))
    batch = fw.solve_batch(problem, points, "multistart_lm", seed=4, tolerance=1e-6, max_iterations=120)
    assert batch.compiled.all() and 0 < batch.success.sum() < len(points)
    for i, p in enumerate(points):
        one = fw.solve(fw.Problem(arm, fw.Position("ee", p)), "multistart_lm", seed=4 + i, tolerance=1e-6,
                       max_iterations=120)
        np.testing.assert_array_equal(batch.configurations[i], one.configuration)
        assert batch.iterations[i] == one.iterations


def test_batched_target_parameters_are_those_of_one_target_at_a_time(puma):
    # the vectorized readers (Position, Orientation, Pose) against the term moved to each target in turn
    rng = np.random.default_rng(4)
    R = np.array([pin.exp3(rng.normal(size=3)) for _ in range(5)])
    p = rng.normal(size=(5, 3))
    T = np.tile(np.eye(4), (5, 1, 1))
    T[:, :3, :3], T[:, :3, 3] = R, p
    for term, targets in ((fw.Position("ee", p[0]), p), (fw.Orientation("ee", R[0]), R), (fw.Pose("ee", T[0]), T)):
        batch = term.target_parameters(puma, targets)
        for k in range(5):
            term.set_target(targets[k])
            np.testing.assert_array_equal(batch[k], term.parameters(puma))
    skewed = R.copy()
    skewed[3] *= 1.01  # RᵀR ≠ I
    with pytest.raises(TaskError, match="item 3 is not a rotation"):
        fw.Orientation("ee", R[0]).target_parameters(puma, skewed)
    mirrored = R.copy()
    mirrored[1] = -mirrored[1]  # det < 0
    with pytest.raises(TaskError, match="item 1 is not a rotation"):
        fw.Orientation("ee", R[0]).target_parameters(puma, mirrored)


def test_a_batch_with_a_loose_collision_cover_is_solved_as_solve_solves_each_item(erd):
    # the hybrid solves such a problem first without its collision terms (kept when coal finds that answer
    # clear): a batch must not answer with the sphere rows' engine instead (a different point where the spheres,
    # fatter than the links, touch; the batch plan that did gave other configurations on 10 of these 12 items)
    from framework.solvers import ik_solver

    robot = fw.load_robot(erd / "panda_description" / "urdf" / "panda.urdf",
                          joints=[f"panda_joint{i}" for i in range(1, 8)], end_effectors=["panda_hand"])
    shape = fw.RobotShape(robot, srdf=erd / "panda_description" / "srdf" / "panda.srdf")
    X = robot.random_configurations(np.random.default_rng(0), 12)
    targets = np.array([robot.frame_placement(x, "panda_hand").translation for x in X])
    problem = fw.Problem(robot, fw.Position("panda_hand", targets[0]) + 0.1 * fw.Motion("all", robot.middle)
                         + fw.SelfCollision(shape, margin=0.01))
    assert problem.program.loose_hulls and ik_solver("hybrid").clears_first(problem)
    batch = fw.solve_batch(problem, targets, seed=0, progress=False)
    assert batch.compiled.sum() >= 6  # most answers: the compiled phase without the terms, clear by coal
    term = problem.objective.terms[0][1]
    for i, target in enumerate(targets):
        term.set_target(target)
        one = fw.solve(problem, seed=i)
        np.testing.assert_array_equal(batch.configurations[i], one.configuration)
        assert batch.success[i] == one.success
        np.testing.assert_allclose(batch.errors[i], [one.errors[name] for name in batch.error_names], atol=1e-15)
        assert batch.costs[i] == pytest.approx(one.cost, abs=1e-12) and batch.iterations[i] == one.iterations


def test_items_the_warm_basin_misses_go_on_from_a_drawn_start_as_solve_does():
    """The hybrid's next step after the warm start's basin (a drawn start, the item's stream going on) runs in the
    compiled batch too: every item equals its one-by-one solve, including those answered from a drawn start."""
    from framework.solvers import ik_solver

    robot = fw.load_robot("youbot_dual_mobile")
    shape = fw.RobotShape(robot)
    rng = np.random.default_rng(5)
    X = [x for x in robot.random_configurations(rng, 200) if not shape.check(x, distances=False).colliding][:16]
    T1 = np.array([robot.frame_placement(x, "arm1_ee").translation for x in X])
    T2 = np.array([robot.frame_placement(x, "arm2_ee").translation for x in X])
    problem = fw.Problem(robot, fw.Position("arm1_ee", T1[0], name="a") + fw.Position("arm2_ee", T2[0], name="b")
                         + 0.1 * fw.Motion("all", robot.middle) + fw.SelfCollision(shape, margin=0.005))
    assert not ik_solver("hybrid").clears_first(problem)
    batch = fw.solve_batch(problem, {"a": T1, "b": T2}, seed=0, progress=False)
    drawn = 0
    for i in range(len(X)):
        problem.objective.terms[0][1].set_target(T1[i])
        problem.objective.terms[1][1].set_target(T2[i])
        one = fw.solve(problem, seed=i)
        np.testing.assert_array_equal(batch.configurations[i], one.configuration)
        assert batch.success[i] == one.success and batch.iterations[i] == one.iterations
        drawn += bool(batch.compiled[i] and one.settings["restart_count"] > 0)
    assert drawn >= 2  # answered in the compiled batch from a drawn start (the check is not vacuous)
