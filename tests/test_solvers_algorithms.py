"""Per-algorithm properties: evaluation accounting, shared operators, parameter schedules."""

from __future__ import annotations

import numpy as np
import pytest

from framework.solvers import Box, available_solvers, get_solver, minimize
from framework.optimizers.cs import levy_steps
from framework.optimizers.population import binomial_crossover, distinct_indices
from framework.optimizers.sde import SDE

N = 6
BOX = Box(np.full(N, -1.0), np.full(N, 1.0))


def sphere(X: np.ndarray) -> np.ndarray:
    return np.sum((X - 0.3) ** 2, axis=1)


# Candidates evaluated per generation, and before the first generation, for population 20.
EVALUATIONS = {
    "cmaes": (20, 0),
    "cmaes_fast": (20, 0),
    "de": (20, 20),
    "sde": (20, 20),
    "pso": (20, 20),
    "impso": (20, 20),
    "qpso": (20, 20),
    "dempso": (40, 20),
    "cs": (40, 20),
    "cpabc": (20, 10),
    "hbbo": (20, 20),
    "ica": (20, 20),
    "tlbo": (40, 20),
    "itlbo": (40, 20),
    "woa": (20, 20),
    "sca": (20, 20),
}


@pytest.mark.parametrize("solver", available_solvers())
def test_evaluations_per_iteration_are_as_documented(solver):
    per_generation, initial = EVALUATIONS[solver]
    result = minimize(
        sphere, BOX, solver=solver, rng=np.random.default_rng(0), max_iterations=7, population=20
    )
    assert result.evaluations == initial + 7 * per_generation


@pytest.mark.parametrize("solver", available_solvers())
def test_every_solver_declares_documented_defaults(solver):
    cls = get_solver(solver)
    assert cls.name == solver
    assert cls.__doc__ and cls.__module__
    for key in cls.DEFAULTS:
        assert key in cls.__doc__, f"{solver}: option {key!r} not documented"


def test_distinct_indices_exclude_self_and_repeat_nothing():
    idx = distinct_indices(np.random.default_rng(0), 7, 3, rows=700)
    assert idx.shape == (700, 3) and idx.min() >= 0 and idx.max() <= 6
    assert np.all(idx != (np.arange(700) % 7)[:, None])
    assert np.all((idx[:, 0] != idx[:, 1]) & (idx[:, 1] != idx[:, 2]) & (idx[:, 0] != idx[:, 2]))
    assert len(np.unique(idx)) == 7  # every index is used


def test_binomial_crossover_takes_at_least_one_mutant_coordinate():
    rng = np.random.default_rng(0)
    target, mutant = np.zeros((500, 4)), np.ones((500, 4))
    trial = binomial_crossover(target, mutant, 0.0, rng)
    np.testing.assert_array_equal(trial.sum(axis=1), 1.0)
    assert binomial_crossover(target, mutant, 1.0, rng).min() == 1.0


def test_levy_steps_are_heavy_tailed():
    steps = levy_steps(np.random.default_rng(0), (200_000,), 1.5)
    gaussian = np.random.default_rng(1).standard_normal(200_000)
    assert np.median(np.abs(steps)) < 2
    assert np.quantile(np.abs(steps), 0.9999) > 10 * np.quantile(np.abs(gaussian), 0.9999)


def test_jde_parameters_self_adapt_within_their_ranges():
    algo = SDE(N, BOX, 20, np.random.default_rng(0))
    for _ in range(60):
        X = algo.ask()
        algo.tell(X, sphere(X))
    assert np.all((algo.F_i >= 0.1) & (algo.F_i <= 1.0))
    assert np.all((algo.CR_i >= 0.0) & (algo.CR_i <= 1.0))
    assert len(np.unique(algo.F_i)) > 1  # some individuals adopted regenerated values


@pytest.mark.parametrize("solver", ["de", "pso", "cmaes_fast", "ica", "cpabc"])
def test_bounds_none_lets_the_cost_see_out_of_box_candidates(solver):
    seen = []

    def cost(X):
        seen.append(X.copy())
        return np.sum((X - 3.0) ** 2, axis=1)  # optimum outside the box, pulls candidates out

    minimize(cost, BOX, solver=solver, rng=np.random.default_rng(0), max_iterations=30, bounds="none")
    assert not np.all(BOX.contains(np.vstack(seen)))
