"""Second-order phases of the local engine, compiled: regularizers minimized on the task, and weighted sums.

:func:`regularize` — *priorities*: from a configuration that reaches the task (level 1), minimize the weighted
regularizers (level 2, e.g. motion) without leaving it: Newton steps on the KKT system
``[H Aᵀ; A 0] [dx; −λ] = [−∇G; −r]`` over the coordinates not held at a bound, with ``H`` the Hessian of the
Lagrangian ``G − λᵀr`` (the regularizers' own curvature plus the task's second-order kinematics, see
:func:`~framework.costs.curvature.block_curvature`), followed by Gauss-Newton steps back onto the task. A step is
kept only if it lowers ``G`` on the task (and leaves it no further than it started); otherwise the Hessian is
damped (``H + μI``). Converges quadratically to a local minimum: where the Lagrangian's Hessian is not positive
definite on the task's null space, or the Newton step is longer than the trust radius, the step is the
trust-region step there instead (:func:`_tangent_step`: negative curvature, a saddle point's included, is followed
to the radius; a too-long step is damped, not cut, so it does not zig-zag along the norms' flat rays).
A coordinate that a step carries through its bound within its first tenth (:data:`PIN`) is moved onto the bound
and the rest of the step solved again (clipped, the step would leave the task's tangent).
One-sided rows (distance bands, cones, collision rows) are inequalities: a row with a Jacobian is held as an
equality until its multiplier lets it go; a row clear where a step starts has no Jacobian there, so when a trial
step enters one and is rejected, the step is solved again holding that row with its Jacobian at the trial
(a *blocking* row: without it, the step would enter the contact again at every halving), at its value at ``x``
by that linearization — or where ``x`` is, when a curved row extrapolates to its violated side at ``x``, which is
clear. When the blocking rows stop a step (no step along them, or every halving rejected), the contact rows
among them are linearized again at ``x`` once (:data:`BAND`: their gap and the closest pair's Jacobian there);
when that finds no step either and each of them presses (its multiplier), the phase has converged on the
contact — otherwise a phase crept along it, a cycle of entering, holding and letting go per tiny gain. Blocking
rows let go, the backtracking then cuts a trial that enters one of them at its boundary (by its linearization)
instead of halving it. A collision row is the smallest distance over sphere pairs, with a
Jacobian that jumps where the closest pair changes: after :data:`KINK_FAILURES` failed iterations in a row with a
one-sided row held, the phase stops. When the step's system is singular with no blocking row held, the task's
rows are dependent (two collision rows pressing along one direction): damping ``H`` cannot make it regular, so
from then on the task's rows are held in least squares, as held norms are (:data:`HELD_DAMPING`).
A norm regularizer at its kink (a joint group at rest: ``‖r‖`` below :data:`HOLD_BELOW`) is an active set of its
own: held at zero as equality rows (out of ``G``'s derivatives) while its multiplier stays within the norm's
slope ``w s`` (the subgradient condition of an optimum at zero), else moved off zero against the multiplier and
left free. The first step gives norms shorter than its trust radius their majorizing curvature (a Newton step on
a norm's own ray is unbounded, and a first step past zero failed its halvings).

:func:`weighted_newton` — the weighted sum ``Σ w ρ(r)`` of every term as it stands, for objectives where
reaching the task costs more than it gains (the papers' weighted objectives with small task weights): damped
Newton steps in the box with the same second-order kinematics.
"""

from __future__ import annotations

import numba
import numpy as np

from ..costs.blocks import (
    COORDINATES,
    HALFSIN,
    IPTR,
    KIND,
    LEVEL,
    NORM,
    RHO,
    ROWS,
    SCALE,
    WEIGHT,
    is_contact,
    is_hinge,
    rho_derivatives,
    rho_value,
    wrap_angle,
)
from ..costs.collision_blocks import widen_margins
from ..costs.curvature import block_curvature
from ..costs.kernels import (
    COMPUTE,
    JACOBIANS_FROM_POSES,
    NO,
    REGULARIZERS,
    REUSE,
    ROW0,
    TASK,
    TASK_AND_REGULARIZERS,
    YES,
    level_value,
    linearize,
    rows_clear,
    task_errors,
    term_values,
    workspace,
    workspace_pair,
)
from ..native import borrow, borrow_kin, borrow_prog, carve, keep_alive, matrix, square
from .clock import monotonic_ns
from .linalg import cholesky_solve, gram, lu_solve, null_space, symmetric_eigen, trust_region_step
from .reach import bounded_step, held, project, rows_of, squared_norm

#: Newton damping: start, floor, and where a phase gives up on further progress.
MU_START, MU_MIN, MU_MAX = 1e-8, 1e-14, 1e6
#: Largest coordinate change of a first Newton step on the task [rad or m], and of any step.
TRUST_START, TRUST_MAX = 0.1, 1.0
#: Newton iterations in a row that find no step lowering G, with a one-sided row held, before the phase stops:
#: a collision row is the smallest distance over sphere pairs, its Jacobian jumps where the closest pair
#: changes, and steps across such a kink fail whatever the damping.
KINK_FAILURES = 2
#: Gauss-Newton steps back onto the task after a Newton step; halvings of a step before it is damped.
RESTORE_STEPS, LINE_SEARCH = 4, 4
#: Damping of those steps: enough for a Cholesky factor of a rank-deficient ``JᵀJ`` (clear hinge rows have no
#: Jacobian), far below the curvature of any row that moves.
RESTORE_DAMPING = 1e-14

#: A coordinate that a Newton step carries through its bound within this fraction of the step is held where it
#: is (near its bound) for that step.
PIN = 0.1
#: Backtracking without the blocking rows, a trial that enters a one-sided row clear at ``x`` is cut to that row's
#: boundary by its linearization (instead of halved), within these fractions of the trial step.
BOUNDARY_MIN, BOUNDARY_MAX = 0.05, 0.95
#: Blocking contact rows that stop a step are linearized again at ``x`` when their gap there is below this [m]
#: (the gap and the closest pair's Jacobian: :func:`~framework.costs.collision_blocks.widen_margins`); the others
#: are let go.
BAND = 1e-3

CONVERGED, STALLED, DEADLINE, ITERATIONS, NOT_APPLICABLE = 0, 1, 2, 3, 4
#: A norm regularizer (``ρ = s‖r‖``) shorter than this [its residual's unit: rad or m] is held at zero as a
#: constraint of the Newton phase (its kink: smoothed, Newton steps stall there with the norm at ~1e-7).
HOLD_BELOW = 1e-5
#: ``−δ`` on the diagonal of the held norms' rows in the step's system: a least-squares hold where they are
#: redundant with the task rows (far below any curvature of the problem); their right-hand side carries
#: ``δλ`` of the last multipliers (the proximal method of multipliers), so the hold is exact once they settle.
HELD_DAMPING = 1e-9
#: How far a held norm is moved off zero, against its multiplier, when the multiplier says leaving zero pays.
KICK = 1e-5
#: States of a regularizer block in the Newton phase: free, held at zero, kicked off it (one step), released
#: (left free for the rest of the phase).
FREE, HELD, KICKED, RELEASED = 0, 1, 2, 3


@numba.njit(cache=True, inline="always")
def _is_held(state) -> bool:
    """Whether a regularizer in this state is a constraint of the step (held at zero, or kicked off it)."""
    return state == HELD or state == KICKED


