"""The Newton phase's state: one record of its scalars and the addresses of its arrays, and views of them.

:func:`~framework.engine.regularize.regularize` keeps everything its steps share in one :data:`NEWTON` record
(laid out once by :func:`lay_out`) and passes it to its parts as one pointer; each part makes views of the arrays it
uses (:func:`multipliers`, :func:`rows`, :func:`moves`, :func:`system`, :func:`restoring`). Its workspaces are five
records (:func:`workspace`): the rows at ``x`` and at the trial point (which swap places after an accepted step),
their regularizer rows (the same poses, the regularizers' rows), and the contact rows with widened margins.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..costs.blocks import BLOCK
from ..compiled.native import internal, view
from .restore import RestoreScratch
from .tangent import tangent_scratch

i8, f8 = np.int64, np.float64
_BLOCK_SIZE = BLOCK.itemsize

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
#: A coordinate that a Newton step carries through its bound within this fraction of the step is held where it
#: is (near its bound) for that step.
PIN = 0.1
#: Backtracking without the blocking rows, a trial that enters a one-sided row clear at ``x`` is cut to that row's
#: boundary by its linearization (instead of halved), within these fractions of the trial step.
BOUNDARY_MIN, BOUNDARY_MAX = 0.05, 0.95
#: ``−δ`` on the diagonal of the held norms' rows in the step's system: a least-squares hold where they are
#: redundant with the task rows (far below any curvature of the problem); their right-hand side carries
#: ``δλ`` of the last multipliers (the proximal method of multipliers), so the hold is exact once they settle.
HELD_DAMPING = 1e-9
#: Status codes: converged, stalled (no step lowers ``G`` any more), out of time, out of iterations, not
#: applicable (no regularizer, or no freedom left); and, between the stages of an iteration, go on.
CONVERGED, STALLED, DEADLINE, ITERATIONS, NOT_APPLICABLE = 0, 1, 2, 3, 4
GO_ON, NEXT = -1, -2
#: The Newton phase's workspaces: at ``x`` and at the trial (swapping), their regularizer rows, the band rows.
CUR, TRI, CUR_REG, TRI_REG, BAND_ROWS = 0, 1, 2, 3, 4

#: The Newton phase's record: sizes, scalar state, the addresses of its arrays.
NEWTON = np.dtype([
    # sizes: coordinates, task rows, regularizer rows, both, blocks, the largest block, workspace rows, parameters
    ("n", i8), ("m", i8), ("q", i8), ("mq", i8), ("nb", i8), ("big", i8), ("ws_rows", i8), ("band_params", i8),
    # scalar state
    ("mu", f8), ("trust", f8), ("last_step", f8), ("G", f8), ("feasible", f8), ("model", f8),
    ("iterations", i8), ("accepted", i8), ("evaluations", i8), ("failed", i8), ("flip", i8),
    ("ma", i8), ("mr", i8), ("own_rows", i8), ("nf", i8),
    ("unblocked", i8), ("redundant", i8), ("fresh", i8), ("band_at_x", i8), ("near_contact", i8),
    # arrays
    ("lam", i8), ("lam_neg", i8), ("lam_a", i8), ("Jb", i8), ("cb", i8), ("sb", i8), ("target", i8), ("shift", i8),
    ("Jn", i8), ("r_cur", i8), ("r_tri", i8), ("Jr_cur", i8), ("Jr_tri", i8), ("g", i8), ("xt", i8), ("dx", i8),
    ("gl", i8), ("delta", i8), ("gs", i8), ("before", i8), ("dxm", i8), ("H", i8), ("Hlb", i8), ("Am", i8),
    ("Lm", i8), ("ym", i8), ("rhs", i8), ("sol", i8), ("gr", i8), ("mu_r", i8), ("Hr", i8), ("Jc", i8), ("Aa", i8),
    ("band_margins", i8), ("rn", i8), ("tangent", i8), ("K", i8), ("M", i8),
    ("fidx", i8), ("arow", i8), ("first", i8), ("held_now", i8), ("blocking", i8), ("pinned", i8), ("hinge", i8),
    ("contact", i8), ("state", i8), ("near", i8),
], align=True)


@internal
def lay_out(st, at) -> int:
    """The phase's arrays laid out from address ``at`` (the record's sizes set); returns the address after them
    (from 0: their size). The arrays the phase reads before it writes them come first (``Jr_cur`` to ``Jn``) and
    last (``held_now`` to ``state``): :func:`zero_state` zeroes them. Flags and small integers take a word each."""
    n, m, q, mq, nb, big = st.n, st.m, st.q, st.mq, st.nb, st.big
    rows, k = st.ws_rows, n + mq
    st.Jr_cur, at = at, at + 8 * q * n
    st.Jr_tri, at = at, at + 8 * q * n
    st.lam, at = at, at + 8 * mq
    st.lam_neg, at = at, at + 8 * mq
    st.lam_a, at = at, at + 8 * mq
    st.Jb, at = at, at + 8 * m * n
    st.cb, at = at, at + 8 * m
    st.sb, at = at, at + 8 * m
    st.target, at = at, at + 8 * q
    st.shift, at = at, at + 8 * n
    st.Jn, at = at, at + 8 * rows * n
    st.r_cur, at = at, at + 8 * q
    st.r_tri, at = at, at + 8 * q
    st.g, at = at, at + 8 * n
    st.xt, at = at, at + 8 * n
    st.dx, at = at, at + 8 * n
    st.gl, at = at, at + 8 * n
    st.delta, at = at, at + 8 * n
    st.gs, at = at, at + 8 * n
    st.before, at = at, at + 8 * n
    st.dxm, at = at, at + 8 * n
    st.H, at = at, at + 8 * n * n
    st.Hlb, at = at, at + 8 * n * n
    st.Am, at = at, at + 8 * mq * mq
    st.Lm, at = at, at + 8 * mq * mq
    st.ym, at = at, at + 8 * max(mq, n)
    st.rhs, at = at, at + 8 * k
    st.sol, at = at, at + 8 * k
    st.gr, at = at, at + 8 * big
    st.mu_r, at = at, at + 8 * big
    st.Hr, at = at, at + 8 * big * big
    st.Jc, at = at, at + 8 * m * n
    st.Aa, at = at, at + 8 * mq * n
    st.band_margins, at = at, at + 8 * st.band_params
    st.rn, at = at, at + 8 * rows
    st.tangent = at
    _, at = tangent_scratch(at, n, mq)
    st.K, at = at, at + 8 * k * k
    st.M, at = at, at + 8 * k * (k + 1)
    st.fidx, at = at, at + 8 * n
    st.arow, at = at, at + 8 * mq
    st.first, at = at, at + 8 * nb
    st.held_now, at = at, at + 8 * m
    st.blocking, at = at, at + 8 * m
    st.pinned, at = at, at + 8 * n
    st.hinge, at = at, at + 8 * m
    st.contact, at = at, at + 8 * m
    st.state, at = at, at + 8 * nb
    st.near, at = at, at + _BLOCK_SIZE * nb
    return at


@internal
def zero_state(st) -> None:
    """The arrays :func:`lay_out` lists first and last set to zero."""
    view(st.Jr_cur, (st.r_cur - st.Jr_cur) // 8, f8)[:] = 0.0
    view(st.held_now, (st.near - st.held_now) // 8, i8)[:] = 0


class Multipliers(NamedTuple):
    """``λ`` of the task rows then the held regularizer rows ``(m + q,)``, its negative, the active rows' ``(ma,)``."""

    lam: np.ndarray
    lam_neg: np.ndarray
    lam_a: np.ndarray


