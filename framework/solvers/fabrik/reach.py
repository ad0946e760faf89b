"""The reach of a planar sub-chain: for each height in its plane, the interval of radii it can reach.

Built once per chain by sampling the planar joints on a grid within their limits. M-FABRIK turns it into the
annulus of base positions from which a target is reachable (its admissible area before obstacles); FABRIK uses it
to choose between the planes in front of and behind the yaw axis.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .chain import PlanarChain


@dataclass(frozen=True)
class ReachTable:
    """Reachable radii of the end-effector, row by row of plane height.

    Row ``i`` covers heights ``[y0 + i·step, y0 + (i+1)·step)`` [m] and keeps, in front of the yaw axis
    (``x >= 0``) and behind it (``x <= 0``), the interval ``[lo, hi]`` of sampled end-effector ``x`` [m] (empty:
    ``lo > hi``). A query intersects the intervals of the row and its two neighbours, and samples only ever
    underestimate an interval, so the table errs on the side of "unreachable". It assumes that on each side the
    reachable radii at one height form an interval (true of planar arms and of the youBot with its limits).

    Attributes:
        y0, step: height of row 0's lower edge and the row height [m].
        front, back: ``(rows, 2)`` intervals ``[lo, hi]`` [m] for ``x >= 0`` and ``x <= 0``.
    """

    y0: float
    step: float
    front: np.ndarray = field(repr=False)
    back: np.ndarray = field(repr=False)

    @classmethod
    def from_chain(cls, chain: PlanarChain, *, samples: int = 200_000, rows: int = 1000) -> ReachTable:
        """Sample ``~samples`` planar configurations on a grid in the joints' limits."""
        k = chain.size
        per_joint = max(2, round(samples ** (1.0 / k)))
        width = np.minimum(chain.upper - chain.lower, 2 * math.pi)
        grids = [
            np.union1d(np.linspace(lo, lo + w, per_joint), [np.clip(q, lo, lo + w)])
            for lo, w, q in zip(chain.lower, width, chain.reference)
        ]
        Q = np.stack(np.meshgrid(*grids, indexing="ij"), axis=-1).reshape(-1, k)
        tips = chain.points(Q)[:, -1]
        y0 = chain.start[1] - chain.reach
        step = 2 * chain.reach / rows
        index = np.clip(((tips[:, 1] - y0) / step).astype(int), 0, rows - 1)
        return cls(
            y0=y0,
            step=step,
            front=_intervals(tips[:, 0], index, rows, tips[:, 0] >= 0),
            back=_intervals(tips[:, 0], index, rows, tips[:, 0] <= 0),
        )

    def interval(self, y: float, front: bool = True) -> tuple[float, float] | None:
        """Reachable ``[lo, hi]`` of ``x`` [m] at plane height ``y`` [m] on one side, or None."""
        table = self.front if front else self.back
        i = math.floor((y - self.y0) / self.step)
        if i < 1 or i >= len(table) - 1:
            return None
        lo, hi = float(table[i - 1 : i + 2, 0].max()), float(table[i - 1 : i + 2, 1].min())
        return (lo, hi) if lo <= hi else None

    def contains(self, x: float, y: float) -> bool:
        """Is the plane point ``(x, y)`` [m] within the sampled reach?"""
        interval = self.interval(y, front=x >= 0)
        return interval is not None and interval[0] <= x <= interval[1]


def _intervals(x: np.ndarray, index: np.ndarray, rows: int, keep: np.ndarray) -> np.ndarray:
    table = np.empty((rows, 2))
    table[:, 0], table[:, 1] = np.inf, -np.inf
    np.minimum.at(table[:, 0], index[keep], x[keep])
    np.maximum.at(table[:, 1], index[keep], x[keep])
    return table
