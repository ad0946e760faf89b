"""The Newton phase's step system (:mod:`~.regularize`): the rows it holds (the task's own, the blocking rows, the
held regularizers), the Lagrangian's gradient and Hessian, the KKT system over the free coordinates, and its
solution (the trust-region step where the Newton step is no minimum within the radius)."""

from __future__ import annotations

import numpy as np

from ..costs.blocks import LEVEL_TASK
from ..costs.workspace import views
from ..compiled.native import internal, matrix, square
from .active_set import active_rows
from .derivatives import KICKED, add_curvature, is_held
from .holds import held_rows, moving_rows, release_holds
from .linalg import lu_solve
from .newton_state import (CONVERGED, GO_ON, HELD_DAMPING, MU_MAX, NEXT, PIN, STALLED, moves, multipliers, rows, system,
                           unblock)
from .steps import held, squared_norm
from .tangent import tangent_step


@internal
def hold_rows(x, box, cur, cur_r, st) -> int:
    """The rows held in the step (the task's own, the blocking rows, the held regularizers), the multipliers of the
    others cleared, the Lagrangian's gradient, the free coordinates. Returns ``GO_ON``, ``NEXT`` (the active set
    changed: next iteration) or ``CONVERGED``."""
    r, mv, lam = rows(st), moves(st), multipliers(st).lam
    c, m, n = views(cur), st.m, st.n
    ma = active_rows(c.J[:m], c.r, lam, r.hinge, r.arow, r.Aa, True)
    st.own_rows = ma  # rows held with their own Jacobian at x; the blocking rows follow them
    r.held_now[:] = False
    for k in range(ma):
        r.held_now[r.arow[k]] = True
    for a in range(m):
        if not r.blocking[a]:
            continue
        if r.held_now[a] or lam[a] * r.sb[a] > 0.0:  # active at x, or its multiplier pulls to its free side
            r.blocking[a] = False
            continue
        r.arow[ma] = a
        for i in range(n):
            r.Aa[ma, i] = r.Jb[a, i]
        r.held_now[a] = True
        ma += 1
    st.mr = ma  # the task's rows (own and blocking); the held regularizers' rows follow them
    ma = held_rows(c.blocks, r.first, r.state, views(cur_r).J, m, r.arow, r.Aa, ma)
    clear_multipliers(st, c.blocks, lam, r)
    for i in range(n):  # gl = ∇G − Aᵀλ, the Lagrangian's gradient
        s = mv.g[i]
        for a in range(ma):
            s -= r.Aa[a, i] * lam[r.arow[a]]
        mv.gl[i] = s
    nf = 0
    for i in range(n):  # the coordinates descent along −gl does not push through a bound
        if not mv.pinned[i] and not held(x[i], box.lower[i], box.upper[i], box.wraps[i], -mv.gl[i]):
            mv.fidx[nf] = i
            nf += 1
    st.nf = nf
    st.ma = moving_rows(r.Aa, r.arow, mv.fidx, nf, st.mr, ma)
    if nf > st.mr:  # (held norms may be redundant with the task: their rows are solved in least squares)
        return GO_ON
    if st.ma > st.mr:  # no freedom left with the held regularizers: let them go
        release_holds(r.state)
        st.fresh = 0
        return NEXT
    if st.ma > st.own_rows:  # held by the blocking rows (linearized at trial points): backtrack without them
        unblock(st)
        return NEXT
    return CONVERGED


@internal
def clear_multipliers(st, blocks, lam, r) -> None:
    """Released and clear rows carry no multiplier (the task's not held now, the regularizers' not held)."""
    m = st.m
    for a in range(m):
        if not r.held_now[a]:
            lam[a] = 0.0
    for b in range(st.nb):
        if r.first[b] >= 0 and not is_held(r.state[b]):
            for k in range(blocks[b].rows):
                lam[m + r.first[b] + k] = 0.0


