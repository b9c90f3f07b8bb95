"""Edge flips judged after relaxing, for ``bubblemesh.mesh`` (not in the paper;
the topological optimisation the paper's §3 leaves to its references).

A 5-7 pair of valences (a dislocation) moves by one edge flip, and the
flip alone makes two poor triangles: only once the nodes around it settle
does it show whether the mesh gained.  So every interior edge ab (not a
segment, its quadrilateral acbd strictly convex by the exact
:func:`orient2d`, one of a, b, c, d off its ideal count, see
:func:`bubblemesh._flips.ideal_counts`, and the flip not raising the sum of
(count - ideal)^2) is flipped to cd, the movable nodes
of the stars of a, b, c and d are relaxed by ``sweeps`` sweeps of
:func:`bubblemesh._odt.polish_gathered` (gradient steps on each star's mean
radius ratio, eq. 10), and the flip is kept if the ratios summed over the
triangles that moved grew by more than GAIN and their smallest stayed at
least min(its value before, ``keep``); otherwise the nodes and the edge go
back, bit for bit.

So the mesh stays valid (every move keeps each star strictly
counter-clockwise, exact) and conforming (segments never flip, boundary
nodes never move), its smallest radius ratio never drops below
min(its value before, ``keep``), and in general it is no longer
constrained-Delaunay.  Edges are tried in triangle order, one at a time,
passes repeat until none is kept (at most ``passes``): deterministic.
"""

import numpy as np
from numba import njit

from ._flips import _flip, _is_segment, _relink, across
from ._odt import polish_gathered
from ._smoothing import _star_row, rho
from .predicates import orient2d

GAIN = 1e-9  # the summed ratios must grow by more than this (far above their rounding)
MAX_DELTA = 0  # flips that raise sum (count - ideal)^2 are not tried: they almost never pay
MOST = 64  # a star or a neighbourhood larger than this is left alone


@njit(cache=True)
def _energy(count, ideal, v, change):
    """How much node v's (count - ideal)^2 grows when its count changes."""
    before = count[v] - ideal[v]
    return (before + change) ** 2 - before**2


@njit(cache=True)
def _slot(tri, t, i):
    return 0 if tri[t, 0] == i else (1 if tri[t, 1] == i else 2)


@njit(cache=True)
def _star(tri, nbr, start, i, out):
    """The triangles at node i into ``out`` in increasing order (so that what
    is read from a star does not depend on where its walk began), walking
    across edges from its triangle ``start`` one way, then, if the star is
    open (i on the boundary), the other way.  Returns their number, -1 if
    more than fit."""
    count = 0
    t = start
    while True:
        if count == out.shape[0]:
            return -1
        out[count] = t
        count += 1
        t = nbr[t, (_slot(tri, t, i) + 1) % 3]
        if t == start or t < 0:
            break
    if t < 0:
        t = nbr[start, (_slot(tri, start, i) + 2) % 3]
        while t >= 0:
            if count == out.shape[0]:
                return -1
            out[count] = t
            count += 1
            t = nbr[t, (_slot(tri, t, i) + 2) % 3]
    for e in range(1, count):  # insertion sort: a star holds a handful
        t = out[e]
        f = e - 1
        while f >= 0 and out[f] > t:
            out[f + 1] = out[f]
            f -= 1
        out[f + 1] = t
    return count


@njit(cache=True)
def _ratios(X, tri, ts, count, limit):
    """(sum, smallest) of the radius ratios of triangles ts[:count]; smallest
    -1 if one has an area above its limit."""
    total = 0.0
    worst = 1.0
    for e in range(count):
        a, b, c = tri[ts[e], 0], tri[ts[e], 1], tri[ts[e], 2]
        q = rho(X[a, 0], X[a, 1], X[b, 0], X[b, 1], X[c, 0], X[c, 1])
        total += q
        worst = min(worst, q)
        area2 = ((X[b, 0] - X[a, 0]) * (X[c, 1] - X[a, 1])
                 - (X[b, 1] - X[a, 1]) * (X[c, 0] - X[a, 0]))
        if 0.5 * area2 > limit[ts[e]]:
            worst = -1.0
    return total, worst


