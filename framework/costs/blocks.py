"""Residual blocks: the compiled definition of every standard cost term.

A term is one or more *blocks*. A block is a residual ``r(x)`` (a few rows) with its Jacobian ``dr/dx`` from the
frame Jacobians, its second-order part (for Newton steps of the engine), and a *ρ* that turns the residual into
the term's value (``‖r‖``, ``sin(‖r‖/2)``, ``Σ|r|``, ``‖r‖²``, times a scale). The term's value is the sum of its
blocks' ρ. Kinds:

==============  ============================================  ==========================  =======================
kind            residual                                      Jacobian                    parameters
==============  ============================================  ==========================  =======================
``POSITION``    ``p_a − t`` (3) [m]                           ``J_p,a``                   ``t`` (3)
``ORIENTATION`` ``log(R_tᵀ R_a)`` (3) [rad], norm = angle      ``J_l⁻¹(r) R_tᵀ J_ω,a``     ``R_t`` (9, row-major)
``RELATIVE``    ``p_b − p_a − o`` (3) [m]                     ``J_p,b − J_p,a``           ``o`` (3)
``COORDINATES`` ``x[idx] − x₀`` (wrapped on continuous axes)  unit rows                   ``x₀`` (count)
``LIMITS``      ``min(0, x − l) + max(0, x − u)`` (n)         ``±1`` outside, 0 inside    ``l`` (n), ``u`` (n)
``AXIS``        ``Bᵀ θ/sinθ (d × R_a e)`` (2) [rad], norm = θ  see :func:`block_residual`  ``e, d, b₁, b₂`` (12)
``DISTANCE``    ``‖v‖ − hi`` above, ``‖v‖ − lo`` below, else 0 ``uᵀ ∂v`` outside the band   ``point, lo, hi`` (5)
``CONE``        ``θ − α`` when the axis is outside, else 0     ``∂θ`` outside the cone      ``e, d, α`` (7)
``RELATIVE_LOCAL``  ``R_aᵀ(p_b − p_a) − o`` (3) [m]            ``R_aᵀ(∂v + v × ω_a)``      ``o`` (3)
``RELATIVE_ROTATION`` ``log((R_a R_o)ᵀ R_b)`` (3) [rad]        ``J_l⁻¹(r)(R_a R_o)ᵀ(ω_b − ω_a)``  ``R_o`` (9)
``LOOK_AT``     ``R_a e − u``, ``u = (t − p_a)/‖t − p_a‖`` (3)  ``ω × R_a e + (I − uuᵀ)J_p,a/‖t − p_a‖``  ``e, t`` (6)
``COM``         ``Σ_k m_k p_k − t`` on chosen axes [m]           ``Σ_k m_k J_p,k``           ``t``, axes mask, ``m_k``
``SPHERES``     ``min(0, min_ij ‖s_ai − s_bj‖ − r_ai − r_bj − m)``  the closest pair's          see below
``SOLIDS``      ``min(0, min_k sd(s_ak) − r_ak − m)`` (1) [m]    the closest sphere's         see below
==============  ============================================  ==========================  =======================

``AXIS``: the frame axis ``e`` (frame coordinates) against a world direction ``d``; ``θ`` is the angle between
``R_a e`` and ``d``, the residual the rotation vector taking ``d`` to ``R_a e`` written in a basis ``B = (b₁, b₂)``
of the plane perpendicular to ``d`` (two rows: the rotation about ``d`` is free). ``DISTANCE``: ``v = p_a − p_b``
(frame ``b``) or ``p_a −`` a point (no frame ``b``), held within ``[lo, hi]`` (one row, a hinge on each side).
``CONE``: the angle ``θ`` between ``R_a e`` and ``d`` held below ``α`` (one row, a hinge; its second order is
left out: Gauss-Newton curvature in the Newton phase). ``RELATIVE_LOCAL`` / ``RELATIVE_ROTATION``: the pose of
frame ``b`` in frame ``a`` against an offset ``(o, R_o)`` (two hands holding one object); their second order is
left out too. ``LOOK_AT``: the frame axis ``e`` pointing at the world point ``t`` (a camera on a target); the
residual's norm is ``2 sin(θ/2)`` of the angle θ between the axis and the line of sight (θ for small angles, no
false minimum at θ = π); zero when the frame origin is at ``t``; its second order is left out. ``COM``: the centre
of mass, a mass-weighted mean of the joints' mass points (frames at their bodies' centres of mass; their slots
are the block's ``idx`` entries, ``m_k`` the mass fractions), on the axes of a 0/1 mask (rows: the mask's sum).
``SPHERES``: two bodies kept ``m`` apart through spheres fixed on them — on frames ``a`` and ``b`` (the bodies'
joint frames), centres ``c`` in those frames, radii ``r``, listed in pairs — by the closest pair: one row, a hinge,
whose Jacobian is the closest pair's (it switches pairs as the bodies move, like any distance between unions).
Parameters: ``n_a, n_b, m``, each body's bounding sphere (centre in its frame, radius: 4 each), a flag (1: every
pair of the two lists, 0: a 0/1 mask of the pairs follows the spheres), ``a``'s spheres and ``b``'s (centre,
radius: 4 each), the mask (``n_a × n_b``, row-major).
``SOLIDS``: the spheres of frame ``a``'s body against one solid — a sphere, box, capsule or half-space
(:data:`SOLID_SPHERE`, ...: a code, a rotation ``R`` and centre ``c``, dims; see :func:`solid_distance`) fixed in
the world, or on frame ``b`` (a link's own box) — by the closest sphere. Parameters: the solid (16), ``m``, the
count, the spheres' bounding sphere (4), the spheres (4 each).
Both keep a collision term to one row per pair of bodies (or body and obstacle) however many spheres cover them.

Layout of the block table ``bint (B, 11)`` (columns below) and ``bflt (B, 2)`` (weight, scale); parameters and
coordinate indices live in flat arrays addressed by ``PPTR`` / ``IPTR``.
"""

