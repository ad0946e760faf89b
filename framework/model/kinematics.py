"""Population forward kinematics: world poses of a set of frames for a whole population in one call.

The kernel reads the Pinocchio model (joint placements, joint kinds and axes, frame placements), never DH
tables, and composes ``oMi = oMparent · jointPlacement · M(x)`` exactly as ``pinocchio.forwardKinematics``
and ``pinocchio.updateFramePlacements`` do. Only the joints on the paths from the root to the requested frames
are visited. The loop over the population is compiled with numba (cached on disk, so the compile cost is paid
once per machine, never per solve). It runs on one thread: a threaded kernel gained < 2x at pop 1000 on two
idle cores and lost 50x when the cores were shared with other processes (benchmark workers).
"""

from __future__ import annotations

from functools import cached_property
from typing import Any, NamedTuple, Protocol

import numpy as np

from ..errors import ConfigurationError, UnknownFrameError
from ..compiled.native import borrow, compiled, internal, keep_alive
from ..compiled.trig import sincos
from .joints import JointKind



class Robot(Protocol):
    """What the kinematics read of a robot (:class:`~framework.model.robot.Robot`, which imports this module)."""

    model: Any  # pinocchio.Model
    joints: tuple
    mimics: tuple

    def frame_id(self, frame: str) -> int: ...

_REVOLUTE, _PRISMATIC, _PLANAR = 0, 1, 2
_KIND_CODE = {
    JointKind.REVOLUTE: _REVOLUTE,
    JointKind.CONTINUOUS: _REVOLUTE,
    JointKind.PRISMATIC: _PRISMATIC,
    JointKind.PLANAR: _PLANAR,
}


class FramePoses(NamedTuple):
    """World poses of ``frames`` for a population.

    Attributes:
        frames: frame names, in the order of axis 1.
        positions: ``(pop, k, 3)`` frame origins in the world frame [m].
        rotations: ``(pop, k, 3, 3)`` world-from-frame rotation matrices.
    """

    frames: tuple[str, ...]
    positions: np.ndarray
    rotations: np.ndarray

    def _index(self, frame: str) -> int:
        try:
            return self.frames.index(frame)
        except ValueError:
            raise UnknownFrameError(f"frame {frame!r} was not computed; computed: {list(self.frames)}") from None

    def position(self, frame: str) -> np.ndarray:
        """``(pop, 3)`` world position of one frame [m]."""
        return self.positions[:, self._index(frame)]

    def rotation(self, frame: str) -> np.ndarray:
        """``(pop, 3, 3)`` world rotation of one frame."""
        return self.rotations[:, self._index(frame)]


def _axis_code(axis: np.ndarray) -> int:
    """1, 2, 3 for +x, +y, +z; 4, 5, 6 for −x, −y, −z; 0 for any other axis."""
    for code, unit in enumerate(np.vstack([np.eye(3), -np.eye(3)]), start=1):
        if np.array_equal(axis, unit):
            return code
    return 0


