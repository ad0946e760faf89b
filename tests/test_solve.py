"""solve(): the shared solver interface over an IK problem, and the hybrid."""

from __future__ import annotations

import numpy as np
import pytest

import framework as fw
from framework.costs import Motion, Position
from framework.costs.problem import Problem
from framework.solvers.solve import solve
from framework.io.taskfile import load_task, resolve_task

Q_PREV = load_task(resolve_task("paper000_circular")).cases[0].initial  # paper 000's q_prev (its task file)


@pytest.fixture(scope="module")
def problem() -> Problem:
    """Paper 000, target point 1 (coordinated: t*_e2 = t*_e1 + t_r), the paper's weighted sum."""
    robot = fw.load_robot("youbot_dual_mobile")
    t1, tr = np.array([0.5, -0.2, 0.45]), np.array([0.2, -0.3, -0.2])
    objective = (
        1.2 * Position("arm1_ee", t1)
        + 1.2 * Position("arm2_ee", t1 + tr)
        + 0.1 * Motion("base", Q_PREV)
        + 0.4 * Motion("arm1", Q_PREV)
        + 0.4 * Motion("arm2", Q_PREV)
    )
    return Problem(robot, objective, priorities=False)


@pytest.mark.parametrize("solver", ["cmaes", "de", "sde", "hybrid"])
def test_same_seed_same_result(problem, solver):
    options = None
    if solver == "hybrid":  # its first descent needs no random numbers: a pose it must restart for (the engine's
        problem, options = pose_needing_restarts(), {"closed_form": False}  # own: a closed form needs none)
    a = solve(problem, solver, seed=5, max_iterations=40, options=options)
    b = solve(problem, solver, seed=5, max_iterations=40, options=options)
    np.testing.assert_array_equal(a.configuration, b.configuration)
    np.testing.assert_array_equal(a.history, b.history)
    c = solve(problem, solver, seed=6, max_iterations=40, options=options)
    assert not np.array_equal(a.configuration, c.configuration)


def pose_needing_restarts() -> Problem:
    """The first of a seeded series of reachable Puma 560 poses that the descent from the middle misses."""
    robot = fw.load_robot("puma560")
    rng = np.random.default_rng(1)
    for _ in range(200):
        pose = robot.frame_placement(robot.random_configurations(rng, 1)[0], "ee")
        problem = Problem(robot, fw.Position("ee", pose.translation) + fw.Orientation("ee", pose.rotation))
        if solve(problem, "hybrid", seed=0, options={"closed_form": False}).settings["restart_count"] > 0:
            return problem
    raise AssertionError("no pose in 200 needed a restart")


def test_result_reports_every_term(problem):
    result = solve(problem, "de", seed=0, max_iterations=50)
    assert set(result.terms) == set(problem.names)
    weighted = sum(w * result.terms[n] for w, n in zip(problem.weights, problem.names))
    assert result.cost == pytest.approx(weighted, rel=1e-12)
    assert result.task_error == pytest.approx(result.terms["position[arm1_ee]"] + result.terms["position[arm2_ee]"])
    assert result.iterations == 50 and len(result.history) == 50
    assert result.evaluations >= 50 * 30
    assert np.all(np.diff(result.history) <= 0)  # best-so-far never increases
    assert np.all(result.configuration >= problem.robot.lower) and np.all(result.configuration <= problem.robot.upper)


def test_result_tables_made_on_first_read_match_the_problem_and_survive_pickling(problem):
    """``terms``, ``errors``, ``task_error`` and ``history`` are made when first read: they equal the problem's
    own evaluation at the answer, and a pickled result (as a Dask worker returns it) carries them made."""
    import pickle

    result = solve(problem, "hybrid", seed=0)
    x = result.configuration
    values = problem.values(x[None])[0]
    copied = pickle.loads(pickle.dumps(result))  # pickled before any table was read
    for r in (copied, result):
        assert r.terms == pytest.approx(dict(zip(problem.names, values)), rel=1e-9, abs=1e-15)
        assert r.errors == pytest.approx(problem.errors(x), rel=1e-9, abs=1e-15)
        assert r.task_error == pytest.approx(values[problem.task_mask].sum(), rel=1e-9, abs=1e-15)
        assert r.cost == pytest.approx(float(problem.cost(x[None])[0]), rel=1e-12)
        np.testing.assert_array_equal(r.history, [r.cost])  # the hybrid's engine alone: no generations
        assert r.success == result.success and r.settings == result.settings
    assert "terms=" in repr(result) and "errors=" in repr(result)