from __future__ import annotations

import numba
import numpy as np

# Block kinds
(POSITION, ORIENTATION, RELATIVE, COORDINATES, LIMITS, AXIS, DISTANCE, CONE, RELATIVE_LOCAL, RELATIVE_ROTATION,
 LOOK_AT, COM, SPHERES, SOLIDS) = range(14)
# Solids of a SOLIDS block (its first parameter)
SOLID_SPHERE, SOLID_BOX, SOLID_CAPSULE, SOLID_HALFSPACE = range(4)
# ρ kinds: how the residual becomes the value
NORM, HALFSIN, L1, SQUARED = 0, 1, 2, 3
# Tolerance classes: which tolerance a task block's error ‖r‖ is held to
TOL_NONE, TOL_LINEAR, TOL_ANGULAR = 0, 1, 2
# Levels: 0 value only (penalties the box already enforces), 1 task (reached first), 2 regularizer (minimized on the task)
LEVEL_VALUE, LEVEL_TASK, LEVEL_REGULARIZER = 0, 1, 2
# Columns of bint
KIND, RHO, TOL, LEVEL, ROWS, FA, FB, PPTR, IPTR, TERM, COUNT = range(11)
# Columns of bflt
WEIGHT, SCALE = 0, 1

TWO_PI = 2.0 * np.pi


@numba.njit(cache=True, inline="always")
def is_hinge(kind) -> bool:
    """Whether a block kind is one-sided: zero residual and Jacobian inside its allowed set (an inequality)."""
    return kind == DISTANCE or kind == CONE or kind == SPHERES or kind == SOLIDS


@numba.njit(cache=True, inline="always")
def wrap_angle(d):
    """``d`` wrapped to ``[−π, π)``."""
    return d - TWO_PI * np.floor((d + np.pi) / TWO_PI)


