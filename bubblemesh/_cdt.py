"""Constrained Delaunay triangulation from a Delaunay one (paper §2.1, §3.5):
edge flips, segment recovery with Lawson restoration, removal of the outside
and the holes by the parity of constrained edges crossed from infinity (in
place of MATLAB's ``isInterior``), and compaction to the kept triangles.

``con`` flags: 0 free, ``BOUNDARY`` (1) a loop segment, counted by the parity,
``INTERIOR`` (2) an interior constraint (interface, crack): kept as an edge,
not counted, and cut in the compacted neighbours so every later walk and
cavity stops at it as at the boundary."""

import numpy as np
from numba import njit

from ._cavity import is_ghost, orient, strictly_between
from ._status import ERR_RECOVERY, ERR_SEGMENTS_CROSS, ERR_STACK, ERR_VERTEX_ON_SEGMENT, OK
from .predicates import incircle

BOUNDARY = 1
INTERIOR = 2


@njit(cache=True, inline="always")
def _index_of(tri, t, v):
    if tri[t, 0] == v:
        return 0
    if tri[t, 1] == v:
        return 1
    return 2


@njit(cache=True, inline="always")
def _opposite(tri, t, x, y):
    """Index in t of the vertex that is neither x nor y."""
    for m in range(3):
        if tri[t, m] != x and tri[t, m] != y:
            return m
    return 0


@njit(cache=True)
def _flip(tri, nbr, con, vt, t, i):
    """Flip the edge opposite vertex i of t with its neighbour n.  With
    t = (q1, u, w) and n = (q2, w, u) it makes t = (q1, u, q2), n = (q2, w, q1)."""
    n = nbr[t, i]
    q1 = tri[t, i]
    u = tri[t, (i + 1) % 3]
    w = tri[t, (i + 2) % 3]
    j = 0
    for m in range(3):
        if nbr[n, m] == t and tri[n, (m + 1) % 3] == w:
            j = m
    q2 = tri[n, j]
    A = nbr[t, (i + 1) % 3]  # across (w, q1)
    cA = con[t, (i + 1) % 3]
    B = nbr[t, (i + 2) % 3]  # across (q1, u)
    cB = con[t, (i + 2) % 3]
    C = nbr[n, (j + 1) % 3]  # across (u, q2)
    cC = con[n, (j + 1) % 3]
    D = nbr[n, (j + 2) % 3]  # across (q2, w)
    cD = con[n, (j + 2) % 3]
    tri[t, 0], tri[t, 1], tri[t, 2] = q1, u, q2
    nbr[t, 0], nbr[t, 1], nbr[t, 2] = C, n, B
    con[t, 0], con[t, 1], con[t, 2] = cC, 0, cB
    tri[n, 0], tri[n, 1], tri[n, 2] = q2, w, q1
    nbr[n, 0], nbr[n, 1], nbr[n, 2] = A, t, D
    con[n, 0], con[n, 1], con[n, 2] = cA, 0, cD
    if A >= 0:
        for m in range(3):
            if nbr[A, m] == t:
                nbr[A, m] = n
    if C >= 0:
        for m in range(3):
            if nbr[C, m] == n:
                nbr[C, m] = t
    if q1 >= 0:
        vt[q1] = t
    if u >= 0:
        vt[u] = t
    if q2 >= 0:
        vt[q2] = t
    if w >= 0:
        vt[w] = n


@njit(cache=True)
def _find_edge(tri, nbr, vt, a, b, max_steps):
    """(t, i) with edge a -> b opposite vertex i of t, found by turning around a;
    (-1, -1) if a and b are not joined."""
    t = vt[a]
    for _ in range(max_steps):
        i = _index_of(tri, t, a)
        if tri[t, (i + 1) % 3] == b:
            return t, (i + 2) % 3
        t = nbr[t, (i + 2) % 3]  # across (a, next): the next triangle around a
        if t == vt[a]:
            break
    return -1, -1


@njit(cache=True, inline="always")
def _push_edges(stack_t, stack_i, top, t, n):
    """Stack the 6 edges of the two triangles a flip just rebuilt."""
    for m in range(3):
        stack_t[top] = t
        stack_i[top] = m
        top += 1
        stack_t[top] = n
        stack_i[top] = m
        top += 1
    return top


