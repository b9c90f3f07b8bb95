"""Independent oracles for checking bubblemesh output.

Nothing here imports bubblemesh: every geometric decision is taken with exact
integer arithmetic on the floats' exact binary values, so a bug in the
library's predicates cannot hide behind the same bug in its checker.

Exactness.  Every float64 is ``m * 2**e`` exactly (``float.as_integer_ratio``).
:func:`exact_integers` multiplies all coordinates of one point set by the same
power of two so that they become Python integers; orientation, in-circle,
circumcentres, point-in-polygon and ray/segment intersections are then plain
(arbitrary precision) integer or ``Fraction`` arithmetic with no rounding.
Floats are used only for *conservative* prefilters (a KD-tree query with an
inflated radius) whose only effect is to skip candidates that are certainly
far away.

Checks raise ``AssertionError`` naming the first few violations (so a failing
hypothesis example prints a readable reason) and return a small dict of facts
on success.

Conventions checked (those of docs/design.md): triangles (M,3) counter-clockwise;
``neighbors[t, i]`` is the triangle across the edge opposite vertex ``i``, that
is edge ``(tri[t,(i+1)%3], tri[t,(i+2)%3])``, or -1 on the boundary; segments
are oriented with the domain on their left (outer loop CCW, holes CW).
"""

from __future__ import annotations

import itertools
import math
from fractions import Fraction
from functools import cmp_to_key

import numpy as np

try:  # scipy is only a speed-up for candidate search; a numpy fallback exists
    from scipy.spatial import cKDTree as _KDTree
except ImportError:  # pragma: no cover - exercised in the "core" tox env
    _KDTree = None

_MAX_REPORT = 5  # violations listed in one assertion message

# ---------------------------------------------------------------------------
# exact arithmetic
# ---------------------------------------------------------------------------


def exact_integers(points) -> tuple[list[tuple[int, int]], int]:
    """Return ``(P, shift)`` with ``points[i] == P[i] / 2**shift`` exactly.

    All coordinates share one scale, so any polynomial predicate evaluated on
    ``P`` has exactly the sign it has on the real numbers the floats denote.
    """
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise ValueError(f"points must have shape (N, 2), got {pts.shape}")
    if not np.all(np.isfinite(pts)):
        raise ValueError("points contain NaN or infinity")
    ratios = [float(x).as_integer_ratio() for x in pts.ravel()]
    shift = max((d.bit_length() - 1 for _, d in ratios), default=0)
    ints = [n << (shift - (d.bit_length() - 1)) for n, d in ratios]
    return list(zip(ints[0::2], ints[1::2], strict=False)), shift


def orient_int(a, b, c) -> int:
    """Twice the signed area of (a, b, c) on integer points: >0 iff CCW."""
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])


def incircle_int(a, b, c, d) -> int:
    """In-circle determinant on integer points: >0 iff d strictly inside the
    circle through CCW a, b, c; 0 iff cocircular (sign flips if abc is CW)."""
    adx, ady = a[0] - d[0], a[1] - d[1]
    bdx, bdy = b[0] - d[0], b[1] - d[1]
    cdx, cdy = c[0] - d[0], c[1] - d[1]
    alift = adx * adx + ady * ady
    blift = bdx * bdx + bdy * bdy
    clift = cdx * cdx + cdy * cdy
    return (
        alift * (bdx * cdy - cdx * bdy)
        + blift * (cdx * ady - adx * cdy)
        + clift * (adx * bdy - bdx * ady)
    )


def _sign(x) -> int:
    return (x > 0) - (x < 0)


def orient2d_sign(ax, ay, bx, by, cx, cy) -> int:
    """Exact sign of orient2d on float inputs (via Fraction): +1 CCW, 0, -1."""
    a, b, c = (
        (Fraction(ax), Fraction(ay)),
        (Fraction(bx), Fraction(by)),
        (Fraction(cx), Fraction(cy)),
    )
    return _sign(orient_int(a, b, c))


def incircle_sign(ax, ay, bx, by, cx, cy, dx, dy) -> int:
    """Exact sign of the in-circle determinant on float inputs (via Fraction)."""
    f = Fraction
    return _sign(incircle_int((f(ax), f(ay)), (f(bx), f(by)), (f(cx), f(cy)), (f(dx), f(dy))))


