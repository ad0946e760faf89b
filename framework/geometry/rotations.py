"""Rotations given by users: a (3, 3) matrix or a quaternion whose component order is named, validated once.

Quaternions are ``(x, y, z, w)`` (scalar last, as ``scipy.spatial.transform.Rotation``) unless given as
``quat_wxyz``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..compiled.native import compiled

from ..errors import TaskError


def rotation_from(target: Sequence[float] | np.ndarray, what: str) -> np.ndarray:
    """A rotation matrix ``(3, 3)`` from a ``(3, 3)`` matrix or an ``(x, y, z, w)`` quaternion; validated."""
    try:
        t = np.array(target, dtype=float)
    except (TypeError, ValueError):
        raise TaskError(f"{what} must be a (3, 3) rotation matrix or an (x, y, z, w) quaternion") from None
    if t.shape == (4,):
        if not np.all(np.isfinite(t)):
            raise TaskError(f"{what} holds NaN or inf")
        norm = np.linalg.norm(t)
        if norm < 1e-9:
            raise TaskError(f"{what}: a zero quaternion is not a rotation")
        x, y, z, w = t / norm
        return np.array(
            [
                [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
            ]
        )
    if t.shape == (3, 3):
        problem = _rotation_defect(t)
        if problem == 1:
            raise TaskError(f"{what} holds NaN or inf")
        if problem == 2:
            raise TaskError(f"{what} is not a rotation matrix (RᵀR ≠ I or det < 0)")
        return t
    raise TaskError(f"{what} must be a (3, 3) rotation matrix or an (x, y, z, w) quaternion; got shape {t.shape}")


def rotation_defects(R: np.ndarray) -> np.ndarray:
    """``bool (B,)``: which of ``R (B, 3, 3)`` (finite) are no rotation matrix (``|RᵀR − I| > 1e-6`` or
    ``det R <= 0``; the test :func:`rotation_from` makes of one)."""
    defect = np.abs(np.einsum("bki,bkj->bij", R, R) - np.eye(3)).max(axis=(1, 2))
    return (defect > 1e-6) | (np.linalg.det(R) <= 0)


@compiled
def _rotation_defect(R) -> int:
    """0 for a rotation matrix (``|RᵀR − I| <= 1e-6``, ``det R > 0``), 1 for NaN/inf, 2 otherwise."""
    for a in range(3):
        for b in range(3):
            if not np.isfinite(R[a, b]):
                return 1
    for a in range(3):
        for b in range(3):
            s = R[0, a] * R[0, b] + R[1, a] * R[1, b] + R[2, a] * R[2, b]
            if abs(s - (1.0 if a == b else 0.0)) > 1e-6:
                return 2
    det = (R[0, 0] * (R[1, 1] * R[2, 2] - R[1, 2] * R[2, 1]) - R[0, 1] * (R[1, 0] * R[2, 2] - R[1, 2] * R[2, 0])
           + R[0, 2] * (R[1, 0] * R[2, 1] - R[1, 1] * R[2, 0]))
    return 0 if det > 0 else 2


@compiled
def transform_defect(T) -> int:
    """0 for a homogeneous transform ``(4, 4)`` (finite, a rotation block, last row ``[0, 0, 0, 1]``), 1 for NaN
    or inf, 2 for a block that is no rotation, 3 for another last row."""
    for a in range(4):
        for b in range(4):
            if not np.isfinite(T[a, b]):
                return 1
    if abs(T[3, 0]) > 1e-9 or abs(T[3, 1]) > 1e-9 or abs(T[3, 2]) > 1e-9 or abs(T[3, 3] - 1.0) > 1e-9:
        return 3
    return _rotation_defect(T[:3, :3])


@compiled
def pack_transform(T, out) -> int:
    """:func:`transform_defect` of ``T (4, 4)``; when 0, its position then its row-major rotation into ``out
    (12,)``."""
    defect = transform_defect(T)
    if defect == 0:
        for a in range(3):
            out[a] = T[a, 3]
            for b in range(3):
                out[3 + 3 * a + b] = T[a, b]
    return defect


def rotation_target(target, quat_xyzw, quat_wxyz, what: str) -> np.ndarray:
    """The rotation matrix of exactly one of ``target`` (matrix, or ``(x, y, z, w)``), ``quat_xyzw``, ``quat_wxyz``."""
    given = [v is not None for v in (target, quat_xyzw, quat_wxyz)]
    if sum(given) != 1:
        raise TaskError(f"{what}: give exactly one of a rotation matrix, quat_xyzw= or quat_wxyz=")
    if quat_wxyz is not None:
        q = np.asarray(quat_wxyz, dtype=float)
        if q.shape != (4,):
            raise TaskError(f"{what}: quat_wxyz must be 4 numbers (w, x, y, z); got shape {q.shape}")
        return rotation_from(np.r_[q[1:], q[0]], what)
    if quat_xyzw is not None:
        q = np.asarray(quat_xyzw, dtype=float)
        if q.shape != (4,):
            raise TaskError(f"{what}: quat_xyzw must be 4 numbers (x, y, z, w); got shape {q.shape}")
        return rotation_from(q, what)
    return rotation_from(target, what)
