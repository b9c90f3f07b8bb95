"""Exact sweep-line test for straight segments (Shamos-Hoey), O(n log n).

Paper §2.1 starts from a refined boundary whose segments meet only at shared
end nodes; the initial constrained triangulation silently goes wrong
otherwise.  :func:`find_crossing` finds a pair of segments that violates this
in O(n log n) time whatever the shape (many long segments, many loops), and
:func:`sweep` additionally tells, for chosen nodes, which segment lies
directly below them, which decides loop nesting in one pass.

The sweep visits the segment end nodes in lexicographic (x, y) order, i.e. a
line ``x + eps*y = const`` for an infinitesimal ``eps``, so vertical segments
need no special case.  The segments cut by the sweep line are kept in a treap
ordered bottom to top with :func:`~bubblemesh.predicates.orient2d`; every two
segments that become neighbours there are tested exactly.  Two segments
*conflict* if they share any point other than a common end node (by index) at
which they do not fold back onto each other.  Why neighbour tests suffice:
let p be the smallest point shared by a conflicting pair.  Segments through p
that started before it are contiguous in the treap just before p, so if two
of them conflict, two neighbouring ones do (they were tested when they became
neighbours).  Otherwise they all end at one node, and a conflict at p
involves a segment starting at p: distinct nodes at p's coordinates are
caught directly (consecutive in the sort), a segment passing through p is
met by the insertion of one starting at p (the comparison ties, or the new
segment lands next to it), and two collinear segments leaving p tie.  Every
reported pair is re-tested exactly, so a report is never wrong.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from bubblemesh.errors import GeometryError, MeshingError
from bubblemesh.predicates import orient2d, out_of_range, out_of_range_message

__all__ = ["CONFLICT_VERB", "NO_CONFLICT", "find_crossing", "pair_conflict", "precedes", "sweep"]

NO_CONFLICT, CROSSES, TOUCHES, OVERLAPS = 0, 1, 2, 3
_INCONSISTENT = -1  # the treap order tied without a conflict: an internal error
CONFLICT_VERB = {CROSSES: "crosses", TOUCHES: "touches", OVERLAPS: "overlaps"}


# --- exact pair test ----------------------------------------------------------------


@njit(cache=True)
def _on_closed_box(px, py, ax, ay, bx, by):
    """p within the bounding box of a-b; for p collinear with a-b: p on segment a-b."""
    return min(ax, bx) <= px <= max(ax, bx) and min(ay, by) <= py <= max(ay, by)


@njit(cache=True)
def _disjoint_pair_conflict(ax, ay, bx, by, cx, cy, dx, dy):
    """How closed segments a-b and c-d (no shared node index) meet: 0 not at all."""
    o_abc = orient2d(ax, ay, bx, by, cx, cy)
    o_abd = orient2d(ax, ay, bx, by, dx, dy)
    if o_abc == 0.0 and o_abd == 0.0:
        # collinear: compare the projections on the dominant axis
        if ax != bx:
            lo, hi = max(min(ax, bx), min(cx, dx)), min(max(ax, bx), max(cx, dx))
        else:
            lo, hi = max(min(ay, by), min(cy, dy)), min(max(ay, by), max(cy, dy))
        if lo < hi:
            return OVERLAPS
        return TOUCHES if lo == hi else NO_CONFLICT
    o_cda = orient2d(cx, cy, dx, dy, ax, ay)
    o_cdb = orient2d(cx, cy, dx, dy, bx, by)
    if (
        o_abc != 0.0
        and o_abd != 0.0
        and (o_abc > 0.0) != (o_abd > 0.0)
        and o_cda != 0.0
        and o_cdb != 0.0
        and (o_cda > 0.0) != (o_cdb > 0.0)
    ):
        return CROSSES
    if (
        (o_abc == 0.0 and _on_closed_box(cx, cy, ax, ay, bx, by))
        or (o_abd == 0.0 and _on_closed_box(dx, dy, ax, ay, bx, by))
        or (o_cda == 0.0 and _on_closed_box(ax, ay, cx, cy, dx, dy))
        or (o_cdb == 0.0 and _on_closed_box(bx, by, cx, cy, dx, dy))
    ):
        return TOUCHES
    return NO_CONFLICT


@njit(cache=True)
def _folds_back(px, py, qx, qy, rx, ry):
    """Segments p-q, q-r overlap iff r lies on the ray from q through p."""
    if orient2d(px, py, qx, qy, rx, ry) != 0.0:
        return False
    if px != qx:
        return (px > qx) == (rx > qx)
    return (py > qy) == (ry > qy)


@njit(cache=True)
def pair_conflict(points, segments, i, j):
    """How segments i and j meet (exact): 0, CROSSES, TOUCHES or OVERLAPS.

    Sharing an end node (by index) is allowed unless the two fold back onto
    each other; the same node pair twice overlaps.
    """
    a, b = segments[i, 0], segments[i, 1]
    c, d = segments[j, 0], segments[j, 1]
    if (a == c and b == d) or (a == d and b == c):
        return OVERLAPS
    if a == c or a == d or b == c or b == d:
        q = a if (a == c or a == d) else b
        p = b if q == a else a
        r = d if q == c else c
        if _folds_back(
            points[p, 0], points[p, 1], points[q, 0], points[q, 1], points[r, 0], points[r, 1]
        ):
            return OVERLAPS
        return NO_CONFLICT
    if _boxes_apart(points[a, 0], points[b, 0], points[c, 0], points[d, 0]) or _boxes_apart(
        points[a, 1], points[b, 1], points[c, 1], points[d, 1]
    ):
        return NO_CONFLICT
    return _disjoint_pair_conflict(
        points[a, 0], points[a, 1], points[b, 0], points[b, 1],
        points[c, 0], points[c, 1], points[d, 0], points[d, 1],
    )  # fmt: skip


@njit(cache=True)
def _boxes_apart(a, b, c, d):
    """The ranges [a, b] and [c, d] (either order) are disjoint: the segments cannot meet."""
    return max(a, b) < min(c, d) or max(c, d) < min(a, b)


# --- the treap of segments cut by the sweep line --------------------------------------


@njit(cache=True)
def _rotate_up(x, left, right, parent, root):
    """Rotate node x above its parent; returns the (possibly new) root."""
    p = parent[x]
    g = parent[p]
    if left[p] == x:
        b = right[x]
        left[p] = b
        right[x] = p
    else:
        b = left[x]
        right[p] = b
        left[x] = p
    if b >= 0:
        parent[b] = p
    parent[p] = x
    parent[x] = g
    if g < 0:
        return x
    if left[g] == p:
        left[g] = x
    else:
        right[g] = x
    return root


@njit(cache=True, inline="always")
def _neighbour(x, left, right, parent, towards_right):
    """The in-order successor (towards_right) or predecessor of node x, -1 if none."""
    if towards_right:
        if right[x] >= 0:
            x = right[x]
            while left[x] >= 0:
                x = left[x]
            return x
        while parent[x] >= 0 and right[parent[x]] == x:
            x = parent[x]
        return parent[x]
    if left[x] >= 0:
        x = left[x]
        while right[x] >= 0:
            x = right[x]
        return x
    while parent[x] >= 0 and left[parent[x]] == x:
        x = parent[x]
    return parent[x]


@njit(cache=True)
def _remove(x, left, right, parent, priority, root):
    """Rotate x down to a leaf and unlink it; returns the new root."""
    while left[x] >= 0 or right[x] >= 0:
        if right[x] < 0 or (left[x] >= 0 and priority[left[x]] > priority[right[x]]):
            child = left[x]
        else:
            child = right[x]
        root = _rotate_up(child, left, right, parent, root)
    p = parent[x]
    if p < 0:
        root = -1
    elif left[p] == x:
        left[p] = -1
    else:
        right[p] = -1
    parent[x] = -1
    return root


@njit(cache=True)
def _side(points, low, high, s, px, py):
    """Sign of point p against segment s directed from its low to its high end."""
    a, b = low[s], high[s]
    o = orient2d(points[a, 0], points[a, 1], points[b, 0], points[b, 1], px, py)
    return 1 if o > 0.0 else (-1 if o < 0.0 else 0)


@njit(cache=True)
def _compare(points, low, high, s, w):
    """+1 if segment s (starting at the sweep point) lies above w there, -1 below, 0 tie."""
    side = _side(points, low, high, w, points[low[s], 0], points[low[s], 1])
    if side == 0 and low[s] == low[w]:  # both leave the same node: compare directions
        side = _side(points, low, high, w, points[high[s], 0], points[high[s], 1])
    return side


@njit(cache=True)
def _below(points, low, high, left, right, root, q):
    """The highest segment in the treap strictly below node q, -1 if none."""
    best = -1
    w = root
    while w >= 0:
        if _side(points, low, high, w, points[q, 0], points[q, 1]) > 0:
            best = w
            w = right[w]
        else:
            w = left[w]
    return best


# --- the sweep ------------------------------------------------------------------------


@njit(cache=True)
def precedes(points, p, q):
    """Node p comes before node q in the sweep: smaller x, or equal x and smaller y."""
    return points[p, 0] < points[q, 0] or (
        points[p, 0] == points[q, 0] and points[p, 1] < points[q, 1]
    )


@njit(cache=True)
def _lexicographic_ends(points, segments):
    """Each segment's end nodes in sweep order: (low, high)."""
    n_seg = segments.shape[0]
    low = np.empty(n_seg, dtype=np.int64)
    high = np.empty(n_seg, dtype=np.int64)
    for s in range(n_seg):
        a, b = segments[s, 0], segments[s, 1]
        low[s], high[s] = (a, b) if precedes(points, a, b) else (b, a)
    return low, high


