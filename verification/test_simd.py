"""bubblemesh.simd: the packed square roots and reciprocals equal Python's
scalar ``math.sqrt`` and ``1.0 / x`` (both correctly rounded) bit for bit,
across the whole range of non-negative doubles, subnormals and zero (whose
reciprocal is inf) included."""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest
from hypothesis import example, given
from hypothesis import strategies as st
from numba import njit

from bubblemesh.simd import roots_and_reciprocals

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
