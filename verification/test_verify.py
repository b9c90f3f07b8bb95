"""bubblemesh.verify, the checker for anyone's mesh: it must accept meshes of
trusted peers (Triangle, Gmsh) and name what is wrong in broken ones.  The
expected answers come from brute force in the tests (Fraction arithmetic,
the peers' own input), never from the checker's output."""

from __future__ import annotations

import ast
import subprocess
import sys
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from strategies import budget

from bubblemesh import verify
from bubblemesh.verify.delaunay import circumcircles
from bubblemesh.verify.exact import ExactPoints, incircle_signs, orient_signs

SQUARE = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.3, 0.3], [0.6, 0.3], [0.6, 0.6],
                   [0.3, 0.6]], dtype=float)
SEGMENTS = np.array([[0, 1], [1, 2], [2, 3], [3, 0], [4, 5], [5, 6], [6, 7], [7, 4]])
HOLE = np.array([[0.45, 0.45]])


def _triangle_mesh(opts="pYY", extra=200, seed=1):
    """Triangle's CDT of the square with a hole and random interior points."""
    triangle = pytest.importorskip("triangle")
    rng = np.random.default_rng(seed)
    inner = rng.random((extra, 2))
    inner = inner[~((inner > 0.29) & (inner < 0.61)).all(axis=1)]  # none in or near the hole
    verts = np.vstack([SQUARE, inner])
    out = triangle.triangulate(dict(vertices=verts, segments=SEGMENTS, holes=HOLE), opts)
    tri = out["triangles"].astype(np.int64)
    return out["vertices"], tri


def _F(p):
    return Fraction(p[0]), Fraction(p[1])


def _orient(a, b, c):
    a, b, c = _F(a), _F(b), _F(c)
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])


def _incircle(a, b, c, d):
    rows = []
    for p in (a, b, c):
        x, y = _F(p)[0] - _F(d)[0], _F(p)[1] - _F(d)[1]
        rows.append((x, y, x * x + y * y))
    (a1, a2, a3), (b1, b2, b3), (c1, c2, c3) = rows
    return a1 * (b2 * c3 - b3 * c2) - a2 * (b1 * c3 - b3 * c1) + a3 * (b1 * c2 - b2 * c1)


def _convex_flips(pts, tri, fixed):
    """Interior non-segment edges whose quadrilateral is strictly convex and
    not cocircular, with the flipped triangle array (brute force, Fractions)."""
    opp = {}
    for t, r in enumerate(tri.tolist()):
        for i in range(3):
            opp[(r[(i + 1) % 3], r[(i + 2) % 3])] = (t, r[i])
    for (a, b), (t, x) in opp.items():
        if a < b and (b, a) in opp and (a, b) not in fixed:
            u, y = opp[(b, a)]
            P = pts
            if _orient(P[x], P[a], P[y]) > 0 and _orient(P[y], P[b], P[x]) > 0 \
                    and _incircle(P[a], P[b], P[x], P[y]) != 0:
                flipped = tri.copy()
                flipped[t], flipped[u] = [x, a, y], [y, b, x]
                yield (a, b), (x, y), (t, u), flipped


# --------------------------------------------------------------------------- peers accepted


@pytest.mark.peers
def test_triangle_cdt_is_reported_valid_and_constrained_delaunay():
    pts, tri = _triangle_mesh("pYY")
    assert np.array_equal(pts[: len(SQUARE)], SQUARE)
    report = verify.check(pts, tri, SEGMENTS, SQUARE, holes=HOLE)
    assert report.ok, report.summary()
    assert report.splits == {}  # Y forbids Steiner points on segments
    assert report.facts["euler"] == 0  # a square with one hole: 1 - 1
    assert "constrained" in report.checks["delaunay"]


@pytest.mark.peers
def test_triangle_quality_mesh_reports_its_segment_splits():
    """With 'q' Triangle splits segments; each split node must lie exactly on
    its segment (Fraction check here), and the checker lists exactly those."""
    pts, tri = _triangle_mesh("pq30a0.005", extra=0)
    report = verify.check(pts, tri, SEGMENTS, SQUARE, holes=HOLE, split_tol=0.0)
    assert report.ok, report.summary()
    expected = {}
    for k, (a, b) in enumerate(SEGMENTS.tolist()):
        on = [v for v in range(len(SQUARE), len(pts))
              if _orient(SQUARE[a], SQUARE[b], pts[v]) == 0
              and min(SQUARE[a][0], SQUARE[b][0]) <= pts[v][0] <= max(SQUARE[a][0], SQUARE[b][0])
              and min(SQUARE[a][1], SQUARE[b][1]) <= pts[v][1] <= max(SQUARE[a][1], SQUARE[b][1])]
        if on:
            expected[k] = set(on)
    assert {k: set(c[1:-1]) for k, c in report.splits.items()} == expected
    strict = verify.check(pts, tri, SEGMENTS, SQUARE, holes=HOLE, allow_splits=False)
    assert {v.segment for v in strict.of_kind("split_segment")} == set(expected)