@njit(cache=True)
def _incidence(n_points, segments):
    """CSR lists of the segments at each node: first[q]..first[q+1] in ``at``."""
    first = np.zeros(n_points + 1, dtype=np.int64)
    for s in range(segments.shape[0]):
        first[segments[s, 0] + 1] += 1
        first[segments[s, 1] + 1] += 1
    for q in range(n_points):
        first[q + 1] += first[q]
    fill = first[:-1].copy()
    at = np.empty(2 * segments.shape[0], dtype=np.int64)
    for s in range(segments.shape[0]):
        for end in range(2):
            q = segments[s, end]
            at[fill[q]] = s
            fill[q] += 1
    return first, at


@njit(cache=True)
def _break_ties(points, order):
    """Reorder runs of equal x in ``order`` (sorted by x) by y: the sweep order."""
    start = 0
    for k in range(1, order.shape[0] + 1):
        if k < order.shape[0] and points[order[k], 0] == points[order[start], 0]:
            continue
        if k - start > 16:
            run = order[start:k].copy()
            order[start:k] = run[np.argsort(points[run, 1], kind="mergesort")]
        else:  # short runs (pairs are common: mirror-symmetric loops) by insertion
            for a in range(start + 1, k):
                node = order[a]
                b = a
                while b > start and points[order[b - 1], 1] > points[node, 1]:
                    order[b] = order[b - 1]
                    b -= 1
                order[b] = node
        start = k


