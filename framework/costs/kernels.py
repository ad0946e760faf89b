"""Compiled evaluation of a packed problem: values of a population, residuals and Jacobians at one configuration.

The arguments are the packed arrays of :class:`~framework.costs.program.Program`, grouped as tuples:
``kin = (jint, jgeo, fslot, fgeo)`` (the kinematic tables), ``prog = (bint, bflt, params, idx, wrap, chain_ptr,
chain_idx)`` (the blocks) and a workspace ``ws = (out, W, Jf, r, Jr, L3, E9)`` carved by :func:`workspace`.
"""

from __future__ import annotations

import numba
import numpy as np

from ..kinematics import fk_one, frame_jacobians_where
from ..native import borrow, borrow_kin, borrow_prog, borrow_ws, carve, keep_alive
from .blocks import (
    COM,
    COUNT,
    FA,
    FB,
    IPTR,
    KIND,
    LEVEL,
    LEVEL_REGULARIZER,
    LEVEL_TASK,
    PPTR,
    RHO,
    ROWS,
    SCALE,
    TERM,
    TOL,
    TOL_ANGULAR,
    TOL_LINEAR,
    WEIGHT,
    is_contact,
    is_hinge,
    rho_value,
)
from .collision_blocks import contact_row, scratch_size
from .dispatch import block_jacobian, block_residual

# Arguments of compiled calls, as numpy scalars: numba compiles a callee once per *literal* Python int / bool it
# is called with (a whole compile, seconds for the engine's kernels), but once for all values of an int64 / bool.
#: ``level`` arguments: the task, the regularizers, both.
TASK, REGULARIZERS, TASK_AND_REGULARIZERS = np.int64(LEVEL_TASK), np.int64(LEVEL_REGULARIZER), np.int64(-1)
#: :func:`linearize`'s ``kinematics``: reuse the poses and Jacobians, compute them, Jacobians from kept poses.
REUSE, COMPUTE, JACOBIANS_FROM_POSES = np.int64(0), np.int64(1), np.int64(2)
YES, NO = np.bool_(True), np.bool_(False)
ROW0 = np.int64(0)


@numba.njit(cache=True, inline="always")
def _workspace_sizes(kin, prog, n):
    """The seven sizes of :func:`workspace`'s views, in order, and their sum."""
    jint, fslot = kin[0], kin[2]
    bint = prog[0]
    rows = 0
    for b in range(bint.shape[0]):
        rows += bint[b, ROWS]
    rows = max(rows, 1)
    k, J = fslot.shape[0], jint.shape[0]
    sizes = (12 * k, 12 * J, 6 * k * n, rows, rows * n, 9, max(scratch_size(bint, prog[2]), k))
    total = 0
    for size in sizes:
        total += size
    return sizes, total, k, J, rows


@numba.njit(cache=True, inline="always")
def _carve_workspace(buffer, a, sizes, k, J, rows, n):
    """A workspace's seven views of ``buffer`` from entry ``a`` on (see :func:`workspace`)."""
    out = carve(buffer, a, (k, 12))
    a += sizes[0]
    W = carve(buffer, a, (J, 12))
    a += sizes[1]
    Jf = carve(buffer, a, (k, 6, n))
    a += sizes[2]
    r = carve(buffer, a, sizes[3])
    a += sizes[3]
    Jr = carve(buffer, a, (rows, n))
    a += sizes[4]
    L3 = carve(buffer, a, (3, 3))
    E9 = carve(buffer, a + 9, sizes[6])
    return out, W, Jf, r, Jr, L3, E9


@numba.njit(cache=True)
def workspace(kin, prog, n):
    """Scratch for one configuration — poses ``(k, 12)``, joint placements ``(J, 12)``, frame Jacobians
    ``(k, 6, n)``, residual rows ``(rows,)`` and their Jacobian ``(rows, n)``, a 3 x 3 matrix and the blocks'
    scratch (:func:`~framework.costs.collision_blocks.scratch_size`, at least ``k``: it holds the frames whose
    Jacobians a call needs, before the blocks use it) — as ``(buffer, ws)``: one allocation and the workspace
    ``ws`` carved from it (views without an owner: the caller keeps ``buffer`` alive while it uses them, see
    :func:`~framework.native.keep_alive`; a ``reshape`` per view cost a fifth of a microsecond more)."""
    sizes, total, k, J, rows = _workspace_sizes(kin, prog, n)
    buffer = np.empty(total)
    return buffer, _carve_workspace(buffer, 0, sizes, k, J, rows, n)


