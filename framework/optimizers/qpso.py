"""Quantum-behaved particle swarm optimization (QPSO).

References: J. Sun, B. Feng, W. Xu, "Particle swarm optimization with particles having quantum
behavior", IEEE CEC 2004, 325-331; used for IK by S. Dereli and R. Koker, Artif. Intell. Rev. 53 (2020)
949-964 (paper 000, ref. [20]). Each particle moves to
``x = p +- beta |mbest - x| ln(1/u)`` with the local attractor ``p = phi P_i + (1 - phi) g``
(phi, u ~ U(0, 1) per coordinate), ``mbest`` the mean of the personal bests, and the
contraction-expansion coefficient beta decreasing linearly from beta1 = 1.0 to beta0 = 0.5 over the
iteration budget (paper 000: beta0 = 0.5, beta1 = 1.0).

Evaluations: ``population`` per generation (plus ``population`` for the initial swarm).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from .registry import register
from .swarm import SwarmAlgorithm


@register("qpso")
class QPSO(SwarmAlgorithm):
    """QPSO with a linearly decreasing contraction-expansion coefficient.

    Options:
        beta0: Final contraction-expansion coefficient, default 0.5.
        beta1: Initial contraction-expansion coefficient, default 1.0.
    """

    DEFAULTS: ClassVar[dict[str, Any]] = {"beta0": 0.5, "beta1": 1.0}

    def propose(self) -> np.ndarray:
        beta = self.schedule(self.options["beta1"], self.options["beta0"])
        shape = self.X.shape
        phi = self.rng.random(shape)
        attractor = phi * self.P + (1 - phi) * self.global_best
        u = 1.0 - self.rng.random(shape)  # in (0, 1]
        sign = np.where(self.rng.random(shape) < 0.5, -1.0, 1.0)
        mbest = self.P.mean(axis=0)
        return attractor + sign * beta * np.abs(mbest - self.X) * np.log(1.0 / u)