@numba.njit(cache=True)
def rotation_log(E, r) -> float:
    """``r = log(E)`` (3,) of a rotation ``E`` (9, row-major); returns the angle ``‖r‖`` in ``[0, π]``.

    Accurate at every angle: the angle from ``atan2(sin, cos)``, the axis from the skew part except near π,
    where it comes from the symmetric part ``a aᵀ = (E + Eᵀ − 2c I) / (2(1 − c))`` with its sign from the skew.
    """
    c = 0.5 * (E[0] + E[4] + E[8] - 1.0)
    c = min(1.0, max(-1.0, c))
    sx, sy, sz = E[7] - E[5], E[2] - E[6], E[3] - E[1]  # 2 sin θ · axis
    s = 0.5 * np.sqrt(sx * sx + sy * sy + sz * sz)
    theta = np.arctan2(s, c)
    if c > -0.9:
        if theta < 1e-4:
            k = 0.5 + theta * theta / 12.0  # θ / (2 sin θ)
        else:
            k = 0.5 * theta / s
        r[0], r[1], r[2] = k * sx, k * sy, k * sz
        return theta
    d0 = (E[0] - c) / (1.0 - c)
    d1 = (E[4] - c) / (1.0 - c)
    d2 = (E[8] - c) / (1.0 - c)
    if d0 >= d1 and d0 >= d2:
        a0 = np.sqrt(max(d0, 0.0))
        a1 = 0.5 * (E[1] + E[3]) / ((1.0 - c) * a0)
        a2 = 0.5 * (E[2] + E[6]) / ((1.0 - c) * a0)
    elif d1 >= d2:
        a1 = np.sqrt(max(d1, 0.0))
        a0 = 0.5 * (E[1] + E[3]) / ((1.0 - c) * a1)
        a2 = 0.5 * (E[5] + E[7]) / ((1.0 - c) * a1)
    else:
        a2 = np.sqrt(max(d2, 0.0))
        a0 = 0.5 * (E[2] + E[6]) / ((1.0 - c) * a2)
        a1 = 0.5 * (E[5] + E[7]) / ((1.0 - c) * a2)
    norm = np.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
    if a0 * sx + a1 * sy + a2 * sz < 0.0:
        norm = -norm
    r[0], r[1], r[2] = theta * a0 / norm, theta * a1 / norm, theta * a2 / norm
    return theta


@numba.njit(cache=True)
def left_jacobian_inverse(r, L):
    """``J_l⁻¹(r) = I − ½[r]× + (1/θ² − cot(θ/2)/(2θ)) [r]×²`` (3, 3): ``log(exp(ε) exp(r)) ≈ r + J_l⁻¹ ε``."""
    t2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2]
    theta = np.sqrt(t2)
    if theta < 1e-4:
        k = 1.0 / 12.0 + t2 / 720.0
    else:
        k = 1.0 / t2 - 0.5 / (theta * np.tan(0.5 * theta))
    # [r]×² = r rᵀ − θ² I
    for a in range(3):
        for b in range(3):
            L[a, b] = k * r[a] * r[b]
        L[a, a] += 1.0 - k * t2
    L[0, 1] += 0.5 * r[2]
    L[0, 2] -= 0.5 * r[1]
    L[1, 0] -= 0.5 * r[2]
    L[1, 2] += 0.5 * r[0]
    L[2, 0] += 0.5 * r[1]
    L[2, 1] -= 0.5 * r[0]


