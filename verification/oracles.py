"""Independent oracles for checking bubblemesh output, for the test suite.

The exact checkers themselves live in :mod:`bubblemesh.verify`, which
imports nothing of the mesher: every geometric decision is taken with exact
integer arithmetic on the floats' binary values, so a bug in the library's
predicates cannot hide behind the same bug in its checker.  This module keeps
the names the tests use: each ``check_*`` runs the matching verify checks and
raises ``AssertionError`` naming the first few violations (so a failing
hypothesis example prints a readable reason), returning a small dict of facts
on success.  A few test-only tools (exact hull, canonical triangle sets, the
trimesh cross-check, outer/holes location) stay here.

Conventions checked (those of docs/design.md): triangles (M,3) counter-clockwise;
``neighbors[t, i]`` is the triangle across the edge opposite vertex ``i``, that
is edge ``(tri[t,(i+1)%3], tri[t,(i+2)%3])``, or -1 on the boundary; segments
are oriented with the domain on their left (outer loop CCW, holes CW).
"""

from __future__ import annotations

import math

import numpy as np

from bubblemesh.errors import GeometryError
from bubblemesh.verify import conform as _conform
from bubblemesh.verify import delaunay as _delaunay
from bubblemesh.verify.domain import Boundary, chain_loops
from bubblemesh.verify.exact import (  # noqa: F401  (re-exported for the tests)
    ExactPoints,
    circumcircle_exact,
    exact_integers,
    incircle_int,
    incircle_sign,
    orient2d_sign,
    orient_int,
    orient_signs,
    point_in_polygon,
    signed_area_exact,
)
from bubblemesh.verify.measures import (  # noqa: F401  (re-exported for the tests)
    angles_reference,
    boundary_radii_reference,
    element_bubble_radii,
    population_bubble_area,
    radius_ratio_reference,
    triangle_areas,
)
from bubblemesh.verify.report import Report
from bubblemesh.verify.topology import HalfEdges, check_validity
from bubblemesh.verify.topology import euler_characteristic as _euler

visible_from_triangle = _delaunay.visible_from_triangle

_VALIDITY = ("bad_index", "empty", "repeated_vertex", "degenerate", "orientation",
             "duplicate_triangle", "non_manifold_edge", "neighbors")

# ---------------------------------------------------------------------------
# small helpers on index arrays
# ---------------------------------------------------------------------------


def _as_triangles(triangles) -> np.ndarray:
    tri = np.asarray(triangles)
    if (
        tri.ndim != 2
        or tri.shape[1] != 3
        or (tri.size and not np.issubdtype(tri.dtype, np.integer))
    ):
        raise AssertionError(
            f"triangles must be an (M, 3) integer array, got {tri.dtype} {tri.shape}"
        )
    return tri.astype(np.int64, copy=False)


def _fail(title: str, problems: list[str]) -> None:
    if problems:
        more = f"\n  ... and {len(problems) - 5} more" if len(problems) > 5 else ""
        raise AssertionError(title + ":\n  " + "\n  ".join(problems[:5]) + more)


def _as_segments(segments) -> np.ndarray:
    return np.asarray(segments, dtype=np.int64).reshape(-1, 2)


def _edges(triangles) -> HalfEdges:
    tri = _as_triangles(triangles)
    return HalfEdges(tri, int(tri.max()) + 1 if tri.size else 1)


def directed_edges(triangles) -> list[tuple[int, int]]:
    """Edges (tri[t,i], tri[t,i+1]) of every triangle, in CCW direction."""
    tri = _as_triangles(triangles)
    return [(int(t[i]), int(t[(i + 1) % 3])) for t in tri for i in range(3)]


def edge_counts(triangles) -> dict[tuple[int, int], int]:
    """Undirected edge -> number of triangles using it."""
    H = _edges(triangles)
    lo, hi = np.divmod(H.keys, H.n)
    return dict(zip(zip(lo.tolist(), hi.tolist()), H.count.tolist()))


def boundary_edges(triangles) -> set[tuple[int, int]]:
    """Directed edges (in their triangle's CCW direction) whose reverse no triangle has."""
    H = _edges(triangles)
    h = np.nonzero(H.reverse < 0)[0]
    return set(zip(H.u[h].tolist(), H.v[h].tolist()))


def canonical_triangles(triangles) -> set[tuple[int, int, int]]:
    """Each triangle as a rotation-normalised tuple (smallest index first,
    orientation kept), so two arrays listing the same CCW triangles in any
    order and any cyclic rotation compare equal as sets."""
    out = set()
    for t in _as_triangles(triangles):
        a, b, c = (int(x) for x in t)
        k = min(range(3), key=lambda i: (a, b, c)[i])
        out.add(((a, b, c) * 2)[k : k + 3])
    return out