@njit(cache=True)
def _lawson(P, tri, nbr, con, vt, stack_t, stack_i, top, max_flips):
    """Flip every non-locally-Delaunay unconstrained edge reachable from the
    stacked (triangle, edge) pairs; each flip stacks the edges it touched."""
    flips = 0
    while top > 0:
        top -= 1
        t = stack_t[top]
        i = stack_i[top]
        n = nbr[t, i]
        if n < 0 or con[t, i] or is_ghost(tri, t) or is_ghost(tri, n):
            continue
        a = tri[t, i]
        u = tri[t, (i + 1) % 3]
        w = tri[t, (i + 2) % 3]
        q2 = -1
        for m in range(3):
            if nbr[n, m] == t and tri[n, (m + 1) % 3] == w:
                q2 = tri[n, m]
        inside = incircle(P[a, 0], P[a, 1], P[u, 0], P[u, 1], P[w, 0], P[w, 1], P[q2, 0], P[q2, 1])
        if inside <= 0.0:
            continue
        _flip(tri, nbr, con, vt, t, i)
        flips += 1
        if flips > max_flips or top + 6 > stack_t.shape[0]:
            return ERR_STACK
        top = _push_edges(stack_t, stack_i, top, t, n)
    return OK


@njit(cache=True)
def _crossed_edges(P, tri, nbr, con, vt, a, b, qu, qw, max_steps):
    """Edges properly crossed by segment a-b, as vertex pairs in qu/qw.
    Returns (status, count); count 0 with OK means a-b is already an edge.
    Crossing a constrained edge is ERR_SEGMENTS_CROSS (its vertex x as count)."""
    # find the triangle around a whose wedge contains the direction to b
    t = vt[a]
    start = t
    found = -1
    for _ in range(max_steps):
        i = _index_of(tri, t, a)
        x = tri[t, (i + 1) % 3]
        y = tri[t, (i + 2) % 3]
        if x == b or y == b:
            return OK, 0
        if x >= 0 and y >= 0:
            ox = orient(P, a, x, b)
            oy = orient(P, a, y, b)
            if ox == 0.0 and strictly_between(P, a, b, P[x, 0], P[x, 1]):
                return ERR_VERTEX_ON_SEGMENT, x
            if oy == 0.0 and strictly_between(P, a, b, P[y, 0], P[y, 1]):
                return ERR_VERTEX_ON_SEGMENT, y
            if ox > 0.0 and oy < 0.0:
                found = t
                break
        t = nbr[t, (i + 2) % 3]
        if t == start:
            break
    if found < 0:
        return ERR_RECOVERY, a
    t = found
    i = _index_of(tri, t, a)
    x = tri[t, (i + 1) % 3]  # right of a->b
    y = tri[t, (i + 2) % 3]  # left of a->b
    count = 0
    for _ in range(max_steps):
        if count >= qu.shape[0]:
            return ERR_STACK, a
        qu[count] = x
        qw[count] = y
        count += 1
        j = _opposite(tri, t, x, y)
        if con[t, j]:
            return ERR_SEGMENTS_CROSS, x
        n = nbr[t, j]
        z = -1
        for m in range(3):
            if tri[n, m] != x and tri[n, m] != y:
                z = tri[n, m]
        if z == b:
            return OK, count
        if z < 0:
            return ERR_RECOVERY, a
        oz = orient(P, a, b, z)
        if oz == 0.0:
            return ERR_VERTEX_ON_SEGMENT, z
        if oz > 0.0:
            y = z
        else:
            x = z
        t = n
    return ERR_RECOVERY, a


@njit(cache=True)
def recover_segment(P, tri, nbr, con, vt, a, b, qu, qw, stack_t, stack_i, max_steps, flag=1):
    """Make a-b an edge by flipping the edges it crosses (Sloan's queue), mark it
    constrained, then restore the constrained Delaunay property by Lawson flips
    around every triangle the recovery changed.  Returns (status, vertex)."""
    status, k = _crossed_edges(P, tri, nbr, con, vt, a, b, qu, qw, max_steps)
    if status != OK:
        return status, k
    top = 0
    head = 0
    tail = k
    qcap = qu.shape[0]
    budget = 10 * k * k + 1000
    while head != tail:
        budget -= 1
        if budget < 0:
            return ERR_RECOVERY, a
        u = qu[head % qcap]
        w = qw[head % qcap]
        head += 1
        t, i = _find_edge(tri, nbr, vt, u, w, max_steps)
        if t < 0:
            return ERR_RECOVERY, u
        n = nbr[t, i]
        q1 = tri[t, i]
        q2 = tri[n, _opposite(tri, n, u, w)]
        o_u = orient(P, q1, q2, u)
        o_w = orient(P, q1, q2, w)
        if (o_u > 0.0 and o_w < 0.0) or (o_u < 0.0 and o_w > 0.0):
            _flip(tri, nbr, con, vt, t, i)
            if top + 6 > stack_t.shape[0]:
                return ERR_STACK, a
            top = _push_edges(stack_t, stack_i, top, t, n)
            o1 = orient(P, a, b, q1)
            o2 = orient(P, a, b, q2)
            if (o1 > 0.0 and o2 < 0.0) or (o1 < 0.0 and o2 > 0.0):
                if tail - head >= qcap:
                    return ERR_STACK, a
                qu[tail % qcap] = q1
                qw[tail % qcap] = q2
                tail += 1
        else:
            if tail - head >= qcap:
                return ERR_STACK, a
            qu[tail % qcap] = u
            qw[tail % qcap] = w
            tail += 1
    t, i = _find_edge(tri, nbr, vt, a, b, max_steps)
    if t < 0:
        return ERR_RECOVERY, a
    _set_constrained(tri, nbr, con, t, i, flag)
    return _lawson(P, tri, nbr, con, vt, stack_t, stack_i, top, budget + 10 * max_steps), -1