def circumcircle_exact(a, b, c) -> tuple[Fraction, Fraction, Fraction]:
    """Exact circumcentre (x, y) and squared radius of integer points a, b, c."""
    bx, by = b[0] - a[0], b[1] - a[1]
    cx, cy = c[0] - a[0], c[1] - a[1]
    d = 2 * (bx * cy - by * cx)
    if d == 0:
        raise ZeroDivisionError("collinear triangle has no circumcircle")
    b2, c2 = bx * bx + by * by, cx * cx + cy * cy
    ux = Fraction(cy * b2 - by * c2, d)
    uy = Fraction(bx * c2 - cx * b2, d)
    return a[0] + ux, a[1] + uy, ux * ux + uy * uy


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


def _as_segments(segments) -> np.ndarray:
    seg = np.asarray(segments, dtype=np.int64)
    return seg.reshape(-1, 2)


def _fail(title: str, problems: list[str]) -> None:
    if problems:
        more = (
            f"\n  ... and {len(problems) - _MAX_REPORT} more" if len(problems) > _MAX_REPORT else ""
        )
        raise AssertionError(title + ":\n  " + "\n  ".join(problems[:_MAX_REPORT]) + more)


def directed_edges(triangles) -> list[tuple[int, int]]:
    """Edges (tri[t,i], tri[t,i+1]) of every triangle, in CCW direction."""
    tri = _as_triangles(triangles)
    return [(int(t[i]), int(t[(i + 1) % 3])) for t in tri for i in range(3)]


def edge_counts(triangles) -> dict[tuple[int, int], int]:
    """Undirected edge -> number of triangles using it."""
    counts: dict[tuple[int, int], int] = {}
    for a, b in directed_edges(triangles):
        key = (a, b) if a < b else (b, a)
        counts[key] = counts.get(key, 0) + 1
    return counts


def boundary_edges(triangles) -> set[tuple[int, int]]:
    """Directed edges (in their triangle's CCW direction) used by one triangle."""
    directed = directed_edges(triangles)
    present = set(directed)
    return {(a, b) for a, b in directed if (b, a) not in present}


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
    P, _ = exact_integers(points)
    tri = _as_triangles(triangles).copy()
    for t in tri:
        if orient_int(P[t[0]], P[t[1]], P[t[2]]) < 0:
            t[1], t[2] = t[2], t[1]
    return tri


# ---------------------------------------------------------------------------
# 4. validity and Euler
# ---------------------------------------------------------------------------


def check_valid(points, triangles, neighbors=None) -> dict:
    """Validity of a triangulation as a combinatorial + geometric object.

    - indices in range, three distinct vertices per triangle;
    - every triangle strictly counter-clockwise (exact orientation > 0);
    - no duplicate triangles (same vertex set);
    - every edge used by at most two triangles, and when by two, in opposite
      directions (so triangles on both sides; same direction = overlap/fold);
    - ``neighbors`` (if given) matches the contract convention exactly.

    Together with :func:`check_conforming` (boundary = the domain boundary)
    this proves the triangles tile the domain exactly once: for positively
    oriented triangles the sum of their indicator functions equals the winding
    number of the chain boundary, which is 1 inside the domain and 0 outside.
    """
    pts = np.asarray(points, dtype=np.float64)
    tri = _as_triangles(triangles)
    n, m = len(pts), len(tri)
    problems: list[str] = []
    if m == 0:
        raise AssertionError("no triangles")
    if tri.min() < 0 or tri.max() >= n:
        bad = np.nonzero((tri < 0).any(1) | (tri >= n).any(1))[0]
        _fail(
            f"triangle indices out of range [0, {n})",
            [f"triangle {t}: {tri[t].tolist()}" for t in bad],
        )
    P, _ = exact_integers(pts)

    seen: dict[frozenset, int] = {}
    for t, (a, b, c) in enumerate(tri.tolist()):
        if a == b or b == c or a == c:
            problems.append(f"triangle {t} {[a, b, c]} repeats a vertex")
            continue
        o = orient_int(P[a], P[b], P[c])
        if o <= 0:
            kind = "is clockwise" if o < 0 else "has zero area (collinear vertices)"
            problems.append(f"triangle {t} {[a, b, c]} {kind}: points {pts[[a, b, c]].tolist()}")
        key = frozenset((a, b, c))
        if key in seen:
            problems.append(f"triangle {t} {[a, b, c]} duplicates triangle {seen[key]}")
        seen[key] = t
    _fail("invalid triangles", problems)

    owner: dict[tuple[int, int], tuple[int, int]] = {}  # directed edge -> (triangle, local i)
    for t, row in enumerate(tri.tolist()):
        for i in range(3):
            e = (row[(i + 1) % 3], row[(i + 2) % 3])
            if e in owner:
                problems.append(
                    f"directed edge {e} used by triangles {owner[e][0]} and {t} "
                    "(same direction: the triangles overlap)"
                )
            owner[e] = (t, i)
    _fail("edges used inconsistently", problems)

    if neighbors is not None:
        nb = np.asarray(neighbors)
        if nb.shape != tri.shape:
            raise AssertionError(f"neighbors shape {nb.shape} != triangles shape {tri.shape}")
        for t, row in enumerate(tri.tolist()):
            for i in range(3):
                a, b = row[(i + 1) % 3], row[(i + 2) % 3]
                expect = owner.get((b, a))
                got = int(nb[t, i])
                if expect is None:
                    if got != -1:
                        problems.append(
                            f"neighbors[{t},{i}] = {got} but edge {(a, b)} is a boundary edge "
                            "(expected -1)"
                        )
                else:
                    u, j = expect
                    if got != u:
                        problems.append(
                            f"neighbors[{t},{i}] = {got}, expected {u} (across edge {(a, b)})"
                        )
                    elif int(nb[u, j]) != t:
                        problems.append(
                            f"neighbors not symmetric: neighbors[{t},{i}]={u} but "
                            f"neighbors[{u},{j}]={int(nb[u, j])}"
                        )
        _fail("neighbour array inconsistent with the contract convention", problems)

    counts = edge_counts(tri)
    return {
        "vertices": len(np.unique(tri)),
        "edges": len(counts),
        "faces": m,
        "boundary_edges": sum(1 for c in counts.values() if c == 1),
    }


