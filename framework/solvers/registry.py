"""The IK solvers' registry: name -> :class:`~framework.solvers.ik.IKSolver` subclass, solving a problem.

Adding an IK solver is one new module whose class is decorated with ``@register_ik("name")`` plus one import line in
``framework/solvers/__init__.py``. Every algorithm of the optimizers' registry (:mod:`framework.optimizers.registry`)
is an IK solver too (:class:`~framework.solvers.metaheuristic.Metaheuristic`); the two share one name space.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import TypeVar

from ..errors import SolverError
from ..optimizers.registry import ALGORITHMS, reserve
from .metaheuristic import Metaheuristic

A = TypeVar("A", bound=type)

#: Registered problem-level IK solvers, name -> class.
IK_SOLVERS: dict[str, type] = {}


def register_ik(name: str) -> Callable[[A], A]:
    """Class decorator registering an :class:`~framework.solvers.ik.IKSolver` under ``name`` (also sets its
    ``name`` attribute); a name the optimizers' registry holds is refused."""

    def decorate(cls: A) -> A:
        reserve(name, cls)
        cls.name = name
        IK_SOLVERS[name] = cls
        return cls

    return decorate


def solver_names() -> list[str]:
    """Every name :func:`framework.solve` accepts: the IK solvers, then the metaheuristics."""
    return sorted(IK_SOLVERS) + sorted(ALGORITHMS)


def ik_solver(name: str, options=None):
    """An IK solver instance for ``name`` with ``options``; raises :class:`SolverError` listing the names.

    Instances are made once per name and options (:meth:`~framework.solvers.ik.IKSolver.instance`)."""
    if name in IK_SOLVERS:
        return IK_SOLVERS[name].instance(options)
    if name in ALGORITHMS:
        return Metaheuristic(name, options)
    raise SolverError(f"unknown solver {name!r}; available: {', '.join(solver_names())}")
