"""The meshing domain: the refined boundary of paper §2.1, validated.

The paper starts from a *refined boundary*: boundary nodes with their
connectivity, one closed loop for the outer boundary and one per hole
(§2.1).  Its node spacing decides the boundary bubbles (eq. 1-2) and its
enclosed area is ``A_geo``, the stopping threshold of the population control
(eq. 6).  :class:`Domain` holds exactly that, after checking that the loops
form a valid polygon with holes, because every later step (the initial
constrained triangulation, the inside test, eq. 6) silently goes wrong on
crossing or badly nested loops.

Every geometric decision here is exact: segment crossings and point-in-loop
tests use :func:`bubblemesh.predicates.orient2d`, and the all-pairs segment
test is a numba sweep over segments sorted by their smallest x, so 10^4-10^5
boundary nodes validate in well under a second.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt
from numba import njit

from bubblemesh.errors import GeometryError
from bubblemesh.predicates import orient2d, out_of_range, out_of_range_message

__all__ = ["Domain"]

# orient2d and incircle are exact only while their products neither overflow nor
# underflow: bubblemesh.predicates sets the coordinate range and checks it.

_NO_CONFLICT, _CROSSES, _TOUCHES, _OVERLAPS = 0, 1, 2, 3
_CONFLICT_VERB = {_CROSSES: "crosses", _TOUCHES: "touches", _OVERLAPS: "overlaps"}


@dataclass(frozen=True, eq=False, repr=False)
class Domain:
    """A polygon with holes given by its refined boundary (paper §2.1).

    Attributes
    ----------
    points : (N, 2) float64
        Every boundary node, loop after loop, in the order the user gave them.
    segments : (N, 2) int64
        One segment per loop edge, oriented so the domain lies on its left
        (outer loop counter-clockwise, holes clockwise).
    loops : tuple of int64 arrays
        Node indices of each loop, ``loops[0]`` the outer one, oriented like
        ``segments`` and starting at the loop's first given node.
    hole_points : (H, 2) float64
        One point strictly inside each hole, ``H = len(loops) - 1``.
    area : float
        ``A_geo`` of eq. 6: outer area minus the hole areas.

    Build one with :meth:`from_loops`, :meth:`from_poly` or
    :meth:`from_shapely`; these validate the geometry and raise
    :class:`~bubblemesh.errors.GeometryError` naming the loop and segment at
    fault.  The arrays are read-only.
    """

    points: np.ndarray
    segments: np.ndarray
    loops: tuple[np.ndarray, ...]
    hole_points: np.ndarray
    area: float

    def __repr__(self) -> str:
        return (
            f"Domain(nodes={len(self.points)}, holes={len(self.loops) - 1}, area={self.area:.6g})"
        )

    @classmethod
    def from_loops(cls, loops: Sequence[npt.ArrayLike]) -> Domain:
        """Validate boundary loops (outer first, then holes) and build a Domain.

        Each loop is an ``(n, 2)`` array of nodes, in either orientation; a last
        node exactly equal to the first (a closed ring, as shapely gives) is
        dropped.  Raises GeometryError for fewer than 3 nodes, a non-finite or
        out-of-range coordinate, repeated consecutive nodes, collinear loops,
        segments that cross, touch or overlap (within a loop or between
        loops), a hole outside the outer loop and a hole inside another hole.
        """
        rings = [_checked_ring(ring, k) for k, ring in enumerate(_as_loop_list(loops))]
        points = np.concatenate(rings)
        offsets = np.cumsum([0] + [len(ring) for ring in rings]).astype(np.int64)
        for k, ring in enumerate(rings):
            if _all_collinear(ring):
                raise GeometryError(f"{_loop_name(k)} has zero area: all its nodes are collinear")
        _check_no_conflicting_segments(points, offsets)
        _check_nesting(points, offsets)

        oriented = []
        for k, ring in enumerate(rings):
            index = np.arange(offsets[k], offsets[k + 1], dtype=np.int64)
            wants_ccw = k == 0
            if _is_counterclockwise(ring) != wants_ccw:
                index = np.concatenate([index[:1], index[:0:-1]])
            oriented.append(index)
        segments = np.concatenate([np.column_stack([ix, np.roll(ix, -1)]) for ix in oriented])

        loop_areas = [_polygon_area(ring) for ring in rings]
        for k, loop_area in enumerate(loop_areas):
            if not loop_area > 0.0:
                raise GeometryError(f"{_loop_name(k)} has zero area (its extent underflows)")
        area = math.fsum([loop_areas[0]] + [-a for a in loop_areas[1:]])
        if not area > 0.0:
            raise GeometryError("the holes leave the domain with zero area")

        hole_points = np.array(
            [_point_inside(ring, k) for k, ring in enumerate(rings) if k > 0], dtype=np.float64
        ).reshape(-1, 2)
        return cls(
            points=_read_only(points),
            segments=_read_only(segments.astype(np.int64)),
            loops=tuple(_read_only(ix) for ix in oriented),
            hole_points=_read_only(hole_points),
            area=area,
        )

    @classmethod
    def from_poly(cls, path: str | Path) -> Domain:
        """Read a Triangle ``.poly`` file (vertices, segments, holes).

        The segments must chain into closed loops; every vertex must lie on
        exactly two segments.  The loop of largest area is the outer one.
        Without hole points every other loop is a hole; with hole points each
        other loop must contain one (internal constraint loops are not
        supported).
        """
        from bubblemesh.io import read_poly

        poly = read_poly(path)
        chains = _chain_segments(poly.segments, poly.vertices, poly.first_index)
        areas = [_polygon_area(poly.vertices[chain]) for chain in chains]
        outer = int(np.argmax(areas))
        chains.insert(0, chains.pop(outer))
        try:
            domain = cls.from_loops([poly.vertices[chain] for chain in chains])
        except GeometryError as error:
            starts = ", ".join(
                f"loop {k} starts at vertex {chain[0] + poly.first_index}"
                for k, chain in enumerate(chains)
            )
            raise GeometryError(f"{path}: {error} ({starts})") from None
        if len(poly.holes):
            _check_hole_markers(domain, poly.holes, chains, poly.first_index, path)
        return domain

    def to_poly(self, path: str | Path) -> None:
        """Write the domain as a Triangle ``.poly`` file with a holes section.

        Vertices are numbered from 1; each vertex and segment carries its loop
        number plus one as boundary marker.
        """
        from bubblemesh.io import write_poly

        loop_of_node = np.empty(len(self.points), dtype=np.int64)
        for k, index in enumerate(self.loops):
            loop_of_node[index] = k + 1
        write_poly(
            path,
            self.points,
            self.segments,
            self.hole_points,
            vertex_markers=loop_of_node,
            segment_markers=loop_of_node[self.segments[:, 0]],
        )

    @classmethod
    def from_shapely(cls, polygon, spacing: float | None = None) -> Domain:
        """Build a Domain from a shapely ``Polygon`` (or a one-part ``MultiPolygon``).

        With ``spacing=None`` the ring vertices are the boundary nodes.  Otherwise
        each ring edge is split into ``ceil(length / spacing)`` equal pieces; the
        ring vertices are kept, so corners stay sharp.
        """
        try:
            from shapely.geometry import MultiPolygon, Polygon
        except ImportError as error:
            raise ImportError(
                "Domain.from_shapely needs shapely: pip install 'bubblemesh[shapely]'"
            ) from error
        if isinstance(polygon, MultiPolygon):
            parts = list(polygon.geoms)
            if len(parts) != 1:
                raise GeometryError(
                    f"a MultiPolygon with {len(parts)} parts is not one domain; "
                    "mesh each part separately"
                )
            polygon = parts[0]
        if not isinstance(polygon, Polygon):
            raise TypeError(f"expected a shapely Polygon, got {type(polygon).__name__}")
        if polygon.is_empty:
            raise GeometryError("the polygon is empty")
        rings = [polygon.exterior, *polygon.interiors]
        loops = [_open_ring(np.asarray(ring.coords, dtype=np.float64)[:, :2]) for ring in rings]
        if spacing is not None:
            if not (math.isfinite(spacing) and spacing > 0):
                raise ValueError(f"spacing must be a positive finite number, got {spacing!r}")
            loops = [_split_edges(ring, spacing) for ring in loops]
        return cls.from_loops(loops)


# --- input checks -------------------------------------------------------------------


def _loop_name(k: int) -> str:
    return "loop 0 (outer)" if k == 0 else f"loop {k} (hole {k})"


def _as_loop_list(loops) -> list:
    if isinstance(loops, np.ndarray) and loops.ndim == 2:
        raise GeometryError(
            "from_loops takes a sequence of loops; wrap a single outer loop as [loop]"
        )
    loops = list(loops)
    if not loops:
        raise GeometryError("a domain needs at least one loop (the outer boundary)")
    return loops


def _checked_ring(ring, k: int) -> np.ndarray:
    """One loop as a contiguous (n, 2) float64 array, closing repeat dropped."""
    name = _loop_name(k)
    try:
        ring = np.array(ring, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise GeometryError(f"{name} is not an array of numbers: {error}") from None
    if ring.ndim != 2 or ring.shape[1] != 2:
        raise GeometryError(f"{name} must be an (n, 2) array of nodes, got shape {ring.shape}")
    finite = np.isfinite(ring).all(axis=1)
    if not finite.all():
        raise GeometryError(f"{name} has a non-finite coordinate at node {int(np.argmin(finite))}")
    outside = out_of_range(ring)
    if outside.any():
        node = int(np.argmax(outside))
        raise GeometryError(f"{name} node {node} = {out_of_range_message(ring[node])}")
    ring = _open_ring(ring)
    if len(ring) < 3:
        raise GeometryError(f"{name} has {len(ring)} distinct nodes; a loop needs at least 3")
    repeats = (ring == np.roll(ring, -1, axis=0)).all(axis=1)
    if repeats.any():
        node = int(np.argmax(repeats))
        x, y = ring[node]
        raise GeometryError(
            f"{name} segment {node} has zero length: nodes {node} and "
            f"{(node + 1) % len(ring)} coincide at ({float(x)!r}, {float(y)!r})"
        )
    return np.ascontiguousarray(ring)


def _open_ring(ring: np.ndarray) -> np.ndarray:
    """Drop a last node that exactly repeats the first (closed rings, as shapely's)."""
    if len(ring) >= 2 and (ring[-1] == ring[0]).all():
        return ring[:-1]
    return ring


def _split_edges(ring: np.ndarray, spacing: float) -> np.ndarray:
    """Split each edge of a ring into ceil(length/spacing) equal pieces."""
    start = ring
    end = np.roll(ring, -1, axis=0)
    lengths = np.hypot(*(end - start).T)
    pieces = np.maximum(1, np.ceil(lengths / spacing)).astype(np.int64)
    edge = np.repeat(np.arange(len(ring)), pieces)
    first_piece = np.repeat(np.cumsum(pieces) - pieces, pieces)
    t = (np.arange(pieces.sum()) - first_piece) / pieces[edge]
    return start[edge] + (end[edge] - start[edge]) * t[:, None]


def _read_only(array: np.ndarray) -> np.ndarray:
    array = np.ascontiguousarray(array)
    array.setflags(write=False)
    return array


# --- exact kernels ------------------------------------------------------------------


@njit(cache=True)
def _all_collinear(ring):
    """True iff every node of the ring lies on one line (exact)."""
    ax, ay = ring[0, 0], ring[0, 1]
    bx, by = ring[1, 0], ring[1, 1]
    for k in range(2, ring.shape[0]):
        if orient2d(ax, ay, bx, by, ring[k, 0], ring[k, 1]) != 0.0:
            return False
    return True


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
            return _OVERLAPS
        return _TOUCHES if lo == hi else _NO_CONFLICT
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
        return _CROSSES
    if (
        (o_abc == 0.0 and _on_closed_box(cx, cy, ax, ay, bx, by))
        or (o_abd == 0.0 and _on_closed_box(dx, dy, ax, ay, bx, by))
        or (o_cda == 0.0 and _on_closed_box(ax, ay, cx, cy, dx, dy))
        or (o_cdb == 0.0 and _on_closed_box(bx, by, cx, cy, dx, dy))
    ):
        return _TOUCHES
    return _NO_CONFLICT


@njit(cache=True)
def _folds_back(px, py, qx, qy, rx, ry):
    """Adjacent segments p-q, q-r overlap iff r lies on the ray from q through p."""
    if orient2d(px, py, qx, qy, rx, ry) != 0.0:
        return False
    if px != qx:
        return (px > qx) == (rx > qx)
    return (py > qy) == (ry > qy)


@njit(cache=True)
def _pair_conflict(points, segments, i, j):
    a, b = segments[i, 0], segments[i, 1]
    c, d = segments[j, 0], segments[j, 1]
    if b == c or a == d:  # consecutive segments of one loop: the shared node is q
        p, q, r = (a, b, d) if b == c else (c, d, b)
        if _folds_back(
            points[p, 0], points[p, 1], points[q, 0], points[q, 1], points[r, 0], points[r, 1]
        ):
            return _OVERLAPS
        return _NO_CONFLICT
    return _disjoint_pair_conflict(
        points[a, 0], points[a, 1], points[b, 0], points[b, 1],
        points[c, 0], points[c, 1], points[d, 0], points[d, 1],
    )  # fmt: skip


@njit(cache=True)
def _first_conflict(points, segments):
    """Sweep along x: the first pair of segments that cross, touch or overlap.

    Segments are sorted by their smallest x; a segment is compared only with
    those that start before it ends in x and overlap it in y.  Returns
    ``(i, j, kind)`` with ``i < j``, or ``(-1, -1, 0)``.
    """
    n = segments.shape[0]
    xa = points[segments[:, 0], 0]
    xb = points[segments[:, 1], 0]
    ya = points[segments[:, 0], 1]
    yb = points[segments[:, 1], 1]
    lo_x, hi_x = np.minimum(xa, xb), np.maximum(xa, xb)
    lo_y, hi_y = np.minimum(ya, yb), np.maximum(ya, yb)
    order = np.argsort(lo_x, kind="mergesort")
    for ii in range(n):
        i = order[ii]
        for jj in range(ii + 1, n):
            j = order[jj]
            if lo_x[j] > hi_x[i]:
                break
            if lo_y[j] > hi_y[i] or hi_y[j] < lo_y[i]:
                continue
            kind = _pair_conflict(points, segments, i, j)
            if kind != _NO_CONFLICT:
                return min(i, j), max(i, j), kind
    return -1, -1, _NO_CONFLICT


@njit(cache=True)
def _point_in_ring(px, py, ring):
    """Exact crossing test: 1 inside, 0 outside, -1 on the ring's boundary."""
    n = ring.shape[0]
    inside = False
    for k in range(n):
        ax, ay = ring[k, 0], ring[k, 1]
        bx, by = ring[(k + 1) % n, 0], ring[(k + 1) % n, 1]
        straddles = (ay > py) != (by > py)
        if not straddles and not _on_closed_box(px, py, ax, ay, bx, by):
            continue
        side = orient2d(ax, ay, bx, by, px, py)
        if side == 0.0 and _on_closed_box(px, py, ax, ay, bx, by):
            return -1
        if straddles and (side > 0.0) == (by > ay):
            inside = not inside
    return 1 if inside else 0


@njit(cache=True)
def _containment(points, offsets):
    """inside[i, j]: the first node of loop i lies inside loop j (bounding boxes first)."""
    n_loops = offsets.shape[0] - 1
    box = np.empty((n_loops, 4))
    for k in range(n_loops):
        ring = points[offsets[k] : offsets[k + 1]]
        box[k, 0], box[k, 1] = ring[:, 0].min(), ring[:, 1].min()
        box[k, 2], box[k, 3] = ring[:, 0].max(), ring[:, 1].max()
    inside = np.zeros((n_loops, n_loops), dtype=np.bool_)
    for i in range(n_loops):
        px, py = points[offsets[i], 0], points[offsets[i], 1]
        for j in range(n_loops):
            if i == j or not (box[j, 0] <= px <= box[j, 2] and box[j, 1] <= py <= box[j, 3]):
                continue
            inside[i, j] = _point_in_ring(px, py, points[offsets[j] : offsets[j + 1]]) == 1
    return inside


# --- validation and derived quantities ----------------------------------------------


def _segment_name(global_index: int, offsets: np.ndarray) -> str:
    k = int(np.searchsorted(offsets, global_index, side="right") - 1)
    return f"{_loop_name(k)} segment {global_index - offsets[k]}"


def _check_no_conflicting_segments(points: np.ndarray, offsets: np.ndarray) -> None:
    """Raise if any two segments share a point other than a common end node."""
    index = np.arange(len(points), dtype=np.int64)
    following = index + 1
    following[offsets[1:] - 1] = offsets[:-1]
    segments = np.column_stack([index, following])
    i, j, kind = _first_conflict(points, segments)
    if kind != _NO_CONFLICT:
        raise GeometryError(
            f"{_segment_name(j, offsets)} {_CONFLICT_VERB[kind]} {_segment_name(i, offsets)}"
        )


def _check_nesting(points: np.ndarray, offsets: np.ndarray) -> None:
    """Holes must lie inside the outer loop and outside each other.

    Called after the segment check: loops that neither cross nor touch are
    either nested or disjoint, so one node per loop decides.
    """
    inside = _containment(points, offsets)
    for i in range(1, len(offsets) - 1):
        if not inside[i, 0]:
            raise GeometryError(
                f"{_loop_name(i)} lies outside the outer loop "
                "(the first loop must be the outer boundary)"
            )
        for j in range(1, len(offsets) - 1):
            if inside[i, j]:
                raise GeometryError(
                    f"{_loop_name(i)} lies inside {_loop_name(j)}; nested holes are not supported"
                )


def _is_counterclockwise(ring: np.ndarray) -> bool:
    """Exact orientation of a simple ring, decided at its lowest-leftmost node.

    That node is strictly convex, so the turn of its two neighbours gives the
    orientation (never zero once fold-backs are excluded).
    """
    k = int(np.lexsort((ring[:, 1], ring[:, 0]))[0])
    prev, node, succ = ring[k - 1], ring[k], ring[(k + 1) % len(ring)]
    return orient2d(prev[0], prev[1], node[0], node[1], succ[0], succ[1]) > 0.0


def _polygon_area(ring: np.ndarray) -> float:
    """Unsigned shoelace area, summed with math.fsum.

    Coordinates are taken relative to the first node, so a domain far from the
    origin loses no digits to large products (the shift is exact for nodes
    within a factor of two of it).
    """
    x, y = ring[:, 0] - ring[0, 0], ring[:, 1] - ring[0, 1]
    terms = np.concatenate([x * np.roll(y, -1), -(np.roll(x, -1) * y)])
    return abs(0.5 * math.fsum(terms.tolist()))


def _point_inside(ring: np.ndarray, k: int) -> tuple[float, float]:
    """A point strictly inside a simple ring, verified with the exact crossing test.

    Scan lines halfway between consecutive distinct node ordinates, widest gap
    first; on each, the widest inside interval's midpoint.
    """
    levels = np.unique(ring[:, 1])
    gaps = np.diff(levels)
    start, end = ring, np.roll(ring, -1, axis=0)
    for g in np.argsort(-gaps, kind="stable"):
        y = 0.5 * (levels[g] + levels[g + 1])
        if not levels[g] < y < levels[g + 1]:
            continue
        crossing = (start[:, 1] > y) != (end[:, 1] > y)
        a, b = start[crossing], end[crossing]
        xs = np.sort(a[:, 0] + (y - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1]))
        widths = xs[1::2] - xs[0::2]
        w = int(np.argmax(widths))
        x = 0.5 * (xs[2 * w] + xs[2 * w + 1])
        if _point_in_ring(x, y, ring) == 1:
            return float(x), float(y)
    raise GeometryError(f"could not find a point strictly inside {_loop_name(k)}")


