"""Frontal insertion (bubblemesh._frontal), the sized §2 of bm.mesh on large
domains with a size cap, against independent checks:

- the §2 mesh is valid, conforming and constrained-Delaunay by the exact
  oracles (Bowyer-Watson insertion keeps the CDT), boundary nodes first and
  unmoved;
- the stop: every triangle's circumradius, recomputed in numpy from the
  coordinates and the size field, is within the acceptance threshold (but
  for a few where a node would have crowded another), and inserted nodes
  keep CROWD h from their neighbours, from any start;
- the frontal node of a front edge is the apex of the isosceles triangle of
  circumradius max(h / sqrt(3), |ab| / 2), closed forms; an input corner
  wider than CORNER_OPEN is never left as one triangle;
- the walk returns a triangle that holds the point (exact orientation in
  rationals) or refuses a point off the domain's interior;
- the rows make a lattice: most interior nodes have six triangles, and the
  §2 mesh's mean radius ratio beats centroid insertion's by far;
- bm.mesh's automatic choice (its documented rule) and the frontal
  pipeline's guarantees: valid, conforming, input nodes kept, never worse
  than its §2 mesh, deterministic.
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import oracles as O
import pytest
from hypothesis import given
from hypothesis import strategies as st
from test_pipeline import corner_domains

import bubblemesh as bm
from bubblemesh._frontal import ACCEPT, CROWD, WALL_ACCEPT, frontal_point, walk_to
from bubblemesh._lattice import lattice_points
from bubblemesh.generation import generate_sized
from bubblemesh.pipeline import (
    ALIGN_OVER,
    ALIGN_PIECES,
    ALIGN_SLACK,
    FRONTAL_ELEMENTS,
    _frontal_wanted,
    _user_size,
    _wall_frame,
    refined_domain,
)
from bubblemesh.refinement import refine_boundary
from bubblemesh.sizing import SizeField


def _refined(loops, size):
    domain = bm.Domain.from_loops(loops)
    field = SizeField.from_domain(domain, size=size)
    return refine_boundary(domain, field).to_domain(), field


def _disk(n, radius=1.0):
    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return [radius * np.column_stack([np.cos(t), np.sin(t)])]


def _circumradii(P, T):
    a, b, c = P[T[:, 0]], P[T[:, 1]], P[T[:, 2]]
    la = np.hypot(*(b - c).T)
    lb = np.hypot(*(c - a).T)
    lc = np.hypot(*(a - b).T)
    area2 = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    return la * lb * lc / (2.0 * area2), np.stack([la, lb, lc], axis=1)


@given(corner_domains(max_holes=2), st.sampled_from([0.3, 0.12]))
def test_frontal_generation_is_a_valid_conforming_cdt(loops, size):
    fine, field = _refined(loops, size)
    m = generate_sized(fine, field, frontal=True)
    O.check_valid(m.points, m.triangles, m.neighbors)
    O.check_conforming(m.points, m.triangles, m.segments, area=fine.area, rel=1e-9)
    O.check_constrained_delaunay(m.points, m.triangles, m.segments)
    np.testing.assert_array_equal(m.points[: m.n_boundary], fine.points)
    assert m.generation.stop == "front"


@given(corner_domains(max_holes=2), st.sampled_from([0.3, 0.12]))
def test_frontal_triangles_meet_their_bubbles(loops, size):
    """The front stops when no triangle is active: a triangle's circumradius
    is at most ACCEPT h(centroid) / sqrt(3), on the walls WALL_ACCEPT times
    that of max(h, its longest boundary edge), except where a node would have
    come too close to another (CROWD): a few."""
    fine, field = _refined(loops, size)
    m = generate_sized(fine, field, frontal=True)
    P, T, N = np.asarray(m.points), np.asarray(m.triangles), np.asarray(m.neighbors)
    R, lengths = _circumradii(P, T)
    h = field(P[T].mean(axis=1))
    wall = (N < 0).any(axis=1)
    reach = np.where(N < 0, lengths, 0.0).max(axis=1)
    limit = np.where(wall, WALL_ACCEPT * np.maximum(h, reach), ACCEPT * h) / math.sqrt(3)
    missed = int(np.sum(R > limit * (1 + 1e-9)))
    assert missed <= max(2, len(T) // 100), f"{missed} of {len(T)} triangles not met"


@pytest.mark.parametrize("sides, divide", [(12, 200), (12, 500), (5, 20), (5, 40)])
def test_an_open_corner_gets_a_node_on_its_bisector(sides, divide):
    """Corners wider than CORNER_OPEN whose walls are split finer than the
    field (a gear's tooth tips, a regular pentagon's corners) are not left as
    one triangle: every such input corner has
    at least two triangles in the frontal §2 mesh.  Angles from the input
    loop in numpy."""
    from bubblemesh._frontal import CORNER_OPEN
    from bubblemesh.studies.geometry import gear

    if sides == 12:
        loop = gear(12, 1.0, 1.2, 10.0)  # its corners only
    else:
        t = 2 * np.pi * np.arange(sides) / sides
        loop = np.column_stack([np.cos(t), np.sin(t)])
    domain = bm.Domain.from_loops([loop])
    field = SizeField.from_domain(domain, size=math.sqrt(4 * domain.area / divide / math.sqrt(3)))
    fine = refine_boundary(domain, field).to_domain()
    m = generate_sized(fine, field, frontal=True)
    before, after = np.roll(loop, 1, axis=0) - loop, np.roll(loop, -1, axis=0) - loop
    cross = after[:, 0] * before[:, 1] - after[:, 1] * before[:, 0]
    angle = np.degrees(np.arctan2(cross, np.einsum("ij,ij->i", after, before)))
    wide = np.flatnonzero((angle % 360 > CORNER_OPEN) & (angle % 360 < 180))
    assert len(wide) >= 5  # the test's premise: open corners there are
    T = np.asarray(m.triangles)
    counts = np.bincount(T.ravel(), minlength=len(m.points))
    corners = [int(np.flatnonzero((np.asarray(m.points) == loop[i]).all(axis=1))[0]) for i in wide]
    assert (counts[corners] >= 2).all(), counts[corners]
    O.check_valid(m.points, T, m.neighbors)
    O.check_constrained_delaunay(m.points, T, m.segments)


@pytest.mark.parametrize("sides, per", [pytest.param(3, 2000, marks=pytest.mark.heavy),
                                        pytest.param(6, 2000, marks=pytest.mark.heavy),
                                        (3, 300), (6, 300)])
def test_a_domain_on_one_lattice_gets_that_lattice(sides, per):
    """An equilateral triangle and a regular hexagon given by their corners:
    their walls, cut into equal pieces, lie on one triangular lattice, and
    the lattice start laid along the longest wall through its first node
    fills them without a seam: every radius ratio (reference formula) at
    least 0.99.  At area / 300 the pieces come out 1.6% (triangle) and 1.4%
    (hexagon) longer than the field's size, and the triangle's perfect
    lattice has 3.2% fewer elements than the centroid mesh it competes with."""
    t = 2 * np.pi * np.arange(sides) / sides
    domain = bm.Domain.from_loops([np.column_stack([np.cos(t), np.sin(t)])])
    m = bm.mesh(domain, max_area=domain.area / per)
    piece = sides * np.hypot(*(domain.points[1] - domain.points[0])) / len(m.domain.points)
    size = _user_size(None, domain.area / per)
    assert (piece > size) == (per == 300)  # the premise
    q = O.radius_ratio_reference(np.asarray(m.points), np.asarray(m.triangles))
    assert q.min() >= 0.99 and q.mean() >= 0.999
    O.check_conforming(m.points, m.triangles, m.segments, area=domain.area, rel=1e-9)


@given(corner_domains(max_holes=2), st.sampled_from([0.3, 0.12, 0.05]))
def test_the_lattice_frame_lies_on_a_wall_cut_in_equal_pieces(loops, size):
    """A frame (origin, u, step) from _wall_frame: an input segment starts
    at the origin and runs along u, and its refined nodes are exactly
    origin + k step u, k = 0 .. pieces (to 1e-6 of a step, by projection),
    at least ALIGN_PIECES pieces, step within the cap's bounds."""
    domain = bm.Domain.from_loops(loops)
    field = SizeField.from_domain(domain, size=size)
    fine = refined_domain(domain, field)
    frame = _wall_frame(domain, fine, float(field.cap))
    if frame is None:
        return
    a, u, step = frame
    P, S = np.asarray(domain.points), np.asarray(domain.segments)
    ends = [P[j] - P[i] for i, j in S if np.array_equal(P[i], a)
            and np.allclose((P[j] - P[i]) / np.hypot(*(P[j] - P[i])), u, atol=1e-12)]
    assert len(ends) == 1
    length = float(np.hypot(*ends[0]))
    F = np.asarray(fine.points) - a
    on = np.abs(F[:, 0] * u[1] - F[:, 1] * u[0]) <= 1e-9 * length
    t = F[on, 0] * u[0] + F[on, 1] * u[1]
    k = np.sort(t[(t >= -1e-9 * length) & (t <= length * (1 + 1e-9))]) / step
    assert len(k) - 1 >= ALIGN_PIECES and np.abs(k - np.arange(len(k))).max() <= 1e-6
    assert (1 - ALIGN_SLACK) * field.cap <= step <= (1 + ALIGN_OVER) * field.cap


