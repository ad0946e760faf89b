"""The Newton phase: regularizers minimized on the task.

From a configuration that reaches the task (level 1), minimize the weighted regularizers (level 2, e.g. motion)
without leaving it: Newton steps on the KKT system ``[H Aᵀ; A 0] [dx; −λ] = [−∇G; −r]`` over the coordinates not
held at a bound, with ``H`` the Hessian of the Lagrangian ``G − λᵀr`` (the regularizers' own curvature plus the
task's second-order kinematics, the block kinds' curvature kernels), followed by Gauss-Newton steps back onto the
task (:mod:`~.restore`). A step is kept only if it lowers ``G`` on the task (and leaves it no further than it
started); otherwise the Hessian is damped (``H + μI``). Converges quadratically to a local minimum: where the
Lagrangian's Hessian is not positive definite on the task's null space, or the Newton step is longer than the trust
radius, the step is the trust-region step there instead (:func:`~.tangent.tangent_step`: negative curvature, a
saddle point's included, is followed to the radius; a too-long step is damped, not cut, so it does not zig-zag
along the norms' flat rays). A coordinate that a step carries through its bound within its first tenth
(:data:`PIN`) is moved onto the bound and the rest of the step solved again (clipped, the step would leave the
task's tangent).
One-sided rows (distance bands, cones, collision rows) are inequalities: a row with a Jacobian is held as an
equality until its multiplier lets it go; a row clear where a step starts has no Jacobian there, so when a trial
step enters one and is rejected, the step is solved again holding that row with its Jacobian at the trial
(a *blocking* row, :mod:`~.active_set`: without it, the step would enter the contact again at every halving), at
its value at ``x`` by that linearization — or where ``x`` is, when a curved row extrapolates to its violated side
at ``x``, which is clear. When the blocking rows stop a step (no step along them, or every halving rejected), the
contact rows among them are linearized again at ``x`` once (:data:`~.active_set.BAND`: their gap and the closest
pair's Jacobian there); when that finds no step either and each of them presses (its multiplier), the phase has
converged on the contact — otherwise a phase crept along it, a cycle of entering, holding and letting go per tiny
gain. Blocking rows let go, the backtracking then cuts a trial that enters one of them at its boundary (by its
linearization) instead of halving it. A collision row is the smallest distance over sphere pairs, with a Jacobian
that jumps where the closest pair changes: after :data:`KINK_FAILURES` failed iterations in a row with a one-sided
row held, the phase stops. When the step's system is singular with no blocking row held, the task's rows are
dependent (two collision rows pressing along one direction): damping ``H`` cannot make it regular, so from then on
the task's rows are held in least squares, as held norms are (:data:`HELD_DAMPING`).
A norm regularizer at its kink (a joint group at rest) is an active set of its own (:mod:`~.holds`). The first
step gives norms shorter than its trust radius their majorizing curvature (a Newton step on a norm's own ray is
unbounded, and a first step past zero failed its halvings).

The phase's state is one record (:mod:`~.newton_state`); an iteration's stages are the step's system
(:mod:`~.newton_system`) and the search along it (:mod:`~.newton_search`).
"""

from __future__ import annotations

import numpy as np

from ..costs.kernels import (COMPUTE, JACOBIANS_FROM_POSES, NO, REGULARIZERS, REUSE, TASK, YES, level_value,
                             linearize, task_errors, term_values, widen_margins)
from ..costs.workspace import WORKSPACE, views, workspaces
from ..compiled.native import address_of, compiled, internal, keep_alive, square, view
from .active_set import BAND, active_rows
from .clock import monotonic_ns
from .derivatives import objective_derivatives
from .holds import held_rows, regularizer_rows, update_holds
from .newton_search import take_step
from .newton_state import (CONVERGED, CUR, CUR_REG, DEADLINE, GO_ON, ITERATIONS, MU_START, NEWTON, NEXT, NOT_APPLICABLE,
                           RESTORE_STEPS, STALLED, TRI, TRI_REG, TRUST_START, lay_out, moves, multipliers, near_table,
                           pick, restoring, rows, system, zero_state)
from .newton_system import build_system, hold_rows, solve_step
from .restore import restore
from .steps import squared_norm
from .tables import hinge_rows, max_rows, rows_of
from .tangent import scatter_multipliers

