"""Shared machinery of the population-based metaheuristics: the population loop and operators.

:class:`PopulationAlgorithm` keeps the population ``X`` (shape ``(pop, n)``) and its costs ``F``
(shape ``(pop,)``). Its first batch is the initial population (uniform in the box, the first rows
replaced by the warm-start points); after that each generation is ``phases`` batches, each produced
by :meth:`PopulationAlgorithm.propose` and consumed by :meth:`PopulationAlgorithm.accept`.
Subclasses vary only these two methods.

The operators (:func:`distinct_indices`, :func:`rand_1`, :func:`binomial_crossover`,
:func:`greedy`) are shared by DE, SDE, DEMPSO and HBBO.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from .base import Algorithm, Box


def seed_rows(X: np.ndarray, box: Box, initial: np.ndarray | None) -> np.ndarray:
    """Replace the first rows of the population ``X`` (pop, n) by the warm-start points, in place.

    Warm-start points beyond ``pop`` are ignored; points outside the box are clipped. Returns ``X``.
    """
    population = X.shape[0]
    if initial is not None:
        k = min(population, initial.shape[0])
        X[:k] = np.clip(initial[:k], box.lower, box.upper)
    return X


class PopulationAlgorithm(Algorithm):
    """Base of algorithms that keep a population ``X`` (pop, n) with costs ``F`` (pop,).

    Subclasses implement :meth:`propose` and :meth:`accept` and may use :attr:`phase`
    (``0 .. phases - 1``) to run several batches per generation; :meth:`start` hooks in after the
    initial population has been evaluated; :meth:`sample` (uniform by default) draws the initial
    population of :meth:`size` rows.
    """

    phases: ClassVar[int] = 1

    def setup(self) -> None:
        super().setup()
        self.X = np.empty((0, self.n))
        self.F = np.empty(0)
        self.phase = 0
        self._initialized = False
        self._complete = False

    @property
    def iteration_complete(self) -> bool:
        return self._complete

    @property
    def best_index(self) -> int:
        """Row of the best member of the current population."""
        return int(np.argmin(self.F))

    def size(self) -> int:
        """Rows of the kept population (``population`` unless the algorithm says otherwise)."""
        return self.population

    def sample(self, count: int) -> np.ndarray:
        """``count`` new random members, shape ``(count, n)``; uniform in the box by default."""
        return self.box.sample(self.rng, count)

    def ask(self) -> np.ndarray:
        if not self._initialized:
            return seed_rows(self.sample(self.size()), self.box, self.initial)
        return self.propose()

    def _tell(self, X: np.ndarray, F: np.ndarray) -> None:
        if not self._initialized:
            self.X, self.F = X.copy(), F.copy()
            self._initialized = True
            self._complete = False
            self.start()
            return
        self.accept(X, F)
        self.phase = (self.phase + 1) % self.phases
        self._complete = self.phase == 0
        if self._complete:
            self.generation += 1

    def start(self) -> None:
        """Called once after the initial population is evaluated (e.g. to set personal bests)."""

    def propose(self) -> np.ndarray:
        """Candidates of the current phase, shape ``(k, n)``."""
        raise NotImplementedError

    def accept(self, X: np.ndarray, F: np.ndarray) -> None:
        """Update the state with the evaluated candidates of the current phase."""
        raise NotImplementedError


def distinct_indices(rng: np.random.Generator, pop: int, k: int, rows: int | None = None) -> np.ndarray:
    """For each row ``i``, ``k`` mutually distinct population indices all different from ``i``.

    Returns shape ``(rows, k)`` (``rows`` defaults to ``pop``). Requires ``pop >= k + 1``.
    """
    rows = pop if rows is None else rows
    # A random permutation of the pop - 1 indices other than i, shifted past i.
    keys = rng.random((rows, pop - 1))
    idx = np.argsort(keys, axis=1)[:, :k]
    own = np.arange(rows)[:, None] % pop
    return idx + (idx >= own)


def rand_1(X: np.ndarray, scale: np.ndarray | float, rng: np.random.Generator) -> np.ndarray:
    """DE/rand/1 mutants ``X[r1] + scale (X[r2] - X[r3])``, shape (pop, n); scale: scalar or (pop,)."""
    r = distinct_indices(rng, X.shape[0], 3)
    scale = np.reshape(scale, (-1, 1)) if np.ndim(scale) else scale
    return X[r[:, 0]] + scale * (X[r[:, 1]] - X[r[:, 2]])


def binomial_crossover(
    target: np.ndarray, mutant: np.ndarray, cr: np.ndarray | float, rng: np.random.Generator
) -> np.ndarray:
    """Binomial crossover: each coordinate from ``mutant`` with probability CR, at least one per row.

    ``target``, ``mutant``: shape ``(pop, n)``; ``cr``: scalar or ``(pop,)``. Returns ``(pop, n)``.
    """
    pop, n = target.shape
    cr = np.reshape(cr, (-1, 1)) if np.ndim(cr) else cr
    mask = rng.random((pop, n)) < cr
    mask[np.arange(pop), rng.integers(0, n, pop)] = True
    return np.where(mask, mutant, target)


def greedy(X: np.ndarray, F: np.ndarray, X_new: np.ndarray, F_new: np.ndarray) -> np.ndarray:
    """One-to-one greedy selection in place: row ``i`` is replaced if ``F_new[i] <= F[i]``.

    Returns the boolean mask of replaced rows, shape ``(pop,)``.
    """
    better = F_new <= F
    X[better] = X_new[better]
    F[better] = F_new[better]
    return better