@numba.njit(cache=True, inline="always")
def block_residual(b, x, out, Jf, bint, params, idx, wrap, r, Jr, row, want_jacobian, L3, E9) -> int:
    """Residual of block ``b`` into ``r[row:]`` (and its Jacobian into ``Jr[row:]``); returns its row count.

    ``out (k, 12)`` and ``Jf (k, 6, n)`` are the frames' poses and Jacobians at ``x``; ``L3 (3, 3)``, ``E9 (9,)`` scratch.
    """
    kind, p, rows = bint[b, KIND], bint[b, PPTR], bint[b, ROWS]
    fa, fb = bint[b, FA], bint[b, FB]
    n = x.shape[0]
    if kind == POSITION:
        for c in range(3):
            r[row + c] = out[fa, 9 + c] - params[p + c]
        if want_jacobian:
            for c in range(3):
                for i in range(n):
                    Jr[row + c, i] = Jf[fa, c, i]
    elif kind == RELATIVE:
        for c in range(3):
            r[row + c] = out[fb, 9 + c] - out[fa, 9 + c] - params[p + c]
        if want_jacobian:
            for c in range(3):
                for i in range(n):
                    Jr[row + c, i] = Jf[fb, c, i] - Jf[fa, c, i]
    elif kind == ORIENTATION:
        E = E9
        for a in range(3):
            for c in range(3):  # E = R_tᵀ R
                E[3 * a + c] = (params[p + a] * out[fa, c] + params[p + 3 + a] * out[fa, 3 + c]
                                + params[p + 6 + a] * out[fa, 6 + c])
        rotation_log(E, r[row : row + 3])
        if want_jacobian:
            left_jacobian_inverse(r[row : row + 3], L3)
            for a in range(3):
                m0 = L3[a, 0] * params[p] + L3[a, 1] * params[p + 1] + L3[a, 2] * params[p + 2]
                m1 = L3[a, 0] * params[p + 3] + L3[a, 1] * params[p + 4] + L3[a, 2] * params[p + 5]
                m2 = L3[a, 0] * params[p + 6] + L3[a, 1] * params[p + 7] + L3[a, 2] * params[p + 8]
                for i in range(n):  # row a of J_l⁻¹ R_tᵀ times J_ω
                    Jr[row + a, i] = m0 * Jf[fa, 3, i] + m1 * Jf[fa, 4, i] + m2 * Jf[fa, 5, i]
    elif kind == AXIS:
        axis_residual(out, Jf, fa, params, p, r, Jr, row, want_jacobian, n)
    elif kind == CONE:
        cone_residual(out, Jf, fa, params, p, r, Jr, row, want_jacobian, n)
    elif kind == LOOK_AT:
        look_at_residual(out, Jf, fa, params, p, r, Jr, row, want_jacobian, n)
    elif kind == COM:
        com_residual(out, Jf, bint[b, IPTR], bint[b, COUNT], idx, params, p, r, Jr, row, want_jacobian, n)
    elif kind == RELATIVE_LOCAL:
        v0, v1, v2 = out[fb, 9] - out[fa, 9], out[fb, 10] - out[fa, 10], out[fb, 11] - out[fa, 11]
        for c in range(3):  # R_aᵀ v: column c of R_a (row-major) dotted with v
            r[row + c] = out[fa, c] * v0 + out[fa, 3 + c] * v1 + out[fa, 6 + c] * v2 - params[p + c]
        if want_jacobian:
            for i in range(n):
                o0, o1, o2 = Jf[fa, 3, i], Jf[fa, 4, i], Jf[fa, 5, i]
                q0 = Jf[fb, 0, i] - Jf[fa, 0, i] + v1 * o2 - v2 * o1  # ∂v + v × ω_a
                q1 = Jf[fb, 1, i] - Jf[fa, 1, i] + v2 * o0 - v0 * o2
                q2 = Jf[fb, 2, i] - Jf[fa, 2, i] + v0 * o1 - v1 * o0
                for c in range(3):
                    Jr[row + c, i] = out[fa, c] * q0 + out[fa, 3 + c] * q1 + out[fa, 6 + c] * q2
    elif kind == RELATIVE_ROTATION:
        relative_rotation_residual(out, Jf, fa, fb, params, p, r, Jr, row, want_jacobian, n, L3, E9)
    elif kind == DISTANCE:
        u0, u1, u2, dist = distance_direction(out, fa, fb, params, p)
        lo, hi = params[p + 3], params[p + 4]
        r[row] = dist - hi if dist > hi else (dist - lo if dist < lo else 0.0)
        if want_jacobian:
            active = r[row] != 0.0 and dist > 0.0
            for i in range(n):
                g = 0.0
                if active:
                    g = u0 * Jf[fa, 0, i] + u1 * Jf[fa, 1, i] + u2 * Jf[fa, 2, i]
                    if fb >= 0:
                        g -= u0 * Jf[fb, 0, i] + u1 * Jf[fb, 1, i] + u2 * Jf[fb, 2, i]
                Jr[row, i] = g
    elif kind == SPHERES:
        spheres_residual(out, Jf, fa, fb, params, p, r, Jr, row, want_jacobian, n, E9)
    elif kind == SOLIDS:
        solids_residual(out, Jf, fa, fb, params, p, r, Jr, row, want_jacobian, n, E9)
    elif kind == COORDINATES:
        q = bint[b, IPTR]
        for c in range(rows):
            k = idx[q + c]
            d = x[k] - params[p + c]
            r[row + c] = wrap_angle(d) if wrap[k] else d
            if want_jacobian:
                for i in range(n):
                    Jr[row + c, i] = 0.0
                Jr[row + c, k] = 1.0
    else:  # LIMITS
        for k in range(n):
            lo, hi = params[p + k], params[p + n + k]
            v = x[k]
            r[row + k] = v - lo if v < lo else (v - hi if v > hi else 0.0)
            if want_jacobian:
                for i in range(n):
                    Jr[row + k, i] = 0.0
                Jr[row + k, k] = 1.0 if (v < lo or v > hi) else 0.0
    return rows


