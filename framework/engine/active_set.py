"""The Newton phase's active set of task rows: rows held as equalities, one-sided rows a step enters (*blocking*
rows, held with their linearization at the trial), where a trial crosses a row's boundary."""

from __future__ import annotations

from ..costs.kernels import JACOBIANS_FROM_POSES, NO, REUSE, TASK, YES, linearize
from ..costs.lie import wrap_angle
from ..costs.workspace import views
from ..compiled.native import internal

#: Blocking contact rows that stop a step are linearized again at ``x`` when their gap there is below this [m]
#: (the gap and the closest pair's Jacobian: :func:`~framework.costs.kernels.widen_margins`); the others are let go.
BAND = 1e-3


@internal
def active_rows(A, r, lam, hinge, arow, Aa, release) -> int:
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


@internal
def step_taken(x, xt, wraps, delta) -> None:
    """``delta = xt − x (n,)``, the wrapping coordinates' differences taken the short way round."""
    for i in range(x.shape[0]):
        d = xt[i] - x[i]
        delta[i] = wrap_angle(d) if wraps[i] else d


@internal
def value_at_start(r, J, delta, a) -> float:
    """Row ``a``'s value at the step's start by its linearization at the trial: ``r_a − J_a · delta``
    (``delta``: the step, :func:`step_taken`)."""
    c = r[a]
    for i in range(delta.shape[0]):
        c -= J[a, i] * delta[i]
    return c


@internal
def entered(x, xt, wraps, hinge, r_x, held_now, r, J, delta, Jb, cb, sb) -> bool:
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
    step_taken(x, xt, wraps, delta)
    c = value_at_start(r, J, delta, pick)
    for i in range(x.shape[0]):
        Jb[pick, i] = J[pick, i]
    sb[pick] = 1.0 if r[pick] > 0.0 else -1.0
    cb[pick] = c if c * sb[pick] < 0.0 else 0.0
    return True


@internal
def boundary_fraction(x, xt, wraps, hinge, r_x, held_now, r, J, delta) -> float:
    """The fraction of the step ``x -> xt`` at which the first one-sided row clear at ``x`` (not held) that ``xt``
    violates reaches its boundary, by each such row's linearization at ``xt`` (``delta (n,)`` scratch); ``1`` when
    none is violated, or none is clear at ``x`` by its linearization."""
    step_taken(x, xt, wraps, delta)
    tau = 1.0
    for a in range(hinge.shape[0]):
        if held_now[a] or not hinge[a] or r_x[a] != 0.0 or r[a] == 0.0:
            continue
        c = value_at_start(r, J, delta, a)
        if c * r[a] < 0.0:  # the row's zero lies on the step
            tau = min(tau, c / (c - r[a]))
    return tau


@internal
def blocking_at_x(x, band, contact, blocking, Jb, cb) -> bool:
    """The blocking rows linearized at ``x`` instead of at the trials they came from: the contact rows evaluated
    with their margins widened by :data:`BAND` (``band``: a workspace whose parameters are those, poses reused:
    at ``x``), each blocking row within the band held at its boundary by that linearization (``Jb``, ``cb``), the
    others let go. Returns whether a blocking row is kept."""
    linearize(x, band, TASK, NO, REUSE)
    linearize(x, band, TASK, YES, JACOBIANS_FROM_POSES)
    v = views(band)
    kept = False
    for a in range(blocking.shape[0]):
        if blocking[a]:
            if contact[a] and v.r[a] < 0.0:
                cb[a] = v.r[a] + BAND
                for i in range(x.shape[0]):
                    Jb[a, i] = v.J[a, i]
                kept = True
            else:
                blocking[a] = False
    return kept


@internal
def moved(x, xt, wraps, blocking, Jb, cb, delta) -> None:
    """The blocking rows' linearized values carried from ``x`` to the accepted ``xt``."""
    step_taken(x, xt, wraps, delta)
    for a in range(blocking.shape[0]):
        if blocking[a]:
            for i in range(x.shape[0]):
                cb[a] += Jb[a, i] * delta[i]
