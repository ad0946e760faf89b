"""The compiled loops' small dense linear algebra against numpy and scipy: the damped Gauss-Newton steps of the
reaching loop, null spaces, symmetric eigenproblems and the trust-region subproblem of the Newton phase."""

import numpy as np
import pytest
import scipy.optimize as so

from framework.engine import linalg
from framework.engine.linalg import DENSE_ROWS
from tests.compiled import python_callable

least_norm_step, levenberg_marquardt_step, moving_columns, moving_columns_step, null_space, symmetric_eigen, \
    trust_region_step = (python_callable(getattr(linalg, name)) for name in (
        "least_norm_step", "levenberg_marquardt_step", "moving_columns", "moving_columns_step", "null_space",
        "symmetric_eigen", "trust_region_step"))


def test_damped_steps_solve_their_normal_equations_and_both_summations_give_the_same_numbers(rng):
    """``dx = −(JᵀJ + λI)⁻¹Jᵀr`` and ``dx = −Jᵀ(JJᵀ + λI)⁻¹r`` against numpy's solve of the same systems (a step of
    zeros, what a loop that did nothing returns, is off by ``‖dx‖``, of order one here). A short stack is summed
    entry by entry, a long one row by row skipping zero rows: the short stack padded with zero rows past
    :data:`DENSE_ROWS` per coordinate takes the second way and must give bit for bit the same step."""
    for trial in range(200):
        n = int(rng.integers(1, 10))
        m = int(rng.integers(n, DENSE_ROWS * n + 1))
        J, r, damping = rng.normal(size=(m, n)), rng.normal(size=m), float(10.0 ** rng.uniform(-12, 0))
        if trial % 4 == 0:
            J[rng.random(size=(m, n)) < 0.2] = 0.0  # zero entries (a coordinate that does not move a block)
        A, L, g, dx = np.empty((n, n)), np.empty((n, n)), np.empty(n), np.empty(n)
        assert levenberg_marquardt_step(J, r, damping, A, L, g, dx)
        expected = -np.linalg.solve(J.T @ J + damping * np.eye(n), J.T @ r)
        np.testing.assert_allclose(dx, expected, rtol=1e-7, atol=1e-9 * np.abs(expected).max())
        padded_J = np.vstack([J, np.zeros((DENSE_ROWS * n + 1 - m, n))])
        padded_r = np.concatenate([r, np.zeros(DENSE_ROWS * n + 1 - m)])
        rows_dx = np.empty(n)
        assert levenberg_marquardt_step(padded_J, padded_r, damping, A, L, g, rows_dx)
        assert np.array_equal(rows_dx, dx)
        k = int(rng.integers(1, n + 1))  # fewer rows than coordinates: the least-norm form
        Jk, rk, y, step = J[:k], r[:k].copy(), np.empty(k), np.empty(n)
        assert least_norm_step(Jk, rk, damping, np.empty((k, k)), np.empty((k, k)), y, step)
        expected = -Jk.T @ np.linalg.solve(Jk @ Jk.T + damping * np.eye(k), rk)
        np.testing.assert_allclose(step, expected, rtol=1e-7, atol=1e-9 * np.abs(expected).max())


