"""Improved PSO with a set of inertia weights (IMPSO).

Paper 000 (Table 3, its ref. [17]: Abdor-Sierra et al., Results Eng. 16 (2022) 100597) gives IMPSO as
PSO with the inertia-weight set w_i in {0.2, 0.4, ..., 2.0} and c1 = c2 = 1.4962, without the update
rule. Our reading: each particle carries one weight of the set (initially assigned in turn); a
particle that fails to improve its personal best in a generation draws a new weight uniformly from the
set, one that improves keeps it. Velocities start at zero and are clamped to ``vmax = 0.2 * box width``
(our choice: weights above 1 would otherwise diverge).

Evaluations: ``population`` per generation (plus ``population`` for the initial swarm).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from .registry import register
from .swarm import SwarmAlgorithm


@register("impso")
class IMPSO(SwarmAlgorithm):
    """PSO whose particles pick their inertia weight from a set.

    Options:
        weights: The inertia-weight set, default (0.2, 0.4, ..., 2.0).
        c1: Cognitive coefficient, default 1.4962.
        c2: Social coefficient, default 1.4962.
        vmax: Velocity clamp as a fraction of the box width, default 0.2.
    """

    DEFAULTS: ClassVar[dict[str, Any]] = {
        "weights": tuple(round(0.2 * k, 1) for k in range(1, 11)),
        "c1": 1.4962,
        "c2": 1.4962,
        "vmax": 0.2,
    }

    def start(self) -> None:
        super().start()
        self.weights = np.asarray(self.options["weights"], dtype=float)
        self.choice = np.arange(self.population) % self.weights.size

    def propose(self) -> np.ndarray:
        o = self.options
        return self.velocity_step(self.weights[self.choice], o["c1"], o["c2"])

    def accept(self, X: np.ndarray, F: np.ndarray) -> None:
        self.X, self.F = X.copy(), F.copy()
        improved = self.update_personal_bests(X, F)
        redraw = ~improved
        self.choice[redraw] = self.rng.integers(0, self.weights.size, int(redraw.sum()))
