"""Frontal insertion for the sized §2 of ``bubblemesh.mesh`` (not the paper).

The paper's §2 splits the triangle of lowest bubble density at its centroid
(eq. 5, §2.4 (c)-(d)).  Nodes then appear all over the domain at once, and
§3 has to relax a polycrystal: grains of good lattice meeting along seams
that its forces heal only slowly.  Here the same Bowyer-Watson insertion
(§2.2) advances a front from the boundary instead, in the manner of Rebay's
frontal Delaunay refinement:

- a triangle is *accepted* when its circumcircle is small against its
  element bubble (eq. 2-4 with the size field's h at the centroid):
  R_t <= ACCEPT h / sqrt(3), h / sqrt(3) the circumradius of the equilateral
  triangle of side h, relaxed by ACCEPT (WALL_ACCEPT, stricter, on the walls);
- a triangle that is not accepted is *active* when one of its edges is on
  the boundary (or an interior constraint) or is shared with an accepted
  triangle: the front;
- the active triangles on the walls come first, so every boundary edge
  gets its own first-row node, then the active triangle whose circumcircle
  is largest against its bubble (a heap, as §2.4 (c)); a node goes on the
  perpendicular bisector of its front edge ab, inside it, at the apex of the
  isosceles triangle on ab whose circumradius is h(midpoint) / sqrt(3) (the
  equilateral apex when |ab| = h), at most at the triangle's circumcentre;
- that node is inserted by the cavity of §2.2 grown from the triangle that
  holds it, reached by a walk that never crosses the boundary; where it
  cannot be placed so (outside the domain, on a node, not in the active
  triangle's circumcircle), the centroid is inserted as in the paper;
- a triangle with two edges on the walls whose angle between them is wider
  than CORNER_OPEN is active however small it is (one triangle cannot fill
  such a corner well: where the walls are split finer than the field, it
  would be accepted), and its node goes on the corner's bisector, as far
  from the corner as the two walls are long on average;
- a node that would come closer than CROWD h to one of its neighbours is
  not inserted: its triangle counts as accepted, the front moves on.  So
  nodes keep at least CROWD times the smallest h apart, which bounds the
  number of insertions whatever the input;
- the run stops when no triangle is active: every triangle meets its bubble.

Rows of nearly equilateral triangles grow from every wall and meet in a
seam, so §3 starts from an almost perfect lattice.  Decisions are exact
(orientation and in-circle), the order is the heap's (key, id): the run is
deterministic.
"""

import math

import numpy as np
from numba import njit, prange

from ._cavity import fill_cavity, find_cavity, in_conflict
from ._insertion import (
    S_CAVITY,
    S_HEAP,
    S_INSERTIONS,
    S_NPTS,
    S_NTRI,
    S_STAMP,
    UNSPLITTABLE,
    _accumulate,
    _bubble_area,
)
from ._queue import heap_pop, heap_push
from ._status import CHUNK_DONE, NEED_CAPACITY, OK, STOP_MAX_INSERTIONS, STOP_POPULATION
from .bubbles import triangle_area
from .memory import unsigned
from .predicates import orient2d
from .sizing import field_at

ACCEPT = 1.35  # circumradius over the equilateral one at which a triangle is accepted
WALL_ACCEPT = 1.2  # the same on the walls
WALL_FIRST = 4.0  # heap keys of wall triangles drop by this: below every other active key
WALK_STEPS = 64  # a frontal node lies next to its triangle: a longer walk gives up
CROWD = 0.35  # no new node closer than this times h to a neighbour
SQRT3 = math.sqrt(3.0)
CORNER_OPEN = 100.0  # degrees: a corner triangle wider than this gets a node on its bisector
OPEN_KEY = 0.5  # the key of such a triangle: active, whatever its size
KEY_BLOCK = 4096  # initial triangles keyed per parallel block


@njit(cache=True, inline="always")
def _circumcentre(ax, ay, bx, by, cx, cy):
    """Circumcentre of triangle abc (counter-clockwise); NaN where its area
    rounds to 0 here (the centre is then at infinity)."""
    bx, by, cx, cy = bx - ax, by - ay, cx - ax, cy - ay
    d = 2.0 * (bx * cy - by * cx)
    if d == 0.0:
        return math.nan, math.nan
    b2, c2 = bx * bx + by * by, cx * cx + cy * cy
    return ax + (cy * b2 - by * c2) / d, ay + (bx * c2 - cx * b2) / d


