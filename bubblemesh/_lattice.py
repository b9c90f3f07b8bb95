"""A close-packed start for the bulk of a uniform field (``bubblemesh.mesh``,
not the paper).

Bubble packing (the paper's refs. [4]-[7]) relaxes bubbles toward a
hexagonal close packing; where the size field is a constant h, that packing
is known in advance: the nodes of the triangular lattice of spacing h.
:func:`lattice_points` lays it over the domain and keeps the nodes that are
at least ``margin`` h from every boundary node and where the field is its
cap; the frontal insertion of §2 then fills only the band between the walls
and the lattice, whose triangles it accepts as they are.  The lattice may
be laid in a frame, through a boundary node along a wall and as fine as that
wall's pieces: walls that lie on one lattice (a regular hexagon) then meet it
without a seam.  A wall made of the lattice's own edges is its first row, so
the lattice may come up to it (``on_lattice_margin``, half a size in
``bubblemesh.mesh``) instead of leaving the margin's band to the front.

Inside or outside is decided per lattice row by the parity of the boundary
segments the row's line crosses (half-open in y, so a line through a node
counts it once); a kept node lies at least (margin - 1/2) h from every
segment, or a row's height from a lattice-edge wall, far beyond any
rounding, so the float test decides exactly.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree

__all__ = ["lattice_points"]

JITTER = 1e-9


def lattice_points(points: np.ndarray, segments: np.ndarray, h: float, margin: float,
                   size, frame=None, on_lattice_margin=None) -> np.ndarray:
    """The triangular lattice of spacing ``h`` (rows along x, anchored at the
    lower left of the boundary's bounding box) inside the domain bounded by
    ``segments`` over ``points``, at least ``margin`` h from every boundary
    node, where ``size`` (a callable h(xy)) is h: (K, 2), row by row.
    ``frame`` (origin, unit direction, spacing[, row height]): the lattice
    of that spacing through the origin, its rows along the direction (rows
    of that height, a stretched lattice, where given), instead.  With
    ``on_lattice_margin``, a boundary node all of whose segments are edges
    of the lattice (:func:`_on_lattice_nodes`) keeps only that many h off
    instead: such a wall is the lattice's own first row."""
    P = np.asarray(points, dtype=np.float64)
    S = np.asarray(segments, dtype=np.int64)
    if frame is None:
        Q, step, axes, anchor = P, h, None, P.min(axis=0)
        dy = 0.5 * math.sqrt(3.0) * step
    else:
        origin, u, step = frame[:3]
        dy = frame[3] if len(frame) > 3 else 0.5 * math.sqrt(3.0) * step
        axes = np.array([[u[0], -u[1]], [u[1], u[0]]])  # columns: u and u turned left
        Q, anchor = _times(P - origin, axes), np.zeros(2)  # the frame's coordinates
    lo, hi = Q.min(axis=0), Q.max(axis=0)
    rows = np.arange(math.ceil((lo[1] - anchor[1]) / dy), math.floor((hi[1] - anchor[1]) / dy) + 1)
    a, b = Q[S[:, 0]], Q[S[:, 1]]
    found = []
    for j in rows:
        y = anchor[1] + j * dy
        xs = _crossings(a, b, y)
        if len(xs) < 2:
            continue
        first = anchor[0] + (0.5 * step if j % 2 else 0.0)
        for x0, x1 in zip(xs[0::2], xs[1::2]):  # inside between pairs of crossings
            i0 = math.ceil((x0 - first) / step)
            i1 = math.floor((x1 - first) / step)
            if i1 >= i0:
                x = first + step * np.arange(i0, i1 + 1)
                row = np.column_stack([x, np.full(len(x), y)])
                found.append(row if axes is None else origin + _times(row, axes.T))
    if not found:
        return np.zeros((0, 2))
    L = np.concatenate(found)
    # a lattice is full of exactly collinear and cocircular nodes, on which every
    # orientation and in-circle test of the triangulation falls back to exact
    # arithmetic (3-4x slower): a fixed offset of 1e-9 h per node breaks the ties
    L += h * JITTER * _offsets(len(L))
    walls = np.zeros(len(P), bool)
    if on_lattice_margin is not None:
        walls = _on_lattice_nodes(Q, S, anchor, step, dy)
        near = on_lattice_margin * h
        if walls.any():
            L = L[cKDTree(P[walls]).query(L, k=1, distance_upper_bound=near)[0] >= near]
    # bounded: a node far from every boundary node (the bulk) answers at once
    if not walls.all():
        far = cKDTree(P[~walls]).query(L, k=1, distance_upper_bound=margin * h)[0]
        L = L[far >= margin * h]
    if len(L):
        L = L[np.asarray(size(L)) >= h * (1.0 - 1e-12)]
    return np.ascontiguousarray(L)


def _on_lattice_nodes(Q: np.ndarray, S: np.ndarray, anchor: np.ndarray,
                      step: float, dy: float) -> np.ndarray:
    """Which boundary nodes (frame coordinates Q) have only lattice edges as
    segments: both ends on a lattice node (rows ``dy`` apart) and one step
    apart, to 1e-6 of a step.  A lattice node then lies at least a row's
    height from each such segment, or on its end."""
    j = np.round((Q[:, 1] - anchor[1]) / dy)
    first = anchor[0] + 0.5 * step * (j % 2)
    i = np.round((Q[:, 0] - first) / step)
    tol = 1e-6 * step
    on = ((np.abs(Q[:, 1] - anchor[1] - j * dy) <= tol)
          & (np.abs(Q[:, 0] - first - i * step) <= tol))
    d = Q[S[:, 1]] - Q[S[:, 0]]
    edge = on[S[:, 0]] & on[S[:, 1]] & (np.abs(np.hypot(d[:, 0], d[:, 1]) - step) <= tol)
    bad = np.zeros(len(Q), bool)
    bad[S[~edge].ravel()] = True
    walls = np.zeros(len(Q), bool)
    walls[S.ravel()] = True
    return walls & ~bad


def _times(V: np.ndarray, M: np.ndarray) -> np.ndarray:
    """V (k, 2) times the 2 x 2 matrix M, written out: numpy's ``@`` goes to
    BLAS, whose bits change with its thread count."""
    return np.column_stack([V[:, 0] * M[0, 0] + V[:, 1] * M[1, 0],
                            V[:, 0] * M[0, 1] + V[:, 1] * M[1, 1]])


def _offsets(n: int) -> np.ndarray:
    """n fixed pseudo-random offsets in [-1, 1)^2 (a seeded generator: the same
    on every run and platform)."""
    return np.random.default_rng(20261202).uniform(-1.0, 1.0, (n, 2))


def _crossings(a: np.ndarray, b: np.ndarray, y: float) -> np.ndarray:
    """Sorted x where the line at height y crosses the segments ab, each
    segment half-open in y (its lower end counts, its upper end not)."""
    ya, yb = a[:, 1], b[:, 1]
    low, high = np.minimum(ya, yb), np.maximum(ya, yb)
    hit = (low <= y) & (y < high)
    if not hit.any():
        return np.zeros(0)
    a, b = a[hit], b[hit]
    t = (y - a[:, 1]) / (b[:, 1] - a[:, 1])
    return np.sort(a[:, 0] + t * (b[:, 0] - a[:, 0]))