def euler_characteristic(triangles) -> int:
    """V - E + F counting only the vertices the triangles use."""
    tri = _as_triangles(triangles)
    return len(np.unique(tri)) - len(edge_counts(tri)) + len(tri)


def euler_ok(triangles, holes: int = 0) -> bool:
    """Euler's formula for a triangulated polygon with ``holes`` holes:
    V - E + F = 1 - holes (F not counting the outer face)."""
    return euler_characteristic(triangles) == 1 - holes


# ---------------------------------------------------------------------------
# 1. Delaunay emptiness (unconstrained and constrained)
# ---------------------------------------------------------------------------


def _circumcircles(P, shift, tri):
    """Exact circumcircles, plus float centres and conservative query radii."""
    exact = []
    centers = np.empty((len(tri), 2))
    radii = np.empty(len(tri))
    for k, (a, b, c) in enumerate(tri.tolist()):
        try:
            cx, cy, r2 = circumcircle_exact(P[a], P[b], P[c])
        except ZeroDivisionError:
            raise AssertionError(
                f"triangle {k} {[a, b, c]} is degenerate (collinear): no circumcircle"
            ) from None
        exact.append((cx, cy, r2))
        # Fraction -> float is correctly rounded (scaling first avoids overflow)
        try:
            centers[k] = (float(cx / (1 << shift)), float(cy / (1 << shift)))
            radii[k] = math.sqrt(float(r2 / (1 << (2 * shift))))
        except OverflowError:  # a sliver whose circle exceeds the float range
            centers[k] = (0.0, 0.0)
            radii[k] = math.inf
    return exact, centers, radii


def _candidates(pts, centers, radii):
    """Indices of points possibly inside each circle (superset, float prefilter).

    The float centre is within a few ulps of the exact one and the float
    distance computation errs by a few ulps of the coordinates involved, so
    inflating the radius by 1e-9 relative plus 64 ulps of the largest
    coordinate magnitude keeps every point that is inside exactly."""
    mag = float(np.max(np.abs(pts))) if len(pts) else 0.0
    big = np.maximum(np.abs(centers).max(axis=1), mag)
    rq = radii * (1 + 1e-9) + 64 * np.spacing(big) + 1e-300
    huge = ~np.isfinite(rq)  # circle beyond the float range: every point is a candidate
    everyone = list(range(len(pts)))
    if _KDTree is not None:
        tree = _KDTree(pts)
        found = tree.query_ball_point(centers, np.where(huge, 0.0, rq))
        return [everyone if h else f for h, f in zip(huge, found, strict=False)]
    out = []
    for c, r in zip(centers, rq, strict=False):
        if not np.isfinite(r):
            out.append(everyone)
            continue
        d = np.hypot(pts[:, 0] - c[0], pts[:, 1] - c[1])
        out.append(np.nonzero(d <= r)[0].tolist())
    return out


def _strictly_inside(P, tri_row, cand):
    a, b, c = tri_row
    return [v for v in cand if v not in tri_row and incircle_int(P[a], P[b], P[c], P[v]) > 0]


