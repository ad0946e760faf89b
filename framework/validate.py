"""Shape checks of user input shared by the API and the task files: a list of names, a table, a table's keys
and value types. Each raises our error naming the field (the caller adds the file and table)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from .errors import SolverError, TaskError

#: Arrays up to this many entries are tested for NaN and inf in Python: ``np.isfinite(a).all()`` costs ~1 µs of
#: dispatch, more than the test itself on a configuration or a target.
SMALL = 64


def all_finite(a: np.ndarray) -> bool:
    """Whether every entry of the float array ``a`` (any shape) is finite."""
    return all(map(math.isfinite, a.ravel().tolist())) if a.size <= SMALL else bool(np.isfinite(a).all())


_FLOAT = np.dtype(np.float64)


def float_copy(a: Any) -> np.ndarray:
    """A float64 copy of ``a`` (same shape, C-contiguous): a float64 array's own copy method, anything else through
    ``np.array`` (whose dtype keyword costs ~0.2 µs a call: a pose solve makes three such copies)."""
    return a.copy() if type(a) is np.ndarray and a.dtype is _FLOAT else np.array(a, dtype=float)


#: A task-file value kind -> (Python types, how the message says it). Booleans are not numbers here.
KINDS: dict[str, tuple[tuple[type, ...], str]] = {
    "text": ((str,), "a string"),
    "integer": ((int,), "an integer"),
    "number": ((int, float), "a number"),
    "bool": ((bool,), "true or false"),
    "list": ((list, tuple), "a list"),
    "table": ((dict,), "a table"),
    "names": ((list, tuple), "a list of names"),
    "folders": ((list, tuple, dict), "a list of folders or a table {package name = folder}"),
}


def names(value: Any, what: str, error: type[Exception] = TaskError) -> tuple[str, ...]:
    """``value`` as a tuple of names; a lone string or anything but a list of strings raises ``error``."""
    if isinstance(value, (str, bytes)) or not isinstance(value, Sequence) \
            or not all(isinstance(v, str) for v in value):
        raise error(f"{what} must be a list of names; got {value!r}")
    return tuple(value)


def table(value: Any, what: str, error: type[Exception] = TaskError) -> Mapping:
    """``value`` if it is a mapping (a TOML table / dict), else ``error`` naming ``what``."""
    if not isinstance(value, Mapping):
        raise error(f"{what} must be a table (name = value, ...); got {value!r}")
    return value


def check_table(values: Mapping[str, Any], schema: Mapping[str, str], where: str) -> None:
    """Every key of ``values`` is in ``schema`` and its value of the schema's kind (see :data:`KINDS`);
    raises :class:`TaskError` naming ``where`` and the key."""
    unknown = sorted(set(values) - set(schema))
    if unknown:
        raise TaskError(f"{where} has unknown keys {unknown}; known: {sorted(schema)}")
    for key, value in values.items():
        types, said = KINDS[schema[key]]
        ok = isinstance(value, types) and not (isinstance(value, bool) and schema[key] in ("integer", "number"))
        if ok and schema[key] == "names":
            ok = all(isinstance(v, str) for v in value)
        if not ok:
            raise TaskError(f"{where} {key} must be {said}; got {value!r}")


def positive_int(value: Any, what: str, *, minimum: int = 1, maximum: int | None = None) -> int:
    """``value`` as an int in ``[minimum, maximum]``; raises :class:`SolverError` naming ``what``."""
    if type(value) is int and value >= minimum and (maximum is None or value <= maximum):  # the common case
        return value
    if isinstance(value, bool) or not isinstance(value, (int, np.integer, float, np.floating)) \
            or not np.isfinite(value) or value != int(value) or int(value) < minimum:
        raise SolverError(f"{what} must be an integer >= {minimum}; got {value!r}")
    if maximum is not None and int(value) > maximum:
        raise SolverError(f"{what} must be at most {maximum:,}; got {int(value):,}")
    return int(value)


def suggest(name: object, known: Sequence[str]) -> str:
    """``"; did you mean ..."`` (up to three close names) or ``"; known: ..."`` (up to twelve), for an error
    naming ``name`` that is not among ``known``."""
    import difflib

    close = difflib.get_close_matches(str(name), list(known), n=3)
    if close:
        return f"; did you mean {', '.join(map(repr, close))}?"
    shown = ", ".join(map(repr, list(known)[:12]))
    return f"; known: {shown}{', ...' if len(known) > 12 else ''}"
