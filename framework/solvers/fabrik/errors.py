"""Errors of the FABRIK package; each is a :class:`framework.errors.MetaikError`."""

from __future__ import annotations

from ...errors import MetaikError


class UnsupportedChainError(MetaikError):
    """The joints between the chain's root and its end-effector are outside the class FABRIK supports here.

    Supported: revolute position joints that are all parallel (a planar arm), or a yaw joint followed by
    parallel joints perpendicular to it (youBot, Puma 560), then any joints whose axes pass through the
    end-effector point. See :mod:`framework.solvers.fabrik.chain`.
    """


class UnsupportedBaseError(MetaikError):
    """The robot's base group is not an omnidirectional planar base ``(x, y, θ)`` in the world's xy-plane."""
