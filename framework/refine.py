"""Local refinement with Pinocchio's analytic Jacobians: the second phase of the hybrid solver.

From a starting configuration (the best of a global metaheuristic phase), the task terms (position,
orientation, relative position) become equality constraints ``r(x) = 0`` and the other terms (motion, ...)
the objective, solved by SLSQP within the search box; a few projected Gauss-Newton steps on the task residuals
then polish the error to machine precision. If the constraints cannot be met (a target out of reach), a
bounded Levenberg-Marquardt on the task residuals gets as close as it can. In parallel, L-BFGS-B minimizes the
whole objective as it stands (with weights too small to make reaching worth its motion, the optimum of ``f``
does not reach). The configuration returned is the best of the start and the refined points *by the
problem's own objective*, so refinement never makes it worse.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize as scipy_minimize

from .costs import JointLimitPenalty, Linearization, LocalKinematics, Orientation
from .problem import Problem


@dataclass(frozen=True)
class Refinement:
    """Outcome of :func:`refine`: configuration ``x`` ``(n,)``, its cost, task error and Jacobian evaluations."""

    x: np.ndarray
    cost: float
    task_error: float
    evaluations: int
    method: str


class _Residuals:
    """Every term linearized at one configuration (one kinematics call, cached per configuration): the stacked
    task residuals ``r(x)`` and Jacobians ``J(x)``, and the weighted objective's value and gradient."""

    def __init__(self, problem: Problem):
        self.problem = problem
        self.task = [t for _, t in problem.objective if t.is_task]
        self._is_task = problem.task_mask
        self._weights = problem.weights
        self.evaluations = 0
        self._key: bytes | None = None
        self._data = problem.robot.model.createData()

    def linearize(self, x: np.ndarray) -> list[Linearization]:
        """Each term of the objective at ``x``, in objective order."""
        key = x.tobytes()
        if key != self._key:
            robot = self.problem.robot
            local = LocalKinematics(robot, x, self._data)
            self._key, self._cache = key, [t.linearize(robot, x, local) for _, t in self.problem.objective]
            self.evaluations += 1
        return self._cache

    def r(self, x: np.ndarray) -> np.ndarray:
        return np.concatenate([lin.residual for lin, task in zip(self.linearize(x), self._is_task) if task])

    def J(self, x: np.ndarray) -> np.ndarray:
        return np.vstack([lin.jacobian for lin, task in zip(self.linearize(x), self._is_task) if task])

    def weighted(self, which: str):
        """``x -> (f, ∇f)`` of the weighted sum of ``"all"`` the terms or of the ``"regularizer"`` (non-task) ones."""
        weights = self._weights if which == "all" else np.where(self._is_task, 0.0, self._weights)
        active = [k for k, w in enumerate(weights) if w != 0.0]

        def fun(x: np.ndarray) -> tuple[float, np.ndarray]:
            terms = self.linearize(x)
            value, grad = 0.0, np.zeros_like(x)
            for k in active:
                value += weights[k] * terms[k].value
                grad += weights[k] * terms[k].gradient
            return value, grad

        return fun


def _reaching_is_optimal(problem: Problem, residuals: _Residuals, x: np.ndarray, tolerance: float) -> bool:
    """Whether ``x`` (task residuals zero) also minimizes the weighted objective locally (exact penalty).

    With multipliers ``λ`` of the constrained problem (``∇g = Jᵀλ``), a term ``w‖r‖`` is an exact penalty
    when ``‖λ_term‖ < w`` (``w/2`` for orientation, whose value is ``sin(φ/2) ≈ φ/2``). Points on the box
    boundary are not judged (``False``): the bound multipliers are not computed.
    """
    robot = problem.robot
    if np.linalg.norm(residuals.r(x)) >= max(tolerance, 1e-9):
        return False
    if np.any(x <= robot.lower) or np.any(x >= robot.upper):
        return False
    _, grad = residuals.weighted("regularizer")(x)
    lam = np.linalg.lstsq(residuals.J(x).T, grad, rcond=None)[0]
    start = 0
    for (weight, term), lin in zip(problem.objective, residuals.linearize(x)):
        if not term.is_task:
            continue
        size = len(lin.residual)
        limit = weight / 2 if isinstance(term, Orientation) else weight
        if np.linalg.norm(lam[start : start + size]) >= limit:
            return False
        start += size
    return True


def gauss_newton(
    residuals: _Residuals,
    x: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    *,
    steps: int,
    damping: float = 0.0,
    tolerance: float = 1e-15,
) -> np.ndarray:
    """Projected Gauss-Newton (``damping = 0``) or Levenberg-Marquardt on the task residuals.

    Steps are clipped to the box; stops at ``‖r‖ < tolerance``, when no step reduces ``‖r‖``, or when ten
    steps in a row gained less than 1 % (stuck in a local minimum or against a limit: better to restart).
    """
    r = residuals.r(x)
    checkpoint, since = np.linalg.norm(r), 0
    for _ in range(steps):
        J = residuals.J(x)
        if damping:
            dx = -J.T @ np.linalg.solve(J @ J.T + damping * np.eye(len(r)), r)
        else:
            dx = -np.linalg.lstsq(J, r, rcond=1e-12)[0]
        x_new = np.clip(x + dx, lower, upper)
        r_new = residuals.r(x_new)
        if not np.linalg.norm(r_new) < np.linalg.norm(r):
            if damping:
                damping *= 10.0
                if damping > 1e6:
                    break
                continue
            break
        x, r = x_new, r_new
        if damping:
            damping = max(damping / 10.0, 1e-12)
        norm = np.linalg.norm(r)
        if norm < tolerance:
            break
        since += 1
        if norm < 0.99 * checkpoint:
            checkpoint, since = norm, 0
        elif since >= 10:
            break
    return x


