"""The weighted blocks' value, gradient and Hessian from their rows: what the Newton phases minimize.

``G = Σ_b w_b ρ_b(r_b)``; ``∇G = Σ_b w_b J_bᵀ ∇ρ_b``; ``∇²G = Σ_b w_b (J_bᵀ ∇²ρ_b J_b + Σ_c (∇ρ_b)_c ∇²r_bc)``,
the last term the blocks' second-order kinematics, from their kinds' curvature kernels
(:class:`~framework.costs.kinds.BlockKind`).
"""

from __future__ import annotations

import numpy as np

from ..costs.blocks import UNIT_ROWS, in_level, rho_derivatives, rho_value
from ..costs.kernels import COMPUTE, YES, linearize
from ..costs.workspace import views, workspaces
from ..compiled.native import call, compiled, internal, keep_alive
from .tables import max_rows

#: States of a regularizer block in the Newton phase: free, held at zero, kicked off it (one step), released
#: (left free for the rest of the phase).
FREE, HELD, KICKED, RELEASED = 0, 1, 2, 3


@internal
def is_held(state) -> bool:
    """Whether a regularizer in this state is a constraint of the step (held at zero, or kicked off it)."""
    return state == HELD or state == KICKED


@internal
def add_curvature(ws, b, row, mu, H) -> None:
    """``Σ_c mu_c ∇²r_c`` of block ``b`` (its rows from ``row`` on in ``ws``'s residuals) added to ``H (n, n)`` by its
    kind's curvature kernel (none: nothing; Gauss-Newton curvature)."""
    address = views(ws).blocks[b].curvature
    if address == 0:
        return
    ws.block, ws.row = b, row
    ws.multipliers, ws.hessian = mu.ctypes.data, H.ctypes.data
    call(address, ws)
    ws.multipliers = ws.hessian = 0


@internal
def objective_derivatives(ws, level, smoothing, curvature, majorize_below, states, g, H, gr, Hr, mu) -> float:
    """Weighted value, gradient ``g (n,)`` and Hessian ``H (n, n)`` of the blocks of ``level`` (``< 0``: all
    levels 1 and 2) from the residual rows in ``ws``; ``curvature`` adds their second-order kinematics.
    ``gr, mu (rows,)`` and ``Hr (rows, rows)`` are scratch at least as large as the largest block; norms shorter
    than ``majorize_below`` get their majorizing curvature (see ``rho_derivatives``); blocks ``b`` whose
    ``states[b]`` is ``HELD`` or ``KICKED`` are left out (norms held at zero as constraints; zeros: none)."""
    v = views(ws)
    n = g.shape[0]
    g[:] = 0.0
    H[:] = 0.0
    row, value = 0, 0.0
    for b in range(v.blocks.shape[0]):
        block = v.blocks[b]
        if not in_level(block.level, level):
            continue
        rows, w = block.rows, block.weight
        if is_held(states[b]):
            row += rows
            continue
        rho_derivatives(block.rho, block.scale, v.r, row, rows, smoothing, gr, Hr, majorize_below)
        value += w * rho_value(block.rho, block.scale, v.r, row, rows)
        if block.flags & UNIT_ROWS:  # unit rows (motion): Jᵀ scatters onto the block's coordinates
            _scatter(v.indices, block.indices, rows, w, gr, Hr, g, H)
            row += rows  # (no curvature: linear in x)
            continue
        _add_gauss_newton(v.J, row, rows, w, gr, Hr, g, H, n)
        if curvature:
            for a in range(rows):
                mu[a] = w * gr[a]
            add_curvature(ws, b, row, mu, H)
        row += rows
    return value


@internal
def _scatter(indices, q, rows, w, gr, Hr, g, H) -> None:
    """``g += w Jᵀ gr``, ``H += w Jᵀ Hr J`` for unit rows on the coordinates ``indices[q:q + rows]``."""
    for a in range(rows):
        g[indices[q + a]] += w * gr[a]
    for a in range(rows):
        for c in range(rows):
            h = w * Hr[a, c]
            if h != 0.0:
                H[indices[q + a], indices[q + c]] += h


@internal
def _add_gauss_newton(J, row, rows, w, gr, Hr, g, H, n) -> None:
    """``g += w Jᵀ gr``, ``H += w Jᵀ Hr J`` for the rows ``row:row + rows`` of ``J``."""
    for i in range(n):
        acc = 0.0
        for a in range(rows):
            acc += J[row + a, i] * gr[a]
        g[i] += w * acc
    for a in range(rows):  # H += w Jᵀ Hr J
        for c in range(rows):
            h = w * Hr[a, c]
            if h == 0.0:
                continue
            for i in range(n):
                ja = J[row + a, i]
                if ja == 0.0:
                    continue
                for j in range(n):
                    H[i, j] += h * ja * J[row + c, j]


@compiled
def derivatives_at(x, level, packed, smoothing, curvature):
    """``(value, gradient (n,), Hessian (n, n))`` of the weighted blocks of ``level`` at ``x`` (for callers
    outside the loops: tests, reports)."""
    n = x.shape[0]
    owners, records = workspaces(packed, n, 1)
    ws = records[0]
    linearize(x, ws, level, YES, COMPUTE)
    big = max_rows(packed.blocks)
    g, H = np.empty(n), np.empty((n, n))
    value = objective_derivatives(ws, level, smoothing, curvature, 0.0, np.zeros(packed.blocks.shape[0], np.int8),
                                  g, H, np.empty(big), np.empty((big, big)), np.empty(big))
    keep_alive(owners, packed)
    return value, g, H