def ccw_triangles(points, triangles) -> np.ndarray:
    """Re-orient triangles counter-clockwise (exactly); used to normalise peer
    output (scipy/qhull does not promise an orientation)."""
    tri = _as_triangles(triangles).copy()
    s = orient_signs(ExactPoints(points), tri[:, 0], tri[:, 1], tri[:, 2])
    tri[s < 0] = tri[s < 0][:, [0, 2, 1]]
    return tri


# ---------------------------------------------------------------------------
# validity and Euler
# ---------------------------------------------------------------------------


def check_valid(points, triangles, neighbors=None) -> dict:
    """Validity of a triangulation as a combinatorial + geometric object
    (bubblemesh.verify.topology): indices in range, three distinct vertices,
    strictly CCW (exact), no duplicate triangles, every edge on at most two
    triangles in opposite directions, ``neighbors`` (if given) matching the
    contract convention.

    Together with :func:`check_conforming` this proves the triangles tile the
    domain exactly once: for positively oriented triangles the sum of their
    indicator functions equals the winding number of the chain boundary,
    which is 1 inside the domain and 0 outside.
    """
    tri = _as_triangles(triangles)
    report = Report()
    H, _ = check_validity(ExactPoints(points), tri, report, neighbors)
    report.raise_if_failed("invalid triangulation", kinds=_VALIDITY)
    return {
        "vertices": len(np.unique(tri)),
        "edges": len(H.keys),
        "faces": len(tri),
        "boundary_edges": int((H.count == 1).sum()),
    }


def euler_characteristic(triangles) -> int:
    """V - E + F counting only the vertices the triangles use."""
    return _euler(_as_triangles(triangles))


def euler_ok(triangles, holes: int = 0) -> bool:
    """Euler's formula for a triangulated polygon with ``holes`` holes:
    V - E + F = 1 - holes (F not counting the outer face)."""
    return euler_characteristic(triangles) == 1 - holes


# ---------------------------------------------------------------------------
# Delaunay emptiness (unconstrained and constrained)
# ---------------------------------------------------------------------------


def _positive(E, tri) -> np.ndarray:
    s = orient_signs(E, tri[:, 0], tri[:, 1], tri[:, 2])
    if (s <= 0).any():
        t = int(np.argmax(s <= 0))
        raise AssertionError(f"triangle {t} {tri[t].tolist()} is not counter-clockwise "
                             "(degenerate or clockwise): no circumcircle test")
    return s > 0


def check_delaunay_empty(points, triangles, vertices=None) -> dict:
    """No point lies strictly inside the circumcircle of any triangle.

    ``vertices`` (default: all points of triangles) are the points tested.
    Points on a circumcircle are allowed."""
    return _delaunay_check(points, triangles, (), vertices, "Delaunay emptiness violated")


def check_constrained_delaunay(points, triangles, segments, vertices=None) -> dict:
    """Constrained Delaunay property, checked against its definition.

    Every segment must be an edge of the triangulation (else the constrained
    Delaunay triangulation is not defined for these triangles).  Then for
    every triangle t, no vertex strictly inside t's circumcircle may be
    visible from the interior of t.  Precondition: :func:`check_valid` passes.
    """
    seg = _as_segments(segments)
    H = _edges(triangles)
    if len(seg):
        missing = np.nonzero(H.edge_count(seg[:, 0], seg[:, 1]) == 0)[0]
        if len(missing):
            shown = "\n  ".join(f"segment {k} {seg[k].tolist()} is not an edge of the "
                                "triangulation" for k in missing[:5].tolist())
            raise AssertionError(f"constrained Delaunay undefined:\n  {shown}")
    return _delaunay_check(points, triangles, seg, vertices,
                           "constrained Delaunay emptiness violated")


def _delaunay_check(points, triangles, segments, vertices, title) -> dict:
    tri = _as_triangles(triangles)
    E = ExactPoints(points)
    H = HalfEdges(tri, len(E.points))
    report = Report()
    facts = _delaunay.check_delaunay(E, H, _positive(E, tri), _as_segments(segments), report,
                                     vertices)
    report.raise_if_failed(title)
    return {"candidates_tested": facts["candidates"], "hidden_inside": facts["hidden_inside"]}


