"""Packed arithmetic for the kernels (no paper equation: speed only).

Eq. 9 (paper §3.4) needs the length l and its reciprocal 1 / l of every
nearby pair, each pass.  A square root and a division per pair kept the
divider of the CPU busy for half of the eq. 9 loop, and LLVM does not pair
them up across loop iterations by itself.  :func:`roots_and_reciprocals`
computes two of each with one packed instruction each.  The gradient of a
star's mean radius ratio (the default mesher's polish) divides both
coordinates by the same lengths: :func:`quotients` makes two divisions one
packed instruction.  IEEE square root and division are correctly rounded
lane by lane, so the bits are those of the scalar operations.  Without the
JIT they are plain Python.
"""

import math

import numba

__all__ = ["quotients", "roots_and_reciprocals"]

if numba.config.DISABLE_JIT:  # type: ignore[attr-defined]

    def roots_and_reciprocals(a, b):
        """(sqrt a, sqrt b, 1 / sqrt a, 1 / sqrt b); 1 / 0 is inf."""
        root_a, root_b = math.sqrt(a), math.sqrt(b)
        return (root_a, root_b, 1.0 / root_a if root_a > 0.0 else math.inf,
                1.0 / root_b if root_b > 0.0 else math.inf)

    def quotients(a, b, c, d):
        """(a / c, b / d); a zero divisor raises (the kernels never pass one)."""
        return a / c, b / d

else:
    from llvmlite import ir
    from numba import types
    from numba.core import cgutils
    from numba.extending import intrinsic

    @intrinsic
    def roots_and_reciprocals(typingctx, a, b):
        """(sqrt a, sqrt b, 1 / sqrt a, 1 / sqrt b) of two float64 as one
        packed square root and one packed division; 1 / 0 is inf."""
        if a != types.float64 or b != types.float64:
            return None

        def codegen(context, builder, signature, args):
            double = ir.DoubleType()
            pair = ir.VectorType(double, 2)
            lanes = [ir.IntType(32)(0), ir.IntType(32)(1)]
            packed = ir.Constant(pair, ir.Undefined)
            for lane, value in zip(lanes, args):
                packed = builder.insert_element(packed, value, lane)
            sqrt = cgutils.get_or_insert_function(builder.module, ir.FunctionType(pair, [pair]),
                                                  "llvm.sqrt.v2f64")
            roots = builder.call(sqrt, [packed])
            reciprocals = builder.fdiv(ir.Constant(pair, [double(1.0), double(1.0)]), roots)
            values = [builder.extract_element(v, lane) for v in (roots, reciprocals)
                      for lane in lanes]
            return context.make_tuple(builder, signature.return_type, values)

        return types.UniTuple(types.float64, 4)(a, b), codegen

    @intrinsic
    def quotients(typingctx, a, b, c, d):
        """(a / c, b / d) of four float64 as one packed division."""
        if any(x != types.float64 for x in (a, b, c, d)):
            return None

        def codegen(context, builder, signature, args):
            double = ir.DoubleType()
            pair = ir.VectorType(double, 2)
            lanes = [ir.IntType(32)(0), ir.IntType(32)(1)]
            packed = []
            for first, second in ((args[0], args[1]), (args[2], args[3])):
                vector = ir.Constant(pair, ir.Undefined)
                for lane, value in zip(lanes, (first, second)):
                    vector = builder.insert_element(vector, value, lane)
                packed.append(vector)
            quotient = builder.fdiv(*packed)
            values = [builder.extract_element(quotient, lane) for lane in lanes]
            return context.make_tuple(builder, signature.return_type, values)

        return types.UniTuple(types.float64, 2)(a, b, c, d), codegen
