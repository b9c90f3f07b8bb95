"""Spatial renumbering of the §2 mesh (not in the paper; the result is the
same mesh): interior nodes along a Hilbert curve, triangles by their lowest
new node, so that every later pass over the mesh reads memory in order."""

import numpy as np
from numba import njit, prange

from ._ordering import hilbert_order
from .memory import prefetch


@njit(cache=True, parallel=True)
def _by_lowest_node(triangles, new_of_old):
    """Triangle order by their lowest renumbered node, ties in id order (a
    counting sort): triangles then follow the nodes' Hilbert order."""
    m = triangles.shape[0]
    lowest = np.empty(m, np.int64)
    first = np.zeros(new_of_old.shape[0] + 1, np.int64)
    for t in prange(m):
        if t + 16 < m:  # the random reads of a later iteration start now
            for j in range(3):
                prefetch(new_of_old, triangles[t + 16, j])
        lowest[t] = min(new_of_old[triangles[t, 0]], new_of_old[triangles[t, 1]],
                        new_of_old[triangles[t, 2]])
    for t in range(m):
        first[lowest[t] + 1] += 1
    for v in range(new_of_old.shape[0]):
        first[v + 1] += first[v]
    order = np.empty(m, np.int64)
    for t in range(m):
        order[first[lowest[t]]] = t
        first[lowest[t]] += 1
    return order


@njit(cache=True, parallel=True)
def _permute_mesh(triangles, neighbors, new_of_old, tri_order, tri_new_of_old):
    """Triangle rows in ``tri_order``, node ids and neighbour ids renamed.
    One parallel loop: numba 0.57 fused a second one (the inverse of
    ``tri_order``) with it and read the inverse before it was written."""
    m = tri_order.shape[0]
    tri = np.empty((m, 3), np.int64)
    nbr = np.empty((m, 3), np.int64)
    first_col = triangles[:, 0]
    for k in prange(m):
        # random reads, started ahead: the record 32 iterations on, then
        # (its record loaded by now) what the one 16 on will look up
        if k + 32 < m:
            prefetch(first_col, tri_order[k + 32])
        if k + 16 < m:
            ahead = tri_order[k + 16]
            for j in range(3):
                prefetch(new_of_old, triangles[ahead, j])
                n = neighbors[ahead, j]
                if n >= 0:
                    prefetch(tri_new_of_old, n)
        t = tri_order[k]
        for j in range(3):
            tri[k, j] = new_of_old[triangles[t, j]]
            n = neighbors[t, j]
            nbr[k, j] = tri_new_of_old[n] if n >= 0 else -1
    return tri, nbr


@njit(cache=True, parallel=True)
def _gather_nodes(P, R, old_of_new):
    """Node positions and radii in the new order (random reads: in parallel)."""
    n = old_of_new.shape[0]
    points = np.empty((n, 2))
    radii = np.empty(n)
    for k in prange(n):
        o = old_of_new[k]
        points[k, 0] = P[o, 0]
        points[k, 1] = P[o, 1]
        radii[k] = R[o]
    return points, radii


def spatial_renumbering(points: np.ndarray, radii: np.ndarray, triangles: np.ndarray,
                        neighbors: np.ndarray, n_fixed: int
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Renumber nodes after ``n_fixed`` along a Hilbert curve, and triangles by
    their lowest new node.

    §2 creates nodes in density order, scattered over the domain; neighbours
    that are far apart in memory make every later pass over the mesh (the §3
    iterations above all) wait on cache misses.  Returns the permuted
    (points, radii, triangles, neighbors)."""
    n = len(points)
    old_of_new = np.arange(n)
    old_of_new[n_fixed:] = n_fixed + hilbert_order(points[n_fixed:])
    new_of_old = np.empty(n, np.int64)
    new_of_old[old_of_new] = np.arange(n)
    tri_order = _by_lowest_node(triangles, new_of_old)
    tri_new_of_old = np.empty(len(tri_order), np.int64)
    tri_new_of_old[tri_order] = np.arange(len(tri_order))
    tri, nbr = _permute_mesh(triangles, neighbors, new_of_old, tri_order, tri_new_of_old)
    points, radii = _gather_nodes(points, radii, old_of_new)
    return points, radii, tri, nbr
