"""Flat-array triangulation kernel: Delaunay, constrained Delaunay, cavity insertion.

Implements the triangulation steps the paper delegates to MATLAB's
``delaunayTriangulation`` and ``isInterior`` (§2.1 initial boundary mesh, §3.5
re-triangulation) and the node insertion of §2.2 (Fig. 1): the cavity is grown
from the triangle that contains the new point through neighbours whose
circumcircle strictly contains it, never across a constrained (boundary) edge,
and is then re-filled by joining the point to the cavity's boundary edges
(Bowyer-Watson).

Data layout (numpy arrays, the same in every kernel):

* ``tri``  (cap, 3) int64, counter-clockwise vertex ids; ``GHOST`` (-1) stands for
  the vertex at infinity, so the convex hull needs no super-triangle (whose huge
  coordinates would break exactness).  Ghost triangle ``(u, v, GHOST)`` lies
  beyond the hull edge ``u -> v``.
* ``nbr``  (cap, 3) int64, ``nbr[t, i]`` is the triangle across the edge opposite
  vertex ``i`` (edge ``tri[t, i+1], tri[t, i+2]``); -1 where there is none (the
  domain boundary of a mesh whose outside was removed).
* ``con``  (cap, 3) uint8, 1 where that edge is a constrained segment.
* ``vt``   (n,) int64, one triangle incident to each vertex.

All predicates are exact (``predicates``), so each decision is the real one.
Every loop has a bound; kernels return negative status codes that the Python
wrappers turn into ``GeometryError``/``MeshingError``.
"""

import numpy as np
from numba import njit, prange

from .errors import GeometryError, MeshingError
from .memory import unsigned
from .predicates import incircle, orient2d, out_of_range, out_of_range_message

GHOST = -1

# status codes returned by the kernels
OK = 0
ERR_NOT_STAR = -2
ERR_CAPACITY = -3
ERR_WALK = -4
ERR_COLLINEAR = -5
ERR_VERTEX_ON_SEGMENT = -6
ERR_RECOVERY = -7
ERR_STACK = -8

_MESSAGES = {
    ERR_NOT_STAR: "cavity is not star-shaped (internal invariant failed)",
    ERR_CAPACITY: "triangle capacity exceeded",
    ERR_WALK: "point location walk exceeded its bound",
    ERR_COLLINEAR: "all points are collinear (or fewer than 3 distinct points)",
    ERR_VERTEX_ON_SEGMENT: "a vertex lies on a segment",
    ERR_RECOVERY: "segment recovery exceeded its flip bound",
    ERR_STACK: "flip stack exceeded its bound",
}


# --- small helpers ------------------------------------------------------------------


@njit(cache=True, inline="always")
def _orient(P, u, v, w):
    return orient2d(P[u, 0], P[u, 1], P[v, 0], P[v, 1], P[w, 0], P[w, 1])


@njit(cache=True, inline="always")
def _orient_pt(P, u, v, px, py):
    return orient2d(P[u, 0], P[u, 1], P[v, 0], P[v, 1], px, py)


@njit(cache=True, inline="always")
def is_ghost(tri, t):
    return tri[t, 0] < 0 or tri[t, 1] < 0 or tri[t, 2] < 0


@njit(cache=True, inline="always")
def _strictly_between(P, u, v, px, py):
    """For p collinear with u, v: is p strictly inside the segment (u, v)?"""
    if P[u, 0] != P[v, 0]:
        lo = min(P[u, 0], P[v, 0])
        hi = max(P[u, 0], P[v, 0])
        return lo < px < hi
    lo = min(P[u, 1], P[v, 1])
    hi = max(P[u, 1], P[v, 1])
    return lo < py < hi


