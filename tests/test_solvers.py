"""Tests of framework.solvers: the shared loop, the box, repair, the registry and every registered solver."""

from __future__ import annotations

import numpy as np
import pytest

from framework.errors import LimitsError, SolverError
from framework.solvers import Box, OptimizeResult, available_solvers, get_solver, minimize, repair

N = 13
BOX = Box(np.full(N, -5.0), np.full(N, 5.0))
SHIFT = np.linspace(-2.0, 2.5, N)  # optimum of the shifted sphere, inside BOX and not at its centre
CORE = ["cmaes", "cmaes_fast", "de", "sde"]


def shifted_sphere(X: np.ndarray) -> np.ndarray:
    return np.sum((X - SHIFT) ** 2, axis=1)


def rosenbrock(X: np.ndarray) -> np.ndarray:
    return np.sum(100.0 * (X[:, 1:] - X[:, :-1] ** 2) ** 2 + (1.0 - X[:, :-1]) ** 2, axis=1)


class Recorder:
    """A population cost that remembers every evaluated row."""

    def __init__(self, cost):
        self.cost = cost
        self.rows: list[np.ndarray] = []

    def __call__(self, X: np.ndarray) -> np.ndarray:
        self.rows.append(X.copy())
        return self.cost(X)

    @property
    def all(self) -> np.ndarray:
        return np.vstack(self.rows)


# Accuracy every solver reaches on the shifted 13-D sphere (box [-5, 5]^13, optimum value 0) within
# 300 iterations of population 30, for both bounds modes (observed values are 10-1000x lower). Random search with
# the same 9,000 evaluations reaches f of about 13-29 (RANDOM below computes it): every stated bound is at least
# 100x below it (test_stated_accuracies_are_well_below_random_search). WOA and SCA move relative to C x*
# (C ~ U(0, 2)), which biases them toward the coordinate origin: on a shifted optimum they are poor (as in paper
# 002; measured 0.3-9 and 2-18) and are only held to beat random search there (``None``); on a centred sphere,
# below, they are held to 1e-4.
SPHERE_ACCURACY = {
    "cmaes": 1e-10,
    "cmaes_fast": 1e-10,
    "de": 1e-5,
    "sde": 1e-8,
    "pso": 1e-8,
    "qpso": 1e-4,
    "impso": 1e-1,
    "cs": 1e-1,
    "cpabc": 1e-7,
    "dempso": 1e-6,
    "hbbo": 1e-1,
    "ica": 1e-7,
    "tlbo": 1e-10,
    "itlbo": 1e-10,
    "woa": None,
    "sca": None,
}
ITERATIONS, POPULATION = 300, 30


def centred_sphere(X: np.ndarray) -> np.ndarray:
    return np.sum(X**2, axis=1)


def random_search(cost, evaluations: int = ITERATIONS * POPULATION, seed: int = 2026) -> float:
    """The best value of ``evaluations`` uniform samples of BOX: what a method without any search reaches."""
    rng = np.random.default_rng(seed)
    return float(cost(rng.uniform(BOX.lower, BOX.upper, (evaluations, N))).min())


RANDOM = {"shifted": random_search(shifted_sphere), "centred": random_search(centred_sphere)}


def test_every_registered_solver_has_a_stated_sphere_accuracy():
    assert set(CORE) <= set(available_solvers())
    assert set(available_solvers()) <= set(SPHERE_ACCURACY)


def test_stated_accuracies_are_well_below_random_search():
    assert 10.0 < RANDOM["shifted"] < 40.0 and 5.0 < RANDOM["centred"] < 30.0  # the reference itself
    for solver, accuracy in SPHERE_ACCURACY.items():
        assert accuracy is None or accuracy <= RANDOM["shifted"] / 100, solver
    assert 1e-4 <= RANDOM["centred"] / 1e4  # the centred-sphere bound of WOA and SCA below


@pytest.mark.parametrize("bounds", ["resample", "clip"])
@pytest.mark.parametrize("solver", available_solvers())
def test_solver_reduces_sphere_and_respects_bounds(solver, bounds):
    cost = Recorder(shifted_sphere)
    target = SPHERE_ACCURACY[solver]
    result = minimize(
        cost,
        BOX,
        solver=solver,
        rng=np.random.default_rng(7),
        max_iterations=ITERATIONS,
        f_target=target or 0.0,
        bounds=bounds,
    )
    bound = RANDOM["shifted"] if target is None else target
    assert result.f <= bound, f"{solver}: f = {result.f:.3e} > {bound:.3e} (random search: {RANDOM['shifted']:.1f})"
    X = cost.all
    assert X.shape == (result.evaluations, N)
    assert np.all(BOX.contains(X)), f"{solver} evaluated candidates outside the box"
    assert result.f == pytest.approx(float(shifted_sphere(result.x[None])[0]), rel=0, abs=0)
    assert np.all(np.diff(result.history) <= 0)


