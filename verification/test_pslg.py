"""Planar straight-line graph domains: interior constraints, free points,
nesting, markers, regions.  Oracles are independent of the mesher: exact
Fraction arithmetic for orientation and in-circle tests, shapely for faces
and areas, meshio and the gmsh API for files read back."""

import os
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st
from strategies import budget

import bubblemesh as bm
from bubblemesh.errors import GeometryError

TRIANGLE_DATA = Path(os.environ.get("BUBBLEMESH_TRIANGLE_DATA", "/work/ref/data"))
EXAMPLES = ["A", "box", "double_hex", "double_hex2", "double_hex3", "face", "la",
            "square_circle_hole"]


def orient(a, b, c):
    a, b, c = ([Fraction(float(v)) for v in p] for p in (a, b, c))
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])


def in_circle(a, b, c, d):
    rows = []
    for p in (a, b, c):
        x, y = Fraction(float(p[0])) - Fraction(float(d[0])), Fraction(float(p[1])) - Fraction(
            float(d[1]))
        rows.append((x, y, x * x + y * y))
    (a1, a2, a3), (b1, b2, b3), (c1, c2, c3) = rows
    return a1 * (b2 * c3 - b3 * c2) - a2 * (b1 * c3 - b3 * c1) + a3 * (b1 * c2 - b2 * c1)


def mesh_edges(triangles):
    e = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    return set(map(tuple, np.sort(e, axis=1).tolist()))


