"""Restoring steps: Gauss-Newton least-norm steps back onto the task after a Newton step left it."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..costs.kernels import COMPUTE, JACOBIANS_FROM_POSES, NO, REUSE, TASK, YES, linearize
from ..costs.workspace import views
from ..compiled.native import internal, matrix
from .steps import bounded_step, copy, project, squared_norm
from .tables import set_aside_clear

#: Damping of the restoring steps: enough for a Cholesky factor of a rank-deficient ``JᵀJ`` (clear hinge rows have
#: no Jacobian), far below the curvature of any row that moves.
RESTORE_DAMPING = 1e-14


class RestoreScratch(NamedTuple):
    """The restoring steps' scratch: the step's matrices (flat, at least ``k²``), vectors (at least ``max(m, n)``
    and ``n``), the bounded step's Jacobian ``(m, n)`` (flat), and the configuration before a step."""

    A: np.ndarray
    L: np.ndarray
    y: np.ndarray
    dx: np.ndarray
    Jc: np.ndarray
    before: np.ndarray


@internal
def restoring_steps(x, box, ws, m, rs, steps, target):
    """Up to ``steps`` Gauss-Newton least-norm steps on the ``m`` task rows stacked in ``ws`` (with their Jacobians
    at ``x``) until ``‖r‖ <= target``; a step that raises ``‖r‖`` by more than rounding (1e-14) is undone, and one
    that does not lower it ends the steps. Returns ``(‖r‖, whether ‖r‖ stopped falling)``."""
    n = x.shape[0]
    v = views(ws)
    e = np.sqrt(squared_norm(v.r, m))
    taken = 0
    while taken < steps and e > target:
        if not bounded_step(x, v.J[:m], v.r[:m], RESTORE_DAMPING, box, matrix(rs.Jc, m, n), rs.A, rs.L, rs.y,
                            rs.dx):
            return e, True
        taken += 1
        copy(rs.before, x)
        for i in range(n):
            x[i] += rs.dx[i]
        project(x, box)
        linearize(x, ws, TASK, YES, COMPUTE)
        e_new = np.sqrt(squared_norm(v.r, m))
        if not e_new < e:
            if e_new > e + 1e-14:  # worse, beyond rounding: undone
                copy(x, rs.before)
                linearize(x, ws, TASK, YES, COMPUTE)
            else:
                e = e_new
            return e, True
        e = e_new
    return e, False


@internal
def restore(x, box, ws, near, m, rs, steps, target):
    """Gauss-Newton least-norm steps on the task residuals until ``‖r‖ <= target`` (coordinates held at a bound
    the step would push through are left out of it); a step that raises ``‖r‖`` by more than rounding is undone.
    ``ws`` holds the task's rows and Jacobians at ``x``.

    The steps leave out the one-sided blocks clear at ``x`` (``near``: a copy of the block table, where they are
    set aside): a clear row has no Jacobian, so it takes no part in a step, and steps this short seldom enter it —
    but its evaluation is the cost of a step (a collision term's rows, almost all clear). The whole task is
    evaluated after them, and steps on every row go on from there if one was entered.
    Returns ``(‖r‖, whether ws holds the Jacobians at x)``: on return ``ws`` holds the whole task's residuals at
    ``x``, without their Jacobians (and frame Jacobians) when the last evaluation was the check of the set-aside
    rows (:data:`~framework.costs.kernels.JACOBIANS_FROM_POSES` adds them)."""
    v = views(ws)
    if steps == 0 or np.sqrt(squared_norm(v.r, m)) <= target:
        return np.sqrt(squared_norm(v.r, m)), True
    mn = set_aside_clear(v.blocks, v.r, v.J, near)
    if mn < m:
        table = ws.blocks
        ws.blocks = near.ctypes.data
        _, stalled = restoring_steps(x, box, ws, mn, rs, steps, target)
        ws.blocks = table
        linearize(x, ws, TASK, NO, REUSE)  # every row again, the set-aside ones included (the steps left the poses
        # at x in ws)
        e = np.sqrt(squared_norm(v.r, m))
        if e <= target or stalled:
            return e, False
        # a step entered a set-aside row: on with every row
        linearize(x, ws, TASK, YES, JACOBIANS_FROM_POSES)
    e, _ = restoring_steps(x, box, ws, m, rs, steps, target)
    return e, True
