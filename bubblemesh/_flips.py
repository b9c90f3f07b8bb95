"""Valence- and quality-driven edge flips for ``bubblemesh.mesh`` (not in the paper),
and Lawson's Delaunay flips (:func:`delaunay_flips`), which turn a valid
conforming triangulation of moved nodes back into their constrained Delaunay
triangulation (§3.5) without building it anew.

An interior edge ab shared by t = (a, b, c) and u = (b, a, d) becomes cd when
the quadrilateral acbd is strictly convex (exact :func:`orient2d`), ab is not a
segment, and either

- the flip lowers sum_v (n_v - ideal_v)^2, with n_v the triangles at node v and
  ideal_v its angle sum over pi / 3 (6 inside, 3 on a straight boundary), and
  does not lower the smaller radius ratio (eq. 10) of the two triangles; or
- it keeps that sum and raises the smaller radius ratio of the two.

So a flip never inverts a triangle, never crosses or removes a segment and
never lowers the mesh's minimum radius ratio; the result is a valid
conforming triangulation that need not be constrained-Delaunay.  Edges are
visited in triangle order, passes repeat until none flips (at most
``max_passes``): deterministic.
"""

import math

import numpy as np
from numba import njit, prange

from ._smoothing import rho
from .predicates import incircle, orient2d

GAIN = 1e-9  # a quality flip must raise the pair's worst ratio by more than this


@njit(cache=True, parallel=True)
def _corner_angles(X, triangles):
    """The angle of every triangle at each of its corners (the triangles in
    parallel: atan2 is the cost)."""
    angles = np.empty((triangles.shape[0], 3))
    for t in prange(triangles.shape[0]):
        for k in range(3):
            i = triangles[t, k]
            j = triangles[t, (k + 1) % 3]
            m = triangles[t, (k + 2) % 3]
            ux, uy = X[j, 0] - X[i, 0], X[j, 1] - X[i, 1]
            vx, vy = X[m, 0] - X[i, 0], X[m, 1] - X[i, 1]
            angles[t, k] = math.atan2(abs(ux * vy - uy * vx), ux * vx + uy * vy)
    return angles


@njit(cache=True)
def ideal_counts(X, triangles, n):
    """Ideal triangle count at every node: its angle sum / (pi / 3), rounded,
    >= 1.  The sums run in triangle order (rounding decides ties of the
    count)."""
    angles = _corner_angles(X, triangles)
    total = np.zeros(n)
    for t in range(triangles.shape[0]):
        for k in range(3):
            total[triangles[t, k]] += angles[t, k]
    ideal = np.empty(n, np.int64)
    for i in range(n):
        ideal[i] = max(1, int(round(total[i] / (math.pi / 3))))
    return ideal


@njit(cache=True)
def _is_segment(keys, n, a, b):
    lo, hi = min(a, b), max(a, b)
    key = lo * n + hi
    s = np.searchsorted(keys, key)
    return s < keys.shape[0] and keys[s] == key


@njit(cache=True)
def segment_keys(segments, n):
    """Sorted keys min * n + max of the undirected segments."""
    keys = np.empty(segments.shape[0], np.int64)
    for s in range(segments.shape[0]):
        a, b = segments[s, 0], segments[s, 1]
        keys[s] = min(a, b) * n + max(a, b)
    return np.sort(keys)


@njit(cache=True, inline="always")
def across(tri, t, k, u):
    """(slot m, node d) of u = nbr[t, k], the triangle across the edge of t
    opposite its k-th node: d is u's node off that edge."""
    a = tri[t, (k + 1) % 3]
    b = tri[t, (k + 2) % 3]
    m = 0
    while m < 2 and (tri[u, m] == a or tri[u, m] == b):
        m += 1
    return m, tri[u, m]


@njit(cache=True)
def _relink(nbr, t, old, new):
    """In triangle t (if any), the neighbour ``old`` becomes ``new``."""
    if t < 0:
        return
    for k in range(3):
        if nbr[t, k] == old:
            nbr[t, k] = new
            return