def assert_chain(points, triangles, a, b):
    """Segment a-b is an edge or a chain of mesh edges: the nodes on it, in
    order, are joined pairwise.  On it: exactly (Fraction orientation), or
    within 1e-12 of its length (the refinement's nodes a fraction of an ulp
    off a general segment, which no float point lies on exactly)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    d = b - a
    length = float(np.hypot(*d))
    rel = points - a
    off = np.abs(d[0] * rel[:, 1] - d[1] * rel[:, 0]) / length
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    near = np.flatnonzero((off <= 1e-12 * length) & np.all((points >= lo) & (points <= hi), 1))
    on = [int(i) for i in near]
    on.sort(key=lambda i: float(np.dot(points[i] - np.asarray(a, float), d)))
    edges = mesh_edges(triangles)
    assert len(on) >= 2
    for u, v in zip(on[:-1], on[1:]):
        assert tuple(sorted((u, v))) in edges, (a, b, u, v)


def assert_valid(mesh, area):
    P, T = mesh.points, mesh.triangles
    assert all(orient(P[a], P[b], P[c]) > 0 for a, b, c in T.tolist())
    total = sum(orient(P[a], P[b], P[c]) for a, b, c in T.tolist()) / 2
    assert abs(float(total) - area) <= 1e-9 * area
    assert len(np.unique(P, axis=0)) == len(P)


# --- the Triangle examples -------------------------------------------------------


@pytest.mark.parametrize("name", EXAMPLES)
def test_triangle_examples_mesh_with_every_segment_and_vertex(name):
    from bubblemesh.io import read_poly

    path = TRIANGLE_DATA / f"{name}.poly"
    if not path.exists():
        pytest.skip(f"{path} not here (Triangle's example files; set BUBBLEMESH_TRIANGLE_DATA)")
    poly = read_poly(path)
    domain = bm.Domain.from_poly(path)
    for mesh in (bm.generate(domain), bm.mesh(domain)):
        assert_valid(mesh, domain.area)
        index = {tuple(p): i for i, p in enumerate(mesh.points.tolist())}
        assert all(tuple(v) in index for v in poly.vertices.tolist())  # free vertices too
        for a, b in poly.segments.tolist():
            assert_chain(mesh.points, mesh.triangles, poly.vertices[a], poly.vertices[b])
        edges, marks = mesh.boundary_edges()
        if poly.segment_markers is not None:  # refined edges inherit their segment's marker
            on_file = set(poly.segment_markers.tolist()) | {1}
            assert set(marks.tolist()) <= on_file


def test_la_regions_are_the_faces_holding_the_region_points():
    shapely = pytest.importorskip("shapely")
    from shapely.ops import polygonize

    from bubblemesh.io import read_poly

    path = TRIANGLE_DATA / "la.poly"
    if not path.exists():
        pytest.skip(f"{path} not here")
    poly = read_poly(path)
    faces = list(polygonize([shapely.LineString(poly.vertices[s]) for s in poly.segments]))
    mesh = bm.mesh(bm.Domain.from_poly(path))
    ids = mesh.region_ids()
    centroids = mesh.points[mesh.triangles].mean(axis=1)
    owner = {}
    for r, (x, y) in enumerate(poly.regions[:, :2].tolist()):
        for f, face in enumerate(faces):
            if face.contains(shapely.Point(x, y)):
                owner[f] = r  # the later region point wins, as in Triangle
    for t in range(0, len(centroids), 7):
        face = [f for f, g in enumerate(faces) if g.contains(shapely.Point(*centroids[t]))]
        assert ids[t] == owner.get(face[0], -1) if face else ids[t] == -1


# --- interior constraints, free points, nesting ------------------------------------


SQUARE = np.array([(0, 0), (8, 0), (8, 8), (0, 8)], float)


@pytest.mark.heavy
def test_crack_interface_and_free_points_are_kept():
    crack = np.array([(1, 1), (3, 2), (5, 2)], float)  # open polyline
    ring = np.array([(5, 5), (7, 5), (7, 7), (5, 7), (5, 5)], float)  # closed interface
    free = np.array([(2, 6), (6.5, 1.5)])
    d = bm.Domain.from_pslg(loops=[SQUARE], constraints=[crack, ring], points=free)
    assert d.area == 64.0
    assert int(d.interior.sum()) == 2 * (2 + 4)
    for mesh in (bm.optimize(bm.generate(d)), bm.mesh(d, size=0.7)):
        assert_valid(mesh, 64.0)
        P = mesh.points
        for line in (crack, ring):
            for a, b in zip(line[:-1], line[1:]):
                assert_chain(P, mesh.triangles, a, b)
        index = {tuple(p) for p in P[: mesh.n_boundary].tolist()}
        assert {tuple(p) for p in free.tolist()} <= index  # fixed: among the first nodes
        assert {tuple(p) for p in crack.tolist()} <= index


def _ratios(P, T):
    """Eq. 10 from side lengths: 2r/R = 16 K^2 / (a b c (a + b + c)), K by the cross product."""
    a, b, c = (np.hypot(*(P[T[:, (k + 1) % 3]] - P[T[:, k]]).T) for k in range(3))
    u, v = P[T[:, 1]] - P[T[:, 0]], P[T[:, 2]] - P[T[:, 0]]
    area = 0.5 * np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0])
    return 16 * area**2 / (a * b * c * (a + b + c))


@pytest.mark.heavy
def test_a_few_free_points_cost_the_mesh_little():
    # a free point's eq. 1-2 bubble spans the distance to its nearest input node,
    # here ten sizes: left in §3, it pushed the lattice around it into clumps and holes
    square = [(0, 0), (1, 0), (1, 1), (0, 1)]
    free = [(0.3, 0.3), (0.7, 0.25), (0.5, 0.6), (0.2, 0.8), (0.8, 0.8)]
    plain = bm.mesh(bm.Domain.from_pslg(loops=[square]), size=0.03)
    dotted = bm.mesh(bm.Domain.from_pslg(loops=[square], points=free), size=0.03)
    assert {tuple(p) for p in free} <= {tuple(p) for p in dotted.points.tolist()}
    assert abs(len(dotted.triangles) / len(plain.triangles) - 1) < 0.03
    mean_plain = _ratios(plain.points, plain.triangles).mean()
    assert _ratios(dotted.points, dotted.triangles).mean() > mean_plain - 0.003


def test_islands_in_holes_nest_by_parity():
    hole = np.array([(1, 1), (7, 1), (7, 7), (1, 7)], float)
    island = np.array([(2, 2), (6, 2), (6, 6), (2, 6)], float)
    pond = np.array([(3, 3), (5, 3), (5, 5), (3, 5)], float)
    d = bm.Domain.from_pslg(loops=[SQUARE, hole, island, pond])
    assert d.area == 64 - 36 + 16 - 4
    mesh = bm.mesh(d, size=0.8)
    assert_valid(mesh, d.area)
    c = mesh.points[mesh.triangles].mean(axis=1)
    inside = lambda box: np.all((c > box.min(0)) & (c < box.max(0)), axis=1)  # noqa: E731
    assert not np.any(inside(hole) & ~inside(island))  # the hole is empty
    assert np.any(inside(island) & ~inside(pond))  # the island is meshed
    assert not np.any(inside(pond))  # the pond in the island is a hole again


def test_crossing_constraints_are_split_at_the_crossing():
    """The domain is the one given the crossing as a node (which the next
    test meshes): the same points and segments."""
    cross = [[(1, 1), (7, 7)], [(1, 7), (7, 1)]]
    d = bm.Domain.from_pslg(loops=[SQUARE], constraints=cross)
    given = bm.Domain.from_pslg(loops=[SQUARE], constraints=cross, points=[(4, 4)])
    assert len(d.points) == 4 + 4 + 1 and d.points[-1].tolist() == [4.0, 4.0]

    def edges(domain):
        return {tuple(map(tuple, domain.points[s].tolist())) for s in domain.segments}

    assert edges(d) == edges(given) and d.area == given.area == 64.0


def exact_crossing(p, q, r, s):
    """The crossing point of segments pq and rs in Fractions, or None where
    they do not cross properly (each one's ends strictly on both sides of the
    other's line)."""
    if not (orient(p, q, r) * orient(p, q, s) < 0 and orient(r, s, p) * orient(r, s, q) < 0):
        return None
    p, q = [Fraction(float(v)) for v in p], [Fraction(float(v)) for v in q]
    t = orient(r, s, p) / (orient(r, s, p) - orient(r, s, q))
    return p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])


