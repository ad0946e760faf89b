"""Weighted sums: damped Newton steps on ``Σ w ρ(r)`` of every term as it stands, and exact penalties.

For objectives where reaching the task costs more than it gains (the papers' weighted objectives with small task
weights): :func:`weighted_newton` minimizes the whole sum in the box with the same second-order kinematics as the
Newton phase; :func:`exact_penalties` tells which task blocks pay for themselves at a point on the task.
"""

from __future__ import annotations

import numpy as np

from ..costs.blocks import HALFSIN, LEVEL_TASK, NORM
from ..costs.kernels import COMPUTE, TASK_AND_REGULARIZERS, YES, level_value, linearize
from ..costs.workspace import workspaces
from ..compiled.native import compiled, internal, keep_alive, matrix
from .clock import monotonic_ns
from .derivatives import objective_derivatives
from .linalg import cholesky_solve
from .newton_state import CONVERGED, DEADLINE, ITERATIONS, MU_MAX, MU_MIN, MU_START, STALLED
from .steps import copy, held, project, squared_norm
from .tables import max_rows


@compiled
def weighted_newton(x, box, packed, settings, stats) -> int:
    """Minimize ``Σ w ρ(r)`` over every task and regularizer block from ``x`` (in place), within the box.

    ``settings``: :class:`~.settings.NewtonSettings`; ``stats`` ``int64 (3,)``: iterations, evaluations, accepted
    steps. Returns ``CONVERGED``, ``STALLED``, ``DEADLINE`` or ``ITERATIONS``.
    """
    n = x.shape[0]
    owners, W = workspaces(packed, n, 2)
    cur, tri = W[0], W[1]
    linearize(x, cur, TASK_AND_REGULARIZERS, YES, COMPUTE)
    big = max_rows(packed.blocks)
    g, H, Hf, Lf, gf, sf, xt = np.empty(n), np.empty((n, n)), np.empty(n * n), np.empty(n * n), np.empty(n), \
        np.empty(n), np.empty(n)
    gr, mu_r, Hr = np.empty(big), np.empty(big), np.empty((big, big))
    every = np.zeros(packed.blocks.shape[0], dtype=np.int8)  # no block left out
    fidx = np.empty(n, dtype=np.int64)
    F = objective_derivatives(cur, TASK_AND_REGULARIZERS, settings.smoothing, YES, 0.0, every, g, H, gr, Hr, mu_r)
    mu, status, iterations, accepted, evaluations = MU_START, ITERATIONS, 0, 0, 1
    fresh = True
    while iterations < settings.max_iterations:
        if settings.deadline_ns > 0 and monotonic_ns() >= settings.deadline_ns:
            status = DEADLINE
            break
        iterations += 1
        if not fresh:
            F = objective_derivatives(cur, TASK_AND_REGULARIZERS, settings.smoothing, YES, 0.0, every, g, H, gr, Hr,
                                      mu_r)
            fresh = True
        nf = 0
        for i in range(n):  # the coordinates descent along −g does not push through a bound
            if not held(x[i], box.lower[i], box.upper[i], box.wraps[i], -g[i]):
                fidx[nf] = i
                nf += 1
        if nf == 0:
            status = CONVERGED
            break
        step = _newton_step(x, g, H, mu, fidx, nf, Hf, Lf, gf, sf, xt)
        if step < 0.0:  # not positive definite
            mu = max(mu * 10.0, 1e-10)
            if mu > MU_MAX:
                status = STALLED
                break
            continue
        project(xt, box)
        linearize(xt, tri, TASK_AND_REGULARIZERS, YES, COMPUTE)
        evaluations += 1
        Ft = level_value(tri, TASK_AND_REGULARIZERS, YES)
        if Ft < F:
            gain = F - Ft
            cur, tri = tri, cur
            copy(x, xt)
            F = Ft
            fresh = False
            accepted += 1
            mu = max(mu * 0.1, MU_MIN)
            if step < 1e-10 or gain <= 1e-16 * (1.0 + abs(F)):
                status = CONVERGED
                break
        else:
            if step < 1e-12:
                status = CONVERGED
                break
            mu *= 10.0
            if mu > MU_MAX:
                status = STALLED
                break
    stats[0], stats[1], stats[2] = iterations, evaluations, accepted
    keep_alive(owners, packed)
    return status


@internal
def _newton_step(x, g, H, mu, fidx, nf, Hf, Lf, gf, sf, xt) -> float:
    """``xt = x + s`` with ``(H + μI) s = −g`` over the free coordinates ``fidx[:nf]`` (``Hf, Lf`` flat
    scratch); returns the step's largest coordinate change, or ``−1`` where ``H + μI`` is not positive definite."""
    Hv, Lv, gv, sv = matrix(Hf, nf, nf), matrix(Lf, nf, nf), gf[:nf], sf[:nf]
    for a in range(nf):
        for c in range(nf):
            Hv[a, c] = H[fidx[a], fidx[c]]
        Hv[a, a] += mu
        gv[a] = -g[fidx[a]]
    if not cholesky_solve(Hv, gv, Lv, sv):
        return -1.0
    step = 0.0
    copy(xt, x)
    for a in range(nf):
        xt[fidx[a]] += sv[a]
        step = max(step, abs(sv[a]))
    return step


@internal
def exact_penalties(blocks, multipliers, pays) -> bool:
    """Whether each task block (level 1, in block order) is an exact penalty for its rows of ``multipliers``,
    into ``pays (blocks,)``; returns whether every one is.

    A block weighted ``w`` with ``ρ = s‖r‖`` is one when ``‖λ_b‖ < w s`` (``w s / 2`` for ``ρ = s sin(‖r‖/2)``):
    then no move off the block lowers the weighted sum. Blocks with other ρ never are.
    """
    row = k = 0
    every = True
    for b in range(blocks.shape[0]):
        block = blocks[b]
        if block.level != LEVEL_TASK:
            continue
        slope = 1.0 if block.rho == NORM else (0.5 if block.rho == HALFSIN else 0.0)
        norm = np.sqrt(squared_norm(multipliers[row:], block.rows))
        pays[k] = slope > 0.0 and norm < block.weight * block.scale * slope
        every = every and pays[k]
        row += block.rows
        k += 1
    return every


@compiled
def exact_penalty(x, box, blocks, multipliers) -> bool:
    """Whether the task's multipliers make every task block an exact penalty at ``x`` (see
    :func:`exact_penalties`): then ``x`` also minimizes the weighted sum locally. ``False`` on the box
    boundary (bound multipliers are not computed)."""
    for i in range(x.shape[0]):
        if not box.wraps[i] and (x[i] <= box.lower[i] or x[i] >= box.upper[i]):
            return False
    return exact_penalties(blocks, multipliers, np.empty(blocks.shape[0], dtype=np.bool_))


@compiled
def released_penalties(blocks, multipliers, pays) -> bool:
    """:func:`exact_penalties` for callers in Python."""
    return exact_penalties(blocks, multipliers, pays)