@njit(cache=True)
def frontal_key(P, tri, nbr, t, r_e, factor, field, stack, limits):
    """Element bubble of triangle t (r_e = factor h(centroid), stored) and its
    key: the equilateral circumradius h / sqrt(3) over t's circumradius, over
    the threshold (ACCEPT; WALL_ACCEPT for a triangle on the boundary, with h
    at least its longest boundary edge: the best a fixed edge allows), so t is
    accepted from 1 up.  Small keys come first; inf for a sliver whose
    floating-point area is 0 (never split: nothing to fill)."""
    a = unsigned(tri[t, 0])
    b = unsigned(tri[t, 1])
    c = unsigned(tri[t, 2])
    ex = (P[a, 0] + P[b, 0] + P[c, 0]) / 3.0
    ey = (P[a, 1] + P[b, 1] + P[c, 1]) / 3.0
    h = field_at(ex, ey, stack, *field)
    r_e[t] = factor * h
    area = triangle_area(P[a, 0], P[a, 1], P[b, 0], P[b, 1], P[c, 0], P[c, 1])
    if area <= 0.0:
        return math.inf
    la = math.sqrt((P[b, 0] - P[c, 0]) ** 2 + (P[b, 1] - P[c, 1]) ** 2)
    lb = math.sqrt((P[c, 0] - P[a, 0]) ** 2 + (P[c, 1] - P[a, 1]) ** 2)
    lc = math.sqrt((P[a, 0] - P[b, 0]) ** 2 + (P[a, 1] - P[b, 1]) ** 2)
    threshold = limits[0]
    if on_wall(nbr, t):
        threshold = limits[1]
        for k, length in ((0, la), (1, lb), (2, lc)):
            if nbr[t, k] < 0:
                h = max(h, length)
    key = (h / SQRT3) / (la * lb * lc / (4.0 * area)) * threshold
    if key >= 1.0 and open_corner(P, tri, nbr, t, limits[2]) >= 0:
        return OPEN_KEY
    return key


@njit(cache=True)
def open_corner(P, tri, nbr, t, cos_open):
    """Slot of t's corner node v when two of t's edges are on the walls and
    its angle at v is wider than the one whose cosine is ``cos_open``, else
    -1.  One triangle cannot fill such a corner well (an isosceles one of
    apex angle 100 degrees has a radius ratio of 0.72, of 120 degrees 0.46):
    it needs a node inside, on the bisector."""
    k = -1
    walls = 0
    for j in range(3):
        if nbr[t, j] < 0:
            walls += 1
        else:
            k = j
    if walls != 2:
        return -1
    v = unsigned(tri[t, k])
    a = unsigned(tri[t, (k + 1) % 3])
    b = unsigned(tri[t, (k + 2) % 3])
    ux, uy = P[a, 0] - P[v, 0], P[a, 1] - P[v, 1]
    wx, wy = P[b, 0] - P[v, 0], P[b, 1] - P[v, 1]
    norms = math.sqrt((ux * ux + uy * uy) * (wx * wx + wy * wy))
    return k if ux * wx + uy * wy < cos_open * norms else -1


@njit(cache=True)
def corner_point(P, tri, t, k):
    """The node for t's open corner v (slot k): on the bisector of its angle,
    as far from v as its two walls' mean length.  Returns (x, y)."""
    v = unsigned(tri[t, k])
    a = unsigned(tri[t, (k + 1) % 3])
    b = unsigned(tri[t, (k + 2) % 3])
    la = math.hypot(P[a, 0] - P[v, 0], P[a, 1] - P[v, 1])
    lb = math.hypot(P[b, 0] - P[v, 0], P[b, 1] - P[v, 1])
    bx = (P[a, 0] - P[v, 0]) / la + (P[b, 0] - P[v, 0]) / lb
    by = (P[a, 1] - P[v, 1]) / la + (P[b, 1] - P[v, 1]) / lb
    reach = 0.5 * (la + lb) / math.hypot(bx, by)
    return P[v, 0] + bx * reach, P[v, 1] + by * reach


