"""Solver registry: metaheuristics (name -> :class:`~framework.solvers.base.Algorithm` subclass, minimizing a
population cost) and IK solvers (name -> :class:`~framework.solvers.ik.IKSolver` subclass, solving a problem).

Adding a solver is one new module whose class is decorated with ``@register("name")`` (a metaheuristic) or
``@register_ik("name")`` plus one import line in ``framework/solvers/__init__.py``. Every metaheuristic is also
an IK solver (:class:`~framework.solvers.metaheuristic.Metaheuristic`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, TypeVar

from framework.errors import SolverError

if TYPE_CHECKING:
    from framework.solvers.base import Algorithm

A = TypeVar("A", bound="type[Algorithm]")

#: Registered solvers, name -> algorithm class.
SOLVERS: dict[str, type[Algorithm]] = {}
#: Registered problem-level IK solvers, name -> class.
IK_SOLVERS: dict[str, type] = {}
_DEFAULT_INSTANCES: dict[str, object] = {}  # an immutable cache: solvers keep no state between solves


def _registrar(table: dict, name: str) -> Callable[[A], A]:
    """A class decorator adding a class to ``table`` under ``name``: one name space over both tables."""

    def decorate(cls: A) -> A:
        for known in (SOLVERS, IK_SOLVERS):
            if name in known and known[name] is not cls:
                raise SolverError(f"Solver name {name!r} is already registered by {known[name].__name__}.")
        cls.name = name
        table[name] = cls
        return cls

    return decorate


def register(name: str) -> Callable[[A], A]:
    """Class decorator registering an algorithm under ``name`` (also sets its ``name`` attribute)."""
    return _registrar(SOLVERS, name)


def available_solvers() -> list[str]:
    """Sorted names of the registered solvers."""
    return sorted(SOLVERS)


def get_solver(name: str) -> type[Algorithm]:
    """The algorithm class registered under ``name``; raises :class:`SolverError` listing the known names."""
    try:
        return SOLVERS[name]
    except (KeyError, TypeError):
        raise SolverError(f"Unknown solver {name!r}; available solvers: {available_solvers()}.") from None


def register_ik(name: str) -> Callable[[A], A]:
    """Class decorator registering an :class:`~framework.solvers.ik.IKSolver` under ``name``."""
    return _registrar(IK_SOLVERS, name)


def solver_names() -> list[str]:
    """Every name :func:`framework.solve` accepts: the IK solvers, then the metaheuristics."""
    return sorted(IK_SOLVERS) + sorted(SOLVERS)


def ik_solver(name: str, options=None):
    """An IK solver instance for ``name`` with ``options``; raises :class:`SolverError` listing the names.

    Solvers hold nothing but their options, so the instance with default options is made once per name.
    """
    if name in IK_SOLVERS:
        if not options:
            if name not in _DEFAULT_INSTANCES:
                _DEFAULT_INSTANCES[name] = IK_SOLVERS[name](None)
            return _DEFAULT_INSTANCES[name]
        return IK_SOLVERS[name](options)
    if name in SOLVERS:
        from .metaheuristic import Metaheuristic

        return Metaheuristic(name, options)
    raise SolverError(f"unknown solver {name!r}; available: {', '.join(solver_names())}")
