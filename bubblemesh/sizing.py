"""A graded size field h(x) for domains whose boundary is not yet refined.

The paper (§2.1) starts from a *refined boundary*: the boundary spacing alone
sets every bubble (eq. 1-2, then eq. 3 inside).  Polygons given by their
corners, or long straight edges next to finely sampled arcs, break that
assumption.  :class:`SizeField` is the element size (edge length) a robust
mesher should aim for, the minimum of

(a) the input spacing: at a boundary node, the edge length of the equilateral
    triangle whose area is eq. 1's A_n, h = sqrt((l1^2 + l2^2) / 2) (the
    eq. 2 radius is r_n = h sqrt(sqrt(3) / (4 pi)), see :meth:`SizeField.radius`);
(b) the local feature size: the distance from a boundary point to the nearest
    boundary segment that does not share a node with the point's own segment
    (at a node: with either of its two segments), so narrow gaps and thin slots
    get small elements while a corner does not shrink by its own sides;
(c) an optional user size, a positive number or a vectorised callable;

limited in gradation: h(x) = min(cap, min_k h_k + g |x - x_k|) over sources
(x_k, h_k), so |grad h| <= g everywhere and h(x) <= h_k + g |x - x_k| holds for
every source by construction.  Sources are the boundary nodes, adaptive samples
along the segments (placed so that h <= ``FEATURE_SLACK`` times (b) all along
the boundary, and spaced at most ``SAMPLING`` times a callable (c)) and, for a
callable, the centres of a quadtree whose cells are at most
``QUADTREE_SAMPLING`` times its value at their centre (a callable is seen only
at its samples).  Sources that others dominate are dropped, which changes no
value.

Evaluation is a branch-and-bound search in a bounding-volume tree over the
sources (Morton order, min h per node), in numba, in parallel; the feature-size
queries use the same tree over the segments with exact point-segment
distances.  Build and queries are O(n log n) for n sources.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numba import njit, prange

from bubblemesh.domain import Domain
from bubblemesh.errors import MeshingError

__all__ = ["SizeField", "as_size_function", "cone_at", "field_at", "field_count", "STACK_SIZE"]

SAMPLING = 0.5  # boundary samples are spaced <= SAMPLING * h
FEATURE_SLACK = 1.25  # on the boundary h <= FEATURE_SLACK * feature size
# gaps thinner than this fraction of the local input segment length are not resolved
# (a node an ulp from a segment would ask for sizes of ~0) but left to the other sizes:
# held at the floor instead, a long gap just under it would fill with floor-sized slivers
FEATURE_FLOOR = 1e-4
QUADTREE_SAMPLING = 0.7  # quadtree cells have sides <= QUADTREE_SAMPLING * user size
MAX_SOURCES = 2**24  # beyond this the requested sizes are unreasonably small
CAP_REACH = 2.0**20  # a size cap beyond this many times the domain's extent is held at it
_LEAF = 8  # items per tree leaf
_STACK = 256  # > twice the depth of any tree over < 2**60 items
_HINT = _STACK  # the stack's last entry: the source of the previous answer, a warm start
STACK_SIZE = _STACK + 1
_BLOCK = 256  # queries per parallel task (one traversal stack each)
SORTED_QUERIES = 4096  # from this many queries on, uncapped fields answer in Morton order
# the cap grid: cells of GRID_CELLS caps (at most GRID_MAX a side), grown by GRID_MARGIN
# of a side and tested against (1 + CAP_MARGIN) cap, far above any rounding
GRID_CELLS, GRID_MAX, GRID_MARGIN, CAP_MARGIN = 8.0, 256, 1e-6, 1e-9
_EQUILATERAL_RADIUS = math.sqrt(math.sqrt(3.0) / (4.0 * math.pi))  # eq. 2 with l1 = l2 = h


# --- bounding-volume tree -------------------------------------------------------------


def _morton_order(centres: np.ndarray) -> np.ndarray:
    """Permutation sorting points along a Z-order curve (21 bits per axis)."""
    lo = centres.min(axis=0)
    extent = float((centres.max(axis=0) - lo).max())
    scale = (2**21 - 1) / extent if extent > 0 else 0.0
    q = ((centres - lo) * scale).astype(np.uint64)
    return np.argsort(_spread(q[:, 0]) | (_spread(q[:, 1]) << np.uint64(1)), kind="stable")


def _spread(v: np.ndarray) -> np.ndarray:
    """The bits of each value (below 2**32) moved to the even places."""
    for shift, mask in ((16, 0x0000FFFF0000FFFF), (8, 0x00FF00FF00FF00FF),
                        (4, 0x0F0F0F0F0F0F0F0F), (2, 0x3333333333333333),
                        (1, 0x5555555555555555)):
        v = (v | (v << np.uint64(shift))) & np.uint64(mask)
    return v


@njit(cache=True)
def _build_tree(box_lo, box_hi, value):
    """Binary tree over items already in Morton order: node i covers items
    start[i]:end[i]; children left[i], left[i] + 1 (left -1: a leaf).  Returns
    (start, end, left, box (x0, y0, x1, y1), least value in the node)."""
    n = box_lo.shape[0]
    cap = 2 * n + 1
    start = np.empty(cap, np.int64)
    end = np.empty(cap, np.int64)
    left = np.full(cap, -1, np.int64)
    start[0], end[0] = 0, n
    count, i = 1, 0
    while i < count:  # breadth first: children come after their parent
        s, e = start[i], end[i]
        if e - s > _LEAF:
            mid = (s + e) // 2
            left[i] = count
            start[count], end[count] = s, mid
            start[count + 1], end[count + 1] = mid, e
            count += 2
        i += 1
    box = np.empty((count, 4))
    least = np.empty(count)
    for i in range(count - 1, -1, -1):
        if left[i] < 0:
            s, e = start[i], end[i]
            box[i, 0], box[i, 1] = box_lo[s:e, 0].min(), box_lo[s:e, 1].min()
            box[i, 2], box[i, 3] = box_hi[s:e, 0].max(), box_hi[s:e, 1].max()
            least[i] = value[s:e].min()
        else:
            a, b = left[i], left[i] + 1
            box[i, 0], box[i, 1] = min(box[a, 0], box[b, 0]), min(box[a, 1], box[b, 1])
            box[i, 2], box[i, 3] = max(box[a, 2], box[b, 2]), max(box[a, 3], box[b, 3])
            least[i] = min(least[a], least[b])
    return start[:count].copy(), end[:count].copy(), left[:count].copy(), box, least


@njit(cache=True, inline="always")
def _box_distance(box, i, x, y):
    dx = max(box[i, 0] - x, 0.0, x - box[i, 2])
    dy = max(box[i, 1] - y, 0.0, y - box[i, 3])
    return math.sqrt(dx * dx + dy * dy)


class _Tree:
    """Items (points or segments) in Morton order with their tree."""

    def __init__(self, box_lo: np.ndarray, box_hi: np.ndarray, value: np.ndarray):
        self.order = _morton_order(0.5 * (box_lo + box_hi))
        self.lo = np.ascontiguousarray(box_lo[self.order])
        self.hi = np.ascontiguousarray(box_hi[self.order])
        self.value = np.ascontiguousarray(value[self.order])
        self.x, self.y = self.lo[:, 0].copy(), self.lo[:, 1].copy()
        self.start, self.end, self.left, self.box, self.least = _build_tree(
            self.lo, self.hi, self.value
        )


# --- cone field: h(x) = min(cap, min_k h_k + g |x - x_k|) ------------------------------


@njit(cache=True, inline="always")
def _cone(k, x, y, px, py, ph, g):
    return ph[k] + g * math.sqrt((px[k] - x) ** 2 + (py[k] - y) ** 2)


@njit(cache=True)
def cone_at(x, y, stack, px, py, ph, start, end, left, box, least, g, cap):
    """min(cap, min_k ph[k] + g |(x, y) - p_k|), exactly the minimum over all
    sources (a node is skipped only when its lower bound, its least h plus g
    times the distance to its box, cannot beat the best so far).  ``stack``:
    int64 scratch of length STACK_SIZE whose last entry, if a source index,
    starts the search at that source's cone (nearby queries share their best
    source; any source gives the same minimum) and is set to the answer's."""
    best = cap
    found = stack[_HINT]
    if found >= 0 and found < ph.shape[0]:
        best = min(best, _cone(found, x, y, px, py, ph, g))
    top = 1
    stack[0] = 0
    while top > 0:
        top -= 1
        i = stack[top]
        if least[i] + g * _box_distance(box, i, x, y) >= best:
            continue
        if left[i] < 0:
            for k in range(start[i], end[i]):
                v = _cone(k, x, y, px, py, ph, g)
                if v < best:
                    best, found = v, k
            continue
        a, b = left[i], left[i] + 1
        if _box_distance(box, a, x, y) + least[a] < _box_distance(box, b, x, y) + least[b]:
            a, b = b, a  # the more promising child on top
        stack[top], stack[top + 1] = a, b
        top += 2
    stack[_HINT] = found
    return best


