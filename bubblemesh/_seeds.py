"""Frontal seeds for ``bubblemesh.mesh`` (not in the paper).

§2 grows the mesh from centroids, so the first nodes off a wall often sit in
line with a boundary node instead of between two: the wall triangles come out
near right-angled and §3's forces, which hold such a node from both sides, do
not move it into the pocket.  A frontal mesher (Gmsh's Frontal-Delaunay)
puts the first row at the apexes of equilateral triangles on the boundary
edges.  :func:`frontal_seeds` does the same before §2: the apex of every
boundary segment, on its domain side at sqrt(3)/2 of its length, kept only
where it has room (no other node, segment midpoint or apex within ``ROOM``
times the segment length; of two seeds that crowd each other the first is
kept); at corners between 84 and 150 degrees a seed on the bisector splits
the corner in two.  Near sharper corners and in narrow gaps the seeds drop
out and §2 fills in as in the paper.  The seeds are ordinary movable nodes;
whether one is really inside the domain is decided exactly by a walk in the
constrained triangulation of the boundary (:func:`inside`).
"""

from __future__ import annotations

import numpy as np
from numba import njit
from scipy.spatial import cKDTree

from ._inside import walk_inside
from .predicates import orient2d

ROOM = 0.75
CORNER_LOW, CORNER_HIGH = np.radians(84.0), np.radians(150.0)  # two triangles beat one from 81.4

__all__ = ["frontal_seeds", "inside"]


