"""A monotonic clock readable from compiled code, so time budgets are checked inside the solver loops.

``monotonic_ns()`` calls the C library's ``clock_gettime(CLOCK_MONOTONIC)`` (about 25 ns) from numba-compiled
functions. It is emitted as an LLVM call to the process's own ``clock_gettime`` symbol, so the functions that
use it stay cacheable on disk (a ctypes pointer would make numba recompile them in every process). Its values
equal ``time.monotonic_ns()`` of the same process.
"""

from __future__ import annotations

import sys
import time

import numba
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from ..compiled.native import internal

#: ``CLOCK_MONOTONIC`` of the C library (Linux 1, macOS 6).
_CLOCK_MONOTONIC = 6 if sys.platform == "darwin" else 1

if sys.platform == "win32":  # pragma: no cover - no clock_gettime: compiled loops read a coarse clock instead

    @internal
    def monotonic_ns() -> int:
        with numba.objmode(now="int64"):
            now = time.monotonic_ns()
        return now

else:

    @intrinsic
    def _clock_gettime_ns(typingctx):
        def codegen(context, builder, signature, args):
            i64, i32 = ir.IntType(64), ir.IntType(32)
            timespec = ir.LiteralStructType([i64, i64])
            function = cgutils.get_or_insert_function(
                builder.module, ir.FunctionType(i32, [i32, timespec.as_pointer()]), "clock_gettime"
            )
            spec = cgutils.alloca_once(builder, timespec)
            builder.call(function, [ir.Constant(i32, _CLOCK_MONOTONIC), spec])
            zero = ir.Constant(i32, 0)
            seconds = builder.load(builder.gep(spec, [zero, zero]))
            nanoseconds = builder.load(builder.gep(spec, [zero, ir.Constant(i32, 1)]))
            return builder.add(builder.mul(seconds, ir.Constant(i64, 1_000_000_000)), nanoseconds)

        return types.int64(), codegen

    @internal
    def monotonic_ns() -> int:
        """Nanoseconds of the monotonic clock (the same clock as ``time.monotonic_ns()``)."""
        return _clock_gettime_ns()