@njit(cache=True)
def field_at(x, y, stack, grid, full, px, py, ph, start, end, left, box, least, g, cap):
    """:func:`cone_at`, the same value, answered at once where the cap grid
    (:func:`_cap_grid`) says the field is the cap all over the cell of (x, y).
    ``grid`` = (x0, y0, 1 / cell side, columns, rows, growth); ``full`` per cell."""
    fx = (x - grid[0]) * grid[2]
    fy = (y - grid[1]) * grid[2]
    if fx >= 0.0 and fy >= 0.0 and fx < grid[3] and fy < grid[4]:
        if full[int(fy) * int(grid[3]) + int(fx)]:
            return cap
    return cone_at(x, y, stack, px, py, ph, start, end, left, box, least, g, cap)


@njit(cache=True, parallel=True)
def _cone_min(q, grid, full, px, py, ph, start, end, left, box, least, g, cap):
    """:func:`field_at` for each query point."""
    n = q.shape[0]
    out = np.empty(n)
    for block in prange((n + _BLOCK - 1) // _BLOCK):
        stack = np.full(STACK_SIZE, -1, np.int64)
        for j in range(block * _BLOCK, min(n, (block + 1) * _BLOCK)):
            out[j] = field_at(q[j, 0], q[j, 1], stack, grid, full, px, py, ph, start, end,
                              left, box, least, g, cap)
    return out


@njit(cache=True, parallel=True)
def _cone_below(q, bound, px, py, ph, start, end, left, box, least, g):
    """:func:`cone_at` at each source point q[j] with ``bound[j]`` (its own
    value) for the cap: min(bound[j], the field there), found with the
    search pruned from the start (a source is dominated exactly when the
    result is below its value)."""
    n = q.shape[0]
    out = np.empty(n)
    for block in prange((n + _BLOCK - 1) // _BLOCK):
        stack = np.full(STACK_SIZE, -1, np.int64)
        for j in range(block * _BLOCK, min(n, (block + 1) * _BLOCK)):
            out[j] = cone_at(q[j, 0], q[j, 1], stack, px, py, ph, start, end, left, box,
                             least, g, bound[j])
    return out


@njit(cache=True)
def _cell_reaches_below(x0, y0, x1, y1, stack, px, py, ph, start, end, left, box, least, g,
                        cap):
    """True if some cone h_k + g |x - x_k| may fall below ``cap`` somewhere in
    the box [x0, x1] x [y0, y1] (its distance to the box, not to a point)."""
    top = 1
    stack[0] = 0
    while top > 0:
        top -= 1
        i = stack[top]
        dx = max(box[i, 0] - x1, 0.0, x0 - box[i, 2])
        dy = max(box[i, 1] - y1, 0.0, y0 - box[i, 3])
        if least[i] + g * math.sqrt(dx * dx + dy * dy) >= cap:
            continue
        if left[i] < 0:
            for k in range(start[i], end[i]):
                dx = max(x0 - px[k], 0.0, px[k] - x1)
                dy = max(y0 - py[k], 0.0, py[k] - y1)
                if ph[k] + g * math.sqrt(dx * dx + dy * dy) < cap:
                    return True
            continue
        stack[top], stack[top + 1] = left[i], left[i] + 1
        top += 2
    return False


@njit(cache=True, parallel=True)
def _full_cells(grid, px, py, ph, start, end, left, box, least, g, cap):
    """Per cell of ``grid``: no cone reaches below (1 + CAP_MARGIN) cap in it
    (the cell grown by grid[5], for the rounding of a query's cell index)."""
    side = 1.0 / grid[2]
    grow = grid[5]
    nx, ny = int(grid[3]), int(grid[4])
    full = np.zeros(nx * ny, np.bool_)
    above = cap * (1.0 + CAP_MARGIN)
    for row in prange(ny):
        stack = np.empty(_STACK, np.int64)
        for col in range(nx):
            x0 = grid[0] + col * side - grow
            y0 = grid[1] + row * side - grow
            full[row * nx + col] = not _cell_reaches_below(
                x0, y0, x0 + side + 2 * grow, y0 + side + 2 * grow, stack, px, py, ph, start,
                end, left, box, least, g, above)
    return full


def _cap_grid(points, cap, tree, g):
    """A grid over the sources' bounding box (cells of GRID_CELLS times the cap,
    at most GRID_MAX a side) flagging the cells where the field is the cap
    throughout, so most queries of a constant user size skip the tree search.
    Empty (no cell) without a finite cap."""
    empty = (np.array([0.0, 0.0, 1.0, 0.0, 0.0, 0.0]), np.zeros(0, np.bool_))
    if not math.isfinite(cap):
        return empty
    lo, hi = points.min(axis=0), points.max(axis=0)
    extent = float((hi - lo).max())
    side = max(GRID_CELLS * cap, extent / GRID_MAX)
    if not (side > 0 and math.isfinite(side)):
        return empty
    nx = int(math.ceil((hi[0] - lo[0]) / side)) + 1
    ny = int(math.ceil((hi[1] - lo[1]) / side)) + 1
    # grown by a share of the side and by a few ulps of the coordinates (far from the
    # origin the cell corners round by more than GRID_MARGIN of a side)
    grow = max(GRID_MARGIN * side, 16 * np.spacing(float(np.abs(points).max())))
    grid = np.array([lo[0], lo[1], 1.0 / side, float(nx), float(ny), grow])
    full = _full_cells(grid, tree.x, tree.y, tree.value, tree.start, tree.end, tree.left,
                       tree.box, tree.least, g, cap)
    return grid, full


# --- feature size: distance to the segments not adjacent to one's own ----------------


@njit(cache=True, inline="always")
def _point_segment_distance(x, y, ax, ay, bx, by):
    dx, dy = bx - ax, by - ay
    t = ((x - ax) * dx + (y - ay) * dy) / (dx * dx + dy * dy)
    t = min(1.0, max(0.0, t))
    return math.sqrt((x - ax - t * dx) ** 2 + (y - ay - t * dy) ** 2)


@njit(cache=True, parallel=True)
def _feature_distance(q, excluded, ids, a, b, start, end, left, box):
    """For each query point j: the distance to the nearest segment whose id is
    not in excluded[j] (inf if there is none)."""
    n = q.shape[0]
    out = np.empty(n)
    for block in prange((n + _BLOCK - 1) // _BLOCK):
        stack = np.empty(_STACK, np.int64)
        for j in range(block * _BLOCK, min(n, (block + 1) * _BLOCK)):
            x, y = q[j, 0], q[j, 1]
            best = np.inf
            top = 1
            stack[0] = 0
            while top > 0:
                top -= 1
                i = stack[top]
                if _box_distance(box, i, x, y) >= best:
                    continue
                if left[i] < 0:
                    for k in range(start[i], end[i]):
                        s = ids[k]
                        skip = False
                        for c in range(excluded.shape[1]):
                            skip = skip or s == excluded[j, c]
                        if skip:
                            continue
                        d = _point_segment_distance(x, y, a[k, 0], a[k, 1], b[k, 0], b[k, 1])
                        best = min(best, d)
                    continue
                c0, c1 = left[i], left[i] + 1
                if _box_distance(box, c0, x, y) < _box_distance(box, c1, x, y):
                    c0, c1 = c1, c0
                stack[top], stack[top + 1] = c0, c1
                top += 2
            out[j] = best
    return out


class _Boundary:
    """The domain's segments, flat, with each segment's loop neighbours."""

    def __init__(self, domain: Domain):
        self.a = np.ascontiguousarray(domain.points[domain.segments[:, 0]])
        self.b = np.ascontiguousarray(domain.points[domain.segments[:, 1]])
        self.length = np.hypot(*(self.b - self.a).T)
        ids = np.arange(len(self.a), dtype=np.int64)
        self.prev, self.next = ids.copy(), ids.copy()
        first = 0
        for loop in domain.loops:  # Domain.segments: loop after loop, in loop order
            span = ids[first : first + len(loop)]
            self.prev[span] = np.roll(span, 1)
            self.next[span] = np.roll(span, -1)
            first += len(loop)
        self.ends = np.asarray(domain.segments, np.int64)
        self.incident = _incident(self.ends, len(domain.points))
        self.tree = _Tree(np.minimum(self.a, self.b), np.maximum(self.a, self.b), self.length)
        self.ids = ids[self.tree.order]
        self.a_sorted = np.ascontiguousarray(self.a[self.tree.order])
        self.b_sorted = np.ascontiguousarray(self.b[self.tree.order])

    def feature_size(self, xy: np.ndarray, excluded: np.ndarray) -> tuple:
        """(b) at each point: (the distance to the segments not in its row of
        ``excluded``, the floor: FEATURE_FLOOR times the point's own
        segments' length, the first two entries of the row).  The feature
        size is the distance where it reaches the floor (:func:`_resolved`)."""
        t = self.tree
        distance = _feature_distance(
            xy, excluded, self.ids, self.a_sorted, self.b_sorted, t.start, t.end, t.left, t.box
        )
        first, second = excluded[:, 0], excluded[:, 1]
        own = np.minimum(self.length[first], self.length[second])
        own[(first < 0) | (second < 0)] = 0.0  # a free point: on no segment
        return distance, FEATURE_FLOOR * own

    def along(self, segment: np.ndarray) -> np.ndarray:
        """Exclusion rows for points inside segments: the segment, its two
        neighbours and every segment meeting it at an end (junctions and the
        other side of an interior constraint, in planar-graph domains)."""
        return np.column_stack([segment, self.prev[segment], self.next[segment],
                                self.incident[self.ends[segment, 0]],
                                self.incident[self.ends[segment, 1]]])


def _incident(ends: np.ndarray, n: int) -> np.ndarray:
    """(n, D) the segments at each node, padded with -1."""
    node = ends.ravel()
    seg = np.repeat(np.arange(len(ends), dtype=np.int64), 2)
    order = np.argsort(node, kind="stable")
    node, seg = node[order], seg[order]
    count = np.bincount(node, minlength=n)
    out = np.full((n, max(int(count.max(initial=0)), 1)), -1, np.int64)
    rank = np.arange(len(node)) - np.concatenate([[0], np.cumsum(count)])[node]
    out[node, rank] = seg
    return out


def _resolved(distance, floor):
    """The feature size (b): the distance, or inf (no size) for a gap below the floor."""
    return np.where(distance >= floor, distance, np.inf)


# --- user size ---------------------------------------------------------------------------


def as_size_function(size, name: str = "size") -> Callable[[np.ndarray], np.ndarray]:
    """A positive number or a vectorised callable h(xy: (n, 2)) -> (n,) as a
    checked function: its values must be finite and > 0, one per point."""
    if callable(size):

        def checked(xy: np.ndarray) -> np.ndarray:
            try:
                values = np.asarray(size(xy), dtype=np.float64)
            except (TypeError, ValueError) as error:
                raise ValueError(f"{name}(xy) did not return numbers: {error}") from None
            if values.shape != (len(xy),):
                raise ValueError(
                    f"{name}(xy) must return shape ({len(xy)},) for xy of shape "
                    f"{xy.shape}, got {values.shape}"
                )
            bad = ~(np.isfinite(values) & (values > 0))
            if bad.any():
                k = int(np.argmax(bad))
                raise ValueError(
                    f"{name}(xy) must be finite and > 0; at {tuple(xy[k].tolist())} "
                    f"it is {float(values[k])!r}"
                )
            return values

        return checked
    value = _positive_number(size, name)
    return lambda xy: np.full(len(xy), value)


def _float(value, name: str, expected: str) -> float:
    """``value`` as a float, or a TypeError naming ``name``: text and booleans are
    refused, though float() would take "0.1" and True."""
    try:
        if isinstance(value, (str, bytes, bool, np.bool_)):
            raise TypeError
        return float(value)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be {expected}, got {type(value).__name__}") from None


def _positive_number(value, name: str) -> float:
    number = _float(value, name, "a positive number or a callable")
    if not (math.isfinite(number) and number > 0):
        raise ValueError(f"{name} must be finite and > 0, got {value!r}")
    return number


# --- the field ---------------------------------------------------------------------------


class SizeField:
    """h(x) = min(cap, min_k h_k + g |x - x_k|): a size field with gradation <= g.

    Attributes
    ----------
    points : (K, 2) float64
        The sources x_k that are kept (no other source dominates them).
    values : (K,) float64
        Their h_k; h(points) == values exactly.
    cap : float
        The user's constant size, or inf.
    gradation : float
        g, the bound on |grad h|.
    sample_points, sample_values : (S, 2), (S,)
        Every source considered before pruning, with its input value
        min(input spacing at nodes, feature size, user size);
        h(x) <= sample_values[k] + g |x - sample_points[k]| for every k.
    """

    def __init__(self, points, values, *, gradation=0.25, cap=math.inf):
        """A field from given sources (x_k, h_k), h_k > 0; dominated sources are dropped."""
        self.gradation = _gradation(gradation)
        self.cap = float(cap)
        points = np.ascontiguousarray(np.asarray(points, dtype=np.float64).reshape(-1, 2))
        values = np.ascontiguousarray(np.asarray(values, dtype=np.float64).reshape(-1))
        if len(points) != len(values) or not len(points):
            raise ValueError(
                f"need as many values as points (> 0), got {len(points)} points and "
                f"{len(values)} values"
            )
        if not (np.isfinite(points).all() and np.isfinite(values).all() and (values > 0).all()):
            raise ValueError("source points must be finite and source values finite and > 0")
        self.sample_points, self.sample_values = points, values
        self._set_sources(points, values)
        t = self._tree
        graded = np.empty(len(values))  # in the tree's (Morton) order: warm starts
        graded[t.order] = _cone_below(t.lo, t.value, t.x, t.y, t.value, t.start, t.end, t.left,
                                      t.box, t.least, float(self.gradation))
        keep = (graded >= values) & (values < self.cap)  # the others change no value
        if not keep.any():
            keep = values == values.min()
        self._set_sources(points[keep], values[keep])

    def _set_sources(self, points, values):
        self._tree = _Tree(points, points, values)
        self.points = self._tree.lo
        self.values = self._tree.value
        self._grid = _cap_grid(self.points, self.cap, self._tree, self.gradation)

    def __call__(self, xy) -> np.ndarray:
        """h at each row of ``xy`` ((n, 2) -> (n,) float64)."""
        xy = np.ascontiguousarray(np.asarray(xy, dtype=np.float64).reshape(-1, 2))
        if len(xy) < SORTED_QUERIES or math.isfinite(self.cap):  # the cap grid answers most
            return _cone_min(xy, *self.kernel_args())
        order = _morton_order(xy)  # neighbours in turn: each answer warm-starts the next
        out = np.empty(len(xy))
        out[order] = _cone_min(np.ascontiguousarray(xy[order]), *self.kernel_args())
        return out

    def kernel_args(self) -> tuple:
        """The arrays and numbers :func:`field_at` takes after its stack, for
        kernels that evaluate h themselves (the cap grid, x_k, y_k, h_k, the
        tree, g, cap)."""
        t = self._tree
        return (*self._grid, t.x, t.y, t.value, t.start, t.end, t.left, t.box, t.least,
                float(self.gradation), float(self.cap))

    def radius(self, xy) -> np.ndarray:
        """The eq. 2 bubble radius of an equilateral triangle of side h(x)."""
        return _EQUILATERAL_RADIUS * self(xy)

    def __repr__(self) -> str:
        return (
            f"SizeField(sources={len(self.values)}, h in [{self.values.min():.4g}, "
            f"{self.values.max():.4g}], gradation={self.gradation:g}, cap={self.cap:g})"
        )

    @classmethod
    def from_domain(
        cls, domain: Domain, size=None, gradation: float = 0.25, max_sources: int = MAX_SOURCES
    ) -> SizeField:
        """The size field of a domain: min of (a) input spacing, (b) feature size
        and (c) the user ``size`` (None, a positive number or a callable
        h(xy: (n, 2)) -> (n,)), graded to ``gradation``.

        Raises ValueError for a bad ``size`` or ``gradation`` and when the sizes
        would need more than ``max_sources`` samples."""
        if not isinstance(domain, Domain):
            raise TypeError(f"expected a Domain, got {type(domain).__name__}")
        g = _gradation(gradation)
        cap = math.inf if size is None or callable(size) else _positive_number(size, "size")
        if math.isfinite(cap):  # no size (cap inf) is not a size far beyond the domain
            cap = min(cap, CAP_REACH * float(np.ptp(domain.points, axis=0).max()))
        user = None if size is None else as_size_function(size)
        boundary = _Boundary(domain)
        points, values = _node_sources(domain, boundary, user, cap)
        nodes = cls(points, values, gradation=g, cap=cap)
        extra_p, extra_v = _segment_sources(boundary, nodes, user, max_sources)
        points, values = np.vstack([points, extra_p]), np.concatenate([values, extra_v])
        if callable(size):
            field = cls(points, values, gradation=g, cap=cap)
            extra_p, extra_v = _quadtree_sources(domain, field, user, max_sources - len(values))
            points, values = np.vstack([points, extra_p]), np.concatenate([values, extra_v])
        return cls(points, values, gradation=g, cap=cap)


def _gradation(g) -> float:
    g = _float(g, "gradation", "a number")
    if not (math.isfinite(g) and g >= 0):
        raise ValueError(f"gradation must be finite and >= 0, got {g!r}")
    return g


def _node_sources(domain, boundary, user, cap):
    """Every boundary node with min((a) spacing, (b) feature size, (c) user size)."""
    seg_from = np.full(len(domain.points), -1, np.int64)
    seg_from[domain.segments[:, 0]] = np.arange(len(domain.segments))
    free = seg_from < 0  # a free point of a planar graph: on no segment
    seg_from[free] = 0
    leaving = boundary.length[seg_from]
    arriving = boundary.length[boundary.prev[seg_from]]
    spacing = np.sqrt(0.5 * (arriving**2 + leaving**2))  # eq. 1 area as an equilateral side
    if free.any():
        from scipy.spatial import cKDTree

        spacing[free] = cKDTree(domain.points).query(domain.points[free], k=2)[0][:, 1]
    excluded = np.column_stack([seg_from, boundary.prev[seg_from], seg_from,
                                boundary.incident])
    excluded[free, :3] = -1
    values = np.minimum(spacing, _resolved(*boundary.feature_size(domain.points, excluded)))
    if user is not None:
        values = np.minimum(values, user(domain.points))
    return np.array(domain.points), np.minimum(values, cap)


def _segment_sources(boundary, nodes, user, max_sources):
    """Samples inside the segments where the feature size (b) or a callable
    user size (c) may dip below the field of the nodes.

    On an interval of length L of segment s the distance d to the other
    segments is 1-Lipschitz, so with f = max(d, floor) (the segment's floor,
    below which the feature size is inf) the feature size is >= (f0 + f1 - L) / 2
    (f0, f1 at the ends), and inf all over if (d0 + d1 + L) / 2 < floor; the
    final field is <= min(e0, e1) + g L / 2 (e: the field's bound at the ends).
    The interval is halved while the first is below the second over
    FEATURE_SLACK, unless the gap is below the floor all over, so on the
    boundary h <= FEATURE_SLACK * feature size; with a callable user size also
    while L > SAMPLING * its smaller end value.  Returns the samples whose value
    is below the node field (the others are dominated)."""
    seg = np.arange(len(boundary.a), dtype=np.int64)
    t0, t1 = np.zeros(len(seg)), np.ones(len(seg))
    ends = [_sample_values(boundary, nodes, user, seg, t) for t in (t0, t1)]
    (d0, floor, u0, _, e0, _), (d1, _, u1, _, e1, _) = ends  # at the nodes: the node field
    g = nodes.gradation
    kept_p, kept_v = [], []
    total = 0
    for _ in range(60):  # t halves each round: 2**-60 is below any float spacing
        L = (t1 - t0) * boundary.length[seg]
        bound = 0.5 * (np.maximum(d0, floor) + np.maximum(d1, floor) - L)
        split = bound < (np.minimum(e0, e1) + 0.5 * g * L) / FEATURE_SLACK
        split &= 0.5 * (d0 + d1 + L) >= floor
        if user is not None:
            split |= L > SAMPLING * np.minimum(u0, u1)
        if not split.any():
            break
        seg, t0, t1 = seg[split], t0[split], t1[split]
        d0, d1, floor, u0, u1, e0, e1 = (v[split] for v in (d0, d1, floor, u0, u1, e0, e1))
        tm = 0.5 * (t0 + t1)
        total += len(tm)
        if total > max_sources:
            raise MeshingError(
                f"the size field needs more than {max_sources} boundary samples: the sizes "
                "(user size or feature size) are too small for this domain"
            )
        dm, _, um, value, em_nodes, xy = _sample_values(boundary, nodes, user, seg, tm)
        useful = value < em_nodes
        em = np.minimum(value, em_nodes)
        kept_p.append(xy[useful])
        kept_v.append(value[useful])
        seg = np.concatenate([seg, seg])
        t0, t1 = np.concatenate([t0, tm]), np.concatenate([tm, t1])
        d0, d1 = np.concatenate([d0, dm]), np.concatenate([dm, d1])
        floor = np.concatenate([floor, floor])
        u0, u1 = np.concatenate([u0, um]), np.concatenate([um, u1])
        e0, e1 = np.concatenate([e0, em]), np.concatenate([em, e1])
    if not kept_p:
        return np.zeros((0, 2)), np.zeros(0)
    return np.vstack(kept_p), np.concatenate(kept_v)


def _sample_values(boundary, nodes, user, seg, t):
    """At p = a + t (b - a) on each segment: (the distance and the floor of
    the feature size, the user size, the sample's input value, the node
    field, p)."""
    xy = boundary.a[seg] + t[:, None] * (boundary.b[seg] - boundary.a[seg])
    distance, floor = boundary.feature_size(xy, boundary.along(seg))
    user_value = np.full(len(t), np.inf) if user is None else user(xy)
    value = np.minimum(np.minimum(_resolved(distance, floor), user_value), nodes.cap)
    return distance, floor, user_value, value, nodes(xy), xy


def _quadtree_sources(domain, field, user, room):
    """Centres of a quadtree over the domain's bounding square, a cell split
    while its side exceeds QUADTREE_SAMPLING times the user size at its centre; only
    centres where the user size is below the field so far are kept."""
    lo = domain.points.min(axis=0)
    side = float((domain.points.max(axis=0) - lo).max())
    centres, sides = (lo + 0.5 * side)[None, :], np.array([side])
    kept_p, kept_v = [], []
    total = 0
    quarter = np.array([[-1, -1], [1, -1], [-1, 1], [1, 1]], dtype=np.float64) * 0.25
    for _ in range(60):
        total += len(centres)
        if total > room:
            raise MeshingError(
                f"the size field needs more than {room} more samples: the user size "
                "is too small for this domain"
            )
        value = user(centres)
        useful = value < field(centres)
        kept_p.append(centres[useful])
        kept_v.append(value[useful])
        split = sides > QUADTREE_SAMPLING * value
        if not split.any():
            break
        c, s = centres[split], sides[split]
        centres = (c[:, None, :] + quarter[None, :, :] * s[:, None, None]).reshape(-1, 2)
        sides = np.repeat(0.5 * s, 4)
    return np.vstack(kept_p), np.concatenate(kept_v)


def field_count(size, points, triangles) -> float:
    """The elements a size field asks for over a triangulated region: the sum
    over its triangles of area * 4 / (sqrt(3) h(centroid)^2), the equilateral
    triangles of side h that fit (a midpoint rule on the mesh itself; the
    quality study's ``predicted_count`` integrates to a tolerance instead).
    ``size`` maps (n, 2) points to (n,) sizes."""
    P = np.asarray(points, dtype=np.float64)
    T = np.asarray(triangles)
    u, v = P[T[:, 1]] - P[T[:, 0]], P[T[:, 2]] - P[T[:, 0]]
    area = 0.5 * np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0])
    h = np.asarray(size(np.ascontiguousarray(P[T].mean(axis=1))), dtype=np.float64)
    return float(np.sum(area * 4.0 / (math.sqrt(3.0) * h * h)))