def check_delaunay_empty(points, triangles, vertices=None) -> dict:
    """No point lies strictly inside the circumcircle of any triangle.

    ``vertices`` (default: all points) are the points tested.  Points on a
    circumcircle are allowed (degenerate inputs have several Delaunay
    triangulations).  Exact in-circle on the integer images of the floats;
    candidates come from a conservative KD-tree query."""
    pts = np.asarray(points, dtype=np.float64)
    tri = _as_triangles(triangles)
    P, shift = exact_integers(pts)
    _, centers, radii = _circumcircles(P, shift, tri)
    allowed = None if vertices is None else {int(v) for v in np.asarray(vertices).ravel()}
    problems = []
    tested = 0
    for k, cand in enumerate(_candidates(pts, centers, radii)):
        if allowed is not None:
            cand = [v for v in cand if v in allowed]
        tested += len(cand)
        for v in _strictly_inside(P, tri[k].tolist(), cand):
            problems.append(
                f"point {v} {pts[v].tolist()} is strictly inside the circumcircle of triangle "
                f"{k} {tri[k].tolist()} = {pts[tri[k]].tolist()}"
            )
    _fail("Delaunay emptiness violated", problems)
    return {"candidates_tested": tested}


def _segment_hits_before(V, D, A, B, lam_in) -> bool:
    """Does the ray V + lam*D (lam > 0) meet the closed segment AB at some
    lam <= lam_in?  D is generic: the ray passes through neither A nor B."""
    ex, ey = B[0] - A[0], B[1] - A[1]
    denom = D[0] * ey - D[1] * ex
    if denom == 0:  # parallel; a collinear AB would contain V or lie off the ray
        return False
    wx, wy = A[0] - V[0], A[1] - V[1]
    lam = Fraction(wx * ey - wy * ex, denom)
    mu = Fraction(wx * D[1] - wy * D[0], denom)
    return 0 < lam <= lam_in and 0 <= mu <= 1


def visible_from_triangle(P, tri_row, v, obstacles) -> bool:
    """Exact visibility of vertex ``v`` from the interior of triangle ``tri_row``.

    Definition (Chew; Shewchuk's "constrained Delaunay"): v is visible from t
    if some point p in the open triangle sees v, i.e. the segment pv meets no
    obstacle segment except possibly at v itself.  Obstacles incident to v
    block a single direction only (measure zero) and are ignored.

    Method: v lies strictly outside t, so t is seen from v inside a wedge of
    angle < pi.  The directions from v to the triangle's vertices and to the
    obstacles' endpoints cut that wedge into open sub-wedges; inside one
    sub-wedge the set of obstacles a ray meets before entering t cannot change
    (obstacles do not cross t's interior or each other), so one generic
    direction per sub-wedge decides it: the sum of the two bounding direction
    vectors.  v is visible iff in some sub-wedge no obstacle is met at or
    before the ray's entry point into t.  All arithmetic is exact.

    Preconditions (guaranteed after check_valid and the segment-is-edge test):
    obstacles do not cross the interior of t and do not cross each other.
    """
    a, b, c = (P[i] for i in tri_row)
    V = P[v]
    oa, ob, oc = orient_int(a, b, V), orient_int(b, c, V), orient_int(c, a, V)
    if oa >= 0 and ob >= 0 and oc >= 0:
        raise AssertionError(f"vertex {v} lies in the closed triangle {list(tri_row)}")

    def ang_cmp(p, q):  # within a wedge of angle < pi: CCW order as seen from V
        o = orient_int(V, p, q)
        return -1 if o > 0 else (1 if o < 0 else 0)

    corners = sorted([a, b, c], key=cmp_to_key(ang_cmp))
    lo, hi = corners[0], corners[-1]

    def in_wedge(q):
        if q == V:
            return False
        return (
            orient_int(V, lo, q) >= 0
            and orient_int(V, q, hi) >= 0
            and not (
                orient_int(V, lo, q) == 0
                and (q[0] - V[0]) * (lo[0] - V[0]) + (q[1] - V[1]) * (lo[1] - V[1]) < 0
            )
        )

    obs = [(P[i], P[j]) for i, j in obstacles if i != v and j != v]
    crit = [a, b, c] + [q for A, B in obs for q in (A, B) if in_wedge(q)]
    crit.sort(key=cmp_to_key(ang_cmp))
    dirs = [crit[0]]
    for q in crit[1:]:
        if ang_cmp(dirs[-1], q) != 0:
            dirs.append(q)

    edges = [(a, b), (b, c), (c, a)]
    for p, q in itertools.pairwise(dirs):
        D = (p[0] + q[0] - 2 * V[0], p[1] + q[1] - 2 * V[1])
        # entry parameter into t: max over the edges that the ray enters through
        lam_in = Fraction(0)
        for e0, e1 in edges:
            f0 = orient_int(e0, e1, V)
            f1 = (e1[0] - e0[0]) * D[1] - (e1[1] - e0[1]) * D[0]
            if f0 < 0 and f1 > 0:
                lam_in = max(lam_in, Fraction(-f0, f1))
        if not any(_segment_hits_before(V, D, A, B, lam_in) for A, B in obs):
            return True
    return False