@njit(cache=True)
def _priorities(n):
    """Pseudo-random treap priorities (Park-Miller; products stay below 2**47)."""
    priority = np.empty(n, dtype=np.int64)
    state = 1
    for s in range(n):
        state = (state * 48271) % 2147483647
        priority[s] = state
    return priority


@njit(cache=True)
def _insert(points, low, high, left, right, parent, priority, root, s):
    """Put segment s (starting at the sweep point) in order: (root, -1) or (root, w) on a tie."""
    if root < 0:
        return s, -1
    w = root
    while True:
        side = _compare(points, low, high, s, w)
        if side == 0:
            return root, w
        child = right[w] if side > 0 else left[w]
        if child < 0:
            break
        w = child
    if side > 0:
        right[w] = s
    else:
        left[w] = s
    parent[s] = w
    while parent[s] >= 0 and priority[s] > priority[parent[s]]:
        root = _rotate_up(s, left, right, parent, root)
    return root, -1


@njit(cache=True, inline="always")
def _replace(t, s, left, right, parent, priority, root):
    """Segment s takes the place of t, which ends where s starts; returns the root.

    Nothing else passes through that node (or t's neighbours would conflict with
    it and have been reported), so s sits exactly where t was.
    """
    left[s], right[s], parent[s], priority[s] = left[t], right[t], parent[t], priority[t]
    for child in (left[s], right[s]):
        if child >= 0:
            parent[child] = s
    p = parent[s]
    left[t] = right[t] = parent[t] = -1
    if p < 0:
        return s
    if left[p] == t:
        left[p] = s
    else:
        right[p] = s
    return root