__all__ = ["CONVERGED", "DEADLINE", "ITERATIONS", "NOT_APPLICABLE", "STALLED", "regularize"]


@compiled
def regularize(x, box, packed, settings, multipliers_out, report) -> int:
    """Minimize the weighted regularizers on the task from ``x`` (which reaches it); ``x`` is updated in place.

    ``settings``: :class:`~.settings.NewtonSettings`. ``multipliers_out (m,)`` receives the task's Lagrange
    multipliers at the result (``∇G = Aᵀλ``); ``report`` (:class:`~.settings.Report`) each task block's error
    there, each term's value, and the iterations, evaluations and accepted steps. Returns ``CONVERGED``,
    ``STALLED``, ``DEADLINE``, ``ITERATIONS`` or ``NOT_APPLICABLE``.
    """
    n = x.shape[0]
    blocks = packed.blocks
    m, q = rows_of(blocks, TASK), rows_of(blocks, REGULARIZERS)
    report.stats[0], report.stats[1], report.stats[2] = 0, 0, 0
    hinge, contact = hinge_rows(blocks, m)
    equalities = 0
    for a in range(m):
        equalities += 0 if hinge[a] else 1
    if q == 0 or equalities >= n:
        return NOT_APPLICABLE
    owners, W = workspaces(packed, n, 5)
    records = np.zeros(1, dtype=NEWTON)
    st = records[0]
    st.n, st.m, st.q, st.mq, st.nb, st.big = n, m, q, m + q, blocks.shape[0], max_rows(blocks)
    st.near_contact = 1 if contact.any() else 0
    st.ws_rows = W[CUR].rows if st.near_contact else 0
    st.band_params = packed.params.shape[0] if st.near_contact else 0
    own = np.empty(lay_out(st, 0) // 8)
    lay_out(st, address_of(own))
    zero_state(st)
    _setup(x, box, packed, W, st, hinge, contact, settings.smoothing)
    status = ITERATIONS
    while st.iterations < settings.max_iterations:
        if settings.deadline_ns > 0 and monotonic_ns() >= settings.deadline_ns:
            status = DEADLINE
            break
        st.iterations += 1
        code = _iteration(x, box, W, st, settings.smoothing)
        if code >= 0:
            status = code
            break
    _finish(x, box, W, st, settings.smoothing, multipliers_out, report)
    keep_alive(owners, own, records, packed)
    return status


def parts(x, box, packed, settings, multipliers_out, report) -> list[tuple[object, tuple]]:
    """``(function, args)`` of the large callees of :func:`regularize` for its arguments, the largest first (for
    :func:`framework.compiled.parallel.entry_points`): arguments of the types regularize passes them."""
    W, st = np.zeros(5, dtype=WORKSPACE), np.zeros(1, dtype=NEWTON)[0]
    rows_ = np.zeros(0, dtype=np.bool_)
    return [(_iteration, (x, box, W, st, settings.smoothing)),
            (_setup, (x, box, packed, W, st, rows_, rows_, settings.smoothing)),
            (_finish, (x, box, W, st, settings.smoothing, multipliers_out, report))]


@internal
def _setup(x, box, packed, W, st, hinge, contact, smoothing) -> None:
    """The phase's workspaces, tables and state at the start ``x``."""
    r, mv, mult, sys = rows(st), moves(st), multipliers(st), system(st)
    for a in range(st.m):
        r.hinge[a], r.contact[a] = hinge[a], contact[a]
    near = near_table(st)
    for k in range(st.nb):
        near[k] = packed.blocks[k]
    for reg, at in ((CUR_REG, CUR), (TRI_REG, TRI)):  # the regularizer rows: their own residual arrays
        W[reg] = W[at]
    W[CUR_REG].residuals, W[CUR_REG].residual_jacobian, W[CUR_REG].rows = st.r_cur, st.Jr_cur, st.q
    W[TRI_REG].residuals, W[TRI_REG].residual_jacobian, W[TRI_REG].rows = st.r_tri, st.Jr_tri, st.q
    if st.near_contact:  # the contact rows' margins widened by BAND (their rows at x once band_at_x)
        widen_margins(packed.blocks, packed.params, BAND, view(st.band_margins, st.band_params, np.float64))
    regularizer_rows(packed.blocks, r.first)
    cur, cur_r = W[CUR], W[CUR_REG]
    linearize(x, cur, TASK, YES, COMPUTE)
    linearize(x, cur_r, REGULARIZERS, YES, REUSE)
    st.evaluations = 1
    st.feasible = max(np.sqrt(squared_norm(views(cur).r, st.m)), 1e-13)
    st.G = level_value(cur_r, REGULARIZERS, YES)
    # norms shorter than the first trust radius: moved to, not past, zero
    objective_derivatives(cur_r, REGULARIZERS, smoothing, YES, TRUST_START, r.state, mv.g, mv.H, sys.gr, sys.Hr,
                          sys.mu_r)
    c = views(cur)
    ma = active_rows(c.J[: st.m], c.r, mult.lam, r.hinge, r.arow, r.Aa, False)
    rs = restoring(st)  # the start's multipliers: least squares A Aᵀ λ = A ∇G
    scatter_multipliers(r.Aa[:ma], mv.g, square(rs.A, ma), square(rs.L, ma), rs.y, mult.lam_a, r.arow, ma, mult.lam)
    st.fresh = 1  # g, H hold the derivatives at x
    st.mu, st.trust, st.last_step = MU_START, TRUST_START, 0.0


@internal
def _iteration(x, box, W, st, smoothing) -> int:
    """One Newton iteration: the active set, the step's system and its solution, the step along it. Returns a
    final status, or ``GO_ON``."""
    cur, cur_r = W[pick(W, st, CUR)], W[pick(W, st, CUR_REG)]
    r, mv, mult, sys = rows(st), moves(st), multipliers(st), system(st)
    if update_holds(views(cur).blocks, views(cur_r).r, r.first, r.state, mult.lam, st.m, r.target):
        st.fresh = 0  # G's derivatives without the held norms
    if st.fresh == 0:  # a norm shorter than the last step gets its majorizing curvature
        objective_derivatives(cur_r, REGULARIZERS, smoothing, YES, 2.0 * st.last_step, r.state, mv.g, mv.H, sys.gr,
                              sys.Hr, sys.mu_r)
        st.fresh = 1
    code = hold_rows(x, box, cur, cur_r, st)
    if code != GO_ON:
        return GO_ON if code == NEXT else code
    extra = build_system(cur, cur_r, st)
    code = solve_step(x, box, st)
    if code != GO_ON:
        return GO_ON if code == NEXT else code
    return take_step(x, box, W, st, extra)


@internal
def _finish(x, box, W, st, smoothing, multipliers_out, report) -> None:
    """The last restoring steps (to the last bit), the derivatives and multipliers at the result, its errors,
    values and counts."""
    r, mv, mult, sys, rs = rows(st), moves(st), multipliers(st), system(st), restoring(st)
    cur, cur_r = W[pick(W, st, CUR)], W[pick(W, st, CUR_REG)]
    m = st.m
    _, current = restore(x, box, cur, near_table(st), m, rs, RESTORE_STEPS, 0.0)
    if not current:
        linearize(x, cur, TASK, YES, JACOBIANS_FROM_POSES)
    linearize(x, cur_r, REGULARIZERS, YES, REUSE)
    objective_derivatives(cur_r, REGULARIZERS, smoothing, NO, 0.0, r.state, mv.g, mv.H, sys.gr, sys.Hr, sys.mu_r)
    c = views(cur)
    ma = active_rows(c.J[:m], c.r, mult.lam, r.hinge, r.arow, r.Aa, False)
    ma = held_rows(c.blocks, r.first, r.state, views(cur_r).J, m, r.arow, r.Aa, ma)  # held norms: out of ∇G
    scatter_multipliers(r.Aa[:ma], mv.g, square(rs.A, ma), square(rs.L, ma), rs.y, mult.lam_a, r.arow, ma, mult.lam)
    for a in range(m):
        multipliers_out[a] = mult.lam[a]
    task_errors(cur, report.errors)
    term_values(x, cur, report.values)
    report.stats[0], report.stats[1], report.stats[2] = st.iterations, st.evaluations, st.accepted