@njit(cache=True)
def in_conflict(P, tri, t, px, py):
    """Does (px, py) lie strictly inside the circumcircle of triangle t?  For a
    ghost triangle the 'circle' is the open outer half-plane of its hull edge
    plus the open edge itself."""
    a = tri[unsigned(t), 0]
    b = tri[unsigned(t), 1]
    c = tri[unsigned(t), 2]
    if a >= 0 and b >= 0 and c >= 0:
        a, b, c = unsigned(a), unsigned(b), unsigned(c)
        return (
            incircle(P[a, 0], P[a, 1], P[b, 0], P[b, 1], P[c, 0], P[c, 1], px, py) > 0.0
        )
    if a < 0:
        u, v = b, c
    elif b < 0:
        u, v = c, a
    else:
        u, v = a, b
    o = _orient_pt(P, u, v, px, py)
    if o > 0.0:
        return True
    if o < 0.0:
        return False
    return _strictly_between(P, u, v, px, py)


@njit(cache=True)
def locate(P, px, py, start, tri, nbr, max_steps):
    """Visibility walk from triangle ``start`` to the triangle whose closure
    contains p, or to the ghost triangle beyond whose hull edge p lies.  Returns
    the triangle, or -1 if the bound was hit."""
    t = start
    for _ in range(max_steps):
        if is_ghost(tri, t):
            return t
        moved = False
        for j in range(3):
            u = unsigned(tri[t, (j + 1) % 3])  # t is not a ghost
            v = unsigned(tri[t, (j + 2) % 3])
            if _orient_pt(P, u, v, px, py) < 0.0:
                t = nbr[t, j]
                moved = True
                break
        if not moved:
            return t
    return -1


# --- Bowyer-Watson cavity insertion (paper §2.2, Fig. 1) ------------------------------


@njit(cache=True)
def find_cavity(P, px, py, t0, tri, nbr, con, mark, stamp, cav, bnd):
    """Collect the cavity of p grown from triangle t0 (which must be in conflict):
    breadth-first through unconstrained edges into triangles whose circumcircle
    strictly contains p.  Fills ``cav[:ncav]`` with cavity triangles and
    ``bnd[:nb]`` with the cavity's boundary edges as rows (u, v, outside
    triangle, constrained flag), u -> v counter-clockwise seen from p.
    ``mark`` holds +stamp for cavity triangles, -stamp for tested outsiders."""
    mark[t0] = stamp
    cav[0] = t0
    ncav = 1
    nb = 0
    i = 0
    while i < ncav:
        t = unsigned(cav[i])
        i += 1
        for j in range(3):
            n = nbr[t, j]
            if n >= 0 and con[t, j] == 0:
                if mark[unsigned(n)] == stamp:
                    continue
                if mark[unsigned(n)] != -stamp:
                    if in_conflict(P, tri, n, px, py):
                        mark[unsigned(n)] = stamp
                        cav[ncav] = n
                        ncav += 1
                        continue
                    mark[unsigned(n)] = -stamp
            # a constrained edge with cavity on both sides is recorded twice, so
            # the count check of fill_cavity rejects it instead of deleting it
            bnd[nb, 0] = tri[t, (j + 1) % 3]
            bnd[nb, 1] = tri[t, (j + 2) % 3]
            bnd[nb, 2] = n
            bnd[nb, 3] = con[t, j]
            nb += 1
    return ncav, nb


