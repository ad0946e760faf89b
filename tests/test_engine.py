"""The compiled local engine: reaching poses, minimizing motion on the task, priorities, continuous joints.

Every answer is checked with Pinocchio's own FK of the model (independent of the compiled kernels)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
import scipy.optimize as so

import framework as fw
from framework.engine import LocalSettings, residuals, solve_local
from framework.costs.problem import Problem


def pose_errors(robot: fw.Robot, x: np.ndarray, frame: str, target: pin.SE3) -> tuple[float, float]:
    M = robot.frame_placement(x, frame)
    return (float(np.linalg.norm(M.translation - target.translation)),
            float(np.linalg.norm(pin.log3(target.rotation.T @ M.rotation))))


@pytest.fixture(scope="module")
def panda(erd) -> fw.Robot:
    return fw.load_robot(erd / "panda_description" / "urdf" / "panda.urdf",
                         joints=[f"panda_joint{i}" for i in range(1, 8)])


def test_pose_ik_reaches_random_poses_where_one_descent_does_not(panda, rng):
    """100 FK-sampled Panda poses: the default solver reaches every one to 1e-9 m / 1e-9 rad (by Pinocchio FK);
    a single Levenberg-Marquardt descent from the middle of the limits (no restart) reaches far fewer."""
    tip = "panda_hand_tcp"
    single = LocalSettings(tolerance=1e-9, restarts=False, max_iterations=200)
    reached = descent = 0
    for k, x in enumerate(panda.random_configurations(rng, 100)):
        target = panda.frame_placement(x, tip)
        problem = Problem(panda, fw.Pose(tip, target))
        result = fw.solve(problem, tolerance=1e-9, seed=k)
        dp, da = pose_errors(panda, result.configuration, tip, target)
        reached += result.success and dp <= 1e-9 and da <= 1e-9
        assert result.errors[f"pose[{tip}].distance"] == pytest.approx(dp, abs=1e-12)
        descent += solve_local(problem.program, panda.middle, k, single).reached
    assert reached == 100
    assert descent <= 95  # measured 80-90: restarts are what makes it reliable


def test_the_damping_follows_the_gain_ratio_of_the_step_taken(panda, rng):
    """Nielsen's factor of the damping after an accepted step (engine.reach.gain_factor) against the gain ratio
    computed here with numpy: the drop of ‖r‖² between Panda poses (the engine's residuals, which other tests check
    against Pinocchio) over the drop the linearization at the start predicts for the step. A wrapping coordinate's
    step is the one before the wrap (2π off in ``xt − x``). A fixed ÷4 would match neither ρ's range."""
    from framework.engine.steps import DAMPING_DOWN, gain_factor
    from tests.compiled import python_callable

    gain_factor = python_callable(gain_factor)

    problem = Problem(panda, fw.Pose("panda_hand_tcp", panda.frame_placement(panda.middle, "panda_hand_tcp")))
    wraps = np.zeros(panda.n, dtype=bool)
    factors = []
    for x in panda.random_configurations(rng, 20):
        r, J = (a.copy() for a in residuals(problem.program, x))
        for damping in (1e-3, 1e-1, 1e1):
            dx = np.linalg.solve(J.T @ J + damping * np.eye(panda.n), -J.T @ r)
            xt = x + dx
            rt = residuals(problem.program, xt)[0]
            e, et = float(r @ r), float(rt @ rt)
            rho = (e - et) / (e - float(np.sum((r + J @ dx) ** 2)))
            expected = max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3)
            got = gain_factor(e, et, J, r, x, xt, dx, wraps)
            assert got == pytest.approx(expected, rel=1e-9, abs=1e-12)
            factors.append(got)
            wrapped = xt.copy()
            wrapped[0] -= 2.0 * np.pi  # the same configuration, wrapped on a full-turn axis
            around = wraps.copy()
            around[0] = True
            assert gain_factor(e, et, J, r, x, wrapped, dx, around) == pytest.approx(got, rel=1e-12, abs=1e-15)
    assert DAMPING_DOWN == 1.0 / 3.0 and min(factors) == pytest.approx(1.0 / 3.0) and max(factors) > 1.0


