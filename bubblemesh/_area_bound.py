"""Hard triangle-area bounds on a finished mesh (Triangle's ``-a``: a global
``max_area`` and the regions' max_area), for :func:`bubblemesh.mesh`.

The size field of ``bubblemesh.mesh`` makes triangles of about the asked
size, so some exceed an area bound by a little.  :func:`bound_areas` then
inserts nodes into the triangles that are too large, in rounds: each such
triangle proposes its circumcentre (Delaunay refinement's point, the farthest
from every node of its empty circle) if an exact walk reaches it without
crossing a segment and it neither encroaches a segment edge (lies in its
diametral circle) nor comes close to a node.  An encroached (or crossed)
segment edge on which an equilateral triangle would exceed the bound is split
at its midpoint instead, as in Ruppert's refinement: the midpoint joins the
boundary nodes and the mesh's domain gets the split segment, marker kept.
Otherwise the triangle's centroid is taken.  Of proposals landing in the same
or neighbouring triangles only the one of the triangle most over its bound is
taken.  The nodes are added and the whole mesh re-triangulated with
the constrained Delaunay triangulation; rounds repeat until no triangle
exceeds its bound (each round splits the worst triangle at least, so the
largest area shrinks), at most :data:`MAX_ROUNDS` times.

A size field that aims at ``FILL`` times the bound (``Domain.region_size``
does) leaves few triangles over it, and the insertions, which leave poor
stars behind, stay few (docs/performance.md has the measurements).

Areas are compared with a relative margin of :data:`MARGIN`, so a triangle
whose floating-point area passes is below its bound exactly.  Paper mode
(``bubblemesh.generate`` / ``optimize``) never calls this.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
from numba import njit

from ._mesh import Mesh, _flood, _half_mean_edge
from ._smoothing import compass_polish, guarded_smooth, stars, triangle_quality
from .errors import GeometryError, MeshingError
from .predicates import orient2d
from .topology import neighbors_of
from .triangulation import constrained_delaunay

__all__ = ["FILL", "MARGIN", "MAX_ROUNDS", "bound_areas", "triangle_limits"]

MAX_ROUNDS = 60
MARGIN = 1e-9  # relative: far above the rounding of a non-degenerate area
SQRT3 = 3.0**0.5
CLOSE = 0.5  # a circumcentre nearer a node than this times the circumradius is refused
POLISH_CYCLES, SMOOTH_SWEEPS, POOR = 3, 4, 0.85  # smoothing after the insertions
# A size field aiming at this fraction of an area bound leaves few triangles over it
FILL = 0.6


@njit(cache=True)
def _areas(X, T):
    """Each triangle's area, from its first vertex (no large-coordinate cancellation)."""
    out = np.empty(T.shape[0])
    for t in range(T.shape[0]):
        a, b, c = T[t, 0], T[t, 1], T[t, 2]
        out[t] = 0.5 * ((X[b, 0] - X[a, 0]) * (X[c, 1] - X[a, 1])
                        - (X[b, 1] - X[a, 1]) * (X[c, 0] - X[a, 0]))
    return out


@njit(cache=True)
def _circumcentre(X, T, t):
    """(x, y, radius) of triangle t's circumcircle, relative to its first vertex."""
    a, b, c = T[t, 0], T[t, 1], T[t, 2]
    bx, by = X[b, 0] - X[a, 0], X[b, 1] - X[a, 1]
    cx, cy = X[c, 0] - X[a, 0], X[c, 1] - X[a, 1]
    d = 2.0 * (bx * cy - by * cx)
    ux = (cy * (bx * bx + by * by) - by * (cx * cx + cy * cy)) / d
    uy = (bx * (cx * cx + cy * cy) - cx * (bx * bx + by * by)) / d
    return X[a, 0] + ux, X[a, 1] + uy, np.sqrt(ux * ux + uy * uy)


@njit(cache=True)
def _walk(X, T, N, t, px, py, max_steps):
    """(u, -1, -1): triangle u's closure holds (px, py), reached from t across
    edges that are no segment (N >= 0); (-1, v, j): the segment edge j of
    triangle v is in the way; (-1, -1, -1): the walk did not end."""
    for _ in range(max_steps):
        moved = False
        for j in range(3):
            a, b = T[t, (j + 1) % 3], T[t, (j + 2) % 3]
            if orient2d(X[a, 0], X[a, 1], X[b, 0], X[b, 1], px, py) < 0.0:
                if N[t, j] < 0:
                    return -1, t, j
                t = N[t, j]
                moved = True
                break
        if not moved:
            return t, -1, -1
    return -1, -1, -1


