"""A compact numpy (mu/mu_w, lambda)-CMA-ES, the same algorithm as ``cmaes`` without pycma's overhead.

Reference: N. Hansen, "The CMA Evolution Strategy: A Tutorial", arXiv:1604.00772 (2016/2023), with the
tutorial's default parameters (positive weights only, c_m = 1, rank-one + rank-mu update, cumulative
step-size adaptation with the h_sigma stall). pycma's ask/tell costs about 0.65 ms per iteration, which
dominates the run time on cheap costs; this module runs one generation in a few tens of microseconds.

Differences from pycma's defaults (so outcomes are equivalent, not bitwise equal): no active
(negative) covariance update, no mirrored sampling, lazy eigendecomposition as in the tutorial's
``purecma``. Candidates the loop repaired and injected warm-start points are handled as pycma does:
their step ``y = (x - m) / sigma`` is shortened to Mahalanobis length at most
``sqrt(n) + 2 n / (n + 2)`` before the update.

Start point and step size as ``cmaes``: ``x0 = initial[0]`` (else uniform in the box),
``sigma0 = 0.3 * mean box width``; the warm-start points replace the first samples of generation 1.

Evaluations: ``population`` per generation.
"""

from __future__ import annotations

from typing import Any, ClassVar, NamedTuple

import numpy as np

from ..costs.kernels import population_cost
from ..errors import SolverError
from ..compiled.native import compiled, internal
from .base import Algorithm
from .cmaes import start_point_and_step
from .registry import register

#: Condition number of C above which it is regularized, and relative floor of its eigenvalues.
MAX_CONDITION = 1e14


class Distribution(NamedTuple):
    """The search distribution's arrays, updated in place: mean, evolution paths (σ's and C's), covariance ``C``,
    its eigenvectors ``B`` and the square roots of its eigenvalues ``D``, and the recombination weights."""

    mean: np.ndarray
    ps: np.ndarray
    pc: np.ndarray
    C: np.ndarray
    B: np.ndarray
    D: np.ndarray
    weights: np.ndarray


class Constants(NamedTuple):
    """The strategy's constants (Hansen's tutorial): learning rates, damping, expected norm, the longest step of a
    foreign candidate, the largest σ, and λ."""

    cs: float
    cc: float
    c1: float
    cmu: float
    mueff: float
    damps: float
    chi_n: float
    max_step: float
    max_sigma: float
    population: int