@internal
def multipliers(st) -> Multipliers:
    mq = st.mq
    return Multipliers(view(st.lam, mq, f8), view(st.lam_neg, mq, f8), view(st.lam_a, mq, f8))


class Rows(NamedTuple):
    """The active set: one-sided rows and contact rows among the task's, the rows held now, the blocking rows (their
    Jacobian at the trial ``Jb``, value at ``x`` ``cb``, violated side ``sb``), the active rows (``arow`` and their
    Jacobian rows ``Aa``), the regularizer blocks' first rows and states."""

    hinge: np.ndarray
    contact: np.ndarray
    held_now: np.ndarray
    blocking: np.ndarray
    Jb: np.ndarray
    cb: np.ndarray
    sb: np.ndarray
    arow: np.ndarray
    Aa: np.ndarray
    first: np.ndarray
    state: np.ndarray
    target: np.ndarray


@internal
def rows(st) -> Rows:
    n, m = st.n, st.m
    return Rows(view(st.hinge, m, np.bool_), view(st.contact, m, np.bool_), view(st.held_now, m, np.bool_),
                view(st.blocking, m, np.bool_), view(st.Jb, (m, n), f8), view(st.cb, m, f8), view(st.sb, m, f8),
                view(st.arow, st.mq, i8), view(st.Aa, (st.mq, n), f8), view(st.first, st.nb, i8),
                view(st.state, st.nb, np.int8), view(st.target, st.q, f8))


