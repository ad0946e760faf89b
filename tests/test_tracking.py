"""Trajectory tracking: accuracy along a path, warm start, coordination, smoothness, Ctrl-C, bad input."""

from __future__ import annotations

import numpy as np

from framework.solvers.settings import DEFAULTS
import pytest

import framework as fw
from framework.tracking import paths
from framework.tracking import trajectory as tr
from framework.costs import Motion, Position
from framework.costs.problem import Problem
from framework.io.taskfile import load_task, resolve_task
from framework.tracking import TrackingTask, joint_steps, predictor, track

Q_PREV = load_task(resolve_task("paper000_circular")).cases[0].initial  # paper 000's q_prev (its task file)
PAPER000 = {
    "frame": "arm1_ee",
    "follower": "arm2_ee",
    "offset": (0.0, -0.3, 0.0),
    "position_weight": 1.2,
    "motion": {"base": 0.1, "arm1": 0.4, "arm2": 0.4},
}


@pytest.fixture(scope="module")
def mobile_dual() -> fw.Robot:
    return fw.load_robot("youbot_dual_mobile")


@pytest.fixture(scope="module")
def arm() -> fw.Robot:
    return fw.load_robot("youbot_arm")


def test_tracked_circle_matches_the_path(arm):
    circle = paths.circle((0.3, 0.0, 0.3), 0.03, 25)
    result = track(arm, circle, TrackingTask(motion=0.01), solver="hybrid", progress=False)
    assert result.completed and result.stop_reason == "completed" and len(result) == 25
    achieved = result.frame_positions(arm, "ee")[:, 0]
    np.testing.assert_allclose(
        achieved, circle.positions, atol=1e-9
    )  # FK of Q, independent of the solver's report
    np.testing.assert_allclose(
        result.position_error, np.linalg.norm(achieved - circle.positions, axis=1), atol=1e-12
    )
    assert result.all_success and result.orientation_error.max() == 0.0
    smooth = result.smoothness(arm)
    assert smooth.max_step["all"] < 0.1  # consecutive waypoints 7.8 mm apart: small joint steps, no jump


def test_paper000_coordinated_tracking_keeps_the_relative_offset(mobile_dual):
    path = paths.paper000("circular", 200)[:15]
    result = track(
        mobile_dual, path, TrackingTask(**PAPER000), solver="hybrid", initial=Q_PREV, progress=False
    )
    P = result.frame_positions(mobile_dual, ("arm1_ee", "arm2_ee"))
    np.testing.assert_allclose(P[:, 0], path.positions, atol=1e-9)
    np.testing.assert_allclose(P[:, 1] - P[:, 0], np.tile([0.0, -0.3, 0.0], (15, 1)), atol=1e-9)
    assert set(result.terms) == {"position", "follower", "motion[base]", "motion[arm1]", "motion[arm2]"}
    np.testing.assert_allclose(result.position_error, result.terms["position"] + result.terms["follower"])
    np.testing.assert_allclose(
        result.motion_error, sum(result.terms[f"motion[{g}]"] for g in ("base", "arm1", "arm2"))
    )
    # each solution is the q_prev of the next: the motion term measures the step from the previous point
    step = np.linalg.norm(result.configurations[5, 3:8] - result.configurations[4, 3:8])
    assert result.terms["motion[arm1]"][5] == pytest.approx(step, rel=1e-9)


def test_relative_coordination_holds_the_follower_at_the_offset(mobile_dual):
    path = paths.paper000("rose", 200)[:8]
    task = TrackingTask(**{**PAPER000, "coordination": "relative"})
    result = track(mobile_dual, path, task, solver="hybrid", initial=Q_PREV, progress=False)
    P = result.frame_positions(mobile_dual, ("arm1_ee", "arm2_ee"))
    np.testing.assert_allclose(P[:, 1] - P[:, 0], np.tile([0.0, -0.3, 0.0], (8, 1)), atol=1e-9)


