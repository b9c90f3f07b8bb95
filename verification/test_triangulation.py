"""bubblemesh.delaunay and bubblemesh.constrained_delaunay.

Properties (each against an oracle in oracles.py or a peer library):
- validity, Euler, exact (constrained) Delaunay emptiness, hull / conformity;
- the same triangle set as scipy.spatial.Delaunay and as Triangle ('pYY')
  whenever the answer is unique (no exactly cocircular flippable edge);
- GeometryError for < 3 distinct points or all collinear;
- determinism, and invariance under translation / scaling by 2^k and 90 degree
  rotation (exact transformations: exact predicates give the same signs).
"""

from __future__ import annotations

import math

import numpy as np
import oracles as O
import pytest
import strategies as S
from hypothesis import example, given, note
from hypothesis import strategies as st

import bubblemesh as bm

# --------------------------------------------------------------------------- helpers


def _distinct_and_collinear(points):
    """(number of distinct positions, all collinear?) decided exactly."""
    P, _ = O.exact_integers(points)
    distinct = list(dict.fromkeys(P))
    if len(distinct) < 3:
        return len(distinct), True
    a, b = distinct[0], distinct[1]
    return len(distinct), all(O.orient_int(a, b, c) == 0 for c in distinct[2:])


def _coord_set(points, triangles):
    """Triangles as sets of coordinate triples (rotation-normalised), so two
    triangulations that pick different copies of a duplicate compare equal."""
    pts = np.asarray(points)
    out = set()
    for t in O.canonical_triangles(triangles):
        c = [tuple(pts[i]) for i in t]
        k = min(range(3), key=lambda i: c[i])
        out.add(tuple((c * 2)[k : k + 3]))
    return out


def _check_delaunay(points, tri):
    """All the properties of an unconstrained Delaunay triangulation."""
    pts = np.asarray(points)
    assert tri.dtype == np.int64 and tri.ndim == 2 and tri.shape[1] == 3
    O.check_valid(pts, tri)
    assert O.euler_ok(tri, 0), "V - E + F != 1"
    O.check_delaunay_empty(pts, tri)
    # every distinct position is a vertex exactly once (duplicates left out)
    used = np.unique(tri)
    used_xy = [tuple(p) for p in pts[used]]
    assert len(set(used_xy)) == len(used_xy), "two vertices at the same position"
    assert set(used_xy) == {tuple(p) for p in pts}, "some distinct input point is not a vertex"
    # boundary = the exact convex hull, traversed CCW, collinear hull points included
    hull = O.convex_hull_exact(pts)
    hull_edges = {
        (tuple(pts[hull[k]]), tuple(pts[hull[(k + 1) % len(hull)]])) for k in range(len(hull))
    }
    bnd = {(tuple(pts[a]), tuple(pts[b])) for a, b in O.boundary_edges(tri)}
    assert bnd == hull_edges, "boundary edges are not the convex hull"


# --------------------------------------------------------------------------- delaunay


@given(S.kernel_points())
@example(S.PointCase(S.CIRCLE_325, kind="all 60 lattice points on the circle"))
@example(S.PointCase(np.vstack([S.CIRCLE_325, [[0.0, 0.0]]]), kind="lattice circle + centre"))
@example(S.PointCase([[0.0, 0.0], [1.0, 0.0], [0.0, 0.0]], kind="two distinct"))
def test_delaunay_properties(case):
    _delaunay_properties(case)


def _delaunay_properties(case):
    pts = case.points
    distinct, collinear = _distinct_and_collinear(pts)
    if distinct < 3 or collinear:
        with pytest.raises(bm.GeometryError):
            bm.delaunay(pts)
        return
    tri = bm.delaunay(pts)
    note(f"{len(tri)} triangles")
    _check_delaunay(pts, tri)


@given(S.degenerate_points())
def test_delaunay_degenerate_inputs(case):
    """The families that break triangulators, on their own (more examples)."""
    _delaunay_properties(case)


@pytest.mark.parametrize(
    "pts",
    [
        [[0.0, 0.0]],
        [[0.0, 0.0], [1.0, 1.0]],
        [[0.0, 0.0], [1.0, 1.0], [2.0, 2.0], [3.0, 3.0]],
        [[1.0, 2.0]] * 5,
        [[0.0, 0.0], [1.0, 0.0], [0.0, 0.0], [1.0, 0.0]],
    ],
)
def test_delaunay_rejects_degenerate_input(pts):
    with pytest.raises(bm.GeometryError):
        bm.delaunay(np.array(pts, dtype=float))