# --- .poly loops ----------------------------------------------------------------------


def _chain_segments(
    segments: np.ndarray, vertices: np.ndarray, first_index: int
) -> list[np.ndarray]:
    """Chain undirected segments into closed loops of vertex indices.

    Each loop starts at its smallest vertex index and heads to the smaller of
    its two neighbours, so a loop written as consecutive vertices keeps its order.
    """
    n = len(vertices)

    def where(v: int) -> str:
        x, y = vertices[v].tolist()
        return f"vertex {v + first_index} at ({x!r}, {y!r})"

    loops_to_self = segments[:, 0] == segments[:, 1]
    if loops_to_self.any():
        s = int(np.argmax(loops_to_self))
        raise GeometryError(f"segment {s + first_index} joins {where(segments[s, 0])} to itself")
    degree = np.bincount(segments.ravel(), minlength=n)
    if (degree == 0).any():
        v = int(np.argmax(degree == 0))
        raise GeometryError(f"{where(v)} is on no segment; free vertices are not supported")
    if (degree != 2).any():
        v = int(np.argmax(degree != 2))
        raise GeometryError(
            f"{where(v)} ends {degree[v]} segments; the segments must form closed loops "
            "with every vertex on exactly two"
        )
    ends = segments.ravel()
    others = segments[:, ::-1].ravel()
    neighbours = others[np.argsort(ends, kind="stable")].reshape(n, 2)

    visited = np.zeros(n, dtype=bool)
    loops = []
    for start in range(n):
        if visited[start]:
            continue
        chain = [start]
        visited[start] = True
        previous, current = start, int(neighbours[start].min())
        while current != start:
            if len(chain) >= n:  # cannot happen when every degree is 2; never loop on
                raise GeometryError(f"the segments through {where(start)} do not close")
            chain.append(current)
            visited[current] = True
            a, b = neighbours[current]
            previous, current = current, int(b if a == previous else a)
        loops.append(np.array(chain, dtype=np.int64))
    return loops


def _check_hole_markers(
    domain: Domain, holes: np.ndarray, chains: list[np.ndarray], first_index: int, path
) -> None:
    """With hole points given, each inner loop must enclose one, none the domain."""
    rings = [domain.points[index] for index in domain.loops]
    marked = np.zeros(len(rings), dtype=bool)
    for h, (x, y) in enumerate(holes.tolist()):
        status = np.array([_point_in_ring(x, y, ring) for ring in rings])
        if (status == -1).any():
            raise GeometryError(
                f"{path}: hole point {h + first_index} at ({x!r}, {y!r}) lies on "
                f"{_loop_name(int(np.argmin(status)))}"
            )
        in_loops = np.flatnonzero(status == 1)
        if in_loops.tolist() == [0]:
            raise GeometryError(
                f"{path}: hole point {h + first_index} at ({x!r}, {y!r}) lies in the domain, "
                "not inside a hole loop"
            )
        marked[in_loops] = True
    for k in range(1, len(rings)):
        if not marked[k]:
            raise GeometryError(
                f"{path}: the loop starting at vertex {chains[k][0] + first_index} contains no "
                "hole point; internal constraint loops are not supported"
            )
