"""Hard triangle-area bounds on a finished mesh (Triangle's ``-a``: a global
``max_area`` and the regions' max_area), for :func:`bubblemesh.mesh`.

The size field of ``bubblemesh.mesh`` makes triangles of about the asked
size, so some exceed an area bound by a little.  :func:`bound_areas` then
inserts nodes into the triangles that are too large, in rounds: each such
triangle proposes its circumcentre (Delaunay refinement's point, the farthest
from every node of its empty circle) if an exact walk reaches it without
crossing a segment and it neither encroaches a segment (lies in its diametral
circle) nor comes close to a node, else its centroid; of proposals landing in
the same or neighbouring triangles only the one of the triangle most over its
bound is taken.  The nodes are added and the whole mesh re-triangulated with
the constrained Delaunay triangulation; rounds repeat until no triangle
exceeds its bound (each round splits the worst triangle at least, so the
largest area shrinks), at most :data:`MAX_ROUNDS` times.

A size field that aims at ``FILL`` times the bound (``Domain.region_size``
does) leaves few triangles over it: on an 8 x 8 square with a hole and
max_area 0.01, 91 of 8388 triangles against 2566 of 6386 when aiming at the
bound itself, and the smallest radius ratio stays 0.826 instead of falling
to 0.48.

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
CLOSE = 0.5  # a circumcentre nearer a node than this times the circumradius is refused
POLISH_CYCLES, SMOOTH_SWEEPS, POOR = 3, 4, 0.85  # smoothing after the insertions
# A size field aiming at this fraction of an area bound leaves few triangles over it
FILL = 0.75


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
    """The triangle whose closure holds (px, py), walking from t across edges
    that are no segment (N >= 0); -1 if a segment is in the way."""
    for _ in range(max_steps):
        moved = False
        for j in range(3):
            a, b = T[t, (j + 1) % 3], T[t, (j + 2) % 3]
            if orient2d(X[a, 0], X[a, 1], X[b, 0], X[b, 1], px, py) < 0.0:
                if N[t, j] < 0:
                    return -1
                t = N[t, j]
                moved = True
                break
        if not moved:
            return t
    return -1


@njit(cache=True)
def _clear(X, T, N, u, px, py, radius):
    """(px, py) in triangle u is no closer than CLOSE * radius to u's nodes and
    outside the diametral circle of every segment edge of u and its neighbours."""
    for k in range(4):
        v = u if k == 3 else N[u, k]
        if v < 0:
            continue
        for j in range(3):
            a, b = T[v, (j + 1) % 3], T[v, (j + 2) % 3]
            if v == u:
                w = T[u, j]
                if (X[w, 0] - px) ** 2 + (X[w, 1] - py) ** 2 < (CLOSE * radius) ** 2:
                    return False
            if N[v, j] < 0 and ((X[a, 0] - px) * (X[b, 0] - px)
                                + (X[a, 1] - py) * (X[b, 1] - py)) <= 0.0:
                return False
    return True


@njit(cache=True)
def _proposals(X, T, N, order):
    """New nodes for the triangles in ``order`` (most over their bound first):
    circumcentre or centroid (module docstring), at most one per triangle and
    its neighbours."""
    taken = np.zeros(T.shape[0], np.bool_)
    out = np.empty((order.shape[0], 2))
    count = 0
    steps = T.shape[0] + 3
    for t in order:
        if taken[t]:
            continue
        px, py, radius = _circumcentre(X, T, t)
        u = -1
        if np.isfinite(px) and np.isfinite(py):
            u = _walk(X, T, N, t, px, py, steps)
        if u < 0 or taken[u] or not _clear(X, T, N, u, px, py, radius):
            a, b, c = T[t, 0], T[t, 1], T[t, 2]
            px = (X[a, 0] + X[b, 0] + X[c, 0]) / 3.0
            py = (X[a, 1] + X[b, 1] + X[c, 1]) / 3.0
            u = t
        for v in (t, u, N[u, 0], N[u, 1], N[u, 2], N[t, 0], N[t, 1], N[t, 2]):
            if v >= 0:
                taken[v] = True
        out[count, 0], out[count, 1] = px, py
        count += 1
    return out[:count]


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


def bound_areas(mesh: Mesh, max_area: float | None = None, *,
                rounds: int = MAX_ROUNDS) -> Mesh:
    """``mesh`` with nodes added until every triangle's area is at most its
    bound (:func:`triangle_limits` from ``mesh.domain.regions`` and
    ``max_area``); ``mesh`` itself when none is exceeded.  MeshingError naming
    the region when ``rounds`` rounds do not reach the bounds."""
    regions = getattr(mesh.domain, "regions", None)
    if max_area is None and (regions is None or not (np.asarray(regions)[:, 3] > 0).any()):
        return mesh
    X = np.ascontiguousarray(mesh.points)
    segments = np.asarray(mesh.segments)
    T = np.ascontiguousarray(mesh.triangles)
    N = _walled(T, np.asarray(mesh.neighbors), segments, len(X))
    bad = _over(X, T, triangle_limits(X, T, N, regions, max_area))
    if not len(bad):
        return mesh
    movable = np.ones(len(X), np.bool_)
    movable[np.unique(segments)] = False
    for cycle in range(POLISH_CYCLES + 1):
        X, T, N = _insert(X, T, N, segments, regions, max_area, bad, rounds)
        if cycle == POLISH_CYCLES:
            break
        movable = np.concatenate([movable, np.ones(len(X) - len(movable), np.bool_)])
        T, N = _polish(X, T, N, segments, mesh.n_boundary, movable)
        bad = _over(X, T, triangle_limits(X, T, N, regions, max_area))
        if not len(bad):
            break
    return _with_nodes(mesh, X, T, N)


def _insert(X, T, N, segments, regions, max_area, bad, rounds):
    """Rounds of insertion (module docstring) until no triangle is over its bound."""
    for _ in range(rounds):
        X = np.vstack([X, _proposals(X, T, N, bad)])
        T, N = _triangulate(X, segments)
        limit = triangle_limits(X, T, N, regions, max_area)
        bad = _over(X, T, limit)
        if not len(bad):
            return X, T, N
    raise MeshingError(_not_reached(X, T, N, regions, max_area, limit, bad, rounds))


def _triangulate(X, segments):
    try:
        return constrained_delaunay(X, segments)
    except GeometryError as error:
        raise MeshingError(f"mesh: the area bound's re-triangulation failed: {error}") from error


def _polish(X, T, N, segments, n_boundary, movable):
    """Quality-guarded smoothing and compass search (:mod:`bubblemesh._smoothing`,
    never lowering a star's worst radius ratio) of the interior nodes, then the
    constrained Delaunay triangulation unless it lowers the smallest ratio; X in
    place.  Returns (T, N)."""
    ptr, idx = stars(T, len(X))
    taken = guarded_smooth(X, T, ptr, idx, n_boundary, SMOOTH_SWEEPS, movable)
    taken += compass_polish(X, T, ptr, idx, n_boundary, POOR, movable)
    if taken == 0:
        return T, N
    T2, N2 = _triangulate(X, segments)
    if triangle_quality(X, T2).min() >= triangle_quality(X, T).min():
        return T2, N2
    return T, _walled(T, neighbors_of(T), segments, len(X))


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


def _with_nodes(mesh: Mesh, X, T, N) -> Mesh:
    """The mesh with the added nodes (radii: half their mean edge) and the
    optimisation record's ``min_ratio`` updated."""
    from .quality import radius_ratio

    n = len(mesh.points)
    radii = np.concatenate([mesh.radii, _half_mean_edge(X, T)[n:]])
    stats: Any = mesh.optimization
    if stats is not None and hasattr(stats, "min_ratio"):  # the robust mesher's record
        stats = dataclasses.replace(stats, min_ratio=float(radius_ratio(X, T).min()))
    return dataclasses.replace(mesh, points=X, triangles=T, neighbors=N, radii=radii,
                               optimization=stats)
