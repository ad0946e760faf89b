"""Compiled residuals of the goal kinds beyond positions and orientations (see :mod:`~.blocks`): ``DISTANCE``,
``AXIS``, ``CONE``, ``RELATIVE_ROTATION``, ``LOOK_AT`` and ``COM``, each with its Jacobian."""

from __future__ import annotations

import numba
import numpy as np

from .blocks import left_jacobian_inverse, rotation_log


@numba.njit(cache=True, inline="always")
def distance_direction(out, fa, fb, params, p):
    """``(u₀, u₁, u₂, ‖v‖)`` of a ``DISTANCE`` block: ``v = p_a − p_b`` (or ``p_a −`` its point when ``fb < 0``),
    ``u = v/‖v‖`` (zero when ``v = 0``); scalars, so the population loop allocates nothing."""
    v0 = out[fa, 9] - (out[fb, 9] if fb >= 0 else params[p])
    v1 = out[fa, 10] - (out[fb, 10] if fb >= 0 else params[p + 1])
    v2 = out[fa, 11] - (out[fb, 11] if fb >= 0 else params[p + 2])
    dist = np.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
    if dist > 0.0:
        return v0 / dist, v1 / dist, v2 / dist, dist
    return 0.0, 0.0, 0.0, dist


@numba.njit(cache=True)
def axis_world(out, fa, params, p):
    """``w = R_a e`` (3,) and ``d`` (3,) of an ``AXIS`` block."""
    w0 = out[fa, 0] * params[p] + out[fa, 1] * params[p + 1] + out[fa, 2] * params[p + 2]
    w1 = out[fa, 3] * params[p] + out[fa, 4] * params[p + 1] + out[fa, 5] * params[p + 2]
    w2 = out[fa, 6] * params[p] + out[fa, 7] * params[p + 1] + out[fa, 8] * params[p + 2]
    return w0, w1, w2, params[p + 3], params[p + 4], params[p + 5]


@numba.njit(cache=True)
def axis_residual(out, Jf, fa, params, p, r, Jr, row, want_jacobian, n) -> None:
    """The ``AXIS`` residual ``r = Bᵀ v``, ``v = f(θ) (d × w)``, ``f = θ/sinθ`` (so ``‖r‖ = θ``), and its Jacobian
    ``dv = f (d × dw) − g (d·dw)(d × w)`` with ``dw = ω_i × w``, ``g = f'/sinθ = (sinθ − θcosθ)/sin³θ`` (series
    below 1e-3 rad). Exactly opposite (θ = π, no rotation axis), ``r = (π, 0)`` and the Jacobian uses ``f = 1``."""
    w0, w1, w2, d0, d1, d2 = axis_world(out, fa, params, p)
    c0, c1, c2 = d1 * w2 - d2 * w1, d2 * w0 - d0 * w2, d0 * w1 - d1 * w0
    s = np.sqrt(c0 * c0 + c1 * c1 + c2 * c2)
    co = d0 * w0 + d1 * w1 + d2 * w2
    theta = np.arctan2(s, co)
    opposite = s < 1e-12 and co < 0.0
    if opposite:
        f, g = 1.0, 0.0
        r[row], r[row + 1] = np.pi, 0.0
    else:
        if s < 1e-3 and co > 0.0:  # θ < 1e-3: the series of θ/sinθ and (sinθ − θcosθ)/sin³θ
            t2 = theta * theta
            f, g = 1.0 + t2 / 6.0 + 7.0 * t2 * t2 / 360.0, 1.0 / 3.0 + 2.0 * t2 / 15.0
        else:
            f, g = theta / s, (s - theta * co) / (s * s * s)
        r[row] = f * (params[p + 6] * c0 + params[p + 7] * c1 + params[p + 8] * c2)
        r[row + 1] = f * (params[p + 9] * c0 + params[p + 10] * c1 + params[p + 11] * c2)
    if not want_jacobian:
        return
    for i in range(n):
        o0, o1, o2 = Jf[fa, 3, i], Jf[fa, 4, i], Jf[fa, 5, i]
        e0, e1, e2 = o1 * w2 - o2 * w1, o2 * w0 - o0 * w2, o0 * w1 - o1 * w0  # dw = ω × w
        dd = d0 * e0 + d1 * e1 + d2 * e2
        u0 = f * (d1 * e2 - d2 * e1) - g * dd * c0
        u1 = f * (d2 * e0 - d0 * e2) - g * dd * c1
        u2 = f * (d0 * e1 - d1 * e0) - g * dd * c2
        Jr[row, i] = params[p + 6] * u0 + params[p + 7] * u1 + params[p + 8] * u2
        Jr[row + 1, i] = params[p + 9] * u0 + params[p + 10] * u1 + params[p + 11] * u2


