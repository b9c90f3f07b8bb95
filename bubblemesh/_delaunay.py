"""Unconstrained Delaunay triangulation by incremental cavity insertion in
Hilbert order (the kernel behind §2.1's boundary triangulation and §3.5's
re-triangulation, before the segments are recovered)."""

import numpy as np
from numba import njit

from ._cavity import GHOST, fill_cavity, find_cavity, is_ghost, locate, orient
from ._status import ERR_COLLINEAR, ERR_WALK, OK


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
        if orient(P, i0, i1, q) != 0.0:
            i2 = q
            break
    if i2 < 0:
        return ERR_COLLINEAR, -1, -1, -1
    if orient(P, i0, i1, i2) < 0.0:
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
