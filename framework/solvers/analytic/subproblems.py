"""The Paden-Kahan subproblems: the rotations about known axes that take known points to known places, in closed form.

Every closed-form 6R solution here is a short sequence of them (:mod:`~framework.solvers.analytic.families`).
Vectors are 3-tuples (values on the stack: no allocation, a microsecond saved per solve), a point is given
relative to a point on the axis, axes are unit vectors.

- :func:`sp1`: θ with ``rot(k, θ) p = q`` (``p``, ``q`` at the same height along ``k`` and distance from it);
- :func:`sp4`: θ with ``hᵀ rot(k, θ) p = d`` — up to two;
- :func:`sp3`: θ with ``‖rot(k, θ) p − q‖ = d`` — up to two (a :func:`sp4` in disguise);
- :func:`sp2`: ``(θ1, θ2)`` with ``rot(k1, θ1) rot(k2, θ2) p = q`` — up to two pairs (:func:`sp4`, then :func:`sp1`).

Where a subproblem has every angle as a solution (a point on the axis; a singular wrist) it reports so and the
caller chooses the angle (the reference configuration's). Where it has none by a hair (a target at the edge of
the workspace, |cos| within :data:`EDGE` of 1), the nearest angle is taken: the caller checks every solution by
forward kinematics and keeps the exact ones only.
"""

from __future__ import annotations

import numpy as np

from ...compiled.native import internal

#: |cos| up to 1 + EDGE is taken as 1 (rounding at the workspace's edge), beyond it there is no solution.
EDGE = 1e-9
#: Below this (relative) size a subproblem's equation does not depend on its angle: every angle solves it.
FREE = 1e-12


@internal(inline=True)
def row(A, i):
    """Row ``i`` of ``A`` as a 3-tuple."""
    return (A[i, 0], A[i, 1], A[i, 2])


@internal(inline=True)
def column(A, j):
    """Column ``j`` of ``A`` as a 3-tuple."""
    return (A[0, j], A[1, j], A[2, j])


@internal(inline=True)
def add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


@internal(inline=True)
def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@internal(inline=True)
def scale(s, a):
    return (s * a[0], s * a[1], s * a[2])


@internal(inline=True)
def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@internal(inline=True)
def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@internal(inline=True)
def norm(a):
    return np.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])


@internal(inline=True)
def times(A, v):
    """``A v`` for the top-left ``(3, 3)`` block of an array ``A``."""
    return (A[0, 0] * v[0] + A[0, 1] * v[1] + A[0, 2] * v[2], A[1, 0] * v[0] + A[1, 1] * v[1] + A[1, 2] * v[2],
            A[2, 0] * v[0] + A[2, 1] * v[1] + A[2, 2] * v[2])


@internal(inline=True)
def times_transposed(A, v):
    """``Aᵀ v`` for the top-left ``(3, 3)`` block of an array ``A``."""
    return (A[0, 0] * v[0] + A[1, 0] * v[1] + A[2, 0] * v[2], A[0, 1] * v[0] + A[1, 1] * v[1] + A[2, 1] * v[2],
            A[0, 2] * v[0] + A[1, 2] * v[1] + A[2, 2] * v[2])


@internal(inline=True)
def rotate(k, theta, v):
    """``rot(k, θ) v`` (Rodrigues)."""
    return rotate_cs(k, np.cos(theta), np.sin(theta), v)


@internal(inline=True)
def rotate_cs(k, c, s, v):
    """``rot(k, θ) v`` given ``cos θ``, ``sin θ``."""
    kv = (1.0 - c) * dot(k, v)
    kxv = cross(k, v)
    return (v[0] * c + kxv[0] * s + k[0] * kv, v[1] * c + kxv[1] * s + k[1] * kv, v[2] * c + kxv[2] * s + k[2] * kv)