def test_pose_targets_as_se3_matrix_or_pair_agree(panda, rng):
    tip = "panda_hand_tcp"
    T = panda.frame_placement(panda.random_configurations(rng, 1)[0], tip)
    quat = pin.Quaternion(T.rotation).coeffs()  # (x, y, z, w)
    forms = [T, T.homogeneous, (T.translation, T.rotation), (T.translation, pin.Quaternion(T.rotation))]
    terms = [fw.Pose(tip, form) for form in forms] + [fw.Pose(tip, (T.translation, quat), quaternion="xyzw")]
    for term in terms[1:]:
        np.testing.assert_allclose(term.position, terms[0].position, atol=1e-15)
        np.testing.assert_allclose(term.rotation, terms[0].rotation, atol=1e-12)
    bad = T.homogeneous.copy()
    bad[3] = [0, 0, 1, 1]
    with pytest.raises(fw.TaskError, match="last row"):
        fw.Pose(tip, bad)
    with pytest.raises(fw.TaskError, match="4x4"):
        fw.Pose(tip, np.eye(3))
    with pytest.raises(fw.TaskError, match=f"pose target of '{tip}' is not a rotation matrix"):
        fw.Pose(tip, pin.SE3(np.diag([1.0, 1.0, 2.0]), np.zeros(3)))  # an SE3 holding no rotation
    moved = panda.frame_placement(panda.middle, tip)
    terms[0].set_target(moved)  # position and rotation follow the target
    np.testing.assert_array_equal(terms[0].position, moved.translation)
    np.testing.assert_array_equal(terms[0].rotation, moved.rotation)


def test_motion_is_minimized_on_the_task(rng):
    """Paper 000's target 1: at the engine's answer the motion terms' gradient has no component along the task's
    null space (the first-order condition of 'least motion on the task'), by finite differences of the motion
    terms' values and the task Jacobian."""
    robot = fw.load_robot("youbot_dual_mobile")
    q_prev = np.r_[0, 0, np.pi / 2, -np.pi / 2, np.pi / 2, -np.pi / 4, np.pi / 4, 0, np.pi / 2, np.pi / 2,
                   -np.pi / 4, np.pi / 4, 0]
    t1, offset = np.array([0.5, -0.2, 0.45]), np.array([0.2, -0.3, -0.2])
    motion = 0.1 * fw.Motion("base", q_prev) + 0.4 * fw.Motion("arm1", q_prev) + 0.4 * fw.Motion("arm2", q_prev)
    problem = Problem(robot, 1.2 * fw.Position("arm1_ee", t1) + 1.2 * fw.Position("arm2_ee", t1 + offset) + motion)
    result = fw.solve(problem, tolerance=1e-12)
    x = result.configuration
    assert result.success and max(result.errors.values()) < 1e-12
    regularizers = Problem(robot, motion)
    h = 1e-6
    E = np.eye(robot.n) * h
    gradient = (regularizers.cost(x + E) - regularizers.cost(x - E)) / (2 * h)
    _, J = residuals(problem.program, x)
    _, s, Vt = np.linalg.svd(J)
    null = Vt[int(np.sum(s > 1e-9 * s[0])):]
    assert np.abs(null @ gradient).max() < 1e-6  # a random point on the task: ~0.1
    assert np.abs(null @ gradient).max() < 1e-3 * np.abs(gradient).max()


