"""framework.bench.stats: the sign test against scipy's exact binomial test, summaries against numpy."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import binomtest

from framework.errors import MetaikError
from framework.bench.stats import binomial_two_sided, sign_test, summarize


@pytest.mark.parametrize("n", [1, 2, 3, 7, 10, 31, 50, 64, 99, 100, 201])
def test_binomial_two_sided_matches_scipy_for_every_k(n):
    for k in range(n + 1):
        assert binomial_two_sided(k, n) == pytest.approx(binomtest(k, n, 0.5).pvalue, rel=1e-12, abs=1e-300)


def test_binomial_edge_cases():
    assert binomial_two_sided(0, 0) == 1.0
    assert binomial_two_sided(5, 10) == 1.0
    assert binomial_two_sided(0, 1) == 1.0
    assert (
        binomial_two_sided(0, 1000) > 0.0
    )  # exact arithmetic: no underflow for a representable value (~2e-301)
    with pytest.raises(MetaikError):
        binomial_two_sided(3, 2)


def test_sign_test_matches_scipy_on_random_paired_samples(rng):
    for _ in range(300):
        size = int(rng.integers(1, 120))
        a = rng.normal(size=size)
        b = a + rng.normal(loc=rng.uniform(-0.5, 0.5), size=size)
        ties = rng.random(size) < 0.15
        b[ties] = a[ties]
        test = sign_test(a, b)
        assert test.wins == np.sum(a < b) and test.losses == np.sum(a > b) and test.ties == np.sum(a == b)
        assert test.wins + test.losses + test.ties == size
        expected = 1.0 if test.n == 0 else binomtest(test.wins, test.n, 0.5).pvalue
        assert test.p_value == pytest.approx(expected, rel=1e-12, abs=1e-300)


def test_sign_test_tolerance_counts_near_equal_pairs_as_ties():
    a = np.array([1.0, 2.0, 3.0, 4.0])
    b = np.array([1.0 + 1e-12, 2.5, 2.0, 4.0])
    assert sign_test(a, b).ties == 1
    loose = sign_test(a, b, atol=1e-9)
    assert (loose.wins, loose.losses, loose.ties) == (1, 1, 2)


def test_sign_test_rejects_bad_samples():
    with pytest.raises(MetaikError, match="equal length"):
        sign_test([1.0, 2.0], [1.0])
    with pytest.raises(MetaikError, match="NaN"):
        sign_test([1.0, np.nan], [1.0, 2.0])


def test_summary_equals_numpy(rng):
    for size in (1, 2, 5, 100):
        x = rng.lognormal(size=size)
        s = summarize(x)
        assert s.count == size
        assert (
            s.mean == np.mean(x) and s.best == np.min(x) and s.worst == np.max(x) and s.median == np.median(x)
        )
        assert s.std == (np.std(x, ddof=1) if size > 1 else 0.0)
    with pytest.raises(MetaikError):
        summarize([])
