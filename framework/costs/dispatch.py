"""One block's residual and Jacobian, by its kind: the branch of every kind (see :mod:`~.blocks` for the table), the
positions and orientations inline, the others in :mod:`~.goal_blocks` and :mod:`~.collision_blocks`."""

from __future__ import annotations

import numba

from .blocks import (AXIS, COM, CONE, COORDINATES, COUNT, DISTANCE, FA, FB, IPTR, KIND, LOOK_AT, ORIENTATION, POSITION,
                     PPTR, RELATIVE, RELATIVE_LOCAL, RELATIVE_ROTATION, ROWS, SOLIDS, SPHERES,
                     left_jacobian_inverse, rotation_log, wrap_angle)
from .collision_blocks import solids_residual, spheres_residual
from .goal_blocks import (axis_residual, com_residual, cone_residual, distance_direction, look_at_residual,
                          relative_rotation_residual)


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
            _translation_jacobian(Jf, fa, -1, Jr, row, n)
    elif kind == RELATIVE:
        for c in range(3):
            r[row + c] = out[fb, 9 + c] - out[fa, 9 + c] - params[p + c]
        if want_jacobian:
            _translation_jacobian(Jf, fb, fa, Jr, row, n)
    elif kind == ORIENTATION:
        E = E9
        for a in range(3):
            for c in range(3):  # E = R_tᵀ R
                E[3 * a + c] = (params[p + a] * out[fa, c] + params[p + 3 + a] * out[fa, 3 + c]
                                + params[p + 6 + a] * out[fa, 6 + c])
        rotation_log(E, r[row : row + 3])
        if want_jacobian:
            _orientation_jacobian(Jf, fa, params, p, r, Jr, row, n, L3)
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


@numba.njit(cache=True)
def block_jacobian(b, out, Jf, bint, params, r, Jr, row, L3) -> int:
    """The Jacobian rows of block ``b`` into ``Jr[row:]`` from its residual rows ``r[row:]``, already written at
    these poses, for a position, relative position or orientation block (returns its row count; ``-1`` for other
    kinds: :func:`block_residual` evaluates them whole). An accepted step's poses were evaluated for its residual:
    its Jacobian needs no second rotation log."""
    kind, p = bint[b, KIND], bint[b, PPTR]
    n = Jf.shape[2]
    if kind == POSITION:
        _translation_jacobian(Jf, bint[b, FA], -1, Jr, row, n)
    elif kind == RELATIVE:
        _translation_jacobian(Jf, bint[b, FB], bint[b, FA], Jr, row, n)
    elif kind == ORIENTATION:
        _orientation_jacobian(Jf, bint[b, FA], params, p, r, Jr, row, n, L3)
    else:
        return -1
    return bint[b, ROWS]


@numba.njit(cache=True, inline="always")
def _translation_jacobian(Jf, f, minus, Jr, row, n) -> None:
    """``Jr[row:row + 3]``: the translation rows of frame ``f``'s Jacobian, less frame ``minus``'s (``-1``: none)."""
    for c in range(3):
        for i in range(n):
            Jr[row + c, i] = Jf[f, c, i] if minus < 0 else Jf[f, c, i] - Jf[minus, c, i]


@numba.njit(cache=True, inline="always")
def _orientation_jacobian(Jf, fa, params, p, r, Jr, row, n, L3) -> None:
    """``Jr[row:row + 3] = J_l⁻¹(r) R_tᵀ J_ω`` of an orientation block with residual ``r[row:row + 3] = log(R_tᵀ R)``
    (``R_t``: the target rotation, row-major at ``params[p:p + 9]``); ``L3 (3, 3)`` scratch."""
    left_jacobian_inverse(r[row : row + 3], L3)
    for a in range(3):
        m0 = L3[a, 0] * params[p] + L3[a, 1] * params[p + 1] + L3[a, 2] * params[p + 2]
        m1 = L3[a, 0] * params[p + 3] + L3[a, 1] * params[p + 4] + L3[a, 2] * params[p + 5]
        m2 = L3[a, 0] * params[p + 6] + L3[a, 1] * params[p + 7] + L3[a, 2] * params[p + 8]
        for i in range(n):  # row a of J_l⁻¹ R_tᵀ times J_ω
            Jr[row + a, i] = m0 * Jf[fa, 3, i] + m1 * Jf[fa, 4, i] + m2 * Jf[fa, 5, i]
