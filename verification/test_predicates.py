"""bubblemesh.predicates: the sign of orient2d / incircle equals the exact sign
of the real determinant (oracle: Fraction arithmetic in oracles.py), on random
and on adversarial inputs (near-collinear triples built with nextafter,
exactly and nearly cocircular lattice points on x^2 + y^2 = 325^2), and it is
invariant under exact transformations (translation and scaling by powers of
two, rotation by 90 degrees)."""

from __future__ import annotations

import math

import numpy as np
import oracles as O
import pytest
import strategies as S
from hypothesis import example, given
from hypothesis import strategies as st

import bubblemesh as bm
from bubblemesh.predicates import incircle, orient2d


def _sign(x: float) -> int:
    return (x > 0) - (x < 0)


def _ccw(a, b, c):
    """Order a, b, c counter-clockwise (exactly) when they are not collinear."""
    return (a, b, c) if O.orient2d_sign(*a, *b, *c) >= 0 else (b, a, c)


# magnitudes for which the contract promises exact signs: products must neither
# overflow nor underflow (orient: degree 2, incircle: degree 4)
def _coords(limit):
    return st.floats(-limit, limit, allow_nan=False, allow_infinity=False).map(
        lambda x: 0.0 if abs(x) < 1e-30 else x
    )


_pt2 = st.tuples(_coords(1e60), _coords(1e60))
_pt4 = st.tuples(_coords(1e30), _coords(1e30))
_small_int = st.integers(-8, 8).map(float)
_grid_pt = st.tuples(_small_int, _small_int)


# --------------------------------------------------------------------------- orient2d


@given(_pt2, _pt2, _pt2)
@example((0.5, 0.5), (12.0, 12.0), (24.0, 24.0))
@example((0.0, 0.0), (0.0, 0.0), (1.0, 1.0))
def test_orient2d_sign_is_exact_random(a, b, c):
    assert _sign(orient2d(*a, *b, *c)) == O.orient2d_sign(*a, *b, *c)


@given(S.near_collinear_triples())
def test_orient2d_sign_is_exact_near_collinear(abc):
    a, b, c = abc
    assert _sign(orient2d(*a, *b, *c)) == O.orient2d_sign(*a, *b, *c)


@given(_grid_pt, _grid_pt, _grid_pt)
def test_orient2d_on_small_grid_is_exact(a, b, c):
    """Many exactly collinear triples: the sign must be exactly 0 there."""
    assert _sign(orient2d(*a, *b, *c)) == O.orient2d_sign(*a, *b, *c)


@given(S.near_collinear_triples())
def test_orient2d_antisymmetry(abc):
    a, b, c = abc
    s = _sign(orient2d(*a, *b, *c))
    assert _sign(orient2d(*b, *c, *a)) == s
    assert _sign(orient2d(*b, *a, *c)) == -s


# --------------------------------------------------------------------------- incircle


@given(_pt4, _pt4, _pt4, _pt4)
def test_incircle_sign_is_exact_random(a, b, c, d):
    assert _sign(incircle(*a, *b, *c, *d)) == O.incircle_sign(*a, *b, *c, *d)


@given(S.cocircular_quadruples())
@example(((325.0, 0.0), (0.0, 325.0), (-325.0, 0.0), (0.0, -325.0)))
@example(((204.0, 253.0), (-253.0, 204.0), (-204.0, -253.0), (253.0, -204.0)))
def test_incircle_sign_is_exact_cocircular(abcd):
    """Exactly cocircular (sign 0) and 1-3 ulp perturbations (tiny nonzero)."""
    a, b, c, d = abcd
    a, b, c = _ccw(a, b, c)
    assert _sign(incircle(*a, *b, *c, *d)) == O.incircle_sign(*a, *b, *c, *d)


@given(S.cocircular_quadruples(perturb=False))
def test_incircle_is_zero_on_lattice_circle(abcd):
    """Directly: four integer points of x^2 + y^2 = 325^2 are cocircular, in
    any order and any orientation."""
    a, b, c, d = abcd
    assert incircle(*a, *b, *c, *d) == 0
    assert incircle(*b, *a, *c, *d) == 0


@given(_grid_pt, _grid_pt, _grid_pt, _grid_pt)
@example((0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0))
def test_incircle_on_small_grid_is_exact(a, b, c, d):
    """Grid squares are cocircular quadruples; coincident points give 0."""
    a, b, c = _ccw(a, b, c)
    assert _sign(incircle(*a, *b, *c, *d)) == O.incircle_sign(*a, *b, *c, *d)


@given(S.cocircular_quadruples())
def test_incircle_symmetries(abcd):
    a, b, c, d = abcd
    s = _sign(incircle(*a, *b, *c, *d))
    assert _sign(incircle(*b, *c, *a, *d)) == s  # cyclic
    assert _sign(incircle(*b, *a, *c, *d)) == -s  # orientation flips the sign


# --------------------------------------------------------------------------- invariance


def _translate(points, tx, ty):
    out = [(x + tx, y + ty) for x, y in points]
    exact = all((x2 - tx, y2 - ty) == p for (x2, y2), p in zip(out, points, strict=False))
    return out, exact


@given(S.cocircular_quadruples(), st.integers(-20, 40), st.integers(-20, 40), st.integers(-40, 40))
def test_signs_invariant_under_exact_transformations(abcd, kx, ky, ks):
    a, b, c, d = abcd
    o = _sign(orient2d(*a, *b, *c))
    s = _sign(incircle(*a, *b, *c, *d))
    moved, exact = _translate(abcd, math.ldexp(1.0, kx), -math.ldexp(1.0, ky))
    if exact:  # translation by 2^k is exact when no bit falls off
        a2, b2, c2, d2 = moved
        assert _sign(orient2d(*a2, *b2, *c2)) == o
        assert _sign(incircle(*a2, *b2, *c2, *d2)) == s
    a2, b2, c2, d2 = ((math.ldexp(x, ks), math.ldexp(y, ks)) for x, y in abcd)
    assert _sign(orient2d(*a2, *b2, *c2)) == o
    assert _sign(incircle(*a2, *b2, *c2, *d2)) == s
    a2, b2, c2, d2 = ((-y, x) for x, y in abcd)
    assert _sign(orient2d(*a2, *b2, *c2)) == o
    assert _sign(incircle(*a2, *b2, *c2, *d2)) == s


@given(S.near_collinear_triples(), st.integers(-30, 30))
def test_orient2d_invariant_under_scaling(abc, k):
    a, b, c = abc
    s = _sign(orient2d(*a, *b, *c))
    a2, b2, c2 = ((math.ldexp(x, k), math.ldexp(y, k)) for x, y in abc)
    assert _sign(orient2d(*a2, *b2, *c2)) == s


def test_predicates_accept_numpy_scalars():
    x = np.float64(0.5)
    assert orient2d(x, x, 12.0, 12.0, 24.0, 24.0) == 0


def test_subnormal_quadruple_is_refused_by_the_kernel():
    """Found by the thorough profile: incircle underflows when d is outside
    the circle by 5e-324 in y (it returns 0, the exact sign is -1).  Such
    coordinates are outside the predicates' documented exact range (nonzero
    |x| in [2**-100, 2**100]), so the kernel must refuse them up front."""
    a, b, c, d = (-325.0, 0.0), (-323.0, -36.0), (-323.0, 36.0), (325.0, 5e-324)
    assert O.incircle_sign(*a, *b, *c, *d) == -1
    with pytest.raises(bm.GeometryError, match="point 3"):
        bm.delaunay(np.array([a, b, c, d]))