@numba.njit(cache=True)
def workspace_pair(kin, prog, n):
    """Two workspaces (:func:`workspace`: a point's and a trial point's) from one allocation:
    ``(buffer, ws, trial)``."""
    sizes, total, k, J, rows = _workspace_sizes(kin, prog, n)
    buffer = np.empty(2 * total)
    return buffer, _carve_workspace(buffer, 0, sizes, k, J, rows, n), _carve_workspace(buffer, total, sizes, k, J,
                                                                                        rows, n)


@numba.njit(cache=True)
def linearize(x, level, kin, prog, ws, want_jacobian, kinematics) -> int:
    """:func:`linearize_inline` as a call of its own: the form every caller takes but the reach loop's trial point,
    which inlines it (a call passes the workspace's and the program's dozen arrays field by field, ~70 ns; each
    inlined copy compiles every block kind's kernel again: see :mod:`~framework.engine.reach` for the cost)."""
    return linearize_inline(x, level, kin, prog, ws, want_jacobian, kinematics)


@numba.njit(cache=True, inline="always")
def linearize_inline(x, level, kin, prog, ws, want_jacobian, kinematics) -> int:
    """Residuals (and Jacobians) of the blocks of ``level`` at ``x``, stacked into ``ws`` rows; returns the rows.

    ``level < 0`` selects every block of level 1 and 2 (the task and the regularizers). ``kinematics``:
    0 reuses the poses and frame Jacobians in ``ws`` (computed at the same ``x``); 1 computes the poses (and,
    with ``want_jacobian``, the frame Jacobians); 2 keeps the poses and computes the frame Jacobians from them
    (after a call with ``kinematics=1, want_jacobian=False`` at the same ``x`` and level: a step that was accepted; the
    hinge blocks that call found clear keep their zero residual and get a zero Jacobian without a second
    evaluation — collision terms are mostly such rows).
    """
    jint, jgeo, fslot, fgeo = borrow_kin(kin)
    prog = borrow_prog(prog)
    bint, params, idx, wrap = prog[0], prog[2], prog[3], prog[4]
    out, W, Jf, r, Jr, L3, E9 = borrow_ws(ws)
    x = borrow(x)
    if kinematics == 1:
        fk_one(x, jint, jgeo, fslot, fgeo, out, W)
    if want_jacobian and kinematics >= 1:  # the frames some block of level 1 or 2 reads (E9: scratch till the blocks)
        frames_needed(level, bint, idx, r, kinematics == 2, E9, fslot.shape[0])
        frame_jacobians_where(x, jint, jgeo, fslot, out, W, Jf, E9)
    row = ROW0
    for b in range(bint.shape[0]):
        lv = bint[b, LEVEL]
        if (level >= 0 and lv != level) or (level < 0 and lv == 0):
            continue
        if kinematics == 2 and is_hinge(bint[b, KIND]) and rows_clear(r, row, bint[b, ROWS]):
            Jr[row : row + bint[b, ROWS], :] = 0.0  # clear at x in the previous call: nothing to recompute
            row += bint[b, ROWS]
            continue
        kind = bint[b, KIND]
        if kinematics == 2 and want_jacobian:  # the residual rows are the previous call's: the Jacobian alone
            rows = block_jacobian(b, out, Jf, bint, params, r, Jr, row, L3)
            if rows >= 0:
                row += rows
                continue
        if is_contact(kind):
            contact_row(kind, out, Jf, bint[b, FA], bint[b, FB], params, bint[b, PPTR], r, Jr, row, want_jacobian,
                        x.shape[0], E9)
            row += bint[b, ROWS]
        else:
            row += block_residual(b, x, out, Jf, bint, params, idx, wrap, r, Jr, row, want_jacobian, L3, E9)
    return row


