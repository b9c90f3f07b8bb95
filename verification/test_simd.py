"""bubblemesh.simd: the packed square roots, reciprocals and quotients equal
Python's scalar ``math.sqrt``, ``1.0 / x`` and ``a / b`` (all correctly
rounded) bit for bit, across the whole range of doubles, subnormals and zero
(whose reciprocal is inf) included."""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest
from hypothesis import example, given
from hypothesis import strategies as st
from numba import njit

from bubblemesh.simd import quotients, roots_and_reciprocals

# without the JIT the helper is math.sqrt and 1 / x themselves: nothing to compare
pytestmark = pytest.mark.skipif(numba.config.DISABLE_JIT,
                                reason="checks the compiled packed path; without the JIT "
                                       "it is the scalar formula")


@njit
def _packed(a, b):
    return roots_and_reciprocals(a, b)


def _scalar(x):
    root = math.sqrt(x)
    return root, 1.0 / root if root > 0.0 else math.inf


_squares = st.floats(0.0, math.inf, allow_nan=False, allow_infinity=False)


@given(_squares, _squares)
@example(0.0, 5e-324)  # zero and the smallest subnormal
@example(2.0, 1.7976931348623157e308)
@example(1e-300, 3.0)
def test_packed_equals_scalar_bit_for_bit(a, b):
    root_a, root_b, inverse_a, inverse_b = _packed(a, b)
    for got, want in zip((root_a, inverse_a, root_b, inverse_b), (*_scalar(a), *_scalar(b))):
        assert np.float64(got).tobytes() == np.float64(want).tobytes(), (a, b, got, want)


@njit
def _divided(a, b, c, d):
    return quotients(a, b, c, d)


_finite = st.floats(allow_nan=False, allow_infinity=False)
_divisors = _finite.filter(lambda x: x != 0.0)


@given(_finite, _finite, _divisors, _divisors)
@example(1.0, -1.0, 5e-324, 3.0)  # the smallest subnormal divisor: overflow to inf
@example(5e-324, 1e-300, 1e300, -7.0)  # underflow to a subnormal and to zero
@example(-0.0, 0.0, 2.0, -2.0)
def test_packed_quotients_equal_scalar_division_bit_for_bit(a, b, c, d):
    for got, want in zip(_divided(a, b, c, d), (a / c, b / d)):
        assert np.float64(got).tobytes() == np.float64(want).tobytes(), (a, b, c, d, got, want)