@numba.njit(cache=True, inline="always")
def _on_frame(out, f, c0, c1, c2):
    """The offset ``R_f c`` (3 scalars) of a point fixed at ``c`` in frame ``f``."""
    return (out[f, 0] * c0 + out[f, 1] * c1 + out[f, 2] * c2, out[f, 3] * c0 + out[f, 4] * c1 + out[f, 5] * c2,
            out[f, 6] * c0 + out[f, 7] * c1 + out[f, 8] * c2)


@numba.njit(cache=True, inline="always")
def _hinge_row(value, r, Jr, row, want_jacobian, n) -> bool:
    """``r[row] = min(0, value)``; whether the caller writes the row's Jacobian (below zero, and wanted). A clear
    row's Jacobian is zeroed here."""
    below = value < 0.0
    r[row] = value if below else 0.0
    if want_jacobian and not below:
        for i in range(n):
            Jr[row, i] = 0.0
    return want_jacobian and below


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
def _world_point(out, f, params, q):
    """The world position (3 scalars) of the point ``params[q:q + 3]`` fixed in frame ``f``."""
    o0, o1, o2 = _on_frame(out, f, params[q], params[q + 1], params[q + 2])
    return out[f, 9] + o0, out[f, 10] + o1, out[f, 11] + o2


@numba.njit(cache=True)
def spheres_residual(out, Jf, fa, fb, params, p, r, Jr, row, want_jacobian, n, S) -> None:
    """The ``SPHERES`` residual: ``min(0, d*)`` with ``d* = min_ij ‖(p_a + R_a c_ai) − (p_b + R_b c_bj)‖ − r_ai
    − r_bj − m`` over the block's sphere pairs, and its Jacobian, the closest pair's
    ``uᵀ(J_p,a − J_p,b) + ω_a·(o_a × u) − ω_b·(o_b × u)`` (``o = R c``, the point's offset on its frame).

    Exact with two prunings: bodies whose bounding spheres are ``m`` apart are clear (every pair is at least that
    far apart), and a sphere of ``a`` farther from ``b``'s bounding sphere than the closest pair found so far
    is skipped. ``b``'s world centres go to the scratch ``S`` (3 per sphere), each computed once.
    """
    na, nb, margin = int(params[p]), int(params[p + 1]), params[p + 2]
    A0, A1, A2 = _world_point(out, fa, params, p + 3)
    B0, B1, B2 = _world_point(out, fb, params, p + 7)
    RA, RB = params[p + 6], params[p + 10]
    gap = np.sqrt((A0 - B0) ** 2 + (A1 - B1) ** 2 + (A2 - B2) ** 2) - RA - RB - margin
    if gap >= 0.0:
        _hinge_row(gap, r, Jr, row, want_jacobian, n)
        return
    full = params[p + 11] != 0.0
    qa = p + 12
    qb = qa + 4 * na
    qm = qb + 4 * nb
    for j in range(nb):
        S[3 * j], S[3 * j + 1], S[3 * j + 2] = _world_point(out, fb, params, qb + 4 * j)
    best, ai, bj = margin, -1, -1  # only pairs closer than the margin count
    for i in range(na):
        a0, a1, a2 = _world_point(out, fa, params, qa + 4 * i)
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
    if not _hinge_row(best - margin if ai >= 0 else 0.0, r, Jr, row, want_jacobian, n):
        return
    q, s = qa + 4 * ai, qb + 4 * bj
    a0, a1, a2 = _on_frame(out, fa, params[q], params[q + 1], params[q + 2])
    b0, b1, b2 = _on_frame(out, fb, params[s], params[s + 1], params[s + 2])
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