def test_cmaes_reaches_the_target_and_the_hybrid_matches_it_with_fewer_evaluations(problem):
    cma = solve(problem, "cmaes_fast", seed=1, max_iterations=1000)  # the paper's budget: 1e-15 to 1e-14 m
    hybrid = solve(problem, "hybrid", seed=1)
    assert cma.task_error < 1e-9
    assert hybrid.success and hybrid.task_error < 1e-12
    assert hybrid.cost <= cma.cost + 1e-6  # still minimizes motion, not only reaches
    assert hybrid.evaluations < cma.evaluations / 5


def test_out_of_reach_target_returns_best_effort_without_raising():
    robot = fw.load_robot("youbot_arm")
    problem = Problem(robot, Position("ee", [3.0, 0.0, 0.5]))
    for solver in ("de", "hybrid"):
        result = solve(problem, solver, seed=0, max_iterations=60)
        assert not result.success
        assert result.task_error > 2.0  # the arm reaches about 0.55 m
        assert result.stop_reason in ("max_iterations", "refinement_stalled")


def test_stop_at_tolerance(problem):
    result = solve(problem, "de", seed=0, max_iterations=1000, tolerance=1e-2, stop_at_tolerance=True)
    assert result.success and result.stop_reason == "tolerance" and result.iterations < 1000


def test_warm_start_from_a_solution(problem):
    first = solve(problem, "hybrid", seed=0)
    again = solve(problem, "cmaes_fast", seed=0, max_iterations=1, initial=first.configuration)
    assert again.cost <= first.cost + 1e-3


def test_bad_solver_and_settings(problem):
    with pytest.raises(fw.SolverError, match="hybrid"):
        solve(problem, "simulated_annealing")
    with pytest.raises(fw.SolverError):
        solve(problem, "de", options={"F_typo": 0.5})
    with pytest.raises(fw.SolverError):
        solve(problem, "de", tolerance=-1)
    with pytest.raises(fw.ConfigurationError):
        solve(problem, "de", initial=np.zeros(12))


def test_bounds_modes(problem):
    with pytest.raises(fw.TaskError):
        Problem(problem.robot, problem.objective, bounds="reflect")
    penalized = Problem(problem.robot, problem.objective, bounds="penalty")
    assert penalized.names[-1] == "joint_limits" and penalized.repair_mode == "none"
    result = solve(penalized, "de", seed=0, max_iterations=100)
    assert result.terms["joint_limits"] == 0.0


def test_hybrid_minimizes_the_objective_when_reaching_is_not_worth_it():
    """Position weighted 0.01, motion 1: as a weighted sum (the papers) the optimum stays at q_prev, short of the
    target; with priorities (the default) the task comes first and the motion is minimized on it."""
    robot = fw.load_robot("youbot_arm")
    prev = robot.middle
    target = robot.frame_placement(prev, "ee").translation + [0.0, 0.0, 0.1]
    objective = 0.01 * Position("ee", target) + 1.0 * Motion("arm", prev)
    result = solve(Problem(robot, objective, priorities=False), "hybrid", seed=0)
    assert not result.success and result.settings["weighted"]
    assert result.cost <= 0.01 * 0.1 + 1e-6  # no worse than not moving at all
    assert result.terms["motion[arm]"] < 1e-3
    first = solve(Problem(robot, objective), "hybrid", seed=0)
    assert first.success and first.errors["position[ee]"] < 1e-12 and first.terms["motion[arm]"] > 0.05
    # ... with the least motion on the task: a reaching configuration from another start moves more
    other = solve(Problem(robot, Position("ee", target)), "hybrid", seed=0)
    assert first.terms["motion[arm]"] <= Problem(robot, objective).values(other.configuration)[0, 1] + 1e-12


