"""Ctrl-C as a request that loops check between steps, so it never lands inside library code that swallows it
(pycma has bare ``except:`` clauses): the first SIGINT sets a flag, a second one raises ``KeyboardInterrupt``."""

from __future__ import annotations

import signal
from collections.abc import Iterator
from contextlib import contextmanager


class Interrupt:
    """SIGINT handler: the first signal sets ``requested`` (finish the step in flight, then stop); a second
    raises ``KeyboardInterrupt`` at once, and so does a first one while ``at_once`` is above zero (set by
    :func:`stop_at_once` around steps that last seconds with nothing to finish, e.g. a compile)."""

    def __init__(self) -> None:
        self.requested = False
        self.at_once = 0

    def __call__(self, signum, frame) -> None:
        if self.requested or self.at_once:
            self.requested = True
            raise KeyboardInterrupt
        self.requested = True


@contextmanager
def stop_at_once() -> Iterator[None]:
    """A block a Ctrl-C stops at once even inside :func:`graceful_interrupt` (its handler raises
    ``KeyboardInterrupt`` instead of setting a flag the block would only read after it ends)."""
    handler = signal.getsignal(signal.SIGINT)
    if not isinstance(handler, Interrupt):
        yield
        return
    handler.at_once += 1
    try:
        yield
    finally:
        handler.at_once -= 1


@contextmanager
def graceful_interrupt() -> Iterator[Interrupt]:
    """Route SIGINT to an :class:`Interrupt` for the block. Nested blocks share the outer one (a bench stopping
    a solve stops the bench too); outside the main thread signals cannot be caught and the flag stays unset."""
    current = signal.getsignal(signal.SIGINT)
    if isinstance(current, Interrupt):
        yield current
        return
    flag = Interrupt()
    try:
        previous = signal.signal(signal.SIGINT, flag)
    except ValueError:  # not the main thread: no signal handling
        yield flag
        return
    try:
        yield flag
    finally:
        signal.signal(signal.SIGINT, previous)