@pytest.mark.heavy
def test_a_wall_graded_toward_a_sharp_corner_does_not_set_the_lattice():
    """The 30-60 right triangle at area/500: its longest wall, the
    hypotenuse, is graded toward the 30 degree corner, so the lattice
    follows the vertical wall (20 pieces 2.1% over the size), whose nodes
    are lattice nodes: the triangles along it, away from the corners, are
    equilateral (reference formula)."""
    domain = bm.Domain.from_loops([np.array([(0, 0), (math.sqrt(3), 0), (0, 1)])])
    m = bm.mesh(domain, max_area=domain.area / 500, insertion="frontal")
    X, T = np.asarray(m.points), np.asarray(m.triangles)
    wall = (X[:, 0] == 0.0) & (X[:, 1] > 0.2) & (X[:, 1] < 0.8)
    along = wall[T].any(axis=1)
    assert along.sum() >= 20
    assert O.radius_ratio_reference(X, T[along]).min() >= 0.999


def _edges(T):
    return np.unique(np.sort(np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]]), 1), axis=0)


@given(corner_domains(max_holes=2), st.sampled_from([0.3, 0.12]),
       st.floats(0.3, 3.0))
def test_frontal_nodes_keep_apart_whatever_the_start(loops, size, margin):
    """Bowyer-Watson only makes edges at the node it inserts, and a node closer
    than CROWD h to a neighbour to be is not inserted: every edge with an
    inserted end is at least CROWD times the smaller h of its ends long, even
    from a start crowded against the walls (a lattice ``margin`` sizes off
    them, down to 0.3), so the run is bounded whatever the input."""
    fine, field = _refined(loops, size)
    seeds = lattice_points(fine.points, fine.segments, size, margin, field)
    m = generate_sized(fine, field, frontal=True, seeds=seeds)
    O.check_valid(m.points, m.triangles, m.neighbors)
    P = np.asarray(m.points)
    E = _edges(np.asarray(m.triangles))
    first = m.n_boundary + len(seeds)  # the boundary and the seeds come first
    inserted = (E >= first).any(axis=1)
    length = np.hypot(*(P[E[:, 0]] - P[E[:, 1]]).T)
    h = np.minimum(field(P[E[:, 0]]), field(P[E[:, 1]]))
    assert np.all(length[inserted] >= CROWD * h[inserted] * (1 - 1e-9))