@pytest.mark.peers
def test_gmsh_mesh_file_is_valid_and_conforming(tmp_path):
    """Gmsh's default 2-D algorithm is not guaranteed Delaunay, so its
    Delaunay verdict is compared with a brute-force local test (by the
    constrained Delaunay lemma, global and local agree on a valid conforming
    mesh) instead of being assumed."""
    gmsh = pytest.importorskip("gmsh")
    from bubblemesh.io import write_poly

    gmsh.initialize(["-noenv"])
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("sq")
        ids = [gmsh.model.geo.addPoint(x, y, 0, 0.08) for x, y in SQUARE.tolist()]
        outer = [gmsh.model.geo.addLine(ids[i], ids[(i + 1) % 4]) for i in range(4)]
        inner = [gmsh.model.geo.addLine(ids[4 + i], ids[4 + (i + 1) % 4]) for i in range(4)]
        loops = [gmsh.model.geo.addCurveLoop(outer), gmsh.model.geo.addCurveLoop(inner)]
        gmsh.model.geo.addPlaneSurface(loops)
        gmsh.model.geo.synchronize()
        gmsh.model.mesh.generate(2)
        gmsh.write(str(tmp_path / "sq.msh"))
    finally:
        gmsh.finalize()
    write_poly(tmp_path / "sq.poly", SQUARE, SEGMENTS, HOLE)
    report = verify.check_file(tmp_path / "sq.msh", boundary=tmp_path / "sq.poly")
    delaunay_kinds = {"not_delaunay"}
    others = [v for v in report.violations if v.kind not in delaunay_kinds]
    assert not others, report.summary()
    assert len(report.splits) == len(SEGMENTS)  # Gmsh refines every boundary line
    pts, tri = verify.read_mesh(tmp_path / "sq.msh")
    bad_local = 0
    opp = {}
    for r in tri.tolist():
        for i in range(3):
            opp[(r[(i + 1) % 3], r[(i + 2) % 3])] = r[i]
    on_boundary = {tuple(sorted(e)) for c in report.splits.values() for e in zip(c, c[1:])}
    for r in tri.tolist():
        for i in range(3):
            a, b = r[(i + 1) % 3], r[(i + 2) % 3]
            if (b, a) in opp and tuple(sorted((a, b))) not in on_boundary:
                bad_local += _incircle(*(pts[j, :2] for j in r), pts[opp[(b, a)], :2]) > 0
    assert (report.count("not_delaunay") > 0) == (bad_local > 0)


# --------------------------------------------------------------------------- broken meshes


@pytest.mark.peers
def test_one_flipped_edge_is_named():
    pts, tri = _triangle_mesh("pYY")
    (a, b), (x, y), (t, u), flipped = next(_convex_flips(pts, tri, set()))
    assert verify.check(pts, tri, SEGMENTS, SQUARE, holes=HOLE).ok
    report = verify.check(pts, flipped, SEGMENTS, SQUARE, holes=HOLE)
    assert {v.kind for v in report.violations} == {"not_delaunay"}, report.summary()
    named = {tuple(sorted(v.edge)) for v in report.violations if v.edge is not None}
    assert named == {tuple(sorted((x, y)))}
    assert {v.triangle for v in report.violations} <= {t, u}
    assert {v.node for v in report.violations} >= {a, b}  # each inside the other's new circle