@pytest.mark.parametrize("solver", ["woa", "sca"])
def test_origin_biased_solvers_solve_a_centred_sphere(solver):
    result = minimize(
        centred_sphere, BOX, solver=solver, rng=np.random.default_rng(7), max_iterations=ITERATIONS, bounds="clip"
    )
    assert result.f < 1e-4  # random search with the same evaluations: RANDOM["centred"], about 23


@pytest.mark.parametrize("solver", CORE)
def test_core_solvers_solve_shifted_sphere_to_1e_10(solver):
    result = minimize(
        shifted_sphere, BOX, solver=solver, rng=np.random.default_rng(1), max_iterations=1500, f_target=1e-11
    )
    assert result.f < 1e-10
    assert np.max(np.abs(result.x - SHIFT)) < 1e-5


@pytest.mark.parametrize("solver", CORE)
def test_core_solvers_solve_rosenbrock_5d(solver):
    box = Box(np.full(5, -5.0), np.full(5, 5.0))
    result = minimize(
        rosenbrock, box, solver=solver, rng=np.random.default_rng(3), max_iterations=1000, f_target=1e-10
    )
    assert result.f <= 1e-10
    np.testing.assert_allclose(result.x, np.ones(5), atol=1e-4)


@pytest.mark.parametrize("solver", available_solvers())
def test_same_seed_same_result_different_seed_different_result(solver):
    def run(seed):
        return minimize(
            shifted_sphere, BOX, solver=solver, rng=np.random.default_rng(seed), max_iterations=15
        )

    a, b, c = run(11), run(11), run(12)
    np.testing.assert_array_equal(a.x, b.x)
    np.testing.assert_array_equal(a.history, b.history)
    assert a.evaluations == b.evaluations
    assert not np.array_equal(a.history, c.history)


@pytest.mark.parametrize("solver", available_solvers())
def test_warm_start_at_the_optimum_gives_zero_in_the_first_iteration(solver):
    result = minimize(
        shifted_sphere,
        BOX,
        solver=solver,
        rng=np.random.default_rng(0),
        max_iterations=3,
        initial=SHIFT[None, :],
    )
    assert result.history[0] == 0.0
    np.testing.assert_array_equal(result.x, SHIFT)


def test_f_target_stops_early():
    result = minimize(
        shifted_sphere, BOX, solver="de", rng=np.random.default_rng(0), max_iterations=1000, f_target=1e-2
    )
    assert result.stop_reason == "f_target"
    assert result.f <= 1e-2
    assert result.iterations < 1000
    assert result.history[-1] <= 1e-2 < result.history[-2]


def test_max_evaluations_stops():
    result = minimize(shifted_sphere, BOX, solver="de", rng=np.random.default_rng(0), max_evaluations=100)
    assert result.stop_reason == "max_evaluations"
    assert 100 <= result.evaluations < 100 + 30


def test_stagnation_stops_on_a_flat_cost():
    def flat(X):
        return np.ones(X.shape[0])

    result = minimize(
        flat, BOX, solver="cmaes_fast", rng=np.random.default_rng(0), max_iterations=500, stagnation=10
    )
    assert result.stop_reason == "stagnation"
    assert result.iterations == 11  # the first iteration improves on +inf, then 10 without improvement


def test_callback_sees_each_iteration_and_can_stop():
    seen = []

    def callback(iteration, best_f, best_x):
        seen.append((iteration, best_f, best_x.shape))
        return iteration == 4

    result = minimize(shifted_sphere, BOX, solver="sde", rng=np.random.default_rng(0), callback=callback)
    assert result.stop_reason == "callback"
    assert [s[0] for s in seen] == [1, 2, 3, 4]
    assert [s[1] for s in seen] == result.history.tolist()
    assert seen[0][2] == (N,)


def test_result_record_counts_evaluations_and_settings():
    result = minimize(
        shifted_sphere, BOX, solver="de", rng=np.random.default_rng(0), max_iterations=20, population=12
    )
    assert isinstance(result, OptimizeResult)
    assert result.iterations == 20 and result.history.shape == (20,)
    assert result.evaluations == 12 * 21  # initial population + 20 generations
    assert result.stop_reason == "max_iterations"
    assert result.solver == "de" and result.wall_time > 0
    assert result.settings["F"] == 0.6 and result.settings["CR"] == 0.9
    assert result.settings["population"] == 12 and result.settings["bounds"] == "resample"


def test_options_override_defaults():
    result = minimize(
        shifted_sphere, BOX, solver="de", rng=np.random.default_rng(0), max_iterations=2, options={"F": 0.8}
    )
    assert result.settings["F"] == 0.8 and result.settings["CR"] == 0.9


def test_keyboard_interrupt_returns_best_so_far():
    calls = {"n": 0}

    def cost(X):
        calls["n"] += 1
        if calls["n"] == 4:
            raise KeyboardInterrupt
        return shifted_sphere(X)

    result = minimize(cost, BOX, solver="cmaes_fast", rng=np.random.default_rng(0), max_iterations=100)
    assert result.stop_reason == "interrupted"
    assert result.iterations == 3 and result.evaluations == 90
    assert np.isfinite(result.f) and result.f == result.history[-1]


