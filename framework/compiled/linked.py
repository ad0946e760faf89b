"""A numba compile pipeline for functions that are only ever linked into other compiled functions.

numba compiles each function into its own LLVM module, optimizes that module with every callee linked in, and
generates its machine code; each caller then links the callee's optimized code and does the same again. A helper
three calls deep under an entry point was so optimized and compiled four times, and the engine's cold start
(about seventy functions under two entry points) spent two thirds of its LLVM time on machine code nobody runs:
a helper called only from compiled code is never called by its own address.

Functions compiled with :data:`PIPELINE` (:func:`framework.compiled.native.internal`) stop before that: their module is
linked into each caller, which optimizes it and generates its code once, in its own context (LLVM inlines the small
ones there). They cannot be called from Python (they have no Python wrapper either) and have no machine code of
their own: their callers' cached code holds it. They are cached on disk as their module's bitcode (callees linked
in), which a caller compiled later — in another process too — links as it would the fresh module: an edit retypes the
functions it changes, and a helper process can type a subtree while another types the rest.

This relies on numba's pipeline classes (``pipeline_class=``, a public option) and on two methods of numba's
code library; :func:`available` tells whether this numba version has what it needs, else
:func:`framework.compiled.native.internal` compiles as numba does by default.
"""

from __future__ import annotations

import llvmlite.binding as llvm
from numba.core import codegen
from numba.core.compiler import CompilerBase, DefaultPassBuilder
from numba.core.compiler_lock import require_global_compiler_lock
from numba.core.compiler_machinery import register_pass
from numba.core.typed_passes import NativeLowering


class _LinkedOnlyLibrary(codegen.JITCodeLibrary):
    """A code library that is only linked into others: its module gets its callees linked in, nothing more."""

    def finalize(self):
        require_global_compiler_lock()
        self._raise_if_finalized()
        seen = set()
        for library in self._linking_libraries:
            if library not in seen:
                self._reload_init.update(library._reload_init)
                seen.add(library)
                self._final_module.link_in(library._get_module_for_linking(), preserve=True)
        self._finalized = True

    def get_pointer_to_function(self, name):  # no machine code: no address
        return 0

    def serialize_using_object_code(self):
        """The library as numba's disk cache keeps it (numba asks every library it saves for this): its module's
        bitcode, its callees linked in — it has no machine code. :func:`unserialize` reads it back."""
        self._ensure_finalized()
        return (self.name, LINKED, self._final_module.as_bitcode())

    @property
    def codegen(self):
        return _Codegen(self._codegen)


class _Codegen:
    """The shared code generator, as a linked-only library's compile sees it: its environment has no address to
    be written to (it has no machine code)."""

    def __init__(self, wrapped):
        self._wrapped = wrapped

    def set_env(self, env_name, env):
        pass

    def __getattr__(self, name):
        return getattr(self._wrapped, name)


@register_pass(mutates_CFG=True, analysis_only=False)
class _LinkedOnlyLowering(NativeLowering):
    """numba's lowering into a :class:`_LinkedOnlyLibrary`."""

    _name = "metaik_linked_only_lowering"

    def run_pass(self, state):
        if state.library is None:
            state.library = _LinkedOnlyLibrary(state.targetctx.codegen(), state.func_id.func_qualname)
        return super().run_pass(state)


class LinkedOnlyCompiler(CompilerBase):
    """numba's nopython pipeline with :class:`_LinkedOnlyLowering` in place of its lowering."""

    def define_pipelines(self):
        pm = DefaultPassBuilder.define_nopython_pipeline(self.state)
        pm.passes = [(_LinkedOnlyLowering if cls is NativeLowering else cls, text) for cls, text in pm.passes]
        pm.finalize()
        return [pm]


#: The pipeline class of linked-only functions.
PIPELINE = LinkedOnlyCompiler
#: The serialization kind of a linked-only library in the disk cache (numba's own are "object" and "bitcode").
LINKED = "linked-only bitcode"


def unserialize(code_generator, state: tuple) -> _LinkedOnlyLibrary:
    """A linked-only library from the disk cache (:meth:`_LinkedOnlyLibrary.serialize_using_object_code`), ready
    to be linked into callers: no optimization, no machine code."""
    name, kind, data = state
    if kind != LINKED:
        raise ValueError(f"not a linked-only library: {kind!r}")
    library = _LinkedOnlyLibrary(code_generator, name)
    library._final_module = llvm.parse_bitcode(data)
    library._finalized = True
    return library


def available() -> bool:
    """Whether numba's code library has what :class:`_LinkedOnlyLibrary` overrides."""
    base = codegen.JITCodeLibrary
    return all(hasattr(base, name) for name in ("_get_module_for_linking", "_raise_if_finalized", "finalize",
                                                "get_pointer_to_function"))