@st.composite
def crossing_lines(draw):
    """2-6 segments with ends drawn in (0.5, 7.5)^2 in the 8 x 8 square, no
    two sharing an end; crossing points at least 1e-6 from every end."""
    coord = st.floats(0.5, 7.5, allow_nan=False, allow_infinity=False)
    n = draw(st.integers(2, 6))
    lines = [np.array([[draw(coord), draw(coord)], [draw(coord), draw(coord)]])
             for _ in range(n)]
    ends = np.vstack(lines)
    assume(len(np.unique(ends, axis=0)) == len(ends))
    assume(all(np.hypot(*(b - a)) > 1e-3 for a, b in lines))
    for i, (p, q) in enumerate(lines):
        for r, s in lines[:i]:
            x = exact_crossing(p, q, r, s)
            if x is not None:
                x = np.array([float(x[0]), float(x[1])])
                assume(np.hypot(*(ends - x).T).min() > 1e-6)
            else:
                assume(all(orient(u, v, w) != 0 for u, v in ((p, q), (r, s))
                           for w in ((r, s) if u is p else (p, q))))
    return lines


@budget(30)
@given(crossing_lines())
def test_crossing_constraints_meet_at_the_rounded_exact_crossing(lines):
    """Every proper crossing (Fraction orientation) becomes one vertex at the
    exact crossing rounded to the nearest float (Python's Fraction -> float),
    no other vertex is added, and each constraint is the chain of domain
    segments through its crossings in order (the mesher keeps every segment:
    the tests above and below)."""
    crossings: dict = {}  # rounded point -> the lines through it
    for i, (p, q) in enumerate(lines):
        for j, (r, s) in enumerate(lines[:i]):
            x = exact_crossing(p, q, r, s)
            if x is not None:
                crossings.setdefault((float(x[0]), float(x[1])), set()).update((i, j))
    d = bm.Domain.from_pslg(loops=[SQUARE], constraints=lines)
    at = {p: k for k, p in enumerate(map(tuple, d.points.tolist()))}
    added = set(at) - {tuple(p) for p in SQUARE.tolist()} - {
        tuple(p) for line in lines for p in line.tolist()}
    assert added == set(crossings)
    segments = {tuple(s) for s in d.segments[d.interior].tolist()}
    for i, (p, q) in enumerate(lines):
        on = sorted([x for x, through in crossings.items() if i in through],
                    key=lambda x: (x[0] - p[0]) * (q[0] - p[0]) + (x[1] - p[1]) * (q[1] - p[1]))
        chain = [at[tuple(p)], *(at[x] for x in on), at[tuple(q)]]
        for u, v in zip(chain[:-1], chain[1:]):
            assert (u, v) in segments and (v, u) in segments, (p, q)
    pieces = sum(1 + sum(i in through for through in crossings.values())
                 for i in range(len(lines)))
    assert len(segments) == 2 * pieces  # both ways, and no other split