@njit(cache=True)
def _flip(tri, nbr, t, k, u, m):
    """Replace t = (a, b, c) (c = tri[t, k]) and u = (b, a, d) (d = tri[u, m])
    by t = (c, a, d) and u = (d, b, c), neighbours kept consistent."""
    c = tri[t, k]
    a = tri[t, (k + 1) % 3]
    b = tri[t, (k + 2) % 3]
    d = tri[u, m]
    n_bc = nbr[t, (k + 1) % 3]  # opposite a in t: edge bc
    n_ca = nbr[t, (k + 2) % 3]  # opposite b in t: edge ca
    ma = (m + 1) % 3 if tri[u, (m + 1) % 3] == a else (m + 2) % 3
    mb = (m + 1) % 3 if ma == (m + 2) % 3 else (m + 2) % 3
    n_db = nbr[u, ma]  # opposite a in u: edge db
    n_ad = nbr[u, mb]  # opposite b in u: edge ad
    tri[t, 0], tri[t, 1], tri[t, 2] = c, a, d
    nbr[t, 0], nbr[t, 1], nbr[t, 2] = n_ad, u, n_ca
    tri[u, 0], tri[u, 1], tri[u, 2] = d, b, c
    nbr[u, 0], nbr[u, 1], nbr[u, 2] = n_bc, t, n_db
    _relink(nbr, n_bc, t, u)  # bc moved from t to u, ad from u to t
    _relink(nbr, n_ad, u, t)


@njit(cache=True)
def _deviation(count, ideal, v, delta):
    e = count[v] + delta - ideal[v]
    return e * e


@njit(cache=True)
def improve_flips(X, tri, nbr, keys, ideal, max_passes, relax):
    """Flip edges by the module docstring's rules until none flips (at most
    ``max_passes`` passes); ``tri`` and ``nbr`` in place.  With ``relax`` at
    least the mesh's minimum radius ratio, that minimum is never lowered.
    Returns the number of flips."""
    n = X.shape[0]
    count = np.zeros(n, np.int64)
    for t in range(tri.shape[0]):
        for k in range(3):
            count[tri[t, k]] += 1
    flips = 0
    for _ in range(max_passes):
        flipped = 0
        for t in range(tri.shape[0]):
            for k in range(3):
                u = nbr[t, k]
                if u < 0:
                    continue
                c = tri[t, k]
                a = tri[t, (k + 1) % 3]
                b = tri[t, (k + 2) % 3]
                m, d = across(tri, t, k, u)
                if _is_segment(keys, n, a, b):
                    continue
                if orient2d(X[c, 0], X[c, 1], X[a, 0], X[a, 1], X[d, 0], X[d, 1]) <= 0.0:
                    continue
                if orient2d(X[d, 0], X[d, 1], X[b, 0], X[b, 1], X[c, 0], X[c, 1]) <= 0.0:
                    continue
                old = (_deviation(count, ideal, a, 0) + _deviation(count, ideal, b, 0)
                       + _deviation(count, ideal, c, 0) + _deviation(count, ideal, d, 0))
                new = (_deviation(count, ideal, a, -1) + _deviation(count, ideal, b, -1)
                       + _deviation(count, ideal, c, 1) + _deviation(count, ideal, d, 1))
                if new > old:
                    continue
                q_old = min(rho(X[a, 0], X[a, 1], X[b, 0], X[b, 1], X[c, 0], X[c, 1]),
                            rho(X[b, 0], X[b, 1], X[a, 0], X[a, 1], X[d, 0], X[d, 1]))
                q_new = min(rho(X[c, 0], X[c, 1], X[a, 0], X[a, 1], X[d, 0], X[d, 1]),
                            rho(X[d, 0], X[d, 1], X[b, 0], X[b, 1], X[c, 0], X[c, 1]))
                if not ((new < old and q_new >= min(q_old, relax)) or q_new > q_old + GAIN):
                    continue
                _flip(tri, nbr, t, k, u, m)
                count[a] -= 1
                count[b] -= 1
                count[c] += 1
                count[d] += 1
                flipped += 1
                break  # t changed: its other edges wait for the next pass
        flips += flipped
        if flipped == 0:
            break
    return flips


