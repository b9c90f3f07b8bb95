"""Boundary conformity: the mesh covers exactly the domain of the input boundary.

Supported: each input segment is one mesh edge, or a chain of mesh edges
through mesh nodes that lie on the segment (a mesher that split it; within
``split_tol`` of the segment's line, relative to its length, or SPLIT_ULPS
units in the last place of its end points' largest coordinate, whichever is
larger: a point on a slanted segment far from the origin has no float
position nearer than that; 0 = exactly on it).  Splits are reported in
``Report.splits`` (and as violations when not allowed).
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np

from .domain import Boundary
from .exact import ExactPoints, orient_int
from .report import Report
from .topology import HalfEdges

SPLIT_ULPS = 4  # a split node's float position may be this many ulps off its segment


def map_boundary_nodes(points: np.ndarray, boundary_points: np.ndarray, report: Report,
                       needed=None):
    """Mesh node of each input boundary node at the same position (-1 if none).

    Positions compare as float values (so 0.0 == -0.0); anything else is a
    ``boundary_moved`` violation naming the nearest mesh node, for the
    ``needed`` nodes (a mask; default all)."""
    index: dict[tuple[float, float], int] = {}
    for i, xy in enumerate(points.tolist()):
        index.setdefault((xy[0], xy[1]), i)
    found = np.array([index.get((x, y), -1) for x, y in boundary_points.tolist()], np.int64)
    lost = np.nonzero((found < 0) & (True if needed is None else needed))[0]
    if len(lost):
        from scipy.spatial import cKDTree

        dist, near = cKDTree(points).query(boundary_points[lost])
        for b, d, v in zip(lost.tolist(), dist.tolist(), near.tolist()):
            report.add("boundary_moved", f"input boundary node {b} {boundary_points[b].tolist()} "
                       f"is not a mesh node; nearest is node {v} {points[v].tolist()} at "
                       f"distance {d:.3e}", node=b)
    return found


def _adjacency(H: HalfEdges):
    lo, hi = np.divmod(H.keys, H.n)
    a, b = np.concatenate([lo, hi]), np.concatenate([hi, lo])
    order = np.argsort(a, kind="stable")
    start = np.searchsorted(a[order], np.arange(H.n + 1))
    return start, b[order]


def _walk(E: ExactPoints, start, nbrs, A, B, tol):
    """Mesh nodes from A to B along edges whose nodes lie on segment AB, or None."""
    pts = E.scaled  # times a power of two, so that d @ d neither underflows nor overflows
    d = pts[B] - pts[A]
    L2 = float(d @ d)
    reach = max(tol * L2, _rounding(pts[[A, B]]) * math.sqrt(L2))  # |cross| = distance * L
    chain, x, t_x = [A], A, 0.0
    for _ in range(len(start)):  # bounded: the parameter grows at every step
        around = nbrs[start[x]:start[x + 1]]
        if B in around:
            return [*chain, B]
        rel = pts[around] - pts[A]
        t = rel @ d / L2
        if tol == 0:
            on = np.array([orient_int(E.P[A], E.P[B], E.P[y]) == 0 for y in around.tolist()])
        else:
            on = np.abs(rel[:, 0] * d[1] - rel[:, 1] * d[0]) <= reach
        ok = on & (t > t_x) & (t < 1)
        if not ok.any():
            return None
        k = int(np.argmin(np.where(ok, t, np.inf)))
        x, t_x = int(around[k]), float(t[k])
        chain.append(x)
    return None


def segment_chains(E, H, seg_mesh, report, split_tol, allow_splits, ids=None):
    """Mesh edge chain of each input segment (mesh ids); returns the sub-edges
    (J, 2) and the input segment each comes from (its number in ``ids``, the
    caller's numbering, when given)."""
    n_seg = len(seg_mesh)
    ids = np.arange(n_seg) if ids is None else np.asarray(ids, np.int64)
    mapped = (seg_mesh >= 0).all(axis=1)
    direct = np.zeros(n_seg, bool)
    direct[mapped] = H.edge_count(seg_mesh[mapped, 0], seg_mesh[mapped, 1]) > 0
    sub = [seg_mesh[direct]]
    owner = [ids[direct]]
    todo = np.nonzero(mapped & ~direct)[0].tolist()
    if todo:
        start, nbrs = _adjacency(H)
    for i in todo:
        A, B, k = int(seg_mesh[i, 0]), int(seg_mesh[i, 1]), int(ids[i])
        chain = _walk(E, start, nbrs, A, B, split_tol)
        if chain is None:
            report.add("missing_segment", f"segment {k} ({A}, {B}) {E.points[A].tolist()} -> "
                       f"{E.points[B].tolist()} is not a mesh edge nor a chain of mesh edges "
                       "along it", segment=k, edge=(A, B))
            continue
        report.splits[k] = tuple(chain)
        if not allow_splits:
            report.add("split_segment", f"segment {k} ({A}, {B}) is split by mesh nodes "
                       f"{chain[1:-1]}", segment=k, edge=(A, B))
        sub.append(np.column_stack([chain[:-1], chain[1:]]))
        owner.append(np.full(len(chain) - 1, k))
    return np.concatenate(sub).astype(np.int64), np.concatenate(owner)


def check_boundary_edges(E, H, sub, owner, report, oriented, inner=None, inner_owner=None):
    """Mesh boundary edges are exactly the segment pieces, each with the mesh
    on one side; the pieces ``inner`` of interior constraints have it on both."""
    if inner is not None and len(inner):
        alone = H.edge_count(inner[:, 0], inner[:, 1]) == 1
        for j in np.nonzero(alone)[0].tolist():
            e = (int(inner[j, 0]), int(inner[j, 1]))
            report.add("one_sided_constraint", f"interior constraint {int(inner_owner[j])} "
                       f"piece {e} has triangles on one side only",
                       segment=int(inner_owner[j]), edge=e)
        sub = np.vstack([sub, inner[alone]])  # reported: not extra boundary edges too
        owner = np.concatenate([owner, inner_owner[alone]])
        keep = np.arange(len(sub)) < len(sub) - int(alone.sum())
    else:
        keep = np.ones(len(sub), bool)
    count = np.where(keep, H.edge_count(sub[:, 0], sub[:, 1]), 1)
    for j in np.nonzero(count == 2)[0].tolist():
        e = (int(sub[j, 0]), int(sub[j, 1]))
        report.add("interior_segment", f"segment {int(owner[j])} piece {e} is an interior edge "
                   "(triangles on both sides)", segment=int(owner[j]), edge=e)
    if oriented:
        wrong = keep & (count == 1) & (H.find_directed(sub[:, 0], sub[:, 1]) < 0)
        for j in np.nonzero(wrong)[0].tolist():
            e = (int(sub[j, 0]), int(sub[j, 1]))
            report.add("segment_orientation", f"segment {e} has the mesh on its right "
                       "(domain should be on the left)", segment=int(owner[j]), edge=e)
    keys = np.minimum(sub[:, 0], sub[:, 1]) * H.n + np.maximum(sub[:, 0], sub[:, 1])
    bnd = H.boundary()
    lo, hi = np.minimum(H.u[bnd], H.v[bnd]), np.maximum(H.u[bnd], H.v[bnd])
    extra = bnd[~np.isin(lo * H.n + hi, keys)]
    for h in extra.tolist():
        e = (int(H.u[h]), int(H.v[h]))
        report.add("extra_boundary_edge", f"mesh boundary edge {e} of triangle {h // 3} "
                   f"({E.points[e[0]].tolist()} -> {E.points[e[1]].tolist()}) is not a segment",
                   triangle=h // 3, edge=e)


def check_inside(E: ExactPoints, tri: np.ndarray, domain: Boundary, report, exact=False):
    """Every triangle's centroid strictly inside the domain (exact even-odd rule)."""
    where = locate_centroids(E, tri, domain, exact=exact)
    for t in np.nonzero(where <= 0)[0].tolist():
        kind = "on a boundary loop" if where[t] == 0 else \
            "outside the domain (outside the outer loop or inside a hole)"
        report.add("outside_domain", f"triangle {t} {tri[t].tolist()} has its centroid {kind}: "
                   f"{E.points[tri[t]].tolist()}", triangle=t)
    return where


def locate_centroids(E: ExactPoints, tri: np.ndarray, domain: Boundary, exact=False):
    """+1 / 0 / -1: each triangle's centroid inside / on / outside the domain."""
    pts = E.points
    q = (pts[tri[:, 0]] + pts[tri[:, 1]] + pts[tri[:, 2]]) / 3.0
    mag = float(np.max(np.abs(pts))) if len(pts) else 0.0
    delta = 8 * np.finfo(np.float64).eps * mag + 1e-300  # |float - exact centroid|
    P = E.P

    def exact_centroid(t):  # 3x the centroid, in E's integer scale
        a, b, c = tri[t].tolist()
        return P[a][0] + P[b][0] + P[c][0], P[a][1] + P[b][1] + P[c][1], 3

    return domain.locate(q, exact_centroid, delta, exact=exact)


def _rounding(points):
    """SPLIT_ULPS units in the last place of the largest |coordinate| of ``points``."""
    return SPLIT_ULPS * float(np.spacing(np.abs(points).max(initial=0.0)))


def check_area(E, tri, domain: Boundary, report, rel):
    """math.fsum of the triangle areas equals the exact domain area within ``rel``
    of it plus the area a boundary moved by its nodes' rounding covers
    (:func:`_rounding` of all points times the boundary's length), both taken
    on E's scaled points (a power of two, so the relative error is the same,
    but no area underflows or overflows); returned at the input's scale,
    where they may be 0 or inf."""
    from .measures import triangle_areas

    expected = float(domain.area_exact() * Fraction(1, 1 << (2 * E.shift))
                     * Fraction(2) ** (-2 * E.exponent))
    total = math.fsum(triangle_areas(E.scaled, tri).tolist())
    ends = E.scaled[domain.segments]
    length = math.fsum(np.hypot(*(ends[:, 1] - ends[:, 0]).T).tolist())
    slack = _rounding(E.scaled) * length
    err = (max(abs(total - expected) - slack, 0.0) / abs(expected) if expected
           else abs(total))
    with np.errstate(over="ignore"):
        total, expected = (float(np.ldexp(v, 2 * E.exponent)) for v in (total, expected))
    if not err <= rel:
        report.add("area", f"triangle areas sum to {total!r}, domain area is {expected!r} "
                   f"(rel err {err:.3e} > {rel})")
    return total, expected, err