@pytest.mark.peers
def test_removed_triangle_names_the_hole_edges():
    pts, tri = _triangle_mesh("pYY")
    nb = len(SQUARE)
    interior = [t for t, r in enumerate(tri.tolist()) if min(r) >= nb]
    k = interior[len(interior) // 2]
    report = verify.check(pts, np.delete(tri, k, axis=0), SEGMENTS, SQUARE, holes=HOLE)
    assert not report.ok
    r = tri[k].tolist()
    hole_edges = {tuple(sorted((r[i], r[(i + 1) % 3]))) for i in range(3)}
    assert {tuple(sorted(v.edge)) for v in report.of_kind("extra_boundary_edge")} == hole_edges
    assert report.count("area") == 1 and report.count("euler") == 1


@pytest.mark.peers
def test_removed_boundary_triangle_loses_its_segment():
    pts, tri = _triangle_mesh("pYY")
    seg_edges = {tuple(sorted(s)) for s in SEGMENTS.tolist()}
    def on_segments(r):
        return {tuple(sorted((r[i], r[(i + 1) % 3]))) for i in range(3)} & seg_edges

    k = next(t for t, r in enumerate(tri.tolist()) if on_segments(r))
    mine = on_segments(tri[k].tolist())
    report = verify.check(pts, np.delete(tri, k, axis=0), SEGMENTS, SQUARE, holes=HOLE)
    lost = {v.segment for v in report.of_kind("missing_segment")}
    want = {i for i, s in enumerate(SEGMENTS.tolist()) if tuple(sorted(s)) in mine}
    assert lost == want


@pytest.mark.peers
def test_clockwise_triangle_is_reported_by_id():
    pts, tri = _triangle_mesh("pYY")
    bad = tri.copy()
    bad[17] = bad[17][::-1]
    report = verify.check(pts, bad, SEGMENTS, SQUARE, holes=HOLE)
    assert [v.triangle for v in report.of_kind("orientation")] == [17]


@pytest.mark.peers
@pytest.mark.parametrize("node", [0, 5])
def test_moved_boundary_node_is_reported(node):
    pts, tri = _triangle_mesh("pYY")
    moved = pts.copy()
    moved[node, 1] = np.nextafter(moved[node, 1], 2.0)  # one ulp: still a fine mesh
    report = verify.check(moved, tri, SEGMENTS, SQUARE, holes=HOLE)
    assert [v.node for v in report.of_kind("boundary_moved")] == [node]


def test_outside_triangle_and_frame():
    """A square of two triangles checked against a smaller domain (the lower
    half): the upper triangle's centroid is outside."""
    pts = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0, 0.5], [1, 0.5]], float)
    tri = np.array([[0, 1, 5], [0, 5, 4], [4, 5, 2], [4, 2, 3]])
    lower = [(0, 1), (1, 5), (5, 4), (4, 0)]
    report = verify.check(pts, tri, lower)
    assert sorted({v.triangle for v in report.of_kind("outside_domain")}) == [2, 3]
    frame = report.to_frame()
    assert list(frame.columns[:2]) == ["kind", "triangle"]
    assert len(frame) == len(report.violations) and set(frame["kind"]) >= {"outside_domain"}
    assert "outside_domain" in report.summary()


@pytest.mark.parametrize("scale", [2.0**-1070, 1e-200, 1e-100, 1.0, 1e100, 1e300])
def test_the_check_is_the_same_at_every_scale(scale):
    """The geometry of test_outside_triangle_and_frame, and a square of four
    right isosceles triangles, times ``scale`` (from subnormal to 1e300,
    where areas and products of lengths underflow or overflow): the verdicts
    are those at scale 1, the radius ratios 2(sqrt 2 - 1) and the angles 45
    and 90 degrees of right isosceles triangles (closed forms), and a missing
    triangle is still an area violation."""
    pts = scale * np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0, 0.5], [1, 0.5]])
    tri = np.array([[0, 1, 5], [0, 5, 4], [4, 5, 2], [4, 2, 3]])
    report = verify.check(pts, tri, [(0, 1), (1, 5), (5, 4), (4, 0)])
    assert sorted({v.triangle for v in report.of_kind("outside_domain")}) == [2, 3]
    square = scale * np.array([[0, 0], [2, 0], [2, 2], [0, 2], [1, 1]])
    fan = np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]])
    report = verify.check(square, fan, [(0, 1), (1, 2), (2, 3), (3, 0)])
    assert report.ok, report.summary()
    assert report.quality["min_radius_ratio"] == pytest.approx(2 * (2**0.5 - 1), rel=1e-12)
    assert report.quality["mean_radius_ratio"] == pytest.approx(2 * (2**0.5 - 1), rel=1e-12)
    assert report.quality["min_angle"] == pytest.approx(45.0, rel=1e-12)
    assert report.quality["max_angle"] == pytest.approx(90.0, rel=1e-12)
    report = verify.check(square, fan[1:], [(0, 1), (1, 2), (2, 3), (3, 0)])
    assert report.of_kind("area")


def _far_split_square(offset, turn):
    """A square of side 5 turned by ``turn`` radians at ``offset`` from the
    origin (map coordinates), each side split in thirds at the nearest floats
    to the exact points (Fraction arithmetic): its 12 boundary nodes, their
    segments (the 4 input sides), and a fan around its centre."""
    c, s = np.cos(turn), np.sin(turn)
    corners = offset + 5.0 * np.array([[0, 0], [c, s], [c - s, s + c], [-s, c]])
    ring = []
    for k in range(4):
        a, b = _F(corners[k]), _F(corners[(k + 1) % 4])
        ring += [corners[k]] + [[float(a[i] + t * (b[i] - a[i])) for i in (0, 1)]
                                for t in (Fraction(1, 3), Fraction(2, 3))]
    pts = np.vstack([np.array(ring), corners.mean(axis=0)])
    fan = np.array([[k, (k + 1) % 12, 12] for k in range(12)])
    return pts, fan, corners, np.array([[0, 1], [1, 2], [2, 3], [3, 0]])


