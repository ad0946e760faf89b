"""What the engine's compiled phases take besides the problem: the search box, their settings, their outputs."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


class Box(NamedTuple):
    """The search box: ``lower``, ``upper`` ``(n,)`` [rad or m], and ``wraps`` ``bool (n,)``, the coordinates that
    wrap around (full turns of continuous joints) instead of stopping at a bound."""

    lower: np.ndarray
    upper: np.ndarray
    wraps: np.ndarray


class ReachSettings(NamedTuple):
    """Settings of :func:`~framework.engine.reach.reach` (see :class:`~framework.engine.local.LocalSettings`)."""

    tol_linear: float  # [m]
    tol_angular: float  # [rad]
    max_iterations: int
    stall: int
    polish: int
    restarts: int  # random restarts a stalled descent may take
    deadline_ns: int  # ``monotonic_ns()`` at which to stop (0: none)


class NewtonSettings(NamedTuple):
    """Settings of the Newton phases (:mod:`framework.engine.regularize`, :mod:`framework.engine.weighted`)."""

    smoothing: float  # ε of the norm-like ρ at zero
    max_iterations: int
    deadline_ns: int


class Report(NamedTuple):
    """What a phase writes besides the configuration: each task block's error at it [m or rad], each term's value,
    and ``int64 (3,)`` counts (iterations, residual evaluations, restarts or accepted steps)."""

    errors: np.ndarray
    values: np.ndarray
    stats: np.ndarray