@njit(cache=True, parallel=True)
def turned_over(X, tri):
    """Per triangle: is it not strictly counter-clockwise at X (exact
    :func:`orient2d`)?  In parallel.  None means nodes that moved without
    crossing the boundary still form a valid triangulation with these
    triangles, from which :func:`delaunay_flips` reaches the constrained
    Delaunay one."""
    turned = np.zeros(tri.shape[0], np.bool_)
    for t in prange(tri.shape[0]):
        a, b, c = tri[t, 0], tri[t, 1], tri[t, 2]
        turned[t] = orient2d(X[a, 0], X[a, 1], X[b, 0], X[b, 1], X[c, 0], X[c, 1]) <= 0.0
    return turned


@njit(cache=True, parallel=True)
def non_delaunay_mask(X, tri, nbr, keys):
    """Per half-edge (t, k) (row-major, 3 t + k): is it an interior
    non-segment edge that :func:`delaunay_flips` would find non-Delaunay in
    its first look?  Each edge is marked once, from its lower-numbered
    triangle (the exact :func:`incircle` of (c, a, b, d) and of (d, b, a, c)
    is the same determinant); the triangles run in parallel: after small
    moves most triangulations are still Delaunay, and this settles it without
    the serial queue."""
    n = X.shape[0]
    mask = np.zeros((tri.shape[0], 3), np.bool_)
    for t in prange(tri.shape[0]):
        for k in range(3):
            u = nbr[t, k]
            if u > t:
                c = tri[t, k]
                a = tri[t, (k + 1) % 3]
                b = tri[t, (k + 2) % 3]
                _, d = across(tri, t, k, u)
                mask[t, k] = incircle(X[c, 0], X[c, 1], X[a, 0], X[a, 1], X[b, 0], X[b, 1],
                                      X[d, 0], X[d, 1]) > 0.0 and not _is_segment(keys, n, a, b)
    return mask


@njit(cache=True)
def delaunay_flips(X, tri, nbr, keys, max_flips):
    """Lawson's flips: while an interior non-segment edge ab of t = (c, a, b)
    and u = (b, a, d) has d strictly inside the circle through c, a, b (exact
    :func:`incircle`), flip it to cd; ``tri`` and ``nbr`` in place.  From a
    valid triangulation this ends at the constrained Delaunay triangulation
    (any one of them when four nodes are cocircular).  Every half-edge is
    looked at, in order (:func:`lawson_flips`).  Returns the number of flips,
    -1 if ``max_flips`` was reached first."""
    return lawson_flips(X, tri, nbr, keys, max_flips, np.arange(3 * tri.shape[0]))


@njit(cache=True)
def lawson_flips(X, tri, nbr, keys, max_flips, first):
    """:func:`delaunay_flips` looking first at the half-edges ``first`` (3 t +
    k, in that order), then at the outer edges of each flip: enough when every
    edge not in ``first`` is a segment or locally Delaunay
    (:func:`non_delaunay_mask`).  Each edge waits in a ring queue at most once
    at a time."""
    n = X.shape[0]
    m_tri = tri.shape[0]
    size = 3 * m_tri
    queued = np.zeros(size, np.bool_)
    queue = np.empty(size, np.int64)
    waiting = 0
    for f in first:
        if not queued[f]:
            queued[f] = True
            queue[waiting] = f
            waiting += 1
    head = 0
    flips = 0
    while waiting > 0:
        e = queue[head]
        head = head + 1 if head + 1 < size else 0
        waiting -= 1
        queued[e] = False
        t, k = e // 3, e % 3
        u = nbr[t, k]
        if u < 0:
            continue
        c = tri[t, k]
        a = tri[t, (k + 1) % 3]
        b = tri[t, (k + 2) % 3]
        m, d = across(tri, t, k, u)
        if incircle(X[c, 0], X[c, 1], X[a, 0], X[a, 1], X[b, 0], X[b, 1],
                    X[d, 0], X[d, 1]) <= 0.0 or _is_segment(keys, n, a, b):
            continue
        if flips == max_flips:
            return -1
        _flip(tri, nbr, t, k, u, m)  # t = (c, a, d), u = (d, b, c)
        flips += 1
        for f in (3 * t, 3 * t + 2, 3 * u, 3 * u + 2):  # the four outer edges
            if not queued[f]:
                queued[f] = True
                queue[(head + waiting) % size] = f
                waiting += 1
    return flips