def test_multistart_lm_solves_full_poses_and_is_deterministic(rng):
    robot = fw.load_robot("puma560")
    x_true = robot.random_configurations(rng, 1)[0]
    target = robot.frame_placement(x_true, "ee")
    problem = Problem(robot, fw.Position("ee", target.translation) + fw.Orientation("ee", target.rotation))
    a = solve(problem, "multistart_lm", seed=3, population=32, tolerance=1e-9, max_iterations=500)
    b = solve(problem, "multistart_lm", seed=3, population=32, tolerance=1e-9, max_iterations=500)
    assert a.success and a.task_error <= 1e-9
    np.testing.assert_array_equal(a.configuration, b.configuration)
    reached = robot.frame_placement(a.configuration, "ee")
    np.testing.assert_allclose(reached.translation, target.translation, atol=1e-9)
    np.testing.assert_allclose(reached.rotation, target.rotation, atol=1e-8)


def test_multistart_lm_minimizes_motion_on_the_task_like_the_hybrid(problem):
    """The engine alone reaches paper 000's target 1 and minimizes the motion terms there: the hybrid's optimum
    (the exact-penalty weights make reaching optimal, so both are the weighted sum's minimum)."""
    engine = solve(problem, "multistart_lm", seed=0, tolerance=1e-12)
    hybrid = solve(problem, "hybrid", seed=0, tolerance=1e-12)
    assert engine.success and max(engine.errors.values()) <= 1e-12
    assert engine.cost == pytest.approx(hybrid.cost, abs=1e-12)
    reached_only = solve(problem, "multistart_lm", seed=0, tolerance=1e-12, options={"regularize": False})
    assert engine.cost < reached_only.cost - 1e-3  # minimizing the motion on the task is worth something


def test_callback_sees_every_iteration_and_can_stop(problem):
    seen = []

    def callback(iteration, best_f, best_x):
        seen.append((iteration, best_f))
        return iteration >= 9

    result = solve(problem, "de", seed=0, max_iterations=100, callback=callback)
    assert [i for i, _ in seen] == list(range(len(seen))) or [i for i, _ in seen] == list(range(1, len(seen) + 1))
    assert result.iterations == len(seen) <= 11
    assert result.stop_reason == "callback"
    np.testing.assert_allclose([f for _, f in seen], result.history[: len(seen)])


def test_hybrid_starts_from_q_prev_and_escalates_when_that_basin_misses():
    """The engine straight from the motion terms' q_prev; if that basin misses the task, random restarts (the
    report counts them, the first drawn start included), then the 30-generation phase from a uniform start; the
    better result by the objective is kept."""
    from framework.costs import Orientation

    robot = fw.load_robot("youbot_arm")
    ee = robot.end_effectors[0]
    rng = np.random.default_rng(0)
    missed = rescued = 0
    for i in range(10):
        goal, q_prev = robot.random_configurations(rng, 2)
        pose = robot.frame_placement(goal, ee)
        problem = Problem(robot, Position(ee, pose.translation) + 0.5 * Orientation(ee, pose.rotation)
                          + 0.01 * Motion("all", q_prev))
        engine = {"closed_form": False}  # the engine's own start and escalation (the arm has a closed form too)
        auto = solve(problem, "hybrid", seed=i, tolerance=1e-9, options=engine)
        basin = solve(problem, "hybrid", seed=i, tolerance=1e-9,
                      options={"restarts": False, "global_iterations": 0, **engine})
        assert auto.settings["start"] == "previous"
        if basin.success:
            np.testing.assert_array_equal(auto.configuration, basin.configuration)
            assert not auto.settings["escalated"] and auto.settings["restart_count"] == 0
        else:
            missed += 1
            assert auto.cost <= basin.cost + 1e-12
            assert auto.settings["restart_count"] >= 1  # the basin was left: a drawn start, counted as a restart
            rescued += auto.success
    assert missed >= 1 and rescued == missed


