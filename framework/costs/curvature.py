"""The second-order part of the blocks (the engine's Newton steps): ``Σ_c μ_c ∇²r_c`` of a block from the product of
exponentials, exact for positions and for orientations on their target (see :func:`block_curvature`); a collision
row's is its closest sphere pair's (``SPHERES``; ``SOLIDS`` rows have none here)."""

from __future__ import annotations

import numba
import numpy as np

from .blocks import (AXIS, COM, CONE, COORDINATES, COUNT, DISTANCE, FA, FB, IPTR, KIND, LIMITS, LOOK_AT, ORIENTATION,
                     PPTR, RELATIVE, RELATIVE_LOCAL, RELATIVE_ROTATION, SOLIDS, SPHERES, left_jacobian_inverse, on_frame)
from .collision_blocks import closest_pair
from .goal_blocks import axis_world, distance_direction


@numba.njit(cache=True)
def block_curvature(b, mu, out, Jf, bint, params, idx, chain_ptr, chain_idx, r, row, H):
    """Add ``Σ_c mu_c ∇²r_c`` of block ``b`` (multipliers ``mu (rows,)``) to ``H (n, n)``.

    From the product of exponentials at ``x``: with ``ω_i`` the world axis of coordinate ``i`` (zero for
    translations) and ``J_i`` its column of the frame's position Jacobian, for ``i`` before ``j`` on the frame's
    chain ``∂²p/∂x_i∂x_j = ω_i × J_j`` (also on the diagonal), and the rotation vector's second derivative is
    ``½ ω_i × ω_j`` (zero on the diagonal) — exact for positions, exact for orientations on the target (``r = 0``).
    """
    kind = bint[b, KIND]
    if kind == COORDINATES or kind == LIMITS or kind == CONE or kind == RELATIVE_LOCAL or kind == RELATIVE_ROTATION \
            or kind == LOOK_AT or kind == SOLIDS:
        return
    if kind == SPHERES:
        _spheres_curvature(mu[0], out, Jf, bint[b, FA], bint[b, FB], params, bint[b, PPTR], chain_ptr, chain_idx, H)
        return
    if kind == COM:  # Σ_k m_k μ·∂²p_k, exact
        p, q, count = bint[b, PPTR], bint[b, IPTR], bint[b, COUNT]
        m = np.zeros(3)
        k = row
        for c in range(3):
            if params[p + 3 + c] != 0.0:
                m[c] = mu[k - row]
                k += 1
        for s in range(count):
            w = params[p + 6 + s]
            _position_curvature(idx[q + s], w * m[0], w * m[1], w * m[2], Jf, chain_ptr, chain_idx, H)
        return
    if kind == ORIENTATION:
        p, fa = bint[b, PPTR], bint[b, FA]
        L = np.empty((3, 3))
        left_jacobian_inverse(r[row : row + 3], L)
        v = np.empty(3)  # μ' = R_t J_l⁻ᵀ μ
        for a in range(3):
            v[a] = L[0, a] * mu[0] + L[1, a] * mu[1] + L[2, a] * mu[2]
        m0 = params[p] * v[0] + params[p + 1] * v[1] + params[p + 2] * v[2]
        m1 = params[p + 3] * v[0] + params[p + 4] * v[1] + params[p + 5] * v[2]
        m2 = params[p + 6] * v[0] + params[p + 7] * v[1] + params[p + 8] * v[2]
        # ½ μ'·(ω_i × ω_j): the chain sum with the angular columns (zero on the diagonal, ω_i × ω_i = 0)
        _chain_curvature(fa, 0.5 * m0, 0.5 * m1, 0.5 * m2, Jf[fa, 3:6], Jf, chain_ptr, chain_idx, H)
        return
    if kind == AXIS:  # Σ μ·∇²r = m·∂²w, m = (Bμ) × d, ∂²w/∂x_i∂x_j = ω_i × (ω_j × w) for i before j
        p, fa = bint[b, PPTR], bint[b, FA]
        w0, w1, w2, d0, d1, d2 = axis_world(out, fa, params, p)
        a0 = mu[0] * params[p + 6] + mu[1] * params[p + 9]
        a1 = mu[0] * params[p + 7] + mu[1] * params[p + 10]
        a2 = mu[0] * params[p + 8] + mu[1] * params[p + 11]
        n = H.shape[0]
        dw = np.empty((3, n))  # ∂w/∂x_j = ω_j × w: the axis moves like a point at w
        for j in range(n):
            vx, vy, vz = Jf[fa, 3, j], Jf[fa, 4, j], Jf[fa, 5, j]
            dw[0, j], dw[1, j], dw[2, j] = vy * w2 - vz * w1, vz * w0 - vx * w2, vx * w1 - vy * w0
        _chain_curvature(fa, a1 * d2 - a2 * d1, a2 * d0 - a0 * d2, a0 * d1 - a1 * d0, dw, Jf, chain_ptr, chain_idx,
                         H)
        return
    if kind == DISTANCE:  # r = ‖v‖ − bound when outside the band: μ[Dᵀ(I − uuᵀ)D/‖v‖ + Σ u_c ∇²v_c], D = ∂v
        p, fa, fb = bint[b, PPTR], bint[b, FA], bint[b, FB]
        u0, u1, u2, dist = distance_direction(out, fa, fb, params, p)
        if dist <= 0.0 or r[row] == 0.0:
            return
        u = np.array((u0, u1, u2))
        _position_curvature(fa, mu[0] * u[0], mu[0] * u[1], mu[0] * u[2], Jf, chain_ptr, chain_idx, H)
        if fb >= 0:
            _position_curvature(fb, -mu[0] * u[0], -mu[0] * u[1], -mu[0] * u[2], Jf, chain_ptr, chain_idx, H)
        n = H.shape[0]
        D = np.zeros((3, n))
        for c in range(3):
            for i in range(n):
                D[c, i] = Jf[fa, c, i] - (Jf[fb, c, i] if fb >= 0 else 0.0)
        _projected_curvature(mu[0] / dist, u, D, H)
        return
    frames = (bint[b, FA], bint[b, FB]) if kind == RELATIVE else (bint[b, FA], -1)
    for which in range(2):
        f = frames[which]
        if f < 0:
            continue
        sign = -1.0 if (kind == RELATIVE and which == 0) else 1.0
        _position_curvature(f, sign * mu[0], sign * mu[1], sign * mu[2], Jf, chain_ptr, chain_idx, H)


