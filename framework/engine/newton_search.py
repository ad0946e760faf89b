"""The Newton phase's search along its step (:mod:`~.regularize`): the step cut to the trust radius, the
backtracking with its restoring steps onto the task, and what follows an accepted or rejected step."""

from __future__ import annotations

from ..costs.kernels import COMPUTE, JACOBIANS_FROM_POSES, NO, REGULARIZERS, REUSE, TASK, YES, level_value, linearize
from ..costs.workspace import views
from ..compiled.native import internal
from .active_set import blocking_at_x, boundary_fraction, entered, moved
from .holds import kick_due, release_kicked
from .newton_state import (BAND_ROWS, BOUNDARY_MAX, BOUNDARY_MIN, CONVERGED, CUR, GO_ON, KINK_FAILURES, LINE_SEARCH,
                           MU_MAX, MU_MIN, RESTORE_STEPS, STALLED, TRI, TRI_REG, TRUST_MAX, moves, multipliers,
                           near_table, pick, restoring, rows, system, unblock)
from .restore import restore
from .steps import copy, project


@internal
def take_step(x, box, W, st, extra) -> int:
    """The step from the system's solution (the pinned coordinates' moves with it), cut to the trust radius and
    searched along; where it gains nothing, a kick, the blocking rows at ``x``, or convergence. Returns a final
    status or ``GO_ON``."""
    mv, sv = moves(st), system(st).sol
    n, nf = st.n, st.nf
    step = 0.0
    for i in range(n):
        mv.dx[i] = mv.shift[i]
        step = max(step, abs(mv.shift[i]))
    for a in range(nf):
        mv.dx[mv.fidx[a]] = sv[a]
        step = max(step, abs(sv[a]))
    predicted = 0.0  # first-order decrease of the Lagrangian along the step (within the trust region)
    for i in range(n):
        predicted -= mv.gl[i] * mv.dx[i]
    if st.model >= 0.0:  # a trust-region step: its model's decrease (negative curvature counts)
        predicted = st.model
    elif step > st.trust:  # along a flat direction of G (a norm along its own ray) Newton steps are unbounded
        predicted *= st.trust / step
    predicted += extra
    if step < 1e-12 or predicted < 1e-15 * (1.0 + abs(st.G)):  # no step, or below what G can resolve
        return no_step(x, W, st)
    if step > st.trust:
        for i in range(n):
            mv.dx[i] *= st.trust / step
        step = st.trust
    alpha, accepted, entering, Gt = line_search(x, box, W, st)
    return after_search(x, box, W, st, alpha * step, accepted, entering, Gt, alpha == 1.0)


@internal
def no_step(x, W, st) -> int:
    """A step that gains nothing: kick the held norms whose multipliers say leaving zero pays, or take the
    blocking rows' linearization at ``x`` once, or let them go; else converged. Returns a status or ``GO_ON``."""
    r, lam, sv = rows(st), multipliers(st).lam, system(st).sol
    nf, ma, mr, own_rows = st.nf, st.ma, st.mr, st.own_rows
    cur = W[pick(W, st, CUR)]
    if ma > mr:  # at rest with norms held at zero: kick those whose multipliers say leaving pays
        for a in range(mr, ma):
            lam[r.arow[a]] = -sv[nf + a]
        if kick_due(views(cur).blocks, r.first, r.state, lam, st.m):
            return GO_ON
    if mr > own_rows:  # stopped by the blocking rows (linearized at trial points)
        if st.near_contact and st.band_at_x == 0:  # once more with their linearization at x
            st.band_at_x = 1
            if band_rows_at_x(x, W, st):
                return GO_ON
        elif st.band_at_x:  # no step with them linearized at x: converged if each presses (its multiplier)
            pressing = True
            for c in range(own_rows, mr):
                pressing = pressing and -sv[nf + c] * r.sb[r.arow[c]] <= 0.0
            if pressing:
                return CONVERGED
        unblock(st)  # backtrack without them
        return GO_ON
    return CONVERGED


@internal
def band_rows_at_x(x, W, st) -> bool:
    """:func:`~.active_set.blocking_at_x` with the band workspace made from the one at ``x``."""
    r = rows(st)
    W[BAND_ROWS] = W[pick(W, st, CUR)]
    band = W[BAND_ROWS]
    band.residuals, band.residual_jacobian, band.params = st.rn, st.Jn, st.band_margins
    return blocking_at_x(x, band, r.contact, r.blocking, r.Jb, r.cb)


