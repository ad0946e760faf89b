"""Seeded uniform draws inside compiled loops: the restart configurations of the local engine.

A *stream* is a ``uint64 (1,)`` array holding the state of SplitMix64 (Steele, Lea & Flood, "Fast splittable
pseudorandom number generators", OOPSLA 2014): the state advances by a fixed odd constant and each output is that
state through a bijective mixing function. It passes BigCrush, costs a few nanoseconds a draw, and its whole state
is one integer, so a solve's stream is made from its seed for free (a ``numpy.random.Generator`` costs ~8 µs to
seed, more than a typical pose solve) and a batch carries one stream per item. The same seed gives the same draws,
in a single solve and in a batch alike; nothing is shared between streams.
"""

from __future__ import annotations

import numpy as np

from ..errors import SolverError
from ..compiled.native import compiled, internal

_GAMMA = np.uint64(0x9E3779B97F4A7C15)
_MIX1 = np.uint64(0xBF58476D1CE4E5B9)
_MIX2 = np.uint64(0x94D049BB133111EB)
_S30, _S27, _S31, _S11 = np.uint64(30), np.uint64(27), np.uint64(31), np.uint64(11)
_UNIT = 2.0**-53
_STATE = np.dtype(np.uint64)


def stream(seed: int | np.random.Generator) -> np.ndarray:
    """A new stream ``uint64 (1,)`` from an integer seed ``>= 0`` (or one integer drawn from a generator)."""
    state = np.empty(1, _STATE)  # (a list would cost a conversion)
    if type(seed) is int and 0 <= seed < 2**64:  # the common case needs no check
        state[0] = seed
        return state
    state[0] = seed_of(seed) % 2**64
    return state


def seed_of(seed: int | np.integer | np.random.Generator) -> int:
    """The integer a stream starts from: an integer ``>= 0`` as a Python int, or one drawn from a generator;
    anything else raises :class:`SolverError`."""
    if isinstance(seed, np.random.Generator):
        return int(seed.integers(0, 2**63))
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise SolverError(f"seed must be an integer >= 0 or a numpy.random.Generator; got {seed!r}")
    return int(seed)


@internal
def uniform(state) -> float:
    """The next number of the stream ``state`` ``uint64 (1,)``, uniform in ``[0, 1)`` (53 random bits)."""
    state[0] += _GAMMA
    z = state[0]
    z = (z ^ (z >> _S30)) * _MIX1
    z = (z ^ (z >> _S27)) * _MIX2
    z = z ^ (z >> _S31)
    return float(z >> _S11) * _UNIT


@internal
def uniform_in_box(state, lower, upper, x) -> None:
    """``x (n,)`` drawn uniformly in the box ``[lower, upper]`` from the stream ``state``."""
    for i in range(x.shape[0]):
        x[i] = lower[i] + (upper[i] - lower[i]) * uniform(state)


@compiled
def draws(state, lower, upper, count):
    """``(count, n)`` configurations drawn uniformly in the box (for tests and callers outside compiled code)."""
    out = np.empty((count, lower.shape[0]))
    for k in range(count):
        uniform_in_box(state, lower, upper, out[k])
    return out
