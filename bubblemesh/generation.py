"""Automatic Delaunay mesh generation: paper §2, steps (a)-(f) of §2.4.

(a) constrained Delaunay triangulation of the refined boundary (§2.1);
(b) node bubbles on the boundary (eq. 1-2), element bubbles at the centroids
    (eq. 3-4) and bubble densities D_e = A_e / A_m (eq. 5);
(c) take the triangle of smallest density from a priority queue (a 4-ary heap
    of (D_e, triangle id) with lazy invalidation: an entry is live only while
    its key equals the current density of its triangle slot; a re-used slot
    leaves its old entries to be skipped when popped (an old entry whose key
    happens to equal the new density stands for the new triangle exactly);
    ties are broken by the smaller triangle id, so the run is deterministic);
(d) create a node at its centroid, with the element bubble's radius r_e;
(e) insert it by Bowyer-Watson (§2.2): the cavity grows from that triangle
    through neighbours whose circumcircle contains the node, never across the
    boundary; the new triangles get their bubbles and enter the queue;
(f) stop the first time the total element-bubble area reaches the domain area,
    sum A_e >= A_geo (eq. 6); sum A_e is kept incrementally with an error-free
    (two-sum) accumulator.

A bound that always holds: every r_e interpolates radii that are >= the
smallest boundary radius r_min, each insertion adds two triangles, so eq. 6
holds after at most A_geo / (2 pi r_min^2) + 1 insertions.  Going past that
bound raises MeshingError instead of looping.
"""

import math

import numpy as np
from numba import njit, prange

from .bubbles import boundary_radii, element_radius, triangle_area
from .errors import MeshingError
from .memory import prefetch, unsigned
from .mesh import Mesh
from .predicates import orient2d
from .timing import PhaseClock
from .triangulation import (
    _MESSAGES,
    OK,
    constrained_delaunay,
    fill_cavity,
    find_cavity,
    hilbert_order,
)

# kernel status codes (beyond the triangulation's)
STOP_POPULATION = 1  # eq. 6 reached
STOP_MAX_INSERTIONS = 2  # the caller's max_insertions reached
NEED_CAPACITY = 3  # arrays full: the caller grows them and resumes
CHUNK_DONE = 4  # a progress chunk is done: the caller reports and resumes
ERR_EMPTY_QUEUE = -20

# initial triangle capacity, as a multiple of the expected count (arrays double
# when full, so this only trades memory against copies)
INITIAL_CAPACITY = 1.1

# integer state slots
S_NPTS, S_NTRI, S_HEAP, S_INSERTIONS, S_STAMP, S_CAVITY = range(6)


# --- 4-ary heap of (key, id) pairs, ordered by key then id ----------------------------
# Keys and ids are two arrays: a sift compares keys only (ids break exact ties),
# so each level reads the 4 children's keys, 32 bytes in one cache line.  The
# heap waits on memory at 1M elements: this layout made its operations ~35%
# faster than (key, id) rows of 16 bytes (a replay of a 1M run's 4.1M
# operations: 0.58 s -> 0.37 s).

INT32_MAX = int(np.iinfo(np.int32).max)  # above it, ids are int64
UNSPLITTABLE = -1.0  # density mark of a triangle too thin to split; no D_e is negative
HEAP_ARITY = 4  # half the depth of a binary heap


@njit(cache=True, inline="always")
def _before(key, ident, other_key, other_ident):
    return key < other_key or (key == other_key and ident < other_ident)


@njit(cache=True)
def heap_push(keys, ids, size, key, ident):
    """Add (key, ident): a hole rises from the end to its place."""
    i = size
    while i > 0:
        parent = (i - 1) // HEAP_ARITY
        p = unsigned(parent)
        if not _before(key, ident, keys[p], ids[p]):
            break
        keys[unsigned(i)] = keys[p]
        ids[unsigned(i)] = ids[p]
        i = parent
    keys[i] = key
    ids[i] = ident
    return size + 1


@njit(cache=True, inline="always")
def _entry_before(keys, ids, a, b):
    """Does heap entry a come before entry b?"""
    ua = unsigned(a)
    ub = unsigned(b)
    return _before(keys[ua], ids[ua], keys[ub], ids[ub])


