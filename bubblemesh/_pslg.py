"""Planar straight-line graphs as domains (the input of paper §2.1, generalised).

A graph of vertices and segments is triangulated exactly (the constrained
Delaunay triangulation of ``triangulation``); its faces are the classes of
triangles joined across unconstrained edges.  Which faces are the domain:

* ``"enclosed"`` (Triangle's ``-p``): every face not reachable from infinity
  without crossing a segment, minus the faces holding a hole point; with
  ``convex_hull`` the hull edges are segments too (Triangle's ``-c``);
* ``"parity"`` (loops and interior constraints): faces behind an odd number of
  loop segments (``BOUNDARY`` flags; interior constraints are not counted), so
  holes and islands in holes nest to any depth, minus hole-point faces.

Each kept segment becomes oriented half-edges with the domain on their left:
one for a boundary segment, two (both ways) for a segment with the domain on
both sides (an interior constraint); segments with the domain on neither side
are dropped.  The half-edges chain into closed boundary walks (``loops``),
found by turning around each head vertex inside the kept triangles, so a
vertex may repeat in a walk (junctions, crack tips).  Vertices of kept
triangles on no kept segment are free points.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._cavity import is_ghost
from ._cdt import BOUNDARY, INTERIOR
from ._crossings import crossing_pairs, segment_text, split_crossings
from ._sweep import (
    _break_ties,
    _incidence,
    _insert,
    _lexicographic_ends,
    _neighbour,
    _priorities,
    _remove,
    _replace,
    _side,
    precedes,
)
from .errors import GeometryError
from .predicates import flush_tiny, orient2d, out_of_range, out_of_range_message
from .triangulation import ghost_constrained

__all__ = ["Graph", "build"]


@njit(cache=True)
def _faces(tri, nbr, con, ntri):
    """Face label of every triangle (ghosts included): classes joined across
    unconstrained edges, numbered in order of their lowest triangle."""
    label = np.full(ntri, -1, np.int64)
    stack = np.empty(ntri, np.int64)
    faces = 0
    for seed in range(ntri):
        if label[seed] >= 0:
            continue
        label[seed] = faces
        top = 1
        stack[0] = seed
        while top > 0:
            top -= 1
            t = stack[top]
            for j in range(3):
                n = nbr[t, j]
                if n >= 0 and con[t, j] == 0 and label[n] < 0:
                    label[n] = faces
                    stack[top] = n
                    top += 1
        faces += 1
    return label


@njit(cache=True)
def _locate(P, tri, con, ntri, px, py):
    """(triangle, status): a real triangle whose closure holds (px, py); status 1
    inside it or on an unconstrained edge, 0 on a constrained edge or a
    vertex, -1 if no triangle holds it."""
    on_edge = -1
    status = 0
    for t in range(ntri):
        if is_ghost(tri, t):
            continue
        a, b, c = tri[t, 0], tri[t, 1], tri[t, 2]
        o1 = orient2d(P[a, 0], P[a, 1], P[b, 0], P[b, 1], px, py)
        o2 = orient2d(P[b, 0], P[b, 1], P[c, 0], P[c, 1], px, py)
        o3 = orient2d(P[c, 0], P[c, 1], P[a, 0], P[a, 1], px, py)
        if o1 > 0.0 and o2 > 0.0 and o3 > 0.0:
            return t, 1
        if o1 >= 0.0 and o2 >= 0.0 and o3 >= 0.0 and on_edge < 0:
            on_edge = t
            zeros = (o1 == 0.0) + (o2 == 0.0) + (o3 == 0.0)
            j = 2 if o1 == 0.0 else (0 if o2 == 0.0 else 1)  # the edge's opposite vertex
            status = 1 if zeros == 1 and con[t, j] == 0 else 0
    return (on_edge, status) if on_edge >= 0 else (-1, -1)


@njit(cache=True)
def _next_heads(tri, nbr, con, start_t, start_i, max_steps):
    """For each half-edge (the edge opposite vertex start_i of kept triangle
    start_t, run counter-clockwise): the far end of the next boundary half-edge,
    found by turning around its head through unconstrained edges."""
    m = start_t.shape[0]
    out = np.full(m, -1, np.int64)
    for k in range(m):
        t = start_t[k]
        head = tri[t, (start_i[k] + 2) % 3]
        for _ in range(max_steps):
            h = 0
            for j in range(3):
                if tri[t, j] == head:
                    h = j
            # edge head -> tri[t, h + 1] is opposite vertex h + 2, i.e. tail's slot
            j = (h + 2) % 3
            if con[t, j] != 0:
                out[k] = tri[t, (h + 1) % 3]
                break
            t = nbr[t, j]
            if t < 0:
                break
    return out


class Graph:
    """A validated planar straight-line graph domain (module docstring): the
    arrays a :class:`~bubblemesh.Domain` is made of."""

    def __init__(self, points, segments, loops, markers, holes, regions, area, dropped):
        self.points = points  # (N, 2) kept vertices, input order
        self.segments = segments  # (S, 2) half-edges, loop after loop
        self.loops = loops  # tuple of node-index arrays (closed walks)
        self.markers = markers  # (S,) marker of each half-edge's input segment
        self.holes = holes
        self.regions = regions
        self.area = area
        self.dropped = dropped  # input vertex indices left out (outside the domain)


def _checked_points(points: np.ndarray, what: str, like=None) -> np.ndarray:
    """(n, 2) float64 points, flushed (:func:`~bubblemesh.predicates.flush_tiny`
    at the scale of ``like``, by default their own) and in range."""
    P = flush_tiny(np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 2), like)
    bad = ~np.isfinite(P).all(axis=1)
    if bad.any():
        raise GeometryError(f"{what} {int(np.argmax(bad))} has a non-finite coordinate")
    outside = out_of_range(P)
    if outside.any():
        k = int(np.argmax(outside))
        raise GeometryError(f"{what} {k} = {out_of_range_message(P[k])}")
    return P


def _unique_segments(segments, markers, flags):
    """Segments without repeats (either way) or zero-length ones; of repeats a
    loop segment (``BOUNDARY``) wins, then the first."""
    S = np.asarray(segments, dtype=np.int64).reshape(-1, 2)
    flags = np.asarray(flags, np.uint8)
    same = S[:, 0] == S[:, 1]
    if same.any():
        s = int(np.argmax(same))
        raise GeometryError(f"segment {s} joins vertex {int(S[s, 0])} to itself")
    order = np.lexsort((np.arange(len(S)), flags != BOUNDARY))
    _, first = np.unique(np.sort(S, axis=1)[order], axis=0, return_index=True)
    first = np.sort(order[first])
    return S[first], np.asarray(markers, np.int64)[first], flags[first]


def build(vertices, segments, markers, *, holes=(), regions=(), mode="enclosed",
          flags=None, convex_hull=False, hull_marker=1, first_index=0,
          split_crossing=True) -> Graph:
    """The domain of a planar straight-line graph (module docstring).

    ``vertices`` (N, 2); ``segments`` (K, 2) vertex indices, either way;
    ``markers`` (K,) ints; ``holes`` (H, 2) points; ``regions`` (R, 4) rows
    (x, y, attribute, max_area); ``flags`` (K,) ``BOUNDARY``/``INTERIOR`` for
    ``mode="parity"``.  A vertex strictly inside a segment splits it (as in
    Triangle; the pieces keep the segment's marker and flag), and so do
    crossing segments, at their crossing (:mod:`bubblemesh._crossings`; the
    new vertices after the input's), unless ``split_crossing`` is False (then
    they are named in a GeometryError).  Raises GeometryError for loops that
    cross in parity mode, duplicate vertices, a hole or region point on a
    segment, and an empty domain."""
    P = _checked_points(vertices, "vertex")
    if len(P) < 3:
        raise GeometryError(f"a domain needs at least 3 vertices, got {len(P)}")
    holes = _checked_points(np.asarray(holes, np.float64).reshape(-1, 2), "hole point", P)
    regions = np.array(() if regions is None else regions, np.float64).reshape(-1, 4)
    regions[:, :2] = _checked_points(regions[:, :2], "region point", P)
    if flags is None:
        flags = np.full(len(np.asarray(segments).reshape(-1, 2)), INTERIOR, np.uint8)
    S, markers, flags = _unique_segments(segments, markers, flags)
    S, markers, flags = _unique_segments(*split_at_vertices(P, S, markers, flags))
    given = len(P)
    try:
        tri, nbr, con, ntri = _triangulated(P, S, flags, mode)
    except GeometryError:
        # segments that cross are split there, as Triangle does; any other fault stands
        if not split_crossing:
            _refuse_crossings(P, S)
        P, S2, markers, flags = split_crossings(P, S, markers, flags, mode == "parity")
        if len(S2) == len(S):
            raise
        S, markers, flags = _unique_segments(*split_at_vertices(P, S2, markers, flags))
        tri, nbr, con, ntri = _triangulated(P, S, flags, mode)
    tri, nbr, con = tri[:ntri], nbr[:ntri], con[:ntri]
    ghost = (tri < 0).any(axis=1)
    if convex_hull:
        S, markers = _close_hull(tri, nbr, con, ghost, S, markers, hull_marker)
    label = _faces(tri, nbr, con, ntri)
    if mode == "parity":
        from ._cdt import interior_mask

        keep = interior_mask(tri, nbr, con, ntri)
    else:
        keep = ~np.isin(label, label[ghost])
    for h, (x, y) in enumerate(holes.tolist()):
        t, status = _locate(P, tri, con, ntri, x, y)
        if status == 0:
            raise GeometryError(f"hole point {h + first_index} at ({x!r}, {y!r}) lies on a "
                                "segment or vertex")
        if t >= 0:
            keep &= label != label[t]
    keep &= ~ghost
    if not keep.any():
        raise GeometryError("the segments and holes leave no domain: no triangle is enclosed")
    graph = _assemble(P, S, markers, tri, nbr, con, keep, holes, regions)
    graph.dropped = graph.dropped[graph.dropped < given]  # a crossing outside: no input
    return graph


def _refuse_crossings(P, S):
    """GeometryError naming the first two segments that cross, if any."""
    pairs = crossing_pairs(P, S)
    if len(pairs):
        i, j = pairs[0].tolist()
        raise GeometryError(f"segments cross: {segment_text(P, S[i])} and "
                            f"{segment_text(P, S[j])}")


def _triangulated(P, S, flags, mode):
    """:func:`ghost_constrained` of the graph; in ``enclosed`` mode every
    segment blocks the eating (INTERIOR)."""
    if mode == "enclosed":
        flags = np.full(len(S), INTERIOR, np.uint8)
    return ghost_constrained(P, np.ascontiguousarray(S), flags)


@njit(cache=True)
def _through(points, low, high, left, right, root, q):
    """Some segment of the treap whose line holds node q (exact), -1 if none."""
    w = root
    while w >= 0:
        side = _side(points, low, high, w, points[q, 0], points[q, 1])
        if side == 0:
            return w
        w = right[w] if side > 0 else left[w]
    return -1


@njit(cache=True)
def _split_kernel(points, segments, node_order):
    """(segment, vertex) pairs, in sweep order, of every vertex strictly inside a
    segment, and a status: 0 done, 2 the sweep met segments that cross (the
    constrained triangulation then names them).

    The sweep of :mod:`bubblemesh._sweep` over all vertices: at each vertex q,
    the segments ending at q leave, those whose line holds q (a contiguous run
    of the bottom-to-top treap) are split there (their low end moves to q: the
    rest of the segment keeps its place), then those starting at q enter.  Of
    collinear segments leaving q only the longest stays in the treap; the
    others lie on it, so it is split at their far ends: overlaps become
    repeated pieces."""
    n_seg = segments.shape[0]
    low, high = _lexicographic_ends(points, segments)
    first, at = _incidence(points.shape[0], segments)
    priority = _priorities(n_seg)
    left = np.full(n_seg, -1, np.int64)
    right = np.full(n_seg, -1, np.int64)
    parent = np.full(n_seg, -1, np.int64)
    in_tree = np.zeros(n_seg, np.bool_)
    capacity = 3 * points.shape[0] + 8  # a planar graph has < 3 V edges
    split_seg = np.empty(capacity, np.int64)
    split_node = np.empty(capacity, np.int64)
    count = 0
    root = -1
    for q in node_order:
        for k in range(first[q], first[q + 1]):
            t = at[k]
            if high[t] == q and in_tree[t]:
                root = _remove(t, left, right, parent, priority, root)
                in_tree[t] = False
        w = _through(points, low, high, left, right, root, q)
        if w >= 0:
            for towards_right in (False, True):
                s = w if not towards_right else _neighbour(w, left, right, parent, True)
                while s >= 0 and _side(points, low, high, s, points[q, 0], points[q, 1]) == 0:
                    if precedes(points, low[s], q):  # not a duplicate of its end
                        if count == capacity:
                            return split_seg[:count], split_node[:count], 2
                        split_seg[count], split_node[count] = s, q
                        count += 1
                        low[s] = q
                    s = _neighbour(s, left, right, parent, towards_right)
        for k in range(first[q], first[q + 1]):
            s = at[k]
            if low[s] != q or high[s] == q:
                continue
            root, w = _insert(points, low, high, left, right, parent, priority, root, s)
            if w < 0:
                in_tree[s] = True
            elif low[w] != q:  # q on w but w not split there: the order is broken
                return split_seg[:count], split_node[:count], 2
            elif precedes(points, high[w], high[s]):  # collinear from q, s reaches further
                root = _replace(w, s, left, right, parent, priority, root)
                in_tree[w], in_tree[s] = False, True
            # else s lies on w, which is split at s's far end when the sweep gets there
    return split_seg[:count], split_node[:count], 0


def split_at_vertices(P, S, markers, flags):
    """Segments split at every vertex strictly inside them, exactly, O(n log n):
    (segments, markers, flags), a split segment's first piece in its place and
    the others appended, each piece with its segment's marker and flag
    (collinear overlapping segments become repeated pieces)."""
    if S.size and (S.min() < 0 or S.max() >= len(P)):
        raise GeometryError("a segment refers to a vertex index out of range")
    if not len(S):
        return S, markers, flags
    node_order = np.argsort(P[:, 0], kind="stable")
    _break_ties(P, node_order)
    seg, node, _ = _split_kernel(P, np.ascontiguousarray(S), node_order)
    if not len(seg):
        return S, markers, flags
    low, high = _lexicographic_ends(P, S)
    order = np.argsort(seg, kind="stable")  # each segment's splits in sweep order
    seg, node = seg[order], node[order]
    starts = np.r_[True, seg[1:] != seg[:-1]]
    ends = np.r_[seg[1:] != seg[:-1], True]
    prev = np.where(starts, low[seg], np.r_[-1, node[:-1]])
    pieces = np.vstack([np.column_stack([prev, node]),
                        np.column_stack([node[ends], high[seg[ends]]])])
    owner = np.concatenate([seg, seg[ends]])
    out = S.copy()
    out[seg[starts]] = pieces[:len(seg)][starts]
    rest = np.ones(len(pieces), bool)
    rest[np.flatnonzero(starts)] = False
    return (np.vstack([out, pieces[rest]]), np.concatenate([markers, markers[owner[rest]]]),
            np.concatenate([flags, flags[owner[rest]]]))


def _close_hull(tri, nbr, con, ghost, S, markers, hull_marker):
    """Triangle's -c: the convex hull edges become segments (marker ``hull_marker``)."""
    real = np.flatnonzero(~ghost)
    t, j = np.nonzero(nbr[real] >= 0)
    t = real[t]
    across = nbr[t, j]
    on_hull = ghost[across] & (con[t, j] == 0)
    t, j = t[on_hull], j[on_hull]
    con[t, j] = INTERIOR
    con[nbr[t, j], 0] = np.where(nbr[nbr[t, j], 0] == t, INTERIOR, con[nbr[t, j], 0])
    con[nbr[t, j], 1] = np.where(nbr[nbr[t, j], 1] == t, INTERIOR, con[nbr[t, j], 1])
    con[nbr[t, j], 2] = np.where(nbr[nbr[t, j], 2] == t, INTERIOR, con[nbr[t, j], 2])
    ends = np.column_stack([tri[t, (j + 1) % 3], tri[t, (j + 2) % 3]])
    return (np.concatenate([S, ends]),
            np.concatenate([markers, np.full(len(ends), hull_marker, np.int64)]))


def _assemble(P, S, markers, tri, nbr, con, keep, holes, regions) -> Graph:
    n = len(P)
    kt = np.flatnonzero(keep)
    # directed edges of kept triangles: edge opposite vertex i runs tri[i+1] -> tri[i+2]
    a = tri[kt][:, [1, 2, 0]].ravel()
    b = tri[kt][:, [2, 0, 1]].ravel()
    key = a * n + b
    order = np.argsort(key, kind="stable")
    key_sorted = key[order]

    def find(u, v):
        k = u * n + v
        pos = np.minimum(np.searchsorted(key_sorted, k), len(key_sorted) - 1)
        hit = key_sorted[pos] == k
        return np.where(hit, order[pos], -1)

    left, right = find(S[:, 0], S[:, 1]), find(S[:, 1], S[:, 0])
    half = []  # (tail, head, marker, edge slot in the kept list)
    for side, (u, v) in ((left, (S[:, 0], S[:, 1])), (right, (S[:, 1], S[:, 0]))):
        ok = side >= 0
        half.append(np.column_stack([u[ok], v[ok], markers[ok], side[ok]]))
    H = np.concatenate(half)
    if not len(H):
        raise GeometryError("no segment bounds the domain")
    slot = H[:, 3]
    start_t = kt[slot // 3]
    start_i = slot % 3
    heads = _next_heads(tri, nbr, con, start_t, start_i, 4 * len(tri) + 8)
    if (heads < 0).any():
        raise GeometryError("the boundary walk did not close (internal invariant failed)")
    hkey = H[:, 0] * n + H[:, 1]
    horder = np.argsort(hkey, kind="stable")
    nxt = horder[np.searchsorted(hkey[horder], H[:, 1] * n + heads)]
    loops, seg_order = _cycles(nxt, H, P)
    used = np.zeros(n, bool)
    used[tri[kt].ravel()] = True
    used[H[:, :2].ravel()] = True
    new_of_old = np.cumsum(used) - 1
    points = P[used]
    H = H[seg_order]
    loops = tuple(new_of_old[loop] for loop in loops)
    area = math.fsum(_signed_areas(P, tri[kt]).tolist())
    return Graph(points=points, segments=new_of_old[H[:, :2]], loops=loops, markers=H[:, 2],
                 holes=holes, regions=regions, area=area, dropped=np.flatnonzero(~used))


def _signed_areas(P, T):
    a, b, c = P[T[:, 0]], P[T[:, 1]], P[T[:, 2]]
    return 0.5 * ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1])
                  - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))


