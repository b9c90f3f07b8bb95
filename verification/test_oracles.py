"""The oracles checked on their own: they must pass on output of trusted
peers (scipy/Qhull, Shewchuk's Triangle) and fail on deliberately broken
triangulations.  An oracle that cannot fail proves nothing."""

from __future__ import annotations

import math

import numpy as np
import oracles as O
import pytest
import strategies as S
from hypothesis import given

# --------------------------------------------------------------------------- helpers


def _flips(triangles, segments=()):
    """Every triangulation obtained by flipping one interior non-segment edge
    whose quadrilateral is strictly convex (so the result is still valid)."""
    tri = np.asarray(triangles)
    fixed = {(min(a, b), max(a, b)) for a, b in np.asarray(segments).reshape(-1, 2).tolist()}
    opp = {}
    for t, r in enumerate(tri.tolist()):
        for i in range(3):
            opp[(r[(i + 1) % 3], r[(i + 2) % 3])] = (t, r[i])
    for (a, b), (t, x) in opp.items():
        if a < b and (b, a) in opp and (a, b) not in fixed:
            u, y = opp[(b, a)]
            f = tri.copy()
            f[t] = [x, a, y]
            f[u] = [y, b, x]
            yield f


def _valid(points, tri):
    try:
        O.check_valid(points, tri)
    except AssertionError:
        return False
    return True


def _pslg(case):
    return case.points, case.segments()


# --------------------------------------------------------------------------- exact arithmetic


def test_exact_integers_are_exact():
    pts = np.array([[0.1, -3.0], [1e-8, 1e8], [5e-324, 0.0], [np.nextafter(1.0, 2.0), 0.5]])
    P, shift = O.exact_integers(pts)
    from fractions import Fraction

    for (x, y), (X, Y) in zip(pts.tolist(), P, strict=False):
        assert Fraction(X, 1 << shift) == Fraction(x)
        assert Fraction(Y, 1 << shift) == Fraction(y)


def test_exact_predicates_on_known_signs():
    # the classic near-collinear failure of float orientation
    a, b, c = (0.5, 0.5), (12.0, 12.0), (24.0, 24.0)
    assert O.orient2d_sign(*a, *b, *c) == 0
    c2 = (24.0, float(np.nextafter(24.0, 25.0)))
    assert O.orient2d_sign(*a, *b, *c2) == 1
    # four exactly cocircular lattice points, then one nudged in by an ulp
    p = S.CIRCLE_325
    q = [tuple(p[i]) for i in (0, 10, 25, 40)]
    if O.orient2d_sign(*q[0], *q[1], *q[2]) < 0:
        q[0], q[1] = q[1], q[0]
    assert O.incircle_sign(*q[0], *q[1], *q[2], *q[3]) == 0
    d = q[3]
    inward = (float(np.nextafter(d[0], 0.0)), d[1])
    assert O.incircle_sign(*q[0], *q[1], *q[2], *inward) == 1


# --------------------------------------------------------------------------- Delaunay oracles


@pytest.mark.peers
@given(S.general_points(min_size=4, max_size=80))
def test_emptiness_oracle_accepts_scipy_and_rejects_flips(case):
    spatial = pytest.importorskip("scipy.spatial")
    pts = case.points
    if not O.convex_hull_exact(pts):
        return  # all collinear: nothing to triangulate
    tri = O.ccw_triangles(pts, spatial.Delaunay(pts).simplices)
    O.check_valid(pts, tri)
    if not O.delaunay_is_unique(pts, tri):
        return  # qhull may break the tie any way: only the unique case is checked
    O.check_delaunay_empty(pts, tri)
    O.check_locally_delaunay(pts, tri)
    assert O.euler_ok(tri, 0)
    for flipped in _flips(tri):
        if _valid(pts, flipped):
            with pytest.raises(AssertionError, match="strictly inside"):
                O.check_delaunay_empty(pts, flipped)
            with pytest.raises(AssertionError, match="not locally Delaunay"):
                O.check_locally_delaunay(pts, flipped)
            break


@pytest.mark.peers
@given(S.general_points(min_size=3, max_size=80))
def test_exact_hull_matches_scipy(case):
    spatial = pytest.importorskip("scipy.spatial")
    pts = case.points
    hull = O.convex_hull_exact(pts)
    if not hull:
        return
    P, _ = O.exact_integers(pts)
    # corners: hull points where the boundary turns strictly
    corners = {
        tuple(pts[h])
        for k, h in enumerate(hull)
        if O.orient_int(P[hull[k - 1]], P[h], P[hull[(k + 1) % len(hull)]]) > 0
    }
    qh = {tuple(pts[i]) for i in spatial.ConvexHull(pts).vertices}
    assert corners == qh