def check_locally_delaunay(points, triangles, segments=()) -> dict:
    """Every edge that is not a segment is locally Delaunay (exact): the vertex
    across it is not strictly inside the triangle's circumcircle.  By the
    constrained Delaunay lemma this is equivalent to the global definition for
    a valid triangulation that contains the segments; kept as a second,
    differently built oracle to cross-check :func:`check_constrained_delaunay`.
    """
    tri = _as_triangles(triangles)
    E = ExactPoints(points)
    H = HalfEdges(tri, len(E.points))
    bad = _delaunay.local_violations(E, H, np.ones(len(tri), bool), _as_segments(segments))
    problems = []
    for h in bad[:5].tolist():
        r = int(H.reverse[h])
        problems.append(f"edge {(int(H.u[h]), int(H.v[h]))} of triangle {h // 3} "
                        f"{tri[h // 3].tolist()} is not locally Delaunay "
                        f"(vertex {int(tri[r // 3, r % 3])} inside)")
    if problems:
        raise AssertionError("edges not locally Delaunay:\n  " + "\n  ".join(problems))
    return {}


def delaunay_is_unique(points, triangles, segments=()) -> bool:
    """True iff no unconstrained interior edge has its four points exactly
    cocircular.  For a (constrained) Delaunay triangulation this is exactly
    when it is the only one, so two correct implementations must agree."""
    tri = _as_triangles(triangles)
    E = ExactPoints(points)
    H = HalfEdges(tri, len(E.points))
    ones = np.ones(len(tri), bool)
    return not len(_delaunay.cocircular_edges(E, H, ones, _as_segments(segments)))


# ---------------------------------------------------------------------------
# hull, loops, point in polygon
# ---------------------------------------------------------------------------


def convex_hull_exact(points) -> list[int]:
    """Indices of the convex hull boundary in CCW order, *including* points in
    the relative interior of hull edges (they are vertices of any Delaunay
    triangulation).  Exact monotone chain; one index per distinct position
    (the lowest).  Empty list if all points are collinear."""
    pts = np.asarray(points, dtype=np.float64)
    P, _ = exact_integers(pts)
    first: dict[tuple[int, int], int] = {}
    for i, p in enumerate(P):
        first.setdefault(p, i)
    order = sorted(first, key=lambda p: p)
    if len(order) < 3:
        return []

    def chain(seq):
        out: list = []
        for p in seq:
            while len(out) >= 2 and orient_int(out[-2], out[-1], p) < 0:
                out.pop()
            out.append(p)
        return out

    lower = chain(order)
    upper = chain(order[::-1])
    if all(orient_int(order[0], order[-1], p) == 0 for p in order):
        return []
    hull = lower[:-1] + upper[:-1]
    return [first[p] for p in hull]


def loops_from_segments(segments) -> list[list[int]]:
    """Chain oriented segments into closed loops (each node: one in, one out)."""
    try:
        return chain_loops(_as_segments(segments), oriented=True)
    except GeometryError as error:
        raise AssertionError(str(error)) from None


def domain_location(P, loops, q) -> int:
    """+1 strictly inside the domain (inside loops[0], outside the others),
    0 on any loop, -1 outside."""
    where = point_in_polygon(q, [P[i] for i in loops[0]])
    if where <= 0:
        return where
    for hole in loops[1:]:
        w = point_in_polygon(q, [P[i] for i in hole])
        if w == 0:
            return 0
        if w > 0:
            return -1
    return 1


def _boundary(points, loops) -> Boundary:
    seg = [(lp[i], lp[(i + 1) % len(lp)]) for lp in loops for i in range(len(lp))]
    try:
        return Boundary(ExactPoints(points), np.array(seg, dtype=np.int64))
    except GeometryError as error:
        raise AssertionError(str(error)) from None


def locate_centroids(points, triangles, loops, P=None, exact=False) -> np.ndarray:
    """Location of every triangle's centroid: +1 inside the domain, 0 on a
    loop, -1 outside (exact; float filter with exact fallback, or all exact
    with ``exact=True``, used to test the fast path).  ``P`` is ignored (kept
    for the callers)."""
    B = _boundary(points, [list(map(int, lp)) for lp in loops])
    return _conform.locate_centroids(B.E, _as_triangles(triangles), B, exact=exact)


def split_outer(P, loops) -> list[list[int]]:
    """Order loops as [outer, holes...]: the outer loop is the one with the
    largest absolute area (it encloses the others in a valid domain)."""
    areas = [abs(signed_area_exact(P, lp)) for lp in loops]
    k = max(range(len(loops)), key=lambda i: areas[i])
    return [loops[k]] + [lp for i, lp in enumerate(loops) if i != k]