@njit(cache=True)
def fill_cavity(P, pi, tri, nbr, con, vt, ntri, cav, ncav, bnd, nb, vstart, newt):
    """Replace the cavity by the fan of triangles (u, v, pi) over its boundary
    edges.  Reuses the cavity's slots, appends the 2 extra ones.  Returns
    (status, new ntri); ``newt[:nb]`` holds the new triangle ids."""
    px = P[pi, 0]
    py = P[pi, 1]
    if nb != ncav + 2:
        return ERR_NOT_STAR, ntri
    if ntri + nb - ncav > tri.shape[0]:
        return ERR_CAPACITY, ntri
    nv = vstart.shape[0] - 1  # slot of the ghost vertex in vstart
    for k in range(nb):
        u = bnd[k, 0]
        v = bnd[k, 1]
        if u >= 0 and v >= 0 and _orient_pt(P, unsigned(u), unsigned(v), px, py) <= 0.0:
            return ERR_NOT_STAR, ntri
    simple = True
    for k in range(nb):
        u = bnd[k, 0]
        uu = u if u >= 0 else nv
        if vstart[uu] != -1:
            simple = False
        vstart[uu] = k
    for k in range(nb):
        v = bnd[k, 1]
        if vstart[v if v >= 0 else nv] == -1:
            simple = False
    if not simple:  # the boundary is not one simple cycle
        for k in range(nb):
            u = bnd[k, 0]
            vstart[u if u >= 0 else nv] = -1
        return ERR_NOT_STAR, ntri
    for k in range(nb):
        newt[k] = cav[k] if k < ncav else ntri + (k - ncav)
    for k in range(nb):
        t = newt[k]
        ut = unsigned(t)
        u = bnd[k, 0]
        v = bnd[k, 1]
        n = bnd[k, 2]
        tri[ut, 0] = u
        tri[ut, 1] = v
        tri[ut, 2] = pi
        nbr[ut, 2] = n
        con[ut, 0] = 0
        con[ut, 1] = 0
        con[ut, 2] = bnd[k, 3]
        if n >= 0:
            un = unsigned(n)
            for m in range(3):
                if tri[un, (m + 1) % 3] == v and tri[un, (m + 2) % 3] == u:
                    nbr[un, m] = t
                    break
    for k in range(nb):
        t = newt[k]
        v = tri[unsigned(t), 1]
        s = newt[vstart[v if v >= 0 else nv]]
        nbr[unsigned(t), 0] = s
        nbr[unsigned(s), 1] = t
    for k in range(nb):
        u = bnd[k, 0]
        vstart[u if u >= 0 else nv] = -1
        if u >= 0:
            vt[u] = newt[k]
    vt[pi] = newt[0]
    return OK, ntri + nb - ncav


# --- unconstrained Delaunay by incremental insertion ---------------------------------


@njit(cache=True)
def _first_triangle(P, order, tri, nbr):
    """Find 3 non-collinear points in insertion order, build them and their 3
    ghosts.  Returns (status, i0, i1, i2)."""
    n = order.shape[0]
    i0 = order[0]
    i1 = -1
    for k in range(1, n):
        q = order[k]
        if P[q, 0] != P[i0, 0] or P[q, 1] != P[i0, 1]:
            i1 = q
            break
    if i1 < 0:
        return ERR_COLLINEAR, -1, -1, -1
    i2 = -1
    for k in range(1, n):
        q = order[k]
        if _orient(P, i0, i1, q) != 0.0:
            i2 = q
            break
    if i2 < 0:
        return ERR_COLLINEAR, -1, -1, -1
    if _orient(P, i0, i1, i2) < 0.0:
        i1, i2 = i2, i1
    # real triangle 0 and ghosts 1..3 beyond its edges (i0,i1), (i1,i2), (i2,i0)
    tri[0, 0], tri[0, 1], tri[0, 2] = i0, i1, i2
    tri[1, 0], tri[1, 1], tri[1, 2] = i1, i0, GHOST
    tri[2, 0], tri[2, 1], tri[2, 2] = i2, i1, GHOST
    tri[3, 0], tri[3, 1], tri[3, 2] = i0, i2, GHOST
    nbr[0, 0], nbr[0, 1], nbr[0, 2] = 2, 3, 1
    nbr[1, 0], nbr[1, 1], nbr[1, 2] = 3, 2, 0
    nbr[2, 0], nbr[2, 1], nbr[2, 2] = 1, 3, 0
    nbr[3, 0], nbr[3, 1], nbr[3, 2] = 2, 1, 0
    return OK, i0, i1, i2


