"""Teaching-learning-based optimization (TLBO).

Reference: R. V. Rao, V. J. Savsani, D. P. Vakharia, "Teaching-learning-based optimization: A novel
method for constrained mechanical design optimization problems", Comput.-Aided Des. 43 (2011) 303-315.
Two phases per generation, each with greedy selection:

* teacher phase: ``x + r (teacher - TF * mean)``, teaching factor TF = round(1 + rand) in {1, 2};
* learner phase: learner i and a random partner j != i: ``x_i + r (x_i - x_j)`` if i is better,
  else ``x_i + r (x_j - x_i)``.

TLBO has no parameters. Evaluations: ``2 * population`` per generation (plus ``population`` initially).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from .population import PopulationAlgorithm, distinct_indices, greedy
from .registry import register


@register("tlbo")
class TLBO(PopulationAlgorithm):
    """TLBO (Rao et al. 2011). Subclasses vary :meth:`teaching_factor` and :meth:`learner_step`."""

    DEFAULTS: ClassVar[dict[str, Any]] = {}
    MIN_POPULATION: ClassVar[int] = 2
    phases: ClassVar[int] = 2

    def teaching_factor(self) -> np.ndarray:
        """Teaching factor per learner, shape ``(pop, 1)``: 1 or 2 at random."""
        return np.round(1 + self.rng.random((self.population, 1)))

    def learner_step(self) -> np.ndarray:
        """Learner-phase candidates, shape ``(pop, n)``."""
        j = distinct_indices(self.rng, self.population, 1)[:, 0]
        toward = np.where((self.F < self.F[j])[:, None], self.X - self.X[j], self.X[j] - self.X)
        return self.X + self.rng.random(self.X.shape) * toward

    def propose(self) -> np.ndarray:
        if self.phase == 0:
            teacher = self.X[self.best_index]
            mean = self.X.mean(axis=0)
            return self.X + self.rng.random(self.X.shape) * (teacher - self.teaching_factor() * mean)
        return self.learner_step()

    def accept(self, X: np.ndarray, F: np.ndarray) -> None:
        greedy(self.X, self.F, X, F)
