"""Compiled residuals of the collision kinds (see :mod:`~.blocks`): ``SPHERES`` (two bodies' sphere covers, the
closest pair, pruned by bounding spheres) and ``SOLIDS`` (one body's spheres against a sphere, box, capsule or
half-space: :func:`framework.solids.solid_distance`), and the scratch the sphere pairs need."""

from __future__ import annotations

import numba
import numpy as np

from ..solids import solid_distance
from .blocks import KIND, PPTR, SOLIDS, SPHERES, hinge_row, on_frame, world_point


@numba.njit(cache=True)
def scratch_size(bint, params) -> int:
    """Length of the blocks' scratch vector: 9 (a rotation), or three per sphere of the largest ``SPHERES``
    block's second body (their world centres)."""
    size = 9
    for b in range(bint.shape[0]):
        if bint[b, KIND] == SPHERES:
            size = max(size, 3 * int(params[bint[b, PPTR] + 1]))
    return size


@numba.njit(cache=True, inline="always")
def spheres_rows(out, Jf, fa, fb, params, p, r, Jr, row, want_jacobian, n, S) -> None:
    """The ``SPHERES`` residual: ``min(0, d*)`` with ``d* = min_ij ‖(p_a + R_a c_ai) − (p_b + R_b c_bj)‖ − r_ai
    − r_bj − m`` over the block's sphere pairs, and its Jacobian, the closest pair's
    ``uᵀ(J_p,a − J_p,b) + ω_a·(o_a × u) − ω_b·(o_b × u)`` (``o = R c``, the point's offset on its frame).

    Exact with two prunings: bodies whose bounding spheres are ``m`` apart are clear (every pair is at least that
    far apart), and a sphere of ``a`` farther from ``b``'s bounding sphere than the closest pair found so far
    is skipped. ``b``'s world centres go to the scratch ``S`` (3 per sphere), each computed once.
    """
    na, margin = int(params[p]), params[p + 2]
    A0, A1, A2 = world_point(out, fa, params, p + 3)
    B0, B1, B2 = world_point(out, fb, params, p + 7)
    RA, RB = params[p + 6], params[p + 10]
    gap = np.sqrt((A0 - B0) ** 2 + (A1 - B1) ** 2 + (A2 - B2) ** 2) - RA - RB - margin
    if gap >= 0.0:
        hinge_row(gap, r, Jr, row, want_jacobian, n)
        return
    best, ai, bj = closest_pair(out, fa, fb, params, p, margin, S)
    if not hinge_row(best - margin if ai >= 0 else 0.0, r, Jr, row, want_jacobian, n):
        return
    qa = p + 12
    q, s = qa + 4 * ai, qa + 4 * na + 4 * bj
    a0, a1, a2 = on_frame(out, fa, params[q], params[q + 1], params[q + 2])
    b0, b1, b2 = on_frame(out, fb, params[s], params[s + 1], params[s + 2])
    v0, v1, v2 = out[fa, 9] + a0 - out[fb, 9] - b0, out[fa, 10] + a1 - out[fb, 10] - b1, \
        out[fa, 11] + a2 - out[fb, 11] - b2
    norm = np.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
    if norm > 0.0:
        u0, u1, u2 = v0 / norm, v1 / norm, v2 / norm
    else:
        u0, u1, u2 = 0.0, 0.0, 1.0
    ca0, ca1, ca2 = a1 * u2 - a2 * u1, a2 * u0 - a0 * u2, a0 * u1 - a1 * u0  # o_a × u
    cb0, cb1, cb2 = b1 * u2 - b2 * u1, b2 * u0 - b0 * u2, b0 * u1 - b1 * u0
    for i in range(n):
        Jr[row, i] = (u0 * (Jf[fa, 0, i] - Jf[fb, 0, i]) + u1 * (Jf[fa, 1, i] - Jf[fb, 1, i])
                      + u2 * (Jf[fa, 2, i] - Jf[fb, 2, i])
                      + ca0 * Jf[fa, 3, i] + ca1 * Jf[fa, 4, i] + ca2 * Jf[fa, 5, i]
                      - cb0 * Jf[fb, 3, i] - cb1 * Jf[fb, 4, i] - cb2 * Jf[fb, 5, i])


