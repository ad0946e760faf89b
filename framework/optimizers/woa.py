"""Whale optimization algorithm (WOA).

Reference: S. Mirjalili and A. Lewis, "The Whale Optimization Algorithm", Adv. Eng. Softw. 95 (2016)
51-67. Per whale (scalars A = 2 a r1 - a, C = 2 r2, p, l ~ U(-1, 1), spiral constant b = 1):
if p < 0.5, encircle the leader (|A| < 1) or a random whale (|A| >= 1): ``x* - A |C x* - x|``;
else the spiral ``|x* - x| e^(b l) cos(2 pi l) + x*``. The leader x* is the best position found so far;
``a`` decreases linearly from 2 to 0 over the iteration budget (paper 002). Whales always move (no
selection).

Evaluations: ``population`` per generation (plus ``population`` initially).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from .population import PopulationAlgorithm
from .registry import register


@register("woa")
class WOA(PopulationAlgorithm):
    """Whale optimization.

    Options:
        a_start, a_end: Linear schedule of ``a``, default 2 -> 0.
        b: Logarithmic-spiral constant, default 1.
    """

    DEFAULTS: ClassVar[dict[str, Any]] = {"a_start": 2.0, "a_end": 0.0, "b": 1.0}
    MIN_POPULATION: ClassVar[int] = 2

    def propose(self) -> np.ndarray:
        pop, rng = self.population, self.rng
        a = self.schedule(self.options["a_start"], self.options["a_end"])
        leader = self.best[0]
        A = (2 * a * rng.random(pop) - a)[:, None]
        C = (2 * rng.random(pop))[:, None]
        p = rng.random(pop)[:, None]
        ell = rng.uniform(-1.0, 1.0, pop)[:, None]  # the paper's l
        guide = np.where(np.abs(A) < 1, leader, self.X[rng.integers(0, pop, pop)])
        encircle = guide - A * np.abs(C * guide - self.X)
        spiral = np.abs(leader - self.X) * np.exp(self.options["b"] * ell) * np.cos(2 * np.pi * ell) + leader
        return np.where(p < 0.5, encircle, spiral)

    def accept(self, X: np.ndarray, F: np.ndarray) -> None:
        self.X, self.F = X.copy(), F.copy()