@numba.njit(cache=True, inline="always")
def frames_needed(level, bint, idx, r, clear_hinges, need, k) -> None:
    """``need[:k]``: 1 for each frame a block of ``level`` or of level 1 or 2 reads (those of ``level`` the call
    evaluates, the others for a later call reusing the kinematics), else 0; with ``clear_hinges``, the one-sided
    blocks of ``level`` whose rows ``r`` are all zero (clear at these poses, their Jacobian zero) read none. A frame
    that only blocks set aside read (level 0 when another level is asked for: value-only terms, the engine's lazy
    contact rows) needs no Jacobian."""
    for f in range(k):
        need[f] = 0.0
    row = ROW0
    for b in range(bint.shape[0]):
        lv = bint[b, LEVEL]
        if lv == 0 and level != 0:
            continue
        if level < 0 or lv == level:
            rows = bint[b, ROWS]
            clear = clear_hinges and is_hinge(bint[b, KIND]) and rows_clear(r, row, rows)
            row += rows
            if clear:
                continue
        if bint[b, KIND] == COM:
            for c in range(bint[b, COUNT]):
                need[idx[bint[b, IPTR] + c]] = 1.0
            continue
        if bint[b, FA] >= 0:
            need[bint[b, FA]] = 1.0
        if bint[b, FB] >= 0:
            need[bint[b, FB]] = 1.0


@numba.njit(cache=True)
def hinges_clear(x, kin, prog, ws) -> bool:
    """Whether no one-sided task block (a distance band, a cone, a collision row) is violated at ``x``: the poses
    into ``ws``, then the one-sided blocks in order until the first violated one (most random configurations of a
    dual arm are in contact: the first contact decides). Other blocks' rows in ``ws`` are left as they were."""
    jint, jgeo, fslot, fgeo = borrow_kin(kin)
    prog = borrow_prog(prog)
    bint, params, idx, wrap = prog[0], prog[2], prog[3], prog[4]
    out, W, Jf, r, Jr, L3, E9 = borrow_ws(ws)
    x = borrow(x)
    fk_one(x, jint, jgeo, fslot, fgeo, out, W)
    row = ROW0
    for b in range(bint.shape[0]):
        if bint[b, LEVEL] != LEVEL_TASK:
            continue
        rows = bint[b, ROWS]
        if is_hinge(bint[b, KIND]):
            block_residual(b, x, out, Jf, bint, params, idx, wrap, r, Jr, row, False, L3, E9)
            if not rows_clear(r, row, rows):
                return False
        row += rows
    return True


@numba.njit(cache=True, inline="always")
def rows_clear(r, row, rows) -> bool:
    """Whether the residual rows ``r[row:row + rows]`` are all zero."""
    for c in range(row, row + rows):
        if r[c] != 0.0:
            return False
    return True


@numba.njit(cache=True)
def level_value(level, prog, r, weighted) -> float:
    """Σ ρ_b (times the term weights if ``weighted``) over the blocks of ``level`` from stacked residuals ``r``."""
    bint, bflt = prog[0], prog[1]
    row, total = ROW0, 0.0
    for b in range(bint.shape[0]):
        lv = bint[b, LEVEL]
        if (level >= 0 and lv != level) or (level < 0 and lv == 0):
            continue
        rows = bint[b, ROWS]
        v = rho_value(bint[b, RHO], bflt[b, SCALE], r, row, rows)
        total += bflt[b, WEIGHT] * v if weighted else v
        row += rows
    return total


@numba.njit(cache=True)
def term_values(x, prog, ws, values):
    """Each term's value into ``values (terms,)`` from the poses in ``ws`` (computed at ``x``); overwrites the
    residual rows of ``ws``."""
    bint, bflt, params, idx, wrap = prog[0], prog[1], prog[2], prog[3], prog[4]
    out, W, Jf, r, Jr, L3, E9 = ws
    values[:] = 0.0
    for b in range(bint.shape[0]):
        rows = block_residual(b, x, out, Jf, bint, params, idx, wrap, r, Jr, ROW0, NO, L3, E9)
        values[bint[b, TERM]] += rho_value(bint[b, RHO], bflt[b, SCALE], r, ROW0, rows)