#: How far beyond its margin [m] a sphere pair still counts as a ``SPHERES`` row's closest (its curvature is asked
#: where the row is held on its boundary, the gap at the margin up to rounding).
PAIR_BAND = 1e-3


@numba.njit(cache=True)
def _spheres_curvature(mu, out, Jf, fa, fb, params, p, chain_ptr, chain_idx, H) -> None:
    """Add ``mu ∇²d`` of a ``SPHERES`` row to ``H``: ``d = ‖v‖ − r_a − r_b``, ``v = c_a − c_b`` between the closest
    pair's centres (within :data:`PAIR_BAND` of the margin; none: nothing), ``∇²d = Dᵀ(I − uuᵀ)D/‖v‖ + Σ u_c ∇²v_c``
    with ``D = D_a − D_b`` the centres' Jacobians (``J_p + ω × o``, ``o = R c``) and ``∇²`` of a point fixed on a
    frame from the product of exponentials (as :func:`_position_curvature`, for a point off the frame's origin)."""
    S = np.empty(3 * int(params[p + 1]))
    _, ai, bj = closest_pair(out, fa, fb, params, p, params[p + 2] + PAIR_BAND, S)
    if ai < 0:
        return
    q = p + 12 + 4 * ai
    s = p + 12 + 4 * int(params[p]) + 4 * bj
    oa = on_frame(out, fa, params[q], params[q + 1], params[q + 2])
    ob = on_frame(out, fb, params[s], params[s + 1], params[s + 2])
    v = np.empty(3)
    for c in range(3):
        v[c] = out[fa, 9 + c] + oa[c] - out[fb, 9 + c] - ob[c]
    dist = np.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    if dist <= 0.0:
        return
    u = v / dist
    n = H.shape[0]
    Da, Db = _point_jacobian(Jf, fa, oa, n), _point_jacobian(Jf, fb, ob, n)
    _chain_curvature(fa, mu * u[0], mu * u[1], mu * u[2], Da, Jf, chain_ptr, chain_idx, H)
    _chain_curvature(fb, -mu * u[0], -mu * u[1], -mu * u[2], Db, Jf, chain_ptr, chain_idx, H)
    _projected_curvature(mu / dist, u, Da - Db, H)