@numba.njit(cache=True)
def objective_derivatives(level, prog, ws, smoothing, curvature, g, H, chain_ptr, chain_idx, gr, Hr, mu,
                          majorize_below, states) -> float:
    """Weighted value, gradient ``g (n,)`` and Hessian ``H (n, n)`` of the blocks of ``level`` (``< 0``: all
    levels 1 and 2) from the residual rows in ``ws``; ``curvature`` adds their second-order kinematics.
    ``gr, mu (rows,)`` and ``Hr (rows, rows)`` are scratch at least as large as the largest block; norms shorter
    than ``majorize_below`` get their majorizing curvature (see ``rho_derivatives``); blocks ``b`` whose
    ``states[b]`` is ``HELD`` or ``KICKED`` are left out (norms held at zero as constraints; zeros: none)."""
    bint, bflt, params, idx = prog[0], prog[1], prog[2], prog[3]
    out, Jf, r, Jr = ws[0], ws[2], ws[3], ws[4]
    n = g.shape[0]
    g[:] = 0.0
    H[:] = 0.0
    row, value = ROW0, 0.0
    for b in range(bint.shape[0]):
        lv = bint[b, LEVEL]
        if (level >= 0 and lv != level) or (level < 0 and lv == 0):
            continue
        rows, w = bint[b, ROWS], bflt[b, WEIGHT]
        if _is_held(states[b]):
            row += rows
            continue
        rho_derivatives(bint[b, RHO], bflt[b, SCALE], r, row, rows, smoothing, gr, Hr, majorize_below)
        value += w * rho_value(bint[b, RHO], bflt[b, SCALE], r, row, rows)
        if bint[b, KIND] == COORDINATES:  # unit rows (motion): Jᵀ scatters onto the block's coordinates
            q = bint[b, IPTR]
            for a in range(rows):
                g[idx[q + a]] += w * gr[a]
            for a in range(rows):
                for c in range(rows):
                    h = w * Hr[a, c]
                    if h != 0.0:
                        H[idx[q + a], idx[q + c]] += h
            row += rows  # (no curvature: linear in x)
            continue
        for i in range(n):
            acc = 0.0
            for a in range(rows):
                acc += Jr[row + a, i] * gr[a]
            g[i] += w * acc
        for a in range(rows):  # H += w Jᵀ Hr J
            for c in range(rows):
                h = w * Hr[a, c]
                if h == 0.0:
                    continue
                for i in range(n):
                    ja = Jr[row + a, i]
                    if ja == 0.0:
                        continue
                    for j in range(n):
                        H[i, j] += h * ja * Jr[row + c, j]
        if curvature:
            for a in range(rows):
                mu[a] = w * gr[a]
            block_curvature(b, mu, out, Jf, bint, params, prog[3], chain_ptr, chain_idx, r, row, H)
        row += rows
    return value


@numba.njit(cache=True)
def _set_aside_clear(bint, r, J, near) -> int:
    """``near``: the block table ``bint`` with the one-sided task blocks whose rows ``r`` are all zero (clear: no
    Jacobian either) set aside (level 0); their rows are dropped from the stacked ``r (m,)`` and ``J (m, n)`` in
    place, the others moved up in order, as :func:`~framework.costs.kernels.linearize` stacks ``near``'s task.
    Returns the rows kept."""
    row = kept = 0
    for b in range(bint.shape[0]):
        near[b, LEVEL] = bint[b, LEVEL]
        if bint[b, LEVEL] != 1:
            continue
        rows = bint[b, ROWS]
        if is_hinge(bint[b, KIND]) and rows_clear(r, row, rows):
            near[b, LEVEL] = 0
        else:
            if kept != row:
                for c in range(rows):
                    r[kept + c] = r[row + c]
                    J[kept + c, :] = J[row + c, :]
            kept += rows
        row += rows
    return kept


@numba.njit(cache=True)
def _restoring_steps(x, lower, upper, box_wrap, kin, prog, ws, m, A, L, y, dx, Jc, steps, target, before):
    """Up to ``steps`` Gauss-Newton least-norm steps on the ``m`` task rows of ``prog`` stacked in ``ws`` (with
    their Jacobians at ``x``) until ``‖r‖ <= target``; a step that raises ``‖r‖`` by more than rounding (1e-14) is
    undone, and one that does not lower it ends the steps. Returns ``(‖r‖, whether ‖r‖ stopped falling)``."""
    n = x.shape[0]
    e = np.sqrt(squared_norm(ws[3], m))
    taken = 0
    while taken < steps and e > target:
        if not bounded_step(x, ws[4][:m], ws[3][:m], RESTORE_DAMPING, lower, upper, box_wrap, Jc[:m], A, L, y, dx):
            return e, True
        taken += 1
        before[:] = x
        for i in range(n):
            x[i] += dx[i]
        project(x, lower, upper, box_wrap)
        linearize(x, TASK, kin, prog, ws, YES, COMPUTE)
        e_new = np.sqrt(squared_norm(ws[3], m))
        if not e_new < e:
            if e_new > e + 1e-14:  # worse, beyond rounding: undone
                x[:] = before
                linearize(x, TASK, kin, prog, ws, YES, COMPUTE)
            else:
                e = e_new
            return e, True
        e = e_new
    return e, False


@numba.njit(cache=True)
def _restore(x, lower, upper, box_wrap, kin, prog, near, ws, m, A, L, y, dx, Jc, steps, target, before):
    """Gauss-Newton least-norm steps on the task residuals until ``‖r‖ <= target`` (coordinates held at a bound
    the step would push through are left out of it; ``A, L`` flat scratch; ``before (n,)`` scratch); a step that
    raises ``‖r‖`` by more than rounding is undone. ``ws`` holds the task's rows and Jacobians at ``x``.

    The steps leave out the one-sided blocks clear at ``x`` (``near``: a copy of ``prog``'s block table, where
    they are set aside): a clear row has no Jacobian, so it takes no part in a step, and steps this short seldom
    enter it — but its evaluation is the cost of a step (a collision term's rows, almost all clear). The whole
    task is evaluated after them, and steps on every row go on from there if one was entered.
    Returns ``(‖r‖, whether ws holds the Jacobians at x)``: on return ``ws`` holds the whole task's residuals at
    ``x``, without their Jacobians (and frame Jacobians) when the last evaluation was the check of the set-aside
    rows (:data:`~framework.costs.kernels.JACOBIANS_FROM_POSES` adds them)."""
    if steps == 0 or np.sqrt(squared_norm(ws[3], m)) <= target:
        return np.sqrt(squared_norm(ws[3], m)), True
    mn = _set_aside_clear(prog[0], ws[3], ws[4], near)
    if mn < m:
        kept = (near, prog[1], prog[2], prog[3], prog[4], prog[5], prog[6])
        _, stalled = _restoring_steps(x, lower, upper, box_wrap, kin, kept, ws, mn, A, L, y, dx, Jc, steps, target,
                                      before)
        linearize(x, TASK, kin, prog, ws, NO, REUSE)  # every row again, the set-aside ones included (the steps
        # left the poses at x in ws)
        e = np.sqrt(squared_norm(ws[3], m))
        if e <= target or stalled:
            return e, False
        # a step entered a set-aside row: on with every row
        linearize(x, TASK, kin, prog, ws, YES, JACOBIANS_FROM_POSES)
    e, _ = _restoring_steps(x, lower, upper, box_wrap, kin, prog, ws, m, A, L, y, dx, Jc, steps, target, before)
    return e, True


@numba.njit(cache=True)
def _max_rows(prog) -> int:
    bint = prog[0]
    rows = 1
    for b in range(bint.shape[0]):
        rows = max(rows, bint[b, ROWS])
    return rows


