"""Corner splits for ``bubblemesh.mesh`` (not in the paper).

A boundary node v whose angle asks for more triangles than it has (its
angle sum over pi / 3, rounded: a 90 degree corner wants 2, a straight wall
3) keeps a triangle t = (v, a, b) with a wide angle at v; the best such a
triangle can do is poor (a right isosceles one has a radius ratio of 0.83,
one with a 120 degree apex 0.54).  The split flips ab to vd, d the node
across ab, and moves d toward the point on the bisector of a v b at the mean
distance of a and b from v, the first of the steps 1, 3/4, 1/2, 1/4, 0 of
the way that keeps every triangle at d strictly counter-clockwise (exact
:func:`orient2d`) and maximises the smallest radius ratio (eq. 10) of the
triangles that change.  It is taken only if that smallest ratio beats the
one before (t, and d's triangles), so the mesh's minimum never drops.  The
result is valid and conforming (ab is never a segment) but in general no
longer constrained-Delaunay.  Nodes are visited in index order and a pass
skips nodes next to a change (their stars are stale until the next pass):
deterministic.
"""

import math

import numpy as np
from numba import njit

from ._flips import _flip, _is_segment, across
from ._smoothing import rho, stars
from .predicates import orient2d

GAIN = 1e-6  # a split must raise the local smallest radius ratio by more than this
STEPS = (1.0, 0.75, 0.5, 0.25, 0.0)
PASSES = 3


@njit(cache=True)
def _angle(X, v, a, b):
    ux, uy = X[a, 0] - X[v, 0], X[a, 1] - X[v, 1]
    wx, wy = X[b, 0] - X[v, 0], X[b, 1] - X[v, 1]
    return math.atan2(abs(ux * wy - uy * wx), ux * wx + uy * wy)


@njit(cache=True)
def _widest(X, tri, ptr, idx, v):
    """(triangle, slot of v) of v's triangle with the widest angle at v."""
    best, slot, widest = -1, -1, -1.0
    for e in range(ptr[v], ptr[v + 1]):
        t = idx[e]
        k = 0 if tri[t, 0] == v else (1 if tri[t, 1] == v else 2)
        angle = _angle(X, v, tri[t, (k + 1) % 3], tri[t, (k + 2) % 3])
        if angle > widest:
            best, slot, widest = t, k, angle
    return best, slot


@njit(cache=True)
def _split_star(X, tri, ptr, idx, d, u, v, a, b, px, py):
    """Smallest ratio of d's triangles after the flip with d at (px, py): its
    star without u = (b, a, d), plus (v, a, d) and (d, b, v); -1 if one is
    not strictly counter-clockwise."""
    worst = 1.0
    for e in range(ptr[d], ptr[d + 1]):
        s = idx[e]
        if s == u:
            continue
        k = 0 if tri[s, 0] == d else (1 if tri[s, 1] == d else 2)
        p = tri[s, (k + 1) % 3]
        q = tri[s, (k + 2) % 3]
        if orient2d(px, py, X[p, 0], X[p, 1], X[q, 0], X[q, 1]) <= 0.0:
            return -1.0
        worst = min(worst, rho(px, py, X[p, 0], X[p, 1], X[q, 0], X[q, 1]))
    for p, q in ((v, a), (b, v)):
        if orient2d(px, py, X[p, 0], X[p, 1], X[q, 0], X[q, 1]) <= 0.0:
            return -1.0
        worst = min(worst, rho(px, py, X[p, 0], X[p, 1], X[q, 0], X[q, 1]))
    return worst


@njit(cache=True)
def _split_pair(X, v, a, b, d):
    """Smaller ratio of (v, a, d) and (d, b, v); -1 if one is not strictly
    counter-clockwise."""
    if orient2d(X[v, 0], X[v, 1], X[a, 0], X[a, 1], X[d, 0], X[d, 1]) <= 0.0:
        return -1.0
    if orient2d(X[d, 0], X[d, 1], X[b, 0], X[b, 1], X[v, 0], X[v, 1]) <= 0.0:
        return -1.0
    return min(rho(X[v, 0], X[v, 1], X[a, 0], X[a, 1], X[d, 0], X[d, 1]),
               rho(X[d, 0], X[d, 1], X[b, 0], X[b, 1], X[v, 0], X[v, 1]))