@numba.njit(cache=True, inline="always")
def within_tolerance(prog, errors, tol_linear, tol_angular) -> bool:
    """Whether every task block's error (from :func:`task_errors`) is within its tolerance (m or rad)."""
    bint = prog[0]
    k = 0
    for b in range(bint.shape[0]):
        if bint[b, LEVEL] != 1:
            continue
        tol = bint[b, TOL]
        if tol == TOL_LINEAR and not errors[k] <= tol_linear:
            return False
        if tol == TOL_ANGULAR and not errors[k] <= tol_angular:
            return False
        k += 1
    return True


@numba.njit(cache=True, inline="always")
def task_errors(prog, r, errors):
    """Each task block's error ``‖r_b‖`` (m or rad) into ``errors``, from stacked task rows."""
    bint = prog[0]
    row, k = 0, 0
    for b in range(bint.shape[0]):
        if bint[b, LEVEL] != 1:
            continue
        rows = bint[b, ROWS]
        s = 0.0
        for c in range(rows):
            s += r[row + c] * r[row + c]
        errors[k] = np.sqrt(s)
        k += 1
        row += rows


@numba.njit(cache=True)
def population_values(X, kin, prog, V) -> int:
    """Unweighted term values ``V (pop, terms)`` (accumulated: zero it first) of every compiled block.

    Returns the first row of ``X`` holding NaN or inf (left unevaluated), or -1.
    """
    return _population(X, kin, prog, V, V[:, 0], False)


@numba.njit(cache=True)
def population_cost(X, kin, prog, F) -> int:
    """The weighted sum of every compiled block's value for each row of ``X`` into ``F (pop,)``.

    Returns the first row of ``X`` holding NaN or inf (left unevaluated), or -1.
    """
    return _population(X, kin, prog, np.empty((0, 0)), F, True)


@numba.njit(cache=True, inline="always")
def _population(X, kin, prog, V, F, weighted) -> int:
    """One FK and every block per member of ``X``: term values into ``V`` or weighted sums into ``F``."""
    kin, prog = borrow_kin(kin), borrow_prog(prog)
    X = borrow(X)
    jint, jgeo, fslot, fgeo = kin
    bint, bflt, params, idx, wrap = prog[0], prog[1], prog[2], prog[3], prog[4]
    n = X.shape[1]
    own, (out, W, Jf, r, Jr, L3, E9) = workspace(kin, prog, n)
    bad = -1
    for m in range(X.shape[0]):
        x = X[m]
        for i in range(n):
            if not np.isfinite(x[i]):
                bad = m
        if bad >= 0:
            break
        fk_one(x, jint, jgeo, fslot, fgeo, out, W)
        f = 0.0
        for b in range(bint.shape[0]):
            rows = block_residual(b, x, out, Jf, bint, params, idx, wrap, r, Jr, ROW0, NO, L3, E9)
            value = rho_value(bint[b, RHO], bflt[b, SCALE], r, ROW0, rows)
            if weighted:
                f += bflt[b, WEIGHT] * value
            else:
                V[m, bint[b, TERM]] += value
        if weighted:
            F[m] = f
    keep_alive(own)
    return bad


@numba.njit(cache=True)
def residuals_at(x, level, kin, prog, r_out, J_out) -> int:
    """Residuals ``r_out`` and Jacobians ``J_out`` (preallocated with every block's rows) of the blocks of
    ``level`` at ``x`` (``-1``: levels 1 and 2); returns the number of rows written."""
    kin, prog = borrow_kin(kin), borrow_prog(prog)
    own, ws = workspace(kin, prog, x.shape[0])
    m = linearize(borrow(x), level, kin, prog, ws, YES, COMPUTE)
    r_out[:m] = ws[3][:m]
    J_out[:m] = ws[4][:m]
    keep_alive(own)
    return m


@numba.njit(cache=True)
def task_errors_at(X, kin, prog, errors):
    """Each task block's error ``‖r_b‖`` [m or rad] at each configuration of ``X`` ``(pop, n)`` into ``errors``
    ``(pop, blocks)``."""
    kin, prog = borrow_kin(kin), borrow_prog(prog)
    own, ws = workspace(kin, prog, X.shape[1])
    X = borrow(X)
    for m in range(X.shape[0]):
        linearize(X[m], TASK, kin, prog, ws, NO, COMPUTE)
        task_errors(prog, ws[3], errors[m])
    keep_alive(own)