@numba.njit(cache=True)
def _hinge_rows(prog, m):
    """``(m,)`` True for the task rows of one-sided blocks (distances, cones, collision rows: zero when clear),
    and ``(m,)`` True for the contact rows among them (collision rows: signed distances above a margin)."""
    bint = prog[0]
    hinge, contact = np.zeros(m, dtype=np.bool_), np.zeros(m, dtype=np.bool_)
    row = 0
    for b in range(bint.shape[0]):
        if bint[b, LEVEL] != 1:
            continue
        for a in range(bint[b, ROWS]):
            hinge[row + a] = is_hinge(bint[b, KIND])
            contact[row + a] = is_contact(bint[b, KIND])
        row += bint[b, ROWS]
    return hinge, contact


@numba.njit(cache=True)
def _active_rows(A, r, lam, hinge, arow, Aa, release) -> int:
    """The task rows held as equalities in the next Newton step, into ``arow`` (and their Jacobian rows into
    ``Aa``); returns their count. A row with no Jacobian (a hinge that is clear) constrains nothing; with
    ``release``, a hinge row whose multiplier pulls to its free side is let go (``λ`` and the violated side's sign
    ``r`` agree: moving off the boundary lowers the objective)."""
    m, n = A.shape
    ma = 0
    for a in range(m):
        moving = False
        for i in range(n):
            if A[a, i] != 0.0:
                moving = True
                break
        if not moving or (release and hinge[a] and lam[a] * r[a] > 0.0):
            continue
        arow[ma] = a
        for i in range(n):
            Aa[ma, i] = A[a, i]
        ma += 1
    return ma


@numba.njit(cache=True)
def _step_taken(x, xt, box_wrap, delta) -> None:
    """``delta = xt − x (n,)``, the wrapping coordinates' differences taken the short way round."""
    for i in range(x.shape[0]):
        d = xt[i] - x[i]
        delta[i] = wrap_angle(d) if box_wrap[i] else d


@numba.njit(cache=True, inline="always")
def _value_at_start(r, J, delta, a) -> float:
    """Row ``a``'s value at the step's start by its linearization at the trial: ``r_a − J_a · delta``
    (``delta``: the step, :func:`_step_taken`)."""
    c = r[a]
    for i in range(delta.shape[0]):
        c -= J[a, i] * delta[i]
    return c


@numba.njit(cache=True)
def _entered(x, xt, box_wrap, hinge, r_x, held_now, r, J, delta, Jb, cb, sb) -> bool:
    """Whether the trial ``xt`` violates a one-sided row that is clear at ``x`` (``r_x`` zero, not held): the most
    violated such row's Jacobian at ``xt`` into ``Jb``, its linearized value at ``x`` into ``cb`` and its violated
    side into ``sb`` (``±1``; ``0`` for the other rows not held).

    A curved row (a collision row's closest sphere pair changes along the step) can extrapolate to the violated
    side at ``x``, where it is clear: held at that value, it would push the step back out of a contact ``x`` is
    not in. It is held where ``x`` is instead (``cb = 0``: no step into it, to first order)."""
    worst, pick = 0.0, -1
    for a in range(hinge.shape[0]):
        if held_now[a] or not hinge[a]:
            continue
        sb[a] = 0.0
        if r_x[a] == 0.0 and abs(r[a]) > worst:
            worst, pick = abs(r[a]), a
    if pick < 0:
        return False
    _step_taken(x, xt, box_wrap, delta)
    c = _value_at_start(r, J, delta, pick)
    for i in range(x.shape[0]):
        Jb[pick, i] = J[pick, i]
    sb[pick] = 1.0 if r[pick] > 0.0 else -1.0
    cb[pick] = c if c * sb[pick] < 0.0 else 0.0
    return True


@numba.njit(cache=True)
def _boundary_fraction(x, xt, box_wrap, hinge, r_x, held_now, r, J, delta) -> float:
    """The fraction of the step ``x -> xt`` at which the first one-sided row clear at ``x`` (not held) that ``xt``
    violates reaches its boundary, by each such row's linearization at ``xt`` (``delta (n,)`` scratch); ``1`` when
    none is violated, or none is clear at ``x`` by its linearization."""
    _step_taken(x, xt, box_wrap, delta)
    tau = 1.0
    for a in range(hinge.shape[0]):
        if held_now[a] or not hinge[a] or r_x[a] != 0.0 or r[a] == 0.0:
            continue
        c = _value_at_start(r, J, delta, a)
        if c * r[a] < 0.0:  # the row's zero lies on the step
            tau = min(tau, c / (c - r[a]))
    return tau


@numba.njit(cache=True)
def _blocking_at_x(x, kin, band_prog, ws, rn, Jn, contact, blocking, Jb, cb) -> bool:
    """The blocking rows linearized at ``x`` instead of at the trials they came from: the contact rows
    evaluated with their margins widened by :data:`BAND` (``band_prog``; poses reused from ``ws``, at ``x``),
    each blocking row within the band held at its boundary by that linearization (``Jb``, ``cb``), the others let
    go. ``rn (rows,)``, ``Jn (rows, n)`` scratch. Returns whether a blocking row is kept."""
    wsn = (ws[0], ws[1], ws[2], rn, Jn, ws[5], ws[6])
    linearize(x, TASK, kin, band_prog, wsn, NO, REUSE)
    linearize(x, TASK, kin, band_prog, wsn, YES, JACOBIANS_FROM_POSES)
    kept = False
    for a in range(blocking.shape[0]):
        if blocking[a]:
            if contact[a] and rn[a] < 0.0:
                cb[a] = rn[a] + BAND
                Jb[a, :] = Jn[a, :]
                kept = True
            else:
                blocking[a] = False
    return kept


@numba.njit(cache=True)
def _moved(x, xt, box_wrap, blocking, Jb, cb, delta) -> None:
    """The blocking rows' linearized values carried from ``x`` to the accepted ``xt``."""
    _step_taken(x, xt, box_wrap, delta)
    for a in range(blocking.shape[0]):
        if blocking[a]:
            for i in range(x.shape[0]):
                cb[a] += Jb[a, i] * delta[i]


@numba.njit(cache=True)
def _regularizer_rows(prog, first) -> None:
    """``first[b]``: block ``b``'s first row among the regularizer rows (``-1``: not a regularizer)."""
    bint = prog[0]
    row = 0
    for b in range(bint.shape[0]):
        first[b] = -1
        if bint[b, LEVEL] == 2:
            first[b] = row
            row += bint[b, ROWS]


@numba.njit(cache=True)
def _update_holds(prog, r_reg, first, state, lam, m, target) -> bool:
    """Hold the free norm regularizers shorter than :data:`HOLD_BELOW` at zero, and kick the held ones whose
    multipliers ``lam[m + row]`` exceed the norm's slope (:func:`_leaving_pays`: moved :data:`KICK` against the
    multiplier, ``target``). Returns whether a state changed."""
    bint = prog[0]
    changed = False
    for b in range(bint.shape[0]):
        f = first[b]
        if f < 0 or bint[b, RHO] != NORM:
            continue
        rows = bint[b, ROWS]
        if state[b] == FREE and np.sqrt(squared_norm(r_reg[f:], rows)) < HOLD_BELOW:
            state[b] = HELD
            changed = True
            for c in range(rows):
                lam[m + f + c], target[f + c] = 0.0, 0.0
        elif state[b] == HELD:
            norm = _leaving_pays(prog, b, lam, m + f)
            if norm > 0.0:
                state[b] = KICKED
                changed = True
                for c in range(rows):
                    target[f + c] = -KICK * lam[m + f + c] / norm
    return changed


@numba.njit(cache=True)
def _release_holds(state) -> None:
    """Every held or kicked regularizer released (for the rest of the phase)."""
    for b in range(state.shape[0]):
        if _is_held(state[b]):
            state[b] = RELEASED


