"""Hybrid of differential evolution and a modified PSO (DEMPSO).

Reference: B. Mao, Z. Xie, Y. Wang, H. Handroos, H. Wu, "A Hybrid Strategy of Differential Evolution
and Modified Particle Swarm Optimization for Numerical Solution of a Parallel Manipulator", Math. Probl.
Eng. 2018. Our reading of the hybrid, in two phases per generation:

1. DE phase: DE/rand/1/bin (F = 0.6, CR = 0.9, as DE in papers 001/002) evolves the personal-best
   memory; trials replace personal bests greedily.
2. MPSO phase: particles move with time-varying coefficients (linear over the iteration budget):
   inertia w 0.9 -> 0.6, cognitive c1 2.5 -> 0.5, social c2 0.5 -> 2.5 (paper 001). Paper 002 uses
   w 0.9 -> 0.1, c1 2 -> 0.1, c2 0.1 -> 2; pass those as options to reproduce it.

Velocities start at zero and are clamped to ``vmax = 0.2 * box width`` (our choice).

Evaluations: ``2 * population`` per generation (plus ``population`` for the initial swarm).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from .population import binomial_crossover, rand_1
from .registry import register
from .swarm import SwarmAlgorithm


@register("dempso")
class DEMPSO(SwarmAlgorithm):
    """DE on the personal bests, then a PSO move with time-varying coefficients.

    Options:
        F, CR: DE/rand/1/bin parameters, default 0.6 and 0.9.
        w_start, w_end: Inertia weight schedule, default 0.9 -> 0.6.
        c1_start, c1_end: Cognitive coefficient schedule, default 2.5 -> 0.5.
        c2_start, c2_end: Social coefficient schedule, default 0.5 -> 2.5.
        vmax: Velocity clamp as a fraction of the box width, default 0.2.
    """

    DEFAULTS: ClassVar[dict[str, Any]] = {
        "F": 0.6,
        "CR": 0.9,
        "w_start": 0.9,
        "w_end": 0.6,
        "c1_start": 2.5,
        "c1_end": 0.5,
        "c2_start": 0.5,
        "c2_end": 2.5,
        "vmax": 0.2,
    }
    MIN_POPULATION: ClassVar[int] = 4
    phases: ClassVar[int] = 2

    def propose(self) -> np.ndarray:
        o = self.options
        if self.phase == 0:
            return binomial_crossover(self.P, rand_1(self.P, o["F"], self.rng), o["CR"], self.rng)
        w = self.schedule(o["w_start"], o["w_end"])
        c1 = self.schedule(o["c1_start"], o["c1_end"])
        c2 = self.schedule(o["c2_start"], o["c2_end"])
        return self.velocity_step(w, c1, c2)

    def accept(self, X: np.ndarray, F: np.ndarray) -> None:
        if self.phase == 0:
            self.update_personal_bests(X, F)
        else:
            super().accept(X, F)