def test_splits_rounded_to_the_nearest_float_far_from_the_origin_conform():
    """Map coordinates (1e6 from the origin): a point on a turned segment has
    no float position, the nearest is an ulp off (checked exactly here), and
    the check must accept the split and its area as it does Triangle's
    at the origin; a node 5e-6 inside its side is still named."""
    turn = 0.6
    pts, fan, corners, sides = _far_split_square(1e6, turn)
    off = [v for v in range(12) if v % 3 and _orient(corners[v // 3], corners[(v // 3 + 1) % 4],
                                                      pts[v]) != 0]
    assert off, "no split node off its segment: the case tests nothing"
    report = verify.check(pts, fan, sides, corners, delaunay=False)
    assert report.ok, report.summary()
    assert sorted(report.splits) == [0, 1, 2, 3]
    pts[4] -= 5e-6 * np.array([np.cos(turn), np.sin(turn)])  # inward, across side 1
    report = verify.check(pts, fan, sides, corners, delaunay=False)
    assert [v.segment for v in report.of_kind("missing_segment")] == [1]


def test_a_collinear_triangle_is_a_violation_not_an_unreadable_mesh():
    """One triangle on three collinear nodes, checked against its own boundary
    edges (which then run back over each other): a report naming the zero
    area and the overlapping boundary, not an exception."""
    report = verify.check(np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]]), [[0, 1, 2]])
    assert not report.ok
    assert report.of_kind("degenerate") and report.of_kind("non_manifold_vertex")


def test_points_off_the_plane_are_named_with_plain_numbers():
    pts = np.array([[0, 0, 0], [1, 0, 0.5], [0, 1, 0]], float)
    with pytest.raises(ValueError, match=r"node 1 has z = 0\.5 \(2-D needs z = 0\)"):
        verify.check(pts, [[0, 1, 2]])


def test_population_criterion_eq6():
    """Equal radii r: every element bubble has radius r (eq. 3), so sum A_e =
    M pi r^2; the criterion holds iff that reaches the domain area 1."""
    pts = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    tri = np.array([[0, 1, 2], [0, 2, 3]])
    r_ok = np.sqrt(1 / (2 * np.pi)) * 1.001
    assert verify.check(pts, tri, radii=np.full(4, r_ok)).ok
    low = verify.check(pts, tri, radii=np.full(4, r_ok * 0.99))
    assert [v.kind for v in low.violations] == ["population"]


# --------------------------------------------------------------------------- exactness


def _near_degenerate(rng, n):
    """Points on a line / circle perturbed by a few ulps, where floats lie."""
    t = rng.random(n)
    line = np.column_stack([0.1 + 3 * t, 0.7 + 3 * t])
    ang = rng.random(n) * 2 * np.pi
    circle = np.column_stack([0.3 + np.cos(ang), 0.2 + np.sin(ang)])
    pts = np.vstack([line, circle, [[0.1, 0.7], [3.1, 3.7]]])
    steps = rng.integers(-3, 4, pts.shape)
    for _ in range(3):
        pts = np.where(steps > 0, np.nextafter(pts, np.inf), pts)
        pts = np.where(steps < 0, np.nextafter(pts, -np.inf), pts)
        steps = steps - np.sign(steps)
    return pts


def test_filtered_predicates_equal_fraction_arithmetic():
    rng = np.random.default_rng(7)
    pts = _near_degenerate(rng, 60)
    E = ExactPoints(pts)
    idx = rng.integers(0, len(pts), (3000, 4))
    a, b, c, d = idx.T
    o = orient_signs(E, a, b, c)
    ic = incircle_signs(E, a, b, c, d)
    for k in range(len(idx)):
        P = [pts[i] for i in idx[k]]
        assert o[k] == np.sign(_orient(P[0], P[1], P[2]))
        assert ic[k] == np.sign(_incircle(*P))
    assert (o == 0).any() and (ic == 0).any()  # the degenerate cases were hit


def test_circumcircle_query_disk_contains_every_inside_point():
    rng = np.random.default_rng(3)
    pts = _near_degenerate(rng, 40)
    E = ExactPoints(pts)
    idx = rng.integers(0, len(pts), (400, 3))
    s = orient_signs(E, *idx.T)
    tri = np.where((s < 0)[:, None], idx[:, [0, 2, 1]], idx)[s != 0]
    centers, radii = circumcircles(E, tri)
    inside = incircle_signs(E, np.repeat(tri[:, 0], len(pts)), np.repeat(tri[:, 1], len(pts)),
                            np.repeat(tri[:, 2], len(pts)), np.tile(np.arange(len(pts)), len(tri)))
    dist = np.hypot(*(np.repeat(centers, len(pts), axis=0) - np.tile(E.scaled, (len(tri), 1))).T)
    assert np.all(dist[inside > 0] <= np.repeat(radii, len(pts))[inside > 0])
    assert (inside > 0).sum() > 100


# --------------------------------------------------------------------------- CLI and isolation


