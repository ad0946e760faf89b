"""The inlined sine and cosine against libm's (numpy's np.sin / np.cos, correctly rounded or within one unit in the
last place themselves)."""

from __future__ import annotations

import numba
import numpy as np

from framework.compiled.trig import REDUCED, sincos


@numba.njit  # (not cached: a cached caller would keep an old inlined sincos)
def _both(x):
    s, c = np.empty_like(x), np.empty_like(x)
    for k in range(x.shape[0]):
        s[k], c[k] = sincos(x[k])
    return s, c


def _ulps(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``|a − b|`` in units in the last place of ``b`` (the smallest subnormal for zeros)."""
    return np.abs(a - b) / np.maximum(np.spacing(np.abs(b)), np.finfo(float).smallest_subnormal)


def test_within_one_ulp_of_libm_over_joint_ranges_and_beyond():
    rng = np.random.default_rng(7)
    x = np.concatenate([
        rng.uniform(-4 * np.pi, 4 * np.pi, 200_000),  # joint angles, continuous joints after a few turns
        rng.uniform(-REDUCED, REDUCED, 100_000),
        rng.uniform(-1e-6, 1e-6, 20_000),  # tiny angles
        np.arange(-64, 65) * (np.pi / 4),  # quadrant boundaries and their neighbours
        np.nextafter(np.arange(-64, 65) * (np.pi / 2), np.inf),
        np.arange(-40_000, 40_000) * (np.pi / 2),  # near multiples of π/2: tiny results, reduced in three parts
        [0.0, -0.0, 5e-324, np.pi, -np.pi, 2 * np.pi],
    ])
    s, c = _both(x)
    # a trivial approximation (sin x ≈ x on the reduced angle, no polynomial) is off by ~1e15 ulps at 0.5 rad;
    # a reduction by π/2 in two parts only, by up to 3.4e9 ulps near multiples of π/2
    assert _ulps(s, np.sin(x)).max() <= 1.0
    assert _ulps(c, np.cos(x)).max() <= 1.0


def test_beyond_the_reduction_nan_and_inf_follow_libm():
    x = np.array([REDUCED * 1.0001, -3e7, 1e300, np.nan, np.inf, -np.inf])
    s, c = _both(x)
    np.testing.assert_array_equal(s, np.sin(x))
    np.testing.assert_array_equal(c, np.cos(x))