@pytest.mark.parametrize("solver", ["cmaes_fast", "de"])
def test_feasibility_ranking_reaches_what_the_weighted_sum_trades_away(solver):
    """A reachable target with a small weight beside a heavy motion term: ranked by the weighted sum (asked for,
    or a problem without priorities), the metaheuristic stops short of it (its optimum does, 0.17 m off); ranked
    by Deb's rules (feasibility first, the default on a problem with priorities) it meets the tolerance, then
    spends less motion than the configuration the target came from."""
    arm = fw.load_robot("youbot_arm")
    x_goal = arm.random_configurations(np.random.default_rng(1), 1)[0]
    target = arm.frame_placement(x_goal, "ee").translation
    objective = 0.05 * fw.Position("ee", target) + 1.0 * fw.Motion("all", arm.middle)
    problem = fw.Problem(arm, objective)
    weighted = fw.Problem(arm, objective, priorities=False)
    runs = {"default": fw.solve(problem, solver, seed=0, max_iterations=300, tolerance=1e-4),
            "weighted": fw.solve(problem, solver, seed=0, max_iterations=300, tolerance=1e-4,
                                 options={"ranking": "weighted"}),
            "no priorities": fw.solve(weighted, solver, seed=0, max_iterations=300, tolerance=1e-4)}
    for name in ("weighted", "no priorities"):
        assert not runs[name].success and runs[name].terms["position[ee]"] > 0.1
    assert runs["weighted"].cost == runs["no priorities"].cost  # the same generations
    assert runs["default"].success and runs["default"].terms["position[ee]"] <= 1e-4
    assert runs["default"].terms["motion[all]"] < np.linalg.norm(x_goal - arm.middle)
    explicit = fw.solve(problem, solver, seed=0, max_iterations=300, tolerance=1e-4,
                        options={"ranking": "feasibility"})
    np.testing.assert_array_equal(explicit.configuration, runs["default"].configuration)
    with pytest.raises(fw.SolverError, match="ranking"):
        fw.solve(problem, solver, options={"ranking": "lexical"})
    with pytest.raises(fw.SolverError, match="needs a problem with priorities"):
        fw.solve(weighted, solver, options={"ranking": "feasibility"})


def test_a_task_alone_is_ranked_by_its_weighted_sum():
    """Without regularizers there is one level: the metaheuristic ranks by the weighted sum, as it always did
    (the same generations as asking for it), and keeps improving past the tolerance (Deb's rules would stop
    telling feasible candidates apart)."""
    arm = fw.load_robot("youbot_arm")
    target = arm.frame_placement(arm.random_configurations(np.random.default_rng(2), 1)[0], "ee").translation
    problem = fw.Problem(arm, fw.Position("ee", target))
    auto = fw.solve(problem, "cmaes_fast", seed=0, max_iterations=200, tolerance=1e-3)
    weighted = fw.solve(problem, "cmaes_fast", seed=0, max_iterations=200, tolerance=1e-3,
                        options={"ranking": "weighted"})
    np.testing.assert_array_equal(auto.configuration, weighted.configuration)
    assert auto.task_error < 1e-6  # far below the tolerance: still ranked by the error itself


def test_hybrid_passes_its_global_options_to_the_global_phase():
    """Options of the global solver are a table inside the hybrid's options (they used to crash the settings
    cache, which hashed the hybrid's options whole)."""
    robot = fw.load_robot("puma560")
    target = robot.frame_placement(robot.middle + 0.4, "ee")
    problem = Problem(robot, fw.Pose("ee", target))
    result = solve(problem, "hybrid", seed=1, options={"global_iterations": 3, "global_options": {"sigma0": 0.05}})
    assert result.success and result.settings["escalated"] is False
    with pytest.raises(fw.SolverError, match="sigma_zero"):  # the table reaches the global solver, which checks it
        solve(problem, "hybrid", seed=1, options={"global_iterations": 3, "global_options": {"sigma_zero": 0.05}})