@pytest.mark.peers
def test_main_check_exit_status(tmp_path, capsys):
    from bubblemesh.io import write_mesh, write_poly

    pts, tri = _triangle_mesh("pYY")
    write_poly(tmp_path / "b.poly", SQUARE, SEGMENTS, HOLE)
    write_mesh(tmp_path / "good.vtu", pts, tri)
    _, _, _, flipped = next(_convex_flips(pts, tri, set()))
    write_mesh(tmp_path / "bad.vtu", pts, flipped)
    assert verify.main_check([str(tmp_path / "good.vtu"), "--boundary",
                              str(tmp_path / "b.poly")]) == 0
    assert "mesh check: OK" in capsys.readouterr().out
    csv = tmp_path / "v.csv"
    assert verify.main_check([str(tmp_path / "bad.vtu"), "--boundary", str(tmp_path / "b.poly"),
                              "--csv", str(csv)]) == 1
    assert "not_delaunay" in capsys.readouterr().out and "not_delaunay" in csv.read_text()
    (tmp_path / "junk.vtu").write_text("not a mesh")
    assert verify.main_check([str(tmp_path / "junk.vtu")]) == 2
    assert verify.main_check([str(tmp_path / "absent.msh")]) == 2
    (tmp_path / "open.poly").write_text("3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n2 0\n1 1 2\n2 2 3\n")
    assert verify.main_check([str(tmp_path / "good.vtu"), "--boundary",
                              str(tmp_path / "open.poly")]) == 2


MESHER = ["generation", "optimization", "triangulation", "_cavity", "_cdt", "_delaunay",
          "_forces", "_insertion", "_inside", "_mesh", "_ordering", "_queue", "_renumber",
          "_rings", "_status", "_verlet", "_workspace", "bubbles", "domain", "memory",
          "predicates", "quality", "simd", "threads", "topology", "cli"]