@numba.njit(cache=True)
def _held_rows(prog, first, state, J_reg, n, m, arow, Aa, ma) -> int:
    """The held and kicked regularizers' rows appended to the active rows (``arow`` entries ``m + row``, their
    Jacobian rows into ``Aa`` from ``ma`` on); returns the new count."""
    bint = prog[0]
    for b in range(bint.shape[0]):
        if not _is_held(state[b]):
            continue
        f = first[b]
        for c in range(bint[b, ROWS]):
            arow[ma] = m + f + c
            for i in range(n):
                Aa[ma, i] = J_reg[f + c, i]
            ma += 1
    return ma


@numba.njit(cache=True)
def _moving_rows(Aa, arow, fidx, nf, mr, ma) -> int:
    """The held regularizers' rows ``mr:ma`` of ``Aa`` kept only where they move a free coordinate ``fidx[:nf]``
    (a coordinate at its bound holds its own motion at zero: its row would make the step's system singular);
    returns the new count."""
    k = mr
    for a in range(mr, ma):
        moving = False
        for c in range(nf):
            if Aa[a, fidx[c]] != 0.0:
                moving = True
                break
        if moving:
            if k != a:
                arow[k] = arow[a]
                Aa[k, :] = Aa[a, :]
            k += 1
    return k


@numba.njit(cache=True)
def _leaving_pays(prog, b, lam, start) -> float:
    """The norm of block ``b``'s multipliers ``lam[start:start + rows]`` when it exceeds the norm's slope ``w s``
    (held at zero, the block then lowers the sum by leaving it: the subgradient condition fails), else 0."""
    norm = np.sqrt(squared_norm(lam[start:], prog[0][b, ROWS]))
    return norm if norm > prog[1][b, WEIGHT] * prog[1][b, SCALE] * (1.0 + 1e-9) else 0.0


@numba.njit(cache=True)
def _kick_due(prog, first, state, lam, m) -> bool:
    """Whether a held regularizer's multiplier ``lam[m + row]`` says leaving zero pays (:func:`_leaving_pays`)."""
    for b in range(state.shape[0]):
        if state[b] == HELD and _leaving_pays(prog, b, lam, m + first[b]) > 0.0:
            return True
    return False


@numba.njit(cache=True, inline="always")
def tangent_size(n: int, rows: int) -> int:
    """Entries of :func:`_tangent_step`'s scratch for ``n`` coordinates and up to ``rows`` active rows."""
    return 2 * n * rows + 3 * rows + 6 * n * n + 6 * n + 2 * rows * rows


@numba.njit(cache=True)
def tangent_views(buffer, start: int, n: int, rows: int) -> tuple:
    """Scratch of :func:`_tangent_step` for ``n`` coordinates and up to ``rows`` active rows: views of ``buffer``
    from entry ``start`` on (:func:`tangent_size` entries)."""
    a, nn, rr = start, n * n, rows * rows
    return (carve(buffer, a, (n, rows)), carve(buffer, a + n * rows, (n, rows)), carve(buffer, a + 2 * n * rows, rows),
            carve(buffer, a + 2 * n * rows + rows, (n, n)), carve(buffer, a + 2 * n * rows + rows + nn, (n, n)),
            carve(buffer, a + 2 * n * rows + rows + 2 * nn, nn), carve(buffer, a + 2 * n * rows + rows + 3 * nn, nn),
            carve(buffer, a + 2 * n * rows + rows + 4 * nn, (n, n)),
            carve(buffer, a + 2 * n * rows + rows + 5 * nn, (n, n)),
            carve(buffer, a + 2 * n * rows + rows + 6 * nn, n), carve(buffer, a + 2 * n * rows + rows + 6 * nn + n, n),
            carve(buffer, a + 2 * n * rows + rows + 6 * nn + 2 * n, n),
            carve(buffer, a + 2 * n * rows + rows + 6 * nn + 3 * n, n),
            carve(buffer, a + 2 * n * rows + rows + 6 * nn + 4 * n, n),
            carve(buffer, a + 2 * n * rows + rows + 6 * nn + 5 * n, n),
            carve(buffer, a + 2 * n * rows + rows + 6 * nn + 6 * n, rr),
            carve(buffer, a + 2 * n * rows + rows + 6 * nn + 6 * n + rr, rr),
            carve(buffer, a + 2 * n * rows + rows + 6 * nn + 6 * n + 2 * rr, rows),
            carve(buffer, a + 2 * n * rows + rows + 6 * nn + 6 * n + 2 * rr + rows, rows))


@numba.njit(cache=True, inline="always")
def _model_gradient(H, rhs, d, nf, u) -> None:
    """``u = g + H d`` over the ``nf`` free coordinates (``rhs[:nf] = −g``): the model's gradient at ``d``."""
    for i in range(nf):
        s = -rhs[i]
        for j in range(nf):
            s += H[i, j] * d[j]
        u[i] = s


@numba.njit(cache=True)
def _tangent_step(K, rhs, nf, ma, trust, sv, scratch) -> float:
    """The solution ``sv`` of the step's KKT system ``K sv = rhs`` (``K[:nf, :nf] = H + μI`` over the free
    coordinates, ``K[nf:, :nf]`` the ``ma`` active rows ``A``, ``rhs[:nf] = −g``; ``sv[:nf]`` the step, then
    ``−λ``) kept if it is a Newton step to a minimum within the trust radius; otherwise replaced by the
    trust-region step: its normal part (onto the rows' linearization) plus the minimizer of the model over the
    rows' null space within ``‖·‖₂ ≤ trust`` (:func:`~.linalg.trust_region_step`: negative curvature, a saddle
    point's included, is followed to the boundary instead of to the saddle), with least-squares multipliers.
    Returns the model's decrease along the tangent part, or ``−1`` when the KKT step stands."""
    W, Vh, beta, Z, HZ, hz, lz, E, Vz, wz, gz, c, p, dn, u, aa, la, ra, y = scratch
    longest = 0.0
    for i in range(nf):
        longest = max(longest, abs(sv[i]))
    H, A = K[:nf, :nf], K[nf:nf + ma, :nf]
    if longest <= trust:  # H + ρAᵀA positive definite: H is on the rows' null space (Debreu's lemma, one way)
        scale, rows = 1.0, 1e-300
        for i in range(nf):
            scale = max(scale, abs(H[i, i]))
        for a in range(ma):
            s = 0.0
            for i in range(nf):
                s += A[a, i] * A[a, i]
            rows = max(rows, s)
        rho = 1e6 * scale / rows
        Ha = square(hz, nf)
        for i in range(nf):
            for j in range(i + 1):
                s = 0.0
                for a in range(ma):
                    s += A[a, i] * A[a, j]
                Ha[i, j] = Ha[j, i] = H[i, j] + rho * s
        if cholesky_solve(Ha, sv, square(lz, nf), c):
            return -1.0  # the Newton step
    nz = null_space(A, W, Vh, beta, Z)
    if nz == 0:
        return -1.0
    for t in range(nz):  # the tangent part p of the step, and its normal part dn
        s = 0.0
        for i in range(nf):
            s += Z[i, t] * sv[i]
        p[t] = s
    for i in range(nf):
        s = sv[i]
        for t in range(nz):
            s -= Z[i, t] * p[t]
        dn[i] = s
    _model_gradient(H, rhs, dn, nf, u)
    for i in range(nf):  # HZ = H Z
        for t in range(nz):
            s = 0.0
            for j in range(nf):
                s += H[i, j] * Z[j, t]
            HZ[i, t] = s
    Hz, Lz = square(hz, nz), square(lz, nz)
    for t in range(nz):  # the reduced Hessian Zᵀ H Z and gradient Zᵀu
        s = 0.0
        for i in range(nf):
            s += Z[i, t] * u[i]
        gz[t] = s
        for v in range(t + 1):
            s = 0.0
            for i in range(nf):
                s += Z[i, t] * HZ[i, v]
            Hz[t, v] = s
            Hz[v, t] = s
    radius = trust
    if cholesky_solve(Hz, gz, Lz, c):  # positive definite on the tangent space
        if longest <= trust:
            return -1.0  # and within the trust radius: the Newton step
        length = 0.0  # too long: the radius is what the step cut to ``trust`` in its largest coordinate is long
        for i in range(nf):
            length += sv[i] * sv[i]
        radius = trust * np.sqrt(length) / longest
    symmetric_eigen(Hz, nz, E, Vz, wz)
    decrease = trust_region_step(wz, Vz, gz, nz, radius, c, p)
    for i in range(nf):  # the step, and the multipliers of Aᵀλ = g + H step (least squares)
        s = dn[i]
        for t in range(nz):
            s += Z[i, t] * p[t]
        sv[i] = s
    _model_gradient(H, rhs, sv, nf, u)
    # a ridge far below the rows' scale: least norm where rows are redundant
    _multipliers(A, u[:nf], square(aa, ma), square(la, ma), ra, y[:ma], 1e-12)
    for a in range(ma):
        sv[nf + a] = -y[a]
    return decrease


