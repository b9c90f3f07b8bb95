"""Keeping interior nodes inside the domain during §3 (the paper does not say
how): an exact visibility walk in the fixed §2 mesh, and a cheap lower bound
on each node's distance to the boundary under which no walk is needed."""

import math

import numpy as np
from numba import njit, prange

from .predicates import orient2d


def boundary_clearance(points, segments, n_boundary, reach):
    """Half a lower bound on each node's distance to the boundary: the distance
    to the nearest segment midpoint minus half the longest segment (a point of
    segment s is within L_s / 2 of its midpoint).  0 for boundary nodes.

    Bounds above ``reach`` are not needed (a move farther than that from the
    §2 position is checked by the walk instead), so the search stops there:
    nodes with no midpoint within L / 2 + 2 reach get the bound ``reach``
    (unbounded, the deep nodes of a disk, about equally far from every
    midpoint, make the search slow).  The midpoints are binned on a grid of
    cells at least that horizon wide, so a node's 3 x 3 cells hold every
    midpoint within it."""
    points = np.asarray(points, dtype=np.float64)
    ends = points[segments]
    midpoints = np.ascontiguousarray(ends.mean(axis=1))
    longest = float(np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1).max())
    clearance = np.zeros(len(points))
    if len(points) > n_boundary:
        horizon = 0.5 * longest + 2.0 * reach
        low = midpoints.min(axis=0)
        extent = float((np.maximum(midpoints.max(axis=0), points.max(axis=0)) - low).max())
        # cells of at least the horizon, and not many more than there are points
        cell = max(horizon, extent / math.sqrt(4.0 * (len(points) + len(midpoints))))
        start, order, dims = _bins(midpoints, low, cell)
        nearest = _nearest_within(points[n_boundary:], midpoints, low, cell, dims, start, order,
                                  horizon)
        clearance[n_boundary:] = 0.5 * np.maximum(nearest - 0.5 * longest, 0.0)
    return clearance


def _bins(midpoints, low, cell):
    """The midpoints by grid cell: (start (cells + 1), order, dims), cell c
    holding order[start[c]:start[c + 1]]."""
    ij = np.floor((midpoints - low) / cell).astype(np.int64)
    dims = ij.max(axis=0) + 1
    key = ij[:, 1] * dims[0] + ij[:, 0]
    order = np.argsort(key, kind="stable")
    start = np.zeros(int(dims[0] * dims[1]) + 1, np.int64)
    np.cumsum(np.bincount(key, minlength=len(start) - 1), out=start[1:])
    return start, order, dims


@njit(cache=True, parallel=True)
def _nearest_within(points, midpoints, low, cell, dims, start, order, horizon):
    """Distance from each point to the nearest midpoint, ``horizon`` where
    none is nearer (the grid's cells are at least ``horizon`` wide)."""
    nearest = np.empty(points.shape[0])
    for p in prange(points.shape[0]):
        x, y = points[p, 0], points[p, 1]
        ci = int(math.floor((x - low[0]) / cell))
        cj = int(math.floor((y - low[1]) / cell))
        least = np.inf
        for j in range(max(cj - 1, 0), min(cj + 2, dims[1])):
            for i in range(max(ci - 1, 0), min(ci + 2, dims[0])):
                c = j * dims[0] + i
                for k in range(start[c], start[c + 1]):
                    m = order[k]
                    dx = x - midpoints[m, 0]
                    dy = y - midpoints[m, 1]
                    least = min(least, dx * dx + dy * dy)
        nearest[p] = min(math.sqrt(least), horizon)
    return nearest


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
