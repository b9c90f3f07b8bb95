"""The §2 insertion kernel: steps (b)-(f) of §2.4 on flat arrays.

(b) element bubbles at the centroids (eq. 3-4) and densities D_e = A_e / A_m
    (eq. 5); (c) the triangle of smallest density from the queue (``_queue``);
(d) a node at its centroid with the element bubble's radius r_e; (e) cavity
insertion grown from that triangle (``_cavity``), the new triangles' bubbles
into the queue; (f) stop when sum A_e >= A_geo (eq. 6), the sum kept with an
error-free two-sum.  All state lives in the arrays (``state``'s slots), so the
driver can grow them and call again.

Sized mode (``bubblemesh.mesh``, not the paper): with ``capped`` true, r_e is
``factor`` h(centroid) for a size field h passed as ``field``
(:meth:`bubblemesh.sizing.SizeField.kernel_args`) instead of eq. 3's
interpolation, so eq. 6 populates the domain to the field (which starts from
the boundary spacing and grows at its gradation).  With ``capped`` false the
kernel computes exactly the paper's eq. 3.
"""

import math

from numba import njit

from ._cavity import fill_cavity, find_cavity
from ._queue import heap_pop, heap_push
from ._status import (
    CHUNK_DONE,
    ERR_EMPTY_QUEUE,
    NEED_CAPACITY,
    OK,
    STOP_MAX_INSERTIONS,
    STOP_POPULATION,
)
from .bubbles import element_radius, triangle_area
from .memory import prefetch, unsigned
from .predicates import orient2d
from .sizing import field_at

# integer state slots
S_NPTS, S_NTRI, S_HEAP, S_INSERTIONS, S_STAMP, S_CAVITY = range(6)
UNSPLITTABLE = -1.0  # density mark of a triangle too thin to split; no D_e is negative


@njit(cache=True, inline="always")
def _prefetch_record(density, t):
    """Start loading triangle t's record (``density`` is one of its fields)."""
    if t >= 0:
        prefetch(density, t)


@njit(cache=True, inline="always")
def _prefetch_around(R, tri, nbr, density, t):
    """Start loading the records of t's nodes and neighbours, which the
    cavity search from t reads first."""
    for k in range(3):
        prefetch(R, tri[t, k])
        _prefetch_record(density, nbr[t, k])


@njit(cache=True, inline="always")
def _prefetch_second_ring(R, tri, nbr, density, t):
    """Then the nodes and neighbours of t's neighbours (their records must
    have arrived): what the cavity search reads next."""
    for k in range(3):
        n = nbr[t, k]
        if n >= 0:
            _prefetch_around(R, tri, nbr, density, n)


@njit(cache=True, inline="always")
def _prefetch_third_ring_nodes(R, tri, nbr, t):
    """Last, the nodes of the triangles two steps from t (whose records the
    second ring requested): the in-circle tests of a larger cavity read them."""
    for k in range(3):
        n = nbr[t, k]
        if n >= 0:
            for q in range(3):
                m = nbr[n, q]
                if m >= 0 and m != t:
                    for r in range(3):
                        prefetch(R, tri[m, r])


@njit(cache=True)
def _bubble(P, R, tri, t, r_e, capped, field, factor, stack):
    """Eq. 3-5 for triangle t: stores r_e and returns D_e (inf for a sliver
    whose floating-point area is 0: nothing to fill, never split).  ``capped``:
    r_e is ``factor`` times the size field at the centroid instead."""
    a = unsigned(tri[t, 0])
    b = unsigned(tri[t, 1])
    c = unsigned(tri[t, 2])
    if capped:  # the field at the centroid (eq. 3's centroid, the same bits)
        ex = (P[a, 0] + P[b, 0] + P[c, 0]) / 3.0
        ey = (P[a, 1] + P[b, 1] + P[c, 1]) / 3.0
        r = factor * field_at(ex, ey, stack, *field)
    else:
        r = element_radius(
            P[a, 0], P[a, 1], R[a], P[b, 0], P[b, 1], R[b], P[c, 0], P[c, 1], R[c]
        )[0]
    r_e[t] = r
    area = triangle_area(P[a, 0], P[a, 1], P[b, 0], P[b, 1], P[c, 0], P[c, 1])
    if area == 0.0:
        return math.inf
    return _bubble_area(r_e, t) / area


@njit(cache=True, inline="always")
def _bubble_area(r_e, t):
    """A_e, eq. 4: recomputed from r_e rather than stored (one array less to
    miss in cache per cavity triangle)."""
    return math.pi * r_e[t] * r_e[t]


@njit(cache=True, inline="always")
def _accumulate(acc, x):
    """acc[0] + acc[1] += x without rounding loss (two-sum)."""
    s = acc[0] + x
    bv = s - acc[0]
    acc[1] += (acc[0] - (s - bv)) + (x - bv)
    acc[0] = s


@njit(cache=True)
def init_queue(P, R, tri, ntri, r_e, density, keys, ids, acc, capped, field, factor, stack):
    """Step (b): bubbles of the initial triangles, their sum, the queue."""
    size = 0
    for t in range(ntri):
        density[t] = _bubble(P, R, tri, t, r_e, capped, field, factor, stack)
        _accumulate(acc, _bubble_area(r_e, t))
        size = heap_push(keys, ids, size, density[t], t)
    return size


