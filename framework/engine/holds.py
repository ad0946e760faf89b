"""Norm regularizers at their kink: a joint group at rest, held at zero as constraints of the Newton phase.

A norm regularizer (``ρ = s‖r‖``) shorter than :data:`HOLD_BELOW` is held at zero as equality rows (out of ``G``'s
derivatives) while its multiplier stays within the norm's slope ``w s`` (the subgradient condition of an optimum
at zero), else moved off zero against the multiplier (*kicked*) and left free.
"""

from __future__ import annotations

import numpy as np

from ..costs.blocks import LEVEL_REGULARIZER, NORM
from ..compiled.native import internal
from .derivatives import FREE, HELD, KICKED, RELEASED, is_held
from .steps import squared_norm

#: A norm regularizer shorter than this [its residual's unit: rad or m] is held at zero as a constraint of the
#: Newton phase (its kink: smoothed, Newton steps stall there with the norm at ~1e-7).
HOLD_BELOW = 1e-5
#: How far a held norm is moved off zero, against its multiplier, when the multiplier says leaving zero pays.
KICK = 1e-5


@internal
def regularizer_rows(blocks, first) -> None:
    """``first[b]``: block ``b``'s first row among the regularizer rows (``-1``: not a regularizer)."""
    row = 0
    for b in range(blocks.shape[0]):
        first[b] = -1
        if blocks[b].level == LEVEL_REGULARIZER:
            first[b] = row
            row += blocks[b].rows


@internal
def leaving_pays(blocks, b, lam, start) -> float:
    """The norm of block ``b``'s multipliers ``lam[start:start + rows]`` when it exceeds the norm's slope ``w s``
    (held at zero, the block then lowers the sum by leaving it: the subgradient condition fails), else 0."""
    norm = np.sqrt(squared_norm(lam[start:], blocks[b].rows))
    return norm if norm > blocks[b].weight * blocks[b].scale * (1.0 + 1e-9) else 0.0


@internal
def update_holds(blocks, r_reg, first, state, lam, m, target) -> bool:
    """Hold the free norm regularizers shorter than :data:`HOLD_BELOW` at zero, and kick the held ones whose
    multipliers ``lam[m + row]`` exceed the norm's slope (:func:`leaving_pays`: moved :data:`KICK` against the
    multiplier, ``target``). Returns whether a state changed."""
    changed = False
    for b in range(blocks.shape[0]):
        f = first[b]
        if f < 0 or blocks[b].rho != NORM:
            continue
        rows = blocks[b].rows
        if state[b] == FREE and np.sqrt(squared_norm(r_reg[f:], rows)) < HOLD_BELOW:
            state[b] = HELD
            changed = True
            for c in range(rows):
                lam[m + f + c], target[f + c] = 0.0, 0.0
        elif state[b] == HELD:
            norm = leaving_pays(blocks, b, lam, m + f)
            if norm > 0.0:
                state[b] = KICKED
                changed = True
                for c in range(rows):
                    target[f + c] = -KICK * lam[m + f + c] / norm
    return changed


@internal
def release_holds(state) -> None:
    """Every held or kicked regularizer released (for the rest of the phase)."""
    for b in range(state.shape[0]):
        if is_held(state[b]):
            state[b] = RELEASED


@internal
def held_rows(blocks, first, state, J_reg, m, arow, Aa, ma) -> int:
    """The held and kicked regularizers' rows appended to the active rows (``arow`` entries ``m + row``, their
    Jacobian rows into ``Aa`` from ``ma`` on); returns the new count."""
    n = Aa.shape[1]
    for b in range(blocks.shape[0]):
        if not is_held(state[b]):
            continue
        f = first[b]
        for c in range(blocks[b].rows):
            arow[ma] = m + f + c
            for i in range(n):
                Aa[ma, i] = J_reg[f + c, i]
            ma += 1
    return ma


@internal
def moving_rows(Aa, arow, fidx, nf, mr, ma) -> int:
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
                for i in range(Aa.shape[1]):
                    Aa[k, i] = Aa[a, i]
            k += 1
    return k


@internal
def kick_due(blocks, first, state, lam, m) -> bool:
    """Whether a held regularizer's multiplier ``lam[m + row]`` says leaving zero pays (:func:`leaving_pays`)."""
    for b in range(state.shape[0]):
        if state[b] == HELD and leaving_pays(blocks, b, lam, m + first[b]) > 0.0:
            return True
    return False


@internal
def release_kicked(state) -> bool:
    """Every kicked regularizer released (off zero along its multiplier: free from here); returns whether one
    was."""
    any_kicked = False
    for b in range(state.shape[0]):
        if state[b] == KICKED:
            state[b] = RELEASED
            any_kicked = True
    return any_kicked
