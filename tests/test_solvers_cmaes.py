"""cmaes_fast (own numpy CMA-ES) against cmaes (pycma): equivalent outcome, not bitwise equality."""

from __future__ import annotations

import numpy as np
import pytest

from framework.solvers import Box, minimize

N = 13
BOX = Box(np.full(N, -5.0), np.full(N, 5.0))
SHIFT = np.linspace(-2.0, 2.5, N)
SEEDS = range(4)
F_TARGET = 1e-10
#: Median iterations-to-target of the two implementations must agree within this factor.
FACTOR = 1.5


def sphere(X: np.ndarray) -> np.ndarray:
    return np.sum((X - SHIFT) ** 2, axis=1)


def rosenbrock(X: np.ndarray) -> np.ndarray:
    return np.sum(100.0 * (X[:, 1:] - X[:, :-1] ** 2) ** 2 + (1.0 - X[:, :-1]) ** 2, axis=1)


def ellipsoid(X: np.ndarray) -> np.ndarray:  # condition number 1e6
    return np.sum(10.0 ** (6.0 * np.arange(N) / (N - 1)) * (X - SHIFT) ** 2, axis=1)


def iterations_to_target(solver: str, cost) -> list[int]:
    runs = [
        minimize(
            cost, BOX, solver=solver, rng=np.random.default_rng(s), max_iterations=1500, f_target=F_TARGET
        )
        for s in SEEDS
    ]
    assert all(r.stop_reason == "f_target" for r in runs), [(r.stop_reason, r.f) for r in runs]
    return [r.iterations for r in runs]


@pytest.mark.parametrize("cost", [sphere, rosenbrock, ellipsoid], ids=lambda c: c.__name__)
def test_cmaes_fast_matches_pycma_in_outcome(cost):
    fast = np.median(iterations_to_target("cmaes_fast", cost))
    reference = np.median(iterations_to_target("cmaes", cost))
    assert 1 / FACTOR <= fast / reference <= FACTOR, (fast, reference)


def test_cmaes_fast_is_faster_per_iteration():
    def run(solver):
        return minimize(sphere, BOX, solver=solver, rng=np.random.default_rng(0), max_iterations=100)

    fast, reference = run("cmaes_fast"), run("cmaes")
    assert fast.wall_time < reference.wall_time


def test_cmaes_warm_start_injects_the_initial_points():
    initial = np.vstack([SHIFT, SHIFT + 0.1])
    for solver in ("cmaes", "cmaes_fast"):
        seen = []

        def cost(X, seen=seen):
            seen.append(X.copy())
            return sphere(X)

        minimize(cost, BOX, solver=solver, rng=np.random.default_rng(0), max_iterations=1, initial=initial)
        np.testing.assert_array_equal(seen[0][:2], initial)


def test_cmaes_fast_starts_from_a_given_covariance_and_hands_its_shape_on():
    """A covariance adapted on one problem (the state of a run) speeds up a run on the same ill-conditioned one."""
    first = minimize(ellipsoid, BOX, solver="cmaes_fast", rng=np.random.default_rng(0), max_iterations=400)
    C = first.state["covariance"]
    np.testing.assert_allclose(C, C.T)
    assert np.linalg.eigvalsh(C)[-1] == pytest.approx(1.0) and np.linalg.eigvalsh(C)[0] > 0
    assert first.settings["covariance"] is None
    start = SHIFT + 0.01
    runs = {
        name: minimize(ellipsoid, BOX, solver="cmaes_fast", rng=np.random.default_rng(1), max_iterations=1500,
                       f_target=F_TARGET, initial=start, options={"sigma0": 0.01, "covariance": cov})
        for name, cov in (("given", C), ("identity", None))
    }
    assert runs["given"].settings["covariance"] == "given"
    assert runs["given"].stop_reason == runs["identity"].stop_reason == "f_target"
    assert runs["given"].iterations < 0.5 * runs["identity"].iterations


@pytest.mark.parametrize("covariance", [np.eye(N - 1), np.triu(np.ones((N, N))), -np.eye(N), np.full((N, N), np.nan)])
def test_cmaes_fast_rejects_a_bad_covariance(covariance):
    from framework.errors import SolverError

    with pytest.raises(SolverError, match="covariance"):
        minimize(sphere, BOX, solver="cmaes_fast", rng=np.random.default_rng(0), max_iterations=2,
                 options={"covariance": covariance})


@pytest.mark.parametrize("bounds", ["resample", "clip", "penalty"])
def test_compiled_loop_is_the_ask_tell_loop(bounds):
    """``solve(problem, "cmaes_fast")`` runs the whole loop compiled; it must give bitwise the same generations as
    the shared Python loop ``minimize`` (same random numbers, repairs, updates), warm start included."""
    import framework as fw
    from framework.costs.problem import Problem
    from framework.solvers.solve import solve
    from framework.solvers import minimize

    robot = fw.load_robot("youbot_dual_mobile")
    prev = robot.middle
    problem = Problem(robot, 1.2 * fw.Position("arm1_ee", [0.5, -0.2, 0.45]) + 0.4 * fw.Motion("all", prev),
                      bounds=bounds, priorities=False)  # the weighted sum: the compiled loop's cost
    compiled = solve(problem, "cmaes_fast", seed=4, max_iterations=120, initial=prev)
    loop = minimize(problem.cost, (robot.lower, robot.upper), solver="cmaes_fast", rng=np.random.default_rng(4),
                    max_iterations=120, population=30, initial=prev[None], bounds=problem.repair_mode)
    np.testing.assert_array_equal(compiled.configuration, loop.x)
    np.testing.assert_array_equal(compiled.history, loop.history)
    np.testing.assert_array_equal(compiled.state["covariance"], loop.state["covariance"])
    assert compiled.evaluations == loop.evaluations
