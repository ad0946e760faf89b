"""Self-adaptive differential evolution (jDE): DE/rand/1/bin with per-individual F and CR.

Reference: J. Brest, S. Greiner, B. Boskovic, M. Mernik, V. Zumer, "Self-Adapting Control Parameters in
Differential Evolution: A Comparative Study on Numerical Benchmark Problems", IEEE Trans. Evol. Comput.
10(6) (2006) 646-657. Before creating its trial vector, individual i regenerates
F_i <- F_l + rand * F_u with probability tau1 and CR_i <- rand with probability tau2; the new values
survive only if the trial replaces the individual. Paper 000 (SDE, its ref. [30]) starts from F = 0.5,
CR = 0.8; tau1 = tau2 = 0.1, F_l = 0.1, F_u = 0.9 as in Brest et al.

Evaluations: ``population`` per generation (plus ``population`` for the initial population).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from .population import PopulationAlgorithm, binomial_crossover, greedy, rand_1
from .registry import register


@register("sde")
class SDE(PopulationAlgorithm):
    """jDE self-adaptive DE.

    Options:
        F: Initial differential weight of every individual, default 0.5.
        CR: Initial crossover probability of every individual, default 0.8.
        tau1: Probability of regenerating F_i, default 0.1.
        tau2: Probability of regenerating CR_i, default 0.1.
        F_lower: F_l, default 0.1 (new F_i in [F_l, F_l + F_u]).
        F_upper: F_u, default 0.9.
    """

    DEFAULTS: ClassVar[dict[str, Any]] = {
        "F": 0.5,
        "CR": 0.8,
        "tau1": 0.1,
        "tau2": 0.1,
        "F_lower": 0.1,
        "F_upper": 0.9,
    }
    MIN_POPULATION: ClassVar[int] = 4

    def start(self) -> None:
        self.F_i = np.full(self.population, float(self.options["F"]))
        self.CR_i = np.full(self.population, float(self.options["CR"]))

    def propose(self) -> np.ndarray:
        o, pop = self.options, self.population
        self._F_trial = np.where(
            self.rng.random(pop) < o["tau1"], o["F_lower"] + self.rng.random(pop) * o["F_upper"], self.F_i
        )
        self._CR_trial = np.where(self.rng.random(pop) < o["tau2"], self.rng.random(pop), self.CR_i)
        mutant = rand_1(self.X, self._F_trial, self.rng)
        return binomial_crossover(self.X, mutant, self._CR_trial, self.rng)

    def accept(self, X: np.ndarray, F: np.ndarray) -> None:
        won = greedy(self.X, self.F, X, F)
        self.F_i[won] = self._F_trial[won]
        self.CR_i[won] = self._CR_trial[won]