@internal
def build_system(cur, cur_r, st) -> float:
    """The step's KKT system over the free coordinates and the active rows into ``K``, ``rhs``; returns what the
    step gains on the held norms (out of the gradient: taken to zero), or ``inf`` for a kick."""
    r, mv, lam, sys = rows(st), moves(st), multipliers(st), system(st)
    extra = lagrangian_hessian(cur, cur_r, st, r, mv, lam)
    n, nf, ma, mr, own_rows = st.n, st.nf, st.ma, st.mr, st.own_rows
    for i in range(n):  # the pinned coordinates' moves onto their bounds, seen by the others
        s = mv.g[i]
        for j in range(n):
            if mv.shift[j] != 0.0:
                s += mv.Hlb[i, j] * mv.shift[j]
        mv.gs[i] = s
    k = nf + ma
    K, rv = square(sys.K, k), sys.rhs[:k]  # contiguous: the LU's loops vectorize
    for a in range(nf):
        i = mv.fidx[a]
        for c in range(nf):
            K[a, c] = mv.Hlb[i, mv.fidx[c]]
        K[a, a] += st.mu
        for c in range(ma):
            K[a, nf + c] = r.Aa[c, i]
            K[nf + c, a] = r.Aa[c, i]
        rv[a] = -mv.gs[i]
    c_r, reg_r = views(cur).r, views(cur_r).r
    for a in range(ma):
        for c in range(ma):
            K[nf + a, nf + c] = 0.0
        if a >= mr or (st.redundant and a < own_rows):  # a held norm's rows, regularized: with the task they may
            K[nf + a, nf + a] = -HELD_DAMPING  # be redundant (a joint group at rest leaves the rest of the task to
        if a < own_rows:  # fewer coordinates); the task's own rows too once they were found dependent
            rv[nf + a] = -c_r[r.arow[a]]
            if st.redundant:  # (+ δλ, as the held norms: exactly on the rows once λ settles)
                rv[nf + a] += HELD_DAMPING * lam.lam[r.arow[a]]
        elif a < mr:
            rv[nf + a] = -r.cb[r.arow[a]]
        else:  # a held norm to zero, a kicked one to its aim (+ δλ: exactly there once λ settles)
            row = r.arow[a] - st.m
            rv[nf + a] = r.target[row] - reg_r[row] + HELD_DAMPING * lam.lam[r.arow[a]]
        for j in range(n):
            if mv.shift[j] != 0.0:
                rv[nf + a] -= r.Aa[a, j] * mv.shift[j]
    return extra


@internal
def lagrangian_hessian(cur, cur_r, st, r, mv, lam) -> float:
    """``Hlb = H − Σ λ_b ∇²r_b`` over the task blocks with a multiplier and the held regularizers (their kinds'
    curvature); returns the held norms' gain (see :func:`system`)."""
    n = st.n
    for i in range(n):
        for j in range(n):
            mv.Hlb[i, j] = mv.H[i, j]
    blocks = views(cur).blocks
    row = 0
    for b in range(st.nb):
        if blocks[b].level != LEVEL_TASK:
            continue
        rows_b = blocks[b].rows
        held_rows_b = False
        for a in range(rows_b):
            lam.lam_neg[row + a] = -lam.lam[row + a]
            held_rows_b = held_rows_b or lam.lam[row + a] != 0.0
        if held_rows_b:  # a clear or released row has no multiplier and adds no curvature
            add_curvature(cur, b, row, lam.lam_neg[row:], mv.Hlb)
        row += rows_b
    extra = 0.0
    reg_r = views(cur_r).r
    for b in range(st.nb):
        if not is_held(r.state[b]):
            continue
        f = r.first[b]
        for c in range(blocks[b].rows):
            lam.lam_neg[st.m + f + c] = -lam.lam[st.m + f + c]
        add_curvature(cur_r, b, f, lam.lam_neg[st.m + f:], mv.Hlb)
        extra += np.inf if r.state[b] == KICKED else \
            blocks[b].weight * blocks[b].scale * np.sqrt(squared_norm(reg_r[f:], blocks[b].rows))
    return extra


@internal
def solve_step(x, box, st) -> int:
    """The step's system solved (the trust-region step where the Newton step is no minimum within the trust
    radius), the coordinates it carries through a bound within its first tenth pinned there. Returns ``GO_ON``,
    ``NEXT`` (a coordinate was pinned: the step solved again) or ``STALLED``."""
    sys, mv = system(st), moves(st)
    nf, ma = st.nf, st.ma
    k = nf + ma
    K, M, rv, sv = square(sys.K, k), matrix(sys.M, k, k + 1), sys.rhs[:k], sys.sol[:k]
    if not lu_solve(K, rv, M, sv):
        if st.mr > st.own_rows:  # the blocking rows' Jacobians (from trial points) made it singular: let them go,
            unblock(st)  # and backtrack without them until a step is taken
            return NEXT
        if st.redundant == 0 and st.own_rows > 0:  # the task's rows are dependent (two contact rows along one
            st.redundant = 1  # direction): held in least squares from here on (damping H cannot help)
            return NEXT
        st.mu *= 10.0
        return STALLED if st.mu > MU_MAX else NEXT
    st.model = tangent_step(K, rv, nf, ma, st.trust, sv, st.tangent, st.n, st.mq)
    pushed = False
    for a in range(nf):  # a coordinate the step carries through its bound within its first tenth: moved onto the
        i = mv.fidx[a]  # bound, and the step solved again (clipped, the step would leave the task)
        if not box.wraps[i] and ((sv[a] > 0.0 and box.upper[i] - x[i] < PIN * sv[a]) or
                                 (sv[a] < 0.0 and x[i] - box.lower[i] < -PIN * sv[a])):
            mv.pinned[i] = pushed = True
            mv.shift[i] = (box.upper[i] if sv[a] > 0.0 else box.lower[i]) - x[i]
    return NEXT if pushed else GO_ON