@numba.njit(cache=True, inline="always")
def closest_pair(out, fa, fb, params, p, within, S):
    """``(d, i, j)``: the sphere pair ``i`` of ``a``, ``j`` of ``b`` of the ``SPHERES`` block at ``params[p:]`` whose
    gap ``d = ‖c_ai − c_bj‖ − r_ai − r_bj`` is smallest among those below ``within`` [m] (``(within, -1, -1)``: none),
    ``a``'s spheres pruned by ``b``'s bounding sphere; ``b``'s world centres go to the scratch ``S``."""
    na, nb = int(params[p]), int(params[p + 1])
    B0, B1, B2 = world_point(out, fb, params, p + 7)
    RB = params[p + 10]
    full = params[p + 11] != 0.0
    qa = p + 12
    qb = qa + 4 * na
    qm = qb + 4 * nb
    for j in range(nb):
        S[3 * j], S[3 * j + 1], S[3 * j + 2] = world_point(out, fb, params, qb + 4 * j)
    best, ai, bj = within, -1, -1  # only pairs closer than ``within`` count
    for i in range(na):
        a0, a1, a2 = world_point(out, fa, params, qa + 4 * i)
        ra = params[qa + 4 * i + 3]
        if np.sqrt((a0 - B0) ** 2 + (a1 - B1) ** 2 + (a2 - B2) ** 2) - ra - RB >= best:
            continue  # every sphere of b is at least this far
        for j in range(nb):
            if not full and params[qm + nb * i + j] == 0.0:
                continue
            reach = best + ra + params[qb + 4 * j + 3]  # a pair closer than best has ‖v‖ < reach
            if reach <= 0.0:
                continue
            v0, v1, v2 = a0 - S[3 * j], a1 - S[3 * j + 1], a2 - S[3 * j + 2]
            vv = v0 * v0 + v1 * v1 + v2 * v2
            if vv < reach * reach:
                best, ai, bj = np.sqrt(vv) - ra - params[qb + 4 * j + 3], i, j
    return best, ai, bj


@numba.njit(cache=True, inline="always")
def _solid_point_distance(out, fb, x, y, z, params, p, g) -> float:
    """:func:`solid_distance` of a world point to the solid at ``params[p:]``, fixed in the world (``fb < 0``) or
    on frame ``fb``; the gradient ``g`` in the world. (One call of :func:`solid_distance`: it is inlined.)"""
    if fb >= 0:  # the point in frame fb
        v0, v1, v2 = x - out[fb, 9], y - out[fb, 10], z - out[fb, 11]
        x = out[fb, 0] * v0 + out[fb, 3] * v1 + out[fb, 6] * v2
        y = out[fb, 1] * v0 + out[fb, 4] * v1 + out[fb, 7] * v2
        z = out[fb, 2] * v0 + out[fb, 5] * v1 + out[fb, 8] * v2
    sd = solid_distance(x, y, z, params, p, g)
    if fb >= 0:
        g0, g1, g2 = g[0], g[1], g[2]
        g[0] = out[fb, 0] * g0 + out[fb, 1] * g1 + out[fb, 2] * g2
        g[1] = out[fb, 3] * g0 + out[fb, 4] * g1 + out[fb, 5] * g2
        g[2] = out[fb, 6] * g0 + out[fb, 7] * g1 + out[fb, 8] * g2
    return sd