def test_cmaes_continues_the_previous_waypoints_distribution(mobile_dual):
    """Paper 000 (its weighted sum) with cmaes_fast, 300 iterations per point: starting each point from the Jacobian prediction with the
    previous point's adapted covariance and a small step is far more accurate than a fresh identity covariance."""
    path = paths.paper000("sinusoidal", 200)[:6]
    runs = {
        name: track(mobile_dual, path, TrackingTask(**PAPER000), solver="cmaes_fast", initial=Q_PREV, seed=0,
                    max_iterations=300, tolerance=1e-4,
                    options=options, priorities=False, progress=False)
        for name, options in (("continued", None), ("fresh", {"covariance": None}))
    }
    continued, fresh = (runs[n].position_error[1:].mean() for n in ("continued", "fresh"))
    assert continued < 1e-9 and continued < 0.1 * fresh
    # the first point (from the paper's q_prev, off the path) searches along the task's null space first: several
    # times more accurate there too (seeds 0-2: 0.07x, 0.001x, 0.02x of the fresh covariance's error; the same
    # covariance would give 1x). Its absolute error depends on the CPU's floating point (1.5e-8 on one machine,
    # below 1e-8 on another), so the ratio is what is held.
    assert runs["continued"].position_error[0] < 0.2 * runs["fresh"].position_error[0]


def test_task_covariance_is_wide_along_the_null_space_and_narrow_across_the_task(mobile_dual):
    from framework.engine import residuals
    from framework.tracking import task_covariance

    problem = Problem(mobile_dual, TrackingTask(**PAPER000).objective(mobile_dual, 0, [0.5, -0.25, 0.4], None, Q_PREV))
    x = predictor(problem, Q_PREV)
    C = task_covariance(problem, x, ratio=1e-4)
    _, J = residuals(problem.program, x)
    _, s, Vt = np.linalg.svd(J)
    rank = int(np.sum(s > 1e-10 * s[0]))
    row, null = Vt[:rank], Vt[rank:]
    np.testing.assert_allclose(np.diag(null @ C @ null.T), 1.0, atol=1e-9)
    np.testing.assert_allclose(np.diag(row @ C @ row.T), 1e-4, atol=1e-9)
    assert task_covariance(problem, Q_PREV) is None  # not on the task: no such covariance


def test_warm_start_cuts_evaluations(arm):
    circle = paths.circle((0.3, 0.0, 0.3), 0.03, 8)
    runs = {
        warm: track(
            arm,
            circle,
            TrackingTask(motion=0.01),
            solver="cmaes_fast",
            max_iterations=300,
            tolerance=1e-6,
            stop_at_tolerance=True,
            warm_start=warm,
            seed=3,
            progress=False,
        )
        for warm in (True, False)
    }
    assert runs[True].all_success and runs[False].all_success
    # after the first point (solved from the same start), warm-started solves need fewer evaluations: CMA-ES
    # still adapts its covariance from scratch (~25 % saved); the hybrid's engine starts next to the solution
    # (a cold start is the middle of the box: 12 evaluations per point here, 8-11 warm)
    warm, cold = (runs[w].evaluations[1:].sum() for w in (True, False))
    assert warm < 0.75 * cold
    hybrid = {
        w: track(arm, circle, TrackingTask(motion=0.01), solver="hybrid", warm_start=w, progress=False)
        for w in (True, False)
    }
    assert hybrid[True].position_error.max() < 1e-9 and hybrid[False].position_error.max() < 1e-9
    assert hybrid[True].evaluations[1:].sum() < 0.9 * hybrid[False].evaluations[1:].sum()


def test_orientation_tracking_with_paper002_weights():
    puma = fw.load_robot("puma560")
    path = paths.paper002("puma560", "circle", 6)
    task = TrackingTask(position_weight=0.7143, orientation_weight=0.1786, motion=0.1071, motion_norm="l1")
    result = track(puma, path, task, solver="hybrid", seed=1, progress=False)
    assert result.position_error.max() < 1e-9 and result.orientation_error.max() < 1e-9
    assert "orientation" in result.terms and "motion[all]" in result.terms