@numba.njit(cache=True)
def _solid_point_distance(out, fb, x, y, z, params, p, g) -> float:
    """:func:`solid_distance` of a world point to the solid at ``params[p:]``, fixed in the world (``fb < 0``) or
    on frame ``fb``; the gradient ``g`` in the world."""
    if fb < 0:
        return solid_distance(x, y, z, params, p, g)
    v0, v1, v2 = x - out[fb, 9], y - out[fb, 10], z - out[fb, 11]
    sd = solid_distance(out[fb, 0] * v0 + out[fb, 3] * v1 + out[fb, 6] * v2,
                        out[fb, 1] * v0 + out[fb, 4] * v1 + out[fb, 7] * v2,
                        out[fb, 2] * v0 + out[fb, 5] * v1 + out[fb, 8] * v2, params, p, g)
    g0, g1, g2 = g[0], g[1], g[2]
    g[0] = out[fb, 0] * g0 + out[fb, 1] * g1 + out[fb, 2] * g2
    g[1] = out[fb, 3] * g0 + out[fb, 4] * g1 + out[fb, 5] * g2
    g[2] = out[fb, 6] * g0 + out[fb, 7] * g1 + out[fb, 8] * g2
    return sd


@numba.njit(cache=True)
def solids_residual(out, Jf, fa, fb, params, p, r, Jr, row, want_jacobian, n, g) -> None:
    """The ``SOLIDS`` residual: ``min(0, min_k sd(p_a + R_a c_k) − r_k − m)`` for the spheres ``(c_k, r_k)`` on
    frame ``a`` against the solid at ``params[p:p + 16]`` (in the world, or on frame ``b``), and the closest
    sphere's Jacobian ``∇sdᵀ(J_p,a + ω_a × o − J_p,b − ω_b × (s − p_b))`` (``o = R_a c``, ``s`` its centre)."""
    margin, count = params[p + 16], int(params[p + 17])
    C0, C1, C2 = _world_point(out, fa, params, p + 18)
    gap = _solid_point_distance(out, fb, C0, C1, C2, params, p, g) - params[p + 21] - margin
    if gap >= 0.0:  # the spheres' bounding sphere is clear (sd is 1-Lipschitz): so is every sphere
        _hinge_row(gap, r, Jr, row, want_jacobian, n)
        return
    best, arg = 1e300, -1
    for k in range(count):
        q = p + 22 + 4 * k
        a0, a1, a2 = _world_point(out, fa, params, q)
        d = _solid_point_distance(out, fb, a0, a1, a2, params, p, g) - params[q + 3]
        if d < best:
            best, arg = d, k
    if not _hinge_row(best - margin, r, Jr, row, want_jacobian, n):
        return
    q = p + 22 + 4 * arg
    a0, a1, a2 = _on_frame(out, fa, params[q], params[q + 1], params[q + 2])
    s0, s1, s2 = out[fa, 9] + a0, out[fa, 10] + a1, out[fa, 11] + a2
    _solid_point_distance(out, fb, s0, s1, s2, params, p, g)
    w0, w1, w2 = g[0], g[1], g[2]
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
def solid_distance(x, y, z, params, p, g) -> float:
    """Signed distance [m] of the point ``(x, y, z)`` to the solid of the SOLIDS parameters at
    ``params[p:]`` (negative inside), and its gradient into ``g[:3]`` (world frame).

    The point in the solid's frame is ``q = Rᵀ(point − c)``; dims are: a sphere's radius; a box's half sides;
    a capsule's radius and half length along its z axis; nothing for a half-space (the solid is ``q_z <= 0``).
    Inside a box the gradient is the nearest face's normal.
    """
    solid = int(params[p])
    v0, v1, v2 = x - params[p + 10], y - params[p + 11], z - params[p + 12]
    q0 = params[p + 1] * v0 + params[p + 4] * v1 + params[p + 7] * v2  # Rᵀ v
    q1 = params[p + 2] * v0 + params[p + 5] * v1 + params[p + 8] * v2
    q2 = params[p + 3] * v0 + params[p + 6] * v1 + params[p + 9] * v2
    d0, d1, d2 = params[p + 13], params[p + 14], params[p + 15]
    l0, l1, l2 = 0.0, 0.0, 0.0  # the gradient in the solid's frame
    if solid == SOLID_HALFSPACE:
        sd, l2 = q2, 1.0
    elif solid == SOLID_BOX:
        a0, a1, a2 = abs(q0) - d0, abs(q1) - d1, abs(q2) - d2
        o0, o1, o2 = max(a0, 0.0), max(a1, 0.0), max(a2, 0.0)
        outside = np.sqrt(o0 * o0 + o1 * o1 + o2 * o2)
        s0, s1, s2 = (1.0 if q0 >= 0.0 else -1.0), (1.0 if q1 >= 0.0 else -1.0), (1.0 if q2 >= 0.0 else -1.0)
        if outside > 0.0:
            sd = outside
            l0, l1, l2 = s0 * o0 / outside, s1 * o1 / outside, s2 * o2 / outside
        elif a0 >= a1 and a0 >= a2:
            sd, l0 = a0, s0
        elif a1 >= a2:
            sd, l1 = a1, s1
        else:
            sd, l2 = a2, s2
    else:  # a sphere (the capsule's segment of half length 0) or a capsule
        if solid == SOLID_CAPSULE:
            q2 -= min(d1, max(-d1, q2))
        norm = np.sqrt(q0 * q0 + q1 * q1 + q2 * q2)
        sd = norm - d0
        if norm > 0.0:
            l0, l1, l2 = q0 / norm, q1 / norm, q2 / norm
        else:
            l2 = 1.0
    for c in range(3):  # g = R l
        g[c] = params[p + 1 + 3 * c] * l0 + params[p + 2 + 3 * c] * l1 + params[p + 3 + 3 * c] * l2
    return sd


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


