"""The Newton phase's step on the task's tangent space: the KKT step where it is a minimum within the trust radius,
else the trust-region step over the rows' null space; least-squares multipliers."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..compiled.native import internal, square, take
from .linalg import cholesky_solve, gram, null_space, symmetric_eigen, trust_region_step


class TangentScratch(NamedTuple):
    """Scratch of :func:`tangent_step` for ``n`` coordinates and up to ``rows`` active rows."""

    W: np.ndarray  # (n, rows)
    Vh: np.ndarray  # (n, rows)
    beta: np.ndarray  # (rows,)
    Z: np.ndarray  # (n, n): the null space's basis
    HZ: np.ndarray  # (n, n)
    hz: np.ndarray  # (n², ) flat
    lz: np.ndarray  # (n², ) flat
    E: np.ndarray  # (n, n)
    Vz: np.ndarray  # (n, n)
    wz: np.ndarray  # (n,)
    gz: np.ndarray  # (n,)
    c: np.ndarray  # (n,)
    p: np.ndarray  # (n,)
    dn: np.ndarray  # (n,)
    u: np.ndarray  # (n,)
    aa: np.ndarray  # (rows², ) flat
    la: np.ndarray  # (rows², ) flat
    ra: np.ndarray  # (rows,)
    y: np.ndarray  # (rows,)


@internal
def tangent_scratch(at, n, rows):
    """:class:`TangentScratch` laid out from address ``at``, and the address after it."""
    W, at = take(at, (n, rows))
    Vh, at = take(at, (n, rows))
    beta, at = take(at, rows)
    Z, at = take(at, (n, n))
    HZ, at = take(at, (n, n))
    hz, at = take(at, n * n)
    lz, at = take(at, n * n)
    E, at = take(at, (n, n))
    Vz, at = take(at, (n, n))
    wz, at = take(at, n)
    gz, at = take(at, n)
    c, at = take(at, n)
    p, at = take(at, n)
    dn, at = take(at, n)
    u, at = take(at, n)
    aa, at = take(at, rows * rows)
    la, at = take(at, rows * rows)
    ra, at = take(at, rows)
    y, at = take(at, rows)
    return TangentScratch(W, Vh, beta, Z, HZ, hz, lz, E, Vz, wz, gz, c, p, dn, u, aa, la, ra, y), at


@internal(inline=True)
def model_gradient(H, rhs, d, nf, u) -> None:
    """``u = g + H d`` over the ``nf`` free coordinates (``rhs[:nf] = −g``): the model's gradient at ``d``."""
    for i in range(nf):
        s = -rhs[i]
        for j in range(nf):
            s += H[i, j] * d[j]
        u[i] = s