@register("cmaes_fast")
class CMAESFast(Algorithm):
    """Numpy (mu/mu_w, lambda)-CMA-ES (Hansen's tutorial defaults).

    Options:
        sigma0: Initial step size; ``None`` = 0.3 * mean box width.
        covariance: Initial covariance matrix ``(n, n)`` (symmetric positive definite; ``None`` = identity),
            e.g. the :attr:`state` of a run on the previous waypoint: its adapted shape, scaled to a largest
            eigenvalue of 1, so that ``sigma0`` is the step along the widest axis.
    """

    DEFAULTS: ClassVar[dict[str, Any]] = {"sigma0": None, "covariance": None}
    MIN_POPULATION: ClassVar[int] = 2

    def setup(self) -> None:
        super().setup()
        n, lam = self.n, self.population
        self.mean, self.sigma = start_point_and_step(self)
        self.sigma0 = self.sigma
        mu = lam // 2
        w = np.log((lam + 1) / 2) - np.log(np.arange(1, mu + 1))
        self.weights = w / w.sum()
        self.mueff = 1.0 / np.sum(self.weights**2)
        mueff = self.mueff
        self.cc = (4 + mueff / n) / (n + 4 + 2 * mueff / n)
        self.cs = (mueff + 2) / (n + mueff + 5)
        self.c1 = 2 / ((n + 1.3) ** 2 + mueff)
        self.cmu = min(1 - self.c1, 2 * (mueff - 2 + 1 / mueff) / ((n + 2) ** 2 + mueff))
        self.damps = 1 + 2 * max(0.0, np.sqrt((mueff - 1) / (n + 1)) - 1) + self.cs
        self.chi_n = np.sqrt(n) * (1 - 1 / (4 * n) + 1 / (21 * n**2))
        self.max_step = np.sqrt(n) + 2 * n / (n + 2)
        self.pc = np.zeros(n)
        self.ps = np.zeros(n)
        self.C = np.eye(n)
        self.B = np.eye(n)
        self.D = np.ones(n)
        self._eigen_generation = 0
        if self.options["covariance"] is not None:
            self.C = _check_covariance(self.options["covariance"], n)
            self._update_eigensystem()
        self._asked = np.empty((0, n))
        self._max_sigma = 1e3 * float(np.max(self.box.width))

    @property
    def settings(self) -> dict[str, Any]:
        given = self.options["covariance"] is not None
        return {"sigma0": self.sigma0, "covariance": "given" if given else None, "mu": self.weights.size,
                "mueff": self.mueff}

    @property
    def state(self) -> dict[str, Any]:
        """``{"covariance": C / λ_max(C)}``: the adapted shape of the search distribution."""
        C = 0.5 * (self.C + self.C.T)
        return {"covariance": C / float(np.linalg.eigvalsh(C)[-1])}

    def ask(self) -> np.ndarray:
        """``lambda`` samples ``m + sigma B D z``, shape ``(lambda, n)``."""
        z = self.rng.standard_normal((self.population, self.n))
        X = _sample(self.mean, self.sigma, self.B, self.D, z)
        if self.generation == 0 and self.initial is not None:
            k = min(self.population - 1, self.initial.shape[0])
            X[:k] = self.initial[:k]
        self._asked = X
        return X.copy()

    def _tell(self, X: np.ndarray, F: np.ndarray) -> None:
        # One compiled update (Hansen's tutorial, eq. 37-48): at lambda = 30 in 13-D, numpy call overhead would
        # be the cost.
        order = np.argsort(F, kind="stable")[: self.weights.size]
        asked = self._asked if self._asked.shape == X.shape else np.full_like(X, np.nan)
        g = self.generation + 1
        self.sigma, hsig = _update(X, asked, order, self._distribution(), self.sigma, self._constants(), float(g))
        self.generation = g
        if g - self._eigen_generation > self.population / (self.c1 + self.cmu) / self.n / 10:
            self._update_eigensystem()

    def run_compiled(self, program, repair_mode: str, max_iterations: int) -> tuple[np.ndarray, float, np.ndarray,
                                                                                      int]:
        """The whole ask/tell loop compiled, on a packed problem (:class:`~framework.costs.Program`): the same
        generations as :func:`~framework.optimizers.base.minimize` with this algorithm (same random numbers, same
        repairs, same updates), without its Python overhead per generation. No callback, no other stop rule.

        Returns ``(best x, best f, history (iterations,), evaluations)``; the algorithm's state is updated.
        """
        mode = {"resample": 0, "clip": 1, "none": 2}[repair_mode]
        initial = np.zeros((0, self.n)) if self.initial is None else self.initial
        best_x = np.empty(self.n)
        history = np.empty(max_iterations)
        program.refresh()
        box = self.box
        out = _run(self.rng, program.packed, box.lower, box.upper, mode, max_iterations, initial, self._distribution(),
                   self._constants(), self.sigma, best_x, history)
        best_f, self.sigma, evaluations, self.generation, self._eigen_generation = out
        return best_x, best_f, history, evaluations

    def _distribution(self) -> Distribution:
        return Distribution(self.mean, self.ps, self.pc, self.C, self.B, self.D, self.weights)

    def _constants(self) -> Constants:
        return Constants(float(self.cs), float(self.cc), float(self.c1), float(self.cmu), float(self.mueff),
                         float(self.damps), float(self.chi_n), float(self.max_step), float(self._max_sigma),
                         int(self.population))

    def _update_eigensystem(self) -> None:
        """Refresh ``B``, ``D`` from ``C`` (symmetrized, regularized above ``MAX_CONDITION``)."""
        self._eigen_generation = self.generation
        self.C = 0.5 * (self.C + self.C.T)
        eigvals, B = np.linalg.eigh(self.C)
        top = max(float(eigvals[-1]), 1e-300)
        if eigvals[0] < top / MAX_CONDITION:
            self.C += (top / MAX_CONDITION - min(float(eigvals[0]), 0.0)) * np.eye(self.n)
            eigvals, B = np.linalg.eigh(self.C)
        self.B, self.D = B, np.sqrt(np.maximum(eigvals, 1e-300))


