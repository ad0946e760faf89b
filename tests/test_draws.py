"""The engine's restart stream: SplitMix64 as published, uniform in the box, seeded, independent per seed."""

import numpy as np
import pytest
from scipy import stats

from framework.engine.draws import draws, stream, uniform
from tests.compiled import python_callable

uniform = python_callable(uniform)
from framework.errors import SolverError

MASK = 2**64 - 1


def splitmix64(seed: int, count: int) -> list[int]:
    """Reference SplitMix64 in Python integers (Steele, Lea & Flood 2014; Vigna's splitmix64.c)."""
    out, state = [], seed
    for _ in range(count):
        state = (state + 0x9E3779B97F4A7C15) & MASK
        z = state
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & MASK
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & MASK
        out.append(z ^ (z >> 31))
    return out


@pytest.mark.parametrize("seed", [0, 1, 12345, 2**63 + 7])
def test_stream_equals_the_reference_splitmix64(seed):
    state = stream(seed)
    expected = [(z >> 11) * 2.0**-53 for z in splitmix64(seed, 100)]
    assert [uniform(state) for _ in range(100)] == expected


def test_first_output_of_seed_zero_is_the_published_one():
    # splitmix64.c's first output from state 0 (also the first word xoshiro's reference seeding produces)
    assert splitmix64(0, 1)[0] == 0xE220A8397B1DCDAF


def test_draws_are_uniform_in_the_box_and_uncorrelated():
    lower, upper = np.array([-np.pi, 0.0, -0.5]), np.array([np.pi, 2.0, 0.25])
    X = draws(stream(2026), lower, upper, 20_000)
    assert np.all(X >= lower) and np.all(X < upper)
    for i in range(3):  # each coordinate uniform on its interval (a fixed seed: the p-values are fixed numbers)
        assert stats.kstest(X[:, i], "uniform", args=(lower[i], upper[i] - lower[i])).pvalue > 0.01
    U = (X - lower) / (upper - lower)
    # coordinates of one draw and successive draws uncorrelated (|r| of 20,000 independent pairs: ~0.007 sd)
    assert abs(np.corrcoef(U[:, 0], U[:, 1])[0, 1]) < 0.03
    assert abs(np.corrcoef(U[:-1, 0], U[1:, 0])[0, 1]) < 0.03


def test_same_seed_same_draws_other_seed_other_draws():
    box = np.zeros(4), np.ones(4)
    a, b, c = draws(stream(5), *box, 10), draws(stream(5), *box, 10), draws(stream(6), *box, 10)
    np.testing.assert_array_equal(a, b)
    assert not np.any(np.isclose(a, c))
    state = stream(5)
    first, second = draws(state, *box, 5), draws(state, *box, 5)  # a stream advances: no repeats
    np.testing.assert_array_equal(np.vstack([first, second]), a)


def test_stream_from_a_generator_and_bad_seeds():
    g1, g2 = np.random.default_rng(3), np.random.default_rng(3)
    np.testing.assert_array_equal(stream(g1), stream(g2))
    for bad in (-1, 1.5, "3", True):
        with pytest.raises(SolverError, match="seed"):
            stream(bad)