@internal
def line_search(x, box, W, st):
    """Backtracking along the step (halved, or cut at the boundary of a one-sided row it enters once the blocking
    rows are let go): each trial restored onto the task, kept where it is no further from the task than ``x`` was
    and lowers ``G``. Returns ``(alpha, accepted, entered a one-sided row, G at the last trial)``."""
    r, mv, rs = rows(st), moves(st), restoring(st)
    cur, tri, tri_r = W[pick(W, st, CUR)], W[pick(W, st, TRI)], W[pick(W, st, TRI_REG)]
    near, m, n = near_table(st), st.m, st.n
    alpha, Gt, entering = 1.0, st.G, False
    for _ in range(LINE_SEARCH):  # backtrack along the Newton direction before damping it
        for i in range(n):
            mv.xt[i] = x[i] + alpha * mv.dx[i]
        project(mv.xt, box)
        if st.near_contact:  # the frame Jacobians only of the rows not clear at the trial (contact rows: most are)
            linearize(mv.xt, tri, TASK, NO, COMPUTE)
            linearize(mv.xt, tri, TASK, YES, JACOBIANS_FROM_POSES)
        else:
            linearize(mv.xt, tri, TASK, YES, COMPUTE)
        c, t = views(cur), views(tri)
        entering = st.unblocked == 0 and entered(x, mv.xt, box.wraps, r.hinge, c.r, r.held_now, t.r, t.J, mv.delta,
                                                 r.Jb, r.cb, r.sb)
        # backtracking without the blocking rows: to the boundary of the first row the trial entered
        tau = boundary_fraction(x, mv.xt, box.wraps, r.hinge, c.r, r.held_now, t.r, t.J, mv.delta) \
            if st.unblocked else 1.0
        e, current = restore(mv.xt, box, tri, near, m, rs, RESTORE_STEPS, st.feasible)
        linearize(mv.xt, tri_r, REGULARIZERS, current, REUSE)
        st.evaluations += 1
        Gt = level_value(tri_r, REGULARIZERS, YES)
        if e <= st.feasible and Gt < st.G:
            if not current:  # the Jacobians at the step taken (a rejected trial needs none)
                linearize(mv.xt, tri, TASK, YES, JACOBIANS_FROM_POSES)
                linearize(mv.xt, tri_r, REGULARIZERS, YES, REUSE)
            return alpha, True, entering, Gt
        if entering:  # the step entered one-sided rows clear at x: solve it again holding them
            break
        alpha *= 0.5 if tau >= 1.0 else min(max(tau, BOUNDARY_MIN), BOUNDARY_MAX)
    return alpha, False, entering, Gt


@internal
def after_search(x, box, W, st, length, accepted, entering, Gt, full) -> int:
    """After the line search: an accepted step moves ``x`` there (multipliers, damping and trust radius updated;
    converged where it gains nothing); a rejected one makes the rows it entered blocking rows, or lets the blocking
    rows go, or shrinks the trust radius. Returns a final status or ``GO_ON``."""
    r, mv, lam, sv = rows(st), moves(st), multipliers(st).lam, system(st).sol
    if accepted:
        gain = st.G - Gt
        st.flip = 1 - st.flip  # the trial's workspaces become x's
        moved(x, mv.xt, box.wraps, r.blocking, r.Jb, r.cb, mv.delta)
        copy(x, mv.xt)
        st.unblocked, st.band_at_x, st.failed = 0, 0, 0
        mv.pinned[:] = False
        mv.shift[:] = 0.0
        st.G = Gt
        lam[:] = 0.0
        for a in range(st.ma):
            lam[r.arow[a]] = -sv[st.nf + a]
        st.accepted += 1
        st.fresh = 0
        st.last_step = length
        if release_kicked(r.state):  # off zero along its multiplier: free from here (no majorizing curvature)
            st.last_step = 0.0
        if full:
            st.mu = max(st.mu * 0.1, MU_MIN)
            st.trust = min(2.0 * st.trust, TRUST_MAX)
        else:
            st.trust = max(length, 1e-12)
        if (length < 1e-10 or gain <= 1e-16 * (1.0 + abs(st.G))) and \
                not kick_due(views(W[pick(W, st, CUR)]).blocks, r.first, r.state, lam, st.m):
            return CONVERGED  # (a held norm whose multiplier says leaving zero pays: kicked next)
        return GO_ON
    if entering:
        for a in range(st.m):  # the candidates written by entered() become blocking rows
            if not r.held_now[a] and r.sb[a] != 0.0:
                r.blocking[a] = True
        return GO_ON
    if st.mr > st.own_rows:  # no step along the blocking rows (linearized at trial points): once more with their
        if st.near_contact and st.band_at_x == 0:  # linearization at x, then backtrack without them
            st.band_at_x = 1
            if band_rows_at_x(x, W, st):
                return GO_ON
        unblock(st)
        return GO_ON
    st.trust *= 0.1
    st.mu *= 10.0
    st.failed += 1
    kinked = False
    for c in range(st.mr):
        kinked = kinked or r.hinge[r.arow[c]]
    if st.mu > MU_MAX or st.trust < 1e-12 or (kinked and st.failed >= KINK_FAILURES):
        return STALLED
    return GO_ON
