"""Solver registry: metaheuristics (name -> :class:`~framework.solvers.base.Algorithm` subclass, minimizing a
population cost) and IK solvers (name -> :class:`~framework.solvers.ik.IKSolver` subclass, solving a problem).

Adding a solver is one new module whose class is decorated with ``@register("name")`` (a metaheuristic) or
``@register_ik("name")`` plus one import line in ``framework/solvers/__init__.py``. Every metaheuristic is also
an IK solver (:class:`~framework.solvers.metaheuristic.Metaheuristic`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any, TypeVar

from framework.errors import SolverError

if TYPE_CHECKING:
    from framework.solvers.base import Algorithm

A = TypeVar("A", bound="type[Algorithm]")

#: Registered solvers, name -> algorithm class.
SOLVERS: dict[str, type[Algorithm]] = {}
#: Registered problem-level IK solvers, name -> class.
IK_SOLVERS: dict[str, type] = {}
#: IK solver instances by name and options (:func:`ik_solver`): a solver keeps no state between solves, only tables
#: derived from its options, so a loop that passes the same options to every solve reuses one instance instead of
#: validating them again (~12 µs a call, a third of a pose solve). Bounded: cleared beyond ``_MAX_INSTANCES``.
_INSTANCES: dict[tuple, object] = {}
_MAX_INSTANCES = 256


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

    Instances are made once per name and options (options of hashable values; others make a new instance)."""
    if name in IK_SOLVERS:
        key = _instance_key(name, options)
        made = _INSTANCES.get(key) if key is not None else None
        if made is None:
            made = IK_SOLVERS[name](options or None)
            if key is not None:
                if len(_INSTANCES) >= _MAX_INSTANCES:
                    _INSTANCES.clear()
                _INSTANCES[key] = made
        return made
    if name in SOLVERS:
        from .metaheuristic import Metaheuristic

        return Metaheuristic(name, options)
    raise SolverError(f"unknown solver {name!r}; available: {', '.join(solver_names())}")


def _instance_key(name: str, options: Any) -> tuple | None:
    """The key of ``name`` with ``options`` in the instance table, ``None`` when the options cannot be one (an
    unhashable value). A value's type is part of it: ``{"stall": 6.0}`` is not ``{"stall": 6}`` (which one is
    valid is the options' own check)."""
    if not options:
        return (name,)
    try:
        if isinstance(options, Mapping):
            key = (name, tuple(sorted((k, type(v), v) for k, v in options.items())))
        else:
            key = (name, type(options), options)
        hash(key)
    except TypeError:
        return None
    return key
