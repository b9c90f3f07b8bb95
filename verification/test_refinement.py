"""Boundary refinement (bubblemesh.refinement) against independent checks.

Oracles: exact collinearity and betweenness by Fraction arithmetic
(oracles.orient2d_sign), the integral of ds / h by a dense midpoint rule
written here, and Domain.from_loops for validity of the result.
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st
from oracles import orient2d_sign
from strategies import budget, domains

import bubblemesh as bm
from bubblemesh.errors import GeometryError
from bubblemesh.refinement import NEAREST_CAP, refine_boundary
from bubblemesh.sizing import SizeField

G = 0.25
UPPER = 1.2  # every piece <= UPPER * h(midpoint); theory 1 / (1 - g/2) = 1.143 plus quadrature
LOWER = 0.45  # pieces of a split segment >= LOWER * h(midpoint); theory 0.5 / (1 + g/4) = 0.47
# the refinement's trapezoid rule (samples <= 0.25 h apart) over-estimates the
# integral of a convex 1/h by up to (0.25 g)^2 / 6 ~ 7e-4 relative, more at a
# kink of a user's h: the piece count ceil(I) is checked to this tolerance
QUADRATURE = 5e-3


def _integral(a, b, h, n=4000):
    """Dense midpoint rule for the integral of ds / h along a-b."""
    t = (np.arange(n) + 0.5) / n
    xy = a + t[:, None] * (b - a)
    return float(np.linalg.norm(b - a) * np.mean(1.0 / h(xy)))


def _strictly_between(p, a, b):
    axis = 0 if abs(b[0] - a[0]) >= abs(b[1] - a[1]) else 1
    lo, hi = sorted((Fraction(a[axis]), Fraction(b[axis])))
    return lo < Fraction(p[axis]) < hi


def check_refinement(rings, result, h=None, exact_expected=False, rounding="up"):
    """Input nodes kept in order; new nodes on (or, flagged, within
    max_deviation of) their segment; lengths follow h (n = ceil(I) pieces, or
    with ``rounding="nearest"`` round(I) but none over NEAREST_CAP h); the
    result is valid."""
    assert len(result.loops) == len(rings)
    for ring, loop, index, exact in zip(rings, result.loops, result.input_index,
                                        result.on_segment):  # fmt: skip
        assert index[0] == 0 and (np.diff(index) > 0).all()
        np.testing.assert_array_equal(loop[index], ring)  # bitwise, in order
        ends = np.append(index, len(loop))
        for s in range(len(ring)):
            a, b = ring[s], ring[(s + 1) % len(ring)]
            new = range(ends[s] + 1, ends[s + 1])
            chain = [a] + [loop[k] for k in new] + [b]
            for k in new:
                p = loop[k]
                on_line = orient2d_sign(*a, *b, *p) == 0
                assert exact[k] == (on_line and _strictly_between(p, a, b)), (s, k)
                if not exact[k]:
                    assert not exact_expected, f"segment {s} node {k} is off the segment"
                    cross = (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
                    dist = abs(cross) / np.linalg.norm(b - a)
                    assert dist <= 1e-15 * (1 + np.abs(chain).max())
                    assert result.max_deviation <= 4e-16 * (1 + np.abs(chain).max())
            axis = 0 if abs(b[0] - a[0]) >= abs(b[1] - a[1]) else 1
            step = np.diff([c[axis] for c in chain])
            assert (step > 0).all() or (step < 0).all()  # strictly advancing: no duplicates
            if h is not None:
                pieces = np.array(chain)
                mids = 0.5 * (pieces[1:] + pieces[:-1])
                ratio = np.linalg.norm(np.diff(pieces, axis=0), axis=1) / h(mids)
                n = len(chain) - 1
                integral = _integral(a, b, h)
                if rounding == "nearest":
                    assert ratio.max() <= NEAREST_CAP * UPPER, (s, ratio.max())
                    # the nearest integer, unless that leaves pieces over the cap
                    nearest = n - 0.5 <= integral * (1 + QUADRATURE)
                    capped = n - 1 < integral / NEAREST_CAP * (1 + QUADRATURE)
                    assert nearest or capped, (s, n, integral)
                    assert n + 0.5 >= integral * (1 - QUADRATURE), (s, n, integral)
                else:
                    assert ratio.max() <= UPPER, (s, ratio.max())
                    assert n - 1 < integral * (1 + QUADRATURE)
                    assert n >= min(1.0, integral) * (1 - QUADRATURE)
                if n >= 2:
                    assert ratio.min() >= LOWER, (s, ratio.min())
    bm.Domain.from_loops(result.loops)  # no new crossings


@given(domains(max_holes=2, max_corners=6, min_spacing=0.3),
       st.sampled_from([None, 0.07, "callable"]), st.sampled_from(["up", "nearest"]))  # fmt: skip
@budget(40)
def test_refined_random_domains(case, size, rounding):
    if size == "callable":
        size = lambda xy: 0.03 + 0.3 * np.abs(xy[:, 0] - 0.2)  # noqa: E731
    domain = bm.Domain.from_loops(case.loops)
    field = SizeField.from_domain(domain, size=size, gradation=G)
    result = refine_boundary(case.loops, field, rounding=rounding)
    rings = [np.asarray(lp, float) for lp in case.loops]
    check_refinement(rings, result, field, rounding=rounding)


def test_nearest_rounding_on_one_segment():
    # a constant h on a square of side 10: I = 10 / h on every side
    square = [np.array([(0, 0), (10, 0), (10, 10), (0, 10)], float)]
    for h, up, nearest in ((10 / 2.3, 3, 2), (10 / 2.7, 3, 3), (10 / 1.4, 2, 2),
                           (10 / 1.2, 2, 1), (10 / 3.0, 3, 3)):
        counts = [len(refine_boundary(square, h, rounding=r).loops[0]) // 4
                  for r in ("up", "nearest")]
        assert counts == [up, nearest], (h, counts)


@st.composite
def integer_polygons(draw):
    """Star polygons with small integer corners: exact points on every segment exist."""
    n = draw(st.integers(3, 8))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    ang = np.linspace(0, 2 * np.pi, n, endpoint=False) + rng.uniform(-0.2, 0.2, n)
    r = rng.uniform(3, 20, n)
    return np.round(np.column_stack([r * np.cos(ang), r * np.sin(ang)]))


@given(integer_polygons(), st.floats(0.3, 5.0))
@budget(40)
def test_integer_corners_refine_exactly(corners, spacing):
    try:
        domain = bm.Domain.from_loops([corners])
    except GeometryError:
        assume(False)
    field = SizeField.from_domain(domain, size=spacing, gradation=G)
    result = refine_boundary(domain, field)
    rings = [domain.points[ix] for ix in domain.loops]
    check_refinement(rings, result, field, exact_expected=True)


def _half_disk(n_arc=32):
    th = np.linspace(0, np.pi, n_arc)
    arc = np.column_stack([np.cos(th), np.sin(th)])
    arc[0], arc[-1] = (1.0, 0.0), (-1.0, 0.0)  # the diameter exactly on y = 0
    return [arc]


def _square_with_hole():
    n = round(2 * math.pi * 0.05 / 0.005)
    th = np.linspace(0, 2 * np.pi, n, endpoint=False)
    hole = 5 + 0.05 * np.column_stack([np.cos(th), np.sin(th)])
    return [np.array([(0, 0), (10, 0), (10, 10), (0, 10)], float), hole]


@pytest.mark.parametrize(
    "loops",
    [
        [np.array([(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)], float)],
        _half_disk(),
        _square_with_hole(),
    ],
    ids=["L-shape", "half-disk", "square-with-hole"],
)
def test_showcases(loops):
    domain = bm.Domain.from_loops(loops)
    field = SizeField.from_domain(domain, gradation=G)
    result = refine_boundary(domain, field)
    rings = [domain.points[ix] for ix in domain.loops]
    check_refinement(rings, result, field, exact_expected=True)
    assert sum(map(len, result.loops)) > len(domain.points)  # the long edges were split


def test_general_slopes_flag_inexact_nodes_honestly():
    # decimal corners: most interior points of these segments are not floats
    corners = np.array([(0.1, 0.2), (3.3, 0.7), (1.7, 2.9)])
    result = refine_boundary([corners], 0.05)
    check_refinement([corners], result)
    assert not all(e.all() for e in result.on_segment)


def test_no_coincident_nodes_on_segments_a_few_ulps_long():
    x = np.nextafter(1.0, 2.0)
    corners = np.array([(0.0, 0.0), (1.0, 0.0), (x, 0.0), (x, 1.0), (0.0, 1.0)])

    def h(xy):  # far below the float spacing at (1, 0), 0.3 elsewhere
        near = np.hypot(xy[:, 0] - 1.0, xy[:, 1]) < 1e-14
        return np.where(near, 1e-18, 0.3)

    result = refine_boundary([corners], h)
    check_refinement([corners], result)


def test_bad_arguments():
    tri = [np.array([(0, 0), (1, 0), (0, 1)], float)]
    with pytest.raises(ValueError, match="h must be finite and > 0"):
        refine_boundary(tri, -1.0)
    with pytest.raises(ValueError, match=r"h\(xy\) must be finite and > 0"):
        refine_boundary(tri, lambda xy: np.full(len(xy), np.nan))
    with pytest.raises(ValueError, match="resolution"):
        refine_boundary(tri, 0.1, resolution=0.0)
    with pytest.raises(ValueError, match="rounding"):
        refine_boundary(tri, 0.1, rounding="down")
    with pytest.raises(bm.MeshingError, match="more than 100"):
        refine_boundary(tri, 1e-3, max_nodes=100)
    with pytest.raises(GeometryError, match="crosses"):
        refine_boundary([np.array([(0, 0), (1, 1), (1, 0), (0, 1)], float)], 0.1)