def test_the_step_over_moving_columns_is_the_damped_step_and_survives_where_j_jt_is_singular(rng):
    """Rows that only some coordinates move (a pose of one leg of a whole quadruped: six rows, three columns
    nonzero among twelve): the step over the moving columns equals numpy's ``−(JᵀJ + λI)⁻¹Jᵀr`` over all of them
    (zero on the others), and, lightly damped where ``J Jᵀ`` is singular (rank 3 of 6), it is still the Gauss-Newton
    step ``J dx = −r`` of a consistent system to rounding, where the least-norm form's Cholesky of ``J Jᵀ + λI``
    fails or returns a step that misses by orders of magnitude."""
    least_norm_misses = 0
    for trial in range(100):
        n, m = int(rng.integers(4, 14)), int(rng.integers(2, 7))
        nz = int(rng.integers(1, min(m, n - 1) + 1))
        J = np.zeros((m, n))
        moving = np.sort(rng.choice(n, size=nz, replace=False))
        J[:, moving] = rng.normal(size=(m, nz))
        assert moving_columns(J, n) == nz and moving_columns(J, nz - 1) == nz and moving_columns(J, 0) == 1
        r = rng.normal(size=m)
        damping = float(10.0 ** rng.uniform(-6, 0))
        dx = np.empty(n)
        assert moving_columns_step(J, r, damping, np.empty((nz, nz)), np.empty((nz, nz)), np.empty(nz), dx, nz)
        expected = -np.linalg.solve(J.T @ J + damping * np.eye(n), J.T @ r)
        np.testing.assert_allclose(dx, expected, rtol=1e-7, atol=1e-9 * np.abs(expected).max())
        assert np.all(dx[np.setdiff1d(np.arange(n), moving)] == 0.0)
        r_consistent = J @ rng.normal(size=n)  # a reachable target: J dx = −r solvable
        assert moving_columns_step(J, r_consistent, 1e-30, np.empty((nz, nz)), np.empty((nz, nz)), np.empty(nz), dx,
                                   nz)
        assert np.linalg.norm(J @ dx + r_consistent) <= 1e-12 * np.linalg.norm(r_consistent)
        if nz < m:
            y, step = np.empty(m), np.empty(n)
            ok = least_norm_step(J, r_consistent, 1e-30, np.empty((m, m)), np.empty((m, m)), y, step)
            least_norm_misses += not ok or not np.linalg.norm(J @ step + r_consistent) <= 1e-9 * np.linalg.norm(
                r_consistent)
    assert least_norm_misses >= 10  # the polish of the reaching loop met this before (measured: 60 of 68)


def test_null_space_is_orthonormal_and_has_the_dimension_numpy_ranks(rng):
    """Random matrices (strided views of larger ones), a third with a redundant row (their rank one lower)."""
    for trial in range(100):
        m, k = int(rng.integers(1, 8)), int(rng.integers(1, 14))
        A = rng.normal(size=(m, k + 3))
        if m > 2 and trial % 3 == 0:
            A[-1] = 2.0 * A[0] - A[1]
        cols = rng.permutation(k + 3)[:k].astype(np.int64)
        W, V, beta, Z = np.empty((k, m)), np.empty((k, m)), np.empty(m), np.empty((k, k))
        nz = null_space(A[:, cols], W, V, beta, Z)
        assert nz == k - np.linalg.matrix_rank(A[:, cols])
        if nz:
            assert np.abs(A[:, cols] @ Z[:, :nz]).max() < 1e-12  # a random basis: ~1
            np.testing.assert_allclose(Z[:, :nz].T @ Z[:, :nz], np.eye(nz), atol=1e-12)


def test_symmetric_eigen_matches_numpy(rng):
    for k in (1, 2, 5, 13):
        for _ in range(20):
            S = rng.normal(size=(k, k))
            S = S + S.T
            if k > 2:
                S[:, 0] = S[0, :] = 0.0  # a zero eigenvalue and a decoupled block
            E, V, w = np.empty((k, k)), np.empty((k, k)), np.empty(k)
            symmetric_eigen(S, k, E, V, w)
            np.testing.assert_allclose(w, np.linalg.eigvalsh(S), atol=1e-12 * max(1.0, np.abs(w).max()))
            np.testing.assert_allclose(V @ np.diag(w) @ V.T, S, atol=1e-12 * max(1.0, np.abs(w).max()))
            np.testing.assert_allclose(V.T @ V, np.eye(k), atol=1e-12)


def _solve(S, g, radius):
    k = S.shape[0]
    E, V, w, c, p = np.empty((k, k)), np.empty((k, k)), np.empty(k), np.empty(k), np.empty(k)
    symmetric_eigen(S, k, E, V, w)
    decrease = trust_region_step(w, V, g, k, radius, c, p)
    return p, decrease


def _model(S, g, p):
    return float(g @ p + 0.5 * p @ S @ p)


def _best_on_ball(S, g, radius, rng, starts=20):
    """The lowest model value scipy's SLSQP finds within ``‖p‖ ≤ radius`` from ``starts`` random starts (0: none)."""
    best = 0.0
    for _ in range(starts):
        start = rng.normal(size=S.shape[0])
        start *= rng.uniform(0, radius) / np.linalg.norm(start)
        s = so.minimize(lambda z: _model(S, g, z), start, method="SLSQP",
                        constraints=[{"type": "ineq", "fun": lambda z: radius**2 - z @ z}],
                        options={"ftol": 1e-14, "maxiter": 200})
        if s.x @ s.x <= radius**2 * (1 + 1e-9):
            best = min(best, s.fun)
    return best