def _segments_near(pts, segments, center, radius):
    """Segments that may meet the disk (float, conservative)."""
    if len(segments) == 0:
        return segments
    A = pts[segments[:, 0]]
    B = pts[segments[:, 1]]
    AB = B - A
    L2 = np.einsum("ij,ij->i", AB, AB)
    t = np.clip(np.einsum("ij,ij->i", center - A, AB) / np.where(L2 > 0, L2, 1), 0, 1)
    closest = A + t[:, None] * AB
    d = np.hypot(*(closest - center).T)
    mag = max(float(np.max(np.abs(pts))), float(np.max(np.abs(center))))
    slack = radius * 1e-6 + 1e3 * np.spacing(mag) + 1e-300
    return segments[d <= radius + slack]


def check_constrained_delaunay(points, triangles, segments, vertices=None) -> dict:
    """Constrained Delaunay property, checked against its definition.

    Every segment must be an edge of the triangulation (else the constrained
    Delaunay triangulation is not defined for these triangles).  Then for
    every triangle t, no vertex strictly inside t's circumcircle may be
    visible from the interior of t (see :func:`visible_from_triangle`).
    Points on a circumcircle are allowed.  Exact throughout; the float KD-tree
    only prefilters candidates and nearby obstacle segments conservatively.

    Precondition: :func:`check_valid` passes (no overlapping triangles).
    """
    pts = np.asarray(points, dtype=np.float64)
    tri = _as_triangles(triangles)
    seg = _as_segments(segments)
    counts = edge_counts(tri)
    missing = [
        f"segment {k} {s.tolist()} is not an edge of the triangulation"
        for k, s in enumerate(seg)
        if (min(s), max(s)) not in counts
    ]
    _fail("constrained Delaunay undefined", missing)
    P, shift = exact_integers(pts)
    _, centers, radii = _circumcircles(P, shift, tri)
    allowed = None if vertices is None else {int(v) for v in np.asarray(vertices).ravel()}
    problems = []
    hidden = 0
    for k, cand in enumerate(_candidates(pts, centers, radii)):
        if allowed is not None:
            cand = [v for v in cand if v in allowed]
        inside = _strictly_inside(P, tri[k].tolist(), cand)
        if not inside:
            continue
        near = _segments_near(pts, seg, centers[k], radii[k])
        for v in inside:
            if visible_from_triangle(P, tri[k].tolist(), v, near.tolist()):
                problems.append(
                    f"point {v} {pts[v].tolist()} is strictly inside the circumcircle of triangle "
                    f"{k} {tri[k].tolist()} = {pts[tri[k]].tolist()} and visible from it"
                )
            else:
                hidden += 1
    _fail("constrained Delaunay emptiness violated", problems)
    return {"hidden_inside": hidden}


def check_locally_delaunay(points, triangles, segments=()) -> dict:
    """Every edge that is not a segment is locally Delaunay (exact): the vertex
    across it is not strictly inside the triangle's circumcircle.  By the
    constrained Delaunay lemma this is equivalent to the global definition for
    a valid triangulation that contains the segments; kept as a second,
    differently built oracle to cross-check :func:`check_constrained_delaunay`.
    """
    pts = np.asarray(points, dtype=np.float64)
    tri = _as_triangles(triangles)
    P, _ = exact_integers(pts)
    constrained = {(min(s), max(s)) for s in _as_segments(segments).tolist()}
    opposite = {}
    for t, row in enumerate(tri.tolist()):
        for i in range(3):
            opposite[(row[(i + 1) % 3], row[(i + 2) % 3])] = (t, row[i])
    problems = []
    for (a, b), (t, _apex) in opposite.items():
        if (min(a, b), max(a, b)) in constrained or (b, a) not in opposite:
            continue
        _, other = opposite[(b, a)]
        row = tri[t].tolist()
        if incircle_int(P[row[0]], P[row[1]], P[row[2]], P[other]) > 0:
            problems.append(
                f"edge {(a, b)} of triangle {t} {row} is not locally Delaunay "
                f"(vertex {other} inside)"
            )
    _fail("edges not locally Delaunay", problems)
    return {}


