"""Search bounds of a robot's joint coordinates: the URDF's limits (or a span for unbounded joints), overrides by
joint name, and their checks."""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence

import numpy as np
import pinocchio as pin

from ..errors import LimitsError, UnknownJointError
from ..validate import suggest
from .joints import Joint, JointKind, coordinate_names


#: Limits of this magnitude or beyond [rad or m] are a file's way of saying "no limit" (URDF continuous joints and
#: planar bases, and files that write ±1e6 or ±1e9): read as none, the coordinate searched over ``±translation``
#: [m] or one turn (``±angle``).
UNBOUNDED = 1e3


#: What :class:`Robot` adds when its search bounds are empty somewhere.
EMPTY_BOUNDS_REMEDY = (" (a URDF <limit> without lower and upper means [0, 0]); lock those joints (locked={name: "
                       "value}) or give their bounds (bounds={name: (lower, upper)})")


def check_bounds(lower: np.ndarray, upper: np.ndarray, names: Sequence[str], *, what: str = "search bounds",
                 remedy: str = "") -> None:
    """Raise :class:`LimitsError` unless ``lower < upper`` elementwise, both finite, shape ``(len(names),)``.

    Empty ranges (``lower == upper``) are named all at once, followed by ``remedy``: a robot's search bounds give
    the ways out (:data:`EMPTY_BOUNDS_REMEDY`; a URDF ``<limit>`` without ``lower`` / ``upper`` declares
    ``[0, 0]``, the format's defaults, which real files do for joints that turn freely, wheels among them)."""
    if lower.shape != (len(names),) or upper.shape != (len(names),):
        raise LimitsError(f"bounds must have shape ({len(names)},); got {lower.shape} and {upper.shape}")
    empty = []
    for i, name in enumerate(names):
        lo, hi = lower[i], upper[i]
        if not (np.isfinite(lo) and np.isfinite(hi)):
            raise LimitsError(f"{what} of {name!r} are not finite ({lo}, {hi}); set them explicitly")
        if lo == hi:
            empty.append((name, float(lo)))
        elif not lo < hi:
            raise LimitsError(f"{what} of {name!r} are inverted: lower {lo} > upper {hi}")
    if empty:
        listed = ", ".join(f"{name!r} [{lo:g}, {lo:g}]" for name, lo in empty)
        raise LimitsError(f"{what} of {len(empty)} coordinate{'s' if len(empty) > 1 else ''} are empty: {listed}"
                          + remedy)


def override_bounds(lower: np.ndarray, upper: np.ndarray, bounds: Mapping[str, tuple[float, float]],
                    joints: Sequence[Joint], robot: str) -> tuple[np.ndarray, np.ndarray]:
    """Copies of the search bounds ``lower, upper`` ``(n,)`` with ``bounds`` (coordinate or joint name ->
    ``(lower, upper)`` [rad or m]) written over them; an unknown name raises :class:`UnknownJointError`."""
    lower, upper = np.array(lower, dtype=float), np.array(upper, dtype=float)
    coordinates = [name for j in joints for name in coordinate_names(j)]
    if not isinstance(bounds, Mapping):
        raise LimitsError(f"bounds must be a table of joint or coordinate name -> (lower, upper); got {bounds!r}")
    for name, pair in bounds.items():
        lo, hi = bound_pair(pair, f"bounds[{name!r}]")
        if name in coordinates:
            idx = [coordinates.index(name)]
        else:
            joint = next((j for j in joints if j.name == name), None)
            if joint is None:
                raise UnknownJointError(f"robot {robot!r} has no solved joint {name!r}"
                                        f"{suggest(name, [j.name for j in joints])}")
            idx = list(joint.coordinates)
        lower[idx], upper[idx] = lo, hi
    return lower, upper


def default_bounds(
    model: pin.Model, joints: Iterable[Joint], *, translation: float = 2.0, angle: float = np.pi
) -> tuple[np.ndarray, np.ndarray]:
    """Search bounds from the model's limits; unbounded coordinates get ``±translation`` [m] or ``±angle`` [rad]."""
    lower, upper = [], []
    for j in joints:
        if j.kind is JointKind.CONTINUOUS:
            lower.append(-angle)
            upper.append(angle)
        elif j.kind is JointKind.PLANAR:
            k = j.idx_q
            for axis in range(2):
                lo, hi = model.lowerPositionLimit[k + axis], model.upperPositionLimit[k + axis]
                bounded = abs(lo) < UNBOUNDED and abs(hi) < UNBOUNDED
                lower.append(lo if bounded else -translation)
                upper.append(hi if bounded else translation)
            lower.append(-angle)
            upper.append(angle)
        else:
            lo, hi = model.lowerPositionLimit[j.idx_q], model.upperPositionLimit[j.idx_q]
            span = translation if j.kind is JointKind.PRISMATIC else angle
            lower.append(lo if abs(lo) < UNBOUNDED else -span)
            upper.append(hi if abs(hi) < UNBOUNDED else span)
    return np.array(lower, dtype=float), np.array(upper, dtype=float)


def bound_pair(value, what: str, error: type[Exception] = LimitsError) -> tuple[float, float]:
    """``(lower, upper)`` of one coordinate's bounds as two finite floats, or ``error`` naming ``what`` (the Python
    argument, or the task file's key)."""
    try:
        values = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        values = None
    if values is None or values.shape != (2,) or not np.all(np.isfinite(values)):
        raise error(f"{what} must be a pair [lower, upper] of finite numbers [rad or m]; got {value!r}")
    return float(values[0]), float(values[1])
