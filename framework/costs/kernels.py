"""Compiled evaluation of a packed problem through its blocks' kernels: residuals and Jacobians at one
configuration (:func:`linearize`), values of a population, each term's value, the task errors.

Every function reads the problem and writes its results through a workspace (:mod:`~.workspace`); each block is
evaluated by its kind's kernel, called by address (:mod:`~.kinds`).
"""

from __future__ import annotations

import numpy as np

from ..model.kinematics import fk_one, frame_jacobians_where
from ..compiled.native import borrow, call, compiled, internal, keep_alive
from .blocks import FRAME_INDICES, HINGE, LEVEL_TASK, TOL_ANGULAR, TOL_LINEAR, in_level, rho_value
from .workspace import JACOBIAN_ONLY, LINEARIZE, RESIDUAL, kinematic_views, views, workspaces

# Arguments of compiled calls, as numpy scalars: numba compiles a callee once per *literal* Python int / bool it
# is called with, but once for all values of an int64 / bool.
#: ``level`` arguments: the task, the regularizers, both.
TASK, REGULARIZERS, TASK_AND_REGULARIZERS = np.int64(LEVEL_TASK), np.int64(2), np.int64(-1)
#: :func:`linearize`'s ``kinematics``: reuse the poses and Jacobians, compute them, Jacobians from kept poses.
REUSE, COMPUTE, JACOBIANS_FROM_POSES = np.int64(0), np.int64(1), np.int64(2)
YES, NO = np.bool_(True), np.bool_(False)


@internal
def linearize(x, ws, level, want_jacobian, kinematics) -> int:
    """Residuals (and Jacobians) of the blocks of ``level`` at ``x``, stacked into ``ws``'s rows; returns the rows.

    ``level < 0`` selects every block of level 1 and 2 (the task and the regularizers). ``kinematics``:
    :data:`REUSE` the poses and frame Jacobians in ``ws`` (computed at the same ``x``); :data:`COMPUTE` the poses
    (and, with ``want_jacobian``, the frame Jacobians); :data:`JACOBIANS_FROM_POSES` keeps the poses and computes
    the frame Jacobians from them (after a call with ``COMPUTE`` and no Jacobian at the same ``x`` and level: a step
    that was accepted; the one-sided blocks that call found clear keep their zero residual and get a zero Jacobian
    without a second evaluation — collision terms are mostly such rows).
    """
    ws.x = x.ctypes.data
    v, k = views(ws), kinematic_views(ws)
    if kinematics == COMPUTE:
        fk_one(x, k.joints, k.joint_geometry, k.frame_joints, k.frame_geometry, v.poses, k.placements)
    if want_jacobian and kinematics != REUSE:  # the frames some block of level 1 or 2 reads
        frames_needed(level, v.blocks, v.indices, v.r, kinematics == JACOBIANS_FROM_POSES, k.need)
        frame_jacobians_where(x, k.joints, k.joint_geometry, k.frame_joints, v.poses, k.placements, v.jacobians,
                              k.need)
    jacobian_only = want_jacobian and kinematics == JACOBIANS_FROM_POSES
    ws.mode = JACOBIAN_ONLY if jacobian_only else (LINEARIZE if want_jacobian else RESIDUAL)
    row = 0
    for b in range(v.blocks.shape[0]):
        block = v.blocks[b]
        if not in_level(block.level, level):
            continue
        rows = block.rows
        if kinematics == JACOBIANS_FROM_POSES and block.flags & HINGE and rows_clear(v.r, row, rows):
            v.J[row : row + rows, :] = 0.0  # clear at x in the previous call: nothing to recompute
        else:
            ws.block, ws.row = b, row
            call(block.residual, ws)
        row += rows
    return row


@internal
def frames_needed(level, blocks, indices, r, clear_hinges, need) -> None:
    """``need (k,)``: 1 for each frame a block of ``level`` or of level 1 or 2 reads (those of ``level`` the call
    evaluates, the others for a later call reusing the kinematics), else 0; with ``clear_hinges``, the one-sided
    blocks of ``level`` whose rows ``r`` are all zero (clear at these poses, their Jacobian zero) read none. A frame
    that only blocks set aside read (level 0 when another level is asked for: value-only terms, the engine's lazy
    contact rows) needs no Jacobian."""
    need[:] = 0.0
    row = 0
    for b in range(blocks.shape[0]):
        block = blocks[b]
        if block.level == 0 and level != 0:
            continue
        if level < 0 or block.level == level:
            rows = block.rows
            clear = clear_hinges and block.flags & HINGE and rows_clear(r, row, rows)
            row += rows
            if clear:
                continue
        if block.flags & FRAME_INDICES:
            for c in range(block.count):
                need[indices[block.indices + c]] = 1.0
            continue
        if block.fa >= 0:
            need[block.fa] = 1.0
        if block.fb >= 0:
            need[block.fb] = 1.0