def frontal_seeds(points: np.ndarray, segments: np.ndarray,
                  interior: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Corner seeds (:func:`corner_seeds`), then the apexes of the boundary
    segments (``interior`` False; each runs with the domain on its left) that
    have room and are clear of the corner seeds: (S, 2), and for each the row
    of the segment it stands on (for a corner, the one leaving it)."""
    P = np.asarray(points, dtype=np.float64)
    every = np.asarray(segments, dtype=np.int64)
    ids = np.nonzero(~np.asarray(interior, dtype=bool))[0]
    if len(ids) == 0:
        return np.zeros((0, 2)), np.zeros(0, np.int64)
    S = every[ids]
    a, b = P[S[:, 0]], P[S[:, 1]]
    edge = b - a
    length = np.hypot(edge[:, 0], edge[:, 1])
    apex = 0.5 * (a + b) + np.column_stack([-edge[:, 1], edge[:, 0]]) * (0.5 * np.sqrt(3.0))
    midpoints = 0.5 * (P[every[:, 0]] + P[every[:, 1]])
    room = ROOM * length
    keep = _clear_of(apex, room, P, S) & _clear_of(apex, room, midpoints, ids[:, None])
    corner, corner_rows = corner_seeds(P, S, ids, midpoints)
    if len(corner):
        keep &= _clear_of(apex, room, corner, None)
    keep[keep] = _clear_of_each_other(apex[keep], room[keep])
    return np.concatenate([corner, apex[keep]]), np.concatenate([corner_rows, ids[keep]])


def corner_seeds(P, S, ids, midpoints):
    """At a boundary corner v whose angle theta is in [CORNER_LOW,
    CORNER_HIGH), where two triangles beat one, the point on the bisector at
    the mean length of v's two segments: its two triangles are isosceles with
    apex theta / 2 (radius ratio 0.95 at 90 degrees, 1 at 120, where a single
    triangle could reach 0.83 and 0.46).  Kept with room as the apexes are
    (v's own nodes and segments excepted).  ``S`` are the boundary segments,
    ``ids`` their rows among all segments, whose ``midpoints`` are given.
    Returns the seeds and the rows of the segments leaving their corners."""
    n = len(P)
    head = np.full(n, -1, np.int64)  # the boundary segment leaving each node
    tail = np.full(n, -1, np.int64)  # the one arriving
    head[S[:, 0]] = np.arange(len(S))
    tail[S[:, 1]] = np.arange(len(S))
    simple = (np.bincount(S[:, 0], minlength=n) == 1) & (np.bincount(S[:, 1], minlength=n) == 1)
    v = np.nonzero(simple & (head >= 0) & (tail >= 0))[0]
    out, into = head[v], tail[v]
    w, u = S[out, 1], S[into, 0]
    to_w, to_u = P[w] - P[v], P[u] - P[v]
    theta = np.arctan2(to_w[:, 0] * to_u[:, 1] - to_w[:, 1] * to_u[:, 0],
                       (to_w * to_u).sum(axis=1)) % (2.0 * np.pi)
    pick = (theta >= CORNER_LOW) & (theta < CORNER_HIGH)
    if not pick.any():
        return np.zeros((0, 2)), np.zeros(0, np.int64)
    v, w, u, out, into = v[pick], w[pick], u[pick], out[pick], into[pick]
    to_w, to_u, theta = to_w[pick], to_u[pick], theta[pick]
    lw, lu = np.hypot(*to_w.T), np.hypot(*to_u.T)
    c, s = np.cos(theta / 2), np.sin(theta / 2)
    unit = to_w / lw[:, None]
    bisector = np.column_stack([c * unit[:, 0] - s * unit[:, 1], s * unit[:, 0] + c * unit[:, 1]])
    reach = 0.5 * (lw + lu)
    seeds = P[v] + bisector * reach[:, None]
    room = ROOM * reach
    keep = _clear_of(seeds, room, P, np.column_stack([v, w, u]))
    keep &= _clear_of(seeds, room, midpoints, np.column_stack([ids[out], ids[into]]))
    keep[keep] = _clear_of_each_other(seeds[keep], room[keep])
    return seeds[keep], ids[out[keep]]


def _clear_of(apex, room, targets, own):
    """No target within ``room`` of a point, except the ids in its row of
    ``own`` (None: no exceptions)."""
    if len(targets) == 0:
        return np.ones(len(apex), dtype=bool)
    tree = cKDTree(targets)
    k = min(4, len(targets))
    dist, idx = tree.query(apex, k=k, distance_upper_bound=float(room.max()))
    idx = idx.reshape(len(apex), k)
    dist = dist.reshape(len(apex), k)
    near = dist < room[:, None]
    if own is not None:
        near &= ~(idx[:, :, None] == own[:, None, :]).any(axis=2)
    clear = ~near.any(axis=1)
    # more than k targets within reach: a ball query each, with its own radius
    crowded = np.nonzero(np.isfinite(dist[:, -1]) & (dist[:, -1] < room))[0]
    if len(crowded):
        balls = tree.query_ball_point(apex[crowded], room[crowded])
        for i, found in zip(crowded.tolist(), balls):
            found = np.asarray(found, dtype=np.int64)
            if own is not None:
                found = found[~np.isin(found, own[i])]
            clear[i] = len(found) == 0
    return clear


def _clear_of_each_other(apex, room):
    """Of points closer than the smaller of their two rooms the first is kept
    (a greedy independent set in index order): a crowded corner or narrow
    end still gets one seed."""
    clear = np.ones(len(apex), dtype=bool)
    if len(apex) < 2:
        return clear
    balls = cKDTree(apex).query_ball_point(apex, room)  # each with its own radius
    sizes = np.fromiter((len(b) for b in balls), dtype=np.int64, count=len(apex))
    i = np.repeat(np.arange(len(apex)), sizes)
    j = np.fromiter((x for b in balls for x in b), dtype=np.int64, count=int(sizes.sum()))
    close = (i < j) & (np.hypot(*(apex[i] - apex[j]).T) < np.minimum(room[i], room[j]))
    i, j = i[close], j[close]
    order = np.lexsort((j, i))
    _first_of_pairs(i[order], j[order], clear)
    return clear


@njit(cache=True)
def _first_of_pairs(i, j, clear):
    """Pairs (i < j) sorted by i: j drops out when i is still in."""
    for k in range(len(i)):
        if clear[i[k]]:
            clear[j[k]] = False


def inside(points: np.ndarray, segments: np.ndarray, triangles: np.ndarray,
           neighbors: np.ndarray, seeds: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """Which seeds lie strictly inside a triangle of the domain's constrained
    triangulation (``triangles``, ``neighbors``), found by an exact visibility
    walk from the triangle on the domain side of the seed's segment (``rows``);
    a walk that meets the boundary or an interior constraint drops the seed."""
    P = np.ascontiguousarray(points, dtype=np.float64)
    tri = np.ascontiguousarray(triangles, dtype=np.int64)
    nbr = np.ascontiguousarray(neighbors, dtype=np.int64)
    n = len(P)
    edge_keys = np.concatenate([tri[:, 1] * n + tri[:, 2], tri[:, 2] * n + tri[:, 0],
                                tri[:, 0] * n + tri[:, 1]])
    order = np.argsort(edge_keys, kind="stable")
    seg = np.asarray(segments, dtype=np.int64)[rows]
    want = seg[:, 0] * n + seg[:, 1]
    at = np.minimum(np.searchsorted(edge_keys[order], want), len(order) - 1)
    found = edge_keys[order][at] == want
    start = np.where(found, order[at] % len(tri), -1)
    return _strictly_inside(P, tri, nbr, np.ascontiguousarray(seeds, dtype=np.float64), start)


@njit(cache=True)
def _strictly_inside(P, tri, nbr, seeds, start):
    keep = np.zeros(len(seeds), np.bool_)
    for i in range(len(seeds)):
        if start[i] < 0:
            continue
        x, y = seeds[i, 0], seeds[i, 1]
        t = walk_inside(P, tri, nbr, start[i], x, y, tri.shape[0])
        if t < 0:
            continue
        keep[i] = (orient2d(P[tri[t, 0], 0], P[tri[t, 0], 1], P[tri[t, 1], 0], P[tri[t, 1], 1],
                            x, y) > 0.0
                   and orient2d(P[tri[t, 1], 0], P[tri[t, 1], 1], P[tri[t, 2], 0],
                                P[tri[t, 2], 1], x, y) > 0.0
                   and orient2d(P[tri[t, 2], 0], P[tri[t, 2], 1], P[tri[t, 0], 0],
                                P[tri[t, 0], 1], x, y) > 0.0)
    return keep