def test_out_of_reach_target_runs_out_the_budget():
    # The optimum (10, ..., 10) is outside the box: the solver ends on the boundary, no error, no hang.
    def cost(X):
        return np.sum((X - 10.0) ** 2, axis=1)

    result = minimize(
        cost, BOX, solver="de", rng=np.random.default_rng(0), max_iterations=200, f_target=1e-8, bounds="clip"
    )
    assert result.stop_reason == "max_iterations" and result.iterations == 200
    assert result.f == pytest.approx(N * 25.0, rel=1e-3)


def test_nan_costs_count_as_infinite():
    def cost(X):
        F = shifted_sphere(X)
        F[::2] = np.nan
        return F

    result = minimize(cost, BOX, solver="de", rng=np.random.default_rng(0), max_iterations=50)
    assert np.isfinite(result.f)


def test_cost_with_wrong_shape_raises():
    with pytest.raises(SolverError, match="shape"):
        minimize(lambda X: np.zeros((X.shape[0], 2)), BOX, solver="de", rng=np.random.default_rng(0))


def test_unknown_solver_raises_and_lists_names():
    with pytest.raises(SolverError, match="cmaes"):
        minimize(shifted_sphere, BOX, solver="nope", rng=np.random.default_rng(0))
    with pytest.raises(SolverError):
        get_solver("nope")


def test_unknown_option_raises():
    with pytest.raises(SolverError, match="F_typo"):
        minimize(shifted_sphere, BOX, solver="de", rng=np.random.default_rng(0), options={"F_typo": 1.0})


@pytest.mark.parametrize(
    "kwargs",
    [
        {"bounds": "wrap"},
        {"max_iterations": 0},
        {"population": 3},
        {"stagnation": 0},
        {"initial": np.zeros(N + 1)},
    ],
)
def test_bad_settings_raise(kwargs):
    with pytest.raises(SolverError):
        minimize(shifted_sphere, BOX, **{"solver": "de", "rng": np.random.default_rng(0), **kwargs})


def test_global_numpy_random_state_is_untouched():
    np.random.seed(123)
    before = np.random.get_state()[1].copy()
    minimize(shifted_sphere, BOX, solver="cmaes", rng=np.random.default_rng(0), max_iterations=5)
    np.testing.assert_array_equal(np.random.get_state()[1], before)


@pytest.mark.parametrize(
    "lower, upper",
    [([0.0, 1.0], [1.0, 0.5]), ([0.0, 0.0], [0.0, 1.0]), ([0.0, -np.inf], [1.0, 1.0]), ([0.0], [1.0, 2.0])],
)
def test_invalid_box_raises_limits_error(lower, upper):
    with pytest.raises(LimitsError):
        Box(np.array(lower), np.array(upper))


def test_inverted_box_raises_through_minimize():
    with pytest.raises(LimitsError):
        minimize(
            shifted_sphere, (np.full(N, 1.0), np.full(N, -1.0)), solver="de", rng=np.random.default_rng(0)
        )


def test_repair_modes():
    rng = np.random.default_rng(0)
    box = Box(np.zeros(3), np.ones(3))
    X = np.array([[0.5, 0.5, 0.5], [1.5, 0.5, 0.5], [0.2, -1.0, np.nan]])
    resampled = repair(X, box, rng, "resample")
    np.testing.assert_array_equal(resampled[0], X[0])  # feasible rows untouched
    assert np.all(box.contains(resampled))
    assert resampled[1, 1] != 0.5 and resampled[2, 0] != 0.2  # the whole infeasible row is re-sampled
    clipped = repair(X[:2], box, rng, "clip")
    np.testing.assert_array_equal(clipped, [[0.5, 0.5, 0.5], [1.0, 0.5, 0.5]])
    assert repair(X, box, rng, "none") is X
    with pytest.raises(SolverError):
        repair(X, box, rng, "reflect")


def test_progress_prints_a_few_lines_to_stderr(capsys):
    minimize(
        shifted_sphere, BOX, solver="de", rng=np.random.default_rng(0), max_iterations=100, progress=True
    )
    lines = capsys.readouterr().err.strip().splitlines()
    assert 2 <= len(lines) <= 21
    assert "iteration 100/100" in lines[-1]


def test_solver_names_are_one_name_space():
    """A metaheuristic named like an IK solver (or the reverse) would shadow it in solve(): refused, by name."""
    from framework.solvers import register, register_ik
    from framework.optimizers.registry import ALGORITHMS as SOLVERS
    from framework.solvers.registry import IK_SOLVERS

    before = (dict(SOLVERS), dict(IK_SOLVERS))
    with pytest.raises(SolverError, match="'hybrid' is already registered"):
        register("hybrid")(type("Shadow", (get_solver("de"),), {}))
    with pytest.raises(SolverError, match="'de' is already registered"):
        register_ik("de")(type("Shadow", (), {}))
    assert (SOLVERS, IK_SOLVERS) == before  # nothing half-registered
    assert register("de")(get_solver("de")) is get_solver("de")  # the same class again is not a collision