def _one_triangle(c, a, b):
    P = np.array([c, a, b], dtype=np.float64)
    return P, np.array([[0, 1, 2]], np.int64)


@pytest.mark.parametrize("length, h", [(1.0, 1.0), (0.8, 1.0), (1.5, 1.0)])
def test_frontal_point_is_the_isosceles_apex(length, h):
    """Front edge ab of length L on the x-axis, the triangle's far corner high
    above (its circumcentre beyond any cap): the node lies on x = L / 2 at
    height rho + sqrt(rho^2 - (L/2)^2), rho = max(h / sqrt(3), L / 2): the
    equilateral apex for L = h, the right angle's for L >= 2 h / sqrt(3)."""
    P, T = _one_triangle((0.5 * length, 50.0), (0.0, 0.0), (length, 0.0))
    x, y = frontal_point(P, 0, T, 0, h)
    rho = max(h / math.sqrt(3), length / 2)
    assert x == pytest.approx(length / 2, abs=1e-12)
    assert y == pytest.approx(rho + math.sqrt(rho * rho - length * length / 4), rel=1e-12)
    if length == h:
        assert y == pytest.approx(math.sqrt(3) / 2 * h, rel=1e-12)


def test_frontal_point_stops_at_the_circumcentre():
    """A small triangle over ab against a large h: the node is t's
    circumcentre (at height 2/3, as far from (0, 0) as from (0.5, 1.5)), not
    the far-away ideal apex; with its circumcentre closer to ab than |ab| / 2,
    the top of the circle through a, b and that circumcentre."""
    P, T = _one_triangle((0.5, 1.5), (0.0, 0.0), (1.0, 0.0))
    assert frontal_point(P, 0, T, 0, 10.0) == pytest.approx((0.5, 2 / 3), abs=1e-12)
    P, T = _one_triangle((0.5, 0.7), (0.0, 0.0), (1.0, 0.0))
    q = (0.49 - 0.25) / 1.4  # the circumcentre's height, below |ab| / 2
    assert frontal_point(P, 0, T, 0, 10.0) == pytest.approx((0.5, 0.25 / q), abs=1e-12)