def test_builder_callable_and_callback_stop(arm):
    calls = []

    def builder(k, position, rotation, previous):
        calls.append(k)
        return Position("ee", position) + 0.01 * Motion("all", previous)

    path = paths.line((0.3, -0.02, 0.3), (0.3, 0.02, 0.3), 10)
    result = track(arm, path, builder, solver="hybrid", progress=False, callback=lambda k, r: k == 3)
    assert len(result) == 4 and result.stop_reason == "callback" and not result.completed
    assert calls == [0, 1, 2, 3]


def test_ctrl_c_keeps_the_points_done(arm):
    def interrupt(k, result):
        if k == 2:
            raise KeyboardInterrupt

    path = paths.line((0.3, -0.02, 0.3), (0.3, 0.02, 0.3), 10)
    result = track(arm, path, solver="hybrid", progress=False, callback=interrupt)
    assert result.stop_reason == "interrupted" and len(result) == 3
    assert result.configurations.shape == (3, arm.n) and result.position_error.shape == (3,)


def test_runs_are_reproducible(arm):
    path = paths.line((0.3, -0.02, 0.3), (0.3, 0.02, 0.3), 4)
    a, b = (track(arm, path, solver="de", max_iterations=20, seed=7, progress=False) for _ in range(2))
    np.testing.assert_array_equal(a.configurations, b.configurations)


def test_predictor_lands_on_the_task(arm):
    x = np.array([0.1, 0.4, -0.8, 0.5, 0.0])
    p = arm.frame_placement(x, "ee").translation
    problem = Problem(arm, Position("ee", p + [0.0, 0.005, -0.004]) + 0.1 * Motion("all", x))
    y = predictor(problem, x)
    assert (
        np.linalg.norm(arm.frame_placement(y, "ee").translation - problem.objective.terms[0][1].target)
        < 1e-12
    )
    assert np.abs(y - x).max() < 0.1


def test_joint_steps_per_group(mobile_dual):
    Q = np.zeros((4, 13))
    Q[:, 0] = [0.0, 0.01, 0.03, 0.03]  # base x [m]
    Q[:, 3] = [0.0, 0.0, 0.5, 0.5]  # arm1 jumps 0.5 rad at point 2
    smooth = joint_steps(mobile_dual, Q, initial=Q[0] - 0.2)
    assert smooth.max_step["arm1"] == pytest.approx(0.5) and smooth.worst_point["arm1"] == 2
    np.testing.assert_allclose(smooth.steps["base"], [0.01, 0.02, 0.0])
    assert smooth.mean_step["base"] == pytest.approx(0.01)
    assert smooth.max_step["arm2"] == 0.0 and smooth.approach["all"] == pytest.approx(0.2)


WHEEL = """<robot name="wheel"><link name="base"/><link name="rim"/><link name="tip"/>
<joint name="spin" type="continuous"><parent link="base"/><child link="rim"/><axis xyz="0 0 1"/></joint>
<joint name="fix" type="fixed"><parent link="rim"/><child link="tip"/><origin xyz="0.1 0 0"/></joint></robot>"""


def test_joint_steps_wrap_continuous_angles():
    wheel = fw.robot_from_urdf(WHEEL, end_effectors=["tip"])
    smooth = joint_steps(wheel, np.array([[3.1], [-3.1], [-3.0]]))
    np.testing.assert_allclose(smooth.steps["all"], [2 * np.pi - 6.2, 0.1], atol=1e-12)