@pytest.mark.peers
@given(S.general_points(min_size=3, max_size=60))
def test_delaunay_matches_scipy(case):
    spatial = pytest.importorskip("scipy.spatial")
    pts = case.points
    if _distinct_and_collinear(pts)[1]:
        return
    ours = bm.delaunay(pts)
    if not O.delaunay_is_unique(pts, ours):
        return  # several Delaunay triangulations exist: properties are tested elsewhere
    theirs = O.ccw_triangles(pts, spatial.Delaunay(pts).simplices)
    assert O.canonical_triangles(ours) == O.canonical_triangles(theirs)


@pytest.mark.peers
@given(S.general_points(min_size=3, max_size=60))
def test_delaunay_hull_matches_scipy(case):
    spatial = pytest.importorskip("scipy.spatial")
    pts = case.points
    if _distinct_and_collinear(pts)[1]:
        return
    tri = bm.delaunay(pts)
    P, _ = O.exact_integers(pts)
    bnd = O.boundary_edges(tri)
    nxt = dict(bnd)
    prv = {b: a for a, b in bnd}
    corners = {tuple(pts[v]) for v in nxt if O.orient_int(P[prv[v]], P[v], P[nxt[v]]) > 0}
    assert corners == {tuple(pts[i]) for i in spatial.ConvexHull(pts).vertices}


@given(S.kernel_points())
def test_delaunay_is_deterministic(case):
    pts = case.points
    distinct, collinear = _distinct_and_collinear(pts)
    if distinct < 3 or collinear:
        return
    first = bm.delaunay(pts)
    again = bm.delaunay(pts.copy())
    assert np.array_equal(first, again)


_transform = st.sampled_from(["translate", "scale", "rotate"])


