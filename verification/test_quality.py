"""bubblemesh.quality: eq. 10 against 2r/R from the inradius/circumradius
formulas (oracles.radius_ratio_reference), angles against atan2 of cross and
dot products (oracles.angles_reference), and summary() against both."""

from __future__ import annotations

import math

import numpy as np
import oracles as O
import pytest
from hypothesis import example, given
from hypothesis import strategies as st

import bubblemesh as bm
from bubblemesh import quality

# coordinates of mesh-like magnitude (|x| <= 1e3, resolution 2^-20): side
# lengths cubed neither overflow nor underflow
_coord = st.integers(-(2**30), 2**30).map(lambda k: k / 2**20)
_triangle = st.tuples(*[st.tuples(_coord, _coord)] * 3).filter(
    lambda t: O.orient2d_sign(*t[0], *t[1], *t[2]) != 0
)


def _one(t):
    pts = np.array(t, dtype=float)
    if O.orient2d_sign(*t[0], *t[1], *t[2]) < 0:
        pts = pts[[0, 2, 1]]
    return pts, np.array([[0, 1, 2]])


def _well_conditioned(pts):
    """Eq. 10 and 16A^2/(P abc) are both accurate unless the triangle is so
    flat that its area is lost in rounding: compare only where the area is
    well above the rounding of its side lengths."""
    a = abs(O.triangle_areas(pts, [[0, 1, 2]])[0])
    longest = max(math.dist(pts[i], pts[(i + 1) % 3]) for i in range(3))
    return a > 1e-6 * longest * longest


@given(_triangle)
@example(((0.0, 0.0), (1.0, 0.0), (0.5, math.sqrt(3) / 2)))
@example(((0.0, 0.0), (1.0, 0.0), (0.0, 1.0)))
def test_radius_ratio_equals_reference(t):
    pts, tri = _one(t)
    rho = bm.radius_ratio(pts, tri)
    assert rho.shape == (1,) and 0.0 <= rho[0] <= 1.0
    if _well_conditioned(pts):
        assert rho[0] == pytest.approx(O.radius_ratio_reference(pts, tri)[0], rel=1e-9, abs=1e-12)


@given(st.floats(1e-6, 1e6), st.floats(0, 2 * math.pi), _coord, _coord)
def test_radius_ratio_is_one_for_equilateral(size, angle, x, y):
    pts = np.array(
        [
            [
                x + size * math.cos(angle + k * 2 * math.pi / 3),
                y + size * math.sin(angle + k * 2 * math.pi / 3),
            ]
            for k in range(3)
        ]
    )
    assert bm.radius_ratio(pts, np.array([[0, 1, 2]]))[0] == pytest.approx(1.0, abs=1e-9)


@pytest.mark.parametrize("eps", [1e-1, 1e-3, 1e-6, 1e-9])
def test_radius_ratio_tends_to_zero_for_degenerate(eps):
    flat = np.array([[0.0, 0.0], [1.0, 0.0], [0.5, eps]])  # apex drops onto the base
    needle = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, eps]])  # one edge shrinks
    for pts in (flat, needle):
        rho = bm.radius_ratio(pts, np.array([[0, 1, 2]]))[0]
        ref = O.radius_ratio_reference(pts, np.array([[0, 1, 2]]))[0]
        assert rho == pytest.approx(ref, rel=1e-6)
        assert rho < 10 * eps


def test_radius_ratio_zero_for_collinear():
    pts = np.array([[0.0, 0.0], [1.0, 0.0], [3.0, 0.0]])
    assert bm.radius_ratio(pts, np.array([[0, 1, 2]]))[0] == 0.0


@given(_triangle)
@example(((0.0, -23726566 / 2**20), (1 / 2**20, 0.0), (1 / 2**20, 1 / 2**20)))
def test_angles_sum_to_180_and_match_reference(t):
    pts, tri = _one(t)
    ang = quality.angles(pts, tri)
    assert ang.shape == (1, 3)
    ref = O.angles_reference(pts, tri)
    # arccos of the law of cosines loses about sqrt(eps * longest/shortest side)
    # radians on needles (found by the thorough profile: an angle of 2.4e-6 deg
    # reported as 2.9e-3 deg at aspect ratio 2e7); tight where every angle is
    # above 1 degree, within that conditioning bound otherwise
    sides = [math.dist(pts[i], pts[(i + 1) % 3]) for i in range(3)]
    conditioning = math.degrees(math.sqrt(np.finfo(float).eps * max(sides) / min(sides)))
    tol = 1e-9 if ref.min() > 1.0 else 1e-5 + 10 * conditioning
    assert ang.sum() == pytest.approx(180.0, abs=tol)
    np.testing.assert_allclose(ang, ref, atol=tol)


@given(st.lists(_triangle, min_size=1, max_size=30))
def test_summary_matches_reference(ts):
    pts = np.vstack([_one(t)[0] for t in ts])
    tri = np.arange(len(pts)).reshape(-1, 3)
    s = quality.summary(pts, tri)
    rho = bm.radius_ratio(pts, tri)
    ang = quality.angles(pts, tri)
    assert s["count"] == len(tri)
    assert s["min"] == pytest.approx(rho.min()) and s["mean"] == pytest.approx(rho.mean())
    assert s["median"] == pytest.approx(np.median(rho))
    assert s["count_below_0_5"] == int((rho < 0.5).sum())
    assert s["count_below_0_7"] == int((rho < 0.7).sum())
    assert s["frac_below_0_5"] == pytest.approx((rho < 0.5).mean())
    assert s["frac_below_0_7"] == pytest.approx((rho < 0.7).mean())
    assert s["min_angle_deg"] == pytest.approx(ang.min()) and s["max_angle_deg"] == pytest.approx(
        ang.max()
    )
    # and the radius ratios themselves follow the reference where it is accurate
    ref = O.radius_ratio_reference(pts, tri)
    ok = [_well_conditioned(pts[3 * k : 3 * k + 3]) for k in range(len(tri))]
    np.testing.assert_allclose(rho[ok], ref[ok], rtol=1e-9, atol=1e-12)