def delaunay_is_unique(points, triangles, segments=()) -> bool:
    """True iff no unconstrained interior edge has its four points exactly
    cocircular.  For a (constrained) Delaunay triangulation this is exactly
    when it is the only one, so two correct implementations must agree."""
    tri = _as_triangles(triangles)
    P, _ = exact_integers(points)
    constrained = {(min(s), max(s)) for s in _as_segments(segments).tolist()}
    opposite = {}
    for t, row in enumerate(tri.tolist()):
        for i in range(3):
            opposite[(row[(i + 1) % 3], row[(i + 2) % 3])] = (t, row[i])
    for (a, b), (t, _) in opposite.items():
        if (min(a, b), max(a, b)) in constrained or (b, a) not in opposite:
            continue
        row = tri[t].tolist()
        if incircle_int(P[row[0]], P[row[1]], P[row[2]], P[opposite[(b, a)][1]]) == 0:
            return False
    return True


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
    seg = _as_segments(segments).tolist()
    nxt: dict[int, int] = {}
    for a, b in seg:
        if a in nxt:
            raise AssertionError(f"node {a} starts two segments")
        nxt[a] = b
    loops, seen = [], set()
    for a, _ in seg:
        if a in seen:
            continue
        loop, x = [], a
        while x not in seen:
            seen.add(x)
            loop.append(x)
            if x not in nxt:
                raise AssertionError(f"segments do not close: node {x} has no outgoing segment")
            x = nxt[x]
        if x != a:
            raise AssertionError(f"segments do not form simple loops (node {x})")
        loops.append(loop)
    return loops


def signed_area_exact(P, loop) -> Fraction:
    """Exact signed area (in the integer scale) of a closed polygon."""
    s = 0
    for i in range(len(loop)):
        p, q = P[loop[i]], P[loop[(i + 1) % len(loop)]]
        s += p[0] * q[1] - q[0] * p[1]
    return Fraction(s, 2)


def point_in_polygon(q, poly) -> int:
    """Exact location of integer point q w.r.t. the closed polygon ``poly``
    (list of integer points): +1 inside, 0 on the boundary, -1 outside.
    Crossing number with half-open edge rule; all comparisons exact."""
    inside = False
    n = len(poly)
    for i in range(n):
        p1, p2 = poly[i], poly[(i + 1) % n]
        o = orient_int(p1, p2, q)
        if (
            o == 0
            and min(p1[0], p2[0]) <= q[0] <= max(p1[0], p2[0])
            and min(p1[1], p2[1]) <= q[1] <= max(p1[1], p2[1])
        ):
            return 0
        # edge crosses the horizontal line through q, to the right of q?
        if (p1[1] > q[1]) != (p2[1] > q[1]) and (o > 0) == (p2[1] > p1[1]):
            inside = not inside
    return 1 if inside else -1


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


def locate_centroids(points, triangles, loops, P=None, exact=False) -> np.ndarray:
    """domain_location of every triangle's centroid: +1 inside the domain,
    0 on a loop, -1 outside.  ``loops[0]`` is the outer loop.

    The exact answer, fast: a vectorised float crossing-number test decides
    every centroid whose decisions are certain (each y comparison farther than
    the centroid's rounding error ``delta``, each orientation larger than its
    error bound); the few uncertain ones are re-decided exactly (integer
    arithmetic on 3x the coordinates).  ``exact=True`` decides all exactly
    (slow; used to test the fast path)."""
    pts = np.asarray(points, dtype=np.float64)
    tri = _as_triangles(triangles)
    if P is None:
        P, _ = exact_integers(pts)
    P3 = [(3 * x, 3 * y) for x, y in P]

    def exact_at(t):
        a, b, c = tri[t].tolist()
        g = (P[a][0] + P[b][0] + P[c][0], P[a][1] + P[b][1] + P[c][1])
        return domain_location(P3, loops, g)

    if exact:
        return np.array([exact_at(t) for t in range(len(tri))], dtype=np.int64)
    q = (pts[tri[:, 0]] + pts[tri[:, 1]] + pts[tri[:, 2]]) / 3.0
    qx, qy = q[:, 0], q[:, 1]
    eps = np.finfo(np.float64).eps
    mag = float(np.max(np.abs(pts))) if len(pts) else 0.0
    delta = 8 * eps * mag + 1e-300  # |float centroid - exact centroid| per coordinate
    uncertain = np.zeros(len(tri), dtype=bool)
    inside = []
    for loop in loops:
        ins = np.zeros(len(tri), dtype=bool)
        for i in range(len(loop)):
            p1 = pts[loop[i]]
            p2 = pts[loop[(i + 1) % len(loop)]]
            dy1, dy2 = p1[1] - qy, p2[1] - qy
            uncertain |= (np.abs(dy1) <= delta) | (np.abs(dy2) <= delta)
            straddle = (p1[1] > qy) != (p2[1] > qy)
            ex, ey = p2[0] - p1[0], p2[1] - p1[1]
            u, w = ex * (qy - p1[1]), ey * (qx - p1[0])
            o = u - w
            err = 2 * (abs(ex) + abs(ey)) * delta + 4 * eps * (np.abs(u) + np.abs(w))
            uncertain |= straddle & (np.abs(o) <= err)
            ins ^= straddle & ((o > 0) == (p2[1] > p1[1]))
        inside.append(ins)
    out = np.where(inside[0], 1, -1).astype(np.int64)
    for ins in inside[1:]:
        out[ins] = -1
    for t in np.nonzero(uncertain)[0]:
        out[t] = exact_at(int(t))
    return out