@njit(cache=True)
def _encroached(X, T, N, u, px, py):
    """(v, j): a segment edge (edge j of triangle v, u or a neighbour of u)
    whose diametral circle holds (px, py); (-1, -1) if none."""
    for k in range(4):
        v = u if k == 3 else N[u, k]
        if v < 0:
            continue
        for j in range(3):
            a, b = T[v, (j + 1) % 3], T[v, (j + 2) % 3]
            if N[v, j] < 0 and ((X[a, 0] - px) * (X[b, 0] - px)
                                + (X[a, 1] - py) * (X[b, 1] - py)) <= 0.0:
                return v, j
    return -1, -1


@njit(cache=True)
def _near_a_node(X, T, u, px, py, radius):
    """(px, py) is closer than CLOSE * radius to a node of triangle u."""
    for k in range(3):
        w = T[u, k]
        if (X[w, 0] - px) ** 2 + (X[w, 1] - py) ** 2 < (CLOSE * radius) ** 2:
            return True
    return False


@njit(cache=True)
def _mark(taken, N, t):
    taken[t] = True
    for k in range(3):
        if N[t, k] >= 0:
            taken[N[t, k]] = True


@njit(cache=True)
def _proposals(X, T, N, order, limit, may_split):
    """For the triangles in ``order`` (most over their bound first): new
    interior nodes (circumcentre or centroid) and segment edges to split at
    their midpoints (module docstring), at most one per triangle and its
    neighbours.  An encroached segment edge is split if ``may_split`` and an
    equilateral triangle on it would exceed the bound; else the centroid."""
    taken = np.zeros(T.shape[0], np.bool_)
    out = np.empty((order.shape[0], 2))
    split = np.empty((order.shape[0], 2), np.int64)
    count = cuts = 0
    steps = T.shape[0] + 3
    for t in order:
        if taken[t]:
            continue
        px, py, radius = _circumcentre(X, T, t)
        u, v, j = -1, -1, -1
        if np.isfinite(px) and np.isfinite(py):
            u, v, j = _walk(X, T, N, t, px, py, steps)
            if u >= 0:
                v, j = _encroached(X, T, N, u, px, py)
        if v >= 0 and may_split:
            a, b = T[v, (j + 1) % 3], T[v, (j + 2) % 3]
            if 0.25 * SQRT3 * ((X[a, 0] - X[b, 0]) ** 2 + (X[a, 1] - X[b, 1]) ** 2) > limit[t]:
                if taken[v]:
                    continue  # the next round
                split[cuts, 0], split[cuts, 1] = a, b
                cuts += 1
                _mark(taken, N, v)
                _mark(taken, N, t)
                continue
        if u >= 0 and v < 0 and taken[u]:
            continue  # the next round
        if u < 0 or v >= 0 or _near_a_node(X, T, u, px, py, radius):
            a, b, c = T[t, 0], T[t, 1], T[t, 2]
            px = (X[a, 0] + X[b, 0] + X[c, 0]) / 3.0
            py = (X[a, 1] + X[b, 1] + X[c, 1]) / 3.0
            u = t
        _mark(taken, N, u)
        _mark(taken, N, t)
        out[count, 0], out[count, 1] = px, py
        count += 1
    return out[:count], split[:cuts]


def triangle_limits(X, T, N, regions, max_area=None) -> np.ndarray:
    """(M,) area bound of each triangle: ``max_area`` (None: none) and the
    max_area (> 0) of the region holding it (faces flood-filled from the region
    points across N >= 0; a later region point wins, as in Triangle); inf for none."""
    limit = np.full(len(T), np.inf)
    if regions is not None and len(regions):
        region = np.full(len(T), -1, np.int64)
        for r, (x, y) in enumerate(np.asarray(regions)[:, :2].tolist()):
            _flood(X, T, N, float(x), float(y), r, region)
        bound = np.asarray(regions, np.float64)[:, 3]
        has = region >= 0
        limit[has] = np.where(bound[region[has]] > 0, bound[region[has]], np.inf)
    if max_area is not None:
        limit = np.minimum(limit, float(max_area))
    return limit


def _walled(T, N, segments, n):
    """Neighbours with -1 across every segment, as the constrained triangulation gives."""
    a, b = T[:, [1, 2, 0]], T[:, [2, 0, 1]]
    key = np.minimum(a, b) * n + np.maximum(a, b)
    S = np.sort(segments, axis=1)
    return np.ascontiguousarray(np.where(np.isin(key, S[:, 0] * n + S[:, 1]), -1, N))


def _over(X, T, limit):
    """Triangles whose area exceeds their bound (with the margin), worst first."""
    ratio = _areas(X, T) * (1.0 + MARGIN) / limit
    bad = np.flatnonzero(ratio > 1.0)
    return bad[np.argsort(-ratio[bad], kind="stable")]