def test_verify_imports_nothing_of_the_mesher():
    """Statically: every import in bubblemesh/verify is numpy/scipy/pandas/
    meshio/stdlib, bubblemesh.errors, bubblemesh.io or verify itself.  Then
    for real: a child process with the mesher modules and numba blocked
    imports verify and checks a mesh."""
    root = Path(verify.__file__).parent
    allowed_top = {"numpy", "scipy", "pandas", "meshio", "__future__", "argparse", "dataclasses",
                   "fractions", "functools", "itertools", "math", "pathlib", "sys", "time",
                   "typing"}
    for path in root.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                names = [("." * node.level) + (node.module or "")]
            else:
                continue
            for name in names:
                ok = (name.startswith(".") and not name.startswith("..")) or \
                    name.split(".")[0] in allowed_top or name in ("bubblemesh.errors",
                                                                  "bubblemesh.io")
                assert ok, f"{path.name} imports {name}"
    package = Path(verify.__file__).parents[1]
    code = f"""
import sys, types
pkg = types.ModuleType("bubblemesh"); pkg.__path__ = [{str(package)!r}]
sys.modules["bubblemesh"] = pkg
for name in {MESHER!r}:
    sys.modules["bubblemesh." + name] = None
sys.modules["numba"] = None
from bubblemesh import verify
r = verify.check([[0, 0], [1, 0], [0, 1]], [[0, 1, 2]], [[0, 1], [1, 2], [2, 0]])
assert r.ok, r.summary()
print("isolated ok")
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0 and "isolated ok" in out.stdout, out.stderr


@pytest.mark.peers
def test_centroid_location_in_small_batches_equals_exact(monkeypatch):
    """The banded float crossing test, forced into many tiny batches, agrees
    with the all-exact location on Triangle's mesh of the convex hull (holes
    filled, so centroids fall inside, in the hole and outside)."""
    from bubblemesh.verify import conform, domain

    triangle = pytest.importorskip("triangle")
    out = triangle.triangulate(dict(vertices=SQUARE, segments=SEGMENTS), "pcq30a0.01")
    pts, tri = out["vertices"], out["triangles"].astype(np.int64)
    E = ExactPoints(pts)
    B = domain.Boundary(E, SEGMENTS)
    monkeypatch.setattr(domain, "_MAX_PAIRS", 7)
    fast = conform.locate_centroids(E, tri, B)
    exact = conform.locate_centroids(E, tri, B, exact=True)
    assert np.array_equal(fast, exact)
    assert set(fast.tolist()) == {1, -1}  # the hole's triangles are outside


# Loops that touch at nodes, with the Euler number of the region by Alexander
# duality (components less bounded components of the complement): two squares
# sharing the corner (1, 1) (1 - 0); a triangular hole whose corner is the
# outer boundary's node (1.5, 0) (1 - 1); two square holes touching at (2, 2)
# inside a 4 x 4 square (1 - 2).
TOUCHING = {
    "corner": ([(0, 0), (1, 0), (1, 1), (0, 1), (2, 1), (2, 2), (1, 2)],
               [(0, 1), (1, 2), (2, 3), (3, 0), (2, 4), (4, 5), (5, 6), (6, 2)], [], 1),
    "hole on the wall": ([(0, 0), (1.5, 0), (3, 0), (3, 3), (0, 3), (2, 1), (1, 1)],
                         [(0, 1), (1, 2), (2, 3), (3, 4), (4, 0), (1, 5), (5, 6), (6, 1)],
                         [(1.5, 0.6)], 0),
    "holes touching": ([(0, 0), (4, 0), (4, 4), (0, 4), (1, 1), (2, 1), (2, 2), (1, 2),
                        (3, 2), (3, 3), (2, 3)],
                       [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4),
                        (6, 8), (8, 9), (9, 10), (10, 6)], [(1.5, 1.5), (2.5, 2.5)], -1),
}


def _touching_case(name):
    points, segments, holes, euler = TOUCHING[name]
    return (np.array(points, float), np.array(segments), np.array(holes, float).reshape(-1, 2),
            euler)


def _shapely_region(points, segments):
    """The even-odd region of the segments by GEOS: the union of the faces of
    their arrangement that a brute-force ray test puts inside."""
    shapely = pytest.importorskip("shapely")

    lines = [shapely.LineString(points[list(s)]) for s in segments.tolist()]
    faces = shapely.polygonize(lines).geoms  # the arrangement's bounded faces
    return shapely.union_all([f for f in faces
                              if _even_odd(points, segments, f.representative_point())])


def _even_odd(points, segments, q):
    """Brute-force even-odd rule: does a rightward ray from q cross an odd
    number of segments (half-open in y)?"""
    x, y, crossings = q.x, q.y, 0
    for a, b in segments.tolist():
        (x1, y1), (x2, y2) = points[a], points[b]
        if (y1 > y) != (y2 > y) and x < x1 + (y - y1) * (x2 - x1) / (y2 - y1):
            crossings += 1
    return crossings % 2 == 1


@pytest.mark.parametrize("name", sorted(TOUCHING))
def test_loops_touching_at_a_node_check_against_triangle_and_geos(name):
    """Triangle's quality mesh of each touching case passes the check,
    whose domain area is GEOS's area of the even-odd region and whose Euler
    number is the region's by topology (pinching two boundaries together at
    a point lowers it by one); given only the mesh, its own boundary edges
    pass too.  Filling a hole, or dropping the triangles on one side of the
    touching node, fails the area and the Euler count."""
    triangle = pytest.importorskip("triangle")
    points, segments, holes, euler = _touching_case(name)
    data = dict(vertices=points, segments=segments)
    if len(holes):
        data["holes"] = holes
    out = triangle.triangulate(data, "pq30a0.05")
    pts, tri = out["vertices"], out["triangles"].astype(np.int64)
    report = verify.check(pts, tri, segments, points, holes=holes if len(holes) else None)
    assert report.ok, report.summary()
    assert report.facts["domain_area"] == pytest.approx(_shapely_region(points, segments).area,
                                                        rel=1e-12)
    assert report.facts["euler"] == euler
    assert verify.check(pts, tri).ok

    filled = triangle.triangulate(dict(vertices=points, segments=segments), "pq30a0.05")
    if len(holes):
        bad = verify.check(filled["vertices"], filled["triangles"].astype(np.int64), segments,
                           points, holes=holes)
        assert bad.count("outside_domain") and bad.count("area")
    pinch = points[np.bincount(segments.ravel()).argmax()]  # the node loops share
    left = pts[tri].mean(axis=1)[:, 0] < pinch[0]
    bad = verify.check(pts, tri[left], segments, points, holes=holes if len(holes) else None)
    assert bad.count("area") and bad.count("euler") == (name != "corner")


def test_touching_loops_are_traced_without_crossing():
    """chain_loops on the touching cases: simple loops (no node twice), every
    segment once, as many loops as GEOS finds rings in the region's boundary
    pieces; segments given in any order and direction give the same loops."""
    from bubblemesh.verify.domain import chain_loops

    for name in TOUCHING:
        points, segments, _, _ = _touching_case(name)
        P = ExactPoints(points).P
        want = {frozenset(map(frozenset, zip(lp, lp[1:] + lp[:1])))
                for lp in chain_loops(segments, False, points=P)}
        rng = np.random.default_rng(3)
        for _ in range(5):
            shuffled = segments[rng.permutation(len(segments))]
            flip = rng.random(len(shuffled)) < 0.5
            shuffled[flip] = shuffled[flip, ::-1]
            loops = chain_loops(shuffled, False, points=P)
            assert all(len(set(lp)) == len(lp) for lp in loops)
            assert sum(map(len, loops)) == len(segments)
            assert {frozenset(map(frozenset, zip(lp, lp[1:] + lp[:1]))) for lp in loops} == want
        assert len(want) == 3 if name == "holes touching" else len(want) == 2


def test_nodes_on_an_odd_number_of_segments_are_refused_by_name():
    """A dangling segment from a square's corner (node 2 on 3 segments) and an
    oriented loop pair whose node starts two segments and ends none: each is a
    GeometryError naming the node."""
    from bubblemesh.errors import GeometryError

    P = np.array([(0, 0), (1, 0), (1, 1), (0, 1), (2, 2)], float)
    T = np.array([(0, 1, 2), (0, 2, 3)])
    S = np.array([(0, 1), (1, 2), (2, 3), (3, 0), (2, 4)])
    with pytest.raises(GeometryError, match=r"node 2 is on 3 segments.*open chains"):
        verify.check(P[:4], T, S, P)
    S = np.array([(0, 1), (1, 2), (2, 3), (0, 3)])
    with pytest.raises(GeometryError, match=r"node 0 starts 2 segments and ends 0"):
        verify.check(P[:4], T, S, P[:4], oriented=True)


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.heavy)
                                  if n in ("corner", "hole on the wall") else n
                                  for n in sorted(TOUCHING)])
def test_bm_meshes_of_touching_loops_pass_the_check(name):
    """bm.mesh of each touching case (its loops given to Domain.from_pslg in
    the order and direction GEOS's rings of the region's boundary have, not
    the checker's) passes the exact check with the case's Euler number."""
    import warnings

    import bubblemesh as bm

    points, segments, holes, euler = _touching_case(name)
    region = _shapely_region(points, segments)
    polygons = getattr(region, "geoms", [region])
    rings = [np.asarray(r.coords)[:-1] for p in polygons for r in [p.exterior, *p.interiors]]
    domain = bm.Domain.from_pslg(rings, holes=holes)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", bm.QualityWarning)
        m = bm.mesh(domain, max_area=domain.area / 200)
    report = verify.check(m.points, m.triangles, segments, points,
                          holes=holes if len(holes) else None)
    assert report.ok, report.summary()
    assert report.facts["euler"] == euler


def _triangle_examples():
    """(name, .poly contents) of every .poly in the triangle package's data."""
    triangle = pytest.importorskip("triangle")
    from bubblemesh.io import read_poly

    data = Path(triangle.__file__).parent / "data"
    return [(p.name, read_poly(p)) for p in sorted(data.glob("*.poly"))]


def _poly_input(poly):
    data = dict(vertices=poly.vertices, segments=poly.segments)
    if len(poly.holes):
        data["holes"] = poly.holes
    return data


def _sides_in(vertices, triangles, poly):
    """Triangles on each of ``poly``'s segments in a mesh that keeps them as edges."""
    at = {tuple(v): i for i, v in enumerate(np.asarray(vertices).tolist())}
    e = np.sort(np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]],
                                triangles[:, [2, 0]]]), axis=1)
    count: dict = {}
    for edge in map(tuple, e.tolist()):
        count[edge] = count.get(edge, 0) + 1
    return np.array([count.get(tuple(sorted((at[tuple(poly.vertices[a])],
                                             at[tuple(poly.vertices[b])]))), 0)
                     for a, b in np.asarray(poly.segments).tolist()])