def test_dependent_task_rows_are_held_in_least_squares_not_left_where_they_start():
    """Paper 000's target 1 with the first hand's Position term given twice: the task's rows are dependent, so the
    Newton phase's KKT matrix is singular whatever the damping of its Hessian block (collision rows do this when
    two bodies' closest pairs press along one direction). From the same point on the task, the phase reaches the
    least motion the problem without the copy reaches (to 1e-12), on the task by Pinocchio's FK; left singular,
    the phase stays at its start (0.4354 against 0.3969)."""
    robot = fw.load_robot("youbot_dual_mobile")
    q_prev = np.r_[0, 0, np.pi / 2, -np.pi / 2, np.pi / 2, -np.pi / 4, np.pi / 4, 0, np.pi / 2, np.pi / 2,
                   -np.pi / 4, np.pi / 4, 0]
    t1, t2 = np.array([0.5, -0.2, 0.45]), np.array([0.7, -0.5, 0.25])
    motion = 0.1 * fw.Motion("base", q_prev) + 0.4 * fw.Motion("arm1", q_prev) + 0.4 * fw.Motion("arm2", q_prev)
    task = 1.2 * fw.Position("arm1_ee", t1) + 1.2 * fw.Position("arm2_ee", t2)
    single = Problem(robot, task + motion)
    double = Problem(robot, task + 1.2 * fw.Position("arm1_ee", t1, name="arm1 again") + motion)
    x0 = solve_local(single.program, q_prev, 0, LocalSettings(tolerance=1e-12, regularize=False)).x
    settings = LocalSettings(tolerance=1e-12)
    one, two = solve_local(single.program, x0, 0, settings), solve_local(double.program, x0, 0, settings)
    regularizers = Problem(robot, motion)
    start, least, found = (float(regularizers.cost(x[None])[0]) for x in (x0, one.x, two.x))
    assert two.reached and two.regularized == "converged"
    assert least < start - 0.03  # the optimum is well away from the start
    assert found == pytest.approx(least, abs=1e-12)
    for frame, target in (("arm1_ee", t1), ("arm2_ee", t2)):
        assert np.linalg.norm(robot.frame_placement(two.x, frame).translation - target) < 1e-12


def _base_shift(base: float, arms: float) -> tuple[Problem, np.ndarray, np.ndarray]:
    """The dual youBot's two hands at their places after the base alone moved (1 cm, -4 mm) from ``q_prev``, with
    motion from ``q_prev`` weighted ``base`` and ``arms`` (each arm): ``(problem, q_prev, shifted)``."""
    robot = fw.load_robot("youbot_dual_mobile")
    q_prev = np.array([0, 0, 0.3, -0.5, 1.0, -1.2, 0.8, 0.2, 0.4, 1.1, -1.0, 0.9, -0.3])
    shifted = q_prev.copy()
    shifted[:2] += [0.01, -0.004]
    task = fw.Position("arm1_ee", robot.frame_placement(shifted, "arm1_ee").translation) + \
        fw.Position("arm2_ee", robot.frame_placement(shifted, "arm2_ee").translation)
    motion = base * fw.Motion("base", q_prev[:3]) + arms * fw.Motion("arm1", q_prev[3:8]) + \
        arms * fw.Motion("arm2", q_prev[8:])
    return Problem(robot, task + motion), q_prev, shifted


def test_a_joint_group_at_rest_is_held_exactly_at_zero_motion():
    """Both hands' targets shifted by the base alone (1 cm, -4 mm) from q_prev: moving the base costs 0.1 x 1.08
    cm, moving an arm instead 0.4 x its joint motion (several cm of joint angle for a hand's centimetre), so the
    optimum keeps both arms exactly at rest — the norms' kink. The answer is that construction to 1e-12 (a
    smoothed Newton phase stalls at the kink with the arms ~1e-8 from rest and the base ~8e-9 off), its cost no
    higher, and the phase converged."""
    problem, q_prev, shifted = _base_shift(base=0.1, arms=0.4)
    result = fw.solve(problem, initial=q_prev, tolerance=1e-12)
    assert result.success and result.settings["regularized"] == "converged"
    assert np.abs(result.configuration - shifted).max() < 1e-12
    assert result.terms["motion[arm1]"] < 1e-12 and result.terms["motion[arm2]"] < 1e-12
    assert result.cost <= float(problem.cost(shifted[None])[0]) + 1e-15


