"""Bowyer-Watson cavity insertion (paper §2.2, Fig. 1), shared by every stage.

The cavity of a new point is grown from a triangle that contains it, through
neighbours whose circumcircle strictly contains it, never across a constrained
(boundary) edge, and is re-filled by joining the point to the cavity's
boundary edges.  The same two kernels build the unconstrained Delaunay
triangulation, the boundary CDT of §2.1, the §2 insertions and the §3.5
re-triangulation.

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

All predicates are exact (``predicates``), so each decision is the real one;
every loop has a bound and failures are status codes (``_status``).
"""

from numba import njit

from ._status import ERR_CAPACITY, ERR_NOT_STAR, OK
from .memory import unsigned
from .predicates import incircle, orient2d

GHOST = -1


@njit(cache=True, inline="always")
def orient(P, u, v, w):
    return orient2d(P[u, 0], P[u, 1], P[v, 0], P[v, 1], P[w, 0], P[w, 1])


@njit(cache=True, inline="always")
def orient_point(P, u, v, px, py):
    return orient2d(P[u, 0], P[u, 1], P[v, 0], P[v, 1], px, py)


@njit(cache=True, inline="always")
def is_ghost(tri, t):
    return tri[t, 0] < 0 or tri[t, 1] < 0 or tri[t, 2] < 0


@njit(cache=True, inline="always")
def strictly_between(P, u, v, px, py):
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
    o = orient_point(P, u, v, px, py)
    if o > 0.0:
        return True
    if o < 0.0:
        return False
    return strictly_between(P, u, v, px, py)


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
            if orient_point(P, u, v, px, py) < 0.0:
                t = nbr[t, j]
                moved = True
                break
        if not moved:
            return t
    return -1


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
        if u >= 0 and v >= 0 and orient_point(P, unsigned(u), unsigned(v), px, py) <= 0.0:
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