@numba.njit(cache=True)
def regularize(x, lower, upper, box_wrap, kin, prog, smoothing, max_iterations, deadline_ns, multipliers,
               errors, values, stats) -> int:
    """Minimize the weighted regularizers on the task from ``x`` (which reaches it); ``x`` is updated in place.

    ``multipliers (m,)`` receives the task's Lagrange multipliers at the result (``∇G = Aᵀλ``), ``errors`` each
    task block's error there, ``values`` each term's value, and ``stats`` ``int64 (3,)`` iterations, evaluations, accepted steps. Returns
    ``CONVERGED``, ``STALLED`` (no step lowers ``G`` any more), ``DEADLINE``, ``ITERATIONS`` or
    ``NOT_APPLICABLE`` (no regularizer, or no freedom left).
    """
    n = x.shape[0]
    m, q = rows_of(prog, TASK), rows_of(prog, REGULARIZERS)
    stats[0], stats[1], stats[2] = 0, 0, 0
    hinge, contact = _hinge_rows(prog, m)
    equalities = 0
    for a in range(m):
        equalities += 0 if hinge[a] else 1
    if q == 0 or equalities >= n:
        return NOT_APPLICABLE
    kin, prog = borrow_kin(kin), borrow_prog(prog)
    x, lower, upper, box_wrap = borrow(x), borrow(lower), borrow(upper), borrow(box_wrap)
    chain_ptr, chain_idx = prog[5], prog[6]
    own_cur, cur, tri = workspace_pair(kin, prog, n)
    big = _max_rows(prog)
    mq = m + q  # task rows, then regularizer rows (held at zero) in the active set
    nb = prog[0].shape[0]
    # the contact rows near x (the blocks with their margins widened by BAND; their rows rn, Jn at x once
    # band_at_x): made only with contact rows
    near_contact, band_at_x = contact.any(), False
    ws_rows = cur[3].shape[0] if near_contact else 0
    band_params = prog[2].shape[0] if near_contact else 0
    # the scratch arrays, carved from one allocation per type, the zeroed ones first (some sixty allocations cost
    # ~5 µs, as much as a Newton iteration)
    zeroed = 2 * q * n + 3 * mq + m * n + 2 * m + q + n + ws_rows * n
    rest = 2 * q + 8 * n + 2 * n * n + 2 * mq * mq + max(mq, n) + 2 * (n + mq) + 2 * big + big * big + m * n \
        + mq * n + band_params + ws_rows
    kkt = (n + mq) ** 2 + (n + mq) * (n + mq + 1)
    own = np.empty(zeroed + rest + tangent_size(n, mq) + kkt)
    own[:zeroed] = 0.0
    own_ints, own_flags = np.empty(n + mq + nb, dtype=np.int64), np.zeros(2 * m + n, dtype=np.bool_)
    state = np.zeros(nb, dtype=np.int8)  # the regularizers' states
    Jr_cur, Jr_tri = carve(own, 0, (q, n)), carve(own, q * n, (q, n))  # (zeroed)
    a = 2 * q * n
    lam, lam_neg, lam_a = carve(own, a, mq), carve(own, a + mq, mq), carve(own, a + 2 * mq, mq)
    a += 3 * mq
    # blocking rows: one-sided rows clear at x (no Jacobian there) that the last trial step entered, held with
    # their linearization at that trial (``Jb`` rows, value at x ``cb``, violated side ``sb``) until they are
    # active at x with a Jacobian of their own, or their multiplier lets them go
    Jb, cb, sb = carve(own, a, (m, n)), carve(own, a + m * n, m), carve(own, a + m * n + m, m)
    a += m * n + 2 * m
    target = carve(own, a, q)  # kicked norms' aims
    shift = carve(own, a + q, n)  # coordinates the last step at x carried through a bound: their moves onto it
    Jn = carve(own, a + q + n, (ws_rows, n))
    a += q + n + ws_rows * n  # (= zeroed)
    r_cur, r_tri, g, xt, dx, gl = carve(own, a, q), carve(own, a + q, q), carve(own, a + 2 * q, n), \
        carve(own, a + 2 * q + n, n), carve(own, a + 2 * q + 2 * n, n), carve(own, a + 2 * q + 3 * n, n)
    a += 2 * q + 4 * n
    # (gs: the gradient g + H shift the free coordinates see; before: a restoring step's start)
    delta, gs, before, dxm = carve(own, a, n), carve(own, a + n, n), carve(own, a + 2 * n, n), \
        carve(own, a + 3 * n, n)
    a += 4 * n
    H, Hlb = carve(own, a, (n, n)), carve(own, a + n * n, (n, n))
    a += 2 * n * n
    Am, Lm, ym = carve(own, a, (mq, mq)), carve(own, a + mq * mq, (mq, mq)), carve(own, a + 2 * mq * mq, max(mq, n))
    a += 2 * mq * mq + max(mq, n)
    rhs, sol = carve(own, a, n + mq), carve(own, a + n + mq, n + mq)
    a += 2 * (n + mq)
    gr, mu_r, Hr = carve(own, a, big), carve(own, a + big, big), carve(own, a + 2 * big, (big, big))
    a += 2 * big + big * big
    Jc, Aa = carve(own, a, (m, n)), carve(own, a + m * n, (mq, n))
    a += m * n + mq * n
    band_margins, rn = carve(own, a, band_params), carve(own, a + band_params, ws_rows)
    a += band_params + ws_rows
    tangent = tangent_views(own, a, n, mq)
    a += tangent_size(n, mq)
    K, M = carve(own, a, (n + mq) ** 2), carve(own, a + (n + mq) ** 2, (n + mq) * (n + mq + 1))
    assert a + kkt == own.size  # the views above tile the allocation whose size the sums before them give
    fidx, arow, first = carve(own_ints, 0, n), carve(own_ints, n, mq), carve(own_ints, n + mq, nb)
    # (pinned: the coordinates the last step at x carried through a bound, moved onto it by shift)
    held_now, blocking, pinned = carve(own_flags, 0, m), carve(own_flags, m, m), carve(own_flags, 2 * m, n)
    own_near = prog[0].copy()  # the restoring steps' block table (one-sided blocks clear at their start set aside)
    near = borrow(own_near)
    if near_contact:
        widen_margins(prog[0], prog[2], BAND, band_margins)
    band_prog = (prog[0], prog[1], band_margins, prog[3], prog[4], prog[5], prog[6])
    _regularizer_rows(prog, first)
    cur_r = (cur[0], cur[1], cur[2], r_cur, Jr_cur, cur[5], cur[6])
    tri_r = (tri[0], tri[1], tri[2], r_tri, Jr_tri, tri[5], tri[6])
    linearize(x, TASK, kin, prog, cur, YES, COMPUTE)
    linearize(x, REGULARIZERS, kin, prog, cur_r, YES, REUSE)
    evaluations = 1
    feasible = max(np.sqrt(squared_norm(cur[3], m)), 1e-13)
    G = level_value(REGULARIZERS, prog, cur_r[3], YES)
    objective_derivatives(REGULARIZERS, prog, cur_r, smoothing, YES, g, H, chain_ptr, chain_idx, gr, Hr, mu_r,
                          TRUST_START, state)  # norms shorter than the first trust radius: moved to, not past, zero
    ma = _active_rows(cur[4][:m], cur[3], lam, hinge, arow, Aa, False)
    _scatter_multipliers(Aa[:ma], g, Am, Lm, ym, lam_a, arow, ma, lam)  # of the start: least squares A Aᵀ λ = A ∇G
    fresh = True  # g, H hold the derivatives at x
    mu, trust, last_step = MU_START, TRUST_START, 0.0
    status, iterations, accepted = ITERATIONS, 0, 0
    bint, bflt = prog[0], prog[1]
    unblocked, failed, redundant = False, 0, False
    while iterations < max_iterations:
        if deadline_ns > 0 and monotonic_ns() >= deadline_ns:
            status = DEADLINE
            break
        iterations += 1
        if _update_holds(prog, cur_r[3], first, state, lam, m, target):
            fresh = False  # G's derivatives without the held norms
        if not fresh:  # a norm shorter than the last step gets its majorizing curvature
            objective_derivatives(REGULARIZERS, prog, cur_r, smoothing, YES, g, H, chain_ptr, chain_idx, gr, Hr, mu_r,
                                  2.0 * last_step, state)
            fresh = True
        ma = _active_rows(cur[4][:m], cur[3], lam, hinge, arow, Aa, True)
        own_rows = ma  # rows held with their own Jacobian at x; the blocking rows follow them
        held_now[:] = False
        for c in range(ma):
            held_now[arow[c]] = True
        for a in range(m):
            if not blocking[a]:
                continue
            if held_now[a] or lam[a] * sb[a] > 0.0:  # active at x, or its multiplier pulls to its free side
                blocking[a] = False
                continue
            arow[ma] = a
            for i in range(n):
                Aa[ma, i] = Jb[a, i]
            held_now[a] = True
            ma += 1
        mr = ma  # the task's rows (own and blocking); the held regularizers' rows follow them
        ma = _held_rows(prog, first, state, cur_r[4], n, m, arow, Aa, ma)
        for a in range(m):  # released and clear rows carry no multiplier
            if not held_now[a]:
                lam[a] = 0.0
        for b in range(nb):
            if first[b] >= 0 and not _is_held(state[b]):
                for c in range(bint[b, ROWS]):
                    lam[m + first[b] + c] = 0.0
        for i in range(n):  # gl = ∇G − Aᵀλ, the Lagrangian's gradient
            s = g[i]
            for a in range(ma):
                s -= Aa[a, i] * lam[arow[a]]
            gl[i] = s
        nf = 0
        for i in range(n):  # the coordinates descent along −gl does not push through a bound
            if not pinned[i] and not held(x[i], lower[i], upper[i], box_wrap[i], -gl[i]):
                fidx[nf] = i
                nf += 1
        ma = _moving_rows(Aa, arow, fidx, nf, mr, ma)
        if nf <= mr:  # (held norms may be redundant with the task: their rows are solved in least squares)
            if ma > mr:  # no freedom left with the held regularizers: let them go
                _release_holds(state)
                fresh = False
                continue
            if ma > own_rows:  # held by the blocking rows (linearized at trial points): backtrack without them
                blocking[:] = False
                unblocked = True
                continue
            status = CONVERGED
            break
        row = ROW0  # the Lagrangian's Hessian: H − Σ λ_b ∇²r_b over the task blocks (into K's free block)
        k = nf + ma
        Kv, Mv, rv, sv = square(K, k), matrix(M, k, k + 1), rhs[:k], sol[:k]  # contiguous: the LU's loops vectorize
        Hlb[:, :] = H
        for b in range(bint.shape[0]):
            if bint[b, LEVEL] != 1:
                continue
            rows = bint[b, ROWS]
            held_rows = False
            for a in range(rows):
                lam_neg[row + a] = -lam[row + a]
                held_rows = held_rows or lam[row + a] != 0.0
            if held_rows:  # a clear or released row has no multiplier and adds no curvature
                block_curvature(b, lam_neg[row:], cur[0], cur[2], bint, prog[2], prog[3], chain_ptr, chain_idx, cur[3],
                                row, Hlb)
            row += rows
        extra = 0.0  # what the step gains on the held norms (out of gl: taken to zero), or inf for a kick
        for b in range(nb):
            if not _is_held(state[b]):
                continue
            f = first[b]
            for c in range(bint[b, ROWS]):
                lam_neg[m + f + c] = -lam[m + f + c]
            block_curvature(b, lam_neg[m + f:], cur[0], cur[2], bint, prog[2], prog[3], chain_ptr, chain_idx,
                            cur_r[3], f, Hlb)
            extra += np.inf if state[b] == KICKED else \
                bflt[b, WEIGHT] * bflt[b, SCALE] * np.sqrt(squared_norm(cur_r[3][f:], bint[b, ROWS]))
        for i in range(n):  # the pinned coordinates' moves onto their bounds, seen by the others
            s = g[i]
            for j in range(n):
                if shift[j] != 0.0:
                    s += Hlb[i, j] * shift[j]
            gs[i] = s
        for a in range(nf):
            i = fidx[a]
            for c in range(nf):
                Kv[a, c] = Hlb[i, fidx[c]]
            Kv[a, a] += mu
            for c in range(ma):
                Kv[a, nf + c] = Aa[c, i]
                Kv[nf + c, a] = Aa[c, i]
            rv[a] = -gs[i]
        for a in range(ma):
            for c in range(ma):
                Kv[nf + a, nf + c] = 0.0
            if a >= mr or (redundant and a < own_rows):  # a held norm's rows, regularized: with the task they may
                Kv[nf + a, nf + a] = -HELD_DAMPING  # be redundant (a joint group at rest leaves the rest of the task
            if a < own_rows:  # to fewer coordinates); the task's own rows too once they were found dependent
                rv[nf + a] = -cur[3][arow[a]]
                if redundant:  # (+ δλ, as the held norms: exactly on the rows once λ settles)
                    rv[nf + a] += HELD_DAMPING * lam[arow[a]]
            elif a < mr:
                rv[nf + a] = -cb[arow[a]]
            else:  # a held norm to zero, a kicked one to its aim (+ δλ: exactly there once λ settles)
                rv[nf + a] = target[arow[a] - m] - cur_r[3][arow[a] - m] + HELD_DAMPING * lam[arow[a]]
            for j in range(n):
                if shift[j] != 0.0:
                    rv[nf + a] -= Aa[a, j] * shift[j]
        if not lu_solve(Kv, rv, Mv, sv):
            if mr > own_rows:  # the blocking rows' Jacobians (from trial points) made it singular: let them go,
                blocking[:] = False  # and backtrack without them until a step is taken
                unblocked = True
                continue
            if not redundant and own_rows > 0:  # the task's rows are dependent (two contact rows along one
                redundant = True  # direction): held in least squares from here on (damping H cannot help)
                continue
            mu *= 10.0
            if mu > MU_MAX:
                status = STALLED
                break
            continue
        model = _tangent_step(Kv, rv, nf, ma, trust, sv, tangent)
        pushed = False
        for a in range(nf):  # a coordinate the step carries through its bound within its first tenth: moved
            i = fidx[a]  # onto the bound, and the step solved again (clipped, the step would leave the task)
            if not box_wrap[i] and ((sv[a] > 0.0 and upper[i] - x[i] < PIN * sv[a]) or
                                    (sv[a] < 0.0 and x[i] - lower[i] < -PIN * sv[a])):
                pinned[i] = pushed = True
                shift[i] = (upper[i] if sv[a] > 0.0 else lower[i]) - x[i]
        if pushed:
            continue
        step = 0.0
        for i in range(n):
            dx[i] = shift[i]
            step = max(step, abs(shift[i]))
        for a in range(nf):
            dx[fidx[a]] = sv[a]
            step = max(step, abs(sv[a]))
        predicted = 0.0  # first-order decrease of the Lagrangian along the step (within the trust region)
        for i in range(n):
            predicted -= gl[i] * dx[i]
        if model >= 0.0:  # a trust-region step: its model's decrease (negative curvature counts)
            predicted = model
        elif step > trust:  # along a flat direction of G (a norm along its own ray) Newton steps are unbounded
            predicted *= trust / step
        predicted += extra
        if step < 1e-12 or predicted < 1e-15 * (1.0 + abs(G)):  # no step, or below what G can resolve
            if ma > mr:  # at rest with norms held at zero: kick those whose multipliers say leaving pays
                for a in range(mr, ma):
                    lam[arow[a]] = -sv[nf + a]
                if _kick_due(prog, first, state, lam, m):
                    continue
            if mr > own_rows:  # stopped by the blocking rows (linearized at trial points)
                if near_contact and not band_at_x:  # once more with their linearization at x
                    band_at_x = True
                    if _blocking_at_x(x, kin, band_prog, cur, rn, Jn, contact, blocking, Jb, cb):
                        continue
                elif band_at_x:  # no step with them linearized at x: converged if each presses (its multiplier)
                    pressing = True
                    for c in range(own_rows, mr):
                        pressing = pressing and -sv[nf + c] * sb[arow[c]] <= 0.0
                    if pressing:
                        status = CONVERGED
                        break
                blocking[:] = False  # backtrack without them
                unblocked = True
                continue
            status = CONVERGED
            break
        if step > trust:
            for i in range(n):
                dx[i] *= trust / step
            step = trust
        alpha, accepted_step, Gt, entered = 1.0, False, G, False
        for _ in range(LINE_SEARCH):  # backtrack along the Newton direction before damping it
            for i in range(n):
                xt[i] = x[i] + alpha * dx[i]
            project(xt, lower, upper, box_wrap)
            if near_contact:  # the frame Jacobians only of the rows not clear at the trial (contact rows: most are)
                linearize(xt, TASK, kin, prog, tri, NO, COMPUTE)
                linearize(xt, TASK, kin, prog, tri, YES, JACOBIANS_FROM_POSES)
            else:
                linearize(xt, TASK, kin, prog, tri, YES, COMPUTE)
            entered = not unblocked and _entered(x, xt, box_wrap, hinge, cur[3], held_now, tri[3], tri[4], delta,
                                                 Jb, cb, sb)
            # backtracking without the blocking rows: to the boundary of the first row the trial entered
            tau = _boundary_fraction(x, xt, box_wrap, hinge, cur[3], held_now, tri[3], tri[4], delta) \
                if unblocked else 1.0
            e, current = _restore(xt, lower, upper, box_wrap, kin, prog, near, tri, m, Am.reshape(Am.size),
                                  Lm.reshape(Lm.size), ym, dxm, Jc, RESTORE_STEPS, feasible, before)
            linearize(xt, REGULARIZERS, kin, prog, tri_r, current, REUSE)
            evaluations += 1
            Gt = level_value(REGULARIZERS, prog, tri_r[3], YES)
            if e <= feasible and Gt < G:
                if not current:  # the Jacobians at the step taken (a rejected trial needs none)
                    linearize(xt, TASK, kin, prog, tri, YES, JACOBIANS_FROM_POSES)
                    linearize(xt, REGULARIZERS, kin, prog, tri_r, YES, REUSE)
                accepted_step = True
                break
            if entered:  # the step entered one-sided rows clear at x: solve it again holding them
                break
            alpha *= 0.5 if tau >= 1.0 else min(max(tau, BOUNDARY_MIN), BOUNDARY_MAX)
        if accepted_step:
            gain = G - Gt
            cur, tri = tri, cur
            cur_r, tri_r = tri_r, cur_r
            _moved(x, xt, box_wrap, blocking, Jb, cb, delta)
            x[:] = xt
            unblocked, band_at_x = False, False
            pinned[:] = False
            shift[:] = 0.0
            failed = 0
            G = Gt
            for a in range(mq):
                lam[a] = 0.0
            for a in range(ma):
                lam[arow[a]] = -sv[nf + a]
            accepted += 1
            fresh = False
            last_step = alpha * step
            for b in range(nb):
                if state[b] == KICKED:  # off zero along its multiplier: free from here (no majorizing curvature)
                    state[b], last_step = RELEASED, 0.0
            if alpha == 1.0:
                mu = max(mu * 0.1, MU_MIN)
                trust = min(2.0 * trust, TRUST_MAX)
            else:
                trust = max(alpha * step, 1e-12)
            if (alpha * step < 1e-10 or gain <= 1e-16 * (1.0 + abs(G))) and not _kick_due(prog, first, state, lam, m):
                status = CONVERGED  # (a held norm whose multiplier says leaving zero pays: kicked next)
                break
        elif entered:
            for a in range(m):  # the candidates written by _entered become blocking rows
                if not held_now[a] and sb[a] != 0.0:
                    blocking[a] = True
        elif mr > own_rows:  # no step along the blocking rows (linearized at trial points): once more with their
            if near_contact and not band_at_x:  # linearization at x, then backtrack without them
                band_at_x = True
                if _blocking_at_x(x, kin, band_prog, cur, rn, Jn, contact, blocking, Jb, cb):
                    continue
            blocking[:] = False
            unblocked = True
        else:
            trust *= 0.1
            mu *= 10.0
            failed += 1
            kinked = False
            for c in range(mr):
                kinked = kinked or hinge[arow[c]]
            if mu > MU_MAX or trust < 1e-12 or (kinked and failed >= KINK_FAILURES):
                status = STALLED
                break
    _, current = _restore(x, lower, upper, box_wrap, kin, prog, near, cur, m, Am.reshape(Am.size), Lm.reshape(Lm.size),
                          ym, dxm, Jc, RESTORE_STEPS, 0.0, before)  # to the last bit
    if not current:
        linearize(x, TASK, kin, prog, cur, YES, JACOBIANS_FROM_POSES)
    linearize(x, REGULARIZERS, kin, prog, cur_r, YES, REUSE)
    objective_derivatives(REGULARIZERS, prog, cur_r, smoothing, NO, g, H, chain_ptr, chain_idx, gr, Hr, mu_r,
                          0.0, state)
    ma = _active_rows(cur[4][:m], cur[3], lam, hinge, arow, Aa, False)
    ma = _held_rows(prog, first, state, cur_r[4], n, m, arow, Aa, ma)  # held norms: constraints, out of ∇G
    _scatter_multipliers(Aa[:ma], g, Am, Lm, ym, lam_a, arow, ma, lam)
    multipliers[:] = lam[:m]
    task_errors(prog, cur[3], errors)
    term_values(x, prog, cur, values)
    stats[0], stats[1], stats[2] = iterations, evaluations, accepted
    keep_alive(own_cur, own, own_ints, own_flags, state, own_near)
    return status


