"""The workspace: what a compiled evaluation of a problem's blocks at one configuration reads and writes.

A workspace is one :data:`WORKSPACE` record holding the addresses and sizes of a problem's packed arrays
(:class:`~framework.costs.blocks.Packed`), of the configuration it is evaluated at, and of its scratch: the frames'
poses ``(k, 12)``, the joints' placements ``(J, 12)``, the frames' Jacobians ``(k, 6, n)``, the stacked residual
rows ``r (rows,)`` and their Jacobian ``J (rows, n)``, the kernels' scratch, and which frames need a Jacobian.
The compiled functions pass it as one pointer and make views of its arrays where they use them (:func:`views`).
A block kind's kernel is called with a workspace whose *call* fields name the block (``block``), its first row
(``row``), what to compute (``mode``: :data:`RESIDUAL`, :data:`LINEARIZE` or :data:`JACOBIAN_ONLY`) and, for a
curvature kernel, its rows' multipliers and the Hessian to add to.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..compiled.native import address_of, internal, view
from .blocks import BLOCK

i8 = np.int64
#: The workspace record (addresses are int64; see the module docstring).
WORKSPACE = np.dtype([
    # sizes
    ("n", i8), ("frames", i8), ("joint_count", i8), ("block_count", i8), ("param_count", i8), ("index_count", i8),
    ("chain_count", i8), ("rows", i8), ("scratch_size", i8),
    # the problem's arrays
    ("joints", i8), ("joint_geometry", i8), ("frame_joints", i8), ("frame_geometry", i8), ("chain_ptr", i8),
    ("chain_idx", i8), ("blocks", i8), ("params", i8), ("indices", i8), ("wraps", i8),
    # the configuration and what is computed at it
    ("x", i8), ("poses", i8), ("placements", i8), ("jacobians", i8), ("residuals", i8), ("residual_jacobian", i8),
    ("scratch", i8), ("need", i8),
    # one kernel call
    ("block", i8), ("row", i8), ("mode", i8), ("multipliers", i8), ("hessian", i8),
], align=True)

#: Kernel modes: the residual rows; the rows and their Jacobian; the Jacobian of rows already evaluated at these
#: poses (a kernel may compute it from them, or evaluate the block again).
RESIDUAL, LINEARIZE, JACOBIAN_ONLY = 0, 1, 2


class Views(NamedTuple):
    """A workspace's arrays (views without owners) as a kernel reads them."""

    x: np.ndarray  # (n,) the configuration
    poses: np.ndarray  # (k, 12) frame poses: rotation row-major, then position
    jacobians: np.ndarray  # (k, 6, n) frame Jacobians: linear rows 0-2, angular 3-5 (world-aligned)
    blocks: np.ndarray  # (B,) the block table
    params: np.ndarray  # (P,) the blocks' parameters
    indices: np.ndarray  # (I,) the blocks' integer lists
    wraps: np.ndarray  # (n,) bool: coordinates whose differences wrap
    r: np.ndarray  # (rows,) the stacked residual rows
    J: np.ndarray  # (rows, n) their Jacobian
    scratch: np.ndarray  # the kernels' scratch
    chain_ptr: np.ndarray  # (k + 1,) CSR of the coordinates moving each frame
    chain_idx: np.ndarray
    multipliers: np.ndarray  # (rows of the called block,) a curvature call's multipliers
    hessian: np.ndarray  # (n, n) the Hessian a curvature call adds to


class KinematicViews(NamedTuple):
    """A workspace's kinematic tables and kinematic scratch (see :mod:`framework.model.kinematics`)."""

    joints: np.ndarray
    joint_geometry: np.ndarray
    frame_joints: np.ndarray
    frame_geometry: np.ndarray
    placements: np.ndarray  # (J, 12) the visited joints' world placements
    need: np.ndarray  # (k,) 1 for the frames whose Jacobians a call computes