@numba.njit(cache=True, inline="always")
def solids_rows(out, Jf, fa, fb, params, p, r, Jr, row, want_jacobian, n, g) -> None:
    """The ``SOLIDS`` residual: ``min(0, min_k sd(p_a + R_a c_k) − r_k − m)`` for the spheres ``(c_k, r_k)`` on
    frame ``a`` against the solid at ``params[p:p + 16]`` (in the world, or on frame ``b``), and the closest
    sphere's Jacobian ``∇sdᵀ(J_p,a + ω_a × o − J_p,b − ω_b × (s − p_b))`` (``o = R_a c``, ``s`` its centre)."""
    margin, count = params[p + 16], int(params[p + 17])
    best, arg, w0, w1, w2 = 1e300, -1, 0.0, 0.0, 0.0
    for k in range(-1, count):  # -1: the spheres' bounding sphere; then each sphere (one call site: inlined)
        q = p + 18 if k < 0 else p + 22 + 4 * k
        a0, a1, a2 = world_point(out, fa, params, q)
        d = _solid_point_distance(out, fb, a0, a1, a2, params, p, g) - params[q + 3]
        if k < 0:
            if d - margin >= 0.0:  # the bounding sphere is clear (sd is 1-Lipschitz): so is every sphere
                hinge_row(d - margin, r, Jr, row, want_jacobian, n)
                return
        elif d < best:
            best, arg, w0, w1, w2 = d, k, g[0], g[1], g[2]  # the gradient at the closest sphere's centre
    if not hinge_row(best - margin, r, Jr, row, want_jacobian, n):
        return
    q = p + 22 + 4 * arg
    a0, a1, a2 = on_frame(out, fa, params[q], params[q + 1], params[q + 2])
    s0, s1, s2 = out[fa, 9] + a0, out[fa, 10] + a1, out[fa, 11] + a2
    ca0, ca1, ca2 = a1 * w2 - a2 * w1, a2 * w0 - a0 * w2, a0 * w1 - a1 * w0  # o × ∇sd
    for i in range(n):
        Jr[row, i] = (w0 * Jf[fa, 0, i] + w1 * Jf[fa, 1, i] + w2 * Jf[fa, 2, i]
                      + ca0 * Jf[fa, 3, i] + ca1 * Jf[fa, 4, i] + ca2 * Jf[fa, 5, i])
    if fb >= 0:
        d0, d1, d2 = s0 - out[fb, 9], s1 - out[fb, 10], s2 - out[fb, 11]
        cb0, cb1, cb2 = d1 * w2 - d2 * w1, d2 * w0 - d0 * w2, d0 * w1 - d1 * w0
        for i in range(n):
            Jr[row, i] -= (w0 * Jf[fb, 0, i] + w1 * Jf[fb, 1, i] + w2 * Jf[fb, 2, i]
                           + cb0 * Jf[fb, 3, i] + cb1 * Jf[fb, 4, i] + cb2 * Jf[fb, 5, i])


@numba.njit(cache=True)
def spheres_residual(out, Jf, fa, fb, params, p, r, Jr, row, want_jacobian, n, S) -> None:
    """:func:`spheres_rows` behind a call (the kernels that evaluate every block kind call it)."""
    spheres_rows(out, Jf, fa, fb, params, p, r, Jr, row, want_jacobian, n, S)


@numba.njit(cache=True)
def solids_residual(out, Jf, fa, fb, params, p, r, Jr, row, want_jacobian, n, g) -> None:
    """:func:`solids_rows` behind a call (the kernels that evaluate every block kind call it)."""
    solids_rows(out, Jf, fa, fb, params, p, r, Jr, row, want_jacobian, n, g)


@numba.njit(cache=True, inline="always")
def contact_row(kind, out, Jf, fa, fb, params, p, r, Jr, row, want_jacobian, n, S) -> None:
    """The row of a ``SPHERES`` or ``SOLIDS`` block, inlined where contact rows are evaluated most (the engine's
    linearization, :func:`~.kernels.linearize`): there a call per block cost as much as the test that finds most
    blocks clear. Only that kernel inlines them (inlined into every kernel that evaluates blocks, through
    :func:`~.dispatch.block_residual`, they tripled the compile time)."""
    if kind == SPHERES:
        spheres_rows(out, Jf, fa, fb, params, p, r, Jr, row, want_jacobian, n, S)
    else:
        solids_rows(out, Jf, fa, fb, params, p, r, Jr, row, want_jacobian, n, S)


@numba.njit(cache=True)
def widen_margins(bint, params, band, out) -> None:
    """``out``: ``params`` with every contact block's margin widened by ``band`` [m]. Evaluated with them, a contact
    row clear of its margin by ``gap < band`` reads ``gap − band`` with the Jacobian of ``gap`` (its closest pair's),
    where with the margin alone it reads 0 with none: how near a clear contact is, and which way it comes."""
    out[:] = params
    for b in range(bint.shape[0]):
        if bint[b, KIND] == SPHERES:
            out[bint[b, PPTR] + 2] += band
        elif bint[b, KIND] == SOLIDS:
            out[bint[b, PPTR] + 16] += band