@njit(cache=True, inline="always")
def on_wall(nbr, t):
    """Has t an edge on the boundary (or an interior constraint)?"""
    return nbr[t, 0] < 0 or nbr[t, 1] < 0 or nbr[t, 2] < 0


@njit(cache=True, inline="always")
def heap_key(nbr, density, t):
    """t's place in the queue: triangles on the walls first (their keys are
    below 1 while active), so every boundary edge gets its own row node."""
    return density[t] - WALL_FIRST if on_wall(nbr, t) else density[t]


@njit(cache=True, inline="always")
def _accepted(density, t):
    """Keys are scaled so that a triangle is accepted from 1 up (:func:`frontal_key`)."""
    return density[unsigned(t)] >= 1.0


@njit(cache=True)
def front_edge(tri, nbr, density, t):
    """Slot k of t's front edge (opposite its k-th node): the first edge on the
    boundary or shared with an accepted triangle, -1 if none (t not active).
    The boundary comes before accepted neighbours: a wall row starts from the wall."""
    found = -1
    for k in range(3):
        n = nbr[t, k]
        if n < 0:
            return k
        if found < 0 and _accepted(density, n):
            found = k
    return found


@njit(cache=True)
def frontal_point(P, t, tri, k, h):
    """The node for front edge ab of t (slot k, so t = (c, a, b) counter-
    clockwise): on the bisector of ab inside t, at the apex of the isosceles
    triangle on ab of circumradius max(h / sqrt(3), |ab| / 2), no farther than
    the top of the circle through a, b and t's circumcentre (the circumcentre
    itself when that lies at least |ab| / 2 inside, Rebay's bound).
    Returns (x, y)."""
    c = unsigned(tri[t, k])
    a = unsigned(tri[t, (k + 1) % 3])
    b = unsigned(tri[t, (k + 2) % 3])
    mx = 0.5 * (P[a, 0] + P[b, 0])
    my = 0.5 * (P[a, 1] + P[b, 1])
    ux = P[b, 0] - P[a, 0]
    uy = P[b, 1] - P[a, 1]
    length = math.sqrt(ux * ux + uy * uy)
    nx, ny = -uy / length, ux / length  # into t: t lies left of a -> b
    p = 0.5 * length
    ox, oy = _circumcentre(P[c, 0], P[c, 1], P[a, 0], P[a, 1], P[b, 0], P[b, 1])
    q = (ox - mx) * nx + (oy - my) * ny
    rho = max(h / SQRT3, p)
    if q > 0.0:  # False for NaN: no circle bounds a flat triangle's node
        rho = min(rho, (p * p + q * q) / (2.0 * q))
    d = rho + math.sqrt(max(rho * rho - p * p, 0.0))
    return mx + d * nx, my + d * ny


@njit(cache=True)
def walk_to(P, tri, nbr, t, x, y, steps):
    """The triangle whose closure holds (x, y), walking from t across the
    edges that (x, y) lies beyond (exact orientation); -1 if the walk meets the
    boundary or an interior constraint, if (x, y) is a node or lies on the
    boundary, or after ``steps`` steps.  A point on an interior edge is fine:
    both triangles at that edge hold it in their circumcircles."""
    for _ in range(steps):
        zeros = 0
        on = -1
        moved = False
        for j in range(3):
            u = unsigned(tri[t, (j + 1) % 3])
            v = unsigned(tri[t, (j + 2) % 3])
            o = orient2d(P[u, 0], P[u, 1], P[v, 0], P[v, 1], x, y)
            if o < 0.0:
                t = nbr[t, j]
                if t < 0:
                    return -1
                moved = True
                break
            if o == 0.0:
                zeros += 1
                on = j
        if not moved:
            if zeros > 1 or (zeros == 1 and nbr[t, on] < 0):
                return -1  # on a node, or on the boundary
            return t
    return -1


