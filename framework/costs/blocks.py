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
``AXIS``        ``Bᵀ θ/sinθ (d × R_a e)`` (2) [rad], norm = θ  see :func:`~.goal_blocks.axis_residual`  ``e, d, b₁, b₂`` (12)
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
whose Jacobian is the closest pair's (it switches pairs as the bodies move, like any distance between unions), and so
is its second order (:mod:`~.curvature`).
Parameters: ``n_a, n_b, m``, each body's bounding sphere (centre in its frame, radius: 4 each), a flag (1: every
pair of the two lists, 0: a 0/1 mask of the pairs follows the spheres), ``a``'s spheres and ``b``'s (centre,
radius: 4 each), the mask (``n_a × n_b``, row-major).
``SOLIDS``: the spheres of frame ``a``'s body against one solid — a sphere, box, capsule or half-space
(a row of :mod:`framework.solids`: a code, a rotation ``R`` and centre ``c``, dims) fixed in
the world, or on frame ``b`` (a link's own box) — by the closest sphere; its second order is left out. Parameters: the solid (16), ``m``, the
count, the spheres' bounding sphere (4), the spheres (4 each).
Both keep a collision term to one row per pair of bodies (or body and obstacle) however many spheres cover them.

Layout of the block table ``bint (B, 11)`` (columns below) and ``bflt (B, 2)`` (weight, scale); parameters and
coordinate indices live in flat arrays addressed by ``PPTR`` / ``IPTR``.

This module holds the table's constants, the rotation and frame helpers every kind uses and the ρ functions; the
kinds' kernels are in :mod:`~.goal_blocks` (directions, distances, relative poses, centre of mass) and
:mod:`~.collision_blocks` (sphere pairs, solids), one residual per kind dispatched by :func:`~.dispatch.block_residual`,
their second order by :func:`~.curvature.block_curvature`.
"""

from __future__ import annotations

import numba
import numpy as np

from ..trig import sincos

# Block kinds
(POSITION, ORIENTATION, RELATIVE, COORDINATES, LIMITS, AXIS, DISTANCE, CONE, RELATIVE_LOCAL, RELATIVE_ROTATION,
 LOOK_AT, COM, SPHERES, SOLIDS) = range(14)
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
def is_contact(kind) -> bool:
    """Whether a block kind is a collision row (``SPHERES``, ``SOLIDS``: a signed distance held above a margin)."""
    return kind == SPHERES or kind == SOLIDS


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
        sh, ch = sincos(0.5 * theta)
        k = 1.0 / t2 - 0.5 * ch / (theta * sh)  # cot(θ/2) = cos / sin
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
def on_frame(out, f, c0, c1, c2):
    """The offset ``R_f c`` (3 scalars) of a point fixed at ``c`` in frame ``f``."""
    return (out[f, 0] * c0 + out[f, 1] * c1 + out[f, 2] * c2, out[f, 3] * c0 + out[f, 4] * c1 + out[f, 5] * c2,
            out[f, 6] * c0 + out[f, 7] * c1 + out[f, 8] * c2)


@numba.njit(cache=True, inline="always")
def hinge_row(value, r, Jr, row, want_jacobian, n) -> bool:
    """``r[row] = min(0, value)``; whether the caller writes the row's Jacobian (below zero, and wanted). A clear
    row's Jacobian is zeroed here."""
    below = value < 0.0
    r[row] = value if below else 0.0
    if want_jacobian and not below:
        for i in range(n):
            Jr[row, i] = 0.0
    return want_jacobian and below


@numba.njit(cache=True, inline="always")
def world_point(out, f, params, q):
    """The world position (3 scalars) of the point ``params[q:q + 3]`` fixed in frame ``f``."""
    o0, o1, o2 = on_frame(out, f, params[q], params[q + 1], params[q + 2])
    return out[f, 9] + o0, out[f, 10] + o1, out[f, 11] + o2


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
        return scale * sincos(0.5 * min(norm, np.pi))[0]
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
    sh, ch = sincos(0.5 * phi)
    c1, c2 = 0.5 * scale * ch, 0.25 * scale * sh
    for a in range(rows):
        ua = r[row + a] / phi
        g[a] = c1 * ua
        for c in range(rows):
            uc = r[row + c] / phi
            H[a, c] = -(c1 / phi + c2) * ua * uc
        H[a, a] += c1 / phi