@pytest.mark.parametrize("kind", ["definite", "indefinite", "saddle"])
def test_trust_region_step_is_the_models_minimum_on_the_ball(rng, kind):
    """Against scipy's SLSQP from 20 starts on the ball (its best), for positive definite models (inside and on the
    boundary), indefinite ones, and saddle points (g = 0, the hard case: the step goes along the lowest eigenvector
    to the boundary). The step returned is never worse than the best start, and its reported decrease is its model's
    (a step of zero decreases nothing: the minima found are all below zero)."""
    for _ in range(10):
        k = int(rng.integers(2, 8))
        Q, _ = np.linalg.qr(rng.normal(size=(k, k)))
        w = rng.uniform(0.1, 2.0, k) if kind == "definite" else rng.uniform(-1.0, 2.0, k)
        if kind != "definite":
            w[0] = -abs(w[0]) - 0.1
        S = Q @ np.diag(w) @ Q.T
        g = np.zeros(k) if kind == "saddle" else rng.normal(size=k)
        radius = float(rng.uniform(0.05, 2.0))
        p, decrease = _solve(S, g, radius)
        assert np.linalg.norm(p) <= radius * (1 + 1e-6)
        assert decrease == pytest.approx(-_model(S, g, p), abs=1e-12)
        best = _best_on_ball(S, g, radius, rng)
        assert best < -1e-6
        assert _model(S, g, p) <= best + 1e-9
        if kind == "saddle":
            assert np.linalg.norm(p) == pytest.approx(radius, rel=1e-9)
            assert decrease == pytest.approx(-0.5 * w.min() * radius**2, rel=1e-9)


def test_taken_views_are_the_buffers_entries_and_the_tangent_scratch_tiles_its_size():
    """``take`` gives C-contiguous views of consecutive entries (writes land where numpy's slicing says); the Newton
    phase's tangent scratch, taken from one buffer, covers exactly the entries its dry run from address 0 counts,
    each entry in one view."""
    import numba

    from framework.engine.tangent import tangent_scratch
    from framework.compiled.native import take

    @numba.njit
    def fill(buffer, start, rows, cols):
        view, at = take(buffer.ctypes.data + 8 * start, (rows, cols))
        for i in range(rows):
            for j in range(cols):
                view[i, j] = 100 * i + j
        tail, _ = take(at, 3)
        for i in range(3):
            tail[i] = -1.0
        return (at - buffer.ctypes.data) // 8

    buffer = np.zeros(40)
    assert fill(buffer, 5, 3, 4) == 17
    expected = np.zeros(40)
    expected[5:17] = (100 * np.arange(3)[:, None] + np.arange(4)).ravel()
    expected[17:20] = -1.0
    np.testing.assert_array_equal(buffer, expected)

    @numba.njit
    def bump(v):  # (1-D)
        for i in range(v.shape[0]):
            v[i] += 1.0
        return 1

    @numba.njit
    def bump2(v):  # (2-D)
        for i in range(v.shape[0]):
            for j in range(v.shape[1]):
                v[i, j] += 1.0
        return 1

    @numba.njit
    def mark(buffer, start, n, rows):
        size = tangent_scratch(0, n, rows)[1] // 8
        v, end = tangent_scratch(buffer.ctypes.data + 8 * start, n, rows)
        marked = (bump2(v.W) + bump2(v.Vh) + bump(v.beta) + bump2(v.Z) + bump2(v.HZ) + bump(v.hz) + bump(v.lz)
                  + bump2(v.E) + bump2(v.Vz) + bump(v.wz) + bump(v.gz) + bump(v.c) + bump(v.p) + bump(v.dn)
                  + bump(v.u) + bump(v.aa) + bump(v.la) + bump(v.ra) + bump(v.y))
        return marked, size, (end - buffer.ctypes.data) // 8 - start

    n, rows, start = 5, 3, 7
    buffer = np.zeros(start + 300)
    marked, size, used = mark(buffer, start, n, rows)
    assert marked == 19 and size == used == 2 * n * rows + 3 * rows + 6 * n * n + 6 * n + 2 * rows * rows
    np.testing.assert_array_equal(buffer[start:start + size], 1.0)  # each entry in exactly one view
    assert not buffer[:start].any() and not buffer[start + size:].any()