@njit(cache=True)
def delaunay_kernel(P, order, tri, nbr, con, vt, dup_of):
    """Insert the points in ``order`` (spatially sorted) into a ghost-closed
    Delaunay triangulation.  ``dup_of[k]`` receives the vertex that point k
    duplicates exactly (else stays -1).  Returns (status, ntri, bad_point)."""
    status, i0, i1, i2 = _first_triangle(P, order, tri, nbr)
    if status != OK:
        return status, 0, -1
    vt[i0] = 0
    vt[i1] = 0
    vt[i2] = 0
    cap = tri.shape[0]
    mark = np.zeros(cap, np.int64)
    cav = np.empty(cap, np.int64)
    bnd = np.empty((cap + 2, 4), np.int64)
    newt = np.empty(cap + 2, np.int64)
    vstart = np.full(P.shape[0] + 1, -1, np.int64)
    ntri = 4
    last = 0
    stamp = 0
    for k in range(order.shape[0]):
        q = order[k]
        if q == i0 or q == i1 or q == i2:
            continue
        px = P[q, 0]
        py = P[q, 1]
        t = locate(P, px, py, last, tri, nbr, ntri + 8)
        if t < 0:
            return ERR_WALK, ntri, q
        if not is_ghost(tri, t):
            dup = -1
            for m in range(3):
                w = tri[t, m]
                if P[w, 0] == px and P[w, 1] == py:
                    dup = w
            if dup >= 0:
                dup_of[q] = dup
                continue
        stamp += 1
        ncav, nb = find_cavity(P, px, py, t, tri, nbr, con, mark, stamp, cav, bnd)
        status, ntri = fill_cavity(P, q, tri, nbr, con, vt, ntri, cav, ncav, bnd, nb, vstart, newt)
        if status != OK:
            return status, ntri, q
        last = newt[0]
        for m in range(nb):
            if not is_ghost(tri, newt[m]):
                last = newt[m]
                break
    return OK, ntri, -1


# --- edge flips, segment recovery, Lawson restoration --------------------------------


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
def _crossed_edges(P, tri, nbr, vt, a, b, qu, qw, max_steps):
    """Edges properly crossed by segment a-b, as vertex pairs in qu/qw.
    Returns (status, count); count 0 with OK means a-b is already an edge."""
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
            ox = _orient(P, a, x, b)
            oy = _orient(P, a, y, b)
            if ox == 0.0 and _strictly_between(P, a, b, P[x, 0], P[x, 1]):
                return ERR_VERTEX_ON_SEGMENT, x
            if oy == 0.0 and _strictly_between(P, a, b, P[y, 0], P[y, 1]):
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
        n = nbr[t, _opposite(tri, t, x, y)]
        z = -1
        for m in range(3):
            if tri[n, m] != x and tri[n, m] != y:
                z = tri[n, m]
        if z == b:
            return OK, count
        if z < 0:
            return ERR_RECOVERY, a
        oz = _orient(P, a, b, z)
        if oz == 0.0:
            return ERR_VERTEX_ON_SEGMENT, z
        if oz > 0.0:
            y = z
        else:
            x = z
        t = n
    return ERR_RECOVERY, a


@njit(cache=True)
def recover_segment(P, tri, nbr, con, vt, a, b, qu, qw, stack_t, stack_i, max_steps):
    """Make a-b an edge by flipping the edges it crosses (Sloan's queue), mark it
    constrained, then restore the constrained Delaunay property by Lawson flips
    around every triangle the recovery changed.  Returns (status, vertex)."""
    status, k = _crossed_edges(P, tri, nbr, vt, a, b, qu, qw, max_steps)
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
        o_u = _orient(P, q1, q2, u)
        o_w = _orient(P, q1, q2, w)
        if (o_u > 0.0 and o_w < 0.0) or (o_u < 0.0 and o_w > 0.0):
            _flip(tri, nbr, con, vt, t, i)
            if top + 6 > stack_t.shape[0]:
                return ERR_STACK, a
            top = _push_edges(stack_t, stack_i, top, t, n)
            o1 = _orient(P, a, b, q1)
            o2 = _orient(P, a, b, q2)
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
    _set_constrained(tri, nbr, con, t, i)
    return _lawson(P, tri, nbr, con, vt, stack_t, stack_i, top, budget + 10 * max_steps), -1