class PopulationKinematics:
    """Compiled forward kinematics of one robot for one tuple of frames: ``(pop, n) -> FramePoses``.

    The model is flattened into two tables the kernel walks: per visited joint ``[parent slot, kind code,
    first coordinate, axis code, identity placement rotation]`` and ``[placement rotation (9, row-major),
    placement translation (3), axis (3), multiplier, offset]`` (the joint's value is ``multiplier · x + offset``:
    1 and 0 but for mimic joints, which read their leader's coordinate); per frame its joint slot and ``[rotation (9), translation (3)]`` in
    that joint. Axis code 1-6 marks a revolute joint about ±x, ±y or ±z (most URDFs): its rotation is applied
    with 6 products instead of Rodrigues' 27.
    """

    def __init__(self, robot: Robot, frames: tuple[str, ...]):
        model = robot.model
        frame_ids = [robot.frame_id(f) for f in frames]
        by_pin_id = {j.pin_id: j for j in (*robot.joints, *robot.mimics)}

        # Joints on the root paths of the requested frames, in Pinocchio (topological) order.
        needed: set[int] = set()
        for fid in frame_ids:
            jid = model.frames[fid].parentJoint
            while jid > 0 and jid not in needed:
                needed.add(jid)
                jid = model.parents[jid]
        order = [0, *sorted(needed)]
        slot = {jid: i for i, jid in enumerate(order)}

        self._joint_int = np.zeros((len(order), 5), dtype=np.int64)
        self._joint_geo = np.zeros((len(order), 17))
        for i, jid in enumerate(order[1:], start=1):
            joint = by_pin_id[jid]
            placement = model.jointPlacements[jid]
            identity = int(np.array_equal(placement.rotation, np.eye(3)))
            self._joint_int[i] = (slot[model.parents[jid]], _KIND_CODE[joint.kind], joint.index,
                                  _axis_code(joint.axis), identity)
            self._joint_geo[i] = np.concatenate([placement.rotation.ravel(), placement.translation, joint.axis,
                                                 [joint.multiplier, joint.offset]])
        self._frame_slot = np.array([slot[model.frames[f].parentJoint] for f in frame_ids], dtype=np.int64)
        self._frame_geo = np.array(
            [np.concatenate([model.frames[f].placement.rotation.ravel(), model.frames[f].placement.translation])
             for f in frame_ids]
        ).reshape(-1, 12)
        self.frames = frames

    @property
    def tables(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The kernel's tables ``(joint ints, joint geometry, frame slots, frame geometry)`` (read-only use)."""
        return self._joint_int, self._joint_geo, self._frame_slot, self._frame_geo

    @cached_property
    def chains(self) -> tuple[np.ndarray, np.ndarray]:
        """Coordinates moving each frame, ascending (an ancestor's before its descendants'): CSR ``(ptr, idx)``.

        Frame ``f`` moves with coordinates ``idx[ptr[f]:ptr[f + 1]]``; in that order, a coordinate's joint is an
        ancestor of (or the same joint as) every later one's, which the second-order terms of the engine use.
        """
        ptr, idx = [0], []
        for slot in self._frame_slot:
            coordinates, j = [], int(slot)
            while j > 0:
                kind, first = int(self._joint_int[j, 1]), int(self._joint_int[j, 2])
                coordinates += range(first, first + (3 if kind == _PLANAR else 1))
                j = int(self._joint_int[j, 0])
            idx += sorted(set(coordinates))  # a leader and its mimic joints share a coordinate
            ptr.append(len(idx))
        return np.array(ptr, dtype=np.int64), np.array(idx, dtype=np.int64)

    def __call__(self, X: np.ndarray) -> FramePoses:
        """Poses for a population ``X`` of shape ``(pop, n)`` (float64); NaN/inf rows raise ConfigurationError."""
        pop, k = X.shape[0], len(self.frames)
        out = np.empty((pop, k, 12))
        bad = _fk_serial(X, self._joint_int, self._joint_geo, self._frame_slot, self._frame_geo, out)
        if bad >= 0:
            raise ConfigurationError(f"configuration holds NaN or inf (row {bad}: {X[bad].tolist()})")
        return FramePoses(self.frames, out[:, :, 9:], out[:, :, :9].reshape(pop, k, 3, 3))

    def jacobians(self, X: np.ndarray, n: int) -> tuple[FramePoses, np.ndarray]:
        """Poses and frame Jacobians for a population ``X`` ``(pop, n)``.

        Returns the poses and ``J`` of shape ``(pop, k, 6, n)``: rows 0-2 the derivative of the frame origin's
        world position [m per coordinate unit], rows 3-5 the world angular velocity per coordinate rate
        (Pinocchio's ``LOCAL_WORLD_ALIGNED`` convention, in joint coordinates).
        """
        pop, k = X.shape[0], len(self.frames)
        out = np.empty((pop, k, 12))
        J = np.empty((pop, k, 6, n))
        bad = _jac_serial(X, self._joint_int, self._joint_geo, self._frame_slot, self._frame_geo, out, J)
        if bad >= 0:
            raise ConfigurationError(f"configuration holds NaN or inf (row {bad}: {X[bad].tolist()})")
        return FramePoses(self.frames, out[:, :, 9:], out[:, :, :9].reshape(pop, k, 3, 3)), J


@internal
def fk_one(x, jint, jgeo, fslot, fgeo, out, W):
    """Forward kinematics of one configuration ``x`` into ``out (k, 12)``.

    ``out`` rows hold the rotation row-major, then the position.

    ``W (m, 12)`` is scratch holding each visited joint's world placement in the same layout.
    """
    for c in range(12):
        W[0, c] = 0.0
    W[0, 0] = W[0, 4] = W[0, 8] = 1.0
    for j in range(1, jint.shape[0]):
        P, kind, i, code = jint[j, 0], jint[j, 1], jint[j, 2], jint[j, 3]
        g = jgeo[j]
        w = W[P]
        # A = R_P · R_placement, a = R_P · t_placement + p_P
        if jint[j, 4]:
            a00, a01, a02, a10, a11, a12, a20, a21, a22 = w[0], w[1], w[2], w[3], w[4], w[5], w[6], w[7], w[8]
        else:
            a00 = w[0] * g[0] + w[1] * g[3] + w[2] * g[6]
            a01 = w[0] * g[1] + w[1] * g[4] + w[2] * g[7]
            a02 = w[0] * g[2] + w[1] * g[5] + w[2] * g[8]
            a10 = w[3] * g[0] + w[4] * g[3] + w[5] * g[6]
            a11 = w[3] * g[1] + w[4] * g[4] + w[5] * g[7]
            a12 = w[3] * g[2] + w[4] * g[5] + w[5] * g[8]
            a20 = w[6] * g[0] + w[7] * g[3] + w[8] * g[6]
            a21 = w[6] * g[1] + w[7] * g[4] + w[8] * g[7]
            a22 = w[6] * g[2] + w[7] * g[5] + w[8] * g[8]
        px = w[0] * g[9] + w[1] * g[10] + w[2] * g[11] + w[9]
        py = w[3] * g[9] + w[4] * g[10] + w[5] * g[11] + w[10]
        pz = w[6] * g[9] + w[7] * g[10] + w[8] * g[11] + w[11]
        o = W[j]
        q = g[15] * x[i] + g[16]  # the joint's value (a mimic joint's from its leader's coordinate)
        if kind == 0 and code > 0:  # revolute about a principal axis: rotate two columns of A
            s, c = sincos(q)
            if code > 3:
                s, code = -s, code - 3
            if code == 3:  # z: columns 0, 1
                o[0], o[1], o[2] = a00 * c + a01 * s, a01 * c - a00 * s, a02
                o[3], o[4], o[5] = a10 * c + a11 * s, a11 * c - a10 * s, a12
                o[6], o[7], o[8] = a20 * c + a21 * s, a21 * c - a20 * s, a22
            elif code == 1:  # x: columns 1, 2
                o[0], o[1], o[2] = a00, a01 * c + a02 * s, a02 * c - a01 * s
                o[3], o[4], o[5] = a10, a11 * c + a12 * s, a12 * c - a11 * s
                o[6], o[7], o[8] = a20, a21 * c + a22 * s, a22 * c - a21 * s
            else:  # y: columns 2, 0
                o[0], o[1], o[2] = a00 * c - a02 * s, a01, a02 * c + a00 * s
                o[3], o[4], o[5] = a10 * c - a12 * s, a11, a12 * c + a10 * s
                o[6], o[7], o[8] = a20 * c - a22 * s, a21, a22 * c + a20 * s
            o[9], o[10], o[11] = px, py, pz
            continue
        if kind == 1:  # prismatic: translate along the axis
            ux, uy, uz = g[12] * q, g[13] * q, g[14] * q
            o[0], o[1], o[2], o[3], o[4], o[5], o[6], o[7], o[8] = a00, a01, a02, a10, a11, a12, a20, a21, a22
            o[9] = px + a00 * ux + a01 * uy + a02 * uz
            o[10] = py + a10 * ux + a11 * uy + a12 * uz
            o[11] = pz + a20 * ux + a21 * uy + a22 * uz
            continue
        if kind == 0:  # revolute: Rodrigues, M = c I + s [u]x + (1 - c) u uᵀ
            s, c = sincos(q)
            ux, uy, uz = g[12], g[13], g[14]
            v = 1.0 - c
            m00, m01, m02 = c + v * ux * ux, v * ux * uy - s * uz, v * ux * uz + s * uy
            m10, m11, m12 = v * uy * ux + s * uz, c + v * uy * uy, v * uy * uz - s * ux
            m20, m21, m22 = v * uz * ux - s * uy, v * uz * uy + s * ux, c + v * uz * uz
        else:  # planar: translate (x, y, 0) in the joint frame, rotate about z
            tx, ty = x[i], x[i + 1]
            s, c = sincos(x[i + 2])
            px += a00 * tx + a01 * ty
            py += a10 * tx + a11 * ty
            pz += a20 * tx + a21 * ty
            m00, m01, m02, m10, m11, m12, m20, m21, m22 = c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0
        o[0] = a00 * m00 + a01 * m10 + a02 * m20
        o[1] = a00 * m01 + a01 * m11 + a02 * m21
        o[2] = a00 * m02 + a01 * m12 + a02 * m22
        o[3] = a10 * m00 + a11 * m10 + a12 * m20
        o[4] = a10 * m01 + a11 * m11 + a12 * m21
        o[5] = a10 * m02 + a11 * m12 + a12 * m22
        o[6] = a20 * m00 + a21 * m10 + a22 * m20
        o[7] = a20 * m01 + a21 * m11 + a22 * m21
        o[8] = a20 * m02 + a21 * m12 + a22 * m22
        o[9], o[10], o[11] = px, py, pz
    for f in range(fslot.shape[0]):
        w = W[fslot[f]]
        g = fgeo[f]
        o = out[f]
        for r in range(3):
            o[3 * r] = w[3 * r] * g[0] + w[3 * r + 1] * g[3] + w[3 * r + 2] * g[6]
            o[3 * r + 1] = w[3 * r] * g[1] + w[3 * r + 1] * g[4] + w[3 * r + 2] * g[7]
            o[3 * r + 2] = w[3 * r] * g[2] + w[3 * r + 1] * g[5] + w[3 * r + 2] * g[8]
            o[9 + r] = w[3 * r] * g[9] + w[3 * r + 1] * g[10] + w[3 * r + 2] * g[11] + w[9 + r]


@internal(inline=True)
def _finite(x) -> bool:
    for i in range(x.shape[0]):
        if not np.isfinite(x[i]):
            return False
    return True


@compiled
def _fk_serial(X, jint, jgeo, fslot, fgeo, out):
    """FK of every row of ``X``; returns the first row holding NaN/inf, or -1."""
    own = np.empty((jint.shape[0], 12))
    W, X, out = borrow(own), borrow(X), borrow(out)
    jint, jgeo, fslot, fgeo = borrow(jint), borrow(jgeo), borrow(fslot), borrow(fgeo)
    bad = -1
    for b in range(X.shape[0]):
        if not _finite(X[b]):
            bad = b
            break
        fk_one(X[b], jint, jgeo, fslot, fgeo, out[b], W)
    keep_alive(own)
    return bad


@compiled
def _jac_serial(X, jint, jgeo, fslot, fgeo, out, J):
    """FK and frame Jacobians of every row of ``X``; returns the first row holding NaN/inf, or -1."""
    own = np.empty((jint.shape[0], 12))
    W, X, out, J = borrow(own), borrow(X), borrow(out), borrow(J)
    jint, jgeo, fslot, fgeo = borrow(jint), borrow(jgeo), borrow(fslot), borrow(fgeo)
    bad = -1
    for b in range(X.shape[0]):
        if not _finite(X[b]):
            bad = b
            break
        fk_jacobian_one(X[b], jint, jgeo, fslot, fgeo, out[b], W, J[b])
    keep_alive(own)
    return bad


@internal
def fk_jacobian_one(x, jint, jgeo, fslot, fgeo, out, W, J):
    """FK of one configuration into ``out (k, 12)`` and its frame Jacobians into ``J (k, 6, n)`` (overwritten).

    ``J[f, 0:3, i]``: derivative of frame ``f``'s origin [m per coordinate unit]; ``J[f, 3:6, i]``: its world
    angular velocity per coordinate rate (zero for prismatic coordinates and planar translations).
    """
    fk_one(x, jint, jgeo, fslot, fgeo, out, W)
    frame_jacobians(x, jint, jgeo, fslot, out, W, J)


@internal
def frame_jacobians(x, jint, jgeo, fslot, out, W, J):
    """Frame Jacobians ``J (k, 6, n)`` from the poses ``out`` and joint placements ``W`` of a FK at ``x``
    (columns add up: a mimic joint adds its multiplier times its own column to its leader's)."""
    J[:] = 0.0
    for f in range(fslot.shape[0]):
        frame_jacobian(f, x, jint, jgeo, fslot, out, W, J)


@internal
def frame_jacobians_where(x, jint, jgeo, fslot, out, W, J, need):
    """:func:`frame_jacobians` of the frames ``f`` with ``need[f] != 0`` only (``need (k,)``; the other frames'
    ``J[f]`` are left as they were)."""
    for f in range(fslot.shape[0]):
        if need[f] != 0.0:
            for r in range(6):
                for i in range(J.shape[2]):
                    J[f, r, i] = 0.0
            frame_jacobian(f, x, jint, jgeo, fslot, out, W, J)


@internal(inline=True)
def frame_jacobian(f, x, jint, jgeo, fslot, out, W, J):
    """Frame ``f``'s Jacobian added into ``J[f] (6, n)`` (zeroed before) along its chain of joints."""
    px, py, pz = out[f, 9], out[f, 10], out[f, 11]
    j = fslot[f]
    while j > 0:
        kind, i = jint[j, 1], jint[j, 2]
        w = W[j]
        ux, uy, uz, m = jgeo[j, 12], jgeo[j, 13], jgeo[j, 14], jgeo[j, 15]
        if kind == 2:  # planar: x, y along the pre-motion frame A's axes, θ about its z
            s, c = sincos(x[i + 2])
            for r in range(3):
                J[f, r, i] = c * w[3 * r] - s * w[3 * r + 1]
                J[f, r, i + 1] = s * w[3 * r] + c * w[3 * r + 1]
            ux, uy, uz, i = 0.0, 0.0, 1.0, i + 2
        # world axis a = R_j u (the joint's own rotation leaves u fixed), times the joint's multiplier
        ax = m * (w[0] * ux + w[1] * uy + w[2] * uz)
        ay = m * (w[3] * ux + w[4] * uy + w[5] * uz)
        az = m * (w[6] * ux + w[7] * uy + w[8] * uz)
        if kind == 1:  # prismatic: translation along a
            J[f, 0, i] += ax
            J[f, 1, i] += ay
            J[f, 2, i] += az
        else:  # revolute (and planar θ): a × (p_frame - p_joint), angular a
            dx, dy, dz = px - w[9], py - w[10], pz - w[11]
            J[f, 0, i] += ay * dz - az * dy
            J[f, 1, i] += az * dx - ax * dz
            J[f, 2, i] += ax * dy - ay * dx
            J[f, 3, i] += ax
            J[f, 4, i] += ay
            J[f, 5, i] += az
        j = jint[j, 0]