def test_pslg_sides_are_those_of_triangles_own_mesh_on_every_example():
    """pslg_sides (faces traced exactly, holes eaten) against Triangle itself:
    its -p mesh of each .poly in its data keeps every segment as an edge, and
    the triangles on a segment are the sides the domain lies on.  Among the
    examples: la.poly (133 interior constraints), face.poly (2), box.poly
    (no closed loop: Triangle eats everything)."""
    from bubblemesh.verify.domain import pslg_sides

    triangle = pytest.importorskip("triangle")
    interior = {}
    for name, poly in _triangle_examples():
        out = triangle.triangulate(_poly_input(poly), "p")
        tri = out.get("triangles", np.zeros((0, 3), np.int64)).astype(np.int64)
        want = _sides_in(out["vertices"], tri, poly)
        got = pslg_sides(poly.vertices, poly.segments, poly.holes)
        np.testing.assert_array_equal(got, want, err_msg=name)
        interior[name] = int((got == 2).sum())
    assert interior["la.poly"] > 100 and interior["face.poly"] > 0 and interior["A.poly"] == 0


def test_quality_meshes_of_every_triangle_example_check_as_triangle_reads_them(tmp_path):
    """Triangle's -pq30 mesh of each example passes check_file with the .poly
    as boundary (interior constraints and all), through a meshio file; the
    same mesh of la.poly made without its interior segments fails on them,
    and one with half of a square cut away by a constraint fails as
    one-sided."""
    meshio = pytest.importorskip("meshio")
    triangle = pytest.importorskip("triangle")
    for name, poly in _triangle_examples():
        out = triangle.triangulate(_poly_input(poly), "pq30")
        if "triangles" not in out:
            continue  # box.poly: nothing is left
        path = tmp_path / f"{name}.vtu"
        meshio.write(path, meshio.Mesh(np.column_stack([out["vertices"],
                                                        np.zeros(len(out["vertices"]))]),
                                       [("triangle", out["triangles"])]))
        data = Path(triangle.__file__).parent / "data" / name
        report = verify.check_file(path, boundary=data)
        assert report.ok, (name, report.summary())

    from bubblemesh.verify.domain import pslg_sides

    poly = dict(_triangle_examples())["la.poly"]
    sides = pslg_sides(poly.vertices, poly.segments, poly.holes)
    outer = dict(vertices=poly.vertices, segments=poly.segments[sides == 1])
    out = triangle.triangulate(outer, "pq30")
    report = verify.check(out["vertices"], out["triangles"].astype(np.int64), poly.segments,
                          poly.vertices, holes=poly.holes, sides="pslg")
    assert report.count("missing_segment") > 50 and not report.count("interior_segment")

    square = np.array([(0, 0), (1, 0), (1, 1), (0, 1)], float)
    cut = np.array([(0, 1), (1, 2), (2, 3), (3, 0), (0, 2)])
    half = np.array([(0, 1, 2)])
    report = verify.check(square[:3], half, cut, square, sides="pslg")
    assert report.count("one_sided_constraint") == 1 and report.count("area")
    assert not verify.check(square, np.array([(0, 1, 2), (0, 2, 3)]), cut, square,
                            sides="pslg").violations


