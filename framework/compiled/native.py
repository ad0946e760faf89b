"""What every compiled function of the package shares: how it is compiled, raw views of memory, calls by address.

**Compiling.** :func:`compiled` makes a function numba-compiled and callable from Python; :func:`internal` one
called only from compiled code (no Python wrapper is built for it: a third less to compile). Both are cached on
disk (:mod:`framework.compiled.cache` keys the cache by content) and use NumPy's floating-point error model: a
division by zero gives ``inf`` or ``nan`` as in C instead of raising, so a division compiles to a division, not to
a branch with a Python exception. Nothing is inlined at numba's level (``inline="always"`` typed and lowered each
callee again at every call site: half of a cold start's compile time went there); LLVM inlines the small callees
it sees in the linked module by itself.

**Views without owners.** Numba counts references to every array it passes around (two atomic operations per
array per call). Compiled loops therefore work on *views* made from raw addresses (:func:`view`, :func:`borrow`,
:func:`take`): arrays without an owner, valid while the memory they view is kept alive by its owner (an argument
of the entry point, or a local the kernel keeps to its end with :func:`keep_alive`).

**Records.** The compiled data of a solve (a workspace, a phase's state) are numpy records holding the addresses
and sizes of their arrays, passed to every function as one pointer (a call passing arrays passes each one's dozen
fields: ~3 ns per array, and the engine's calls carried twenty). A record's arrays are views made on entry.

**Calls by address.** :func:`call` calls a compiled C callback (a block kind's kernel: :mod:`framework.costs.kinds`)
through its address with a record: the caller's machine code does not hold the callee's, so each kernel is compiled
once, only when a problem uses its kind, and the engine once for every kind.

A call through numba's dispatcher resolves the types of every argument first (~1-2 µs); Python callers whose
argument types are fixed resolve the compiled entry point once (:func:`compiled_entry`) and call it directly.
"""

from __future__ import annotations

import functools

import numba
import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic, typeof_impl

from . import linked
from .cache import cached

#: numba's options for every compiled function of the package (see the module docstring); each is cached on disk
#: by :func:`framework.compiled.cache.cached`.
OPTIONS = {"error_model": "numpy"}


def compiled(function=None, **options):
    """``function`` compiled by numba with :data:`OPTIONS` (and ``options``), callable from Python."""
    if function is None:
        return lambda f: compiled(f, **options)
    return _one_type_per_value(cached(numba.njit(**OPTIONS, **options)(function)))


def internal(function=None, *, inline: bool = False):
    """``function`` compiled by numba with :data:`OPTIONS`, callable only from compiled code: linked into each
    caller, which compiles it to machine code (:mod:`framework.compiled.linked`; cached as bitcode). A call from
    Python raises :class:`TypeError` (it has no Python entry point).

    ``inline``: LLVM inlines it into every caller (``alwaysinline``: numba's ``forceinline``; typed and lowered once,
    unlike numba's ``inline="always"``) — for small helpers on the hot path whose call costs more than their body
    (views of a record's arrays, most of which the caller drops once inlined; a sine and cosine)."""
    if function is None:
        return lambda f: internal(f, inline=inline)
    options = dict(OPTIONS, no_cpython_wrapper=True, no_cfunc_wrapper=True, forceinline=inline)
    if not linked.available():  # pragma: no cover - a numba without the code library linked.py relies on
        return Internal(_one_type_per_value(cached(numba.njit(**options)(function))))
    return Internal(_one_type_per_value(cached(numba.njit(**options, pipeline_class=linked.PIPELINE)(function),
                                               linked_only=True)))


class Internal:
    """A compiled function for compiled callers only (:func:`internal`): compiled code calls its dispatcher
    (numba types it as that dispatcher), Python gets a :class:`TypeError` instead of a call through a null
    address."""

    def __init__(self, dispatcher):
        self.dispatcher = dispatcher
        functools.update_wrapper(self, dispatcher.py_func)

    def __call__(self, *args, **kwargs):
        raise TypeError(f"{self.__module__}.{self.__qualname__} is compiled for compiled callers only: it has no "
                        f"Python entry point")


@typeof_impl.register(Internal)
def _typeof_internal(value, context):
    return types.Dispatcher(value.dispatcher)


