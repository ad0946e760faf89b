"""Chaotic artificial bee colony with modification rate (CPABC).

Paper 000 (Table 3, its ref. [21]) compares a "chaotic and parallelized ABC" with limit L = 40,
modification rate MR = 0.8 and scaling factor SF = 0.6. We implement:

* the modified ABC of B. Akay and D. Karaboga, "A modified Artificial Bee Colony algorithm for
  real-parameter optimization", Inf. Sci. 192 (2012) 120-142: a bee changes each coordinate j of its
  source with probability MR (at least one), ``v_j = x_j + phi (x_j - x_kj)``, phi ~ U(-SF, SF), k a
  random other source; greedy selection; onlookers pick sources with probability proportional to the
  fitness ``1 / (1 + f)`` (``1 + |f|`` for f < 0);
* chaos as in B. Alatas, "Chaotic bee colony algorithms for global numerical optimization", Expert
  Syst. Appl. 37 (2010) 5682-5687: the initial sources and the scouts' new sources come from the
  logistic map ``c <- 4 c (1 - c)`` scaled to the box;
* the scout: the source with the most failed trials, once above L, is replaced (at most one per
  generation); its new position is evaluated in the next employed phase and accepted unconditionally.

"Parallelized" in ref. [21] concerns running colonies in parallel; with a population-vectorized cost
this gives no different search and is not reproduced.

``population`` bees: ``SN = population // 2`` employed bees (one per food source) and
``population - SN`` onlookers. Evaluations: ``population`` per generation (plus SN initially).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from .population import PopulationAlgorithm
from .registry import register

#: Logistic-map iterations discarded after seeding, so the sequence forgets its uniform start.
CHAOS_WARMUP = 20


def logistic_map(c: np.ndarray, steps: int) -> np.ndarray:
    """Iterate the fully chaotic logistic map ``c <- 4 c (1 - c)`` ``steps`` times (elementwise)."""
    for _ in range(steps):
        c = 4.0 * c * (1.0 - c)
    return c


@register("cpabc")
class CPABC(PopulationAlgorithm):
    """Chaotic modified ABC.

    Options:
        limit: Failed trials before a source is abandoned (L), default 40.
        MR: Modification rate, default 0.8.
        SF: Scaling factor of phi, default 0.6.
    """

    DEFAULTS: ClassVar[dict[str, Any]] = {"limit": 40, "MR": 0.8, "SF": 0.6}
    MIN_POPULATION: ClassVar[int] = 4
    phases: ClassVar[int] = 2

    def size(self) -> int:
        return self.population // 2

    def sample(self, count: int) -> np.ndarray:
        """Chaotic sources: logistic-map sequences scaled to the box, shape ``(count, n)``."""
        c = self.rng.uniform(0.01, 0.99, (count, self.n))
        c = logistic_map(c, CHAOS_WARMUP)
        return self.box.lower + np.clip(c, 0.0, 1.0) * self.box.width

    def start(self) -> None:
        self.trials = np.zeros(self.size(), dtype=int)
        self._scout = -1

    def neighbour_moves(self, sources: np.ndarray) -> np.ndarray:
        """Modified-ABC candidates around ``X[sources]`` (k,), shape ``(k, n)``."""
        k, sn, n = sources.size, self.size(), self.n
        partner = (sources + self.rng.integers(1, sn, k)) % sn  # a random other source
        change = self.rng.random((k, n)) < self.options["MR"]
        change[np.arange(k), self.rng.integers(0, n, k)] = True
        phi = self.rng.uniform(-self.options["SF"], self.options["SF"], (k, n))
        x = self.X[sources]
        return np.where(change, x + phi * (x - self.X[partner]), x)

    def propose(self) -> np.ndarray:
        sn = self.size()
        if self.phase == 0:
            self._sources = np.arange(sn)
            V = self.neighbour_moves(self._sources)
            if self._scout >= 0:
                V[self._scout] = self.sample(1)[0]
            return V
        fitness = np.where(self.F >= 0, 1.0 / (1.0 + self.F), 1.0 + np.abs(self.F))
        fitness = np.where(np.isfinite(fitness), fitness, 0.0)
        p = fitness / fitness.sum() if fitness.sum() > 0 else np.full(sn, 1.0 / sn)
        self._sources = self.rng.choice(sn, size=self.population - sn, p=p)
        return self.neighbour_moves(self._sources)

    def accept(self, X: np.ndarray, F: np.ndarray) -> None:
        sources = self._sources
        # Best candidate per source (several onlookers may work on the same source).
        order = np.lexsort((F, sources))
        first = np.ones(order.size, dtype=bool)
        first[1:] = sources[order][1:] != sources[order][:-1]
        rows, targets = order[first], sources[order][first]
        better = F[rows] <= self.F[targets]
        if self.phase == 0 and self._scout >= 0:
            better[targets == self._scout] = True
        won = targets[better]
        self.X[won], self.F[won] = X[rows[better]], F[rows[better]]
        np.add.at(self.trials, sources, 1)
        self.trials[won] = 0
        if self.phase == 1:
            worst = int(np.argmax(self.trials))
            self._scout = worst if self.trials[worst] > self.options["limit"] else -1
            if self._scout >= 0:
                self.trials[self._scout] = 0
