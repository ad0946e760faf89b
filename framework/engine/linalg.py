"""Small dense linear algebra for the compiled solver loops: no BLAS call, no thread, no allocation.

The systems are small (a few to a few dozen unknowns) and solved thousands of times per second; LAPACK through
numpy costs more in call overhead (and, on a shared 2-core machine, in OpenBLAS threads) than the arithmetic.
"""

from __future__ import annotations

import numpy as np

from ..compiled.native import internal


@internal(inline=True)
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


@internal
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
        pivot_row = M[c]
        first, end = np.uint64(c + 1), np.uint64(k + 1)  # unsigned: no negative-index wrap test, the loop vectorizes
        for i in range(c + 1, k):
            row = M[i]
            f = row[c] * inverse
            if f != 0.0:
                for j in range(first, end):
                    row[j] -= f * pivot_row[j]
    for i in range(k - 1, -1, -1):
        s = M[i, k]
        for j in range(i + 1, k):
            s -= M[i, j] * out[j]
        out[i] = s * M[i, i]
    return True


@internal
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


@internal
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


#: Rows per coordinate up to which :func:`levenberg_marquardt_step` sums every entry (beyond: row by row,
#: skipping zero rows).
DENSE_ROWS = 4


@internal
def levenberg_marquardt_step(Jr, r, damping, A, L, g, dx) -> bool:
    """``dx = −(JᵀJ + damping I)⁻¹ Jᵀ r`` for ``Jr (m, n)``; ``A, L (n, n)``, ``g (n,)`` scratch.

    A short stack (at most :data:`DENSE_ROWS` rows per coordinate: a pose, two hands) is summed entry by entry
    without tests. A longer one is summed row by row, skipping rows whose residual and first Jacobian entries
    are zero — hinge rows that are clear (a collision term has hundreds, almost all clear) — so the cost follows
    the rows that count. Both add the rows' products in row order: the same numbers (a skipped term is a zero)."""
    m, n = Jr.shape
    if m <= DENSE_ROWS * n:
        for i in range(n):
            s = 0.0
            for p in range(m):
                s -= Jr[p, i] * r[p]
            g[i] = s
        gram(Jr.T, damping, A)  # JᵀJ + λI: the Gram matrix of Jᵀ's rows
        return cholesky_solve(A, g, L, dx)
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


@internal(inline=True)
def _moves(Jr, i) -> bool:
    """Whether column ``i`` of ``Jr`` has a nonzero entry (the rows depend on coordinate ``i`` here)."""
    for a in range(Jr.shape[0]):
        if Jr[a, i] != 0.0:
            return True
    return False


@internal
def moving_columns(Jr, beyond) -> int:
    """How many columns of ``Jr (m, n)`` have a nonzero entry, counted until there are more than ``beyond``."""
    count = 0
    for i in range(Jr.shape[1]):
        if _moves(Jr, i):
            count += 1
            if count > beyond:
                break
    return count


@internal
def moving_columns_step(Jr, r, damping, A, L, g, dx, nz) -> bool:
    """``dx = −(JᵀJ + damping I)⁻¹ Jᵀ r`` for ``Jr (m, n)`` whose ``nz`` nonzero columns are the only ones solved
    for (the others' coordinates do not move the rows: their ``dx`` is 0, as the damped system gives them): the
    normal equations over those columns, ``A, L (nz, nz)`` and ``g (nz,)`` scratch, ``dx (n,)``. The same step as
    :func:`least_norm_step` in exact arithmetic, but where the rows outnumber the coordinates that move them (a
    full pose of a three-joint leg on a whole quadruped: six rows, three columns) ``J Jᵀ`` is singular and a
    lightly damped least-norm step is lost to rounding, while ``JᵀJ`` over the moving columns is not."""
    m, n = Jr.shape
    p = 0
    for i in range(n):
        if not _moves(Jr, i):
            continue
        s = 0.0
        for a in range(m):
            s -= Jr[a, i] * r[a]
        g[p] = s
        q = 0
        for j in range(i + 1):
            if not _moves(Jr, j):
                continue
            s = 0.0
            for a in range(m):
                s += Jr[a, i] * Jr[a, j]
            A[p, q] = s
            A[q, p] = s
            q += 1
        A[p, p] += damping
        p += 1
    if not cholesky_solve(A, g, L, dx[:nz]):
        return False
    for i in range(n - 1, -1, -1):  # scattered back in place: the p-th moving column's value moves up to i >= p
        if _moves(Jr, i):
            p -= 1
            dx[i] = dx[p]
        else:
            dx[i] = 0.0
    return True


@internal(inline=True)
def _reflect(V, beta, j, k, M, col) -> None:
    """Column ``col`` of ``M`` times the ``j``-th Householder reflection ``I − β_j v_j v_jᵀ`` (``v_j = V[j:k, j]``)."""
    s = 0.0
    for i in range(j, k):
        s += V[i, j] * M[i, col]
    s *= beta[j]
    for i in range(j, k):
        M[i, col] -= s * V[i, j]


