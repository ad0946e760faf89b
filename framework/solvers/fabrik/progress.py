"""When a FABRIK loop stops, and when it starts again from a new arm shape.

FABRIK with joint limits can stall: the limits hold the chain in a shape from which the passes no longer bring
the end-effector closer (a local minimum, well known for hinge constraints). The loop watches the error over a
sliding window of iterations; if it has not halved, the solver starts again from a new arm shape (a restart),
keeping the best configuration met so far, until its restarts run out.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .chain import PlanarChain


@dataclass
class Progress:
    """The error history of one solve and the decision taken after each iteration.

    Two phases. While restarts remain, an attempt that has not halved the error over ``window`` iterations is
    abandoned for a new arm shape (``"restart"``). When they run out, the solver goes back to the best state met
    (``"resume"``) and keeps iterating as long as the error still decreases at all over a window (slow
    convergence near a stretched chain is not a stall), up to ``max_iterations``.

    Attributes:
        tolerance: success threshold [m].
        max_iterations: cap on iterations over all attempts.
        window: iterations over which progress is judged.
        restarts: restarts allowed.
        history: error [m] at the start and after every iteration.
        since: index in ``history`` where the current attempt began.
        finishing: the restarts are spent and the best attempt is being finished.
    """

    tolerance: float
    max_iterations: int
    window: int
    restarts: int
    history: list[float] = field(default_factory=list)
    since: int = 0
    finishing: bool = False

    @property
    def iterations(self) -> int:
        return len(self.history) - 1

    def decide(self) -> str:
        """``"continue"``, ``"restart"``, ``"resume"``, or why to stop: ``"converged"``, ``"max_iterations"``,
        ``"stalled"``."""
        if self.history[-1] <= self.tolerance:
            return "converged"
        if self.iterations >= self.max_iterations:
            return "max_iterations"
        if len(self.history) - 1 - self.since < self.window:
            return "continue"
        before = self.history[-1 - self.window]
        if self.finishing:
            return "stalled" if self.history[-1] >= before * (1.0 - 1e-6) else "continue"
        if self.history[-1] <= 0.5 * before:
            return "continue"
        self.since = len(self.history) - 1
        if self.restarts > 0:
            self.restarts -= 1
            return "restart"
        self.finishing = True
        return "resume"


def random_shape(chain: PlanarChain, rng: np.random.Generator) -> tuple[list[float], list[float]]:
    """Plane points of a planar configuration drawn uniformly within the joints' limits."""
    q = chain.lower + (chain.upper - chain.lower) * rng.random(chain.size)
    points = chain.points(q)
    return points[:, 0].tolist(), points[:, 1].tolist()