def test_hull_keeps_collinear_boundary_points():
    grid = np.array([[i, j] for i in range(3) for j in range(3)], dtype=float)
    hull = O.convex_hull_exact(grid)
    assert len(hull) == 8 and 4 not in hull  # every point but the centre
    assert O.convex_hull_exact(np.array([[0.0, 0], [1, 1], [2, 2]])) == []


# --------------------------------------------------------------------------- constrained oracles


@pytest.mark.peers
@given(S.domains(max_holes=3))
def test_constrained_oracles_accept_triangle_and_reject_mutants(case):
    triangle = pytest.importorskip("triangle")
    pts, seg = _pslg(case)
    args = dict(vertices=pts, segments=seg)
    if case.n_holes:
        args["holes"] = case.hole_points
    out = triangle.triangulate(args, "pYY")
    assert np.array_equal(out["vertices"], pts)
    tri = O.ccw_triangles(pts, out["triangles"])
    O.check_valid(pts, tri)
    assert O.euler_ok(tri, case.n_holes)
    O.check_conforming(pts, tri, seg)
    O.check_constrained_delaunay(pts, tri, seg)
    O.check_locally_delaunay(pts, tri, seg)

    # global definition and local lemma agree on every valid one-flip mutant
    for n, flipped in enumerate(_flips(tri, seg)):
        if n >= 15:
            break
        if not _valid(pts, flipped):
            continue
        local = glob = True
        try:
            O.check_locally_delaunay(pts, flipped, seg)
        except AssertionError:
            local = False
        try:
            O.check_constrained_delaunay(pts, flipped, seg)
        except AssertionError:
            glob = False
        assert local == glob
        if O.delaunay_is_unique(pts, tri, seg):
            assert not glob  # flipping an edge of the unique CDT breaks it

    # a triangle left inside a hole / a lost segment are caught
    if case.n_holes:
        filled = O.ccw_triangles(
            pts, triangle.triangulate(dict(vertices=pts, segments=seg), "pYY")["triangles"]
        )
        with pytest.raises(AssertionError):
            O.check_conforming(pts, filled, seg)
        assert not O.euler_ok(filled, case.n_holes)


def test_visibility_through_a_gap():
    """Hand-made: triangle (0,0),(2,0),(1,1) seen from v=(1,-1) past a
    horizontal obstacle at y=-1/2."""
    pts = [(0, 0), (2, 0), (1, 1), (1, -1), (0.5, -0.5), (1.5, -0.5), (0.6, -0.5)]
    P, _ = O.exact_integers(np.array(pts, dtype=float))
    t = [0, 1, 2]
    assert O.visible_from_triangle(P, t, 3, [])
    assert not O.visible_from_triangle(P, t, 3, [(0, 1)])  # t's own edge blocks
    # the obstacle from (0.5,-0.5) to (1.5,-0.5) spans the whole view exactly
    assert not O.visible_from_triangle(P, t, 3, [(4, 5)])
    # shortened by 0.1 on the left: a thin sliver of t is visible
    assert O.visible_from_triangle(P, t, 3, [(6, 5)])
    # an obstacle incident to v blocks only one direction
    assert O.visible_from_triangle(P, t, 3, [(3, 2)])


def test_constrained_check_hidden_vs_visible():
    """A vertex inside a circumcircle is allowed only while a segment hides it."""
    pts = np.array([[0, 0], [4, 0], [2, 0.5], [2, -0.2], [0, -3], [4, -3]], dtype=float)
    # upper triangle 0-1-2 is flat, its circumcircle contains vertex 3 below edge 0-1
    tri = np.array([[0, 1, 2], [0, 3, 1], [0, 4, 3], [3, 4, 5], [3, 5, 1]])
    O.check_valid(pts, tri)
    with pytest.raises(AssertionError, match="visible"):
        O.check_constrained_delaunay(pts, tri, [])
    O.check_constrained_delaunay(pts, tri, [(0, 1)])


# --------------------------------------------------------------------------- validity details