@njit(cache=True)
def _set_constrained(tri, nbr, con, t, i, flag):
    con[t, i] = flag
    n = nbr[t, i]
    if n >= 0:
        u = tri[t, (i + 1) % 3]
        for m in range(3):
            if nbr[n, m] == t and tri[n, (m + 2) % 3] == u:
                con[n, m] = flag


@njit(cache=True)
def recover_segments(P, tri, nbr, con, vt, ntri, segments, flags, capacity):
    """Recover every segment, marking its edge ``flags[s]``; returns (status,
    segment index, vertex).  ``capacity`` sizes the crossing queue and the flip
    stack (ERR_STACK if a single recovery needs more)."""
    qu = np.empty(capacity, np.int64)
    qw = np.empty(capacity, np.int64)
    stack_t = np.empty(4 * capacity, np.int64)
    stack_i = np.empty(4 * capacity, np.int64)
    for s in range(segments.shape[0]):
        a = segments[s, 0]
        b = segments[s, 1]
        t, i = _find_edge(tri, nbr, vt, a, b, ntri + 8)
        if t >= 0:
            _set_constrained(tri, nbr, con, t, i, flags[s])
            continue
        status, v = recover_segment(P, tri, nbr, con, vt, a, b, qu, qw, stack_t, stack_i,
                                    ntri + 8, flags[s])
        if status != OK:
            return status, s, v
    return OK, -1, -1


@njit(cache=True)
def interior_mask(tri, nbr, con, ntri):
    """True for real triangles separated from infinity by an odd number of
    boundary edges (``con == BOUNDARY``; interior constraints are crossed
    freely): inside the outer loop and outside every hole, islands in holes
    kept, to any depth."""
    depth = np.full(ntri, -1, np.int64)
    cur = np.empty(ntri, np.int64)
    nxt = np.empty(3 * ntri, np.int64)
    ncur = 0
    for t in range(ntri):
        if is_ghost(tri, t):
            depth[t] = 0
            cur[ncur] = t
            ncur += 1
    level = 0
    while ncur > 0:
        nnext = 0
        i = 0
        while i < ncur:
            t = cur[i]
            i += 1
            for j in range(3):
                n = nbr[t, j]
                if n < 0 or depth[n] != -1:
                    continue
                if con[t, j] == BOUNDARY:
                    nxt[nnext] = n
                    nnext += 1
                else:
                    depth[n] = level
                    cur[ncur] = n
                    ncur += 1
        level += 1
        ncur = 0
        for k in range(nnext):
            n = nxt[k]
            if depth[n] == -1:
                depth[n] = level
                cur[ncur] = n
                ncur += 1
    out = np.zeros(ntri, np.bool_)
    for t in range(ntri):
        out[t] = depth[t] % 2 == 1 and not is_ghost(tri, t)
    return out


@njit(cache=True)
def compact(tri, nbr, keep, con):
    """Keep the flagged triangles; neighbours outside the kept set and across
    interior constraints (``con == INTERIOR``) become -1."""
    ntri = keep.shape[0]
    new_id = np.full(ntri, -1, np.int64)
    m = 0
    for t in range(ntri):
        if keep[t]:
            new_id[t] = m
            m += 1
    out_tri = np.empty((m, 3), np.int64)
    out_nbr = np.empty((m, 3), np.int64)
    for t in range(ntri):
        k = new_id[t]
        if k < 0:
            continue
        for j in range(3):
            out_tri[k, j] = tri[t, j]
            n = nbr[t, j]
            out_nbr[k, j] = new_id[n] if n >= 0 and con[t, j] != INTERIOR else -1
    return out_tri, out_nbr