@njit(cache=True)
def _neighbourhood(tri, nbr, home, quad, movable, node_mark, tri_mark, stamp, nodes, ts, buf):
    """The movable nodes of the stars of the four ``quad`` nodes into
    ``nodes`` and the triangles at those nodes into ``ts`` (each once, by the
    stamps; two slots left for the quad's own).  Returns (nodes, triangles),
    (-1, -1) where a star is larger than MOST or the lists overflow."""
    n_nodes = 0
    n_ts = 0
    for j in range(4):
        deg = _star(tri, nbr, home[quad[j]], quad[j], buf)
        if deg < 0:
            return -1, -1
        for e in range(deg):
            for k in range(3):
                v = tri[buf[e], k]
                if movable[v] and node_mark[v] != stamp:
                    if n_nodes == nodes.shape[0]:
                        return -1, -1
                    node_mark[v] = stamp
                    nodes[n_nodes] = v
                    n_nodes += 1
    for j in range(n_nodes):
        deg = _star(tri, nbr, home[nodes[j]], nodes[j], buf)
        if deg < 0:
            return -1, -1
        for e in range(deg):
            if tri_mark[buf[e]] != stamp:
                if n_ts >= ts.shape[0] - 2:
                    return -1, -1
                tri_mark[buf[e]] = stamp
                ts[n_ts] = buf[e]
                n_ts += 1
    return n_nodes, n_ts


@njit(cache=True)
def _newest(tri, ts, count, touched):
    """The latest ``touched`` of any node of triangles ts[:count]."""
    newest = 0
    for e in range(count):
        for k in range(3):
            newest = max(newest, touched[tri[ts[e], k]])
    return newest


@njit(cache=True)
def _relax(X, tri, nbr, home, nodes, n_nodes, keep, sweeps, halvings, steps, buf, rows):
    """``sweeps`` sweeps of mean-ratio steps over nodes[:n_nodes] (their
    stars walked afresh: the flip changed some)."""
    for _ in range(sweeps):
        for j in range(n_nodes):
            i = nodes[j]
            deg = _star(tri, nbr, home[i], i, buf)
            if deg < 0:
                continue
            for e in range(deg):
                _star_row(X, tri, buf[e], i, rows, e)
            polish_gathered(X, i, rows, deg, keep, halvings, 1.0, steps)


@njit(cache=True)
def _unflip(tri, nbr, t, u, saved_tri, saved_nbr):
    """Undo :func:`_flip` of t and u from their saved rows."""
    _relink(nbr, nbr[u, 0], u, t)  # edge bc went back to t
    _relink(nbr, nbr[t, 0], t, u)  # and ad to u
    for k in range(3):
        tri[t, k], tri[u, k] = saved_tri[0, k], saved_tri[1, k]
        nbr[t, k], nbr[u, k] = saved_nbr[0, k], saved_nbr[1, k]