@internal(inline=True)
def views(ws) -> Views:
    """The arrays of workspace ``ws`` (a :data:`WORKSPACE` record)."""
    n, k, rows = ws.n, ws.frames, ws.rows
    called = ws.blocks != 0 and ws.multipliers != 0
    size = view(ws.blocks, ws.block_count, BLOCK)[ws.block].rows if called else 0
    return Views(view(ws.x, n, np.float64), view(ws.poses, (k, 12), np.float64),
                 view(ws.jacobians, (k, 6, n), np.float64), view(ws.blocks, ws.block_count, BLOCK),
                 view(ws.params, ws.param_count, np.float64), view(ws.indices, ws.index_count, np.int64),
                 view(ws.wraps, n, np.bool_), view(ws.residuals, rows, np.float64),
                 view(ws.residual_jacobian, (rows, n), np.float64), view(ws.scratch, ws.scratch_size, np.float64),
                 view(ws.chain_ptr, k + 1, np.int64), view(ws.chain_idx, ws.chain_count, np.int64),
                 view(ws.multipliers, size, np.float64), view(ws.hessian, (n if ws.hessian != 0 else 0, n),
                                                              np.float64))


@internal(inline=True)
def kinematic_views(ws) -> KinematicViews:
    """The kinematic tables and scratch of workspace ``ws``."""
    k, J = ws.frames, ws.joint_count
    return KinematicViews(view(ws.joints, (J, 5), np.int64), view(ws.joint_geometry, (J, 17), np.float64),
                          view(ws.frame_joints, k, np.int64), view(ws.frame_geometry, (k, 12), np.float64),
                          view(ws.placements, (J, 12), np.float64), view(ws.need, k, np.float64))


@internal
def _attach(ws, packed, n) -> None:
    """The problem's arrays and sizes into ``ws``."""
    ws.n, ws.frames, ws.joint_count = n, packed.frame_joints.shape[0], packed.joints.shape[0]
    ws.block_count, ws.param_count = packed.blocks.shape[0], packed.params.shape[0]
    ws.index_count, ws.chain_count = packed.indices.shape[0], packed.chain_idx.shape[0]
    ws.joints, ws.joint_geometry = packed.joints.ctypes.data, packed.joint_geometry.ctypes.data
    ws.frame_joints, ws.frame_geometry = packed.frame_joints.ctypes.data, packed.frame_geometry.ctypes.data
    ws.chain_ptr, ws.chain_idx = packed.chain_ptr.ctypes.data, packed.chain_idx.ctypes.data
    ws.blocks, ws.params = packed.blocks.ctypes.data, packed.params.ctypes.data
    ws.indices, ws.wraps = packed.indices.ctypes.data, packed.wraps.ctypes.data
    rows = 0
    for b in range(packed.blocks.shape[0]):
        rows += packed.blocks[b].rows
    ws.rows, ws.scratch_size = max(rows, 1), packed.scratch[0]
    ws.x = ws.block = ws.row = ws.mode = ws.multipliers = ws.hessian = 0


@internal
def _carve(ws, at) -> int:
    """The workspace's scratch laid out from address ``at``; returns the address after it (from 0: its size)."""
    n, k, J, rows = ws.n, ws.frames, ws.joint_count, ws.rows
    ws.poses, at = at, at + 8 * 12 * k
    ws.placements, at = at, at + 8 * 12 * J
    ws.jacobians, at = at, at + 8 * 6 * k * n
    ws.residuals, at = at, at + 8 * rows
    ws.residual_jacobian, at = at, at + 8 * rows * n
    ws.scratch, at = at, at + 8 * ws.scratch_size
    ws.need, at = at, at + 8 * k
    return at


@internal
def workspaces(packed, n, count):
    """``count`` workspaces for a problem's ``packed`` arrays and ``n`` coordinates: ``(owners, records)``, the
    records ``records[i]`` valid while ``owners`` (their memory) and ``packed`` are alive."""
    records = np.empty(count, dtype=WORKSPACE)
    _attach(records[0], packed, n)
    size = _carve(records[0], 0)
    buffer = np.empty(count * (size // 8))
    for i in range(count):
        if i > 0:
            records[i] = records[0]
        _carve(records[i], address_of(buffer) + i * size)
    return (buffer, records), records


@internal(inline=True)
def hinge_row(value, r, J, row, want_jacobian, n) -> bool:
    """``r[row] = min(0, value)``; whether the caller writes the row's Jacobian (below zero, and wanted). A clear
    row's Jacobian is zeroed here."""
    below = value < 0.0
    r[row] = value if below else 0.0
    if want_jacobian and not below:
        for i in range(n):
            J[row, i] = 0.0
    return want_jacobian and below
