"""Hybrid biogeography-based optimization (HBBO): BBO migration hybridized with DE mutation.

Reference: Z. W. Ren, Z. H. Wang, L. N. Sun, "A hybrid biogeography-based optimization method for the
inverse kinematics problem of an 8-DOF redundant humanoid manipulator", Front. Inf. Technol. Electron.
Eng. 16 (2015) 607-616, whose hybrid migration follows W. Gong, Z. Cai, C. X. Ling, "DE/BBO: a hybrid
differential evolution with biogeography-based optimization", Soft Comput. 15 (2010) 645-665.

Habitats are ranked by cost; with k the number of habitats worse than habitat i, immigration
``lambda_i = I (1 - k / pop)`` and emigration ``mu_i = E k / pop``. Each coordinate of the trial:
with probability CR (at least one coordinate), it immigrates (probability lambda_i) from a habitat
chosen by roulette on mu, or else takes the DE/rand/1 mutant value (scale F); otherwise it keeps the
habitat's own value. BBO mutation then re-samples a coordinate uniformly with probability
``m_max (1 - P_k / P_max)``, where P_k is the equilibrium species-count probability (binomial in k for
linear rates with I = E). Greedy one-to-one selection. Paper 002: F = 0.7, CR = 0.8, I = E = 1,
m_max = 0.05.

Evaluations: ``population`` per generation (plus ``population`` initially).
"""

from __future__ import annotations

from math import lgamma
from typing import Any, ClassVar

import numpy as np

from .population import PopulationAlgorithm, greedy, rand_1
from .registry import register


def species_probability(pop: int) -> np.ndarray:
    """Equilibrium probability of species count k = 0..pop-1 over its maximum, shape ``(pop,)``."""
    m = pop - 1
    log_binom = np.array([lgamma(m + 1) - lgamma(k + 1) - lgamma(m - k + 1) for k in range(pop)])
    return np.exp(log_binom - log_binom.max())


@register("hbbo")
class HBBO(PopulationAlgorithm):
    """DE/BBO hybrid migration + BBO mutation.

    Options:
        F: DE mutation scale, default 0.7.
        CR: Crossover (migration) probability, default 0.8.
        I: Maximum immigration rate, default 1.
        E: Maximum emigration rate, default 1.
        m_max: Maximum mutation probability, default 0.05.
    """

    DEFAULTS: ClassVar[dict[str, Any]] = {"F": 0.7, "CR": 0.8, "I": 1.0, "E": 1.0, "m_max": 0.05}
    MIN_POPULATION: ClassVar[int] = 4

    def start(self) -> None:
        self.relative_p = species_probability(self.population)

    def propose(self) -> np.ndarray:
        o, pop, n, rng = self.options, self.population, self.n, self.rng
        k = np.empty(pop)
        k[np.argsort(self.F, kind="stable")] = np.arange(pop - 1, -1, -1)  # best habitat: k = pop - 1
        immigration = o["I"] * (1 - k / pop)
        emigration = o["E"] * k / pop
        source = rng.choice(pop, size=(pop, n), p=emigration / emigration.sum())
        migrated = np.where(
            rng.random((pop, n)) < immigration[:, None],
            self.X[source, np.arange(n)],
            rand_1(self.X, o["F"], rng),
        )
        change = rng.random((pop, n)) < o["CR"]
        change[np.arange(pop), rng.integers(0, n, pop)] = True
        trial = np.where(change, migrated, self.X)
        mutation = o["m_max"] * (1 - self.relative_p[k.astype(int)])
        mutate = rng.random((pop, n)) < mutation[:, None]
        return np.where(mutate, self.sample(pop), trial)

    def accept(self, X: np.ndarray, F: np.ndarray) -> None:
        greedy(self.X, self.F, X, F)
