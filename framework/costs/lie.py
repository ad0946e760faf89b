"""Rotations and points on frames for the block kernels: ``log`` on SO(3), ``J_l⁻¹``, offsets and world points.

Poses are rows of 12: the rotation row-major, then the position (:mod:`framework.model.kinematics`).
"""

from __future__ import annotations

import numpy as np

from ..compiled.native import internal
from ..compiled.trig import sincos

TWO_PI = 2.0 * np.pi


@internal(inline=True)
def wrap_angle(d):
    """``d`` wrapped to ``[−π, π)``."""
    return d - TWO_PI * np.floor((d + np.pi) / TWO_PI)


@internal(inline=True)
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


@internal(inline=True)
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


@internal(inline=True)
def on_frame(poses, f, c0, c1, c2):
    """The offset ``R_f c`` (3 scalars) of a point fixed at ``c`` in frame ``f``."""
    return (poses[f, 0] * c0 + poses[f, 1] * c1 + poses[f, 2] * c2,
            poses[f, 3] * c0 + poses[f, 4] * c1 + poses[f, 5] * c2,
            poses[f, 6] * c0 + poses[f, 7] * c1 + poses[f, 8] * c2)


@internal(inline=True)
def world_point(poses, f, params, q):
    """The world position (3 scalars) of the point ``params[q:q + 3]`` fixed in frame ``f``."""
    o0, o1, o2 = on_frame(poses, f, params[q], params[q + 1], params[q + 2])
    return poses[f, 9] + o0, poses[f, 10] + o1, poses[f, 11] + o2