@numba.njit(cache=True)
def _scatter_multipliers(Aa, g, Am, Lm, y, lam_a, arow, ma, lam):
    """:func:`_multipliers` of the active rows ``Aa (ma, n)``, written to their rows ``arow`` of ``lam (m,)``
    (zeros elsewhere)."""
    lam[:] = 0.0
    if ma == 0:
        return
    _multipliers(Aa, g, Am[:ma, :ma], Lm[:ma, :ma], y, lam_a[:ma])
    for a in range(ma):
        lam[arow[a]] = lam_a[a]


@numba.njit(cache=True)
def _multipliers(A, g, Am, Lm, y, lam, ridge=0.0):
    """Least-squares multipliers ``λ = (A Aᵀ + R)⁻¹ A g`` of ``g ≈ Aᵀλ``, ``R`` the diagonal ``ridge (1 + (A Aᵀ)ᵢᵢ)``
    (zeros if ``A Aᵀ + R`` is not positive definite: ``A`` rank deficient without a ridge)."""
    m, n = A.shape
    for a in range(m):
        s = 0.0
        for i in range(n):
            s += A[a, i] * g[i]
        y[a] = s
    gram(A, 0.0, Am)
    for a in range(m):
        Am[a, a] += ridge * (1.0 + Am[a, a])
    if not cholesky_solve(Am, y, Lm, lam):
        lam[:] = 0.0


