"""Improved teaching-learning-based optimization (ITLBO).

Paper 001 names ITLBO (its ref. 19, lost in the text extraction) without details. We implement the
improvements of R. V. Rao and V. Patel, "An improved teaching-learning-based optimization algorithm for
solving unconstrained optimization problems", Scientia Iranica 20(3) (2013) 710-720, on top of
:class:`~framework.optimizers.tlbo.TLBO`:

* adaptive teaching factor: instead of a random 1 or 2, ``TF_i = 1 + (f_i - f_best) / (f_worst - f_best)``
  in [1, 2] (weak learners are pulled harder), a rank-free form of Rao & Patel's ratio rule;
* learning through tutorial: the learner phase adds the teacher's pull,
  ``x_i + r1 (x_i - x_j or x_j - x_i) + r2 (teacher - E_F x_i)``, with exploration factor
  E_F = round(1 + rand).

Rao & Patel's multiple-teacher grouping and self-motivated learning are not included.
Evaluations: ``2 * population`` per generation (plus ``population`` initially).
"""

from __future__ import annotations

import numpy as np

from .registry import register
from .tlbo import TLBO


@register("itlbo")
class ITLBO(TLBO):
    """TLBO with an adaptive teaching factor and learning through tutorial. No parameters."""

    def teaching_factor(self) -> np.ndarray:
        spread = float(np.max(self.F) - np.min(self.F))
        if not np.isfinite(spread) or spread <= 0:
            return np.ones((self.population, 1))
        return (1 + (self.F - np.min(self.F)) / spread)[:, None]

    def learner_step(self) -> np.ndarray:
        teacher = self.X[self.best_index]
        exploration = np.round(1 + self.rng.random((self.population, 1)))
        return super().learner_step() + self.rng.random(self.X.shape) * (teacher - exploration * self.X)
