"""Keeping interior nodes inside the domain during §3 (the paper does not say
how): an exact visibility walk in the fixed §2 mesh, and a cheap lower bound
on each node's distance to the boundary under which no walk is needed."""

import numpy as np
from numba import njit

from .predicates import orient2d


def boundary_clearance(points, segments, n_boundary, reach):
    """Half a lower bound on each node's distance to the boundary: the distance
    to the nearest segment midpoint minus half the longest segment (a point of
    segment s is within L_s / 2 of its midpoint).  0 for boundary nodes.

    Bounds above ``reach`` are not needed (a move farther than that from the
    §2 position is checked by the walk instead), so the search stops there:
    nodes with no midpoint within L / 2 + 2 reach get the bound ``reach``
    (unbounded, the deep nodes of a disk, about equally far from every
    midpoint, make the search slow)."""
    from scipy.spatial import cKDTree

    ends = points[segments]
    midpoints = ends.mean(axis=1)
    longest = float(np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1).max())
    clearance = np.zeros(len(points))
    if len(points) > n_boundary:
        horizon = 0.5 * longest + 2.0 * reach
        nearest, _ = cKDTree(midpoints).query(points[n_boundary:], workers=-1,
                                              distance_upper_bound=horizon)
        nearest = np.minimum(nearest, horizon)  # inf: no midpoint within the horizon
        clearance[n_boundary:] = 0.5 * np.maximum(nearest - 0.5 * longest, 0.0)
    return clearance


@njit(cache=True)
def walk_inside(P0, tri0, nbr0, start, px, py, max_steps):
    """Triangle of the §2 mesh whose closure holds (px, py) without lying on the
    domain boundary, reached by a visibility walk from ``start``; -1 if the walk
    would cross or touch the boundary (or exceeds its bound)."""
    t = start
    for _ in range(max_steps):
        moved = False
        for j in range(3):
            u = tri0[t, (j + 1) % 3]
            v = tri0[t, (j + 2) % 3]
            if orient2d(P0[u, 0], P0[u, 1], P0[v, 0], P0[v, 1], px, py) < 0.0:
                t = nbr0[t, j]
                moved = True
                break
        if t < 0:
            return -1
        if not moved:
            for j in range(3):
                if nbr0[t, j] < 0:
                    u = tri0[t, (j + 1) % 3]
                    v = tri0[t, (j + 2) % 3]
                    if orient2d(P0[u, 0], P0[u, 1], P0[v, 0], P0[v, 1], px, py) == 0.0:
                        return -1
            return t
    return -1