def test_bad_input(arm, mobile_dual):
    path = paths.line((0.3, 0.0, 0.3), (0.3, 0.01, 0.3), 3)
    with pytest.raises(fw.ConfigurationError):
        track(arm, path, initial=np.zeros(4), progress=False)
    with pytest.raises(fw.ConfigurationError):
        track(arm, path, initial=np.full(5, np.nan), progress=False)
    with pytest.raises(fw.TaskError, match="follower"):
        TrackingTask(follower="arm2_ee")
    with pytest.raises(fw.TaskError, match="t_r"):
        TrackingTask(follower="arm2_ee", offset=(0.0, np.nan, 0.0))
    with pytest.raises(fw.TaskError, match="weight"):
        TrackingTask(position_weight=-1.0)
    with pytest.raises(fw.TaskError, match="coordination"):
        TrackingTask(follower="arm2_ee", offset=(0, 0, 0), coordination="mirror")
    with pytest.raises(fw.UnknownFrameError):
        track(arm, path, TrackingTask(frame="hand"), progress=False)
    with pytest.raises(fw.UnknownJointError):
        track(arm, path, TrackingTask(motion={"legs": 1.0}), progress=False)
    with pytest.raises(fw.TaskError, match="Trajectory"):
        track(arm, np.zeros((3, 3)), progress=False)
    with pytest.raises(fw.SolverError, match="max_iterations"):
        track(arm, path, max_iterations=0, progress=False)
    with pytest.raises(fw.SolverError):
        track(arm, path, solver="gradient_descent", progress=False)


def _one_solve_per_waypoint(robot, path, spec, solver, initial, seed=0, tolerance=DEFAULTS.tolerance, after=None):
    """The tracking loop's definition, written out: one ``solve`` per waypoint from the previous solution, the
    targets and motion references moved in place, one generator through every solve."""
    from framework.solvers.solve import solve
    from framework.tracking import FIRST_GLOBAL_ITERATIONS

    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    previous, results = np.array(initial, dtype=float), []
    problem = Problem(robot, spec.objective(robot, 0, path.positions[0], path.rotation(0), previous))
    for k in range(path.K):
        spec.update(problem.objective, path.positions[k], path.rotation(k), previous)
        first = k == 0 and solver == "hybrid"
        options = {"global_iterations": FIRST_GLOBAL_ITERATIONS} if first else {}
        if solver in ("hybrid", "multistart_lm"):  # track's descents from the previous solution, not a closed form
            options["closed_form"] = False
        results.append(solve(problem, solver, seed=rng, max_iterations=DEFAULTS.max_iterations, tolerance=tolerance,
                             initial=previous[None], options=options or None))
        previous = results[-1].configuration
        if after is not None:  # what a callback does after waypoint k
            after(k, results[-1])
    return results


@pytest.mark.parametrize("solver", ["hybrid", "multistart_lm"])
def test_chained_waypoints_are_what_one_solve_per_waypoint_gives(arm, solver, monkeypatch):
    # waypoints 4-5 are 2 m out of the arm's reach: the engine misses them, the solver itself takes them (the
    # hybrid's global phase draws from the generator), and the compiled stretches go on after them
    from framework.tracking import chain

    chained = []
    follow = chain.follow_items
    monkeypatch.setattr(chain, "follow_items", lambda *a: chained.append(follow(*a)) or chained[-1])
    positions = paths.circle((0.3, 0.0, 0.3), 0.03, 14).positions.copy()
    positions[4:6] += (2.0, 0.0, 0.0)
    path = tr.Trajectory(positions, name="with a gap")
    spec = TrackingTask(motion=0.01)
    seen = []
    result = track(arm, path, spec, solver=solver, progress=False, callback=lambda k, r: seen.append(r))
    reference = _one_solve_per_waypoint(arm, path, spec, solver, arm.middle)
    assert sum(chained) >= 9 and len(chained) >= 2  # waypoints 1-3 and 6-13 ran chained
    np.testing.assert_array_equal(result.configurations, [r.configuration for r in reference])
    np.testing.assert_array_equal(result.iterations, [r.iterations for r in reference])
    np.testing.assert_array_equal(result.cost, [r.cost for r in reference])
    np.testing.assert_array_equal(result.success, [r.success for r in reference])
    assert not result.success[4:6].any() and result.success[6:].all()
    assert [r.settings for r in seen] == [r.settings for r in reference]
    assert [r.terms for r in seen] == [r.terms for r in reference]
    # the answers meet the path by Pinocchio's FK, not only by the engine's report
    reached = result.success
    np.testing.assert_allclose(result.frame_positions(arm, "ee")[reached, 0], positions[reached], atol=1e-4)


