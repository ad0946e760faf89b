"""Distance of a frame to another frame or to a point, held within bounds (at least, at most, or exactly)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..errors import TaskError
from ..robot import Robot
from . import blocks as B
from .base import Term, as_vector
from .program import Block


class Distance(Term):
    """``‖p_frame − p_to‖`` [m] within ``[at_least, at_most]``: ``to`` is another frame's name or a point
    (3,) [m, world]; ``exactly=d`` sets both bounds (keep two hands 30 cm apart, stay 10 cm from a point).

    Residual (1,): the distance minus the bound it crosses (0 inside the band) [m]; a task term held to the
    linear tolerance.
    """

    level = "task"
    has_target = True

    def __init__(self, frame: str, to: str | Sequence[float], *, at_least: float | None = None,
                 at_most: float | None = None, exactly: float | None = None, name: str | None = None):
        if exactly is not None:
            if at_least is not None or at_most is not None:
                raise TaskError("distance: give exactly= alone, or at_least= / at_most=")
            at_least = at_most = exactly
        if at_least is None and at_most is None:
            raise TaskError("distance needs at_least=, at_most= or exactly= [m]")
        lo = 0.0 if at_least is None else float(at_least)
        hi = np.inf if at_most is None else float(at_most)
        if not (np.isfinite(lo) and lo >= 0 and (np.isinf(hi) or np.isfinite(hi)) and hi >= lo):
            raise TaskError(f"distance bounds must satisfy 0 <= at_least <= at_most; got {at_least!r}, {at_most!r}")
        self.frame, self.bounds = frame, (lo, hi)
        self.to_frame = to if isinstance(to, str) else None
        self.frames = (frame, to) if self.to_frame else (frame,)
        self.name = name or f"distance[{frame}, {to if self.to_frame else 'point'}]"
        self.point = np.zeros(3)
        if self.to_frame is None:
            self.set_target(to)

    def set_target(self, point: Sequence[float]) -> None:
        """Move the point (3,) [m, world] the distance is measured to (a frame-to-frame distance has none)."""
        if self.to_frame is not None:
            raise TaskError(f"{self.name} measures to frame {self.to_frame!r}: it has no point to move")
        self.point = as_vector(point, 3, lambda: f"point of {self.name}")
        self._touch()

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        params = np.concatenate([self.point, [self.bounds[0], min(self.bounds[1], 1e300)]])
        return (Block(B.DISTANCE, B.NORM, 1, self.frames, params, tolerance=B.TOL_LINEAR),)

    def __repr__(self) -> str:
        return f"Distance({self.frame!r}, {self.to_frame or self.point.tolist()}, bounds={self.bounds})"
