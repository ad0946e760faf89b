"""Borrowed array views for compiled kernels: no reference counting in the hot loops; compiled entry points
resolved once for fixed argument types.

Numba counts references to every array it passes to a function (two atomic operations per array per call).
With a dozen arrays per helper call that is ~70 ns — more than the arithmetic of a residual block. A kernel
therefore *borrows* its arrays once at entry (:func:`borrow`: a view of the same memory without an owner) and
passes the views down; the owning arrays stay referenced by the kernel's arguments, or by a local variable the
kernel keeps alive to its end (:func:`keep_alive`), so the memory outlives every view.

A call through numba's dispatcher resolves the types of every argument first (for a tuple of arrays, a
fingerprint string per call): ~2.5 µs for the engine's calls with ~18 arrays, against ~1.1 µs through the
compiled entry point of the matching specialization. Callers whose argument types are fixed by construction
resolve that entry point once (:func:`compiled_entry`) and call it directly.
"""

from __future__ import annotations

import numba
from numba.core import cgutils, types
from numba.extending import intrinsic


def compiled_entry(dispatcher, args: tuple):
    """The compiled entry point of the numba function ``dispatcher`` for the types of ``args`` (loaded from the
    disk cache or compiled on first use, as a dispatched call would). A call through it skips the per-call type
    resolution and does not check its arguments: the caller must pass arguments of exactly these types (dtypes,
    dimensions, layouts, read-only flags, scalar kinds) on every call."""
    return dispatcher.compile(tuple(dispatcher.typeof_pyval(a) for a in args))


@intrinsic
def _address_as_pointer(typingctx, address):
    def codegen(context, builder, signature, args):
        return builder.inttoptr(args[0], cgutils.voidptr_t)

    return types.voidptr(address), codegen


@numba.njit(cache=True, inline="always")
def borrow(a):
    """A view of the C-contiguous array ``a`` without an owner (valid while ``a`` is alive)."""
    return numba.carray(_address_as_pointer(a.ctypes.data), a.shape, a.dtype)


@numba.njit(cache=True, inline="always")
def carve(buffer, start, shape):
    """A C-contiguous view of ``shape`` (an int or a tuple) without an owner, of the flat ``buffer`` from entry
    ``start`` on: a kernel's scratch arrays carved from one allocation (each allocation costs ~0.1 µs)."""
    address = buffer.ctypes.data + start * buffer.itemsize
    return numba.carray(_address_as_pointer(address), shape, buffer.dtype)


@numba.njit(cache=True, inline="always")
def square(buffer, k):
    """A ``(k, k)`` C-contiguous view (without an owner) of the first ``k²`` entries of the flat ``buffer`` (a
    ``reshape`` would call into numba's runtime on every use; a ``[:k, :k]`` slice would be strided)."""
    return carve(buffer, 0, (k, k))


@numba.njit(cache=True, inline="always")
def matrix(buffer, rows, cols):
    """A ``(rows, cols)`` C-contiguous view (without an owner) of the first entries of the flat ``buffer``, as
    :func:`square`."""
    return carve(buffer, 0, (rows, cols))


@numba.njit(cache=True, inline="always")
def borrow_kin(kin):
    """:func:`borrow` over the kinematic tables ``(jint, jgeo, fslot, fgeo)``."""
    return borrow(kin[0]), borrow(kin[1]), borrow(kin[2]), borrow(kin[3])


@numba.njit(cache=True, inline="always")
def borrow_prog(prog):
    """:func:`borrow` over a packed program ``(bint, bflt, params, idx, wrap, chain_ptr, chain_idx)``."""
    return (borrow(prog[0]), borrow(prog[1]), borrow(prog[2]), borrow(prog[3]), borrow(prog[4]),
            borrow(prog[5]), borrow(prog[6]))


@numba.njit(cache=True, inline="always")
def borrow_ws(ws):
    """:func:`borrow` over a workspace ``(out, W, Jf, r, Jr, L3, E9)``."""
    return (borrow(ws[0]), borrow(ws[1]), borrow(ws[2]), borrow(ws[3]), borrow(ws[4]), borrow(ws[5]),
            borrow(ws[6]))


@numba.njit(cache=True)
def keep_alive(*owners) -> int:
    """Reference ``owners`` here, so a kernel keeps them (and the views borrowed from them) alive to this point."""
    return len(owners)
