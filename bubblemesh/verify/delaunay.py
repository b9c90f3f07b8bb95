"""Exact (constrained) Delaunay emptiness, checked against its definition.

For every triangle t, no mesh node strictly inside t's circumcircle may be
visible from the interior of t, visibility being blocked by the obstacle
segments (Chew; Shewchuk's constrained Delaunay).  Points on a circumcircle
are allowed.  Candidates come from a KD-tree query around a float
circumcentre with a radius proved to contain the exact disk; the in-circle
decisions are exact (filtered), and visibility is exact integer/Fraction
arithmetic.
"""

from __future__ import annotations

import itertools
import math
from fractions import Fraction
from functools import cmp_to_key

import numpy as np

from .exact import ExactPoints, circumcircle_exact, incircle_signs, orient_int
from .report import Report
from .topology import HalfEdges

_U = 2.0**-53


def circumcircles(E: ExactPoints, tri: np.ndarray):
    """Float circumcentres (in E.scaled units) and radii enclosing the exact disks.

    Well-conditioned triangles use a float formula with an a-priori bound on
    the centre's error e: every point strictly inside the exact circle is
    within R_float + 2e of the float centre.  The others get the exact
    circle rounded once, with a 1e-9 relative margin."""
    s = E.scaled
    a, b, c = s[tri[:, 0]], s[tri[:, 1]], s[tri[:, 2]]
    bx, by = b[:, 0] - a[:, 0], b[:, 1] - a[:, 1]
    cx, cy = c[:, 0] - a[:, 0], c[:, 1] - a[:, 1]
    b2, c2 = bx * bx + by * by, cx * cx + cy * cy
    eps = 64 * _U  # generous: each quantity below is a few roundings deep
    d = 2 * (bx * cy - by * cx)
    e_d = eps * 2 * (np.abs(bx * cy) + np.abs(by * cx))
    with np.errstate(all="ignore"):
        ux = (cy * b2 - by * c2) / d
        uy = (bx * c2 - cx * b2) / d
        e_x = 2 * (eps * (np.abs(cy) * b2 + np.abs(by) * c2) + np.abs(ux) * e_d) / np.abs(d)
        e_y = 2 * (eps * (np.abs(bx) * c2 + np.abs(cx) * b2) + np.abs(uy) * e_d) / np.abs(d)
        centers = a + np.column_stack([ux, uy])
        err = np.hypot(e_x, e_y) + 4 * _U * (np.abs(centers).sum(axis=1) + np.abs(a).sum(axis=1))
        reach = np.max([np.hypot(*(centers - p).T) for p in (a, b, c)], axis=0)
        radii = (reach + 2 * err) * (1 + 1e-12) + 1e-290
    bad = ~(np.abs(d) > 2 * e_d) | ~np.isfinite(radii) | ~np.isfinite(centers).all(axis=1)
    bad |= E.unsafe[tri].any(axis=1)
    for k in np.nonzero(bad)[0].tolist():
        centers[k], radii[k] = _exact_circle(E, tri[k])
    return centers, radii


def _exact_circle(E: ExactPoints, row):
    P = E.P
    try:
        cx, cy, r2 = circumcircle_exact(P[row[0]], P[row[1]], P[row[2]])
    except ZeroDivisionError:
        return (0.0, 0.0), math.inf
    mag = float(np.max(np.abs(E.points))) if len(E.points) else 1.0
    k = int(np.frexp(mag)[1]) if mag > 0 else 0
    unit = 1 << E.shift
    try:
        center = (math.ldexp(float(cx / unit), -k), math.ldexp(float(cy / unit), -k))
        radius = math.ldexp(math.sqrt(float(r2 / (unit * unit))), -k)
    except OverflowError:  # a sliver whose circle exceeds the float range
        return (0.0, 0.0), math.inf
    return center, radius * (1 + 1e-9) + 64 * _U * max(abs(center[0]), abs(center[1]), 1.0)