def test_a_constraint_a_rounding_error_past_a_wall_joins_it():
    d = bm.Domain.from_pslg(loops=[SQUARE], constraints=[[(4, 4), (3, -1e-17)]])
    assert len(d.points) == 6  # no vertex a rounding error from the constraint's end
    mesh = bm.mesh(d, size=1.0)
    assert_chain(mesh.points, mesh.triangles, (4, 4), (3, -1e-17))
    assert abs(float(sum(orient(*mesh.points[t]) for t in mesh.triangles) / 2) - 64.0) < 1e-9


def test_nearly_equal_nodes_whose_segments_cross_are_named():
    end = (8 + 2.0 ** -47, 4 + 2.0 ** -48)  # meant to be the wall's node (8, 4), past it
    with pytest.raises(GeometryError, match=r"nodes .* apart and their segments cross"):
        bm.Domain.from_pslg(loops=[[(0, 0), (8, 0), (8, 4), (8, 8), (0, 8)]],
                            constraints=[[(4, 4), end]])


def test_crossing_loops_are_refused():
    with pytest.raises(GeometryError, match=r"loops cross: segment \(8.0, 0.0\)-\(8.0, 8.0\)"):
        bm.Domain.from_pslg(loops=[SQUARE, SQUARE + 4])


@pytest.mark.heavy
def test_a_vertex_at_the_crossing_splits_both_constraints():
    cross = [[(1, 1), (7, 7)], [(1, 7), (7, 1)]]
    d = bm.Domain.from_pslg(loops=[SQUARE], constraints=cross, points=[(4, 4)])
    mesh = bm.mesh(d, size=1.0)
    assert_valid(mesh, 64.0)
    for a in [(1, 1), (7, 7), (1, 7), (7, 1)]:
        assert_chain(mesh.points, mesh.triangles, a, (4, 4))


def test_overlapping_collinear_constraints_are_merged():
    d = bm.Domain.from_pslg(loops=[SQUARE], constraints=[[(2, 4), (6, 4)], [(4, 4), (7, 4)],
                                                         [(0, 2), (3, 2)]])
    T, _ = bm.constrained_delaunay(d.points, d.segments)
    at = {tuple(p): i for i, p in enumerate(d.points.tolist())}
    edges = mesh_edges(T)
    for a, b in [((2, 4), (4, 4)), ((4, 4), (6, 4)), ((6, 4), (7, 4))]:
        assert tuple(sorted((at[a], at[b]))) in edges
    walls = set(map(tuple, np.sort(d.segments, axis=1).tolist()))
    assert tuple(sorted((at[(2, 4)], at[(6, 4)]))) not in walls
    # (0, 2) lies on the outer loop: the piece below it is still a loop edge
    assert d.area == 64.0 and int((~d.interior).sum()) == 5


def write_square_poly(path, midpoint_first=False):
    """A .poly square whose bottom side (marker 3) is one segment, its midpoint
    a vertex of no segment; the other sides have marker 1."""
    corners = [(0, 0), (8, 0), (8, 8), (0, 8)]
    vertices = [(4, 0)] + corners if midpoint_first else corners + [(4, 0)]
    at = {v: i + 1 for i, v in enumerate(vertices)}
    sides = [((0, 0), (8, 0), 3), ((8, 0), (8, 8), 1), ((8, 8), (0, 8), 1), ((0, 8), (0, 0), 1)]
    lines = [f"{len(vertices)} 2 0 0"] + [f"{i + 1} {x} {y}" for i, (x, y) in enumerate(vertices)]
    lines += ["4 1"] + [f"{k + 1} {at[a]} {at[b]} {m}" for k, (a, b, m) in enumerate(sides)]
    lines += ["0"]
    path.write_text("\n".join(lines) + "\n")