@njit(cache=True)
def _set_constrained(tri, nbr, con, t, i):
    con[t, i] = 1
    n = nbr[t, i]
    if n >= 0:
        u = tri[t, (i + 1) % 3]
        for m in range(3):
            if nbr[n, m] == t and tri[n, (m + 2) % 3] == u:
                con[n, m] = 1


@njit(cache=True)
def recover_segments(P, tri, nbr, con, vt, ntri, segments, capacity):
    """Recover every segment; returns (status, segment index, vertex).
    ``capacity`` sizes the crossing queue and the flip stack (ERR_STACK if a
    single recovery needs more)."""
    qu = np.empty(capacity, np.int64)
    qw = np.empty(capacity, np.int64)
    stack_t = np.empty(4 * capacity, np.int64)
    stack_i = np.empty(4 * capacity, np.int64)
    for s in range(segments.shape[0]):
        a = segments[s, 0]
        b = segments[s, 1]
        t, i = _find_edge(tri, nbr, vt, a, b, ntri + 8)
        if t >= 0:
            _set_constrained(tri, nbr, con, t, i)
            continue
        status, v = recover_segment(P, tri, nbr, con, vt, a, b, qu, qw, stack_t, stack_i, ntri + 8)
        if status != OK:
            return status, s, v
    return OK, -1, -1


# --- inside/outside by parity of crossed segments (MATLAB's isInterior) ---------------


@njit(cache=True)
def interior_mask(tri, nbr, con, ntri):
    """True for real triangles separated from infinity by an odd number of
    constrained edges: inside the outer loop and outside every hole."""
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
                if con[t, j]:
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
def compact(tri, nbr, keep):
    """Keep the flagged triangles; neighbours outside the kept set become -1."""
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
            out_nbr[k, j] = new_id[n] if n >= 0 else -1
    return out_tri, out_nbr


# --- spatial sort ----------------------------------------------------------------------


@njit(cache=True, parallel=True)
def _hilbert_keys(P, bits):
    n = P.shape[0]
    xmin = P[:, 0].min()
    ymin = P[:, 1].min()
    span = max(P[:, 0].max() - xmin, P[:, 1].max() - ymin)
    if span == 0.0:
        span = 1.0
    side = (1 << bits) - 1
    keys = np.empty(n, np.int64)
    for k in prange(n):
        x = int((P[k, 0] - xmin) / span * side)
        y = int((P[k, 1] - ymin) / span * side)
        d = 0
        s = 1 << (bits - 1)
        while s > 0:
            rx = 1 if (x & s) > 0 else 0
            ry = 1 if (y & s) > 0 else 0
            d += s * s * ((3 * rx) ^ ry)
            if ry == 0:
                if rx == 1:
                    x = side - x
                    y = side - y
                x, y = y, x
            s >>= 1
        keys[k] = d
    return keys


@njit(cache=True)
def _radix_argsort(keys, digits):
    """Stable argsort of non-negative keys below 2**(16 digits): least
    significant 16 bits first (what np.argsort(kind="stable") gives, in O(n))."""
    n = keys.shape[0]
    order = np.arange(n)
    spare = np.empty(n, np.int64)
    count = np.empty(65537, np.int64)
    for d in range(digits):
        shift = 16 * d
        count[:] = 0
        for k in range(n):
            count[((keys[order[k]] >> shift) & 0xFFFF) + 1] += 1
        for b in range(65536):
            count[b + 1] += count[b]
        for k in range(n):
            digit = (keys[order[k]] >> shift) & 0xFFFF
            spare[count[digit]] = order[k]
            count[digit] += 1
        order, spare = spare, order
    return order


def hilbert_order(points):
    """Insertion order along a Hilbert curve: each new point lands next to the
    previous one, so the walking point location takes O(1) steps on average."""
    if len(points) == 0:
        return np.zeros(0, np.int64)
    keys = _hilbert_keys(np.ascontiguousarray(points, dtype=np.float64), 16)
    return _radix_argsort(keys, 2)  # keys < 4**16


# --- Python wrappers ----------------------------------------------------------------


