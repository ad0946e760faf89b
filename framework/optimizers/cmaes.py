"""CMA-ES through pycma (``cma`` package): the (mu/mu_w, lambda)-CMA-ES of Hansen.

Reference: N. Hansen, "The CMA Evolution Strategy: A Tutorial", arXiv:1604.00772; pycma
(https://github.com/CMA-ES/pycma). Paper 000 uses the standard (mu, lambda)-CMA-ES with lambda = 30.

How pycma is driven:

* ``popsize = population`` (lambda), pycma's default weights, cumulation and step-size control, but
  ``CMA_active = False``: the standard (mu/mu_w, lambda)-CMA-ES of the tutorial and paper 000. The active
  (negative) update learns from the worst candidates, and with ``bounds="resample"`` those are uniform
  re-samples that the distribution never produced; with it on, a 13-D ellipsoid in a box stalled in 3 of
  8 runs (covariance condition -> 1e12). Turn it on with ``cma_options={"CMA_active": True}``.
* Start point ``x0 = initial[0]`` if warm-start points are given, else uniform in the box;
  ``sigma0 = 0.3 * mean(upper - lower)`` unless the ``sigma0`` option says otherwise. The warm-start
  points are also injected (``es.inject(..., force=True)``) so the first generation evaluates them.
* Randomness: pycma's ``randn`` option is replaced by ``rng.standard_normal``, so pycma never touches
  ``numpy.random``'s global state and runs are bitwise reproducible from the passed Generator.
* Bounds are *not* given to pycma: the shared loop repairs candidates (``bounds=`` of ``minimize``) and
  pycma is told the repaired points (it clips their Mahalanobis length, ``check_points=None``).
* Termination: ``es.stop()`` is never called, so none of pycma's termination criteria (tolfun, tolx,
  tolflatfitness, tolstagnation, ...) end a run early; the shared loop stops it. The remaining criteria
  that pycma also uses internally are set permissive (``maxiter``/``maxfevals`` infinite).

Evaluations: ``population`` per generation.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from ..errors import SolverError
from .base import Algorithm
from .registry import register


def start_point_and_step(algorithm: Algorithm) -> tuple[np.ndarray, float]:
    """CMA-ES start: mean ``x0`` (shape ``(n,)``) and step size ``sigma0``.

    ``x0`` is the first warm-start point, else uniform in the box; ``sigma0`` the ``sigma0`` option,
    else ``0.3 * mean(box width)``.
    """
    box = algorithm.box
    if algorithm.initial is not None:
        x0 = np.clip(algorithm.initial[0], box.lower, box.upper)
    else:
        x0 = box.sample(algorithm.rng, 1)[0]
    sigma0 = algorithm.options["sigma0"]
    sigma0 = 0.3 * float(np.mean(box.width)) if sigma0 is None else float(sigma0)
    if not (np.isfinite(sigma0) and sigma0 > 0):
        raise SolverError(f"{algorithm.name}: sigma0 must be a positive number, got {sigma0}.")
    return x0, sigma0


@register("cmaes")
class CMAES(Algorithm):
    """CMA-ES via ``cma.CMAEvolutionStrategy``.

    Options:
        sigma0: Initial step size; ``None`` = 0.3 * mean box width.
        cma_options: Extra pycma options (dict) merged over ours, e.g. ``{"CMA_active": True}``.
    """

    DEFAULTS: ClassVar[dict[str, Any]] = {"sigma0": None, "cma_options": None}
    MIN_POPULATION: ClassVar[int] = 2

    def setup(self) -> None:
        super().setup()
        import cma  # imported here: only this solver needs pycma

        x0, self.sigma0 = start_point_and_step(self)
        rng = self.rng
        opts: dict[str, Any] = {
            "popsize": self.population,
            "verbose": -9,
            "verb_log": 0,
            "verb_disp": 0,
            "seed": np.nan,  # no global seeding: randomness comes from `randn` below
            "randn": lambda *shape: rng.standard_normal(shape),
            "maxiter": np.inf,
            "maxfevals": np.inf,
            "CMA_active": False,
        }
        extra = self.options["cma_options"] or {}
        opts.update(extra)
        try:
            self.es = cma.CMAEvolutionStrategy(x0, self.sigma0, opts)
        except (ValueError, TypeError) as exc:
            raise SolverError(f"cmaes: pycma rejected the options {sorted(extra)}: {exc}") from exc
        if self.initial is not None:
            self.es.inject(list(self.initial[: self.population - 1]), force=True)

    @property
    def settings(self) -> dict[str, Any]:
        return {"sigma0": self.sigma0, "cma_options": self.options["cma_options"]}

    def ask(self) -> np.ndarray:
        return np.array(self.es.ask(), dtype=float)

    def _tell(self, X: np.ndarray, F: np.ndarray) -> None:
        # pycma works with finite values; an infinite cost ranks last anyway.
        finite = np.where(np.isfinite(F), F, np.finfo(float).max)
        self.es.tell(list(X), finite.tolist())
        self.generation += 1