@numba.njit(cache=True)
def weighted_newton(x, lower, upper, box_wrap, kin, prog, smoothing, max_iterations, deadline_ns, stats) -> int:
    """Minimize ``Σ w ρ(r)`` over every task and regularizer block from ``x`` (in place), within the box.

    ``stats`` ``int64 (3,)``: iterations, evaluations, accepted steps. Returns ``CONVERGED``, ``STALLED``,
    ``DEADLINE`` or ``ITERATIONS``.
    """
    n = x.shape[0]
    kin, prog = borrow_kin(kin), borrow_prog(prog)
    x, lower, upper, box_wrap = borrow(x), borrow(lower), borrow(upper), borrow(box_wrap)
    chain_ptr, chain_idx = prog[5], prog[6]
    own_cur, cur, tri = workspace_pair(kin, prog, n)
    linearize(x, TASK_AND_REGULARIZERS, kin, prog, cur, YES, COMPUTE)
    evaluations = 1
    g, H = np.empty(n), np.empty((n, n))
    big = _max_rows(prog)
    gr, Hr, mu_r = np.empty(big), np.empty((big, big)), np.empty(big)
    every = np.zeros(prog[0].shape[0], dtype=np.int8)  # no block left out
    F = objective_derivatives(TASK_AND_REGULARIZERS, prog, cur, smoothing, YES, g, H, chain_ptr, chain_idx, gr,
                              Hr, mu_r, 0.0, every)
    Hf, Lf, gf, sf = np.empty((n, n)), np.empty((n, n)), np.empty(n), np.empty(n)
    fidx = np.empty(n, dtype=np.int64)
    xt = np.empty(n)
    mu = MU_START
    status, iterations, accepted = ITERATIONS, 0, 0
    fresh = True
    while iterations < max_iterations:
        if deadline_ns > 0 and monotonic_ns() >= deadline_ns:
            status = DEADLINE
            break
        iterations += 1
        if not fresh:
            F = objective_derivatives(TASK_AND_REGULARIZERS, prog, cur, smoothing, YES, g, H, chain_ptr, chain_idx, gr,
                                      Hr, mu_r, 0.0, every)
            fresh = True
        nf = 0
        for i in range(n):  # the coordinates descent along −g does not push through a bound
            if not held(x[i], lower[i], upper[i], box_wrap[i], -g[i]):
                fidx[nf] = i
                nf += 1
        if nf == 0:
            status = CONVERGED
            break
        Hv, Lv, gv, sv = Hf[:nf, :nf], Lf[:nf, :nf], gf[:nf], sf[:nf]
        for a in range(nf):
            for c in range(nf):
                Hv[a, c] = H[fidx[a], fidx[c]]
            Hv[a, a] += mu
            gv[a] = -g[fidx[a]]
        if not cholesky_solve(Hv, gv, Lv, sv):
            mu = max(mu * 10.0, 1e-10)
            if mu > MU_MAX:
                status = STALLED
                break
            continue
        step = 0.0
        xt[:] = x
        for a in range(nf):
            xt[fidx[a]] += sv[a]
            step = max(step, abs(sv[a]))
        project(xt, lower, upper, box_wrap)
        linearize(xt, TASK_AND_REGULARIZERS, kin, prog, tri, YES, COMPUTE)
        evaluations += 1
        Ft = level_value(TASK_AND_REGULARIZERS, prog, tri[3], YES)
        if Ft < F:
            gain = F - Ft
            cur, tri = tri, cur
            x[:] = xt
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
    keep_alive(own_cur)
    return status