class Moves(NamedTuple):
    """The objective's gradient and Hessian, the Lagrangian's, the step and the trial point, the coordinates pinned
    at a bound and their moves onto it, the free coordinates."""

    g: np.ndarray
    H: np.ndarray
    Hlb: np.ndarray
    gl: np.ndarray
    gs: np.ndarray
    shift: np.ndarray
    pinned: np.ndarray
    fidx: np.ndarray
    xt: np.ndarray
    dx: np.ndarray
    delta: np.ndarray


@internal
def moves(st) -> Moves:
    n = st.n
    return Moves(view(st.g, n, f8), view(st.H, (n, n), f8), view(st.Hlb, (n, n), f8), view(st.gl, n, f8),
                 view(st.gs, n, f8), view(st.shift, n, f8), view(st.pinned, n, np.bool_), view(st.fidx, n, i8),
                 view(st.xt, n, f8), view(st.dx, n, f8), view(st.delta, n, f8))


class System(NamedTuple):
    """The step's KKT matrix (flat), the elimination's scratch (flat), its right-hand side and solution, the
    derivatives' scratch per block."""

    K: np.ndarray
    M: np.ndarray
    rhs: np.ndarray
    sol: np.ndarray
    gr: np.ndarray
    mu_r: np.ndarray
    Hr: np.ndarray


@internal
def system(st) -> System:
    k, big = st.n + st.mq, st.big
    return System(view(st.K, k * k, f8), view(st.M, k * (k + 1), f8), view(st.rhs, k, f8), view(st.sol, k, f8),
                  view(st.gr, big, f8), view(st.mu_r, big, f8), view(st.Hr, (big, big), f8))


@internal
def restoring(st) -> RestoreScratch:
    """The restoring steps' scratch (its matrices shared with the multipliers' least squares)."""
    mq, n = st.mq, st.n
    return RestoreScratch(view(st.Am, mq * mq, f8), view(st.Lm, mq * mq, f8), view(st.ym, max(mq, n), f8),
                          view(st.dxm, n, f8), view(st.Jc, st.m * n, f8), view(st.before, n, f8))


@internal
def near_table(st):
    """The restoring steps' block table (one-sided blocks clear at their start set aside)."""
    return view(st.near, st.nb, BLOCK)


@internal
def pick(W, st, which):
    """Index of the workspace ``which`` (``CUR``, ``TRI``, ``CUR_REG``, ``TRI_REG``) after the swaps so far."""
    if which == CUR or which == TRI:
        return which if st.flip == 0 else 1 - which
    return which if st.flip == 0 else 5 - which


@internal
def unblock(st) -> None:
    """The blocking rows let go: the backtracking goes on without them (cut at the boundaries they cross)."""
    rows(st).blocking[:] = False
    st.unblocked = 1
