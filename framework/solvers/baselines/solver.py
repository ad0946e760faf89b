"""``pinv`` and ``dls``: the papers' Jacobian baselines as solvers of the framework.

``solve(problem, "pinv")`` (or ``"dls"``) runs :func:`~framework.solvers.baselines.jacobian.jacobian_ik` on the problem's
task terms from the warm start (else the regularizers' reference, else the box middle) and returns the common
:class:`~framework.solvers.solve.IKResult`. The regularizers are not minimized (the methods know only the task), and there
are no restarts: these are the conventional methods the papers compare against — paper 001's closed-loop
pseudo-inverse (gain ``K``) and paper 003's pseudo-inverse and damped least squares with Buss's clamps
(``max_error`` 0.1 m, ``max_step`` 5°).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ...errors import SolverError
from ..ik import IKSolver, Outcome, Request
from ..multistart import start_configuration
from ..registry import register_ik
from .jacobian import dls_inverse, jacobian_ik, svd_pinv

#: Steps when the request names none.
DEFAULT_ITERATIONS = 1000


@dataclass(frozen=True)
class JacobianOptions:
    """Options of ``pinv`` and ``dls``.

    Attributes:
        gain: fraction ``K`` of the step taken (1: Gauss-Newton).
        rcond: ``pinv``: singular values below ``rcond · σ_max`` are dropped.
        damping: ``dls``: ``λ`` [m/rad] of ``Jᵀ (J Jᵀ + λ² I)⁻¹``.
        max_step: largest change of one coordinate per step [rad or m], or ``None`` (paper 003, after Buss:
            5° = 0.0873).
        max_error: the error is clamped to this length before the step [m], or ``None`` (paper 003: 0.1).
    """

    gain: float = 1.0
    rcond: float = 1e-6
    damping: float = 0.05
    max_step: float | None = None
    max_error: float | None = None

    def __post_init__(self) -> None:
        for name in ("gain", "rcond", "damping", "max_step", "max_error"):
            value = getattr(self, name)
            if value is None and name in ("max_step", "max_error"):
                continue
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 < value < math.inf:
                raise SolverError(f"Jacobian baseline option {name} must be a number > 0; got {value!r}")


#: Paper 003's settings, after Buss's code (lengths in metres for a ~0.5 m arm): ``solve(..., options=BUSS)``.
BUSS = JacobianOptions(rcond=0.01, damping=0.1, max_step=math.radians(5.0), max_error=0.1)


class JacobianBaseline(IKSolver):
    """Closed-loop Jacobian IK on the task terms, one inverse per subclass."""

    Options = JacobianOptions
    uses_jacobians = True
    kind = "Jacobian baseline"
    method: ClassVar[str] = ""

    def inverse_of(self, J: np.ndarray) -> np.ndarray:
        """``J⁺`` ``(n, m)`` of ``J`` ``(m, n)``."""
        raise NotImplementedError

    def solve(self, problem, request: Request) -> Outcome:
        x0, start = start_configuration(problem, request, True, closed_form=False)
        o = self.options
        cap = request.max_iterations or DEFAULT_ITERATIONS
        run = jacobian_ik(problem.program, x0, self.inverse_of, gain=o.gain, max_step=o.max_step,
                          max_error=o.max_error, tolerance=request.tolerance, angle_tolerance=request.angle_tolerance,
                          max_iterations=cap, deadline=request.deadline, callback=request.callback)
        settings = {**o.__dict__, "method": self.method, "start": start, "max_iterations": cap}
        return Outcome(run.x, run.stop, run.steps, run.evaluations, history=run.history, settings=settings)


@register_ik("pinv")
class PseudoInverse(JacobianBaseline):
    """``Δx = K J⁺ e``, ``J⁺`` the Moore-Penrose pseudo-inverse by SVD (small singular values dropped)."""

    reference = "Whitney 1969 (resolved motion rate); Buss 2004 (clamps); papers 001 and 003's baseline"
    method = "pinv"

    def inverse_of(self, J: np.ndarray) -> np.ndarray:
        return svd_pinv(J, self.options.rcond)


@register_ik("dls")
class DampedLeastSquares(JacobianBaseline):
    """``Δx = K Jᵀ (J Jᵀ + λ² I)⁻¹ e``."""

    reference = "Wampler 1986, Nakamura & Hanafusa 1986 (damped least squares); Buss 2004; paper 003's baseline"
    method = "dls"

    def inverse_of(self, J: np.ndarray) -> np.ndarray:
        return dls_inverse(J, self.options.damping)


#: The baselines by name.
JACOBIAN_BASELINES: dict[str, type[JacobianBaseline]] = {"pinv": PseudoInverse, "dls": DampedLeastSquares}