@njit(cache=True)
def relaxed_flips(X, tri, nbr, keys, movable, ideal, limit, keep, passes, sweeps, halvings,
                  steps, changed, remember=True):
    """The module docstring's flips; X, tri and nbr in place.  ``ideal``: the
    ideal triangle count of every node; ``limit``: the largest area each
    triangle may take (inf: none; a flip is kept only if every triangle that
    changed is within its own; t and u keep theirs, their quadrilateral lies
    in one region).  With ``remember`` an edge is not tried again while no
    node of the triangles its trial read has moved or changed its star since
    (the trial would find what it did: an exact active set).  ``changed``
    (n,) bool is set at every node that a kept flip moved or re-linked.
    Returns the flips kept."""
    n, m = X.shape[0], tri.shape[0]
    home = np.empty(n, np.int64)  # a triangle at every node, kept valid across flips
    count = np.zeros(n, np.int64)
    for t in range(m):
        for k in range(3):
            home[tri[t, k]] = t
            count[tri[t, k]] += 1
    node_mark = np.zeros(n, np.int32)  # stamps and flip counts stay far below 2^31
    tri_mark = np.zeros(m, np.int32)
    nodes = np.empty(4 * MOST, np.int64)
    ts = np.empty(4 * MOST * MOST + 2, np.int64)  # t and u come on top
    buf = np.empty(MOST, np.int64)
    rows = np.empty((MOST, 5))
    saved_x = np.empty((4 * MOST, 2))
    saved_tri = np.empty((2, 3), np.int64)
    saved_nbr = np.empty((2, 3), np.int64)
    quad = np.empty(4, np.int64)
    touched = np.zeros(n, np.int32)  # the last kept flip that moved a node or changed its star
    tried = np.full((m, 3), -1, np.int32)  # kept flips so far when an edge's trial failed
    stamp = 0
    kept = 0
    for _ in range(passes):
        kept_now = 0
        for t in range(m):
            for k in range(3):
                u = nbr[t, k]
                if u < t:  # the boundary, or the pair already tried from u
                    continue
                c, a, b = tri[t, k], tri[t, (k + 1) % 3], tri[t, (k + 2) % 3]
                slot, d = across(tri, t, k, u)
                if (count[a] == ideal[a] and count[b] == ideal[b] and count[c] == ideal[c]
                        and count[d] == ideal[d]):
                    continue
                if (_energy(count, ideal, a, -1) + _energy(count, ideal, b, -1)
                        + _energy(count, ideal, c, 1) + _energy(count, ideal, d, 1) > MAX_DELTA):
                    continue
                if _is_segment(keys, n, a, b):
                    continue
                if (orient2d(X[c, 0], X[c, 1], X[a, 0], X[a, 1], X[d, 0], X[d, 1]) <= 0.0
                        or orient2d(X[d, 0], X[d, 1], X[b, 0], X[b, 1], X[c, 0], X[c, 1])
                        <= 0.0):
                    continue
                stamp += 1
                quad[0], quad[1], quad[2], quad[3] = a, b, c, d
                n_nodes, n_ts = _neighbourhood(tri, nbr, home, quad, movable, node_mark,
                                               tri_mark, stamp, nodes, ts, buf)
                if n_nodes <= 0:
                    continue
                if tri_mark[t] != stamp:
                    ts[n_ts] = t
                    n_ts += 1
                if tri_mark[u] != stamp:
                    ts[n_ts] = u
                    n_ts += 1
                if remember and tried[t, k] >= 0 and _newest(tri, ts, n_ts, touched) <= tried[t, k]:
                    continue
                before, worst_before = _ratios(X, tri, ts, n_ts, limit)
                for j in range(n_nodes):
                    saved_x[j, 0], saved_x[j, 1] = X[nodes[j], 0], X[nodes[j], 1]
                for j in range(3):
                    saved_tri[0, j], saved_tri[1, j] = tri[t, j], tri[u, j]
                    saved_nbr[0, j], saved_nbr[1, j] = nbr[t, j], nbr[u, j]
                _flip(tri, nbr, t, k, u, slot)
                home[a], home[b], home[c], home[d] = t, u, t, u
                _relax(X, tri, nbr, home, nodes, n_nodes, keep, sweeps, halvings, steps, buf,
                       rows)
                after, worst_after = _ratios(X, tri, ts, n_ts, limit)
                if (after > before + GAIN and worst_after >= min(worst_before, keep)
                        and worst_after >= 0.0):
                    count[a] -= 1
                    count[b] -= 1
                    count[c] += 1
                    count[d] += 1
                    kept_now += 1
                    kept += 1
                    for j in range(n_nodes):
                        touched[nodes[j]] = kept
                    touched[a], touched[b], touched[c], touched[d] = kept, kept, kept, kept
                    break  # t changed: its other edges wait for the next pass
                for j in range(n_nodes):
                    X[nodes[j], 0], X[nodes[j], 1] = saved_x[j, 0], saved_x[j, 1]
                _unflip(tri, nbr, t, u, saved_tri, saved_nbr)
                home[a], home[b], home[c], home[d] = t, u, t, u
                tried[t, k] = kept
        if kept_now == 0:
            break
    for i in range(n):
        if touched[i] > 0:
            changed[i] = True
    return kept
