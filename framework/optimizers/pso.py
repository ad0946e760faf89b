"""Particle swarm optimization with a constant inertia weight.

Reference: Y. Shi and R. Eberhart, "A modified particle swarm optimizer", IEEE ICEC 1998, 69-73 (the
inertia-weight form of J. Kennedy and R. Eberhart's PSO, 1995). Paper 002 settings: c1 = 1.1312,
c2 = 2.0149, w = 0.53514. Velocities start at zero and are clamped to ``vmax = 0.2 * box width``
(our choice; the paper does not give one).

Evaluations: ``population`` per generation (plus ``population`` for the initial swarm).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from .registry import register
from .swarm import SwarmAlgorithm


@register("pso")
class PSO(SwarmAlgorithm):
    """Inertia-weight PSO with global-best topology.

    Options:
        w: Inertia weight, default 0.53514.
        c1: Cognitive coefficient, default 1.1312.
        c2: Social coefficient, default 2.0149.
        vmax: Velocity clamp as a fraction of the box width, default 0.2.
    """

    DEFAULTS: ClassVar[dict[str, Any]] = {"w": 0.53514, "c1": 1.1312, "c2": 2.0149, "vmax": 0.2}

    def propose(self) -> np.ndarray:
        o = self.options
        return self.velocity_step(o["w"], o["c1"], o["c2"])