class _Nodes:
    """The growing node and segment arrays: interior nodes are appended,
    segment midpoints join the boundary block (the boundary nodes stay first,
    the interior ones shift), each segment row split in place into its two
    halves with its marker and its loop."""

    def __init__(self, mesh: Mesh):
        self.X = np.ascontiguousarray(mesh.points)
        self.segments = np.asarray(mesh.segments)
        self.n_b = mesh.n_boundary
        self.old = np.arange(len(self.X))  # index in ``mesh``, -1 for a new node
        domain = mesh.domain
        self.may_split = domain is not None and len(domain.segments) == len(self.segments)
        if self.may_split:
            self.loop = np.repeat(np.arange(len(domain.loops)), [len(ix) for ix in domain.loops])
            self.marks = domain.segment_markers
        self.movable = np.ones(len(self.X), np.bool_)
        self.movable[np.unique(self.segments)] = False

    def add(self, points):
        self.X = np.vstack([self.X, points])
        self.old = np.concatenate([self.old, np.full(len(points), -1)])
        self.movable = np.concatenate([self.movable, np.ones(len(points), np.bool_)])

    def split(self, edges):
        """Split the segment rows of ``edges`` (either way) at their midpoints."""
        if not len(edges):
            return
        edges = np.unique(np.sort(edges, axis=1), axis=0)  # both sides of an interface
        k, n_b, n = len(edges), self.n_b, len(self.X)
        shift = np.where(np.arange(n) >= n_b, np.arange(n) + k, np.arange(n))
        mid = 0.5 * (self.X[edges[:, 0]] + self.X[edges[:, 1]])
        self.X = np.vstack([self.X[:n_b], mid, self.X[n_b:]])
        self.old = np.concatenate([self.old[:n_b], np.full(k, -1), self.old[n_b:]])
        self.movable = np.concatenate([self.movable[:n_b], np.zeros(k, np.bool_),
                                       self.movable[n_b:]])
        key = np.sort(edges, axis=1) @ np.array([n, 1])
        S = self.segments
        row_key = np.sort(S, axis=1) @ np.array([n, 1])
        order = np.argsort(key)
        at = np.minimum(np.searchsorted(key[order], row_key), k - 1)
        hit = key[order][at] == row_key
        w = n_b + order[at]  # the midpoint's new index for each split row
        S = shift[S]
        rows = np.repeat(np.arange(len(S)), np.where(hit, 2, 1))
        first = np.r_[True, rows[1:] != rows[:-1]]
        out = S[rows].copy()
        out[first & hit[rows], 1] = w[rows][first & hit[rows]]
        out[~first, 0] = w[rows][~first]
        self.segments = out
        self.loop = self.loop[rows]
        self.marks = None if self.marks is None else self.marks[rows]
        self.n_b += k

    def domain(self, domain):
        """``domain`` with the split segments (same area, holes and regions)."""
        if self.n_b == len(domain.points):
            return domain
        tails = self.segments[:, 0]
        loops = np.split(tails, np.cumsum(np.bincount(self.loop))[:-1])
        marks = None if self.marks is None else _frozen(self.marks)
        return dataclasses.replace(domain, points=_frozen(self.X[: self.n_b]),
                                   segments=_frozen(self.segments),
                                   loops=tuple(_frozen(ix) for ix in loops),
                                   segment_markers=marks)


def _frozen(array):
    out = np.ascontiguousarray(array)
    out.setflags(write=False)
    return out


def bound_areas(mesh: Mesh, max_area: float | None = None, *,
                rounds: int = MAX_ROUNDS, settle=None) -> Mesh:
    """``mesh`` with nodes added until every triangle's area is at most its
    bound (:func:`triangle_limits` from ``mesh.domain.regions`` and
    ``max_area``); ``mesh`` itself when none is exceeded.  MeshingError naming
    the region when ``rounds`` rounds do not reach the bounds.  ``settle``
    (X, T, N, segments, n_boundary, movable) -> (T, N), X in place: the
    caller's own settling passes, run once at the end (the insertions'
    re-triangulation undoes its flips) and kept only if every triangle stays
    within its bound and the smallest radius ratio does not drop."""
    regions = getattr(mesh.domain, "regions", None)
    if max_area is None and (regions is None or not (np.asarray(regions)[:, 3] > 0).any()):
        return mesh
    T = np.ascontiguousarray(mesh.triangles)
    N = _walled(T, np.asarray(mesh.neighbors), np.asarray(mesh.segments), len(mesh.points))
    limit = triangle_limits(mesh.points, T, N, regions, max_area)
    if not len(_over(mesh.points, T, limit)):
        return mesh
    nodes = _Nodes(mesh)
    for cycle in range(POLISH_CYCLES + 1):
        T, N = _insert(nodes, T, N, regions, max_area, rounds)
        if cycle == POLISH_CYCLES:
            break
        T, N = _polish(nodes, T, N)
        if not len(_over(nodes.X, T, triangle_limits(nodes.X, T, N, regions, max_area))):
            break
    if settle is not None:
        T, N = _settled(nodes, T, N, regions, max_area, settle)
    return _with_nodes(mesh, nodes, T, N)