@numba.njit(cache=True)
def _projected_curvature(k, u, D, H) -> None:
    """Add ``k Dᵀ(I − uuᵀ)D`` to ``H``: a distance ``‖v‖``'s curvature through its direction ``u`` (``D = ∂v``,
    ``(3, n)``; ``k = μ / ‖v‖``)."""
    n = H.shape[0]
    uD = np.zeros(n)
    for i in range(n):
        uD[i] = u[0] * D[0, i] + u[1] * D[1, i] + u[2] * D[2, i]
    for i in range(n):
        for j in range(n):
            H[i, j] += k * (D[0, i] * D[0, j] + D[1, i] * D[1, j] + D[2, i] * D[2, j] - uD[i] * uD[j])


@numba.njit(cache=True)
def _point_jacobian(Jf, f, o, n):
    """``(3, n)``: the Jacobian ``J_p + ω × o`` of the point at offset ``o`` (world axes) from frame ``f``'s
    origin."""
    D = np.empty((3, n))
    for i in range(n):
        wx, wy, wz = Jf[f, 3, i], Jf[f, 4, i], Jf[f, 5, i]
        D[0, i] = Jf[f, 0, i] + wy * o[2] - wz * o[1]
        D[1, i] = Jf[f, 1, i] + wz * o[0] - wx * o[2]
        D[2, i] = Jf[f, 2, i] + wx * o[1] - wy * o[0]
    return D


@numba.njit(cache=True)
def _position_curvature(f, m0, m1, m2, Jf, chain_ptr, chain_idx, H) -> None:
    """Add ``m·∂²p_f/∂x_i∂x_j`` (``∂²p/∂x_i∂x_j = ω_i × J_j`` for ``i`` before ``j``) to ``H``."""
    _chain_curvature(f, m0, m1, m2, Jf[f, 0:3], Jf, chain_ptr, chain_idx, H)


@numba.njit(cache=True)
def _chain_curvature(f, m0, m1, m2, V, Jf, chain_ptr, chain_idx, H) -> None:
    """Add ``m·(ω_i × V_j)`` to ``H[i, j]`` (and ``H[j, i]``) for ``i`` before or at ``j`` on frame ``f``'s chain:
    the second derivative of a vector attached to the frame whose first derivatives are the columns ``V (3, n)``
    (a point's position Jacobian, or ``ω_j × w`` for an axis ``w``)."""
    lo, hi = chain_ptr[f], chain_ptr[f + 1]
    for s in range(lo, hi):
        i = chain_idx[s]
        wx, wy, wz = Jf[f, 3, i], Jf[f, 4, i], Jf[f, 5, i]
        if wx == 0.0 and wy == 0.0 and wz == 0.0:
            continue
        for t in range(s, hi):
            j = chain_idx[t]
            vx, vy, vz = V[0, j], V[1, j], V[2, j]
            h = m0 * (wy * vz - wz * vy) + m1 * (wz * vx - wx * vz) + m2 * (wx * vy - wy * vx)
            H[i, j] += h
            if j != i:
                H[j, i] += h
