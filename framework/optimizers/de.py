"""Differential evolution, DE/rand/1/bin with one-to-one greedy selection.

Reference: R. Storn and K. Price, "Differential Evolution - A Simple and Efficient Heuristic for Global
Optimization over Continuous Spaces", J. Global Optim. 11 (1997) 341-359. Settings of papers 000, 001
and 002: F = 0.6, CR = 0.9.

Evaluations: ``population`` per generation (plus ``population`` for the initial population).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from ..errors import SolverError
from .population import PopulationAlgorithm, binomial_crossover, greedy, rand_1
from .registry import register


@register("de")
class DE(PopulationAlgorithm):
    """DE/rand/1/bin.

    Options:
        F: Differential weight (mutation scale), default 0.6.
        CR: Crossover probability, default 0.9.
    """

    DEFAULTS: ClassVar[dict[str, Any]] = {"F": 0.6, "CR": 0.9}
    MIN_POPULATION: ClassVar[int] = 4

    def setup(self) -> None:
        super().setup()
        if not (0.0 < self.options["F"] <= 2.0 and 0.0 <= self.options["CR"] <= 1.0):
            raise SolverError(f"de: need 0 < F <= 2 and 0 <= CR <= 1, got {self.options}.")

    def propose(self) -> np.ndarray:
        mutant = rand_1(self.X, self.options["F"], self.rng)
        return binomial_crossover(self.X, mutant, self.options["CR"], self.rng)

    def accept(self, X: np.ndarray, F: np.ndarray) -> None:
        greedy(self.X, self.F, X, F)