@st.composite
def _random_pslgs(draw):
    """A 32-square, random interior integer points, a random subset of the
    edges of their Delaunay triangulation as segments (trees, cycles,
    interfaces touching each other), and hole points at the centroids of a
    few of its triangles (a face a cycle closes is eaten, an open one eats
    everything around it)."""
    from scipy.spatial import Delaunay

    n = draw(st.integers(4, 16))
    pts = draw(st.lists(st.tuples(st.integers(1, 31), st.integers(1, 31)), min_size=n,
                        max_size=n, unique=True))
    P = np.vstack([[(0, 0), (32, 0), (32, 32), (0, 32)], np.array(pts, float)])
    try:
        tri = Delaunay(P).simplices
    except Exception:  # noqa: BLE001 - collinear draws: the square alone
        tri = np.zeros((0, 3), np.int64)
    edges = sorted({tuple(sorted((int(t[k]), int(t[(k + 1) % 3])))) for t in tri
                    for k in range(3)} - {(0, 1), (1, 2), (2, 3), (0, 3)})
    picks = draw(st.lists(st.sampled_from(edges), max_size=12, unique=True)) if edges else []
    segments = np.array([(0, 1), (1, 2), (2, 3), (3, 0), *picks], np.int64)
    holes = [P[t].mean(axis=0) for t in draw(st.lists(st.sampled_from(list(tri)) if len(tri)
                                                       else st.nothing(), max_size=2))]
    return P, segments, np.array(holes, float).reshape(-1, 2)


@budget(40)
@given(_random_pslgs())
def test_pslg_sides_agree_with_triangle_on_random_graphs(pslg):
    """On random planar straight-line graphs, pslg_sides equals the number of
    triangles on each segment in Triangle's -p mesh, and Triangle's -pq30
    mesh passes the check with sides='pslg' (when anything is meshed)."""
    from bubblemesh.verify.domain import pslg_sides

    triangle = pytest.importorskip("triangle")
    points, segments, holes = pslg
    data = dict(vertices=points, segments=segments)
    if len(holes):
        data["holes"] = holes
    plain = triangle.triangulate(data, "p")
    tri = plain.get("triangles", np.zeros((0, 3), np.int64)).astype(np.int64)
    poly = type("Poly", (), dict(vertices=points, segments=segments))
    want = _sides_in(plain["vertices"], tri, poly)
    np.testing.assert_array_equal(pslg_sides(points, segments, holes), want)
    fine = triangle.triangulate(data, "pq30a40j")  # j: the eaten vertices dropped
    if "triangles" in fine and len(fine["triangles"]):
        report = verify.check(fine["vertices"], fine["triangles"].astype(np.int64), segments,
                              points, holes=holes if len(holes) else None, sides="pslg")
        assert report.ok, report.summary()


def test_crossing_or_touching_segments_are_refused_by_pslg_sides():
    """Faces are traced only on a planar graph: two crossing diagonals, a node
    strictly inside a wall (a T-junction), a collinear overlap and a wall
    given twice are each a GeometryError naming the segments; segments
    meeting at their ends are not."""
    from bubblemesh.errors import GeometryError
    from bubblemesh.verify.domain import pslg_sides

    sq = np.array([(0, 0), (4, 0), (4, 4), (0, 4), (1, 1), (3, 3), (1, 3), (3, 1), (2, 0)],
                  float)
    walls = [(0, 1), (1, 2), (2, 3), (3, 0)]
    with pytest.raises(GeometryError, match="segments 4 and 5 cross"):
        pslg_sides(sq, np.array(walls + [(4, 5), (6, 7)]))
    with pytest.raises(GeometryError, match="segments 0 and 4 overlap or meet inside"):
        pslg_sides(sq, np.array(walls + [(8, 2)]))
    with pytest.raises(GeometryError, match="segments 0 and 4 overlap"):
        pslg_sides(sq, np.array(walls + [(0, 8)]))
    with pytest.raises(GeometryError, match=r"segment 1 \[1, 2\] is given more than once"):
        pslg_sides(sq, np.array(walls + [(2, 1)]))
    assert pslg_sides(sq, np.array([(0, 8), (8, 1)] + walls[1:] + [(4, 5)])).tolist() == [
        1, 1, 1, 1, 1, 2]
