"""The two half-iterations of FABRIK in the chain's plane, with joint limits (Aristidou & Lasenby 2011).

Points are plane coordinates (lists ``xs``, ``ys`` of ``K + 1`` floats [m], updated in place): ``0`` is the first
planar joint, ``K`` the end-effector. Each new point lies on the line from its new neighbour to its old
position, one link length away; where the turn between two links would leave a joint's limits, the link is
rotated to the limit instead (the 2-D form of FABRIK's joint constraints). Link directions are absolute angles
[rad] from the plane's ``e_x``; the first joint's turn is taken from ``e_x`` itself, which is fixed in the yaw
frame, so its limits hold in both passes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .angles import clamp_turn
from .chain import PlanarChain


@dataclass(frozen=True)
class Links:
    """The chain's links as plain floats, for the passes: one tuple ``(length, turn0, sign, q0, lower, upper)``
    per planar joint (see :class:`PlanarChain`)."""

    links: tuple[tuple[float, float, float, float, float, float], ...]

    @classmethod
    def of(cls, chain: PlanarChain) -> Links:
        return cls(
            tuple(
                (float(L), float(t), float(s), float(q), float(lo), float(hi))
                for L, t, s, q, lo, hi in zip(
                    chain.lengths, chain.turns, chain.signs, chain.reference, chain.lower, chain.upper
                )
            )
        )


def forward(
    xs: list[float], ys: list[float], tx: float, ty: float, links: Links, first_height: float | None = None
) -> None:
    """Forward reaching: put the end-effector on the target ``(tx, ty)`` and pull each joint after it, tip to base.

    The first joint ends wherever the chain puts it (off its fixed position); limits of every joint hold. With
    ``first_height`` [m] (a mobile base, which moves the first joint along a line of that height), the first joint
    is put on that line where the first link still reaches it, on the side of its line-of-FABRIK position.
    """
    chain = links.links
    k = len(chain)
    xs[k], ys[k] = tx, ty
    after = 0.0  # direction of the link after the current one
    for i in range(k - 1, -1, -1):
        length, *_ = chain[i]
        dx, dy = xs[i + 1] - xs[i], ys[i + 1] - ys[i]
        direction = math.atan2(dy, dx) if dx or dy else after
        if i == 0 and first_height is not None:
            rise = ys[1] - first_height  # the link must climb this much from the first joint
            run = math.sqrt(max(length * length - rise * rise, 0.0))
            direction = math.atan2(max(min(rise, length), -length), math.copysign(run, math.cos(direction)))
        if i + 1 < k:  # joint i + 1 turns link i + 1 relative to link i
            direction = after - clamp_turn(after - direction, *chain[i + 1][1:])
        if i == 0:  # joint 0 turns link 0 relative to e_x
            direction = clamp_turn(direction, *chain[0][1:])
        xs[i] = xs[i + 1] - length * math.cos(direction)
        ys[i] = ys[i + 1] - length * math.sin(direction)
        after = direction


def backward(xs: list[float], ys: list[float], sx: float, sy: float, links: Links) -> None:
    """Backward reaching: put the first joint back at ``(sx, sy)`` and push each joint after it, base to tip."""
    xs[0], ys[0] = sx, sy
    before = 0.0  # direction of the previous link (e_x for the first joint)
    for i, (length, *limits) in enumerate(links.links):
        dx, dy = xs[i + 1] - xs[i], ys[i + 1] - ys[i]
        direction = math.atan2(dy, dx) if dx or dy else before
        direction = before + clamp_turn(direction - before, *limits)
        xs[i + 1] = xs[i] + length * math.cos(direction)
        ys[i + 1] = ys[i] + length * math.sin(direction)
        before = direction