def _on_kink(problem: Problem, residuals: _Residuals, x: np.ndarray) -> bool:
    """Whether a non-task term with a residual view (a motion term) is exactly zero at ``x``: not differentiable."""
    terms = zip(problem.objective, residuals.linearize(x))
    return any(not t.is_task and lin.residual is not None and lin.value == 0.0 for (_, t), lin in terms)


def _constrained(
    problem: Problem, residuals: _Residuals, x0: np.ndarray, tolerance: float, max_iterations: int, callback=None
) -> list[tuple[np.ndarray, str]]:
    """SLSQP on the non-task terms subject to ``r(x) = 0`` in the box, Gauss-Newton polish; LM if that fails."""
    lower, upper = problem.robot.lower, problem.robot.upper
    if _on_kink(problem, residuals, x0):
        # A regularizer at zero (x0 = the previous configuration, say) has no gradient there, and SLSQP crawls
        # (≈90 iterations instead of ≈15): one minimum-norm Gauss-Newton step towards the task first.
        x0 = gauss_newton(residuals, x0, lower, upper, steps=1)
    slsqp = scipy_minimize(
        residuals.weighted("regularizer"),
        x0,
        jac=True,
        method="SLSQP",
        bounds=list(zip(lower, upper)),
        constraints=[{"type": "eq", "fun": residuals.r, "jac": residuals.J}],
        options={"maxiter": max_iterations, "ftol": 1e-12},
        callback=callback,
    )
    x = gauss_newton(residuals, np.clip(slsqp.x, lower, upper), lower, upper, steps=10)
    out = [(x, "slsqp+gauss-newton")]
    if not np.linalg.norm(residuals.r(x)) < tolerance:  # infeasible or stuck: get as close as possible
        x = gauss_newton(residuals, x0, lower, upper, steps=50, damping=1e-3, tolerance=tolerance)
        out.append((x, "levenberg-marquardt"))
    return out


def refine(
    problem: Problem,
    x0: np.ndarray,
    *,
    tolerance: float = 1e-12,
    max_iterations: int = 100,
    callback: Callable[[np.ndarray], object] | None = None,
) -> Refinement:
    """Refine ``x0`` locally: minimize the non-task terms subject to the task residuals being zero.

    Args:
        problem: the IK problem (its task terms need residual views: all shipped task terms have them).
        x0: starting configuration ``(n,)`` inside the search box.
        tolerance: task error [m or unitless] below which the Gauss-Newton polish stops.
        max_iterations: SLSQP iteration limit.
        callback: ``callback(x)`` after every SLSQP / L-BFGS-B iteration (recordings trace the terms with it).
    """
    robot = problem.robot
    lower, upper = robot.lower, robot.upper
    x0 = np.clip(np.asarray(x0, dtype=float), lower, upper)
    residuals = _Residuals(problem)
    candidates = [(x0, "start")]
    regularized = any(not t.is_task and not isinstance(t, JointLimitPenalty) for _, t in problem.objective)
    if residuals.task and not regularized:  # pure task (e.g. pose IK): Levenberg-Marquardt alone
        x = gauss_newton(residuals, x0, lower, upper, steps=max_iterations, damping=1e-6, tolerance=tolerance)
        candidates.append((x, "levenberg-marquardt"))
    elif residuals.task:
        # Task terms as constraints, the rest minimized: exact when the weights make the task a priority ...
        candidates += _constrained(problem, residuals, x0, tolerance, max_iterations, callback)
    if regularized and not _reaching_is_optimal(problem, residuals, candidates[-1][0], tolerance):
        # ... else the whole objective minimized as it stands: reaching costs more than it gains ...
        lbfgs = scipy_minimize(
            residuals.weighted("all"),
            x0,
            jac=True,
            method="L-BFGS-B",
            bounds=list(zip(lower, upper)),
            options={"maxiter": max_iterations},
            callback=callback,
        )
        x = np.clip(lbfgs.x, lower, upper)
        candidates.append((x, "l-bfgs-b"))
        if residuals.task:  # ... or the constrained solve failed from x0 but succeeds from closer in
            candidates += [(c, f"l-bfgs-b+{m}") for c, m in _constrained(problem, residuals, x, tolerance, max_iterations, callback)]
    X = np.array([c[0] for c in candidates])
    evaluation = problem.evaluate(X)
    best = int(np.argmin(evaluation.cost))
    return Refinement(
        X[best], float(evaluation.cost[best]), float(evaluation.task_error[best]), residuals.evaluations, candidates[best][1]
    )