@njit(cache=True)
def heap_pop(keys, ids, size):
    """Move the smallest pair to ``size - 1`` and restore the heap: the last
    pair sinks from the root through a hole to its place."""
    size -= 1
    top_key = keys[0]
    top_id = ids[0]
    key = keys[size]
    ident = ids[size]
    i = 0
    while True:
        first = HEAP_ARITY * i + 1
        if first >= size:
            break
        # the next level's keys (all 16 grandchildren, at most 3 cache lines)
        # start loading while this level's comparisons wait for theirs
        grand = HEAP_ARITY * first + 1
        if grand < size:
            last = min(grand + HEAP_ARITY * HEAP_ARITY, size) - 1
            prefetch(keys, grand)
            prefetch(keys, (grand + last) // 2)
            prefetch(keys, last)
        prefetch(ids, first)  # read on ties and by the move below
        child = first
        for c in range(first + 1, min(first + HEAP_ARITY, size)):
            if _entry_before(keys, ids, c, child):
                child = c
        u = unsigned(child)
        if not _before(keys[u], ids[u], key, ident):
            break
        keys[unsigned(i)] = keys[u]
        ids[unsigned(i)] = ids[u]
        i = child
    keys[i] = key
    ids[i] = ident
    keys[size] = top_key
    ids[size] = top_id
    return size


# --- the §2 kernel -------------------------------------------------------------------


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
def _bubble(P, R, tri, t, r_e):
    """Eq. 3-5 for triangle t: stores r_e and returns D_e."""
    a = unsigned(tri[t, 0])
    b = unsigned(tri[t, 1])
    c = unsigned(tri[t, 2])
    r, _, _ = element_radius(
        P[a, 0], P[a, 1], R[a], P[b, 0], P[b, 1], R[b], P[c, 0], P[c, 1], R[c]
    )
    r_e[t] = r
    area = triangle_area(P[a, 0], P[a, 1], P[b, 0], P[b, 1], P[c, 0], P[c, 1])
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
def init_queue(P, R, tri, ntri, r_e, density, keys, ids, acc):
    """Step (b): bubbles of the initial triangles, their sum, the queue."""
    size = 0
    for t in range(ntri):
        density[t] = _bubble(P, R, tri, t, r_e)
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
    mark, cav, bnd, newt, vstart,
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
            density[s] = _bubble(P, R, tri, s, r_e)
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


# --- Python driver -------------------------------------------------------------------


# Records: per triangle, every field the insertion loop touches shares one
# cache line (64 bytes with int32 ids); per node, its position, radius and the
# two id fields share half a line.  (name, dtype, byte offset, width).
_TRIANGLE_FIELDS = {
    np.int32: (64, [("tri", "i4", 0, 3), ("nbr", "i4", 12, 3), ("con", "i4", 24, 3),
                    ("mark", "i4", 36, 1), ("density", "f8", 40, 1), ("r_e", "f8", 48, 1)]),
    np.int64: (128, [("tri", "i8", 0, 3), ("nbr", "i8", 24, 3), ("con", "i8", 48, 3),
                     ("mark", "i8", 72, 1), ("density", "f8", 80, 1), ("r_e", "f8", 88, 1)]),
}
_NODE_FIELDS = {
    np.int32: (32, [("P", "f8", 0, 2), ("R", "f8", 16, 1), ("vt", "i4", 24, 1),
                    ("vstart", "i4", 28, 1)]),
    np.int64: (64, [("P", "f8", 0, 2), ("R", "f8", 16, 1), ("vt", "i8", 24, 1),
                    ("vstart", "i8", 32, 1)]),
}
_UNSET = {"nbr": -1, "vt": -1, "vstart": -1}  # initial value if not 0


def _records(rows, record_bytes, fields):
    """Zeroed, cache-line-aligned records; returns {name: strided view}."""
    buf = np.zeros(rows * record_bytes + 64, np.uint8)
    skip = -buf.ctypes.data % 64
    table = buf[skip:skip + rows * record_bytes].reshape(rows, record_bytes)
    views = {}
    for name, dtype, offset, width in fields:
        words = table.view(dtype)
        col = offset // words.itemsize
        views[name] = words[:, col:col + width] if width > 1 else words[:, col]
        if name in _UNSET:
            views[name][:] = _UNSET[name]
    return views


class _Workspace:
    """The growable arrays of one generation run (capacity doubles on demand).

    The loop waits on memory: each insertion visits a few triangles and nodes
    at random places of arrays far larger than the cache.  So a triangle's
    vertex and neighbour ids, constraint flags, cavity stamp, density and
    element bubble are one record (one cache line), and a node's position,
    radius and ids another; the kernels see them as strided views.  Ids and
    stamps are int32 (widened to int64 in the returned mesh); runs that could
    pass 2**31 - 1 use int64 records."""

    def __init__(self, points, radii, tri, nbr, n_cap, t_cap, wide=False):
        self.index = np.int64 if wide else np.int32
        self._allocate(n_cap, t_cap)
        n0, m0 = len(points), len(tri)
        self.P[:n0] = points
        self.R[:n0] = radii
        self.tri[:m0] = tri
        self.nbr[:m0] = nbr
        self.keys, self.ids = _heap_arrays(2 * t_cap, self.index)

    def _allocate(self, n_cap, t_cap):
        nodes = _records(n_cap + 1, *_NODE_FIELDS[self.index])  # + the ghost's vstart slot
        nodes["P"], nodes["R"], nodes["vt"] = (nodes[k][:n_cap] for k in ("P", "R", "vt"))
        triangles = _records(t_cap, *_TRIANGLE_FIELDS[self.index])
        for name, view in {**nodes, **triangles}.items():
            setattr(self, name, view)
        self.cav = np.zeros(t_cap, self.index)
        self.bnd = np.zeros((t_cap + 2, 4), self.index)
        self.newt = np.zeros(t_cap + 2, self.index)

    def grow(self):
        """Double every capacity, keeping contents (heap entries included)."""
        if self.index == np.int32 and not _fits_int32(2 * len(self.tri)):
            raise MeshingError("generation: more triangles than the id type holds")
        names = ("P", "R", "vt", "tri", "nbr", "con", "r_e", "density")
        old = {name: getattr(self, name) for name in names}
        self._allocate(2 * len(self.P), 2 * len(self.tri))
        for name in names:
            getattr(self, name)[: len(old[name])] = old[name]
        keys, ids = _heap_arrays(2 * len(self.keys), self.index)
        keys[: len(self.keys)] = self.keys
        ids[: len(self.ids)] = self.ids
        self.keys, self.ids = keys, ids

    def kernel_args(self):
        return (self.P, self.R, self.tri, self.nbr, self.con, self.vt, self.r_e, self.density,
                self.keys, self.ids)


def _heap_arrays(rows, index):
    """Zeroed heap keys and ids; keys[1] starts a cache line, so the keys of
    every group of children (4p+1 .. 4p+4) share one."""
    buf = np.zeros(rows + 8)
    skip = (-(buf.ctypes.data + 8) % 64) // 8 if buf.ctypes.data % 8 == 0 else 0
    return buf[skip:skip + rows], np.zeros(rows, index)


def _fits_int32(t_cap):
    """Ids, cavity stamps (one per insertion) and heap rows (2 t_cap) all stay
    below 4 t_cap."""
    return 4 * t_cap <= INT32_MAX


def _insertion_bound(domain_area, radii):
    """The a-priori bound on insertions (module docstring)."""
    r_min = float(radii.min())
    return int(math.ceil(domain_area / (2.0 * math.pi * r_min * r_min))) + 1


def generate(domain, *, max_insertions=None, progress=False):
    """Paper §2: the Delaunay mesh of ``domain`` with bubble-controlled node
    insertion, stopped by eq. 6.

    ``max_insertions`` stops earlier (after at most that many insertions), so the
    population criterion can be checked from outside.  ``progress`` shows a tqdm
    bar.  Returns a :class:`Mesh` whose ``stats`` hold ``insertions``,
    ``bubble_area`` (sum A_e), ``domain_area`` (A_geo) and ``stop`` ("population"
    or "max_insertions") and ``phases`` (seconds in boundary_cdt, setup,
    insertion, renumbering)."""
    if max_insertions is not None and int(max_insertions) < 0:
        raise ValueError(f"max_insertions must be >= 0, got {max_insertions}")
    clock = PhaseClock()
    points = np.asarray(domain.points, dtype=np.float64)
    tri, nbr = constrained_delaunay(points, domain.segments)  # (a)
    clock.lap("boundary_cdt")
    radii = boundary_radii(points, domain.loops)  # (b) eq. 1-2
    area_geo = float(domain.area)
    bound = _insertion_bound(area_geo, radii)
    limit = bound if max_insertions is None else min(int(max_insertions), bound)
    expected = int(area_geo / float(np.mean(math.pi * radii**2))) + len(tri)
    t_cap = max(64, int(INITIAL_CAPACITY * expected) + 2 * len(tri))
    wide = not _fits_int32(t_cap)
    ws = _Workspace(points, radii, tri, nbr, len(points) + t_cap // 2 + 16, t_cap, wide)
    acc = np.zeros(2)
    state = np.zeros(6, np.int64)
    state[S_NPTS] = len(points)
    state[S_NTRI] = len(tri)
    state[S_HEAP] = init_queue(ws.P, ws.R, ws.tri, len(tri), ws.r_e, ws.density,
                               ws.keys, ws.ids, acc)
    bar = _progress_bar(progress, expected // 2)
    clock.lap("setup")
    try:
        status = _run(ws, state, acc, area_geo, limit, bar)
    finally:
        if bar is not None:
            bar.close()
    clock.lap("insertion")
    if status == STOP_MAX_INSERTIONS and (max_insertions is None or limit < max_insertions):
        raise MeshingError(f"generation reached its insertion bound {bound} without eq. 6")
    mesh = _as_mesh(domain, ws, state, acc, radii, status)
    clock.lap("renumbering")
    mesh.stats["seconds"] = clock.total()
    mesh.stats["phases"] = clock.seconds
    return mesh


def _run(ws, state, acc, area_geo, limit, bar):
    """Call the kernel until it stops; every call inserts at least one node or
    follows a growth that did, so the loop ends within ``limit`` insertions."""
    chunk = 20000 if bar is not None else 1 << 62
    grown_without_progress = False
    while True:
        before = int(state[S_INSERTIONS])
        status = insertion_loop(*ws.kernel_args(), state, acc, area_geo, limit, chunk,
                                ws.mark, ws.cav, ws.bnd, ws.newt, ws.vstart)
        progressed = int(state[S_INSERTIONS]) > before
        if bar is not None:
            bar.update(int(state[S_INSERTIONS]) - before)
        if status == NEED_CAPACITY:
            if grown_without_progress and not progressed:
                raise MeshingError("generation: the arrays grew but no insertion followed")
            grown_without_progress = not progressed
            ws.grow()
        elif status == CHUNK_DONE:
            continue
        elif status < 0:
            message = "priority queue ran empty" if status == ERR_EMPTY_QUEUE else (
                _MESSAGES.get(status, status))
            raise MeshingError(f"generation: {message}")
        else:
            return status


def _progress_bar(progress, total):
    if not progress:
        return None
    from tqdm.auto import tqdm

    return tqdm(total=total, desc="generate (§2)", unit="node")


@njit(cache=True, parallel=True)
def _by_lowest_node(triangles, new_of_old):
    """Triangle order by their lowest renumbered node, ties in id order (a
    counting sort): triangles then follow the nodes' Hilbert order."""
    m = triangles.shape[0]
    lowest = np.empty(m, np.int64)
    first = np.zeros(new_of_old.shape[0] + 1, np.int64)
    for t in prange(m):
        if t + 16 < m:  # the random reads of a later iteration start now
            for j in range(3):
                prefetch(new_of_old, triangles[t + 16, j])
        lowest[t] = min(new_of_old[triangles[t, 0]], new_of_old[triangles[t, 1]],
                        new_of_old[triangles[t, 2]])
    for t in range(m):
        first[lowest[t] + 1] += 1
    for v in range(new_of_old.shape[0]):
        first[v + 1] += first[v]
    order = np.empty(m, np.int64)
    for t in range(m):
        order[first[lowest[t]]] = t
        first[lowest[t]] += 1
    return order


@njit(cache=True, parallel=True)
def _permute_mesh(triangles, neighbors, new_of_old, tri_order, tri_new_of_old):
    """Triangle rows in ``tri_order``, node ids and neighbour ids renamed.
    One parallel loop: numba 0.57 fused a second one (the inverse of
    ``tri_order``) with it and read the inverse before it was written."""
    m = tri_order.shape[0]
    tri = np.empty((m, 3), np.int64)
    nbr = np.empty((m, 3), np.int64)
    first_col = triangles[:, 0]
    for k in prange(m):
        # random reads, started ahead: the record 32 iterations on, then
        # (its record loaded by now) what the one 16 on will look up
        if k + 32 < m:
            prefetch(first_col, tri_order[k + 32])
        if k + 16 < m:
            ahead = tri_order[k + 16]
            for j in range(3):
                prefetch(new_of_old, triangles[ahead, j])
                n = neighbors[ahead, j]
                if n >= 0:
                    prefetch(tri_new_of_old, n)
        t = tri_order[k]
        for j in range(3):
            tri[k, j] = new_of_old[triangles[t, j]]
            n = neighbors[t, j]
            nbr[k, j] = tri_new_of_old[n] if n >= 0 else -1
    return tri, nbr


@njit(cache=True, parallel=True)
def _gather_nodes(P, R, old_of_new):
    """Node positions and radii in the new order (random reads: in parallel)."""
    n = old_of_new.shape[0]
    points = np.empty((n, 2))
    radii = np.empty(n)
    for k in prange(n):
        o = old_of_new[k]
        points[k, 0] = P[o, 0]
        points[k, 1] = P[o, 1]
        radii[k] = R[o]
    return points, radii


def spatial_renumbering(points, radii, triangles, neighbors, n_fixed):
    """Renumber nodes after ``n_fixed`` along a Hilbert curve, and triangles by
    their lowest new node.

    §2 creates nodes in density order, scattered over the domain; neighbours
    that are far apart in memory make every later pass over the mesh (the §3
    iterations above all) wait on cache misses.  Returns the permuted
    (points, radii, triangles, neighbors)."""
    n = len(points)
    old_of_new = np.arange(n)
    old_of_new[n_fixed:] = n_fixed + hilbert_order(points[n_fixed:])
    new_of_old = np.empty(n, np.int64)
    new_of_old[old_of_new] = np.arange(n)
    tri_order = _by_lowest_node(triangles, new_of_old)
    tri_new_of_old = np.empty(len(tri_order), np.int64)
    tri_new_of_old[tri_order] = np.arange(len(tri_order))
    tri, nbr = _permute_mesh(triangles, neighbors, new_of_old, tri_order, tri_new_of_old)
    points, radii = _gather_nodes(points, radii, old_of_new)
    return points, radii, tri, nbr


def _as_mesh(domain, ws, state, acc, boundary, status):
    npts, ntri = int(state[S_NPTS]), int(state[S_NTRI])
    n_b = len(boundary)
    points, radii, triangles, neighbors = spatial_renumbering(
        ws.P[:npts], ws.R[:npts], ws.tri[:ntri], ws.nbr[:ntri], n_b
    )
    stats = {
        "insertions": int(state[S_INSERTIONS]),
        "cavity_triangles": int(state[S_CAVITY]),
        "bubble_area": float(acc[0] + acc[1]),
        "domain_area": float(domain.area),
        "stop": "population" if status == STOP_POPULATION else "max_insertions",
    }
    return Mesh(
        points=points,
        triangles=triangles,
        neighbors=neighbors,
        radii=radii,
        segments=np.asarray(domain.segments, dtype=np.int64),
        n_boundary=n_b,
        domain=domain,
        stats=stats,
    )