def _check_covariance(C: Any, n: int) -> np.ndarray:
    """A copy of ``C`` as a symmetric positive-definite ``(n, n)`` matrix; raises :class:`SolverError`."""
    C = np.array(C, dtype=float)
    if C.shape != (n, n) or not np.all(np.isfinite(C)):
        raise SolverError(f"cmaes_fast: covariance must be a finite ({n}, {n}) matrix, got shape {C.shape}.")
    if not np.allclose(C, C.T, rtol=1e-10, atol=1e-14 * np.abs(C).max()):
        raise SolverError("cmaes_fast: covariance must be symmetric.")
    if np.linalg.eigvalsh(C)[0] <= 0:
        raise SolverError("cmaes_fast: covariance must be positive definite.")
    return 0.5 * (C + C.T)


@compiled
def _sample(mean, sigma, B, D, z):
    """``m + sigma B D z`` for each row ``z`` of ``z (lambda, n)``.

    Each sum ``Σ_j (B_ij D_j) z_kj`` is accumulated in ``j`` order, all ``i`` at once (the inner loop over ``i`` runs
    along a row of ``(BD)ᵀ`` and vectorizes; the sums are the same, term by term)."""
    lam, n = z.shape
    X = np.empty((lam, n))
    BDt = np.empty((n, n))  # (B D)ᵀ: row j holds column j of B D
    for i in range(n):
        for j in range(n):
            BDt[j, i] = B[i, j] * D[j]
    acc = np.empty(n)
    for k in range(lam):
        acc[:] = 0.0
        for j in range(n):
            zk = z[k, j]
            row = BDt[j]
            for i in range(n):
                acc[i] += row[i] * zk
        for i in range(n):
            X[k, i] = mean[i] + sigma * acc[i]
    return X


@internal
def _inv_sqrt(B, D, y, out):
    """``out = C^{-1/2} y = B D⁻¹ Bᵀ y``."""
    n = y.shape[0]
    t = np.empty(n)
    for j in range(n):
        s = 0.0
        for i in range(n):
            s += B[i, j] * y[i]
        t[j] = s / D[j]
    for i in range(n):
        s = 0.0
        for j in range(n):
            s += B[i, j] * t[j]
        out[i] = s


@compiled
def _update(X, asked, order, state, sigma, k, g):
    """The CMA-ES update from told candidates ``X`` (in place on the :class:`Distribution` ``state``'s ``mean, ps,
    pc, C``; ``k``: :class:`Constants`); returns the new sigma and h_sigma. Candidates that differ from the
    ``asked`` ones (repaired, injected) have their step ``y = (x − m)/σ`` shortened to Mahalanobis length
    ``max_step``, as pycma does."""
    mean, ps, pc, C, B, D, w = state
    cs, cc, c1, cmu, mueff, damps, chi_n, max_step, max_sigma = k.cs, k.cc, k.c1, k.cmu, k.mueff, k.damps, k.chi_n, \
        k.max_step, k.max_sigma
    mu, n = order.shape[0], X.shape[1]
    y_sel = np.empty((mu, n))
    tmp = np.empty(n)
    for a in range(mu):
        k = order[a]
        foreign = False
        for i in range(n):
            y_sel[a, i] = (X[k, i] - mean[i]) / sigma
            if X[k, i] != asked[k, i]:
                foreign = True
        if foreign:
            _inv_sqrt(B, D, y_sel[a], tmp)
            length = np.sqrt(np.sum(tmp * tmp))
            if length > max_step:
                for i in range(n):
                    y_sel[a, i] *= max_step / length
    y_w = np.zeros(n)
    for a in range(mu):
        for i in range(n):
            y_w[i] += w[a] * y_sel[a, i]
    for i in range(n):
        mean[i] += sigma * y_w[i]
    _inv_sqrt(B, D, y_w, tmp)
    kps = np.sqrt(cs * (2 - cs) * mueff)
    for i in range(n):
        ps[i] = (1 - cs) * ps[i] + kps * tmp[i]
    ps_norm = np.sqrt(np.sum(ps * ps))
    hsig = ps_norm / np.sqrt(1 - (1 - cs) ** (2 * g)) / chi_n < 1.4 + 2 / (n + 1)
    kpc = np.sqrt(cc * (2 - cc) * mueff)
    for i in range(n):
        pc[i] = (1 - cc) * pc[i] + (kpc * y_w[i] if hsig else 0.0)
    decay = 1 - c1 - cmu + (0.0 if hsig else c1 * cc * (2 - cc))
    S = np.zeros((n, n))  # Σ_a (w_a y_ai) y_aj, accumulated in a order, a row of j at a time (vectorizes)
    for a in range(mu):
        ya = y_sel[a]
        for i in range(n):
            wy = w[a] * ya[i]
            row = S[i]
            for j in range(n):
                row[j] += wy * ya[j]
    for i in range(n):
        for j in range(n):
            C[i, j] = decay * C[i, j] + c1 * pc[i] * pc[j] + cmu * S[i, j]
    new = sigma * np.exp((cs / damps) * (ps_norm / chi_n - 1))
    return min(max(new, 1e-300), max_sigma), hsig