def test_valid_rejects_bad_neighbours_and_orientation():
    pts = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float)
    tri = np.array([[0, 1, 2], [0, 2, 3]])
    nbr = np.array([[-1, 1, -1], [-1, -1, 0]])
    O.check_valid(pts, tri, nbr)
    with pytest.raises(AssertionError, match="neighbo"):
        O.check_valid(pts, tri, np.array([[-1, -1, -1], [-1, -1, 0]]))
    with pytest.raises(AssertionError, match="clockwise"):
        O.check_valid(pts, tri[:, ::-1])
    with pytest.raises(AssertionError, match="duplicates"):
        O.check_valid(pts, np.vstack([tri, [[1, 2, 0]]]))
    with pytest.raises(AssertionError, match="same direction"):
        O.check_valid(pts, np.array([[0, 1, 2], [0, 1, 3]]))
    assert O.euler_ok(tri, 0) and not O.euler_ok(tri, 1)


def test_conforming_catches_a_moved_boundary_edge():
    pts = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float)
    seg = [(0, 1), (1, 2), (2, 3), (3, 0)]
    O.check_conforming(pts, [[0, 1, 2], [0, 2, 3]], seg)
    with pytest.raises(AssertionError, match="not a mesh edge"):
        O.check_conforming(pts, [[0, 1, 3], [1, 2, 3]], [*seg, (0, 2)])
    with pytest.raises(AssertionError, match="on its right"):
        O.check_conforming(pts, [[0, 1, 2], [0, 2, 3]], [(b, a) for a, b in seg])


# --------------------------------------------------------------------------- references


def test_radius_ratio_reference_known_values():
    h = math.sqrt(3) / 2
    pts = np.array([[0, 0], [1, 0], [0.5, h], [0, 1], [2, 0], [1, 0]], dtype=float)
    rho = O.radius_ratio_reference(pts, [[0, 1, 2], [0, 1, 3], [0, 5, 4]])
    assert rho[0] == pytest.approx(1.0, rel=1e-12)
    assert rho[1] == pytest.approx(2 * math.sqrt(2) - 2, rel=1e-12)  # right isoceles
    assert rho[2] == 0.0


def test_boundary_radii_reference_eq2():
    pts = np.array([[0, 0], [3, 0], [3, 4]], dtype=float)
    r = O.boundary_radii_reference(pts, [(0, 1), (1, 2), (2, 0)])
    assert r[1] == pytest.approx(math.sqrt(math.sqrt(3) / (8 * math.pi) * (9 + 16)))
    # eq. 1 -> eq. 2: pi r^2 equals the mean area of the two equilateral triangles
    assert math.pi * r[0] ** 2 == pytest.approx(0.5 * (math.sqrt(3) / 4) * (9 + 25))


def test_population_reference_on_equal_radii():
    # equal node radii interpolate to the same element radius (eq. 3)
    pts = np.array([[0, 0], [1, 0], [0, 1], [1, 1]], dtype=float)
    area = O.population_bubble_area(pts, [[0, 1, 2], [1, 3, 2]], [0.2] * 4)
    assert area == pytest.approx(2 * math.pi * 0.04)


@pytest.mark.peers
@given(S.domains(max_holes=3))
def test_fast_centroid_location_equals_exact(case):
    """The vectorised float path of locate_centroids agrees with the exact
    one, here on Triangle's triangulation of the convex hull (holes filled),
    so centroids lie inside, in holes and outside the outer loop."""
    triangle = pytest.importorskip("triangle")
    pts, seg = _pslg(case)
    out = triangle.triangulate({"vertices": pts, "segments": seg}, "pcYY")
    tri = O.ccw_triangles(pts, out["triangles"])
    P, _ = O.exact_integers(pts)
    loops = O.split_outer(P, O.loops_from_segments(seg))
    fast = O.locate_centroids(pts, tri, loops, P)
    assert np.array_equal(fast, O.locate_centroids(pts, tri, loops, P, exact=True))


def test_centroid_exactly_on_a_loop_is_found():
    pts = np.array([[0, 0], [3, 0], [3, 3], [0, 3], [0, -1], [1, 1], [2, 0], [1, 2]], float)
    loops = [[0, 1, 2, 3]]
    P, _ = O.exact_integers(pts)
    tri = np.array([[4, 6, 5], [5, 6, 7], [0, 1, 4]])  # centroids (1,0) on, (1,1) in, below
    got = O.locate_centroids(pts, tri, loops, P)
    assert got.tolist() == [0, 1, -1]
    assert got.tolist() == O.locate_centroids(pts, tri, loops, P, exact=True).tolist()
