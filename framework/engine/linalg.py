"""Small dense linear algebra for the compiled solver loops: no BLAS call, no thread, no allocation.

The systems are small (a few to a few dozen unknowns) and solved thousands of times per second; LAPACK through
numpy costs more in call overhead (and, on a shared 2-core machine, in OpenBLAS threads) than the arithmetic.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def cholesky_solve(A, b, L, out) -> bool:
    """Solve ``A out = b`` for symmetric positive definite ``A (k, k)`` by Cholesky into ``out (k,)``.

    ``L (k, k)`` is scratch (its diagonal holds the reciprocals of the factor's). Returns False (``out``
    undefined) when ``A`` is not numerically positive definite.
    """
    k = A.shape[0]
    for j in range(k):  # column by column; the diagonal of L holds 1 / L_jj (one division per column)
        s = A[j, j]
        for p in range(j):
            s -= L[j, p] * L[j, p]
        if not s > 0.0:
            return False
        d = 1.0 / np.sqrt(s)
        L[j, j] = d
        for i in range(j + 1, k):
            t = A[i, j]
            for p in range(j):
                t -= L[i, p] * L[j, p]
            L[i, j] = t * d
    for i in range(k):  # forward: L y = b
        s = b[i]
        for p in range(i):
            s -= L[i, p] * out[p]
        out[i] = s * L[i, i]
    for i in range(k - 1, -1, -1):  # backward: Lᵀ x = y
        s = out[i]
        for p in range(i + 1, k):
            s -= L[p, i] * out[p]
        out[i] = s * L[i, i]
    return True


@numba.njit(cache=True)
def lu_solve(A, b, M, out) -> bool:
    """Solve ``A out = b`` for a square ``A (k, k)`` by Gaussian elimination with partial pivoting.

    ``M (k, k + 1)`` is scratch. Returns False when a pivot vanishes (``A`` numerically singular).
    """
    k = A.shape[0]
    scale = 0.0
    for i in range(k):
        for j in range(k):
            M[i, j] = A[i, j]
            scale = max(scale, abs(A[i, j]))
        M[i, k] = b[i]
    tiny = 1e-14 * max(scale, 1e-300)
    for c in range(k):
        p = c
        for i in range(c + 1, k):
            if abs(M[i, c]) > abs(M[p, c]):
                p = i
        if not abs(M[p, c]) > tiny:
            return False
        if p != c:
            for j in range(c, k + 1):
                M[c, j], M[p, j] = M[p, j], M[c, j]
        inverse = 1.0 / M[c, c]
        M[c, c] = inverse  # kept for the back substitution
        for i in range(c + 1, k):
            f = M[i, c] * inverse
            if f != 0.0:
                for j in range(c + 1, k + 1):
                    M[i, j] -= f * M[c, j]
    for i in range(k - 1, -1, -1):
        s = M[i, k]
        for j in range(i + 1, k):
            s -= M[i, j] * out[j]
        out[i] = s * M[i, i]
    return True


@numba.njit(cache=True)
def gram(Jr, damping, A):
    """``A = J Jᵀ + damping I`` for ``Jr (m, n)`` into ``A (m, m)``."""
    m, n = Jr.shape
    for i in range(m):
        for j in range(i + 1):
            s = 0.0
            for c in range(n):
                s += Jr[i, c] * Jr[j, c]
            A[i, j] = s
            A[j, i] = s
        A[i, i] += damping


@numba.njit(cache=True)
def least_norm_step(Jr, r, damping, A, L, y, dx) -> bool:
    """``dx = −Jᵀ (J Jᵀ + damping I)⁻¹ r``: the (damped) least-norm Gauss-Newton step, ``Jr (m, n)``.

    ``A, L (m, m)`` and ``y (m,)`` are scratch. With ``damping = 0`` and full row rank, ``J dx = −r`` exactly.
    """
    m, n = Jr.shape
    gram(Jr, damping, A)
    if not cholesky_solve(A, r, L, y):
        return False
    for c in range(n):
        s = 0.0
        for i in range(m):
            s -= Jr[i, c] * y[i]
        dx[c] = s
    return True


@numba.njit(cache=True)
def levenberg_marquardt_step(Jr, r, damping, A, L, g, dx) -> bool:
    """``dx = −(JᵀJ + damping I)⁻¹ Jᵀ r`` for ``Jr (m, n)``; ``A, L (n, n)``, ``g (n,)`` scratch.

    Summed row by row, skipping rows whose residual and first Jacobian entries are zero — hinge rows that are
    clear (a collision term has hundreds, almost all clear) — so the cost follows the rows that count."""
    m, n = Jr.shape
    for i in range(n):
        g[i] = 0.0
        for j in range(i + 1):
            A[i, j] = 0.0
    for p in range(m):
        rp = r[p]
        if rp == 0.0:
            zero = True
            for i in range(n):
                if Jr[p, i] != 0.0:
                    zero = False
                    break
            if zero:
                continue
        for i in range(n):
            ji = Jr[p, i]
            if ji == 0.0:
                continue
            g[i] -= ji * rp
            for j in range(i + 1):
                A[i, j] += ji * Jr[p, j]
    for i in range(n):
        A[i, i] += damping
        for j in range(i):
            A[j, i] = A[i, j]
    return cholesky_solve(A, g, L, dx)
