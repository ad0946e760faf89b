"""Solver registry: name -> :class:`~framework.solvers.base.Algorithm` subclass.

Adding a solver is one new module whose class is decorated with ``@register("name")`` plus one import
line in ``framework/solvers/__init__.py``.
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


def register(name: str) -> Callable[[A], A]:
    """Class decorator registering an algorithm under ``name`` (also sets its ``name`` attribute)."""

    def decorate(cls: A) -> A:
        if name in SOLVERS and SOLVERS[name] is not cls:
            raise SolverError(f"Solver name {name!r} is already registered by {SOLVERS[name].__name__}.")
        cls.name = name
        SOLVERS[name] = cls
        return cls

    return decorate


def available_solvers() -> list[str]:
    """Sorted names of the registered solvers."""
    return sorted(SOLVERS)


def get_solver(name: str) -> type[Algorithm]:
    """The algorithm class registered under ``name``; raises :class:`SolverError` listing the known names."""
    try:
        return SOLVERS[name]
    except (KeyError, TypeError):
        raise SolverError(f"Unknown solver {name!r}; available solvers: {available_solvers()}.") from None