def _settled(nodes, T, N, regions, max_area, settle):
    """(T, N) after ``settle`` (see :func:`bound_areas`) if it keeps the bounds
    and the smallest ratio, nodes.X moved with it; else as they were."""
    X = nodes.X.copy()
    movable = nodes.movable.copy()
    movable[: nodes.n_b] = False
    T2, N2 = settle(X, np.array(T), np.array(N), nodes.segments, nodes.n_b, movable)
    N2 = _walled(T2, N2, nodes.segments, len(X))
    if len(_over(X, T2, triangle_limits(X, T2, N2, regions, max_area))):
        return T, N
    if triangle_quality(X, T2).min() < triangle_quality(nodes.X, T).min():
        return T, N
    nodes.X = X
    return T2, N2


def _insert(nodes, T, N, regions, max_area, rounds):
    """Rounds of insertion (module docstring) until no triangle is over its bound."""
    for _ in range(rounds):
        limit = triangle_limits(nodes.X, T, N, regions, max_area)
        bad = _over(nodes.X, T, limit)
        if not len(bad):
            return T, N
        points, edges = _proposals(nodes.X, T, N, bad, limit, nodes.may_split)
        nodes.add(points)
        nodes.split(edges)
        T, N = _triangulate(nodes.X, nodes.segments)
    limit = triangle_limits(nodes.X, T, N, regions, max_area)
    bad = _over(nodes.X, T, limit)
    if not len(bad):
        return T, N
    raise MeshingError(_not_reached(nodes.X, T, N, regions, max_area, limit, bad, rounds))


def _triangulate(X, segments):
    try:
        return constrained_delaunay(X, segments)
    except GeometryError as error:
        raise MeshingError(f"mesh: the area bound's re-triangulation failed: {error}") from error


def _polish(nodes, T, N):
    """Quality-guarded smoothing and compass search (:mod:`bubblemesh._smoothing`,
    never lowering a star's worst radius ratio) of the interior nodes, then the
    constrained Delaunay triangulation unless it lowers the smallest ratio;
    ``nodes.X`` in place.  Returns (T, N)."""
    X, n_b, movable = nodes.X, nodes.n_b, nodes.movable
    ptr, idx = stars(T, len(X))
    taken = guarded_smooth(X, T, ptr, idx, n_b, SMOOTH_SWEEPS, movable)
    taken += compass_polish(X, T, ptr, idx, n_b, POOR, movable)
    if taken == 0:
        return T, N
    T2, N2 = _triangulate(X, nodes.segments)
    if triangle_quality(X, T2).min() >= triangle_quality(X, T).min():
        return T2, N2
    return T, _walled(T, neighbors_of(T), nodes.segments, len(X))


def _not_reached(X, T, N, regions, max_area, limit, bad, rounds) -> str:
    t = int(bad[0])
    where = "the global max_area"
    if regions is not None and len(regions):
        region = np.full(len(T), -1, np.int64)
        for r, (x, y) in enumerate(np.asarray(regions)[:, :2].tolist()):
            _flood(X, T, N, float(x), float(y), r, region)
        r = int(region[t])
        if r >= 0 and (max_area is None or limit[t] < float(max_area)):
            x, y = np.asarray(regions)[r, :2].tolist()
            where = f"region {r} (point ({x!r}, {y!r}))"
    return (f"mesh: the area bound {limit[t]!r} of {where} is not reached after {rounds} "
            f"rounds of insertion: {len(bad)} triangles are larger (triangle {t}: area "
            f"{float(_areas(X, T[t:t + 1])[0])!r})")


def _with_nodes(mesh: Mesh, nodes, T, N) -> Mesh:
    """The mesh with the added nodes (radii: half their mean edge), the split
    segments in it and its domain, and the optimisation record's ``min_ratio``."""
    from .quality import radius_ratio

    X = nodes.X
    radii = np.where(nodes.old >= 0, np.asarray(mesh.radii)[np.maximum(nodes.old, 0)],
                     _half_mean_edge(X, T))
    stats: Any = mesh.optimization
    if stats is not None and hasattr(stats, "min_ratio"):  # the robust mesher's record
        stats = dataclasses.replace(stats, min_ratio=float(radius_ratio(X, T).min()))
    domain = nodes.domain(mesh.domain) if nodes.may_split else mesh.domain
    return dataclasses.replace(mesh, points=X, triangles=T, neighbors=N, radii=radii,
                               segments=nodes.segments, n_boundary=nodes.n_b, domain=domain,
                               optimization=stats)