def candidates(E: ExactPoints, tri, centers, radii, nodes):
    """(triangle, node) pairs, node among ``nodes`` possibly inside the circle."""
    from scipy.spatial import cKDTree

    huge = ~np.isfinite(radii)
    tree = cKDTree(E.scaled[nodes])
    found = tree.query_ball_point(centers, np.where(huge, 0.0, radii))
    lengths = np.fromiter((len(f) for f in found), np.int64, len(found))
    flat = np.fromiter(itertools.chain.from_iterable(found), np.int64, int(lengths.sum()))
    t = np.repeat(np.arange(len(tri)), lengths)
    v = nodes[flat]
    if huge.any():  # circle beyond the float range: every node is a candidate
        big = np.nonzero(huge)[0]
        t = np.concatenate([t, np.repeat(big, len(nodes))])
        v = np.concatenate([v, np.tile(nodes, len(big))])
    own = (v == tri[t, 0]) | (v == tri[t, 1]) | (v == tri[t, 2])
    return t[~own], v[~own]


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

    Preconditions (hold for a valid, conforming mesh): obstacles do not cross
    the interior of t and do not cross each other.  Raises ValueError if v is
    in the closed triangle.
    """
    a, b, c = (P[i] for i in tri_row)
    V = P[v]
    oa, ob, oc = orient_int(a, b, V), orient_int(b, c, V), orient_int(c, a, V)
    if oa >= 0 and ob >= 0 and oc >= 0:
        raise ValueError(f"vertex {v} lies in the closed triangle {list(tri_row)}")

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


def segments_near(pts, segments, center, radius):
    """Segments (K, 2) that may meet the disk (float, conservative)."""
    if len(segments) == 0 or not math.isfinite(radius):
        return segments
    A, B = pts[segments[:, 0]], pts[segments[:, 1]]
    AB = B - A
    L2 = np.einsum("ij,ij->i", AB, AB)
    t = np.clip(np.einsum("ij,ij->i", center - A, AB) / np.where(L2 > 0, L2, 1), 0, 1)
    d = np.hypot(*(A + t[:, None] * AB - center).T)
    mag = max(float(np.max(np.abs(pts))), float(np.max(np.abs(center))))
    slack = radius * 1e-6 + 1e3 * np.spacing(mag) + 1e-300
    return segments[d <= radius + slack]


def local_violations(E: ExactPoints, H: HalfEdges, positive, obstacles) -> np.ndarray:
    """Half-edges h (one per interior edge, both triangles CCW, not an
    obstacle) whose far vertex is strictly inside h's triangle's circumcircle."""
    h, r = _interior_pairs(H, positive, obstacles)
    tri = H.tri
    t = h // 3
    far = tri[r // 3, r % 3]
    s = incircle_signs(E, tri[t, 0], tri[t, 1], tri[t, 2], far)
    return h[s > 0]


def cocircular_edges(E: ExactPoints, H: HalfEdges, positive, obstacles) -> np.ndarray:
    """Interior non-obstacle half-edges whose four points are exactly cocircular."""
    h, r = _interior_pairs(H, positive, obstacles)
    t = h // 3
    s = incircle_signs(E, H.tri[t, 0], H.tri[t, 1], H.tri[t, 2], H.tri[r // 3, r % 3])
    return h[s == 0]


def _interior_pairs(H: HalfEdges, positive, obstacles):
    h = np.nonzero((H.reverse >= 0) & (H.reverse > np.arange(len(H.reverse))))[0]
    r = H.reverse[h]
    keep = positive[h // 3] & positive[r // 3]
    if len(obstacles):
        ob = np.asarray(obstacles, dtype=np.int64).reshape(-1, 2)
        keys = np.minimum(ob[:, 0], ob[:, 1]) * H.n + np.maximum(ob[:, 0], ob[:, 1])
        mine = np.minimum(H.u[h], H.v[h]) * H.n + np.maximum(H.u[h], H.v[h])
        keep &= ~np.isin(mine, keys)
    return h[keep], r[keep]


def check_delaunay(E, H: HalfEdges, positive, obstacles, report: Report, vertices=None):
    """Constrained Delaunay emptiness of the CCW triangles (see module doc).

    ``obstacles`` (K, 2) node pairs block visibility (empty: plain Delaunay);
    ``vertices`` restricts the nodes tested (default: every node of a triangle).
    Returns facts: candidates tested, nodes inside but hidden, pairs left
    untested once ``report.limit`` violations were found."""
    tri = H.tri
    ids = np.nonzero(positive)[0]
    nodes = np.unique(tri) if vertices is None else \
        np.intersect1d(np.unique(tri), np.asarray(vertices, dtype=np.int64).ravel())
    if not len(ids) or not len(nodes):
        return dict(candidates=0, hidden_inside=0, untested=0)
    centers, radii = circumcircles(E, tri[ids])
    t, v = candidates(E, tri[ids], centers, radii, nodes)
    row = tri[ids[t]]
    inside = incircle_signs(E, row[:, 0], row[:, 1], row[:, 2], v) > 0
    t, v = t[inside], v[inside]
    obstacles = np.asarray(obstacles, dtype=np.int64).reshape(-1, 2)
    across = _across_edge(H, ids[t], v, obstacles)
    hidden = untested = 0
    for k, (tk, vk) in enumerate(zip(t.tolist(), v.tolist())):
        T = int(ids[tk])
        h = int(across[k])
        if h < 0 and report.full("not_delaunay"):
            untested += 1
            continue
        if h < 0 and not _visible(E, tri[T], vk, obstacles, centers[tk], radii[tk], report, T):
            hidden += 1
            continue
        _report_inside(E, tri, T, vk, h, H, report)
    return dict(candidates=len(inside), hidden_inside=hidden, untested=untested)


def _across_edge(H: HalfEdges, t, v, obstacles):
    """Half-edge of t, not an obstacle, whose twin's far vertex is v (then v
    is visible through that edge), else -1."""
    keys = np.minimum(obstacles[:, 0], obstacles[:, 1]) * H.n + np.maximum(*obstacles.T)
    out = np.full(len(t), -1, np.int64)
    for i in range(3):
        h = 3 * t + i
        r = np.maximum(H.reverse[h], 0)
        far = np.where(H.reverse[h] >= 0, H.tri[r // 3, r % 3], -1)
        free = ~np.isin(np.minimum(H.u[h], H.v[h]) * H.n + np.maximum(H.u[h], H.v[h]), keys)
        out = np.where((out < 0) & (far == v) & free, h, out)
    return out


def _visible(E, row, v, obstacles, center, radius, report, t) -> bool:
    near = segments_near(E.scaled, obstacles, center, radius)
    try:
        return visible_from_triangle(E.P, row.tolist(), v, near.tolist())
    except ValueError:
        report.add("vertex_in_triangle", f"node {v} {E.points[v].tolist()} lies in the closed "
                   f"triangle {t} {row.tolist()} without being its vertex", triangle=t, node=v)
        return False


def _report_inside(E, tri, t, v, h, H, report):
    edge = None if h < 0 else (int(H.u[h]), int(H.v[h]))
    why = "" if edge is None else f" (across edge {edge}: that edge is not locally Delaunay)"
    report.add("not_delaunay", f"point {v} {E.points[v].tolist()} is strictly inside the "
               f"circumcircle of triangle {t} {tri[t].tolist()} = {E.points[tri[t]].tolist()} "
               f"and visible from it{why}", triangle=t, node=v, edge=edge)