def split_outer(P, loops) -> list[list[int]]:
    """Order loops as [outer, holes...]: the outer loop is the one with the
    largest absolute area (it encloses the others in a valid domain)."""
    areas = [abs(signed_area_exact(P, lp)) for lp in loops]
    k = max(range(len(loops)), key=lambda i: areas[i])
    return [loops[k]] + [lp for i, lp in enumerate(loops) if i != k]


def domain_area(points, loops) -> float:
    """Exact area |outer| - sum |holes| rounded once to float."""
    P, shift = exact_integers(points)
    loops = [list(map(int, lp)) for lp in loops]
    ordered = split_outer(P, loops)
    a = abs(signed_area_exact(P, ordered[0])) - sum(
        abs(signed_area_exact(P, lp)) for lp in ordered[1:]
    )
    return float(a / (1 << (2 * shift)))


def triangle_areas(points, triangles) -> np.ndarray:
    pts = np.asarray(points, dtype=np.float64)
    tri = _as_triangles(triangles)
    a, b, c = pts[tri[:, 0]], pts[tri[:, 1]], pts[tri[:, 2]]
    return 0.5 * (
        (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    )


# ---------------------------------------------------------------------------
# 2. boundary conformity
# ---------------------------------------------------------------------------


def check_conforming(points, triangles, segments, area=None, rel=1e-12) -> dict:
    """Boundary conformity of a triangulated domain.

    - every segment is an edge of the mesh;
    - the mesh's boundary edges (used by one triangle) are exactly the
      segments, and each is traversed by its triangle in the segment's
      direction (domain on the left);
    - no triangle centroid lies outside the outer loop, inside a hole or on a
      loop (exact point-in-polygon on 3x the integer coordinates);
    - math.fsum of the triangle areas equals the domain area (exact shoelace
      over the loops chained from ``segments``, or ``area`` if given) within
      relative error ``rel``.
    """
    pts = np.asarray(points, dtype=np.float64)
    tri = _as_triangles(triangles)
    seg = _as_segments(segments)
    problems = []
    counts = edge_counts(tri)
    for k, (a, b) in enumerate(seg.tolist()):
        if (min(a, b), max(a, b)) not in counts:
            problems.append(
                f"segment {k} {[a, b]} ({pts[a].tolist()} -> {pts[b].tolist()}) is not a mesh edge"
            )
    _fail("boundary segments missing from the mesh", problems)

    bnd = boundary_edges(tri)
    seg_directed = {(a, b) for a, b in seg.tolist()}
    seg_undirected = {(min(a, b), max(a, b)) for a, b in seg_directed}
    for a, b in sorted(bnd):
        if (min(a, b), max(a, b)) not in seg_undirected:
            problems.append(
                f"mesh boundary edge {(a, b)} ({pts[a].tolist()} -> {pts[b].tolist()}) "
                "is not a segment"
            )
        elif (a, b) not in seg_directed:
            problems.append(
                f"segment {(b, a)} has the mesh on its right (domain should be on the left)"
            )
    for a, b in sorted(seg_directed):
        if (a, b) not in bnd and (b, a) not in bnd:
            problems.append(f"segment {(a, b)} is an interior edge (triangles on both sides)")
    _fail("mesh boundary differs from the segments", problems)

    P, _shift = exact_integers(pts)
    loops = split_outer(P, loops_from_segments(seg))
    where_all = locate_centroids(pts, tri, loops, P)
    for t, (a, b, c) in enumerate(tri.tolist()):
        where = where_all[t]
        if where <= 0:
            kind = (
                "outside the domain (outside the outer loop or inside a hole)"
                if where < 0
                else "on a boundary loop"
            )
            problems.append(
                f"triangle {t} {[a, b, c]} has its centroid {kind}: {pts[[a, b, c]].tolist()}"
            )
    _fail("triangles outside the domain", problems)

    expected = domain_area(pts, loops) if area is None else float(area)
    total = math.fsum(triangle_areas(pts, tri))
    err = abs(total - expected) / abs(expected)
    if not err <= rel:
        raise AssertionError(
            f"triangle areas sum to {total!r}, domain area is {expected!r} "
            f"(rel err {err:.3e} > {rel})"
        )
    return {"loops": len(loops), "area": total, "rel_area_error": err}


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


# ---------------------------------------------------------------------------
# 8. radius ratio, angles
# ---------------------------------------------------------------------------


def radius_ratio_reference(points, triangles) -> np.ndarray:
    """2r/R from the classical formulas, not from eq. 10:
    inradius r = 2A / perimeter, circumradius R = abc / (4A), A from the cross
    product.  So 2r/R = 16 A^2 / (perimeter * a * b * c).  0 for zero area."""
    pts = np.asarray(points, dtype=np.float64)
    tri = _as_triangles(triangles)
    A = np.abs(triangle_areas(pts, tri))
    p0, p1, p2 = pts[tri[:, 0]], pts[tri[:, 1]], pts[tri[:, 2]]
    la = np.hypot(*(p1 - p2).T)
    lb = np.hypot(*(p2 - p0).T)
    lc = np.hypot(*(p0 - p1).T)
    perimeter = la + lb + lc
    with np.errstate(divide="ignore", invalid="ignore"):
        r_in = 2 * A / perimeter
        R_circ = la * lb * lc / (4 * A)
        rho = np.where(A > 0, 2 * r_in / R_circ, 0.0)
    return rho


def angles_reference(points, triangles) -> np.ndarray:
    """Interior angles in degrees at each triangle vertex, from atan2 of the
    cross and dot products of the two incident edge vectors."""
    pts = np.asarray(points, dtype=np.float64)
    tri = _as_triangles(triangles)
    out = np.empty(tri.shape)
    for i in range(3):
        p = pts[tri[:, i]]
        u = pts[tri[:, (i + 1) % 3]] - p
        w = pts[tri[:, (i + 2) % 3]] - p
        cross = u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0]
        dot = u[:, 0] * w[:, 0] + u[:, 1] * w[:, 1]
        out[:, i] = np.degrees(np.arctan2(np.abs(cross), dot))
    return out