@njit(cache=True)
def _rebuild_queue(ntri, density, keys, ids):
    """Drop stale heap entries: push every live, splittable triangle afresh."""
    size = 0
    for t in range(ntri):
        if density[t] != UNSPLITTABLE:
            size = heap_push(keys, ids, size, density[t], t)
    return size


@njit(cache=True)
def insertion_loop(
    P, R, tri, nbr, con, vt, r_e, density, keys, ids,
    state, acc, area_geo, max_insertions, chunk,
    mark, cav, bnd, newt, vstart, capped, field, factor, stack,
):
    """Steps (c)-(f) until eq. 6, ``max_insertions``, a full array or ``chunk``
    insertions.  All state lives in the arrays, so the caller can grow them and
    call again.  Returns a status code."""
    npts = state[S_NPTS]
    ntri = state[S_NTRI]
    size = state[S_HEAP]
    done = 0
    status = OK
    while True:
        if acc[0] + acc[1] >= area_geo:
            status = STOP_POPULATION
            break
        if state[S_INSERTIONS] >= max_insertions:
            status = STOP_MAX_INSERTIONS
            break
        if done >= chunk:
            status = CHUNK_DONE
            break
        if npts >= P.shape[0] or ntri + 2 > tri.shape[0]:
            status = NEED_CAPACITY
            break
        if size + ntri + 2 > keys.shape[0]:
            size = _rebuild_queue(ntri, density, keys, ids)
            if size + ntri + 2 > keys.shape[0]:
                status = NEED_CAPACITY
                break
        # (c) the live triangle of smallest density
        t = -1
        while size > 0:
            _prefetch_record(density, ids[0])  # read by the staleness test below
            size = heap_pop(keys, ids, size)
            cand = ids[size]
            if keys[size] == density[cand]:  # else stale (or UNSPLITTABLE)
                t = cand
                break
        if t < 0:
            status = ERR_EMPTY_QUEUE
            break
        # The next triangle to split is probably the heap's top (99% of the
        # time at 1M): its record, then its neighbourhood ring by ring load
        # during this insertion (prefetching; results do not depend on it).
        if size > 0:
            _prefetch_record(density, ids[0])
        # (d) its centroid, which must be strictly inside it in exact arithmetic
        a = unsigned(tri[t, 0])
        b = unsigned(tri[t, 1])
        c = unsigned(tri[t, 2])
        ex = (P[a, 0] + P[b, 0] + P[c, 0]) / 3.0
        ey = (P[a, 1] + P[b, 1] + P[c, 1]) / 3.0
        if (
            orient2d(P[a, 0], P[a, 1], P[b, 0], P[b, 1], ex, ey) <= 0.0
            or orient2d(P[b, 0], P[b, 1], P[c, 0], P[c, 1], ex, ey) <= 0.0
            or orient2d(P[c, 0], P[c, 1], P[a, 0], P[a, 1], ex, ey) <= 0.0
        ):
            density[t] = UNSPLITTABLE  # too thin to split in floating point: leave it
            continue
        # (e) Bowyer-Watson insertion from t
        state[S_STAMP] += 1
        ncav, nb = find_cavity(P, ex, ey, t, tri, nbr, con, mark, state[S_STAMP], cav, bnd)
        state[S_CAVITY] += ncav
        # stale entries on top would be dropped by the next pop anyway: drop
        # them now, so that the top is a live triangle worth prefetching
        while size > 0 and keys[0] != density[ids[0]]:
            size = heap_pop(keys, ids, size)
            if size > 0:
                _prefetch_record(density, ids[0])
        nxt = ids[0] if size > 0 and mark[ids[0]] != state[S_STAMP] else -1  # not doomed
        if nxt >= 0:
            _prefetch_around(R, tri, nbr, density, nxt)
        if ntri + nb - ncav > tri.shape[0] or size + nb > keys.shape[0]:
            size = heap_push(keys, ids, size, density[t], t)  # put t back: retried first
            status = NEED_CAPACITY
            break
        P[npts, 0] = ex
        P[npts, 1] = ey
        R[npts] = r_e[t]
        for k in range(ncav):
            _accumulate(acc, -_bubble_area(r_e, cav[k]))
        status, ntri_new = fill_cavity(
            P, npts, tri, nbr, con, vt, ntri, cav, ncav, bnd, nb, vstart, newt
        )
        if status != OK:
            break
        ntri = ntri_new
        npts += 1
        if nxt >= 0:
            _prefetch_second_ring(R, tri, nbr, density, nxt)
        for k in range(nb):
            s = newt[k]
            density[s] = _bubble(P, R, tri, s, r_e, capped, field, factor, stack)
            _accumulate(acc, _bubble_area(r_e, s))
            size = heap_push(keys, ids, size, density[s], s)
        if nxt >= 0:
            _prefetch_third_ring_nodes(R, tri, nbr, nxt)
        state[S_INSERTIONS] += 1
        done += 1
    state[S_NPTS] = npts
    state[S_NTRI] = ntri
    state[S_HEAP] = size
    return status
