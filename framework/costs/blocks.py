"""Residual blocks as the compiled code reads them: the block table, a problem's packed arrays, and ρ.

A term is one or more *blocks*. A block is a residual ``r(x)`` (a few rows) with its Jacobian ``dr/dx`` from the
frame Jacobians, its second-order part (for the Newton steps of the engine), and a *ρ* that turns the residual into
the term's value (``‖r‖``, ``sin(‖r‖/2)``, ``Σ|r|``, ``‖r‖²``, times a scale). The term's value is the sum of its
blocks' ρ. What a block computes is its *kind* (:class:`~framework.costs.kinds.BlockKind`: a position, an
orientation, a collision row, ...), defined with its term in the term's module; the table below says how a block
is laid out and addressed, the same for every kind.

The block table is an array of :data:`BLOCK` records, one per block, in the order the objective lists them:

===============  ==============================================================================================
field            meaning
===============  ==============================================================================================
``level``        0 value only, 1 task (reached first), 2 regularizer (minimized on the task)
``rows``         residual rows
``rho``          how the residual becomes the value (:data:`NORM`, :data:`HALFSIN`, :data:`L1`, :data:`SQUARED`)
``tolerance``    which tolerance the task block's error ``‖r‖`` is held to (:data:`TOL_LINEAR` [m], ...)
``flags``        what the engine may rely on (:data:`HINGE`, :data:`CONTACT`, :data:`UNIT_ROWS`, ...)
``fa``, ``fb``   the frames it reads (slots in the problem's frame list; ``-1``: none)
``params``       where its parameters start in the problem's parameter vector
``indices``      where its integer list starts (coordinates, or frame slots), ``count`` its length
``term``         the term it belongs to (objective order)
``residual``     the address of its kind's compiled residual kernel
``curvature``    the address of its kind's curvature kernel (0: none, Gauss-Newton curvature)
``margin``       its margin's place among its parameters (contact rows; ``-1``: none)
``weight``       its term's weight; ``scale`` the factor of ρ
===============  ==============================================================================================
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..compiled.native import internal
from ..compiled.trig import sincos

# ρ kinds: how the residual becomes the value
NORM, HALFSIN, L1, SQUARED = 0, 1, 2, 3
# Tolerance classes: which tolerance a task block's error ‖r‖ is held to
TOL_NONE, TOL_LINEAR, TOL_ANGULAR = 0, 1, 2
# Levels: 0 value only (penalties the box already enforces), 1 task (reached first), 2 regularizer (minimized on the task)
LEVEL_VALUE, LEVEL_TASK, LEVEL_REGULARIZER = 0, 1, 2
#: Flags: one-sided (zero residual and Jacobian inside its allowed set: an inequality).
HINGE = 1
#: A collision row: a signed distance held above a margin (one-sided too).
CONTACT = 2
#: Each row is ``x[i] − c`` for a coordinate ``i`` of the block's indices: its Jacobian rows are unit vectors.
UNIT_ROWS = 4
#: The block's indices are frame slots (a block that reads more frames than ``fa`` and ``fb``).
FRAME_INDICES = 8

i8, f8 = np.int64, np.float64
#: One block of the table (see the module docstring).
BLOCK = np.dtype([("level", i8), ("rows", i8), ("rho", i8), ("tolerance", i8), ("flags", i8), ("fa", i8),
                  ("fb", i8), ("params", i8), ("indices", i8), ("count", i8), ("term", i8), ("residual", i8),
                  ("curvature", i8), ("margin", i8), ("weight", f8), ("scale", f8)], align=True)


class Packed(NamedTuple):
    """A problem's arrays, as the compiled code reads them (see :class:`~framework.costs.program.Program`).

    Attributes:
        joints: ``int64 (J, 5)`` the visited joints of the population kinematics (:mod:`framework.model.kinematics`).
        joint_geometry: ``(J, 17)`` their placements and axes.
        frame_joints: ``int64 (k,)`` each frame's joint slot; frame_geometry: ``(k, 12)`` its placement there.
        chain_ptr, chain_idx: the coordinates moving each frame, CSR (``int64 (k + 1,)``, ``int64 (c,)``).
        blocks: ``(B,)`` the block table (:data:`BLOCK` records).
        params: ``(P,)`` the blocks' parameters (targets, offsets, sphere covers, ...).
        indices: ``int64 (I,)`` the blocks' integer lists.
        wraps: ``bool (n,)`` the coordinates that are angles without end stops (their differences wrap).
        scratch: ``int64 (1,)`` the scratch entries the blocks' kernels need at most.
    """

    joints: np.ndarray
    joint_geometry: np.ndarray
    frame_joints: np.ndarray
    frame_geometry: np.ndarray
    chain_ptr: np.ndarray
    chain_idx: np.ndarray
    blocks: np.ndarray
    params: np.ndarray
    indices: np.ndarray
    wraps: np.ndarray
    scratch: np.ndarray


@internal(inline=True)
def in_level(block_level, level) -> bool:
    """Whether a block of ``block_level`` is selected by ``level`` (``< 0``: the task and the regularizers)."""
    return block_level == level if level >= 0 else block_level != LEVEL_VALUE


@internal(inline=True)
def rho_value(rho, scale, r, row, rows) -> float:
    """The value of a block from its residual ``r[row:row + rows]``."""
    if rho == L1:
        s = 0.0
        for c in range(rows):
            s += abs(r[row + c])
        return scale * s
    s = 0.0
    for c in range(rows):
        s += r[row + c] * r[row + c]
    if rho == SQUARED:
        return scale * s
    norm = np.sqrt(s)
    if rho == HALFSIN:
        return scale * sincos(0.5 * min(norm, np.pi))[0]
    return scale * norm


@internal
def rho_derivatives(rho, scale, r, row, rows, smoothing, g, H, majorize_below) -> None:
    """Gradient ``g (rows,)`` and Hessian ``H (rows, rows)`` of the block value with respect to its residual.

    The norm-like ρ are not differentiable at ``r = 0``; there they are smoothed as ``√(‖r‖² + ε²)`` (``|r|`` per
    component for L1) with ``ε = smoothing``, which changes the value by at most ``scale · ε`` per block.
    A norm shorter than ``majorize_below`` gets the majorizing curvature ``scale/‖r‖ · I`` instead of its own
    ``scale/‖r‖ · (I − uuᵀ)`` (flat along ``u``): a Newton step then moves it straight to (not past) zero, where
    an optimum with a joint group at rest sits.
    """
    for a in range(rows):
        for c in range(rows):
            H[a, c] = 0.0
    if rho == SQUARED:
        for a in range(rows):
            g[a] = 2.0 * scale * r[row + a]
            H[a, a] = 2.0 * scale
        return
    if rho == L1:
        e2 = smoothing * smoothing
        for a in range(rows):
            v = r[row + a]
            d = np.sqrt(v * v + e2)
            g[a] = scale * v / d
            H[a, a] = scale * e2 / (d * d * d)
        return
    s = 0.0
    for a in range(rows):
        s += r[row + a] * r[row + a]
    if rho == NORM:
        d = np.sqrt(s + smoothing * smoothing)
        radial = 0.0 if d < majorize_below else 1.0
        for a in range(rows):
            g[a] = scale * r[row + a] / d
            for c in range(rows):
                H[a, c] = -radial * scale * r[row + a] * r[row + c] / (d * d * d)
            H[a, a] += scale / d
        return
    # HALFSIN: ρ = s sin(φ/2), φ = ‖r‖ (smoothed): ∇ρ = ½ s cos(φ/2) u, ∇²ρ = s[½cos(φ/2)/φ (I − uuᵀ) − ¼ sin(φ/2) uuᵀ]
    phi = np.sqrt(s + smoothing * smoothing)
    sh, ch = sincos(0.5 * phi)
    c1, c2 = 0.5 * scale * ch, 0.25 * scale * sh
    for a in range(rows):
        ua = r[row + a] / phi
        g[a] = c1 * ua
        for c in range(rows):
            uc = r[row + c] / phi
            H[a, c] = -(c1 / phi + c2) * ua * uc
        H[a, a] += c1 / phi
