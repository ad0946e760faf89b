"""Angle helpers shared by the FABRIK passes: wrapping, and joint limits on the turn between two links.

A *turn* ``δ`` [rad] is the signed angle, counter-clockwise in the chain's plane, from one link's direction to
the next. A revolute joint ``i`` turns its link by ``δ = δ0 + σ (q - q0)``, where ``δ0`` is the turn at the
reference angle ``q0`` and ``σ = ±1`` tells whether its axis is the plane normal or its opposite. All inputs and
outputs are Python floats (these run inside the FABRIK loops, where numpy scalars are slower).
"""

from __future__ import annotations

import math

TWO_PI = 2.0 * math.pi


def wrap(angle: float) -> float:
    """``angle`` wrapped to ``[-π, π)`` [rad]."""
    return (angle + math.pi) % TWO_PI - math.pi


def joint_angle(
    turn: float, turn0: float, sign: float, q0: float, lower: float, upper: float
) -> tuple[float, bool]:
    """Joint angle [rad] that produces ``turn``, in ``[lower, upper]`` if any ``2π`` representative is.

    Returns ``(q, inside)``; when no representative is inside the limits, ``q`` is the nearer limit (by angular
    distance) and ``inside`` is False.
    """
    q = q0 + sign * wrap(turn - turn0)
    if lower <= q <= upper:
        return q, True
    for shift in (TWO_PI, -TWO_PI):
        if lower <= q + shift <= upper:
            return q + shift, True
    if abs(wrap(q - lower)) <= abs(wrap(q - upper)):
        return lower, False
    return upper, False


def clamp_turn(turn: float, turn0: float, sign: float, q0: float, lower: float, upper: float) -> float:
    """``turn`` if its joint angle is within limits, else the turn of the nearer limit [rad]."""
    q, inside = joint_angle(turn, turn0, sign, q0, lower, upper)
    if inside:
        return turn
    return turn0 + sign * (q - q0)


def clamp_angle(q: float, lower: float, upper: float) -> float:
    """A ``2π`` representative of ``q`` within ``[lower, upper]``, else the nearer limit (angularly) [rad]."""
    return joint_angle(q, 0.0, 1.0, 0.0, lower, upper)[0]