def _orient(p, q, r):
    p, q, r = ([Fraction(v) for v in u] for u in (p, q, r))
    return (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])


_TARGETS = st.lists(st.tuples(st.floats(-1.2, 1.2), st.floats(-1.2, 1.2)), max_size=20)


def _check_walk(loops, targets, complete):
    """Every triangle the walk returns holds the target (exact, in rationals,
    on at most one edge); a refused target is off the domain's interior or
    on a node, or (a walk is local) the boundary was in the way, which
    ``complete`` rules out."""
    domain = bm.Domain.from_loops(loops)
    P = np.asarray(domain.points)
    T, N = bm.constrained_delaunay(P, domain.segments)
    for q in targets:
        where = O.domain_location(P, domain.loops, q)
        t = walk_to(P, T, N, 0, q[0], q[1], 10 * len(T))
        if t < 0:
            on_node = any(tuple(p) == q for p in P.tolist())
            assert not complete or where <= 0 or on_node, q
            continue
        assert where > 0, f"{q} is not inside the domain but the walk found triangle {t}"
        signs = [_orient(P[T[t, k]], P[T[t, (k + 1) % 3]], q) for k in range(3)]
        assert min(signs) >= 0 and sum(s == 0 for s in signs) <= 1, (q, signs)


@given(corner_domains(max_holes=2), _TARGETS)
def test_walk_returns_a_triangle_holding_the_point(loops, targets):
    _check_walk(loops, targets, complete=False)


@given(st.lists(st.floats(0.0, 2 * np.pi), min_size=3, max_size=12, unique=True), _TARGETS)
def test_walk_reaches_every_point_of_a_convex_domain(angles, targets):
    """No boundary in the way: the visibility walk on a Delaunay triangulation
    reaches every point strictly inside."""
    t = np.sort(np.asarray(angles))
    corners = np.column_stack([np.cos(t), np.sin(t)])
    try:
        bm.Domain.from_loops([corners])
    except bm.GeometryError:
        return  # corners too close to each other for a valid loop
    _check_walk([corners], targets, complete=True)


