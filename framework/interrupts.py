"""Ctrl-C as a request that loops check between steps, so it never lands inside library code that swallows it
(pycma has bare ``except:`` clauses): the first SIGINT sets a flag, a second one raises ``KeyboardInterrupt``."""

from __future__ import annotations

import signal
from collections.abc import Iterator
from contextlib import contextmanager


class Interrupt:
    """SIGINT handler: the first signal sets ``requested`` (finish the step in flight, then stop); a second
    raises ``KeyboardInterrupt`` at once, and so does a first one while ``at_once`` is above zero (set by
    :func:`stop_at_once` around waits that last seconds with nothing to finish, e.g. for a compile helper)."""

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
def held_interrupt() -> Iterator[Interrupt | None]:
    """A block during which a Ctrl-C is held as a request (an :class:`Interrupt`, the one in place or a new one)
    for the block to act on at its safe points, and raised as ``KeyboardInterrupt`` at its end if it did not —
    for numba's compiles, where a ``KeyboardInterrupt`` raised inside LLVM's callbacks is lost and leaves numba's
    state broken. ``None`` where SIGINT is not Python's default (ignored, or someone else's) or not this thread's."""
    handler = signal.getsignal(signal.SIGINT)
    if isinstance(handler, Interrupt):
        yield handler
        return
    if handler is not signal.default_int_handler:
        yield None
        return
    flag = Interrupt()
    try:
        signal.signal(signal.SIGINT, flag)
    except ValueError:  # not the main thread
        yield None
        return
    try:
        yield flag
    finally:
        signal.signal(signal.SIGINT, handler)
    if flag.requested:
        raise KeyboardInterrupt


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
