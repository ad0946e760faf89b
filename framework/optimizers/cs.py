"""Cuckoo search with Lévy flights (Mantegna's algorithm).

Reference: X.-S. Yang and S. Deb, "Cuckoo Search via Lévy Flights", NaBIC 2009, 210-214, following the
authors' reference implementation: each generation (1) every nest takes a Lévy step
``x + alpha * L * (x - best) * N(0, 1)`` with ``L`` drawn by Mantegna's algorithm (exponent beta = 1.5,
alpha = 0.01), kept if better; (2) a fraction ``pa`` of the coordinates of every nest is "discovered"
and rebuilt by a random differential step ``x + r (x_perm1 - x_perm2)``, kept if better.
Paper 000: discovery rate pa = 0.25.

Evaluations: ``2 * population`` per generation (plus ``population`` for the initial nests).
"""

from __future__ import annotations

from math import gamma, pi, sin
from typing import Any, ClassVar

import numpy as np

from .population import PopulationAlgorithm, greedy
from .registry import register


def levy_steps(rng: np.random.Generator, shape: tuple[int, ...], beta: float) -> np.ndarray:
    """Lévy-stable step lengths by Mantegna's algorithm, ``u / |v|^(1/beta)``. Shape ``shape``."""
    sigma_u = (
        gamma(1 + beta) * sin(pi * beta / 2) / (gamma((1 + beta) / 2) * beta * 2 ** ((beta - 1) / 2))
    ) ** (1 / beta)
    u = rng.standard_normal(shape) * sigma_u
    v = rng.standard_normal(shape)
    return u / np.abs(v) ** (1 / beta)


@register("cs")
class CuckooSearch(PopulationAlgorithm):
    """Cuckoo search (Yang & Deb 2009).

    Options:
        pa: Discovery rate (fraction of abandoned coordinates), default 0.25.
        alpha: Lévy step scale, default 0.01.
        beta: Lévy exponent, default 1.5.
    """

    DEFAULTS: ClassVar[dict[str, Any]] = {"pa": 0.25, "alpha": 0.01, "beta": 1.5}
    MIN_POPULATION: ClassVar[int] = 2
    phases: ClassVar[int] = 2

    def propose(self) -> np.ndarray:
        shape = self.X.shape
        if self.phase == 0:
            step = levy_steps(self.rng, shape, self.options["beta"])
            best = self.X[self.best_index]
            return self.X + self.options["alpha"] * step * (self.X - best) * self.rng.standard_normal(shape)
        discovered = self.rng.random(shape) > self.options["pa"]  # as in Yang's code: K = rand > pa
        i, j = self.rng.permutation(self.population), self.rng.permutation(self.population)
        return self.X + self.rng.random() * (self.X[i] - self.X[j]) * discovered

    def accept(self, X: np.ndarray, F: np.ndarray) -> None:
        greedy(self.X, self.F, X, F)