def test_the_rows_make_a_lattice():
    """Uniform size on a disk: at least 90% of the interior nodes of the
    frontal §2 mesh have six triangles, and its mean radius ratio beats
    centroid insertion's by more than 0.05 (about 0.99 against 0.87)."""
    fine, field = _refined(_disk(160), 2 * np.pi / 160)
    frontal = generate_sized(fine, field, frontal=True)
    centroid = generate_sized(fine, field)
    count = np.bincount(np.asarray(frontal.triangles).ravel())[frontal.n_boundary:]
    assert np.mean(count == 6) >= 0.9
    q_front = bm.radius_ratio(frontal.points, frontal.triangles).mean()
    q_centre = bm.radius_ratio(centroid.points, centroid.triangles).mean()
    assert q_front > q_centre + 0.05


def test_auto_insertion_is_frontal_for_a_large_capped_field():
    """Frontal from FRONTAL_ELEMENTS equilateral triangles of the cap size up."""
    square = bm.Domain.from_loops([[(0, 0), (1, 0), (1, 1), (0, 1)]])
    enough = math.sqrt(1.0 / (FRONTAL_ELEMENTS * math.sqrt(3) / 4))  # the largest such cap
    for size, frontal in ((0.999 * enough, True), (1.001 * enough, False), (0.02, True)):
        field = SizeField.from_domain(square, size=size)
        assert _frontal_wanted("auto", square, field) is frontal, size
    uncapped = SizeField.from_domain(bm.Domain.from_loops(_disk(500)))  # no size: no cap
    assert not _frontal_wanted("auto", bm.Domain.from_loops(_disk(500)), uncapped)
    assert _frontal_wanted("frontal", square, uncapped)
    assert not _frontal_wanted("centroid", square, SizeField.from_domain(square, size=0.02))
    with pytest.raises(ValueError, match="insertion"):
        bm.mesh(square, insertion="sideways")


@pytest.mark.slow
def test_mesh_records_its_insertion():
    square = bm.Domain.from_loops([[(0, 0), (1, 0), (1, 1), (0, 1)]])
    assert bm.mesh(square, size=0.02).generation.insertion == "frontal"
    assert bm.mesh(square, size=0.1, insertion="centroid").generation.insertion == "centroid"
    small = bm.mesh(square, size=0.1)  # several tried: the record names the one returned
    if small.generation.seeds:  # (the one without frontal seeds has no public switch)
        again = bm.mesh(square, size=0.1, insertion=small.generation.insertion)
        assert np.array_equal(small.points, again.points)


@pytest.mark.heavy
@given(corner_domains(max_holes=2))
def test_frontal_mesh_is_valid_conforming_and_never_worse_than_its_generation(loops):
    domain = bm.Domain.from_loops(loops)
    m = bm.mesh(domain, max_area=domain.area / 100, insertion="frontal")
    O.check_valid(m.points, m.triangles, m.neighbors)
    O.check_conforming(m.points, m.triangles, m.segments, area=domain.area, rel=1e-9)
    have = {p.tobytes() for p in np.asarray(m.points[: m.n_boundary])}
    assert all(p.tobytes() in have for p in np.asarray(domain.points))
    q = bm.radius_ratio(m.points, m.triangles)
    # the record is the compiled kernel's ratio: on a perfect lattice it and
    # bm.radius_ratio's formula differ in the last bits
    assert q.min() >= m.optimization.min_ratio_generation - 1e-14
    # the front's first row is held like seeds and counted as such
    assert m.generation.seeds > 0


@pytest.mark.heavy
def test_frontal_mesh_is_deterministic():
    domain = bm.Domain.from_loops(_disk(48))
    one = bm.mesh(domain, size=0.12, insertion="frontal")
    two = bm.mesh(domain, size=0.12, insertion="frontal")
    for name in ("points", "triangles", "neighbors", "radii"):
        assert np.array_equal(getattr(one, name), getattr(two, name)), name
