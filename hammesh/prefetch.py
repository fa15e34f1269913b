"""A cache hint for compiled kernels that read rows scattered across a big array.

``prefetch_row(arr, i)`` asks the processor to fetch the cache line holding row ``i``
of ``arr`` now, so that a loop can ask for the row it will read some iterations
ahead while it works on the current one (a pass bound by the latency of its
scattered reads overlaps them). A hint only: it changes no value, and an address
past the array's end is never formed (the callers ask only for rows in range).
Shared by the construction's renumbering (``hammesh.halfedge``), sparse mode's
plan of joins (``_sparse_kernels``' Kruskal) and the certificate's passes over the
caller's rows (``hammesh.verify``), as the exact
predicates are: it computes nothing either could share. (Kernels cached by numba
hold its code compiled in, and numba checks only each kernel's own file: a change
here needs their ``__pycache__`` entries cleared.)
"""

from __future__ import annotations

from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

__all__ = ["prefetch_row"]


@intrinsic
def prefetch_row(typingctx, arr, i):
    """Ask for the cache line of ``arr[i]`` (1-D) or ``arr[i, 0]`` (2-D) now (LLVM's
    ``llvm.prefetch``: a read, kept in all cache levels). No effect on any value; any
    layout (the address is numba's own item pointer)."""
    if not isinstance(arr, types.Array) or arr.ndim not in (1, 2) or not isinstance(i, types.Integer):
        return None

    def codegen(context, builder, signature, args):
        aryty = signature.args[0]
        ary = context.make_array(aryty)(context, builder, args[0])
        idx = context.cast(builder, args[1], signature.args[1], types.intp)
        at = [idx] if aryty.ndim == 1 else [idx, context.get_constant(types.intp, 0)]
        ptr = cgutils.get_item_pointer(context, builder, aryty, ary, at, wraparound=False)
        i8p = ir.IntType(8).as_pointer()
        i32 = ir.IntType(32)
        name = "llvm.prefetch.p0"
        fn = builder.module.globals.get(name) or ir.Function(
            builder.module, ir.FunctionType(ir.VoidType(), [i8p, i32, i32, i32]), name=name)
        builder.call(fn, [builder.bitcast(ptr, i8p), ir.Constant(i32, 0), ir.Constant(i32, 3), ir.Constant(i32, 1)])
        return context.get_dummy_value()

    return types.void(arr, i), codegen
