"""Sine cosine algorithm (SCA).

Reference: S. Mirjalili, "SCA: A Sine Cosine Algorithm for solving optimization problems",
Knowl.-Based Syst. 96 (2016) 120-133. Per coordinate: ``x + r1 sin(r2) |r3 P - x|`` or with cos
(r4 < 0.5 chooses), r1 = a (1 - t / T) decreasing linearly from a = 2 (paper 002) to 0,
r2 ~ U(0, 2 pi), r3 ~ U(0, 2), r4 ~ U(0, 1); P is the best position found so far. Candidates always
move (no selection).

Evaluations: ``population`` per generation (plus ``population`` initially).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from .population import PopulationAlgorithm
from .registry import register


@register("sca")
class SCA(PopulationAlgorithm):
    """Sine cosine algorithm.

    Options:
        a: Initial amplitude r1, default 2.
    """

    DEFAULTS: ClassVar[dict[str, Any]] = {"a": 2.0}
    MIN_POPULATION: ClassVar[int] = 1

    def propose(self) -> np.ndarray:
        shape, rng = self.X.shape, self.rng
        r1 = self.schedule(self.options["a"], 0.0)
        r2 = rng.uniform(0.0, 2 * np.pi, shape)
        r3 = rng.uniform(0.0, 2.0, shape)
        wave = np.where(rng.random(shape) < 0.5, np.sin(r2), np.cos(r2))
        return self.X + r1 * wave * np.abs(r3 * self.best[0] - self.X)

    def accept(self, X: np.ndarray, F: np.ndarray) -> None:
        self.X, self.F = X.copy(), F.copy()
