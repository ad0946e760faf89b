"""The IK solvers' registry: name -> :class:`~framework.solvers.ik.IKSolver` subclass, solving a problem.

Adding an IK solver is one new module whose class is decorated with ``@register_ik("name")`` plus one import line in
``framework/solvers/__init__.py``. Every algorithm of the optimizers' registry (:mod:`framework.optimizers.registry`)
is an IK solver too (:class:`~framework.solvers.metaheuristic.Metaheuristic`); the two share one name space.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, TypeVar

from ..errors import SolverError
from ..optimizers.registry import ALGORITHMS, reserve
from .metaheuristic import Metaheuristic

A = TypeVar("A", bound=type)

#: Registered problem-level IK solvers, name -> class.
IK_SOLVERS: dict[str, type] = {}
#: IK solver instances by name and options (:func:`ik_solver`): a solver keeps no state between solves, only tables
#: derived from its options, so a loop that passes the same options to every solve reuses one instance instead of
#: validating them again (~12 µs a call, a third of a pose solve). Bounded: cleared beyond ``_MAX_INSTANCES``.
_INSTANCES: dict[tuple, object] = {}
_MAX_INSTANCES = 256


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
    if name in ALGORITHMS:
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
