"""The block table as the engine's phases read it: rows per level, one-sided rows, the tables they swap in."""

from __future__ import annotations

import numpy as np

from ..costs.blocks import CONTACT, HINGE, LEVEL_TASK, LEVEL_VALUE, in_level
from ..costs.kernels import rows_clear
from ..compiled.native import internal


@internal
def rows_of(blocks, level) -> int:
    """Residual rows of the blocks of ``level`` (``-1``: levels 1 and 2) in the block table ``blocks``."""
    rows = 0
    for b in range(blocks.shape[0]):
        if in_level(blocks[b].level, level):
            rows += blocks[b].rows
    return rows


@internal
def has_hinges(blocks) -> bool:
    """Whether the table has a one-sided task block (a distance band, a cone, a collision row)."""
    for b in range(blocks.shape[0]):
        if blocks[b].level == LEVEL_TASK and blocks[b].flags & HINGE:
            return True
    return False


@internal
def without_contacts(blocks):
    """The table with the collision blocks of the task taken out of it (level 0: no level selects them; a copy,
    or ``blocks`` itself when it has none), and whether there were any."""
    for b in range(blocks.shape[0]):
        if blocks[b].level == LEVEL_TASK and blocks[b].flags & CONTACT:
            lazy = blocks.copy()
            for c in range(b, blocks.shape[0]):
                if blocks[c].level == LEVEL_TASK and blocks[c].flags & CONTACT:
                    lazy[c].level = LEVEL_VALUE
            return lazy, True
    return blocks, False


@internal
def hinge_rows(blocks, m):
    """``(m,)`` True for the task rows of one-sided blocks (distances, cones, collision rows: zero when clear),
    and ``(m,)`` True for the contact rows among them (collision rows: signed distances above a margin)."""
    hinge, contact = np.zeros(m, dtype=np.bool_), np.zeros(m, dtype=np.bool_)
    row = 0
    for b in range(blocks.shape[0]):
        block = blocks[b]
        if block.level != LEVEL_TASK:
            continue
        for a in range(block.rows):
            hinge[row + a] = block.flags & HINGE != 0
            contact[row + a] = block.flags & CONTACT != 0
        row += block.rows
    return hinge, contact


@internal
def set_aside_clear(blocks, r, J, near) -> int:
    """``near``: the table ``blocks`` with the one-sided task blocks whose rows ``r`` are all zero (clear: no
    Jacobian either) set aside (level 0); their rows are dropped from the stacked ``r (m,)`` and ``J (m, n)`` in
    place, the others moved up in order, as :func:`~framework.costs.kernels.linearize` stacks ``near``'s task.
    Returns the rows kept."""
    row = kept = 0
    for b in range(blocks.shape[0]):
        near[b].level = blocks[b].level
        if blocks[b].level != LEVEL_TASK:
            continue
        rows = blocks[b].rows
        if blocks[b].flags & HINGE and rows_clear(r, row, rows):
            near[b].level = LEVEL_VALUE
        else:
            if kept != row:
                for c in range(rows):
                    r[kept + c] = r[row + c]
                    for i in range(J.shape[1]):
                        J[kept + c, i] = J[row + c, i]
            kept += rows
        row += rows
    return kept


@internal
def max_rows(blocks) -> int:
    """The most rows of one block (at least 1)."""
    rows = 1
    for b in range(blocks.shape[0]):
        rows = max(rows, blocks[b].rows)
    return rows