# ---------------------------------------------------------------------------
# 3. population criterion (paper eq. 1-4, 6)
# ---------------------------------------------------------------------------

_PI = math.pi


def boundary_radii_reference(points, segments) -> dict[int, float]:
    """Eq. 1-2: radius of each boundary node's bubble from the lengths l1, l2
    of its two boundary edges: r = sqrt(sqrt(3)/(8 pi) (l1^2 + l2^2))."""
    pts = np.asarray(points, dtype=np.float64)
    incident: dict[int, list[float]] = {}
    for a, b in _as_segments(segments).tolist():
        length = math.hypot(pts[b, 0] - pts[a, 0], pts[b, 1] - pts[a, 1])
        incident.setdefault(a, []).append(length)
        incident.setdefault(b, []).append(length)
    out = {}
    for node, lengths in incident.items():
        if len(lengths) != 2:
            raise AssertionError(
                f"boundary node {node} has {len(lengths)} boundary edges, expected 2"
            )
        out[node] = math.sqrt(math.sqrt(3) / (8 * _PI) * (lengths[0] ** 2 + lengths[1] ** 2))
    return out


def element_bubble_radii(points, triangles, radii) -> np.ndarray:
    """Eq. 3: r_e at each triangle's centroid e by reciprocal-distance
    interpolation of the node radii: sum(r_i / l_ie) / sum(1 / l_ie)."""
    pts = np.asarray(points, dtype=np.float64)
    tri = _as_triangles(triangles)
    r = np.asarray(radii, dtype=np.float64)
    out = np.empty(len(tri))
    for t, row in enumerate(tri.tolist()):
        xs = [pts[i] for i in row]
        ex = math.fsum(x[0] for x in xs) / 3
        ey = math.fsum(x[1] for x in xs) / 3
        w = [1.0 / math.hypot(x[0] - ex, x[1] - ey) for x in xs]
        out[t] = math.fsum(r[i] * wi for i, wi in zip(row, w, strict=False)) / math.fsum(w)
    return out


def population_bubble_area(points, triangles, radii) -> float:
    """Eq. 4 summed: sum over triangles of A_e = pi r_e^2 (the left side of eq. 6)."""
    re = element_bubble_radii(points, triangles, radii)
    return math.fsum(_PI * x * x for x in re)