@pytest.mark.parametrize("midpoint_first", [False, pytest.param(True, marks=pytest.mark.heavy)])
def test_a_vertex_on_a_segment_splits_it_and_keeps_the_marker(tmp_path, midpoint_first):
    path = tmp_path / "split.poly"
    write_square_poly(path, midpoint_first)
    for d in (bm.Domain.from_poly(path),
              bm.Domain.from_pslg(loops=[SQUARE], points=[(4, 0)], markers=[3])):
        assert d.area == 64.0
        for mesh in (bm.generate(d), bm.mesh(d, size=1.5)):
            assert_valid(mesh, 64.0)
            at = {tuple(p): i for i, p in enumerate(mesh.points.tolist())}
            assert (4.0, 0.0) in at
            assert_chain(mesh.points, mesh.triangles, (0, 0), (4, 0))
            assert_chain(mesh.points, mesh.triangles, (4, 0), (8, 0))
            edges, marks = mesh.boundary_edges()
            bottom = (mesh.points[edges][:, :, 1] == 0.0).all(axis=1)
            assert bottom.sum() >= 2
            assert np.all(marks[bottom] == 3)
            if 1 in d.markers:  # the .poly: the other sides keep their own marker
                assert np.all(marks[~bottom] == 1)
        paper = bm.generate(d)  # no refinement: the two halves are exactly edges
        at = {tuple(p): i for i, p in enumerate(paper.points.tolist())}
        halves = {tuple(sorted((at[(0.0, 0.0)], at[(4.0, 0.0)]))),
                  tuple(sorted((at[(4.0, 0.0)], at[(8.0, 0.0)])))}
        assert halves <= mesh_edges(paper.triangles)


@st.composite
def on_segment_graphs(draw):
    """A 64-square, a segment a-b (a loop side or an interior constraint) and
    vertices a + j (b - a) / m strictly inside it, all with integer
    coordinates, so exactly on it; plus free integer points."""
    m = draw(st.integers(2, 6))
    dx, dy = draw(st.sampled_from([(1, 0), (0, 1), (1, 1), (1, -1), (2, 1), (1, 3), (-3, 2)]))
    step = draw(st.integers(1, 3))
    dx, dy = dx * step, dy * step
    lo_x, hi_x = max(1, 1 - m * dx), min(63, 63 - m * dx)
    lo_y, hi_y = max(1, 1 - m * dy), min(63, 63 - m * dy)
    if lo_x > hi_x or lo_y > hi_y:
        dx, dy, lo_x, hi_x, lo_y, hi_y = 1, 0, 1, 50, 1, 50
    ax, ay = draw(st.integers(lo_x, hi_x)), draw(st.integers(lo_y, hi_y))
    js = draw(st.lists(st.integers(1, m - 1), min_size=1, max_size=m - 1, unique=True))
    on = [(ax + j * dx, ay + j * dy) for j in sorted(js)]
    a, b = (ax, ay), (ax + m * dx, ay + m * dy)
    free = draw(st.lists(st.tuples(st.integers(1, 63), st.integers(1, 63)), max_size=6,
                         unique=True))
    free = [p for p in free if orient(a, b, p) != 0]  # Fractions: off the segment's line
    return a, b, on, free


@pytest.mark.heavy
@budget(30)
@given(on_segment_graphs())
def test_vertices_exactly_on_a_segment_split_it(graph):
    a, b, on, free = graph
    box = np.array([(0, 0), (64, 0), (64, 64), (0, 64)], float)
    d = bm.Domain.from_pslg(loops=[box], constraints=[[a, b]], points=on + free)
    P = d.points
    at = {tuple(p): i for i, p in enumerate(P.tolist())}
    chain = [at[tuple(map(float, p))] for p in [a, *on, b]]
    walls = set(map(tuple, np.sort(d.segments, axis=1).tolist()))
    expected = {tuple(sorted(e)) for e in zip(chain[:-1], chain[1:])}
    assert expected <= walls  # each piece a constraint ...
    assert tuple(sorted((chain[0], chain[-1]))) not in walls  # ... not the whole segment
    T, N = bm.constrained_delaunay(P, d.segments)
    assert_valid(bm.Mesh(P, T, N, np.ones(len(P)), d.segments, len(P)), 4096.0)
    assert expected <= mesh_edges(T)
    mesh = bm.mesh(d, size=8.0)
    assert_valid(mesh, 4096.0)
    for u, v in zip([a, *on], [*on, b]):
        assert_chain(mesh.points, mesh.triangles, u, v)


