"""Memory access in the kernels (no paper equation: speed only).

The §2 insertion loop (paper §2.4 c-e) waits on memory at a million elements:
the lowest-density triangle of eq. 5 lies anywhere in the domain, so the heap
levels, its record and its neighbours' records are cache misses that follow
one another.  :func:`prefetch` lets a kernel start such a load early, while
it still works on something else.  It is a hint: no load, no fault, no change
to any result; without the JIT it does nothing.

:func:`unsigned` makes an index unsigned.  numba wraps every signed index
around (a negative one counts from the end): a shift, an and and an add per
array access in the §3 loops (eq. 7-9) and the §2 cavity search.  An
unsigned index has no negative values to wrap.  Only for indices known to be
>= 0 (a -1 "none" would become a huge index).
"""

import numba
import numpy as np

__all__ = ["prefetch", "unsigned"]


@numba.njit(cache=True, inline="always")
def unsigned(index):
    """``index`` (>= 0) as an unsigned integer: indexing with it skips the
    negative-index wrap-around."""
    return np.uint64(index)


if numba.config.DISABLE_JIT:  # type: ignore[attr-defined]

    def prefetch(array, index):
        """Without the JIT: nothing to hint."""

else:
    from llvmlite import ir
    from numba import types
    from numba.core import cgutils
    from numba.extending import intrinsic

    @intrinsic
    def prefetch(typingctx, array, index):
        """Hint that ``array[index]`` (a 1-D array, any strides) will be read
        soon: LLVM's prefetch intrinsic (read, keep in all cache levels)."""
        if not isinstance(array, types.Array) or array.ndim != 1:
            return None

        def codegen(context, builder, signature, args):
            array_type, index_type = signature.args
            view = context.make_array(array_type)(context, builder, args[0])
            at = context.cast(builder, args[1], index_type, types.intp)
            address = cgutils.get_item_pointer(context, builder, array_type, view, [at],
                                               wraparound=False)
            byte_ptr = ir.IntType(8).as_pointer()
            i32 = ir.IntType(32)
            hint = ir.FunctionType(ir.VoidType(), [byte_ptr, i32, i32, i32])
            # named llvm.prefetch.p0 (opaque pointers) or .p0i8 (older llvmlite)
            intrinsic_fn = builder.module.declare_intrinsic("llvm.prefetch", [byte_ptr], hint)
            # (address, read = 0, locality = 3: keep, data cache = 1)
            builder.call(intrinsic_fn, [builder.bitcast(address, byte_ptr), i32(0), i32(3),
                                        i32(1)])
            return context.get_dummy_value()

        return types.void(array, index), codegen
