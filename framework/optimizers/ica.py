"""Imperialist competitive algorithm (ICA).

Reference: E. Atashpaz-Gargari and C. Lucas, "Imperialist competitive algorithm: an algorithm for
optimization inspired by imperialistic competition", IEEE CEC 2007, 4661-4667, in the common form of
the Yarpiz reference implementation whose parameter names paper 002 uses (10 imperialists, selection
pressure alpha = 1, assimilation coefficient beta = 1.5).

* Empires: the best ``n_imperialists`` countries are imperialists; the colonies are shared out with
  probability ``exp(-alpha c_k / max c)`` of the imperialists' costs.
* Each generation every colony moves toward its imperialist, ``x + beta U(0, 1) (imp - x)``, and
  with probability ``revolution_probability`` a fraction ``revolution_rate`` of its coordinates gets a
  Gaussian kick (sd = 0.1 box width); each imperialist proposes such a revolution of itself, kept if
  better. A colony better than its imperialist takes its place.
* Imperialistic competition: the total cost ``c_imp + zeta mean(c_colonies)`` ranks the empires; a
  random colony of the weakest empire goes to an empire drawn with probability
  ``exp(-alpha total / max total)`` (weakest excluded); an empire without colonies collapses and its
  imperialist becomes a colony of the winner.

Evaluations: ``population`` per generation (all colonies plus one revolution per imperialist; plus
``population`` initially).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from .population import PopulationAlgorithm
from .registry import register


def pressure_weights(costs: np.ndarray, alpha: float) -> np.ndarray:
    """Selection probabilities ``exp(-alpha c / max|c|)`` normalized to sum 1, shape of ``costs``."""
    finite = np.where(np.isfinite(costs), costs, np.nan)
    scale = np.nanmax(np.abs(finite)) if np.any(np.isfinite(finite)) else 1.0
    weights = np.exp(-alpha * np.nan_to_num(finite, nan=np.inf) / max(scale, 1e-300))
    total = weights.sum()
    return weights / total if total > 0 else np.full(costs.shape, 1.0 / costs.size)


@register("ica")
class ICA(PopulationAlgorithm):
    """Imperialist competitive algorithm.

    Options:
        n_imperialists: Number of initial empires, default 10 (at most population // 2).
        alpha: Selection pressure, default 1.
        beta: Assimilation coefficient, default 1.5.
        revolution_probability: Probability that a colony revolts, default 0.05.
        revolution_rate: Fraction of coordinates changed by a revolution, default 0.1.
        zeta: Weight of the colonies' mean cost in an empire's total cost, default 0.2.
    """

    DEFAULTS: ClassVar[dict[str, Any]] = {
        "n_imperialists": 10,
        "alpha": 1.0,
        "beta": 1.5,
        "revolution_probability": 0.05,
        "revolution_rate": 0.1,
        "zeta": 0.2,
    }
    MIN_POPULATION: ClassVar[int] = 2

    def start(self) -> None:
        pop = self.population
        order = np.argsort(self.F, kind="stable")
        self.X, self.F = self.X[order], self.F[order]
        n_imp = max(1, min(int(self.options["n_imperialists"]), pop // 2))
        # owner[i] = row of the imperialist of country i (imperialists own themselves)
        self.owner = np.arange(pop)
        shares = pressure_weights(self.F[:n_imp], self.options["alpha"])
        self.owner[n_imp:] = self.rng.choice(n_imp, size=pop - n_imp, p=shares)

    @property
    def imperialists(self) -> np.ndarray:
        return np.flatnonzero(self.owner == np.arange(self.population))

    def revolution(self, X: np.ndarray, rows: np.ndarray) -> np.ndarray:
        """Gaussian kick of a random ``revolution_rate`` fraction of coordinates of ``X[rows]``, in place."""
        count = rows.size
        if count == 0:
            return X
        n_changed = max(1, int(np.ceil(self.options["revolution_rate"] * self.n)))
        keys = self.rng.random((count, self.n))
        chosen = keys <= np.sort(keys, axis=1)[:, n_changed - 1 : n_changed]
        kick = 0.1 * self.box.width * self.rng.standard_normal((count, self.n))
        X[rows] = X[rows] + kick * chosen
        return X

    def propose(self) -> np.ndarray:
        o, pop = self.options, self.population
        colony = self.owner != np.arange(pop)
        step = o["beta"] * self.rng.random(self.X.shape) * (self.X[self.owner] - self.X)
        X = self.X + step * colony[:, None]
        revolt = np.flatnonzero(colony & (self.rng.random(pop) < o["revolution_probability"]))
        return self.revolution(X, np.concatenate([revolt, self.imperialists]))

    def accept(self, X: np.ndarray, F: np.ndarray) -> None:
        pop = self.population
        colony = self.owner != np.arange(pop)
        improved_imp = ~colony & (F < self.F)
        keep = colony | improved_imp
        self.X[keep], self.F[keep] = X[keep], F[keep]
        self._promote_best_colonies()
        self._compete()

    def _promote_best_colonies(self) -> None:
        """Swap each imperialist with its best colony if that colony is better."""
        for imp in self.imperialists:
            members = np.flatnonzero(self.owner == imp)
            best = members[np.argmin(self.F[members])]
            if best != imp:
                self.X[[imp, best]] = self.X[[best, imp]]
                self.F[[imp, best]] = self.F[[best, imp]]

    def _compete(self) -> None:
        """Move one colony of the weakest empire to another empire (or collapse the weakest)."""
        imps = self.imperialists
        if imps.size < 2:
            return
        total = np.empty(imps.size)
        for e, imp in enumerate(imps):
            colonies = np.flatnonzero((self.owner == imp) & (np.arange(self.population) != imp))
            mean = self.F[colonies].mean() if colonies.size else 0.0
            total[e] = self.F[imp] + self.options["zeta"] * mean
        total = np.where(np.isfinite(total), total, np.finfo(float).max)
        weakest = int(np.argmax(total))
        others = np.delete(np.arange(imps.size), weakest)
        winner = imps[
            others[self.rng.choice(others.size, p=pressure_weights(total[others], self.options["alpha"]))]
        ]
        loser = imps[weakest]
        colonies = np.flatnonzero((self.owner == loser) & (np.arange(self.population) != loser))
        if colonies.size:
            self.owner[colonies[self.rng.integers(colonies.size)]] = winner
        else:
            self.owner[loser] = winner