@internal(inline=True)
def rows_clear(r, row, rows) -> bool:
    """Whether the residual rows ``r[row:row + rows]`` are all zero."""
    for c in range(row, row + rows):
        if r[c] != 0.0:
            return False
    return True


@internal
def hinges_clear(x, ws) -> bool:
    """Whether no one-sided task block (a distance band, a cone, a collision row) is violated at ``x``: the poses
    into ``ws``, then the one-sided blocks in order until the first violated one (most random configurations of a
    dual arm are in contact: the first contact decides). Other blocks' rows in ``ws`` are left as they were."""
    ws.x = x.ctypes.data
    v, k = views(ws), kinematic_views(ws)
    fk_one(x, k.joints, k.joint_geometry, k.frame_joints, k.frame_geometry, v.poses, k.placements)
    ws.mode = RESIDUAL
    row = 0
    for b in range(v.blocks.shape[0]):
        block = v.blocks[b]
        if block.level != LEVEL_TASK:
            continue
        if block.flags & HINGE:
            ws.block, ws.row = b, row
            call(block.residual, ws)
            if not rows_clear(v.r, row, block.rows):
                return False
        row += block.rows
    return True


@internal
def level_value(ws, level, weighted) -> float:
    """Σ ρ_b (times the term weights if ``weighted``) over the blocks of ``level`` from the stacked rows in ``ws``."""
    v = views(ws)
    row, total = 0, 0.0
    for b in range(v.blocks.shape[0]):
        block = v.blocks[b]
        if not in_level(block.level, level):
            continue
        value = rho_value(block.rho, block.scale, v.r, row, block.rows)
        total += block.weight * value if weighted else value
        row += block.rows
    return total


@internal
def term_values(x, ws, values) -> None:
    """Each term's value into ``values (terms,)`` from the poses in ``ws`` (computed at ``x``); overwrites the
    residual rows of ``ws``."""
    ws.x = x.ctypes.data
    v = views(ws)
    values[:] = 0.0
    ws.mode, ws.row = RESIDUAL, 0
    for b in range(v.blocks.shape[0]):
        block = v.blocks[b]
        ws.block = b
        call(block.residual, ws)
        values[block.term] += rho_value(block.rho, block.scale, v.r, 0, block.rows)


@internal(inline=True)
def within_tolerance(ws, errors, tol_linear, tol_angular) -> bool:
    """Whether every task block's error (from :func:`task_errors`) is within its tolerance (m or rad)."""
    blocks = views(ws).blocks
    k = 0
    for b in range(blocks.shape[0]):
        block = blocks[b]
        if block.level != LEVEL_TASK:
            continue
        if block.tolerance == TOL_LINEAR and not errors[k] <= tol_linear:
            return False
        if block.tolerance == TOL_ANGULAR and not errors[k] <= tol_angular:
            return False
        k += 1
    return True


@internal(inline=True)
def task_errors(ws, errors) -> None:
    """Each task block's error ``‖r_b‖`` (m or rad) into ``errors``, from the stacked task rows in ``ws``."""
    v = views(ws)
    row, k = 0, 0
    for b in range(v.blocks.shape[0]):
        block = v.blocks[b]
        if block.level != LEVEL_TASK:
            continue
        s = 0.0
        for c in range(block.rows):
            s += v.r[row + c] * v.r[row + c]
        errors[k] = np.sqrt(s)
        k += 1
        row += block.rows


@internal
def widen_margins(blocks, params, band, out) -> None:
    """``out``: ``params`` with every contact block's margin widened by ``band`` [m]. Evaluated with them, a contact
    row clear of its margin by ``gap < band`` reads ``gap − band`` with the Jacobian of ``gap`` (its closest pair's),
    where with the margin alone it reads 0 with none: how near a clear contact is, and which way it comes."""
    for i in range(params.shape[0]):
        out[i] = params[i]
    for b in range(blocks.shape[0]):
        if blocks[b].margin >= 0:
            out[blocks[b].params + blocks[b].margin] += band