@numba.njit(cache=True)
def exact_penalties(prog, multipliers, pays) -> bool:
    """Whether each task block (level 1, in block order) is an exact penalty for its rows of ``multipliers``,
    into ``pays (blocks,)``; returns whether every one is.

    A block weighted ``w`` with ``ρ = s‖r‖`` is one when ``‖λ_b‖ < w s`` (``w s / 2`` for ``ρ = s sin(‖r‖/2)``):
    then no move off the block lowers the weighted sum. Blocks with other ρ never are.
    """
    bint, bflt = prog[0], prog[1]
    row = k = 0
    every = True
    for b in range(bint.shape[0]):
        if bint[b, LEVEL] != 1:
            continue
        rows, rho = bint[b, ROWS], bint[b, RHO]
        slope = 1.0 if rho == NORM else (0.5 if rho == HALFSIN else 0.0)
        norm = np.sqrt(squared_norm(multipliers[row:], rows))
        pays[k] = slope > 0.0 and norm < bflt[b, WEIGHT] * bflt[b, SCALE] * slope
        every = every and pays[k]
        row += rows
        k += 1
    return every


@numba.njit(cache=True)
def exact_penalty(x, lower, upper, box_wrap, prog, multipliers) -> bool:
    """Whether the task's multipliers make every task block an exact penalty at ``x`` (see
    :func:`exact_penalties`): then ``x`` also minimizes the weighted sum locally. ``False`` on the box
    boundary (bound multipliers are not computed)."""
    for i in range(x.shape[0]):
        if not box_wrap[i] and (x[i] <= lower[i] or x[i] >= upper[i]):
            return False
    return exact_penalties(prog, multipliers, np.empty(prog[0].shape[0], dtype=np.bool_))


@numba.njit(cache=True)
def derivatives_at(x, level, kin, prog, smoothing, curvature):
    """``(value, gradient (n,), Hessian (n, n))`` of the weighted blocks of ``level`` at ``x`` (for callers
    outside the loops: tests, reports)."""
    n = x.shape[0]
    kin, prog = borrow_kin(kin), borrow_prog(prog)
    own, ws = workspace(kin, prog, n)
    linearize(borrow(x), level, kin, prog, ws, YES, COMPUTE)
    big = _max_rows(prog)
    g, H = np.empty(n), np.empty((n, n))
    value = objective_derivatives(level, prog, ws, smoothing, curvature, g, H, prog[5], prog[6], np.empty(big),
                                  np.empty((big, big)), np.empty(big), 0.0, np.zeros(prog[0].shape[0], dtype=np.int8))
    keep_alive(own)
    return value, g, H