def test_a_group_held_at_rest_leaves_it_when_its_multiplier_says_so():
    """The same targets with the base dear (1.0) and the arms cheap (0.01 each): from ``shifted`` (on the task, arms
    at rest: both arm norms start at their kink and are held there) the optimum lies elsewhere (the base at rest,
    the arms moving). The held arms' multipliers exceed their norms' slope, so they are moved off zero: the answer
    costs 10x less than the start and the same (to 1e-12) as the answer from q_prev, reached without holds at the
    start (a smoothed Newton phase stays at the start, at 1.08e-2)."""
    problem, q_prev, shifted = _base_shift(base=1.0, arms=0.01)
    held = fw.solve(problem, initial=shifted, tolerance=1e-12)
    free = fw.solve(problem, initial=q_prev, tolerance=1e-12)
    assert held.success and free.success
    start = float(problem.cost(shifted[None])[0])
    assert held.cost < 0.2 * start  # measured 1.05e-3 against 1.08e-2
    assert held.cost == pytest.approx(free.cost, abs=1e-12)
    assert held.terms["motion[base]"] < 1e-12  # the base at rest now: its own kink, held there



def test_least_motion_answers_are_local_minima_that_slsqp_cannot_lower(rng):
    """The dual youBot's two hands at random reachable places, least motion from paper 000's start: scipy's SLSQP,
    started at the engine's answer with the task as equality constraints and the joint box, lowers none of the
    weighted motion costs by more than 1e-6 (it would from a point that is not a local minimum: a Newton phase
    that stopped at saddle points and zig-zagged along cut steps left 10 of these 20 answers 1e-4 to 0.6 above)."""
    robot = fw.load_robot("youbot_dual_mobile")
    q_prev = np.r_[0, 0, np.pi / 2, -np.pi / 2, np.pi / 2, -np.pi / 4, np.pi / 4, 0, np.pi / 2, np.pi / 2,
                   -np.pi / 4, np.pi / 4, 0]
    motion = 0.1 * fw.Motion("base", q_prev[:3]) + 0.4 * fw.Motion("arm1", q_prev[3:8]) + \
        0.4 * fw.Motion("arm2", q_prev[8:])
    regularizers = Problem(robot, motion)
    lowered = []
    for k in range(20):
        x_goal = robot.random_configurations(rng, 1)[0]
        t1, t2 = (robot.frame_placement(x_goal, f).translation for f in ("arm1_ee", "arm2_ee"))
        result = fw.solve(Problem(robot, 1.2 * fw.Position("arm1_ee", t1) + 1.2 * fw.Position("arm2_ee", t2) + motion),
                          seed=k, tolerance=1e-10)
        assert result.success
        x = result.configuration
        cost = float(regularizers.cost(x[None])[0])

        def task(z, t1=t1, t2=t2):
            return np.r_[robot.frame_placement(z, "arm1_ee").translation - t1,
                         robot.frame_placement(z, "arm2_ee").translation - t2]

        polished = so.minimize(lambda z: float(regularizers.cost(z[None])[0]), x, method="SLSQP",
                               bounds=list(zip(robot.lower, robot.upper)), constraints=[{"type": "eq", "fun": task}],
                               options={"maxiter": 500, "ftol": 1e-12})
        if np.abs(task(polished.x)).max() < 1e-8:
            lowered.append(cost - polished.fun)
    assert len(lowered) >= 18  # SLSQP's answers on the task
    assert max(lowered) < 1e-6

def test_priorities_reach_whatever_the_weights_and_weighted_sums_do_not():
    """Position weighted 0.01 against motion weighted 1: the task first reaches; the weighted sum (papers) stays
    short of the target with a lower weighted cost than the reaching answer."""
    robot = fw.load_robot("youbot_arm")
    prev = robot.middle
    target = robot.frame_placement(prev, "ee").translation + [0.05, 0.0, 0.08]
    objective = 0.01 * fw.Position("ee", target) + 1.0 * fw.Motion("arm", prev)
    first = fw.solve(Problem(robot, objective), seed=0)
    weighted = fw.solve(Problem(robot, objective, priorities=False), seed=0)
    assert first.success and first.errors["position[ee]"] < 1e-12
    assert not weighted.success and weighted.cost < first.cost


