"""Compiling several entry points side by side: the first here, the others in a helper process.

numba compiles under a process-wide lock, one function at a time: a problem whose first solve needs two entry
points not yet in the disk cache (the reach loop and the Newton phase) waited for both in turn, on one core. Here
the other entry points compile in a helper process — the same interpreter, the same cache folder
(:mod:`framework.compiled.cache`) — while this process compiles the first; this process then loads them from the
cache. A machine with one core, a process that cannot start a helper (``METAIK_COMPILE_HELPER=0`` too), or a
helper that fails compile here instead, as without a helper.

The helper is ``python -m framework.compiled.parallel``; it reads the pickled ``(module, name, signature)`` jobs on
its standard input and compiles each with numba's own cache writing (an index and a data file per signature, each
written whole then renamed: a reader sees the old file or the new one).
"""

from __future__ import annotations

import importlib
import os
import pickle
import subprocess
import sys
import tempfile
from collections.abc import Sequence

from .cache import NOTICE, has_signature, package_name
from ..interrupts import stop_at_once

#: The environment variable that turns the helper off (``0``).
ENVIRONMENT = "METAIK_COMPILE_HELPER"


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def entry_points(jobs: Sequence[tuple[object, tuple]], callees: Sequence[tuple[object, tuple]] = ()) -> list:
    """The compiled entry point of each ``(dispatcher, args)`` job for the types of ``args`` (numba's
    ``dispatcher.compile``: loaded from the disk cache, else compiled), those not cached compiled side by side:
    the first here, the others in a helper process (list the longest compile first).

    ``callees``: ``(function, args)`` of large linked-only callees of the first job (:func:`framework.compiled.native.internal`,
    cached as bitcode), the first of them the largest. When the first job compiles, the helper takes that largest
    callee before its other jobs while this process compiles the other callees; the first job then compiles here
    with the callees loaded from the cache."""
    signatures = [_signature(dispatcher, args) for dispatcher, args in jobs]
    missing = [k for k, ((dispatcher, _), signature) in enumerate(zip(jobs, signatures))
               if not _ready(dispatcher, signature)]
    parts = []
    if missing[:1] == [0]:
        parts = [(_dispatcher(c), _signature(c, args)) for c, args in callees]
        parts = [(d, s) for d, s in parts if not _ready(d, s)]
    ahead = parts[:1] if parts and parts[0][0] is _dispatcher(callees[0][0]) else []
    beside = ahead + [(jobs[k][0], signatures[k]) for k in missing[1:]]
    helper = _start(beside) if beside else None
    if helper is None:
        ahead = []
    try:
        for dispatcher, signature in parts[len(ahead):] + ahead:  # the helper's callee compiles here if it fails
            if ahead and (dispatcher, signature) == ahead[0]:
                helper.wait(package_name(dispatcher), jobs=1)
            dispatcher.compile(signature)
        points = [None] * len(jobs)
        for k, (dispatcher, _) in enumerate(jobs):
            if helper is None or k not in missing[1:]:
                points[k] = dispatcher.compile(signatures[k])
        if helper is not None:
            helper.wait(", ".join(package_name(jobs[k][0]) for k in missing[1:]))
            for k in missing[1:]:
                points[k] = jobs[k][0].compile(signatures[k])
    except BaseException:  # Ctrl-C (or an error) here: the helper stops too
        if helper is not None:
            helper.stop()
        raise
    return points


def _dispatcher(function):
    """The numba dispatcher of a compiled function (a linked-only one's, :class:`framework.compiled.native.Internal`)."""
    return getattr(function, "dispatcher", function)


def _signature(function, args: tuple) -> tuple:
    dispatcher = _dispatcher(function)
    return tuple(dispatcher.typeof_pyval(a) for a in args)


def _ready(dispatcher, signature: tuple) -> bool:
    """Whether ``dispatcher`` has code for ``signature`` in this process or in the disk cache."""
    return signature in dispatcher.overloads or has_signature(dispatcher, signature)


class _Helper:
    """A helper process compiling jobs into the disk cache; it writes a line on its standard output as each job
    is done."""

    def __init__(self, process: subprocess.Popen, errors):
        self.process = process
        self.errors = errors
        self.done = 0
        self.ended = False

    def stop(self) -> None:
        """End the helper now (what it has cached stays)."""
        if not self.ended:
            self.ended = True
            self.process.kill()
            self.process.wait()
            self.process.stdout.close()
            self.errors.close()

    def wait(self, names: str, jobs: int | None = None) -> None:
        """Wait for the helper — for its first ``jobs`` jobs, or until it ends — the wait shown as a compile of
        ``names``; a failure is said on stderr (this process then compiles what the helper did not)."""
        if self.ended:
            return
        NOTICE.start(names, where="in a helper process")
        try:
            with stop_at_once():  # a Ctrl-C ends the wait at once (the helper is then stopped)
                code = self._wait(jobs)
            if code is None:
                return
        finally:
            NOTICE.end()
        self.ended = True
        self.process.stdout.close()
        if code:
            self.errors.seek(0)
            tail = self.errors.read().decode(errors="replace").strip().splitlines()[-3:]
            sys.stderr.write(f"metaik: the helper process compiling {names} failed (exit {code}): "
                             f"{' / '.join(tail)}; compiling here\n")
        self.errors.close()

    def _wait(self, jobs: int | None) -> int | None:
        """Wait for the first ``jobs`` jobs (``None``: they are done) or the helper's end (its exit code)."""
        while jobs is not None and self.done < jobs and self.process.stdout.readline():
            self.done += 1
        if jobs is not None and self.done >= jobs:
            return None
        return self.process.wait()


def _start(jobs: list[tuple[object, tuple]]) -> _Helper | None:
    """A helper process compiling ``(dispatcher, signature)`` jobs, or ``None`` where there is none to start."""
    if os.environ.get(ENVIRONMENT, "1") == "0" or _cores() < 2 or not sys.executable:
        return None
    try:
        payload = pickle.dumps([(d.py_func.__module__, d.py_func.__qualname__, s) for d, s in jobs])
    except (AttributeError, pickle.PicklingError):  # pragma: no cover - a signature numba cannot pickle
        return None
    errors = tempfile.TemporaryFile()
    try:
        process = subprocess.Popen([sys.executable, "-m", __name__], stdin=subprocess.PIPE,
                                   stdout=subprocess.PIPE, stderr=errors,
                                   env={**os.environ, "METAIK_COMPILE_NOTICE": "0", ENVIRONMENT: "0"},
                                   start_new_session=True)  # a Ctrl-C at the terminal is this process's to handle
    except OSError:  # pragma: no cover - no process to start here
        errors.close()
        return None
    try:
        process.stdin.write(payload)
        process.stdin.close()
    except OSError:  # it ended before reading its jobs: a failed helper, which its wait reports
        pass
    return _Helper(process, errors)


def main() -> None:
    """The helper: compile the jobs pickled on standard input."""
    for module, name, signature in pickle.loads(sys.stdin.buffer.read()):
        _dispatcher(getattr(importlib.import_module(module), name)).compile(signature)
        print("done", flush=True)


if __name__ == "__main__":
    main()
