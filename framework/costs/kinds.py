"""Block kinds: what a residual block computes, as compiled kernels the engine calls by address.

A :class:`BlockKind` is defined in its term's module, beside the term's class: its residual kernel (the rows
``r(x)`` and their Jacobian), optionally its curvature kernel (``Σ μ_c ∇²r_c``, for the Newton phases), and what
the engine may rely on (one-sided rows, collision rows, unit rows). A kernel is a Python function of one
workspace record (:mod:`~framework.costs.workspace`) returning its rows; it is compiled as a C callback the first
time a problem uses its kind (and cached on disk), and the block table holds its address: the engine's compiled
code calls it through that address, so the engine is compiled once whatever kinds a problem holds, and a kind is
compiled only where it is used.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable
from dataclasses import dataclass, field

import numba
from numba import types

from ..compiled.cache import NOTICE, cached, is_cached
from ..compiled.native import OPTIONS
from .blocks import CONTACT, FRAME_INDICES, HINGE, UNIT_ROWS
from .workspace import WORKSPACE

#: The C signature of every kernel: ``int64 kernel(workspace record)``.
KERNEL_SIGNATURE = types.int64(numba.from_dtype(WORKSPACE))


@dataclass(eq=False)
class BlockKind:
    """A kind of residual block.

    Attributes:
        name: what it measures (reports, errors).
        residual: ``(ws) -> rows``: the block ``ws.block``'s rows into the workspace's ``r`` from row ``ws.row``
            on, and (mode :data:`~.workspace.LINEARIZE` or :data:`~.workspace.JACOBIAN_ONLY`) their Jacobian.
        curvature: ``(ws) -> 0``: ``Σ_c μ_c ∇²r_c`` added to the workspace's Hessian, ``μ`` its multipliers
            (``None``: the engine uses Gauss-Newton curvature for the block).
        hinge: one-sided: zero residual and Jacobian inside its allowed set (an inequality).
        contact: a collision row (a signed distance held above a margin).
        unit_rows: each row is ``x[i] − c`` for one of the block's coordinates (indices).
        frame_indices: the block's indices are the frame slots it reads.
        margin: its margin's place among its parameters (contact rows, whose margins the Newton phase widens).
    """

    name: str
    residual: Callable
    curvature: Callable | None = None
    hinge: bool = False
    contact: bool = False
    unit_rows: bool = False
    frame_indices: bool = False
    margin: int = -1
    _compiled: dict = field(default_factory=dict, repr=False)

    @property
    def flags(self) -> int:
        """The block table's ``flags`` of the kind's blocks."""
        return ((HINGE if self.hinge or self.contact else 0) | (CONTACT if self.contact else 0)
                | (UNIT_ROWS if self.unit_rows else 0) | (FRAME_INDICES if self.frame_indices else 0))

    def addresses(self) -> tuple[int, int]:
        """``(residual, curvature)``: the addresses of the compiled kernels (compiled or loaded from the disk cache
        on first use; the curvature's 0 when there is none)."""
        return self._address(self.residual), (self._address(self.curvature) if self.curvature else 0)

    def __reduce__(self):
        """Pickled by reference (a kind is a module-level constant; its compiled kernels are this process's)."""
        module = sys.modules[self.residual.__module__]
        for name, value in vars(module).items():
            if value is self:
                return _kind_named, (module.__name__, name)
        raise TypeError(f"block kind {self.name!r} is not a module-level name of {module.__name__}")

    def _address(self, function: Callable) -> int:
        made = self._compiled.get(function)
        if made is None:
            made = self._compiled[function] = compile_kernel(function)
        return made.address


def _kind_named(module: str, name: str) -> BlockKind:
    """The block kind ``module.name`` (unpickling)."""
    return getattr(importlib.import_module(module), name)


def compile_kernel(function: Callable):
    """``function`` compiled as a kernel (:data:`KERNEL_SIGNATURE`), or loaded from the disk cache."""
    from numba.core.ccallback import CFunc

    kernel = cached(CFunc(function, (KERNEL_SIGNATURE.args, KERNEL_SIGNATURE.return_type), locals={},
                          options=dict(OPTIONS)))
    if is_cached(kernel):
        kernel.compile()
        return kernel
    NOTICE.start(f"{function.__module__.split('.', 1)[-1]}.{function.__qualname__}")
    try:
        kernel.compile()
    finally:
        NOTICE.end()
    return kernel