@compiled
def population_values(X, packed, V) -> int:
    """Unweighted term values ``V (pop, terms)`` (accumulated: zero it first) of every compiled block.

    Returns the first row of ``X`` holding NaN or inf (left unevaluated), or -1.
    """
    return _population(X, packed, V, np.empty(0), NO)


@compiled
def population_cost(X, packed, F) -> int:
    """The weighted sum of every compiled block's value for each row of ``X`` into ``F (pop,)``.

    Returns the first row of ``X`` holding NaN or inf (left unevaluated), or -1.
    """
    return _population(X, packed, np.empty((0, 0)), F, YES)


@internal
def _population(X, packed, V, F, weighted) -> int:
    """One FK and every block per member of ``X``: term values into ``V`` or weighted sums into ``F``."""
    owners, records = workspaces(packed, X.shape[1], 1)
    ws = records[0]
    X = borrow(X)
    bad = -1
    for m in range(X.shape[0]):
        x = X[m]
        for i in range(x.shape[0]):
            if not np.isfinite(x[i]):
                bad = m
        if bad >= 0:
            break
        _member(x, ws, V, F, m, weighted, F[:0])
    keep_alive(owners, packed)
    return bad


@internal
def _member(x, ws, V, F, m, weighted, errors) -> None:
    """Member ``m`` (at ``x``) of :func:`_population`; with ``errors`` (not empty), each task block's error
    ``‖r_b‖`` too, from the same residuals."""
    ws.x = x.ctypes.data
    v, k = views(ws), kinematic_views(ws)
    fk_one(x, k.joints, k.joint_geometry, k.frame_joints, k.frame_geometry, v.poses, k.placements)
    ws.mode, ws.row = RESIDUAL, 0
    f = 0.0
    t = 0
    for b in range(v.blocks.shape[0]):
        block = v.blocks[b]
        ws.block = b
        call(block.residual, ws)
        value = rho_value(block.rho, block.scale, v.r, 0, block.rows)
        if weighted:
            f += block.weight * value
        else:
            V[m, block.term] += value
        if errors.shape[0] > 0 and block.level == LEVEL_TASK:
            s = 0.0
            for c in range(block.rows):
                s += v.r[c] * v.r[c]
            errors[t] = np.sqrt(s)
            t += 1
    if weighted:
        F[m] = f


@compiled
def residuals_at(x, level, packed, r_out, J_out) -> int:
    """Residuals ``r_out`` and Jacobians ``J_out`` (preallocated with every block's rows) of the blocks of
    ``level`` at ``x`` (``-1``: levels 1 and 2); returns the number of rows written."""
    owners, records = workspaces(packed, x.shape[0], 1)
    ws = records[0]
    m = linearize(borrow(x), ws, level, YES, COMPUTE)
    v = views(ws)
    for a in range(m):
        r_out[a] = v.r[a]
        for i in range(x.shape[0]):
            J_out[a, i] = v.J[a, i]
    keep_alive(owners, packed)
    return m


@compiled
def values_and_errors(x, packed, V, errors) -> None:
    """Unweighted term values ``V (terms,)`` (accumulated: zero it first) and each task block's error ``‖r_b‖``
    ``errors (blocks,)`` at one configuration ``x (n,)`` (finite): :func:`population_values` and
    :func:`task_errors_at` in one pass (one FK, each block's residual once; a solve's answer found on another
    problem, e.g. without its collision terms)."""
    owners, records = workspaces(packed, x.shape[0], 1)
    _member(borrow(x), records[0], V.reshape((1, V.shape[0])), V[:0], 0, NO, errors)
    keep_alive(owners, packed)


@compiled
def task_errors_at(X, packed, errors) -> None:
    """Each task block's error ``‖r_b‖`` [m or rad] at each configuration of ``X`` ``(pop, n)`` into ``errors``
    ``(pop, blocks)``."""
    owners, records = workspaces(packed, X.shape[1], 1)
    ws = records[0]
    X = borrow(X)
    for m in range(X.shape[0]):
        linearize(X[m], ws, TASK, NO, COMPUTE)
        task_errors(ws, errors[m])
    keep_alive(owners, packed)