@numba.njit(cache=True)
def rho_value(rho, scale, r, row, rows) -> float:
    """The value of a block from its residual ``r[row:row + rows]``."""
    if rho == L1:
        s = 0.0
        for c in range(rows):
            s += abs(r[row + c])
        return scale * s
    s = 0.0
    for c in range(rows):
        s += r[row + c] * r[row + c]
    if rho == SQUARED:
        return scale * s
    norm = np.sqrt(s)
    if rho == HALFSIN:
        return scale * np.sin(0.5 * min(norm, np.pi))
    return scale * norm


@numba.njit(cache=True)
def rho_derivatives(rho, scale, r, row, rows, smoothing, g, H, majorize_below=0.0):
    """Gradient ``g (rows,)`` and Hessian ``H (rows, rows)`` of the block value with respect to its residual.

    The norm-like ρ are not differentiable at ``r = 0``; there they are smoothed as ``√(‖r‖² + ε²)`` (``|r|`` per
    component for L1) with ``ε = smoothing``, which changes the value by at most ``scale · ε`` per block.
    A norm shorter than ``majorize_below`` gets the majorizing curvature ``scale/‖r‖ · I`` instead of its own
    ``scale/‖r‖ · (I − uuᵀ)`` (flat along ``u``): a Newton step then moves it straight to (not past) zero, where
    an optimum with a joint group at rest sits.
    """
    for a in range(rows):
        for c in range(rows):
            H[a, c] = 0.0
    if rho == SQUARED:
        for a in range(rows):
            g[a] = 2.0 * scale * r[row + a]
            H[a, a] = 2.0 * scale
        return
    if rho == L1:
        e2 = smoothing * smoothing
        for a in range(rows):
            v = r[row + a]
            d = np.sqrt(v * v + e2)
            g[a] = scale * v / d
            H[a, a] = scale * e2 / (d * d * d)
        return
    s = 0.0
    for a in range(rows):
        s += r[row + a] * r[row + a]
    if rho == NORM:
        d = np.sqrt(s + smoothing * smoothing)
        radial = 0.0 if d < majorize_below else 1.0
        for a in range(rows):
            g[a] = scale * r[row + a] / d
            for c in range(rows):
                H[a, c] = -radial * scale * r[row + a] * r[row + c] / (d * d * d)
            H[a, a] += scale / d
        return
    # HALFSIN: ρ = s sin(φ/2), φ = ‖r‖ (smoothed): ∇ρ = ½ s cos(φ/2) u, ∇²ρ = s[½cos(φ/2)/φ (I − uuᵀ) − ¼ sin(φ/2) uuᵀ]
    phi = np.sqrt(s + smoothing * smoothing)
    c1 = 0.5 * scale * np.cos(0.5 * phi)
    c2 = 0.25 * scale * np.sin(0.5 * phi)
    for a in range(rows):
        ua = r[row + a] / phi
        g[a] = c1 * ua
        for c in range(rows):
            uc = r[row + c] / phi
            H[a, c] = -(c1 / phi + c2) * ua * uc
        H[a, a] += c1 / phi


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
            or kind == LOOK_AT or kind == SPHERES or kind == SOLIDS:
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
        lo, hi = chain_ptr[fa], chain_ptr[fa + 1]
        for s in range(lo, hi):
            i = chain_idx[s]
            wx, wy, wz = Jf[fa, 3, i], Jf[fa, 4, i], Jf[fa, 5, i]
            if wx == 0.0 and wy == 0.0 and wz == 0.0:
                continue
            for t in range(s + 1, hi):
                j = chain_idx[t]
                vx, vy, vz = Jf[fa, 3, j], Jf[fa, 4, j], Jf[fa, 5, j]
                h = 0.5 * (m0 * (wy * vz - wz * vy) + m1 * (wz * vx - wx * vz) + m2 * (wx * vy - wy * vx))
                H[i, j] += h
                H[j, i] += h
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
        uD = np.zeros(n)
        for i in range(n):
            uD[i] = u[0] * D[0, i] + u[1] * D[1, i] + u[2] * D[2, i]
        k = mu[0] / dist
        for i in range(n):
            for j in range(n):
                H[i, j] += k * (D[0, i] * D[0, j] + D[1, i] * D[1, j] + D[2, i] * D[2, j] - uD[i] * uD[j])
        return
    frames = (bint[b, FA], bint[b, FB]) if kind == RELATIVE else (bint[b, FA], -1)
    for which in range(2):
        f = frames[which]
        if f < 0:
            continue
        sign = -1.0 if (kind == RELATIVE and which == 0) else 1.0
        _position_curvature(f, sign * mu[0], sign * mu[1], sign * mu[2], Jf, chain_ptr, chain_idx, H)


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