@njit(cache=True)
def _try_split(X, tri, nbr, keys, ptr, idx, movable, t, k):
    """Split at v = tri[t, k] as in the module docstring; True if taken."""
    n = X.shape[0]
    v = tri[t, k]
    a = tri[t, (k + 1) % 3]
    b = tri[t, (k + 2) % 3]
    u = nbr[t, k]
    if u < 0 or _is_segment(keys, n, a, b):
        return False
    m, d = across(tri, t, k, u)
    old_t = rho(X[v, 0], X[v, 1], X[a, 0], X[a, 1], X[b, 0], X[b, 1])
    old_star = 1.0  # d's triangles, u among them: they all change if d moves
    for e in range(ptr[d], ptr[d + 1]):
        w = idx[e]
        old_star = min(old_star, rho(X[tri[w, 0], 0], X[tri[w, 0], 1], X[tri[w, 1], 0],
                                     X[tri[w, 1], 1], X[tri[w, 2], 0], X[tri[w, 2], 1]))
    old_u = rho(X[b, 0], X[b, 1], X[a, 0], X[a, 1], X[d, 0], X[d, 1])
    la = math.hypot(X[a, 0] - X[v, 0], X[a, 1] - X[v, 1])
    lb = math.hypot(X[b, 0] - X[v, 0], X[b, 1] - X[v, 1])
    bx = (X[a, 0] - X[v, 0]) / la + (X[b, 0] - X[v, 0]) / lb
    by = (X[a, 1] - X[v, 1]) / la + (X[b, 1] - X[v, 1]) / lb
    norm = math.hypot(bx, by)
    if norm == 0.0:
        return False
    reach = 0.5 * (la + lb) / norm
    tx, ty = X[v, 0] + bx * reach, X[v, 1] + by * reach
    best, gain, bestx, besty = -1.0, GAIN, X[d, 0], X[d, 1]
    for s in STEPS:
        if s > 0.0 and not movable[d]:
            continue
        px = X[d, 0] + s * (tx - X[d, 0])
        py = X[d, 1] + s * (ty - X[d, 1])
        if s > 0.0:  # every triangle at d changes
            q = _split_star(X, tri, ptr, idx, d, u, v, a, b, px, py)
            before = min(old_t, old_star)
        else:  # only t and u change
            q = _split_pair(X, v, a, b, d)
            before = min(old_t, old_u)
        if q - before > gain and q > best:
            best, bestx, besty = q, px, py
    if best < 0.0:
        return False
    _flip(tri, nbr, t, k, u, m)
    X[d, 0] = bestx
    X[d, 1] = besty
    return True


@njit(cache=True)
def split_corners(X, tri, nbr, keys, ideal, fixed, movable):
    """Corner splits (module docstring) at the nodes flagged ``fixed`` whose
    triangle count is below ``ideal``; ``X``, ``tri``, ``nbr`` in place.
    Returns the number of splits."""
    n = X.shape[0]
    splits = 0
    for _ in range(PASSES):
        ptr, idx = stars(tri, n)
        stale = np.zeros(n, np.bool_)
        taken = 0
        for v in range(n):
            if not fixed[v] or stale[v] or ptr[v + 1] - ptr[v] >= ideal[v]:
                continue
            t, k = _widest(X, tri, ptr, idx, v)
            u = nbr[t, k]
            if u < 0:
                continue
            a = tri[t, (k + 1) % 3]
            b = tri[t, (k + 2) % 3]
            _, d = across(tri, t, k, u)
            if stale[a] or stale[b] or stale[d]:
                continue
            if _try_split(X, tri, nbr, keys, ptr, idx, movable, t, k):
                taken += 1
                for w in (v, a, b, d):
                    stale[w] = True
                for e in range(ptr[d], ptr[d + 1]):  # d moved: its neighbours' stars changed
                    for j in range(3):
                        stale[tri[idx[e], j]] = True
        splits += taken
        if taken == 0:
            break
    return splits