@internal
def null_space(A, W, V, beta, Z) -> int:
    """An orthonormal basis of the null space of ``A (m, k)`` into the columns of ``Z[:k, :nz]``; returns ``nz``
    (``k`` minus the numerical rank).

    Householder QR with column pivoting of ``Aᵀ``: its first ``rank`` reflections span the rows, and the rest of
    ``Q`` is the null space. A row whose remainder is below ``1e-9`` of the largest row norm adds no rank
    (redundant rows: held groups that repeat the task's constraints). ``W, V (k, m)``, ``beta (m,)`` are scratch.
    """
    m, k = A.shape
    biggest = 0.0
    for a in range(m):
        s = 0.0
        for i in range(k):
            W[i, a] = A[a, i]
            s += W[i, a] * W[i, a]
        biggest = max(biggest, s)
    tiny = 1e-18 * biggest  # (1e-9 of the norm, squared)
    rank = 0
    for j in range(min(k, m)):
        pick, best = j, -1.0
        for a in range(j, m):  # the row with the largest remainder (column of W) next
            s = 0.0
            for i in range(j, k):
                s += W[i, a] * W[i, a]
            if s > best:
                pick, best = a, s
        if not best > tiny:
            break
        if pick != j:
            for i in range(k):
                W[i, j], W[i, pick] = W[i, pick], W[i, j]
        alpha = -np.sqrt(best) if W[j, j] >= 0.0 else np.sqrt(best)
        for i in range(k):
            V[i, j] = W[i, j] if i >= j else 0.0
        V[j, j] -= alpha
        vv = 0.0
        for i in range(j, k):
            vv += V[i, j] * V[i, j]
        beta[j] = 2.0 / vv
        for a in range(j, m):  # W ← (I − β v vᵀ) W
            _reflect(V, beta, j, k, W, a)
        rank += 1
    nz = k - rank
    for t in range(nz):  # Z e_t = H_0 H_1 … H_{rank−1} e_{rank+t}
        for i in range(k):
            Z[i, t] = 1.0 if i == rank + t else 0.0
        for j in range(rank - 1, -1, -1):
            _reflect(V, beta, j, k, Z, t)
    return nz


@internal
def symmetric_eigen(S, k, E, V, w) -> None:
    """Eigenvalues ``w[:k]`` (ascending) and orthonormal eigenvectors (the columns of ``V[:k, :k]``) of the
    symmetric ``S[:k, :k]``: Householder reduction to tridiagonal form, then the QL algorithm with implicit shifts
    (``tred2`` and ``tqli`` of Numerical Recipes, 2nd ed., §11.2-11.3). ``E (k, k)`` is scratch; its first row
    holds the off-diagonal."""
    a, d, e = V, w, E[0]
    for i in range(k):
        for j in range(k):
            a[i, j] = S[i, j]
    _tridiagonal(a, d, e, k)
    _tridiagonal_ql(a, d, e, k)
    for i in range(k):  # ascending (selection sort, the vectors along)
        j = i
        for c in range(i + 1, k):
            if w[c] < w[j]:
                j = c
        if j != i:
            w[i], w[j] = w[j], w[i]
            for r in range(k):
                V[r, i], V[r, j] = V[r, j], V[r, i]


@internal
def _tridiagonal(a, d, e, k) -> None:
    """Householder: ``a ← Qᵀ a Q`` tridiagonal (diagonal ``d``, off-diagonal ``e``), ``Q`` accumulated in ``a``."""
    for i in range(k - 1, 0, -1):  # Householder: a ← Qᵀ a Q tridiagonal, Q accumulated in a
        l = i - 1
        h = 0.0
        if l > 0:
            scale = 0.0
            for q in range(l + 1):
                scale += abs(a[i, q])
            if scale == 0.0:
                e[i] = a[i, l]
            else:
                for q in range(l + 1):
                    a[i, q] /= scale
                    h += a[i, q] * a[i, q]
                f = a[i, l]
                g = -np.sqrt(h) if f >= 0.0 else np.sqrt(h)
                e[i] = scale * g
                h -= f * g
                a[i, l] = f - g
                f = 0.0
                for j in range(l + 1):
                    a[j, i] = a[i, j] / h
                    g = 0.0
                    for q in range(j + 1):
                        g += a[j, q] * a[i, q]
                    for q in range(j + 1, l + 1):
                        g += a[q, j] * a[i, q]
                    e[j] = g / h
                    f += e[j] * a[i, j]
                hh = f / (h + h)
                for j in range(l + 1):
                    f = a[i, j]
                    g = e[j] - hh * f
                    e[j] = g
                    for q in range(j + 1):
                        a[j, q] -= f * e[q] + g * a[i, q]
        else:
            e[i] = a[i, l]
        d[i] = h
    d[0] = 0.0
    e[0] = 0.0
    for i in range(k):  # the transformation Q
        if d[i] != 0.0:
            for j in range(i):
                g = 0.0
                for q in range(i):
                    g += a[i, q] * a[q, j]
                for q in range(i):
                    a[q, j] -= g * a[q, i]
        d[i] = a[i, i]
        a[i, i] = 1.0
        for j in range(i):
            a[j, i] = 0.0
            a[i, j] = 0.0


