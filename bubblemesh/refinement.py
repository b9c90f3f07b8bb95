"""Boundary refinement to a size field: the *refined boundary* of paper §2.1.

The paper's eq. 1-2 read the element size off the boundary spacing, so a
polygon given by its corners, or a long edge next to a finely sampled arc,
must first be split.  :func:`refine_boundary` splits every input segment
whose length the size field h does not allow:

* the number of pieces is n = ceil(integral of ds / h) along the segment (the
  trapezoid rule on adaptive samples spaced <= ``resolution`` times h: at an
  eighth, its error at the kinks of a cone field stays far below 1%), and the
  new nodes sit at equal h-weighted arc length, so each piece has
  integral ds / h = I / n <= 1: its length is at most h(midpoint) / (1 - g / 2)
  for a field of gradation g, and at least about half of it when n >= 2;
* input nodes are never moved or dropped and keep their order; each loop starts
  at its first input node;
* a new node is computed as a + t (b - a); if that is not exactly on the
  segment, with t rounded to 40, 30 or 20 bits (exact when the coordinates
  have spare low bits: integers, short binary fractions); else it is moved to
  the nearest float point (within ``WINDOW`` ulps along the dominant axis, the other coordinate
  recomputed on the line and tried at +-1 ulp) that is *exactly* on the
  segment by :func:`bubblemesh.predicates.orient2d`.  Such a point exists for
  axis-aligned segments and for slopes of small integers or dyadic rationals;
  for a general segment none may exist in the float grid at all, and the node
  is then the candidate of the window nearest the line (a fraction of an ulp
  off it): ``RefinedBoundary.on_segment`` marks which nodes are exact and
  ``max_deviation`` bounds the others' distance to their input segment;
* nodes advance strictly along the segment's dominant axis; a node that cannot
  (pieces a few ulps long) is dropped, so no two nodes coincide;
* with ``sharp_angle``, the walls of sharper corners first get nodes in
  geometric progression from the corner (:mod:`bubblemesh._wedges`) and
  the rule above splits the rest of each wall.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, replace

import numpy as np
from numba import njit, prange

from bubblemesh._wedges import corner_angles, free_points, wedge_parameters
from bubblemesh.domain import Domain
from bubblemesh.errors import GeometryError, MeshingError
from bubblemesh.predicates import orient2d
from bubblemesh.sizing import MAX_SOURCES, SizeField, as_size_function

__all__ = ["RefinedBoundary", "refine_boundary"]

DYADIC_BITS = (40, 30, 20)  # t rounded to these many bits moves a node <= 2**-21 L
NEAREST_CAP = 1.3  # rounding="nearest": no piece longer than this many h
WINDOW = 2  # ulps searched along the dominant axis for a point exactly on the segment
_EXACT, _NEAR, _DROPPED = 1, 0, -1


@dataclass(frozen=True, eq=False)
class RefinedBoundary:
    """The refined loops (outer first), ready for :meth:`Domain.from_loops`.

    Attributes
    ----------
    loops : tuple of (m_k, 2) float64 arrays
        The refined loops, in the input's orientation, each starting at its
        first input node.
    input_index : tuple of int64 arrays
        ``loops[k][input_index[k][i]]`` is input node i of loop k (bitwise).
    on_segment : tuple of bool arrays
        Per refined node: exactly on its input segment (orient2d == 0, inside
        the segment); input nodes are True.
    max_deviation : float
        Largest distance of a node with ``on_segment`` False from its segment's
        line (0.0 when every node is exact).
    """

    loops: tuple[np.ndarray, ...]
    input_index: tuple[np.ndarray, ...]
    on_segment: tuple[np.ndarray, ...]
    max_deviation: float
    source: Domain | None = None

    def segment_sources(self) -> np.ndarray:
        """Per refined segment (loop after loop): the index of the input segment
        (of ``source.segments``) it lies on."""
        out, first = [], 0
        for loop, index in zip(self.loops, self.input_index):
            out.append(first + np.searchsorted(index, np.arange(len(loop)), side="right") - 1)
            first += len(index)
        return np.concatenate(out) if out else np.zeros(0, np.int64)

    def to_domain(self) -> Domain:
        """Validate the refined loops as a Domain (GeometryError if they conflict);
        refined segments keep their input segment's marker, and a planar-graph
        source keeps its interior constraints, free points and regions."""
        source = self.source
        if source is None:
            return Domain.from_loops(self.loops)
        origin = self.segment_sources()
        marks = np.asarray(source.markers)[origin]
        interior = np.asarray(source.interior)
        if not interior.any() and len(source.points) == sum(len(ix) for ix in source.loops):
            try:
                domain = Domain.from_loops(self.loops)
            except GeometryError as error:  # islands in holes: the planar-graph reading nests
                if not any(why in str(error) for why in ("nested holes", "outside the outer")):
                    raise
                return _graph_domain(self, source, marks, interior[origin])
            if source.segment_markers is None and not source.marker_names and (
                    source.regions is None):
                return domain
            return replace(domain, segment_markers=_frozen(marks),
                           marker_names=source.marker_names, regions=source.regions)
        return _graph_domain(self, source, marks, interior[origin])

    def exact_only(self) -> RefinedBoundary:
        """The same refinement without the nodes that are not exactly on their
        input segment: its segments lie on the input's, so it is as valid as
        the input."""
        keep = self.on_segment
        index = tuple(np.cumsum(k)[i] - 1 for k, i in zip(keep, self.input_index))
        return RefinedBoundary(tuple(loop[k] for loop, k in zip(self.loops, keep)), index,
                               tuple(k[k] for k in keep), 0.0, self.source)


def _frozen(array: np.ndarray) -> np.ndarray:
    array = np.ascontiguousarray(array)
    array.setflags(write=False)
    return array


def _graph_domain(refined: RefinedBoundary, source: Domain, marks, interior) -> Domain:
    """The refined walks, the source's free points and regions, as a planar-graph
    domain (loop segments counted by parity, interior ones not)."""
    from bubblemesh._cdt import BOUNDARY, INTERIOR

    on_loops = np.zeros(len(source.points), bool)
    on_loops[np.concatenate(source.loops)] = True
    free = np.asarray(source.points)[~on_loops]
    vertices = np.concatenate([*refined.loops, free])
    pairs, first = [], 0
    for loop in refined.loops:
        ix = first + np.arange(len(loop))
        pairs.append(np.column_stack([ix, np.roll(ix, -1)]))
        first += len(loop)
    unique, where, inverse = np.unique(vertices, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(where, kind="stable")
    rank = np.empty(len(order), np.int64)
    rank[order] = np.arange(len(order))
    S = rank[inverse.reshape(-1)][np.concatenate(pairs)]
    flags = np.where(interior, INTERIOR, BOUNDARY).astype(np.uint8)
    regions = () if source.regions is None else source.regions
    return Domain._from_graph(unique[order], S, marks, (), regions,
                              source.marker_names, mode="parity", flags=flags)


def refine_boundary(
    domain_or_loops, h, *, resolution: float = 0.125, max_nodes: int = MAX_SOURCES,
    sharp_angle: float = 0.0, rounding: str = "up", splits=None, ladders: bool = False,
) -> RefinedBoundary:
    """Split the boundary segments to the size ``h`` (a :class:`SizeField`, a
    positive number or a vectorised callable (n, 2) -> (n,)).

    ``domain_or_loops`` is a :class:`Domain` (its loops, oriented) or loops as
    :meth:`Domain.from_loops` takes them (validated, kept in the given order).
    The walls of corners sharper than ``sharp_angle`` (radians) get nodes in
    geometric progression from the corner (:mod:`bubblemesh._wedges`), the
    rest of them the nodes above, every one a zigzag unless ``ladders``: then
    a corner that holds a ladder gets its in-phase walls, whose rungs, free
    nodes, :func:`~bubblemesh._wedges.ladder_points` gives (walls without
    their rungs leave 0.68 trapezoids).  ``rounding="nearest"`` takes n = round(I)
    pieces instead of ceil(I) (at least ceil(I / NEAREST_CAP)): pieces up to
    NEAREST_CAP h, but on average as long as h, so the first row of elements
    along a wall is as dense as the field, not up to twice as dense.
    ``splits`` {(i, j): t}: the new nodes of the input segment from node i
    to node j (of a given Domain) at the increasing parameters t in (0, 1)
    instead (a segment with graded corner walls keeps those).  Raises
    ValueError for a bad ``h``, ``rounding`` or ``splits`` and when more
    than ``max_nodes`` samples or nodes would be needed."""
    given = isinstance(domain_or_loops, Domain)
    domain = domain_or_loops if given else Domain.from_loops(domain_or_loops)
    rings = _input_rings(domain, given)
    size = h if isinstance(h, SizeField) else as_size_function(h, "h")
    if not (math.isfinite(resolution) and 0 < resolution <= 1):
        raise ValueError(f"resolution must be in (0, 1], got {resolution!r}")
    if isinstance(sharp_angle, bool) or not (
            isinstance(sharp_angle, numbers.Real) and 0 <= sharp_angle <= math.pi):
        raise ValueError(f"sharp_angle must be in [0, pi], got {sharp_angle!r}")
    if rounding not in ("up", "nearest"):
        raise ValueError(f"rounding must be 'up' or 'nearest', got {rounding!r}")
    a = np.concatenate(rings)
    b = np.concatenate([np.roll(ring, -1, axis=0) for ring in rings])
    source = domain if given else None
    canon, flip = _canonical(source)
    ca, cb = (a, b) if canon is None else (a[canon], b[canon])
    length = np.hypot(*(cb - ca).T)
    node_a = np.concatenate(domain.loops) if source is not None else np.arange(len(a))
    node_b = np.concatenate([np.roll(ix, -1) for ix in np.split(
        node_a, np.cumsum([len(ring) for ring in rings])[:-1])])
    if canon is not None:
        node_a, node_b = node_a[canon], node_b[canon]
    walls = ~np.asarray(domain.interior, bool) & ladders  # where a ladder may stand
    graded = wedge_parameters(ca, cb, node_a, node_b, corner_angles(domain), size,
                              float(sharp_angle), free_points(domain),
                              walls if canon is None else walls[canon])
    if splits:
        graded = _with_splits(graded, node_a, node_b, splits, given)
    seg, t, values = _samples(ca, cb, length, size, resolution, max_nodes)
    t_new, ptr = _split_parameters(seg, t, values, length, len(ca), max_nodes, graded,
                                   rounding == "nearest")
    points, status, offset = _place(ca, cb, t_new, ptr)
    if canon is not None:  # both sides of an interior constraint get the same nodes
        points, status, offset, ptr = _expand(points, status, offset, ptr, canon, flip)
    out = _assemble(rings, a, points, status, offset, ptr)
    return replace(out, source=source)


def _with_splits(graded, node_a, node_b, splits, given):
    """The graded parameters (seg, t, lo, hi) with the ``splits`` of
    :func:`refine_boundary` added: their segments' t given, nothing left to
    split to the field ([lo, hi] empty)."""
    if not given:
        raise ValueError("splits needs a Domain: they name its segments by their nodes")
    fixed_seg, fixed_t, lo, hi = graded
    lo, hi = lo.copy(), hi.copy()
    segs, ts = [fixed_seg], [fixed_t]
    for key, t in splits.items():
        try:
            i, j = (int(v) for v in key)
        except (TypeError, ValueError):
            raise ValueError(f"splits: a key must be a pair of node indices, got {key!r}") from None
        hit = np.flatnonzero((node_a == i) & (node_b == j))
        try:
            t = np.asarray(t, dtype=np.float64).reshape(-1)
        except (TypeError, ValueError):
            t = np.array([np.nan])  # refused below
        if not len(hit):
            raise ValueError(f"splits: ({i}, {j}) is not a segment of the domain")
        if not (np.all(np.isfinite(t)) and np.all(t > 0) and np.all(t < 1)
                and np.all(np.diff(t) > 0)):
            raise ValueError(f"splits: the parameters of ({i}, {j}) must increase within (0, 1)")
        k = int(hit[0])
        if lo[k] > 0 or hi[k] < 1:  # graded toward a sharp corner: the grading wins
            continue
        segs.append(np.full(len(t), k, np.int64))
        ts.append(t)
        lo[k] = hi[k] = 0.0
    seg, t = np.concatenate(segs), np.concatenate(ts)
    order = np.lexsort((t, seg))
    return seg[order], t[order], lo, hi


def _canonical(domain: Domain | None):
    """For a domain with interior constraints (segments present both ways): the
    first segment of each pair of twins, and whether each segment runs against
    it; (None, None) when every segment is its own."""
    if domain is None or not np.asarray(domain.interior).any():
        return None, None
    S = np.asarray(domain.segments)
    key = np.sort(S, axis=1)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    canon_of = first[inverse]  # the segment refined for each one
    keep = np.sort(first)
    slot = np.searchsorted(keep, canon_of)
    flip = S[:, 0] != S[canon_of, 0]
    return keep, (slot, flip)


def _expand(points, status, offset, ptr, canon, slot_flip):
    """The refined nodes of every segment from its canonical twin's (reversed
    when it runs the other way)."""
    slot, flip = slot_flip
    counts = ptr[slot + 1] - ptr[slot]
    new_ptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    pos = np.arange(new_ptr[-1]) - np.repeat(new_ptr[:-1], counts)
    reverse = np.repeat(flip, counts)
    src = np.repeat(ptr[slot], counts) + np.where(reverse, np.repeat(counts, counts) - 1 - pos, pos)
    return points[src], status[src], offset[src], new_ptr


def _input_rings(domain: Domain, given: bool) -> list[np.ndarray]:
    """A given domain's oriented loops, or loops as the user gave them
    (:meth:`Domain.from_loops` keeps their points in order)."""
    if given:
        return [np.array(domain.points[ix]) for ix in domain.loops]
    ends = np.cumsum([len(ix) for ix in domain.loops])[:-1]
    return [np.array(ring) for ring in np.split(domain.points, ends)]


def _samples(a, b, length, size, resolution, max_nodes):
    """Adaptive samples (segment, t, h) with ends: an interval is halved while
    it is longer than ``resolution`` times the smaller h at its ends."""
    n = len(a)
    seg = np.arange(n, dtype=np.int64)
    all_seg, all_t = [seg, seg], [np.zeros(n), np.ones(n)]
    all_h = [size(a), size(b)]
    t0, t1, h0, h1 = all_t[0], all_t[1], all_h[0], all_h[1]
    total = 2 * n
    for _ in range(60):  # t halves each round: 2**-60 is below any float spacing
        split = (t1 - t0) * length[seg] > resolution * np.minimum(h0, h1)
        if not split.any():
            break
        seg, t0, t1, h0, h1 = seg[split], t0[split], t1[split], h0[split], h1[split]
        tm = 0.5 * (t0 + t1)
        total += len(tm)
        if total > max_nodes:
            raise MeshingError(
                f"refining the boundary needs more than {max_nodes} samples: h is too "
                "small for this boundary"
            )
        hm = size(a[seg] + tm[:, None] * (b[seg] - a[seg]))
        all_seg.append(seg)
        all_t.append(tm)
        all_h.append(hm)
        seg = np.concatenate([seg, seg])
        t0, t1 = np.concatenate([t0, tm]), np.concatenate([tm, t1])
        h0, h1 = np.concatenate([h0, hm]), np.concatenate([hm, h1])
    seg, t, values = np.concatenate(all_seg), np.concatenate(all_t), np.concatenate(all_h)
    order = np.lexsort((t, seg))
    return seg[order], t[order], values[order]


def _split_parameters(seg, t, values, length, n_seg, max_nodes, graded, nearest=False):
    """Parameters of the new nodes of each segment (flat, with offsets ``ptr``):
    the ``graded`` ones (:func:`~bubblemesh._wedges.wedge_parameters`) and,
    over the interval [lo, hi] of t they leave, n = ceil(I) pieces of equal
    integral ds / h, I by the trapezoid rule (``nearest``: n = round(I), at
    least ceil(I / NEAREST_CAP))."""
    fixed_seg, fixed_t, lo, hi = graded
    same = seg[1:] == seg[:-1]
    trapezoid = np.diff(t) * length[seg[:-1]] * 0.5 * (1 / values[:-1] + 1 / values[1:])
    weight = np.where(same, trapezoid, 0.0)
    cumulative = np.concatenate([[0.0], np.cumsum(weight)])
    first = np.searchsorted(seg, np.arange(n_seg), side="left")
    last = np.searchsorted(seg, np.arange(n_seg), side="right") - 1
    start = _integral_to(lo, seg, t, cumulative, first, last)
    integral = _integral_to(hi, seg, t, cumulative, first, last) - start
    if nearest:
        pieces = np.maximum(np.floor(integral + 0.5), np.ceil(integral / NEAREST_CAP * (1 - 1e-12)))
    else:
        pieces = np.ceil(integral * (1 - 1e-12))
    pieces = np.maximum(1, pieces).astype(np.int64)
    if pieces.sum() + len(fixed_t) > max_nodes:
        raise MeshingError(f"refining the boundary would create more than {max_nodes} nodes: "
                           "the sizes are far finer than the boundary")
    ptr = np.concatenate([[0], np.cumsum(pieces - 1)]).astype(np.int64)
    owner = np.repeat(np.arange(n_seg), pieces - 1)
    k = np.arange(ptr[-1]) - ptr[owner] + 1
    target = start[owner] + integral[owner] * k / pieces[owner]
    j = np.searchsorted(cumulative, target, side="right") - 1
    j = np.clip(j, first[owner], last[owner] - 1)  # stay inside the segment's samples
    span = cumulative[j + 1] - cumulative[j]
    frac = np.clip((target - cumulative[j]) / np.where(span > 0, span, 1.0), 0.0, 1.0)
    t_new = t[j] + frac * (t[j + 1] - t[j])
    if not len(fixed_t):
        return t_new, ptr
    owner = np.concatenate([owner, fixed_seg])
    order = np.lexsort((np.concatenate([t_new, fixed_t]), owner))
    ptr = np.concatenate([[0], np.cumsum(np.bincount(owner, minlength=n_seg))]).astype(np.int64)
    return np.concatenate([t_new, fixed_t])[order], ptr


def _integral_to(u, seg, t, cumulative, first, last):
    """Per segment s, the running integral of ds / h at t = u[s] (linear between
    its samples; u = 0 and u = 1 give the samples' own values exactly)."""
    below = np.bincount(seg, weights=t < u[seg], minlength=len(u)).astype(np.int64)
    j = np.clip(first + below - 1, first, last - 1)
    span = t[j + 1] - t[j]
    frac = np.clip((u - t[j]) / np.where(span > 0, span, 1.0), 0.0, 1.0)
    inner = cumulative[j] + frac * (cumulative[j + 1] - cumulative[j])
    return np.where(u <= 0.0, cumulative[first], np.where(u >= 1.0, cumulative[last], inner))


@njit(cache=True, inline="always")
def _step(x, k):
    """x moved by k ulps (k in [-WINDOW, WINDOW])."""
    for _ in range(abs(k)):
        x = np.nextafter(x, np.inf if k > 0 else -np.inf)
    return x


@njit(cache=True)
def _candidate(px, py, ax, ay, bx, by, axis, i, j):
    """The point i ulps from p along the dominant axis, its other coordinate put
    back on the line a-b (in floats) and then moved j ulps."""
    if axis == 0:
        cx = _step(px, i)
        return cx, _step(ay + (cx - ax) * ((by - ay) / (bx - ax)), j)
    cy = _step(py, i)
    return _step(ax + (cy - ay) * ((bx - ax) / (by - ay)), j), cy


@njit(cache=True, parallel=True)
def _place(a, b, t, ptr):
    """New nodes of each segment: at a + t (b - a), moved within WINDOW ulps along
    the dominant axis (the other coordinate recomputed on the line, +-1 ulp) to a
    point exactly on the segment if there is one, the nearest first; else the
    candidate nearest the line.  Nodes advance strictly along the dominant axis;
    a node that cannot is dropped."""
    points = np.empty((t.shape[0], 2))
    status = np.full(t.shape[0], _DROPPED, np.int8)
    offset = np.zeros(t.shape[0])  # |orient2d(a, b, p)| / |b - a|: the distance to the line
    order = np.array([0, -1, 1, -2, 2, -3, 3, -4, 4])[: 2 * WINDOW + 1]
    for s in prange(a.shape[0]):
        ax, ay, bx, by = a[s, 0], a[s, 1], b[s, 0], b[s, 1]
        axis = 0 if abs(bx - ax) >= abs(by - ay) else 1
        end = b[s, axis]
        forward = end > a[s, axis]
        behind = a[s, axis]  # the last kept node's coordinate on the dominant axis
        for k in range(ptr[s], ptr[s + 1]):
            px, py = ax + t[k] * (bx - ax), ay + t[k] * (by - ay)
            best_off = np.inf
            for bits in DYADIC_BITS:  # t with few bits: exact for coordinates with spare bits
                scale = 2.0**bits
                td = np.round(t[k] * scale) / scale
                cx, cy = ax + td * (bx - ax), ay + td * (by - ay)
                c = cx if axis == 0 else cy
                if ((behind < c < end) if forward else (end < c < behind)) and orient2d(
                    ax, ay, bx, by, cx, cy
                ) == 0.0:
                    best_off = 0.0
                    points[k, 0], points[k, 1] = cx, cy
                    break
            for i in order if best_off > 0.0 else order[:0]:
                for j in order[:3]:
                    cx, cy = (
                        (px, py)
                        if i == 0 and j == 0
                        else _candidate(px, py, ax, ay, bx, by, axis, i, j)
                    )
                    c = cx if axis == 0 else cy
                    if not ((behind < c < end) if forward else (end < c < behind)):
                        continue
                    off = abs(orient2d(ax, ay, bx, by, cx, cy))
                    if off < best_off:
                        best_off = off
                        points[k, 0], points[k, 1] = cx, cy
                    if off == 0.0:
                        break
                if best_off == 0.0:
                    break
            if best_off < np.inf:
                status[k] = _EXACT if best_off == 0.0 else _NEAR
                offset[k] = best_off / math.hypot(bx - ax, by - ay)
                behind = points[k, axis]
    return points, status, offset


def _assemble(rings, a, points, status, offset, ptr) -> RefinedBoundary:
    """Input node of each segment, then its kept new nodes, loop by loop."""
    kept = status != _DROPPED
    owner = np.repeat(np.arange(len(a)), np.diff(ptr))
    per_segment = 1 + np.bincount(owner[kept], minlength=len(a))
    start = np.concatenate([[0], np.cumsum(per_segment)]).astype(np.int64)
    rank = np.cumsum(kept) - np.concatenate([[0], np.cumsum(kept)])[ptr[owner]]
    out = np.empty((start[-1], 2))
    exact = np.ones(start[-1], dtype=bool)
    out[start[:-1]] = a
    new_at = start[owner[kept]] + rank[kept]
    out[new_at] = points[kept]
    exact[new_at] = status[kept] == _EXACT
    deviation = float(offset[status == _NEAR].max(initial=0.0))
    bounds = np.cumsum([0] + [len(ring) for ring in rings])
    loops, index, flags = [], [], []
    for k in range(len(rings)):
        lo, hi = start[bounds[k]], start[bounds[k + 1]]
        loops.append(out[lo:hi])
        index.append(start[bounds[k] : bounds[k + 1]] - lo)
        flags.append(exact[lo:hi])
    return RefinedBoundary(tuple(loops), tuple(index), tuple(flags), deviation)
