"""Local repair of the few triangles the default mesher's forces turn over (not
in the paper), so that the §2 connectivity can still go to Lawson's flips
(``pipeline._retriangulate_moved``) instead of a fresh constrained Delaunay
triangulation of all nodes.

The turned-over triangles and the triangles sharing a node with them make a
patch.  The patch's outline, at the moved positions, and the nodes inside it
are triangulated afresh (:func:`bubblemesh.constrained_delaunay`) and put in
the patch's slots.  Outside the patch nothing changes.  The result is used
only if it keeps every node and has the patch's triangle count, and the
caller checks that every triangle is now counter-clockwise: with the boundary
unchanged, that makes it a valid triangulation of the domain.  A patch whose
outline crosses itself, or that loses a node, grows by another ring of
triangles, up to :data:`GROWTH` times.
"""

import numpy as np

from .errors import GeometryError
from .triangulation import constrained_delaunay

GROWTH = 3  # rings of triangles around the turned-over ones tried before giving up


def untangle(X, tri, nbr, segments, turned):
    """Re-triangulate a patch around the triangles flagged in ``turned`` (a
    boolean per triangle), ``tri`` and ``nbr`` in place.  Returns True if a
    patch was replaced, False (nothing changed) if none would do."""
    region = np.asarray(turned, dtype=bool)
    for _ in range(GROWTH):
        region = _grown(tri, region, len(X))
        if _replace(X, tri, nbr, segments, region):
            return True
    return False


def _grown(tri, region, n):
    """``region`` and every triangle sharing a node with it."""
    touched = np.zeros(n, bool)
    touched[tri[region].ravel()] = True
    return touched[tri].any(axis=1)


def _outline(tri, nbr, region, rows):
    """The patch's boundary edges (a, b), the patch on their left, each with
    the triangle across it outside the patch (-1: the domain's boundary or an
    interior constraint)."""
    across = nbr[rows]
    out = (across < 0) | ~region[np.maximum(across, 0)]
    r, k = np.nonzero(out)
    t = tri[rows]
    return t[r, (k + 1) % 3], t[r, (k + 2) % 3], across[r, k]


def _constraint_inside(tri, rows, a, b, segments, n):
    """Does a segment run between two triangles of the patch (then the local
    triangulation, which knows only the outline, might not keep it)?"""
    t = tri[rows]
    edges = np.concatenate([t[:, [1, 2]], t[:, [2, 0]], t[:, [0, 1]]])
    inner = np.setdiff1d(np.minimum(*edges.T) * n + np.maximum(*edges.T),
                         np.minimum(a, b) * n + np.maximum(a, b))
    seg = np.asarray(segments, dtype=np.int64).reshape(-1, 2)
    return bool(np.isin(np.minimum(*seg.T) * n + np.maximum(*seg.T), inner).any())


def _replace(X, tri, nbr, segments, region):
    """Triangulate the patch ``region`` afresh and write it into its slots;
    False, and nothing written, if that triangulation would not do."""
    n = len(X)
    rows = np.flatnonzero(region)
    a, b, outside = _outline(tri, nbr, region, rows)
    if _constraint_inside(tri, rows, a, b, segments, n):
        return False
    nodes = np.unique(tri[rows])
    local = np.full(n, -1, np.int64)
    local[nodes] = np.arange(len(nodes))
    try:
        T, N = constrained_delaunay(X[nodes], np.stack([local[a], local[b]], axis=1))
    except GeometryError:  # the outline crosses itself at the moved positions
        return False
    if len(T) != len(rows) or len(np.unique(T)) != len(nodes):
        return False  # a node fell outside the outline
    T = nodes[T]
    N = np.where(N >= 0, rows[np.maximum(N, 0)], -1)
    edge_of = {(int(u), int(v)): int(w) for u, v, w in zip(a, b, outside)}
    links = []
    for j, k in zip(*np.nonzero(N < 0)):  # the outline: link to the old outside
        edge = (int(T[j, (k + 1) % 3]), int(T[j, (k + 2) % 3]))
        if edge not in edge_of:
            return False
        N[j, k] = edge_of[edge]
        links.append((edge_of[edge], edge, int(rows[j])))
    tri[rows] = T
    nbr[rows] = N
    for w, (u, v), t in links:
        if w >= 0:  # w's edge (v, u) now borders t
            k = [m for m in range(3) if (tri[w, (m + 1) % 3], tri[w, (m + 2) % 3]) == (v, u)][0]
            nbr[w, k] = t
    return True
