"""Frontal seeds for ``bubblemesh.mesh`` (not in the paper).

§2 grows the mesh from centroids, so the first nodes off a wall often sit in
line with a boundary node instead of between two: the wall triangles come out
near right-angled and §3's forces, which hold such a node from both sides, do
not move it into the pocket.  A frontal mesher (Gmsh's Frontal-Delaunay)
puts the first row at the apexes of equilateral triangles on the boundary
edges.  :func:`frontal_seeds` does the same before §2: the apex of every
boundary segment, on its domain side at sqrt(3)/2 of its length, kept only
where it has room (no other node, segment midpoint or apex within
``ROOM`` times the segment length): near corners and narrow gaps the seeds
drop out and §2 fills in as in the paper.  The seeds are ordinary movable
nodes; whether one is really inside the domain is decided exactly by the
constrained triangulation (:func:`inside`).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from .triangulation import constrained_delaunay

ROOM = 0.75

__all__ = ["frontal_seeds", "inside"]


def frontal_seeds(points: np.ndarray, segments: np.ndarray, interior: np.ndarray) -> np.ndarray:
    """Apexes (S, 2) of the boundary segments (``interior`` False; each runs
    with the domain on its left) that have room, in segment order."""
    P = np.asarray(points, dtype=np.float64)
    S = np.asarray(segments, dtype=np.int64)[~np.asarray(interior, dtype=bool)]
    if len(S) == 0:
        return np.zeros((0, 2))
    a, b = P[S[:, 0]], P[S[:, 1]]
    edge = b - a
    length = np.hypot(edge[:, 0], edge[:, 1])
    normal = np.column_stack([-edge[:, 1], edge[:, 0]]) * (0.5 * np.sqrt(3.0))
    apex = 0.5 * (a + b) + normal
    every = np.asarray(segments, dtype=np.int64)
    midpoints = 0.5 * (P[every[:, 0]] + P[every[:, 1]])
    room = ROOM * length
    keep = _clear_of(apex, room, P, S) & _clear_of(apex, room, midpoints, None)
    keep &= _clear_of_each_other(apex, room)
    return apex[keep]


def _clear_of(apex, room, targets, own):
    """No target within ``room`` of an apex, except its own segment's ends."""
    if len(targets) == 0:
        return np.ones(len(apex), dtype=bool)
    tree = cKDTree(targets)
    k = min(4, len(targets))
    dist, idx = tree.query(apex, k=k, distance_upper_bound=float(room.max()))
    idx = idx.reshape(len(apex), k)
    dist = dist.reshape(len(apex), k)
    near = dist < room[:, None]
    if own is not None:
        near &= (idx != own[:, :1]) & (idx != own[:, 1:])
    clear = ~near.any(axis=1)
    # more than k targets within reach: check with a full ball query
    crowded = np.nonzero(np.isfinite(dist[:, -1]) & (dist[:, -1] < room))[0]
    for i in crowded:
        ids = np.asarray(tree.query_ball_point(apex[i], room[i]), dtype=np.int64)
        if own is not None:
            ids = ids[(ids != own[i, 0]) & (ids != own[i, 1])]
        clear[i] = len(ids) == 0
    return clear


def _clear_of_each_other(apex, room):
    """Apexes closer than the smaller of their two rooms both drop out."""
    pairs = cKDTree(apex).query_pairs(float(room.max()), output_type="ndarray")
    clear = np.ones(len(apex), dtype=bool)
    if len(pairs):
        i, j = pairs[:, 0], pairs[:, 1]
        close = np.hypot(*(apex[i] - apex[j]).T) < np.minimum(room[i], room[j])
        clear[i[close]] = False
        clear[j[close]] = False
    return clear


def inside(points: np.ndarray, segments: np.ndarray, seeds: np.ndarray) -> np.ndarray:
    """Exactly which seeds are nodes of the constrained triangulation of the
    domain with them (a seed outside the domain is in no kept triangle)."""
    allp = np.concatenate([points, seeds])
    tri, _ = constrained_delaunay(allp, segments)
    used = np.zeros(len(allp), dtype=bool)
    used[np.asarray(tri).ravel()] = True
    return used[len(points):]