@internal
def tangent_step(K, rhs, nf, ma, trust, sv, at, n, rows) -> float:
    """The solution ``sv`` of the step's KKT system ``K sv = rhs`` (``K[:nf, :nf] = H + μI`` over the free
    coordinates, ``K[nf:, :nf]`` the ``ma`` active rows ``A``, ``rhs[:nf] = −g``; ``sv[:nf]`` the step, then
    ``−λ``) kept if it is a Newton step to a minimum within the trust radius; otherwise replaced by the
    trust-region step: its normal part (onto the rows' linearization) plus the minimizer of the model over the
    rows' null space within ``‖·‖₂ ≤ trust`` (:func:`~.linalg.trust_region_step`: negative curvature, a saddle
    point's included, is followed to the boundary instead of to the saddle), with least-squares multipliers.
    Returns the model's decrease along the tangent part, or ``−1`` when the KKT step stands."""
    W, Vh, beta, Z, HZ, hz, lz, E, Vz, wz, gz, c, p, dn, u, aa, la, ra, y = tangent_scratch(at, n, rows)[0]
    longest = 0.0
    for i in range(nf):
        longest = max(longest, abs(sv[i]))
    H, A = K[:nf, :nf], K[nf:nf + ma, :nf]
    if longest <= trust:  # H + ρAᵀA positive definite: H is on the rows' null space (Debreu's lemma, one way)
        scale, rows = 1.0, 1e-300
        for i in range(nf):
            scale = max(scale, abs(H[i, i]))
        for a in range(ma):
            s = 0.0
            for i in range(nf):
                s += A[a, i] * A[a, i]
            rows = max(rows, s)
        rho = 1e6 * scale / rows
        Ha = square(hz, nf)
        for i in range(nf):
            for j in range(i + 1):
                s = 0.0
                for a in range(ma):
                    s += A[a, i] * A[a, j]
                Ha[i, j] = Ha[j, i] = H[i, j] + rho * s
        if cholesky_solve(Ha, sv, square(lz, nf), c):
            return -1.0  # the Newton step
    nz = null_space(A, W, Vh, beta, Z)
    if nz == 0:
        return -1.0
    for t in range(nz):  # the tangent part p of the step, and its normal part dn
        s = 0.0
        for i in range(nf):
            s += Z[i, t] * sv[i]
        p[t] = s
    for i in range(nf):
        s = sv[i]
        for t in range(nz):
            s -= Z[i, t] * p[t]
        dn[i] = s
    model_gradient(H, rhs, dn, nf, u)
    for i in range(nf):  # HZ = H Z
        for t in range(nz):
            s = 0.0
            for j in range(nf):
                s += H[i, j] * Z[j, t]
            HZ[i, t] = s
    Hz, Lz = square(hz, nz), square(lz, nz)
    for t in range(nz):  # the reduced Hessian Zᵀ H Z and gradient Zᵀu
        s = 0.0
        for i in range(nf):
            s += Z[i, t] * u[i]
        gz[t] = s
        for v in range(t + 1):
            s = 0.0
            for i in range(nf):
                s += Z[i, t] * HZ[i, v]
            Hz[t, v] = s
            Hz[v, t] = s
    radius = trust
    if cholesky_solve(Hz, gz, Lz, c):  # positive definite on the tangent space
        if longest <= trust:
            return -1.0  # and within the trust radius: the Newton step
        length = 0.0  # too long: the radius is what the step cut to ``trust`` in its largest coordinate is long
        for i in range(nf):
            length += sv[i] * sv[i]
        radius = trust * np.sqrt(length) / longest
    symmetric_eigen(Hz, nz, E, Vz, wz)
    decrease = trust_region_step(wz, Vz, gz, nz, radius, c, p)
    for i in range(nf):  # the step, and the multipliers of Aᵀλ = g + H step (least squares)
        s = dn[i]
        for t in range(nz):
            s += Z[i, t] * p[t]
        sv[i] = s
    model_gradient(H, rhs, sv, nf, u)
    # a ridge far below the rows' scale: least norm where rows are redundant
    least_squares_multipliers(A, u[:nf], square(aa, ma), square(la, ma), ra, y[:ma], 1e-12)
    for a in range(ma):
        sv[nf + a] = -y[a]
    return decrease


@internal
def scatter_multipliers(Aa, g, Am, Lm, y, lam_a, arow, ma, lam) -> None:
    """:func:`least_squares_multipliers` of the active rows ``Aa (ma, n)``, written to their rows ``arow`` of
    ``lam (m,)`` (zeros elsewhere); ``Am, Lm (ma, ma)`` scratch."""
    lam[:] = 0.0
    if ma == 0:
        return
    least_squares_multipliers(Aa, g, Am, Lm, y, lam_a[:ma], 0.0)
    for a in range(ma):
        lam[arow[a]] = lam_a[a]


@internal
def least_squares_multipliers(A, g, Am, Lm, y, lam, ridge) -> None:
    """Least-squares multipliers ``λ = (A Aᵀ + R)⁻¹ A g`` of ``g ≈ Aᵀλ``, ``R`` the diagonal ``ridge (1 + (A Aᵀ)ᵢᵢ)``
    (zeros if ``A Aᵀ + R`` is not positive definite: ``A`` rank deficient without a ridge)."""
    m, n = A.shape
    for a in range(m):
        s = 0.0
        for i in range(n):
            s += A[a, i] * g[i]
        y[a] = s
    gram(A, 0.0, Am)
    for a in range(m):
        Am[a, a] += ridge * (1.0 + Am[a, a])
    if not cholesky_solve(Am, y, Lm, lam):
        lam[:] = 0.0