@internal
def _tridiagonal_ql(a, d, e, k) -> None:
    """QL with implicit shifts on the tridiagonal ``(d, e)``: the eigenvalues into ``d``, the rotations
    accumulated in ``a`` (its columns the eigenvectors)."""
    for i in range(1, k):  # QL with implicit shifts on the tridiagonal (d, e), rotations accumulated in a
        e[i - 1] = e[i]
    e[k - 1] = 0.0
    for l in range(k):
        for _ in range(60):
            m = l
            while m < k - 1:
                dd = abs(d[m]) + abs(d[m + 1])
                if abs(e[m]) <= 1e-16 * dd:
                    break
                m += 1
            if m == l:
                break
            g = (d[l + 1] - d[l]) / (2.0 * e[l])
            r = np.sqrt(g * g + 1.0)
            g = d[m] - d[l] + e[l] / (g + (r if g >= 0.0 else -r))
            s = c = 1.0
            p = 0.0
            deflated = False
            for i in range(m - 1, l - 1, -1):
                f = s * e[i]
                b = c * e[i]
                r = np.sqrt(f * f + g * g)
                e[i + 1] = r
                if r == 0.0:
                    d[i + 1] -= p
                    e[m] = 0.0
                    deflated = True
                    break
                s = f / r
                c = g / r
                g = d[i + 1] - p
                r = (d[i] - g) * s + 2.0 * c * b
                p = s * r
                d[i + 1] = g + p
                g = c * r - b
                for q in range(k):
                    f = a[q, i + 1]
                    a[q, i + 1] = s * a[q, i] + c * f
                    a[q, i] = c * a[q, i] - s * f
            if deflated:
                continue
            d[l] -= p
            e[l] = g
            e[m] = 0.0


@internal
def _length(c, w, tau, k) -> float:
    """``‖(S + τI)⁻¹ g‖`` in the eigenbasis (``c = Vᵀg``, ``w`` the eigenvalues)."""
    s = 0.0
    for i in range(k):
        d = c[i] / (w[i] + tau)
        s += d * d
    return np.sqrt(s)


@internal
def trust_region_step(w, V, g, k, radius, c, p) -> float:
    """The minimizer ``p[:k]`` of the model ``gᵀp + ½ pᵀSp`` within ``‖p‖ ≤ radius`` (Moré and Sorensen's
    characterization, solved in the eigenbasis of ``S = V diag(w) Vᵀ``, ``w`` ascending): ``p = −(S + τI)⁻¹ g``
    with ``S + τI`` positive semidefinite and ``τ (radius − ‖p‖) = 0``. Where ``g`` has (almost) nothing along the
    lowest eigenvector and that leaves the step short (the *hard case*, e.g. at a saddle point, where ``g ≈ 0``),
    the step is completed along that eigenvector to the boundary. ``c (k,)`` is scratch. Returns the model's
    decrease ``−(gᵀp + ½ pᵀSp) ≥ 0``."""
    for i in range(k):
        s = 0.0
        for r in range(k):
            s += V[r, i] * g[r]
        c[i] = s
    scale = max(abs(w[0]), abs(w[k - 1]), 1e-300)
    if w[0] > 1e-12 * scale and _length(c, w, 0.0, k) <= radius:
        tau, t = 0.0, 0.0  # the Newton step, inside
    else:
        lo = max(0.0, -w[0]) + 1e-12 * scale  # S + τI positive definite beyond it
        t = 0.0
        if _length(c, w, lo, k) <= radius:  # the hard case: the rest of the way along the lowest eigenvector
            tau = lo
            short = _length(c, w, tau, k)
            t = np.sqrt(max(radius * radius - short * short, 0.0))
            if c[0] > 0.0:
                t = -t
        else:  # Newton on 1/‖p(τ)‖ − 1/radius (concave, increasing in τ): from the left, monotone to the root
            tau = lo
            for _ in range(50):
                length = _length(c, w, tau, k)
                if length <= radius * (1.0 + 1e-6):
                    break
                s3 = 0.0
                for i in range(k):
                    d = w[i] + tau
                    s3 += c[i] * c[i] / (d * d * d)
                tau += (length - radius) / radius * length * length / s3
    decrease = 0.0
    for i in range(k):
        a = -c[i] / (w[i] + tau) if w[i] + tau > 0.0 else 0.0
        if i == 0:
            a += t
        decrease -= c[i] * a + 0.5 * w[i] * a * a
        c[i] = a  # the step's coordinates in the eigenbasis
    for r in range(k):
        s = 0.0
        for i in range(k):
            s += V[r, i] * c[i]
        p[r] = s
    return decrease