def _apply(pts, how, k):
    if how == "translate":
        t = np.array([math.ldexp(1.0, k), -math.ldexp(1.0, k // 2)])
        moved = pts + t
        return moved, bool(np.array_equal(moved - t, pts))
    if how == "scale":
        return np.ldexp(pts, k), True
    return np.column_stack([-pts[:, 1], pts[:, 0]]), True


@given(
    st.one_of(S.general_points(max_size=40), S.grid_points(), S.circle_lattice_points()),
    _transform,
    st.integers(-20, 30),
)
def test_delaunay_invariant_under_exact_transformations(case, how, k):
    """Translation/scaling by 2^k and rotation by 90 degrees are exact, so the
    exact predicates see the same signs: the triangles must be the same.  For
    rotation this is only required where the triangulation is unique (a
    rotation may legitimately break cocircular ties differently)."""
    pts = case.points
    if _distinct_and_collinear(pts)[1]:
        return
    moved, exact = _apply(pts, how, k)
    if not exact:
        return
    ours = bm.delaunay(pts)
    theirs = bm.delaunay(moved)
    _check_delaunay(moved, theirs)
    if how == "rotate" and not O.delaunay_is_unique(pts, ours):
        return
    assert O.canonical_triangles(ours) == O.canonical_triangles(theirs)


# --------------------------------------------------------------------------- constrained


def _check_cdt(case, points, segments, tri, nbr):
    O.check_valid(points, tri, nbr)
    assert tri.dtype == np.int64 and nbr.dtype == np.int64
    # conformity first: its messages say which segment / triangle is wrong
    O.check_conforming(points, tri, segments)
    assert O.euler_ok(tri, case.n_holes), f"Euler characteristic {O.euler_characteristic(tri)}"
    O.check_constrained_delaunay(points, tri, segments)


@st.composite
def domains_with_interior_points(draw, max_holes=4):
    """A random domain plus up to 30 random points strictly inside it."""
    case = draw(S.domains(max_holes=max_holes))
    raw = draw(
        st.lists(
            st.tuples(st.integers(-1000, 1000), st.integers(-1000, 1000)), max_size=30, unique=True
        )
    )
    pts = case.points
    P, shift = O.exact_integers(np.vstack([pts, np.array(raw, dtype=float).reshape(-1, 2) / 1000]))
    loops = O.split_outer(P, O.loops_from_segments(case.segments()))
    extra = [
        (x / 1000, y / 1000)
        for (x, y), q in zip(raw, P[len(pts) :], strict=False)
        if O.domain_location(P, loops, q) > 0
    ]
    return case, np.array(extra, dtype=float).reshape(-1, 2)


@given(S.domains())
def test_constrained_delaunay_of_boundary(case):
    pts, seg = case.points, case.segments()
    tri, nbr = bm.constrained_delaunay(pts, seg)
    _check_cdt(case, pts, seg, tri, nbr)
    assert set(np.unique(tri)) == set(range(len(pts))), "a boundary node is not a vertex"


@given(domains_with_interior_points())
def test_constrained_delaunay_with_interior_points(arg):
    case, extra = arg
    pts = np.vstack([case.points, extra])
    seg = case.segments()
    tri, nbr = bm.constrained_delaunay(pts, seg)
    _check_cdt(case, pts, seg, tri, nbr)
    assert set(np.unique(tri)) == set(range(len(pts))), "an input point is not a vertex"


@pytest.mark.peers
@given(domains_with_interior_points())
def test_constrained_delaunay_matches_triangle(arg):
    triangle = pytest.importorskip("triangle")
    case, extra = arg
    pts = np.vstack([case.points, extra])
    seg = case.segments()
    ours, _ = bm.constrained_delaunay(pts, seg)
    args = {"vertices": pts, "segments": seg}
    if case.n_holes:
        args["holes"] = case.hole_points
    out = triangle.triangulate(args, "pYY")
    assert np.array_equal(out["vertices"], pts), "Triangle added or moved points"
    theirs = O.ccw_triangles(pts, out["triangles"])
    if not O.delaunay_is_unique(pts, theirs, seg):
        return
    assert O.canonical_triangles(ours) == O.canonical_triangles(theirs)


@given(S.domains(max_holes=2))
def test_constrained_delaunay_is_deterministic(case):
    pts, seg = case.points, case.segments()
    t1, n1 = bm.constrained_delaunay(pts, seg)
    t2, n2 = bm.constrained_delaunay(pts.copy(), seg.copy())
    assert np.array_equal(t1, t2) and np.array_equal(n1, n2)


@given(S.domains(max_holes=2), _transform, st.integers(-20, 30))
def test_constrained_delaunay_invariant_under_exact_transformations(case, how, k):
    pts, seg = case.points, case.segments()
    moved, exact = _apply(pts, how, k)
    if not exact:
        return
    ours, _ = bm.constrained_delaunay(pts, seg)
    theirs, nbr = bm.constrained_delaunay(moved, seg)
    _check_cdt(case, moved, seg, theirs, nbr)
    if how == "rotate" and not O.delaunay_is_unique(pts, ours, seg):
        return
    assert O.canonical_triangles(ours) == O.canonical_triangles(theirs)


def test_constrained_delaunay_on_grid_square_with_square_hole():
    """Every interior quad of a grid is cocircular: a degenerate CDT input."""
    n = 6
    ring = [(i, 0) for i in range(n)] + [(n, j) for j in range(n)]
    ring += [(n - i, n) for i in range(n)] + [(0, n - j) for j in range(n)]
    hole = [(2, 2), (2, 3), (2, 4), (3, 4), (4, 4), (4, 3), (4, 2), (3, 2)]
    inner = [(x, y) for x in range(1, n) for y in range(1, n) if not (2 <= x <= 4 and 2 <= y <= 4)]
    case = S.DomainCase(
        loops=(np.array(ring, float), np.array(hole, float)), hole_points=np.array([[3.0, 3.0]])
    )
    pts = np.vstack([case.points, np.array(inner, float)])
    seg = case.segments()
    tri, nbr = bm.constrained_delaunay(pts, seg)
    _check_cdt(case, pts, seg, tri, nbr)


@pytest.mark.parametrize(
    "points",
    [
        [[0.0, 0.0], [0.0, 1.0], [0.0, -0.5], [5e-324, 1.0]],
        [[0.0, 0.0], [0.0, 0.0009765625], [0.0, -0.5], [5e-324, 0.0009765625]],
        [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1e31, 1.0]],
    ],
)
def test_delaunay_refuses_coordinates_outside_the_exact_range(points):
    """Outside the predicates' exact range (nonzero |x| in [2**-100, 2**100])
    the library must refuse with a GeometryError naming the point, rather than
    return a triangulation decided by underflowed or overflowed products."""
    with pytest.raises(bm.GeometryError, match="point 3"):
        bm.delaunay(np.array(points))


@given(st.lists(st.integers(0, 2**32 - 1), max_size=300), st.integers(0, 2**16))
def test_radix_argsort_is_numpys_stable_argsort(values, spread):
    """The insertion order's sort (Hilbert keys < 4**16, two 16-bit digits)
    against numpy's stable argsort; keys folded to few distinct values so
    that ties (which must keep their input order) are common."""
    from bubblemesh._ordering import _radix_argsort

    keys = np.array(values, dtype=np.int64)
    if spread:
        keys = keys % (spread + 1) * (2**32 // (spread + 1))
    assert np.array_equal(_radix_argsort(keys, 2), np.argsort(keys, kind="stable"))


@pytest.mark.parametrize("bits", [1, 2, 3, 4, 6])
def test_hilbert_keys_walk_the_grid_one_cell_at_a_time(bits):
    """On the full 2**bits square grid the keys are 0 .. 4**bits - 1, each
    once, and cells of consecutive keys are edge neighbours (the Hilbert
    curve's defining property), in one thread and in the pool alike."""
    from bubblemesh._ordering import _hilbert_keys, _hilbert_keys_serial

    side = 2**bits
    xy = np.array([(x, y) for x in range(side) for y in range(side)], np.float64)
    for keys in (_hilbert_keys_serial(xy, bits), _hilbert_keys(xy, bits)):
        assert sorted(keys.tolist()) == list(range(side * side))
        path = xy[np.argsort(keys)]
        assert (np.abs(np.diff(path, axis=0)).sum(axis=1) == 1).all()


@given(st.lists(st.tuples(st.floats(-1e3, 1e3), st.floats(-1e3, 1e3)), min_size=1,
                max_size=60))
def test_the_small_insertion_order_is_the_pools(points):
    """Below SMALL points the keys come from one thread: the same keys, and
    the same stable order, as the pool's."""
    from bubblemesh._ordering import _hilbert_keys, _hilbert_keys_serial, hilbert_order

    P = np.array(points, np.float64)
    keys = _hilbert_keys(P, 16)
    assert np.array_equal(_hilbert_keys_serial(P, 16), keys)
    assert np.array_equal(hilbert_order(P), np.argsort(keys, kind="stable"))


@given(st.lists(st.tuples(st.integers(0, 12), st.integers(0, 12)), max_size=150))
def test_a_segment_is_interior_exactly_when_its_reverse_is_given(pairs):
    """Segment flags, for a patch's few segments and a domain's many, against
    a set of the given pairs."""
    from bubblemesh._cdt import BOUNDARY, INTERIOR
    from bubblemesh.triangulation import segment_flags

    given_pairs = set(pairs)
    expected = [INTERIOR if (b, a) in given_pairs else BOUNDARY for a, b in pairs]
    assert segment_flags(np.array(pairs, np.int64).reshape(-1, 2)).tolist() == expected


def _properly_cross(P, s, t):
    """Exact: do segments s and t cross at a point interior to both?"""
    a, b = (tuple(int(c) for c in P[i]) for i in s)
    c, d = (tuple(int(c) for c in P[i]) for i in t)
    return (O.orient_int(a, b, c) * O.orient_int(a, b, d) < 0
            and O.orient_int(c, d, a) * O.orient_int(c, d, b) < 0)


@given(st.lists(st.tuples(st.integers(0, 6), st.integers(0, 6)), min_size=4, max_size=12,
                unique=True),
       st.lists(st.tuples(st.integers(0, 11), st.integers(0, 11)), min_size=1, max_size=6))
def test_crossing_segments_are_refused_never_dropped(points, pairs):
    """Segments that properly cross (exact integer oracle) raise a GeometryError
    naming both (a dropped
    constraint used to give a triangulation without it, silently): the exact
    oracle and the triangulation agree on whether any two segments cross."""
    P = np.array(points, dtype=np.float64)
    S = [(a, b) for a, b in pairs if a < len(P) and b < len(P) and a != b]
    if not S:
        return
    crossing = any(_properly_cross(P, s, t) for i, s in enumerate(S) for t in S[i + 1:])
    try:
        bm.constrained_delaunay(P, np.array(S))
    except bm.GeometryError as error:
        if "cross" in str(error):
            assert crossing, f"no two segments cross, yet: {error}"
        return  # collinear input or a vertex on a segment: other checks cover these
    assert not crossing, "crossing segments were accepted"