@njit(cache=True)
def _centroid_inside(P, tri, t):
    """t's centroid if it lies strictly inside t in exact arithmetic (not a
    floating-point sliver), else (nan, nan)."""
    a = unsigned(tri[t, 0])
    b = unsigned(tri[t, 1])
    c = unsigned(tri[t, 2])
    ex = (P[a, 0] + P[b, 0] + P[c, 0]) / 3.0
    ey = (P[a, 1] + P[b, 1] + P[c, 1]) / 3.0
    if (orient2d(P[a, 0], P[a, 1], P[b, 0], P[b, 1], ex, ey) <= 0.0
            or orient2d(P[b, 0], P[b, 1], P[c, 0], P[c, 1], ex, ey) <= 0.0
            or orient2d(P[c, 0], P[c, 1], P[a, 0], P[a, 1], ex, ey) <= 0.0):
        return math.nan, math.nan
    return ex, ey


@njit(cache=True)
def _is_active(tri, nbr, density, t):
    return not _accepted(density, t) and front_edge(tri, nbr, density, t) >= 0


@njit(cache=True)
def init_front(P, tri, nbr, ntri, r_e, density, keys, ids, acc, factor, field, stack, limits):
    """Bubbles and keys of the initial triangles, sum A_e, and the heap of the
    active ones.  Returns the heap size."""
    _initial_keys(P, tri, nbr, ntri, r_e, density, factor, field, stack.shape[0], limits)
    for t in range(ntri):  # in order: the same sum on any thread count
        _accumulate(acc, _bubble_area(r_e, t))
    size = 0
    for t in range(ntri):
        if _is_active(tri, nbr, density, t):
            size = heap_push(keys, ids, size, heap_key(nbr, density, t), t)
    return size