@internal
def _eigensystem(C, B, D):
    """``B, D`` from ``C`` (symmetrized, regularized above ``MAX_CONDITION``), as ``_update_eigensystem``."""
    n = C.shape[0]
    for i in range(n):
        for j in range(i + 1, n):
            v = 0.5 * (C[i, j] + C[j, i])
            C[i, j] = v
            C[j, i] = v
    eigvals, vectors = np.linalg.eigh(C)
    top = max(eigvals[-1], 1e-300)
    if eigvals[0] < top / MAX_CONDITION:
        shift = top / MAX_CONDITION - min(eigvals[0], 0.0)
        for i in range(n):
            C[i, i] += shift
        eigvals, vectors = np.linalg.eigh(C)
    for i in range(n):
        for j in range(n):
            B[i, j] = vectors[i, j]
    for i in range(n):
        D[i] = np.sqrt(max(eigvals[i], 1e-300))


@compiled
def _run(rng, packed, lower, upper, mode, max_iterations, initial, state, consts, sigma, best_x, history):
    """``max_iterations`` generations of ask / repair / evaluate / tell (see :meth:`CMAESFast.run_compiled`).

    Returns ``(best f, sigma, evaluations, generation, eigen generation)``; the :class:`Distribution` ``state`` is
    updated in place (``consts``: :class:`Constants`), ``best_x`` and ``history`` written."""
    mean, B, D, C = state.mean, state.B, state.D, state.C
    lam, c1, cmu = consts.population, consts.c1, consts.cmu
    n = mean.shape[0]
    best_f = np.inf
    evaluations, generation, eigen_generation = 0, 0, 0
    F = np.empty(lam)
    for iteration in range(max_iterations):
        z = rng.standard_normal((lam, n))
        X = _sample(mean, sigma, B, D, z)
        if generation == 0 and initial.shape[0] > 0:
            for k in range(min(lam - 1, initial.shape[0])):
                X[k] = initial[k]
        asked = X.copy()
        if mode != 2:  # repair: rows out of the box resampled whole (mode 0), or clipped (mode 1)
            for k in range(lam):
                bad = False
                for i in range(n):
                    v = X[k, i]
                    if mode == 0 and not (lower[i] <= v <= upper[i]):
                        bad = True
                    elif mode == 1:
                        if not np.isfinite(v):
                            bad = True
                        elif v < lower[i]:
                            X[k, i] = lower[i]
                        elif v > upper[i]:
                            X[k, i] = upper[i]
                if bad:
                    u = rng.random(n)
                    for i in range(n):
                        X[k, i] = lower[i] + u[i] * (upper[i] - lower[i])
        population_cost(X, packed, F)
        for k in range(lam):
            if np.isnan(F[k]):
                F[k] = np.inf
        evaluations += lam
        i_best = np.argmin(F)
        if F[i_best] < best_f:
            best_f = F[i_best]
            for i in range(n):
                best_x[i] = X[i_best, i]
        order = np.argsort(F, kind="mergesort")[: state.weights.shape[0]]
        generation += 1
        sigma, hsig = _update(X, asked, order, state, sigma, consts, float(generation))
        if generation - eigen_generation > lam / (c1 + cmu) / n / 10:
            eigen_generation = generation
            _eigensystem(C, B, D)
        history[iteration] = best_f
    return best_f, sigma, evaluations, generation, eigen_generation
