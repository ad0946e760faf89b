"""Rotations given by users, read one way everywhere and validated once.

A ``pinocchio.Quaternion``, a ``scipy.spatial.transform.Rotation``, a ``pinocchio.SE3`` (its rotation), a (3, 3)
rotation matrix and a (4, 4) homogeneous matrix (its rotation) are taken as they are. A bare 4-vector is a
quaternion only with its order named — ``quaternion="xyzw"`` (scipy's ``as_quat()``, ROS messages) or
``quaternion="wxyz"`` (``pinocchio.Quaternion(w, x, y, z)``, Eigen, MuJoCo): read in the other order it is another
rotation, and no check could tell. Every term, the floating base, the obstacles and the task files take that one
keyword (task files: a ``quaternion = "xyzw"`` key beside the value).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from ..compiled.native import compiled

from ..errors import TaskError

#: The component orders a bare 4-vector quaternion may be given in (``quaternion=``).
QUATERNION_ORDERS = ("xyzw", "wxyz")
#: What a rotation may be given as, for error messages.
ROTATION_FORMS = ("a (3, 3) rotation matrix, a pinocchio.Quaternion, a scipy Rotation, or 4 numbers with "
                  "quaternion='xyzw' or 'wxyz'")


def check_order(quaternion: str | None, what: str) -> str | None:
    """``quaternion`` if it names an order (or is ``None``), else a :class:`TaskError` naming ``what``."""
    if quaternion is not None and quaternion not in QUATERNION_ORDERS:
        raise TaskError(f"{what}: quaternion must be 'xyzw' or 'wxyz' (the order of a 4-vector's components); "
                        f"got {quaternion!r}")
    return quaternion


def rotation_from(target: Any, what: str, quaternion: str | None = None) -> np.ndarray:
    """A validated rotation matrix ``(3, 3)`` from any form of :data:`ROTATION_FORMS` (see the module docstring);
    ``quaternion`` names the order of a bare 4-vector, which without it is a :class:`TaskError` saying how."""
    check_order(quaternion, what)
    if isinstance(target, pin.Quaternion):
        norm = target.norm()
        if not np.isfinite(norm) or norm < 1e-9:
            raise TaskError(f"{what}: a zero or non-finite quaternion is not a rotation")
        return target.normalized().toRotationMatrix()
    if isinstance(target, pin.SE3):
        target = target.rotation
    elif hasattr(target, "as_matrix") and hasattr(target, "as_quat"):  # scipy.spatial.transform.Rotation
        target = target.as_matrix()
    try:
        t = np.array(target, dtype=float)
    except (TypeError, ValueError):
        raise TaskError(f"{what} must be {ROTATION_FORMS}; got {target!r:.80}") from None
    if t.shape == (4,):
        if quaternion is None:
            raise TaskError(f"{what} is 4 numbers: name their order, quaternion \"xyzw\" (scipy's as_quat, ROS) or "
                            f"\"wxyz\" (pinocchio.Quaternion(w, x, y, z), Eigen, MuJoCo); a matrix (and, in Python, a "
                            f"pinocchio.Quaternion or a scipy Rotation) needs none")
        if not np.all(np.isfinite(t)):
            raise TaskError(f"{what} holds NaN or inf")
        norm = np.linalg.norm(t)
        if norm < 1e-9:
            raise TaskError(f"{what}: a zero quaternion is not a rotation")
        x, y, z, w = (t if quaternion == "xyzw" else np.r_[t[1:], t[0]]) / norm
        return np.array(
            [
                [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
            ]
        )
    if quaternion is not None:
        raise TaskError(f"{what}: quaternion={quaternion!r} names the order of 4 numbers; the rotation given is "
                        f"of shape {t.shape}")
    if t.shape == (4, 4):
        if not np.all(np.isfinite(t)) or np.abs(t[3] - [0.0, 0.0, 0.0, 1.0]).max() > 1e-9:
            raise TaskError(f"{what}: a 4x4 homogeneous matrix needs finite entries and a last row [0, 0, 0, 1]")
        t = np.ascontiguousarray(t[:3, :3])
    if t.shape == (3, 3):
        problem = _rotation_defect(t)
        if problem == 1:
            raise TaskError(f"{what} holds NaN or inf")
        if problem == 2:
            raise TaskError(f"{what} is not a rotation matrix (RᵀR ≠ I or det < 0)")
        return t
    raise TaskError(f"{what} must be {ROTATION_FORMS}; got shape {t.shape}")


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