@internal(inline=True)
def sp1(p, q, k, free):
    """θ with ``rot(k, θ) p = q`` (least squares when they differ in height or distance); ``free`` when ``p`` lies
    on the axis (every θ)."""
    return sp1_cs(p, q, k, free)[0]


@internal(inline=True)
def sp4(h, p, k, d, free):
    """θ with ``hᵀ rot(k, θ) p = d``: ``(count, θa, θb)``, count 0 (none), 1, 2, or 3 (every θ: ``θa = free``)."""
    count, ta, _, _, tb, _, _ = sp4_cs(h, p, k, d, free)
    return count, ta, tb


@internal(inline=True)
def sp3(p, q, k, d, free):
    """θ with ``‖rot(k, θ) p − q‖ = d`` (``p``, ``q`` relative to a point on the axis): as :func:`sp4`."""
    return sp4(q, p, k, 0.5 * (dot(p, p) + dot(q, q) - d * d), free)


@internal(inline=True)
def sp2(p, q, k1, k2, free1, free2):
    """``(θ1, θ2)`` with ``rot(k1, θ1) rot(k2, θ2) p = q``: ``(count, θ1a, θ2a, θ1b, θ2b)`` (count as :func:`sp4`;
    with 3, θ1 is free and set to ``free1``)."""
    count, ta, tb = sp4(k2, q, k1, dot(k2, p), -free1)  # rot(k1, −θ1) q lies at p's height along k2
    if count == 0:
        return 0, 0.0, 0.0, 0.0, 0.0
    t2a = sp1(p, rotate(k1, ta, q), k2, free2)
    t2b = sp1(p, rotate(k1, tb, q), k2, free2)
    return count, -ta, t2a, -tb, t2b


@internal(inline=True)
def sp1_cs(p, q, k, free):
    """:func:`sp1` with the angle's cosine and sine (from the same products: no trigonometry): ``(θ, cos, sin)``."""
    a = sub(p, scale(dot(k, p), k))
    b = sub(q, scale(dot(k, q), k))
    c = dot(k, cross(a, b))
    d = dot(a, b)
    r = np.sqrt(c * c + d * d)
    if r <= FREE * (1.0 + dot(a, a) + dot(b, b)):
        return free, np.cos(free), np.sin(free)
    return np.arctan2(c, d), d / r, c / r


@internal(inline=True)
def sp4_cs(h, p, k, d, free):
    """:func:`sp4` with each angle's cosine and sine: ``(count, θa, cos θa, sin θa, θb, cos θb, sin θb)``."""
    hk, kp = dot(h, k), dot(k, p)
    a = dot(h, p) - hk * kp
    b = dot(h, cross(k, p))
    rest = d - hk * kp
    r = np.sqrt(a * a + b * b)
    size = 1.0 + norm(p) + abs(d)
    if r <= FREE * size:
        if abs(rest) <= 1e-9 * size:
            cf, sf = np.cos(free), np.sin(free)
            return 3, free, cf, sf, free, cf, sf
        return 0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0
    c = rest / r
    if abs(c) > 1.0 + EDGE:
        return 0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0
    c = min(1.0, max(-1.0, c))
    phi, delta = np.arctan2(b, a), np.arccos(c)
    cp, sp, sd = a / r, b / r, np.sqrt(max(0.0, 1.0 - c * c))
    count = 1 if delta == 0.0 else 2
    return (count, phi + delta, cp * c - sp * sd, sp * c + cp * sd,
            phi - delta, cp * c + sp * sd, sp * c - cp * sd)


@internal(inline=True)
def sp3_cs(p, q, k, d, free):
    """:func:`sp3` with each angle's cosine and sine, as :func:`sp4_cs`."""
    return sp4_cs(q, p, k, 0.5 * (dot(p, p) + dot(q, q) - d * d), free)


@internal(inline=True)
def branches(count):
    """How many solutions a subproblem's count gives to loop over (a free angle: one)."""
    return 2 if count == 2 else (0 if count == 0 else 1)