@njit(cache=True, parallel=True)
def _initial_keys(P, tri, nbr, ntri, r_e, density, factor, field, depth, limits):
    """:func:`frontal_key` of each initial triangle, in blocks of KEY_BLOCK
    with a field stack of ``depth`` each."""
    for block in prange((ntri + KEY_BLOCK - 1) // KEY_BLOCK):
        stack = np.full(depth, -1, np.int64)
        for t in range(block * KEY_BLOCK, min(ntri, (block + 1) * KEY_BLOCK)):
            density[t] = frontal_key(P, tri, nbr, t, r_e, factor, field, stack, limits)


@njit(cache=True)
def _rebuild_front(tri, nbr, ntri, density, keys, ids):
    """Drop stale heap entries: push every active triangle afresh."""
    size = 0
    for t in range(ntri):
        if density[t] != UNSPLITTABLE and _is_active(tri, nbr, density, t):
            size = heap_push(keys, ids, size, heap_key(nbr, density, t), t)
    return size


@njit(cache=True)
def _place(P, tri, nbr, t, density, field, stack):
    """Where t is split and from which triangle the cavity grows: the frontal
    node (module docstring) or, failing that, t's centroid.  Returns
    (x, y, start triangle); start -1 when t cannot be split at all."""
    if density[t] == OPEN_KEY:
        c = open_corner(P, tri, nbr, t, -2.0)  # any angle: the key says it is open
        if c >= 0:
            x, y = corner_point(P, tri, t, c)
            if in_conflict(P, tri, t, x, y):
                s = walk_to(P, tri, nbr, t, x, y, WALK_STEPS)
                if s >= 0:
                    return x, y, s
    k = front_edge(tri, nbr, density, t)
    a = unsigned(tri[t, (k + 1) % 3])
    b = unsigned(tri[t, (k + 2) % 3])
    mx = 0.5 * (P[a, 0] + P[b, 0])
    my = 0.5 * (P[a, 1] + P[b, 1])
    h = field_at(mx, my, stack, *field)
    x, y = frontal_point(P, t, tri, k, h)
    if in_conflict(P, tri, t, x, y):
        s = walk_to(P, tri, nbr, t, x, y, WALK_STEPS)
        if s >= 0:
            return x, y, s
    x, y = _centroid_inside(P, tri, t)
    if x != x:
        return x, y, -1
    return x, y, t


@njit(cache=True)
def frontal_loop(P, R, tri, nbr, con, vt, r_e, density, keys, ids, state, acc, max_insertions,
                 chunk, mark, cav, bnd, newt, vstart, factor, field, stack, limits):
    """Frontal insertions (module docstring) until no triangle is active,
    ``max_insertions``, a full array or ``chunk`` insertions; all state in the
    arrays, as :func:`bubblemesh._insertion.insertion_loop`.  ``limits``:
    (ACCEPT, WALL_ACCEPT).  Returns a status: STOP_POPULATION when the front
    has closed."""
    npts = state[S_NPTS]
    ntri = state[S_NTRI]
    size = state[S_HEAP]
    done = 0
    status = OK
    while True:
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
            size = _rebuild_front(tri, nbr, ntri, density, keys, ids)
            if size + ntri + 2 > keys.shape[0]:
                status = NEED_CAPACITY
                break
        t = -1
        while size > 0:
            size = heap_pop(keys, ids, size)
            cand = ids[size]
            live = keys[size] == heap_key(nbr, density, cand)
            if live and _is_active(tri, nbr, density, cand):
                t = cand
                break
        if t < 0:
            status = STOP_POPULATION  # the front has closed
            break
        x, y, s = _place(P, tri, nbr, t, density, field, stack)
        if s < 0:
            density[t] = UNSPLITTABLE
            continue
        state[S_STAMP] += 1
        ncav, nb = find_cavity(P, x, y, s, tri, nbr, con, mark, state[S_STAMP], cav, bnd)
        if ntri + nb - ncav > tri.shape[0] or size + nb + 3 > keys.shape[0]:
            size = heap_push(keys, ids, size, heap_key(nbr, density, t), t)  # retried first
            status = NEED_CAPACITY
            break
        h = field_at(x, y, stack, *field)
        if _crowded(P, bnd, nb, x, y, CROWD * h):
            # no node this close to another: t stays as it is, and the front
            # moves on past it (this also bounds the run: nodes keep apart)
            density[t] = 1.0
            size = _activate_around(tri, nbr, density, keys, ids, size, t)
            continue
        P[npts, 0] = x
        P[npts, 1] = y
        R[npts] = factor * h
        for j in range(ncav):  # the cavity's bubbles leave the sum (their slots are reused)
            _accumulate(acc, -_bubble_area(r_e, cav[j]))
        status, ntri_new = fill_cavity(P, npts, tri, nbr, con, vt, ntri, cav, ncav, bnd, nb,
                                       vstart, newt)
        if status != OK:
            break
        state[S_CAVITY] += ncav
        ntri = ntri_new
        npts += 1
        size = _enter_new(P, tri, nbr, r_e, density, keys, ids, size, acc, newt, nb, factor,
                          field, stack, limits)
        state[S_INSERTIONS] += 1
        done += 1
    state[S_NPTS] = npts
    state[S_NTRI] = ntri
    state[S_HEAP] = size
    return status


@njit(cache=True)
def _crowded(P, bnd, nb, x, y, reach):
    """Is a node of the cavity's boundary (the new node's neighbours to be)
    closer than ``reach`` to (x, y)?"""
    for k in range(nb):
        v = bnd[k, 0]
        if v >= 0 and (P[v, 0] - x) ** 2 + (P[v, 1] - y) ** 2 < reach * reach:
            return True
    return False


@njit(cache=True)
def _activate_around(tri, nbr, density, keys, ids, size, t):
    """t was just accepted: its neighbours that are not become active."""
    for k in range(3):
        n = nbr[t, k]
        if n >= 0 and density[n] != UNSPLITTABLE and not _accepted(density, n):
            size = heap_push(keys, ids, size, heap_key(nbr, density, n), n)
    return size


@njit(cache=True)
def _enter_new(P, tri, nbr, r_e, density, keys, ids, size, acc, newt, nb, factor, field,
               stack, limits):
    """Keys of the new triangles; the active ones enter the heap, and so do
    the outside neighbours an accepted new triangle makes active."""
    for j in range(nb):
        s = newt[j]
        density[s] = frontal_key(P, tri, nbr, s, r_e, factor, field, stack, limits)
        _accumulate(acc, _bubble_area(r_e, s))
    for j in range(nb):
        s = newt[j]
        if _accepted(density, s):
            n = nbr[s, 2]  # across the cavity's boundary edge (fill_cavity's slot 2)
            if n >= 0 and density[n] != UNSPLITTABLE and not _accepted(density, n):
                size = heap_push(keys, ids, size, heap_key(nbr, density, n), n)
        elif front_edge(tri, nbr, density, s) >= 0:
            size = heap_push(keys, ids, size, heap_key(nbr, density, s), s)
    return size