def _writable(array, dtype):
    """A contiguous, writable array: numba compiles a separate copy of every
    kernel for read-only arrays (a frozen Mesh's), which doubled the cold
    compile time of the triangulation."""
    out = np.ascontiguousarray(array, dtype=dtype)
    return out if out.flags.writeable else out.copy()


def _as_points(points):
    P = _writable(points, np.float64)
    if P.ndim != 2 or P.shape[1] != 2:
        raise GeometryError(f"points must be an (N, 2) array, got shape {P.shape}")
    bad = out_of_range(P)
    if bad.any():
        k = int(np.argmax(bad))
        raise GeometryError(f"point {k} = {out_of_range_message(P[k])}")
    return P


def _raise(status, what, where=""):
    msg = f"{what}: {_MESSAGES.get(status, status)}{where}"
    if status in (ERR_COLLINEAR, ERR_VERTEX_ON_SEGMENT):
        raise GeometryError(msg)
    raise MeshingError(msg)


def ghost_delaunay(points):
    """Delaunay triangulation with ghost triangles: (tri, nbr, con, vt, ntri,
    dup_of), arrays sized to capacity with the first ntri rows in use."""
    P = _as_points(points)
    n = P.shape[0]
    if n < 3:
        raise GeometryError(f"need at least 3 points, got {n}")
    cap = 2 * n + 8
    tri = np.empty((cap, 3), np.int64)
    nbr = np.empty((cap, 3), np.int64)
    con = np.zeros((cap, 3), np.uint8)
    vt = np.full(n, -1, np.int64)
    dup_of = np.full(n, -1, np.int64)
    status, ntri, bad = delaunay_kernel(P, hilbert_order(P), tri, nbr, con, vt, dup_of)
    if status != OK:
        _raise(status, "delaunay", f" (point {bad})" if bad >= 0 else "")
    return tri, nbr, con, vt, ntri, dup_of


def delaunay(points):
    """Unconstrained Delaunay triangulation of a point set, (M, 3) int64 CCW.

    Exact duplicates are left out of every triangle (as Qhull does).  Raises
    GeometryError for fewer than 3 points or when all points are collinear."""
    tri, _, _, _, ntri, _ = ghost_delaunay(points)
    real = (tri[:ntri] >= 0).all(axis=1)
    return np.ascontiguousarray(tri[:ntri][real])


def constrained_delaunay(points, segments):
    """Constrained Delaunay triangulation of the region enclosed by ``segments``
    (paper §2.1 and §3.5): triangles outside the outer loop and inside holes are
    removed by the parity of segments crossed from infinity.

    Returns (triangles (M,3) int64 CCW, neighbors (M,3) int64, -1 across the
    domain boundary)."""
    P = _as_points(points)
    S = _writable(segments, np.int64).reshape(-1, 2)
    if S.size and (S.min() < 0 or S.max() >= P.shape[0]):
        raise GeometryError("a segment refers to a point index out of range")
    # Stacks for a few thousand crossed edges per segment; a recovery that needs
    # more reruns the whole (deterministic) triangulation with 4x the room.
    capacity = min(4 * len(P) + 64, 1 << 16)
    for _ in range(8):
        tri, nbr, con, vt, ntri, dup_of = ghost_delaunay(P)
        dups = np.flatnonzero(dup_of >= 0)
        if dups.size:
            k = int(dups[0])
            raise GeometryError(f"point {k} duplicates point {int(dup_of[k])}")
        status, s, v = recover_segments(P, tri, nbr, con, vt, ntri, S, capacity)
        if status != ERR_STACK or capacity >= 4 * len(P) + 64:
            break
        capacity *= 4
    if status != OK:
        where = f" (segment {s} = {tuple(int(x) for x in S[s])}"
        where += f", vertex {v})" if status == ERR_VERTEX_ON_SEGMENT else ")"
        _raise(status, "constrained delaunay", where)
    keep = interior_mask(tri, nbr, con, ntri)
    return compact(tri[:ntri], nbr[:ntri], keep)