@numba.njit(cache=True)
def relative_rotation_residual(out, Jf, fa, fb, params, p, r, Jr, row, want_jacobian, n, L3, E9) -> None:
    """``r = log(Mᵀ R_b)``, ``M = R_a R_o``; Jacobian ``J_l⁻¹(r) Mᵀ (ω_b − ω_a)`` (a left perturbation of
    ``Mᵀ R_b`` by the relative angular velocity, exact to first order)."""
    for a in range(3):
        for c in range(3):  # E = Mᵀ R_b, M[k, a] = Σ_m R_a[k, m] R_o[m, a]
            e = 0.0
            for k in range(3):
                m = out[fa, 3 * k] * params[p + a] + out[fa, 3 * k + 1] * params[p + 3 + a] \
                    + out[fa, 3 * k + 2] * params[p + 6 + a]
                e += m * out[fb, 3 * k + c]
            E9[3 * a + c] = e
    rotation_log(E9, r[row : row + 3])
    if not want_jacobian:
        return
    left_jacobian_inverse(r[row : row + 3], L3)
    for k in range(3):  # E9 ← M (row-major)
        for a in range(3):
            E9[3 * k + a] = out[fa, 3 * k] * params[p + a] + out[fa, 3 * k + 1] * params[p + 3 + a] \
                + out[fa, 3 * k + 2] * params[p + 6 + a]
    for i in range(n):
        u0 = Jf[fb, 3, i] - Jf[fa, 3, i]
        u1 = Jf[fb, 4, i] - Jf[fa, 4, i]
        u2 = Jf[fb, 5, i] - Jf[fa, 5, i]
        m0 = E9[0] * u0 + E9[3] * u1 + E9[6] * u2  # Mᵀ u
        m1 = E9[1] * u0 + E9[4] * u1 + E9[7] * u2
        m2 = E9[2] * u0 + E9[5] * u1 + E9[8] * u2
        for a in range(3):
            Jr[row + a, i] = L3[a, 0] * m0 + L3[a, 1] * m1 + L3[a, 2] * m2


@numba.njit(cache=True)
def cone_residual(out, Jf, fa, params, p, r, Jr, row, want_jacobian, n) -> None:
    """The ``CONE`` residual ``θ − α`` outside the cone (0 inside), ``θ = atan2(‖d × w‖, d·w)``, and its Jacobian
    ``dθ = cosθ (d×w)·(d×dw)/sinθ − sinθ d·dw`` with ``dw = ω_i × w`` (zero inside the cone)."""
    w0, w1, w2, d0, d1, d2 = axis_world(out, fa, params, p)
    c0, c1, c2 = d1 * w2 - d2 * w1, d2 * w0 - d0 * w2, d0 * w1 - d1 * w0
    s = np.sqrt(c0 * c0 + c1 * c1 + c2 * c2)
    co = d0 * w0 + d1 * w1 + d2 * w2
    theta = np.arctan2(s, co)
    active = theta > params[p + 6]
    r[row] = theta - params[p + 6] if active else 0.0
    if not want_jacobian:
        return
    for i in range(n):
        g = 0.0
        if active and s > 0.0:
            o0, o1, o2 = Jf[fa, 3, i], Jf[fa, 4, i], Jf[fa, 5, i]
            e0, e1, e2 = o1 * w2 - o2 * w1, o2 * w0 - o0 * w2, o0 * w1 - o1 * w0  # dw = ω × w
            x0, x1, x2 = d1 * e2 - d2 * e1, d2 * e0 - d0 * e2, d0 * e1 - d1 * e0  # d × dw
            g = co * (c0 * x0 + c1 * x1 + c2 * x2) / s - s * (d0 * e0 + d1 * e1 + d2 * e2)
        Jr[row, i] = g


@numba.njit(cache=True)
def look_at_residual(out, Jf, fa, params, p, r, Jr, row, want_jacobian, n) -> None:
    """The ``LOOK_AT`` residual ``w − u`` (``w = R_a e``, ``u`` the unit line of sight to ``t``) and its Jacobian
    ``ω_i × w + (I − uuᵀ) J_p,i / ‖t − p_a‖``; zero at ``p_a = t``."""
    e0, e1, e2 = params[p], params[p + 1], params[p + 2]
    w0 = out[fa, 0] * e0 + out[fa, 1] * e1 + out[fa, 2] * e2
    w1 = out[fa, 3] * e0 + out[fa, 4] * e1 + out[fa, 5] * e2
    w2 = out[fa, 6] * e0 + out[fa, 7] * e1 + out[fa, 8] * e2
    v0, v1, v2 = params[p + 3] - out[fa, 9], params[p + 4] - out[fa, 10], params[p + 5] - out[fa, 11]
    dist = np.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
    if dist == 0.0:
        r[row], r[row + 1], r[row + 2] = 0.0, 0.0, 0.0
        if want_jacobian:
            for c in range(3):
                for i in range(n):
                    Jr[row + c, i] = 0.0
        return
    u0, u1, u2 = v0 / dist, v1 / dist, v2 / dist
    r[row], r[row + 1], r[row + 2] = w0 - u0, w1 - u1, w2 - u2
    if not want_jacobian:
        return
    for i in range(n):
        o0, o1, o2 = Jf[fa, 3, i], Jf[fa, 4, i], Jf[fa, 5, i]
        j0, j1, j2 = Jf[fa, 0, i], Jf[fa, 1, i], Jf[fa, 2, i]
        uj = u0 * j0 + u1 * j1 + u2 * j2
        Jr[row, i] = o1 * w2 - o2 * w1 + (j0 - u0 * uj) / dist
        Jr[row + 1, i] = o2 * w0 - o0 * w2 + (j1 - u1 * uj) / dist
        Jr[row + 2, i] = o0 * w1 - o1 * w0 + (j2 - u2 * uj) / dist


@numba.njit(cache=True)
def com_residual(out, Jf, q, count, idx, params, p, r, Jr, row, want_jacobian, n) -> None:
    """The ``COM`` residual ``Σ_k m_k p_k − t`` on the masked axes and its Jacobian ``Σ_k m_k J_p,k``; the mass
    points' frame slots are ``idx[q:q + count]``; params ``t (3), mask (3), m (count)``."""
    k = row
    for c in range(3):
        if params[p + 3 + c] == 0.0:
            continue
        v = -params[p + c]
        for s in range(count):
            v += params[p + 6 + s] * out[idx[q + s], 9 + c]
        r[k] = v
        if want_jacobian:
            for i in range(n):
                g = 0.0
                for s in range(count):
                    g += params[p + 6 + s] * Jf[idx[q + s], c, i]
                Jr[k, i] = g
        k += 1
