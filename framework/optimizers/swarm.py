"""Shared machinery of the particle-swarm family (PSO, IMPSO, QPSO, DEMPSO).

:class:`SwarmAlgorithm` keeps particle positions ``X`` (pop, n), velocities ``V`` (pop, n), personal
bests ``P`` (pop, n) with costs ``PF`` (pop,), and the global best (best personal best). Subclasses
only say how particles move (:meth:`SwarmAlgorithm.propose`).
"""

from __future__ import annotations

import numpy as np

from .population import PopulationAlgorithm


class SwarmAlgorithm(PopulationAlgorithm):
    """Particles with personal bests. Velocities start at zero and are clamped to ``vmax * box width``
    when the subclass declares a ``vmax`` option."""

    def start(self) -> None:
        self.P = self.X.copy()
        self.PF = self.F.copy()
        self.V = np.zeros_like(self.X)
        self.vmax = self.options.get("vmax", np.inf) * self.box.width

    @property
    def global_best(self) -> np.ndarray:
        """Best personal best, shape ``(n,)``."""
        return self.P[int(np.argmin(self.PF))]

    def velocity_step(self, w: np.ndarray | float, c1: float, c2: float) -> np.ndarray:
        """Inertia-weight PSO move; updates ``V`` and returns the new positions, shape ``(pop, n)``.

        ``v <- w v + c1 r1 (p - x) + c2 r2 (g - x)``, ``x <- x + v``; ``w`` scalar or ``(pop,)``.
        """
        r1 = self.rng.random(self.X.shape)
        r2 = self.rng.random(self.X.shape)
        w = np.reshape(w, (-1, 1)) if np.ndim(w) else w
        V = w * self.V + c1 * r1 * (self.P - self.X) + c2 * r2 * (self.global_best - self.X)
        self.V = np.clip(V, -self.vmax, self.vmax)
        return self.X + self.V

    def accept(self, X: np.ndarray, F: np.ndarray) -> None:
        """Particles move to the evaluated positions; personal bests improve where ``F < PF``."""
        self.X, self.F = X.copy(), F.copy()
        self.update_personal_bests(X, F)

    def update_personal_bests(self, X: np.ndarray, F: np.ndarray) -> np.ndarray:
        """Replace personal bests where ``F < PF``; returns the mask of improved particles (pop,)."""
        better = F < self.PF
        self.P[better] = X[better]
        self.PF[better] = F[better]
        return better