@njit(cache=True)
def _sweep_kernel(points, segments, node_order, locate):
    """Shamos-Hoey over lexicographically sorted nodes (see the module docstring).

    Returns ``(i, j, kind, below)``: the first conflicting pair found (``kind``
    0 if none) and, for each node with ``locate[q]``, the segment directly
    below it when the sweep reaches it (-1: none).
    """
    n_seg = segments.shape[0]
    low, high = _lexicographic_ends(points, segments)
    first, at = _incidence(points.shape[0], segments)
    priority = _priorities(n_seg)
    left = np.full(n_seg, -1, dtype=np.int64)
    right = np.full(n_seg, -1, dtype=np.int64)
    parent = np.full(n_seg, -1, dtype=np.int64)
    below = np.full(points.shape[0], -1, dtype=np.int64)
    root = -1
    previous = -1
    for q in node_order:
        if first[q] == first[q + 1]:
            continue  # not the end of any segment
        if (
            previous >= 0
            and points[previous, 0] == points[q, 0]
            and points[previous, 1] == points[q, 1]
        ):  # two nodes at one place: their segments meet there
            i, j = at[first[previous]], at[first[q]]
            kind = pair_conflict(points, segments, i, j)
            return i, j, (TOUCHES if kind == NO_CONFLICT else kind), below
        previous = q
        ending = starting = 0
        for k in range(first[q], first[q + 1]):
            if high[at[k]] == q:
                ending += 1
                t = at[k]
            else:
                starting += 1
                s = at[k]
        if ending == 1 and starting == 1 and not locate[q]:  # the common case: pass through q
            root = _replace(t, s, left, right, parent, priority, root)
            for towards_right in (False, True):
                w = _neighbour(s, left, right, parent, towards_right)
                if w >= 0:
                    kind = pair_conflict(points, segments, s, w)
                    if kind != NO_CONFLICT:
                        return s, w, kind, below
            continue
        for k in range(first[q], first[q + 1]):  # segments ending at q leave first
            t = at[k]
            if high[t] != q:
                continue
            a = _neighbour(t, left, right, parent, False)
            b = _neighbour(t, left, right, parent, True)
            root = _remove(t, left, right, parent, priority, root)
            if a >= 0 and b >= 0:
                kind = pair_conflict(points, segments, a, b)
                if kind != NO_CONFLICT:
                    return a, b, kind, below
        if locate[q]:
            below[q] = _below(points, low, high, left, right, root, q)
        for k in range(first[q], first[q + 1]):
            s = at[k]
            if low[s] != q:
                continue
            root, w = _insert(points, low, high, left, right, parent, priority, root, s)
            if w >= 0:  # s ties with w: they meet
                kind = pair_conflict(points, segments, s, w)
                return s, w, (_INCONSISTENT if kind == NO_CONFLICT else kind), below
            for towards_right in (False, True):
                w = _neighbour(s, left, right, parent, towards_right)
                if w >= 0:
                    kind = pair_conflict(points, segments, s, w)
                    if kind != NO_CONFLICT:
                        return s, w, kind, below
    return -1, -1, NO_CONFLICT, below


def sweep(
    points: np.ndarray, segments: np.ndarray, locate: np.ndarray | None = None
) -> tuple[int, int, int, np.ndarray]:
    """Run the exact sweep over valid arrays: ``(i, j, kind, below)`` with ``i < j``.

    ``points`` (N, 2) float64 within the predicates' range, ``segments`` (M, 2)
    int64 node indices of distinct coordinates.  ``kind`` is NO_CONFLICT (then
    ``i = j = -1``) or the exact kind of a conflicting pair; ``below[q]`` is
    the segment directly below node q for each q with ``locate[q]`` (valid
    only without a conflict).
    """
    points = np.ascontiguousarray(points, dtype=np.float64)
    segments = np.ascontiguousarray(segments, dtype=np.int64).reshape(-1, 2)
    if locate is None:
        locate = np.zeros(len(points), dtype=np.bool_)
    node_order = np.argsort(points[:, 0])  # numpy's sort is several times numba's
    _break_ties(points, node_order)
    i, j, kind, below = _sweep_kernel(points, segments, node_order, locate)
    if kind == _INCONSISTENT:
        raise MeshingError(f"segment sweep: segments {i} and {j} tie without meeting")
    return min(int(i), int(j)), max(int(i), int(j)), int(kind), below


def find_crossing(points, segments) -> tuple[int, int, str] | None:
    """A pair of segments that cross, touch or overlap, or None (exact, O(n log n)).

    ``points`` is (N, 2), ``segments`` (M, 2) node indices.  Segments may share
    end nodes (by index) as long as they do not fold back onto each other;
    any other common point is reported as ``(i, j, verb)`` with ``i < j`` and
    ``verb`` one of "crosses", "touches" (a single common point that is not a
    shared end node), "overlaps" (a common piece).  Raises GeometryError for
    out-of-range coordinates, bad indices and zero-length segments.
    """
    points = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 2)
    segments = np.ascontiguousarray(segments, dtype=np.int64).reshape(-1, 2)
    outside = out_of_range(points)
    if outside.any():
        k = int(np.argmax(outside))
        raise GeometryError(f"point {k} = {out_of_range_message(points[k])}")
    if segments.size and (segments.min() < 0 or segments.max() >= len(points)):
        raise GeometryError("a segment refers to a point index out of range")
    ends = points[segments]
    zero = (ends[:, 0] == ends[:, 1]).all(axis=1)
    if zero.any():
        s = int(np.argmax(zero))
        raise GeometryError(f"segment {s} = {tuple(segments[s].tolist())} has zero length")
    i, j, kind, _ = sweep(points, segments)
    return None if kind == NO_CONFLICT else (i, j, CONFLICT_VERB[kind])
