"""Steps in the search box: damped Gauss-Newton steps, bounds held, projection, the gain ratio."""

from __future__ import annotations

import numpy as np

from ..compiled.native import internal, square
from .linalg import least_norm_step, levenberg_marquardt_step, moving_columns, moving_columns_step

#: ``μ``'s smallest factor after an accepted step (Nielsen's rule; see :mod:`~framework.engine.reach`).
DAMPING_DOWN = 1.0 / 3.0


@internal(inline=True)
def project(x, box) -> None:
    """``x`` into the box in place: clipped, or wrapped into ``[lower, lower + 2π)`` on full-turn axes."""
    lower, upper, wraps = box
    for i in range(x.shape[0]):
        if wraps[i]:
            x[i] = lower[i] + np.mod(x[i] - lower[i], 2.0 * np.pi)
        elif x[i] < lower[i]:
            x[i] = lower[i]
        elif x[i] > upper[i]:
            x[i] = upper[i]


@internal(inline=True)
def copy(target, source) -> None:
    """``target[:] = source`` for 1-D arrays of one length (a loop: a slice assignment compiles a shape check with
    its formatted message)."""
    for i in range(target.shape[0]):
        target[i] = source[i]


@internal(inline=True)
def damped_step(Jr, r, damping, A, L, y, dx) -> bool:
    """The Levenberg-Marquardt step ``dx = −(JᵀJ + λI)⁻¹Jᵀr = −Jᵀ(JJᵀ + λI)⁻¹r``, in the smaller of the two
    systems (``A, L`` flat buffers of at least ``k²`` with ``k = min(m, n)``, ``y`` at least ``max(m, n)``; their
    leading parts are used, as contiguous ``(k, k)`` matrices: with ``[:k, :k]`` slices, strided, the step cost
    a third more). Where fewer columns than rows move the rows (``m < n`` coordinates, but at most ``m`` of them
    nonzero columns: a full pose of a short limb on a whole robot, coordinates held at their bounds), ``J Jᵀ`` is
    singular: the step is solved over the moving columns instead (:func:`~.linalg.moving_columns_step`; the same
    step, without losing the last, lightly damped ones to rounding)."""
    m, n = Jr.shape
    k = min(m, n)
    Ak, Lk = square(A, k), square(L, k)
    if m < n:
        nz = moving_columns(Jr, m)
        if nz <= m:
            return moving_columns_step(Jr, r, damping, square(A, nz), square(L, nz), y[:nz], dx, nz)
        return least_norm_step(Jr, r, damping, Ak, Lk, y[:k], dx)
    return levenberg_marquardt_step(Jr, r, damping, Ak, Lk, y[:k], dx)


@internal(inline=True)
def held(x, lower, upper, wraps, d) -> bool:
    """Whether a coordinate at ``x`` in ``[lower, upper]`` (``wraps``: no bounds) sits on a bound that a move in
    direction ``d`` (its sign) pushes through."""
    return not wraps and ((x <= lower and d < 0.0) or (x >= upper and d > 0.0))


@internal(inline=True)
def bounded_step(x, Jr, r, damping, box, Jc, A, L, y, dx) -> bool:
    """:func:`damped_step`, then again without the coordinates it would push through a bound they sit on."""
    if not damped_step(Jr, r, damping, A, L, y, dx):
        return False
    lower, upper, wraps = box
    m, n = Jr.shape
    blocked = False
    for i in range(n):
        if held(x[i], lower[i], upper[i], wraps[i], dx[i]):
            blocked = True
            break
    if not blocked:
        return True
    for i in range(n):
        keep = not held(x[i], lower[i], upper[i], wraps[i], dx[i])
        for a in range(m):
            Jc[a, i] = Jr[a, i] if keep else 0.0
    return damped_step(Jc, r, damping, A, L, y, dx)


@internal
def projected_step(x, Jr, r, damping, box, Jc, pins, A, L, y, dx) -> bool:
    """:func:`bounded_step`, then, while the step carries coordinates through their bounds, those moved onto the
    bounds and the step solved again for the others (with the pinned moves' effect ``J_i (b_i − x_i)`` added to
    the residual): a Gauss-Newton step projected on the box, where a clipped one is a partial step (a polish near
    a whole body's limits converged linearly, 3 steps leaving ``1e-7``). ``pins`` scratch of ``m + n``."""
    if not bounded_step(x, Jr, r, damping, box, Jc, A, L, y, dx):
        return False
    lower, upper, wraps = box
    m, n = Jr.shape
    rp, side = pins[:m], pins[m : m + n]  # the residual with the pinned moves; -1 / +1: pinned at lower / upper
    side[:] = 0.0
    for _ in range(n):
        new = False
        for i in range(n):
            if side[i] == 0.0 and not wraps[i]:
                t = x[i] + dx[i]
                if t < lower[i] or t > upper[i]:
                    side[i] = -1.0 if t < lower[i] else 1.0
                    new = True
        if not new:
            return True
        for a in range(m):
            s = r[a]
            for i in range(n):
                if side[i] != 0.0:
                    s += Jr[a, i] * ((lower[i] if side[i] < 0.0 else upper[i]) - x[i])
                    Jc[a, i] = 0.0
                else:
                    Jc[a, i] = Jr[a, i]
            rp[a] = s
        if not damped_step(Jc, rp, damping, A, L, y, dx):
            return False
        for i in range(n):
            if side[i] != 0.0:
                dx[i] = (lower[i] if side[i] < 0.0 else upper[i]) - x[i]
    return True


@internal(inline=True)
def gain_factor(e, et, Jr, r, x, xt, dx, wraps) -> float:
    """Nielsen's factor of ``μ`` after an accepted step from ``x`` to ``xt`` that took ``‖r‖²`` from ``e`` to
    ``et``: ``max(DAMPING_DOWN, 1 − (2ρ − 1)³)`` with ``ρ = (e − et) / (e − ‖r + J d‖²)``, ``d`` the step taken
    (``xt − x``: clipped at the bounds; ``dx`` on coordinates that wrap around)."""
    m, n = Jr.shape
    model = 0.0
    for a in range(m):
        s = r[a]
        for i in range(n):
            s += Jr[a, i] * (dx[i] if wraps[i] else xt[i] - x[i])
        model += s * s
    predicted = e - model
    if not predicted > 0.0:
        return DAMPING_DOWN
    t = 2.0 * (e - et) / predicted - 1.0
    return max(DAMPING_DOWN, 1.0 - t * t * t)


@internal(inline=True)
def squared_norm(r, m) -> float:
    """``‖r[:m]‖²``."""
    s = 0.0
    for i in range(m):
        s += r[i] * r[i]
    return s


@internal(inline=True)
def squared_entries(J, m) -> float:
    """``‖J[:m]‖²``: the sum of the squared entries of the first ``m`` rows of ``J``."""
    s = 0.0
    for a in range(m):
        for i in range(J.shape[1]):
            s += J[a, i] * J[a, i]
    return s