def test_solvers_are_made_once_per_options_and_bad_options_still_raise():
    """A loop passing the same options to every solve reuses one solver instance (validating options costs a
    third of a pose solve); options that differ — in value or in type — make their own, and invalid ones raise
    every time (nothing is cached for them)."""
    from framework.solvers import ik_solver

    a = ik_solver("hybrid", {"stall": 8, "polish": 2})
    assert ik_solver("hybrid", {"polish": 2, "stall": 8}) is a  # the order of the table does not matter
    assert a.options.stall == 8 and a.options.polish == 2
    assert ik_solver("hybrid", {"stall": 9, "polish": 2}) is not a
    assert ik_solver("hybrid") is ik_solver("hybrid", {}) is not a
    whole = ik_solver("hybrid", {"stall": 8.0, "polish": 2})  # an integral float is a valid count, its own entry
    assert whole is not a and whole.options.stall == 8 and type(whole.options.stall) is int
    for _ in range(2):
        with pytest.raises(fw.SolverError, match="stall"):
            ik_solver("hybrid", {"stall": 8.5})
        with pytest.raises(fw.SolverError, match="polish"):
            ik_solver("hybrid", {"polish": -1})
    table = {"global_iterations": 3, "global_options": {"sigma0": 0.05}}  # unhashable: a new instance each time
    assert ik_solver("hybrid", table) is not ik_solver("hybrid", table)
    robot = fw.load_robot("puma560")
    problem = Problem(robot, fw.Pose("ee", robot.frame_placement(robot.middle + 0.4, "ee")))
    first, again = (solve(problem, "hybrid", seed=2, options={"stall": 8}) for _ in range(2))
    np.testing.assert_array_equal(first.configuration, again.configuration)
    assert first.settings["stall"] == 8


def test_float_copy_gives_an_own_native_float64_array_of_any_input():
    """The copy a solve makes of a start, a target's parameters and its answer: always a new float64 array of the same
    values and shape (C-contiguous), whatever the input's dtype, byte order or strides — checked against numpy."""
    from framework.validate import float_copy

    rng = np.random.default_rng(5)
    a = rng.normal(size=(4, 6))
    for given in (a, a[:, ::2], a.T, a.astype(">f8"), a.astype(np.float32), [[1, 2], [3, 4]], (0.5, 1.5)):
        made = float_copy(given)
        expected = np.array(given, dtype=float)
        assert made.dtype == np.float64 and made.dtype.isnative and made.flags.c_contiguous
        assert made.shape == expected.shape and np.array_equal(made, expected)
        if isinstance(given, np.ndarray):
            assert not np.shares_memory(made, given)
    made = float_copy(a)
    made[0, 0] += 1.0  # the copy is the caller's own
    assert made[0, 0] != a[0, 0]


FIRST_SOLVES = """
import json
import numpy as np
import framework as fw
robot = fw.load_robot("puma560")
rng = np.random.default_rng(4)
targets = [robot.frame_placement(x, "ee") for x in robot.random_configurations(rng, 3)]
seeded = fw.solve(fw.Problem(robot, fw.Pose("ee", targets[0])), time_budget=0.005)
runs = [fw.solve(fw.Problem(robot, fw.Pose("ee", M)), time_budget=0.005, seed=k, options={"closed_form": False})
        for k, M in enumerate(targets)]
cma = fw.solve(fw.Problem(robot, fw.Pose("ee", targets[0])), "cmaes", time_budget=0.5, max_iterations=40)
print(json.dumps({"engine": [[r.success, r.stop_reason, r.iterations] for r in runs],
                  "cmaes": [cma.stop_reason, cma.iterations],
                  "seeded": [seeded.success, seeded.settings["start"], seeded.stop_reason]}))
"""


def test_the_first_solve_of_a_process_has_its_whole_time_budget():
    """A process's first call of a solver's compiled code loads it from numba's disk cache (about half a second
    for the engine, more for pycma's import; minutes to compile on a fresh install): ``solve`` loads it before the
    time budget starts (``IKSolver.prepare``). So the first solve of a fresh process with a 5 ms budget reaches a
    reachable Puma pose as the later ones do (before: 0 iterations, ``time_budget``, every first solve), a first
    CMA-ES solve with a 0.5 s budget runs its 40 generations (before: 1, the import ate the budget), and a first
    solve starting from the closed form reaches the pose within its budget too."""
    import json
    import subprocess
    import sys

    from tests.conftest import same_framework_env

    out = subprocess.run([sys.executable, "-c", FIRST_SOLVES], env=same_framework_env(), capture_output=True,
                         text=True, timeout=900, check=True)
    report = json.loads(out.stdout.strip().splitlines()[-1])
    assert [run[:2] for run in report["engine"]] == [[True, "tolerance"]] * 3, report
    assert all(run[2] > 0 for run in report["engine"])
    assert report["seeded"] == [True, "closed form", "tolerance"], report
    assert report["cmaes"] == ["max_iterations", 40], report