def domain_area(points, loops) -> float:
    """Exact area |outer| - sum |holes| rounded once to float."""
    return _boundary(points, [list(map(int, lp)) for lp in loops]).area()


# ---------------------------------------------------------------------------
# boundary conformity
# ---------------------------------------------------------------------------


def check_conforming(points, triangles, segments, area=None, rel=1e-12) -> dict:
    """Boundary conformity of a triangulated domain (bubblemesh.verify.conform).

    - every segment is an edge of the mesh (no splits: the contract keeps them);
    - the mesh's boundary edges (used by one triangle) are exactly the
      segments, and each is traversed by its triangle in the segment's
      direction (domain on the left);
    - no triangle centroid lies outside the outer loop, inside a hole or on a
      loop (exact);
    - math.fsum of the triangle areas equals the domain area (exact shoelace
      over the loops chained from ``segments``, or ``area`` if given) within
      relative error ``rel``.
    """
    tri = _as_triangles(triangles)
    seg = _as_segments(segments)
    E = ExactPoints(points)
    H = HalfEdges(tri, len(E.points))
    report = Report()
    sub, owner = _conform.segment_chains(E, H, seg, report, 0.0, allow_splits=False)
    report.raise_if_failed("boundary segments missing from the mesh")
    _conform.check_boundary_edges(E, H, sub, owner, report, oriented=True)
    report.raise_if_failed("mesh boundary differs from the segments")
    B = Boundary(E, seg, oriented=True)
    _conform.check_inside(E, tri, B, report)
    report.raise_if_failed("triangles outside the domain")
    total = math.fsum(triangle_areas(E.points, tri).tolist())
    expected = B.area() if area is None else float(area)
    err = abs(total - expected) / abs(expected)
    if not err <= rel:
        raise AssertionError(
            f"triangle areas sum to {total!r}, domain area is {expected!r} "
            f"(rel err {err:.3e} > {rel})"
        )
    return {"loops": len(B.loops), "area": total, "rel_area_error": err}


def check_trimesh(points, triangles, segments=None, area=None) -> dict:
    """Cross-check with trimesh (an independent mesh library).

    Builds ``trimesh.Trimesh`` with z = 0 and compares: every face normal is
    +z (CCW), trimesh's unique-edge count equals ours, its boundary edges
    (edges of one face) equal the segments, its outline has one closed curve
    per loop, and its area equals the domain area (or our fsum)."""
    import trimesh
    from trimesh import grouping

    pts = np.asarray(points, dtype=np.float64)
    tri = _as_triangles(triangles)
    v3 = np.column_stack([pts, np.zeros(len(pts))])
    tm = trimesh.Trimesh(vertices=v3, faces=tri, process=False, validate=False)
    problems = []
    normals = tm.face_normals
    bad = np.nonzero(~(normals[:, 2] > 0.5))[0]
    for t in bad:
        problems.append(
            f"trimesh face normal of triangle {t} is {normals[t].tolist()} (expected +z)"
        )
    ours = len(edge_counts(tri))
    if len(tm.edges_unique) != ours:
        problems.append(f"trimesh counts {len(tm.edges_unique)} unique edges, we count {ours}")
    rows = grouping.group_rows(tm.edges_sorted, require_count=1)
    tm_boundary = {tuple(sorted(map(int, e))) for e in tm.edges_sorted[rows]}
    if segments is not None:
        seg = _as_segments(segments)
        want = {(min(a, b), max(a, b)) for a, b in seg.tolist()}
        if tm_boundary != want:
            problems.append(
                "trimesh boundary edges differ from segments: "
                f"extra {sorted(tm_boundary - want)[:5]}, "
                f"missing {sorted(want - tm_boundary)[:5]}"
            )
        n_loops = len(loops_from_segments(seg))
        outline = tm.outline()
        if len(outline.entities) != n_loops:
            problems.append(
                f"trimesh outline has {len(outline.entities)} curves, the domain {n_loops} loops"
            )
        for ent in outline.entities:
            if not ent.closed:
                problems.append("trimesh outline curve is not closed")
    expected = math.fsum(triangle_areas(pts, tri)) if area is None else float(area)
    if not abs(tm.area - expected) <= 1e-9 * abs(expected):
        problems.append(f"trimesh area {tm.area!r} != expected {expected!r}")
    _fail("trimesh cross-check failed", problems)
    return {"edges": ours, "boundary_edges": len(tm_boundary), "area": float(tm.area)}


