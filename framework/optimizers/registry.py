"""The optimizers' registry: name -> :class:`~framework.optimizers.base.Algorithm` subclass.

Adding an algorithm is one new module whose class is decorated with ``@register("name")`` plus one import line in
``framework/optimizers/__init__.py``. The IK solvers have a registry of their own (:mod:`framework.solvers.registry`),
which offers every algorithm named here as an IK solver too.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

from ..errors import SolverError

A = TypeVar("A", bound=type)

#: Registered algorithms, name -> class.
ALGORITHMS: dict[str, type] = {}
#: Names other registries sharing this name space hold (the IK solvers: :func:`reserve`), name -> class.
RESERVED: dict[str, type] = {}


def register(name: str) -> Callable[[A], A]:
    """Class decorator registering an algorithm under ``name`` (also sets its ``name`` attribute)."""

    def decorate(cls: A) -> A:
        _refuse_taken(name, cls)
        cls.name = name
        ALGORITHMS[name] = cls
        return cls

    return decorate


def reserve(name: str, cls: type) -> None:
    """Hold ``name`` for ``cls`` of a registry sharing this name space; a name already taken is refused."""
    _refuse_taken(name, cls)
    RESERVED[name] = cls


def _refuse_taken(name: str, cls: type) -> None:
    for known in (ALGORITHMS, RESERVED):
        if name in known and known[name] is not cls:
            raise SolverError(f"Solver name {name!r} is already registered by {known[name].__name__}.")


def available_solvers() -> list[str]:
    """Sorted names of the registered algorithms."""
    return sorted(ALGORITHMS)


def get_solver(name: str) -> type:
    """The algorithm class registered under ``name``; raises :class:`SolverError` listing the known names."""
    try:
        return ALGORITHMS[name]
    except (KeyError, TypeError):
        raise SolverError(f"Unknown solver {name!r}; available solvers: {available_solvers()}.") from None