def test_continuous_joints_wrap_in_motion_and_in_the_box(erd):
    """PR2's forearm and wrist rolls are continuous: a motion from 3.1 to -3.1 rad is 0.083 rad, not 6.2, and the
    engine reaches a two-hand pose target through the wrap (answers checked by Pinocchio FK)."""
    joints = ["torso_lift_joint"] + [f"{s}_{j}_joint" for s in "lr" for j in (
        "shoulder_pan", "shoulder_lift", "upper_arm_roll", "elbow_flex", "forearm_roll", "wrist_flex", "wrist_roll")]
    robot = fw.load_robot(erd / "pr2_description" / "urdf" / "pr2.urdf", joints=joints)
    roll = robot.joint("l_forearm_roll_joint").index
    previous, x = robot.middle.copy(), robot.middle.copy()
    previous[roll], x[roll] = 3.1, -3.1
    value = Problem(robot, fw.Motion("l_forearm_roll_joint", previous)).values(x)[0, 0]
    assert value == pytest.approx(2 * np.pi - 6.2, abs=1e-12)
    rng = np.random.default_rng(3)
    hands = ("l_gripper_tool_frame", "r_gripper_tool_frame")
    for k in range(10):
        goal = robot.random_configurations(rng, 1)[0]
        goal[roll] = np.pi - 0.05  # next to the seam
        targets = [robot.frame_placement(goal, hand) for hand in hands]
        rest = robot.middle.copy()
        rest[roll] = -np.pi + 0.05  # 0.1 rad away across the seam, 6.18 rad the long way
        objective = fw.Pose(hands[0], targets[0]) + fw.Pose(hands[1], targets[1]) + 0.1 * fw.Motion("all", rest)
        result = fw.solve(Problem(robot, objective), seed=k, tolerance=1e-9)
        assert result.success
        for hand, target in zip(hands, targets):
            dp, da = pose_errors(robot, result.configuration, hand, target)
            assert dp <= 1e-9 and da <= 1e-9


def test_time_budget_stops_the_engine():
    """An unreachable target under a time budget: the engine restarts until the budget, then reports it."""
    robot = fw.load_robot("puma560")
    problem = Problem(robot, fw.Position("ee", [5.0, 0.0, 0.0]))
    fw.solve(problem, max_iterations=10)  # the compiled code loaded (the first call in a process takes ~0.3 s)
    result = fw.solve(problem, time_budget=0.003, seed=0)
    assert not result.success and result.stop_reason == "time_budget"
    assert result.settings["restart_count"] > 0


def test_a_blocking_row_is_cut_at_its_boundary_and_never_held_past_x():
    """The Newton phase's one-sided rows a trial step enters. Three rows clear at x = 0, violated at the trial
    x + dx, each linear: f_a(q) = c_a + g_a·q on its violated side. The boundary fraction is where the first of
    them crosses zero along the step (found here by bisection on the functions themselves); a row whose
    linearization at the trial puts x on its violated side is held where x is (``cb = 0``), the others at their
    linearized value at x."""
    from framework.engine.active_set import boundary_fraction, entered
    from tests.compiled import python_callable

    _boundary_fraction, _entered = python_callable(boundary_fraction), python_callable(entered)

    n, m = 3, 4
    x, dx = np.zeros(n), np.array([1.0, -0.5, 0.25])
    xt = x + dx
    c = np.array([-0.2, -0.05, 0.1, -0.3])  # row 2 is "violated at x" by its linearization; row 3 is held
    G = np.array([[0.5, 0.0, 0.0], [0.0, -0.4, 0.0], [0.2, 0.0, 0.0], [0.0, 0.0, 2.0]])

    def f(a: int, q: np.ndarray) -> float:
        return c[a] + G[a] @ q

    r = np.array([max(f(a, xt), 0.0) for a in range(m)])  # hinge rows at the trial: zero when clear
    assert np.all(r > 0)
    hinge, r_x = np.ones(m, dtype=bool), np.zeros(m)
    held = np.array([False, False, False, True])
    box_wrap, delta = np.zeros(n, dtype=bool), np.empty(n)
    tau = _boundary_fraction(x, xt, box_wrap, hinge, r_x, held, r, G, delta)
    crossings = []
    for a in (0, 1):  # rows clear at x: where f_a reaches zero along the step, by bisection
        lo, hi = 0.0, 1.0
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if f(a, x + mid * dx) < 0 else (lo, mid)
        crossings.append(lo)
    assert tau == pytest.approx(min(crossings), abs=1e-12)  # row 1 at 0.25, before row 0 at 0.4
    assert _boundary_fraction(x, x + 0.2 * dx, box_wrap, hinge, r_x, held, np.zeros(m), G, delta) == 1.0

    Jb, cb, sb = np.zeros((m, n)), np.full(m, np.nan), np.zeros(m)
    r_only = np.where(np.arange(m) == 2, r, 0.0)  # only row 2 entered: its linearization says x is violated
    assert _entered(x, xt, box_wrap, hinge, r_x, held, r_only, G, delta, Jb, cb, sb)
    assert sb[2] == 1.0 and cb[2] == 0.0 and np.array_equal(Jb[2], G[2])
    r_only = np.where(np.arange(m) == 0, r, 0.0)  # only row 0: clear at x by its linearization
    assert _entered(x, xt, box_wrap, hinge, r_x, held, r_only, G, delta, Jb, cb, sb)
    assert cb[0] == pytest.approx(c[0]) and sb[0] == 1.0