def _one_type_per_value(dispatcher):
    """``dispatcher`` compiled for the non-literal types of its arguments when compiled code calls it: numba
    compiles a callee again for each constant ``0``, ``-1``, ``True`` a caller passes (its *literal* types), each
    a compile of its own."""
    typed = dispatcher.get_call_template

    def get_call_template(args, kws):
        return typed(tuple(types.unliteral(a) for a in args), {k: types.unliteral(v) for k, v in kws.items()})

    dispatcher.get_call_template = get_call_template
    return dispatcher


def compiled_entry(dispatcher, args: tuple):
    """The compiled entry point of the numba function ``dispatcher`` for the types of ``args`` (loaded from the
    disk cache or compiled on first use, as a dispatched call would). A call through it skips the per-call type
    resolution and does not check its arguments: the caller must pass arguments of exactly these types (dtypes,
    dimensions, layouts, read-only flags, scalar kinds) on every call."""
    return dispatcher.compile(tuple(dispatcher.typeof_pyval(a) for a in args))


@intrinsic
def pointer(typingctx, address):
    """The integer ``address`` as a ``void*``."""

    def codegen(context, builder, signature, args):
        return builder.inttoptr(args[0], cgutils.voidptr_t)

    return types.voidptr(address), codegen


@intrinsic
def call(typingctx, address, record):
    """``int64 f(record)`` for the compiled C callback ``f`` at ``address`` (a numba record is passed as its
    pointer)."""
    if not isinstance(record, types.Record):  # pragma: no cover - a programming error, caught at compile time
        return None

    def codegen(context, builder, signature, args):
        function = ir.FunctionType(ir.IntType(64), [args[1].type])
        return builder.call(builder.inttoptr(args[0], function.as_pointer()), [args[1]])

    return types.int64(address, record), codegen


@internal(inline=True)
def view(address, shape, dtype):
    """A C-contiguous array of ``shape`` (an int or a tuple) and ``dtype`` at ``address``, without an owner."""
    return numba.carray(pointer(address), shape, dtype)


@internal(inline=True)
def record_at(address, dtype):
    """The record of ``dtype`` (a numpy structured dtype) at ``address``."""
    return numba.carray(pointer(address), 1, dtype)[0]


@internal(inline=True)
def address_of(a) -> int:
    """The address of ``a``'s first element, as an int64 (as :func:`take` counts addresses from 0: one type for
    both)."""
    return np.int64(a.ctypes.data)


@internal(inline=True)
def borrow(a):
    """A view of the C-contiguous array ``a`` without an owner (valid while ``a`` is alive)."""
    return numba.carray(pointer(a.ctypes.data), a.shape, a.dtype)


#: Bytes of one float64 / int64 entry: every region :func:`take` carves is a whole number of them.
WORD = 8


@internal(inline=True)
def take(at, shape):
    """``(view, next)``: a float64 array of ``shape`` at address ``at`` (without an owner), and the address after it.

    Scratch laid out by consecutive takes from one allocation's address: the same function, run from address 0
    (nothing is read or written), gives the allocation's size (``next`` at its end), so a layout is written once."""
    a = numba.carray(pointer(at), shape, np.float64)
    return a, at + WORD * a.size


@internal(inline=True)
def take_int(at, shape):
    """:func:`take` for an int64 array."""
    a = numba.carray(pointer(at), shape, np.int64)
    return a, at + WORD * a.size


@internal(inline=True)
def take_flags(at, shape):
    """:func:`take` for a boolean array (its region rounded up to whole words)."""
    a = numba.carray(pointer(at), shape, np.bool_)
    return a, at + WORD * ((a.size + WORD - 1) // WORD)


@internal(inline=True)
def square(buffer, k):
    """A ``(k, k)`` view (without an owner) of the first ``k²`` entries of the flat ``buffer`` (a ``reshape`` would
    call into numba's runtime on every use; a ``[:k, :k]`` slice would be strided)."""
    return numba.carray(pointer(buffer.ctypes.data), (k, k), np.float64)


@internal(inline=True)
def matrix(buffer, rows, cols):
    """A ``(rows, cols)`` view (without an owner) of the first entries of the flat ``buffer``, as :func:`square`."""
    return numba.carray(pointer(buffer.ctypes.data), (rows, cols), np.float64)


@internal
def keep_alive(*owners) -> int:
    """Reference ``owners`` here, so a kernel keeps them (and the views of their memory) alive to this point."""
    return len(owners)