@pytest.mark.heavy
def test_vertices_on_a_loop_side_split_it():
    box = np.array([(0, 0), (64, 0), (64, 64), (0, 64)], float)
    on = [(16, 0), (40, 0), (64, 32), (10, 54)]  # (10, 54) on the diagonal constraint
    d = bm.Domain.from_pslg(loops=[box], constraints=[[(0, 64), (64, 0)]], points=on,
                            markers=[2, 5])
    assert int((~d.interior).sum()) == 7 and int(d.interior.sum()) == 2 * 2
    mesh = bm.mesh(d, size=6.0)
    assert_valid(mesh, 4096.0)
    edges, marks = mesh.boundary_edges()
    E = mesh.points[edges]
    on_diagonal = (E.sum(axis=2) == 64.0).all(axis=1)
    assert np.all(marks[on_diagonal] == 5) and np.all(marks[~on_diagonal] == 2)


# --- exact constrained-Delaunay property with interior constraints ----------------


@st.composite
def graphs(draw):
    """A square, random interior integer points, and a random subset of the
    edges of a triangulation of them as interior constraints (edges of one
    triangulation never cross); the other points are free."""
    from scipy.spatial import Delaunay

    n = draw(st.integers(4, 14))
    pts = draw(st.lists(st.tuples(st.integers(1, 31), st.integers(1, 31)), min_size=n,
                        max_size=n, unique=True))
    box = np.array([(0, 0), (32, 0), (32, 32), (0, 32)], float)
    P = np.array(pts, float)
    try:
        tri = Delaunay(P).simplices
    except Exception:  # collinear draws: no constraints
        tri = np.zeros((0, 3), int)
    edges = sorted(mesh_edges(tri)) if len(tri) else []
    picks = draw(st.lists(st.sampled_from(edges), max_size=6, unique=True)) if edges else []
    return box, [P[list(e)] for e in picks], P


@budget(25)
@given(graphs())
def test_constrained_delaunay_with_interior_constraints_is_exact(graph):
    box, constraints, free = graph
    d = bm.Domain.from_pslg(loops=[box], constraints=constraints, points=free)
    T, N = bm.constrained_delaunay(d.points, d.segments)
    P = d.points
    assert_valid(bm.Mesh(P, T, N, np.ones(len(P)), d.segments, len(P)), 1024.0)
    walls = set(map(tuple, np.sort(d.segments, axis=1).tolist()))
    edges = mesh_edges(T)
    assert walls <= edges  # conformity: every constraint is an edge
    for t, row in enumerate(T.tolist()):
        for j in range(3):
            u, v = row[(j + 1) % 3], row[(j + 2) % 3]
            n = N[t, j]
            if tuple(sorted((u, v))) in walls:
                assert n == -1  # no neighbour across a constraint: walls for every walk
                continue
            assert n >= 0
            w = [x for x in T[n].tolist() if x not in (u, v)][0]
            # locally Delaunay across every unconstrained edge, hence a CDT
            assert in_circle(P[row[0]], P[row[1]], P[row[2]], P[w]) <= 0


@pytest.mark.heavy
@budget(8)
@given(graphs())
def test_default_mesher_honours_interior_constraints_and_free_points(graph):
    box, constraints, free = graph
    d = bm.Domain.from_pslg(loops=[box], constraints=constraints, points=free)
    mesh = bm.mesh(d, size=6.0)
    assert_valid(mesh, 1024.0)
    for line in constraints:
        assert_chain(mesh.points, mesh.triangles, line[0], line[1])
    assert {tuple(p) for p in free.tolist()} <= {tuple(p) for p in mesh.points.tolist()}


# --- markers in files --------------------------------------------------------------


def marked_mesh():
    crack = np.array([(2, 4), (6, 4)], float)
    d = bm.Domain.from_pslg(loops=[SQUARE], constraints=[crack], markers=[7, 9],
                            names={"wall": 7, "crack": 9})
    return bm.mesh(d, size=1.0)