def test_the_engine_through_its_resolved_entry_points_gives_the_dispatched_answers(panda, rng, monkeypatch):
    """``solve_local`` calls ``reach`` and ``regularize`` through compiled entry points resolved once per layout
    (numba's per-call type resolution skipped): Panda poses, and the dual youBot's positions with motion terms
    (both phases), give bit for bit the answers of calls through numba's dispatchers."""
    import framework.engine.local as local

    youbot = fw.load_robot("youbot_dual_mobile")
    q = youbot.middle
    problems = [Problem(panda, fw.Pose("panda_hand_tcp", panda.frame_placement(x, "panda_hand_tcp")))
                for x in panda.random_configurations(rng, 10)]
    for x in youbot.random_configurations(rng, 10):
        problems.append(Problem(youbot, fw.Position("arm1_ee", youbot.frame_placement(x, "arm1_ee").translation)
                                + fw.Position("arm2_ee", youbot.frame_placement(x, "arm2_ee").translation)
                                + 0.1 * fw.Motion("base", q) + 0.4 * fw.Motion("arm1", q)
                                + 0.4 * fw.Motion("arm2", q)))
    settings = LocalSettings(tolerance=1e-9)
    resolved = [solve_local(p.program, p.robot.middle, k, settings) for k, p in enumerate(problems)]
    assert all(p.program.layout.entries for p in problems)  # the entry points were resolved and kept
    monkeypatch.setattr(local, "_entry", lambda program, kernel, args: kernel)
    dispatched = [solve_local(p.program, p.robot.middle, k, settings) for k, p in enumerate(problems)]
    assert sum(r.regularized is not None for r in resolved) == 10
    for a, b in zip(resolved, dispatched):
        assert a.reached and np.array_equal(a.x, b.x) and np.array_equal(a.task_errors, b.task_errors)
        assert (a.iterations, a.evaluations, a.regularized) == (b.iterations, b.evaluations, b.regularized)


def test_the_engine_refuses_starts_and_streams_of_other_shapes(panda):
    """The entry points do not check types: ``solve_local`` refuses what would not match them, naming it."""
    problem = Problem(panda, fw.Pose("panda_hand_tcp", panda.frame_placement(panda.middle, "panda_hand_tcp")))
    with pytest.raises(fw.SolverError, match="start must be 7 joint coordinates"):
        solve_local(problem.program, np.zeros((2, 7)), 0)
    with pytest.raises(fw.SolverError, match="restart stream"):
        solve_local(problem.program, panda.middle, np.zeros(1))  # float64, not a uint64 stream
    settings = LocalSettings(tolerance=1, max_iterations=np.int32(50))  # plain numbers for the compiled calls
    assert type(settings.tolerance) is float and type(settings.max_iterations) is int
    assert solve_local(problem.program, panda.middle, 0, settings).reached