def test_chained_orientation_path_and_a_callback_stop_inside_a_stretch():
    puma = fw.load_robot("puma560")
    path = paths.paper002("puma560", "circle", 12)
    spec = TrackingTask(position_weight=0.7143, orientation_weight=0.1786, motion=0.1071, motion_norm="l1")
    ours, theirs = np.random.default_rng(3), np.random.default_rng(3)
    result = track(puma, path, spec, solver="hybrid", seed=ours, progress=False, callback=lambda k, r: k == 7)
    assert result.stop_reason == "callback" and len(result) == 8
    reference = _one_solve_per_waypoint(puma, path[:8], spec, "hybrid", puma.middle, seed=theirs)
    np.testing.assert_array_equal(result.configurations, [r.configuration for r in reference])
    assert ours.bit_generator.state == theirs.bit_generator.state  # drawn as 8 solves draw, no more
    assert result.position_error.max() < 1e-9 and result.orientation_error.max() < 1e-9


@pytest.mark.parametrize("table", [False, True])
def test_tracking_with_collision_terms_gives_what_one_solve_per_waypoint_gives(mobile_dual, monkeypatch, table):
    # collision terms as TrackingTask's extra terms. SelfCollision (an exact sphere cover): chained, each waypoint
    # checked by coal as solve checks it. With the table of tasks/paper000_circular_table.toml (Obstacles: a loose
    # cover, the hybrid solves each waypoint without the terms first): one solve per waypoint. Either way the
    # answers and successes of one solve per waypoint, every point clear by coal.
    from framework.tracking import chain

    chained = []
    follow = chain.follow_items
    monkeypatch.setattr(chain, "follow_items", lambda *a: chained.append(follow(*a)) or chained[-1])
    scene = load_task(resolve_task("paper000_circular_table")).scene
    shape = fw.RobotShape(mobile_dual)
    extra = fw.SelfCollision(shape) + fw.Obstacles(shape, scene, margin=0.01) if table else fw.SelfCollision(shape)
    path = paths.paper000("circular", 200)[:12]
    spec = TrackingTask(**PAPER000, extra=extra)
    result = track(mobile_dual, path, spec, solver="hybrid", initial=Q_PREV, tolerance=1e-6, progress=False)
    reference = _one_solve_per_waypoint(mobile_dual, path, spec, "hybrid", Q_PREV, tolerance=1e-6)
    assert (not chained) if table else sum(chained) == 11
    np.testing.assert_array_equal(result.configurations, [r.configuration for r in reference])
    np.testing.assert_array_equal(result.success, [r.success for r in reference])
    assert result.all_success
    for q in result.configurations:  # clear of the table and of itself by coal on the exact geometry
        assert not shape.check(q, scene=scene if table else None, distances=False).colliding
    with pytest.raises(fw.TaskError, match="names other than"):
        TrackingTask(extra=fw.Position("ee", (0.3, 0.0, 0.3), name="position"))


def test_a_callback_that_moves_a_term_is_seen_from_the_next_waypoint(arm):
    # an extra posture term (a motion term with a reference of its own, which the path does not move) moved by
    # the callback after waypoint 4, inside a compiled stretch: the waypoints after it are solved with the moved
    # term, as one solve per waypoint solves them
    posture = Motion("all", arm.middle, name="posture")
    spec = TrackingTask(motion=0.01, extra=0.05 * posture)
    path = paths.circle((0.3, 0.0, 0.3), 0.03, 10)
    elsewhere = arm.middle + 0.3

    def move(k, result):
        if k == 4:
            posture.set_target(elsewhere)

    result = track(arm, path, spec, solver="hybrid", progress=False, callback=move)
    posture.set_target(arm.middle)
    reference = _one_solve_per_waypoint(arm, path, spec, "hybrid", arm.middle, after=move)
    np.testing.assert_array_equal(result.configurations, [r.configuration for r in reference])
    posture.set_target(arm.middle)  # the move matters: without it the waypoints after 4 differ
    assert not np.array_equal(result.configurations[5:], track(arm, path, spec, solver="hybrid",
                                                               progress=False).configurations[5:])