def _cycles(nxt, H, P):
    """The half-edge permutation's cycles as walks, largest signed area first
    (an outer boundary), each starting at its smallest half-edge."""
    seen = np.zeros(len(nxt), bool)
    cycles = []
    for s in range(len(nxt)):
        if seen[s]:
            continue
        cycle = []
        k = s
        while not seen[k]:
            seen[k] = True
            cycle.append(k)
            k = int(nxt[k])
        cycles.append(np.array(cycle, np.int64))
    areas = []
    for c in cycles:
        ring = P[H[c, 0]] - P[H[c[0], 0]]
        areas.append(0.5 * math.fsum((ring[:, 0] * np.roll(ring[:, 1], -1)
                                      - np.roll(ring[:, 0], -1) * ring[:, 1]).tolist()))
    rank = sorted(range(len(cycles)), key=lambda i: (-areas[i], int(cycles[i][0])))
    cycles = [cycles[i] for i in rank]
    return [H[c, 0] for c in cycles], np.concatenate(cycles)


@njit(cache=True)
def triangle_values(P, T, values, Q, outside):
    """values[t] of the triangle t holding each query point (closed, the first
    found), ``outside`` where none does; triangles pre-filtered by their boxes."""
    m = T.shape[0]
    lo = np.empty((m, 2))
    hi = np.empty((m, 2))
    for t in range(m):
        for d in range(2):
            a, b, c = P[T[t, 0], d], P[T[t, 1], d], P[T[t, 2], d]
            lo[t, d] = min(a, b, c)
            hi[t, d] = max(a, b, c)
    out = np.full(Q.shape[0], outside)
    for k in range(Q.shape[0]):
        x, y = Q[k, 0], Q[k, 1]
        for t in range(m):
            if x < lo[t, 0] or x > hi[t, 0] or y < lo[t, 1] or y > hi[t, 1]:
                continue
            u, v, w = T[t, 0], T[t, 1], T[t, 2]
            if (orient2d(P[u, 0], P[u, 1], P[v, 0], P[v, 1], x, y) >= 0.0
                    and orient2d(P[v, 0], P[v, 1], P[w, 0], P[w, 1], x, y) >= 0.0
                    and orient2d(P[w, 0], P[w, 1], P[u, 0], P[u, 1], x, y) >= 0.0):
                out[k] = values[t]
                break
    return out