def test_msh_round_trip_keeps_markers_and_names(tmp_path):
    meshio = pytest.importorskip("meshio")
    mesh = marked_mesh()
    mesh.write(tmp_path / "m.msh")
    m = meshio.read(tmp_path / "m.msh")
    lines = [(c.data, d) for c, d in zip(m.cells, m.cell_data["gmsh:physical"])
             if c.type == "line"]  # Gmsh 4.1: one block per marker
    data, tags = (np.concatenate(x) for x in zip(*lines))
    assert set(tags.tolist()) == {7, 9}
    assert {k: int(v[0]) for k, v in m.field_data.items()} == {"wall": 7, "crack": 9}
    P = m.points[:, :2]
    on_crack = (P[data][:, :, 1] == 4.0).all(axis=1) & (P[data][:, :, 0] > 0).all(axis=1) & (
        P[data][:, :, 0] < 8).all(axis=1)
    assert np.all(tags[on_crack] == 9) and np.all(tags[~on_crack] == 7)
    back = bm.read(tmp_path / "m.msh")
    _, marks = back.boundary_edges()
    assert set(marks.tolist()) == {7, 9} and dict(back.marker_names) == {"wall": 7, "crack": 9}


def test_gmsh_api_reads_the_physical_groups(tmp_path):
    gmsh = pytest.importorskip("gmsh")
    marked_mesh().write(tmp_path / "m.msh")
    gmsh.initialize(["-v", "0"])
    try:
        gmsh.open(str(tmp_path / "m.msh"))
        groups = {gmsh.model.getPhysicalName(dim, tag): tag
                  for dim, tag in gmsh.model.getPhysicalGroups(1)}
    finally:
        gmsh.finalize()
    assert groups == {"wall": 7, "crack": 9}


def test_xdmf_facet_tags(tmp_path):
    meshio = pytest.importorskip("meshio")
    from bubblemesh.interop import write_xdmf

    mesh = marked_mesh()
    cells, facets = write_xdmf(mesh, tmp_path / "m.xdmf")
    f = meshio.read(facets)
    assert [c.type for c in f.cells] == ["line"]
    assert set(f.cell_data["markers"][0].tolist()) == {7, 9}
    assert [c.type for c in meshio.read(cells).cells] == ["triangle"]


# --- shapely input and regional sizes ------------------------------------------------


@pytest.mark.heavy
def test_shapely_multipolygon_lines_and_points():
    shapely = pytest.importorskip("shapely")
    two = shapely.MultiPolygon([shapely.box(0, 0, 4, 4), shapely.box(6, 0, 10, 4)])
    crack = shapely.LineString([(1, 1), (3, 3)])
    d = bm.Domain.from_shapely(two, spacing=1.0, constraints=[crack],
                               points=shapely.MultiPoint([(8, 2)]))
    assert d.area == pytest.approx(two.area, rel=1e-15)
    mesh = bm.mesh(d, size=0.8)
    assert_valid(mesh, two.area)
    assert_chain(mesh.points, mesh.triangles, (1, 1), (3, 3))
    assert (8.0, 2.0) in {tuple(p) for p in mesh.points.tolist()}
    # shapely's oracle: the union of the triangles is the MultiPolygon
    cover = shapely.union_all([shapely.Polygon(mesh.points[t]) for t in mesh.triangles])
    assert cover.symmetric_difference(two).area <= 1e-9 * two.area


@pytest.mark.heavy
def test_region_max_area_bounds_the_mean_element_area():
    left, right = (1.0, 4.0, 0.0, 0.02), (7.0, 4.0, 1.0, 0.5)
    wall = np.array([(4, 0), (4, 8)], float)
    square = np.array([(0, 0), (4, 0), (8, 0), (8, 8), (4, 8), (0, 8)], float)
    d = bm.Domain.from_pslg(loops=[square], constraints=[wall], regions=[left, right])
    mesh = bm.mesh(d, size=d.region_size())
    P, T = mesh.points, mesh.triangles
    area = np.array([float(orient(P[a], P[b], P[c])) / 2 for a, b, c in T.tolist()])
    ids = mesh.region_ids()
    c = P[T].mean(axis=1)
    assert np.array_equal(ids, np.where(c[:, 0] < 4, 0, 1))  # the wall separates the regions
    for r, (_, _, _, max_area) in enumerate((left, right)):
        assert area[ids == r].mean() <= max_area
    assert area[ids == 0].mean() < area[ids == 1].mean() / 3  # graded across the wall
