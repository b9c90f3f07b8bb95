"""The meshing domain: the refined boundary of paper §2.1, validated.

The paper starts from a *refined boundary*: boundary nodes with their
connectivity, one closed loop for the outer boundary and one per hole
(§2.1).  Its node spacing decides the boundary bubbles (eq. 1-2) and its
enclosed area is ``A_geo``, the stopping threshold of the population control
(eq. 6).  :class:`Domain` holds exactly that, after checking that the loops
form a valid polygon with holes, because every later step (the initial
constrained triangulation, the inside test, eq. 6) silently goes wrong on
crossing or badly nested loops.

Every geometric decision here is exact (:func:`bubblemesh.predicates.orient2d`)
and takes O(n log n) time whatever the shape: one sweep line
(:mod:`bubblemesh._sweep`) finds any two segments that meet where they should
not and, for each loop, the segment directly below its lowest node, which
decides the nesting of all loops at once.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from decimal import Decimal
from pathlib import Path
from types import MappingProxyType

import numpy as np
import numpy.typing as npt
from numba import njit

from bubblemesh._sweep import CONFLICT_VERB, NO_CONFLICT, precedes, sweep
from bubblemesh.errors import GeometryError
from bubblemesh.predicates import flush_tiny, orient2d, out_of_range, out_of_range_message

__all__ = ["Domain"]

# orient2d and incircle are exact only while their products neither overflow nor
# underflow: bubblemesh.predicates sets the coordinate range and checks it.


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
    segment_markers : (N,) int64 or None
        The marker of each segment's input segment (a ``.poly`` file's, the
        user's); None means the default, the loop number plus one (``markers``).
    marker_names : mapping of str to int
        Names of markers (e.g. ``{"inlet": 3}``); written as physical names.
    regions : (R, 4) float64 or None
        Region points (x, y, attribute, max_area; max_area <= 0 for none), as
        Triangle's regional attributes.

    A domain from :meth:`from_pslg` or a ``.poly`` file may also hold interior
    constraints (each such segment appears both ways in ``segments``, the
    domain lying on both sides) and free points (on no segment); ``loops`` are
    then the closed walks around the boundary and the constraints, a node
    repeating where constraints meet.  Every node of ``points`` is fixed.


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
    segment_markers: np.ndarray | None = None
    marker_names: Mapping[str, int] = field(default_factory=lambda: MappingProxyType({}))
    regions: np.ndarray | None = None

    @property
    def markers(self) -> np.ndarray:
        """(len(segments),) int64: each segment's marker (the loop number plus
        one unless the input gave markers)."""
        if self.segment_markers is not None:
            return self.segment_markers
        return _read_only(np.concatenate(
            [np.full(len(ix), k + 1, np.int64) for k, ix in enumerate(self.loops)]))

    @property
    def interior(self) -> np.ndarray:
        """(len(segments),) bool: the segment is an interior constraint (its
        reverse is a segment too)."""
        from bubblemesh._cdt import INTERIOR
        from bubblemesh.triangulation import segment_flags

        return segment_flags(self.segments) == INTERIOR

    def region_size(self, default: float | None = None):
        """The regions' max_area as a size for ``bubblemesh.mesh(domain,
        size=domain.region_size())``: a vectorised h(xy), the side of the
        equilateral triangle of ``FILL`` (0.6) times the max_area of the region
        holding each point (a later region point wins, as in Triangle), so that
        few triangles exceed the bound that ``bubblemesh.mesh`` then enforces
        (:mod:`bubblemesh._area_bound`); ``default`` (the domain's diameter)
        where no region with a max_area holds it."""
        from bubblemesh._area_bound import FILL
        from bubblemesh._mesh import _flood
        from bubblemesh._pslg import triangle_values
        from bubblemesh.triangulation import constrained_delaunay

        P = np.ascontiguousarray(self.points)
        T, N = constrained_delaunay(P, self.segments)  # -1 across every constraint
        region = np.full(len(T), -1, np.int64)
        regions = np.zeros((0, 4)) if self.regions is None else np.asarray(self.regions)
        for r, (x, y) in enumerate(regions[:, :2].tolist()):
            _flood(P, T, N, float(x), float(y), r, region)
        wide = float(np.hypot(*(P.max(axis=0) - P.min(axis=0)))) if default is None else float(
            default)
        area = np.where(region >= 0, regions[np.maximum(region, 0), 3] if len(regions) else -1,
                        -1.0)
        side = np.where(area > 0, np.sqrt(4.0 * FILL * np.abs(area) / math.sqrt(3.0)), wide)

        def size(xy: np.ndarray) -> np.ndarray:
            Q = np.ascontiguousarray(np.asarray(xy, np.float64).reshape(-1, 2))
            return triangle_values(P, T, side, Q, wide)

        return size

    def __repr__(self) -> str:
        return (
            f"Domain(nodes={len(self.points)}, holes={len(self.loops) - 1}, area={self.area:.6g})"
        )

    @classmethod
    def from_loops(cls, loops: Sequence[npt.ArrayLike]) -> Domain:
        """Validate boundary loops (outer first, then holes) and build a Domain.

        Each loop is an ``(n, 2)`` array of nodes, in either orientation; a last
        node exactly equal to the first (a closed ring, as shapely gives) is
        dropped.  Coordinates may be any real numbers (converted to the nearest
        float64).  Raises GeometryError, naming the loop and the node or
        segment, for coordinates that are not real numbers (complex, strings,
        booleans, masked or ragged entries, ints beyond float64), fewer than 3
        nodes, a non-finite or out-of-range coordinate, repeated consecutive
        nodes, collinear loops, segments that cross, touch or overlap (within a
        loop or between loops), a hole outside the outer loop and a hole inside
        another hole; TypeError if ``loops`` is not a sequence.
        """
        points, offsets = _checked_rings(_as_loop_list(loops))
        ccw = _check_layout(points, offsets)

        # loop 0 counter-clockwise, holes clockwise; each keeps its first node
        order, segments = _oriented(offsets, ccw != (np.arange(len(ccw)) == 0))
        oriented = np.split(order, offsets[1:-1])

        loop_areas = _loop_areas(points, offsets)
        for k, loop_area in enumerate(loop_areas):
            if not loop_area > 0.0:
                raise GeometryError(f"{_loop_name(k)} has zero area (its extent underflows)")
        area = math.fsum([loop_areas[0]] + [-a for a in loop_areas[1:]])
        if not area > 0.0:
            raise GeometryError("the holes leave the domain with zero area")

        hole_points, failed = _hole_points(points, offsets)
        if failed >= 0:
            raise GeometryError(f"could not find a point strictly inside {_loop_name(failed)}")
        return cls(
            points=_read_only(points),
            segments=_read_only(segments),
            loops=tuple(_read_only(ix) for ix in oriented),
            hole_points=_read_only(hole_points),
            area=area,
        )

    @classmethod
    def from_poly(cls, path: str | Path, *, convex_hull: bool | None = None,
                  names: Mapping[str, int] | None = None) -> Domain:
        """Read a Triangle ``.poly`` file as Triangle's ``-p`` reads it.

        The domain is every face the segments enclose (reached from outside
        only across a segment) minus the faces of the hole points; segments
        inside it are interior constraints, vertices on no segment free
        points, vertices outside it left out, a vertex strictly inside a
        segment splits it (both pieces keep its marker), and so does the
        point where two segments cross (rounded to the nearest float, as
        Triangle inserts one there).  ``convex_hull=True`` closes the
        convex hull with segments first (``-c``, marker 1); the default
        (None) does so only when the segments enclose nothing.  Segment
        markers (a boundary segment marked 0 gets 1, as in Triangle), the
        regional attributes and ``names`` (marker names) are kept.
        """
        from bubblemesh.io import read_poly

        poly = read_poly(path)
        if convex_hull is None:  # closed loops only: as before, markers and regions kept
            try:
                domain = cls._from_loop_poly(path, poly)
                return replace(domain, marker_names=MappingProxyType(_checked_names(names)))
            except GeometryError as error:
                if not any(why in str(error) for why in _NOT_LOOPS):
                    raise
        markers = (np.zeros(len(poly.segments), np.int64) if poly.segment_markers is None
                   else poly.segment_markers)
        hull = [convex_hull] if convex_hull is not None else [False, True]
        for closed in hull:
            try:
                return cls._from_graph(poly.vertices, poly.segments, markers, poly.holes,
                                       poly.regions, names, mode="enclosed",
                                       convex_hull=closed, boundary_zero=1,
                                       first_index=poly.first_index)
            except GeometryError as error:
                if closed or convex_hull is not None or "no domain" not in str(error):
                    raise GeometryError(f"{path}: {error}") from None
        raise AssertionError("unreachable")

    @classmethod
    def from_pslg(cls, loops: Sequence[npt.ArrayLike] = (),
                  constraints: Sequence[npt.ArrayLike] = (), points: npt.ArrayLike = (), *,
                  markers: Sequence[int] | None = None,
                  names: Mapping[str, int] | None = None, holes: npt.ArrayLike = (),
                  regions: npt.ArrayLike = ()) -> Domain:
        """A planar straight-line graph domain.

        ``loops``: closed rings (either orientation); a point is in the domain
        when an odd number of loops surround it, so outer loops, holes and
        islands in holes nest to any depth.  ``constraints``: polylines
        inside the domain (open, or closed when the last node repeats the
        first): material interfaces, cracks; their nodes may be loop nodes.
        ``points``: free interior nodes.  ``markers``: one int per loop then
        per constraint (default: their position plus one); ``names`` maps
        names to markers; ``holes`` are extra hole points (each removes its
        face); ``regions`` rows (x, y, attribute, max_area).  Coincident nodes
        are merged exactly; a node strictly inside a segment splits it,
        collinear overlapping segments merge, and a constraint that crosses
        another or a loop is split with it at the crossing point, rounded to
        the nearest float (as in Triangle; one that ends a rounding error past
        a segment joins it at its end).  GeometryError for loops that cross
        each other, two nodes a rounding error apart whose segments cross,
        and the like, naming the items.
        """
        from bubblemesh._cdt import BOUNDARY, INTERIOR

        items = [(np.asarray(r, np.float64).reshape(-1, 2), True) for r in loops]
        items += [(np.asarray(c, np.float64).reshape(-1, 2), False) for c in constraints]
        if markers is not None and len(markers) != len(items):
            raise ValueError(f"markers: {len(markers)} given for {len(items)} loops and "
                             "constraints")
        coords, segs, marks, flags = [], [], [], []
        base = 0
        for k, (line, is_loop) in enumerate(items):
            closed = is_loop or (len(line) > 2 and (line[0] == line[-1]).all())
            line = _open_ring(line) if closed else line
            need = 3 if is_loop else 2
            if len(line) < need:
                raise GeometryError(f"{'loop' if is_loop else 'constraint'} {k} has "
                                    f"{len(line)} nodes; it needs at least {need}")
            ix = base + np.arange(len(line))
            pairs = np.column_stack([ix, np.roll(ix, -1)]) if closed else np.column_stack(
                [ix[:-1], ix[1:]])
            coords.append(line)
            segs.append(pairs)
            marks.append(np.full(len(pairs), k + 1 if markers is None else int(markers[k])))
            flags.append(np.full(len(pairs), BOUNDARY if is_loop else INTERIOR, np.uint8))
            base += len(line)
        coords.append(np.asarray(points, np.float64).reshape(-1, 2))
        vertices, S = _merged(coords, segs, "from_pslg")
        if not len(S):
            raise GeometryError("from_pslg: give at least one loop")
        return cls._from_graph(vertices, S, np.concatenate(marks), holes, regions, names,
                               mode="parity", flags=np.concatenate(flags))

    @classmethod
    def from_geopandas(cls, frame, *, region: str | None = None, max_area: str | None = None,
                       names: Mapping[str, int] | None = None) -> Domain:
        """A domain from a GeoDataFrame or GeoSeries of (Multi)Polygons: a
        partition of the plane into materials, each feature a region.

        The domain is the union of the features, read as Triangle's ``-p``
        reads a ``.poly`` file: the rings are segments, an edge two features
        share is an interior constraint (a node of one on the other's edge
        splits it), the holes of the union (a feature's hole no other feature
        fills) stay holes.  Each feature gets a region point (one per polygon
        part) with the attribute of column ``region`` (default: the feature's
        row position) and the max_area of column ``max_area`` (default none;
        NaN or <= 0 for none), so ``mesh.region_attributes()`` and the area
        bounds of ``bubblemesh.mesh`` follow the features.  Markers: 1 on the
        boundary, 2 on the interfaces (``names`` may name them).  Edges of
        features that cross (overlapping features, no partition) raise a
        GeometryError naming two of them.  Nothing of
        geopandas is imported: any object with a ``geometry`` of shapely
        polygons (and the columns) will do."""
        try:
            from shapely import union_all
            from shapely.geometry import Polygon
        except ImportError as error:
            raise ImportError("Domain.from_geopandas needs shapely: pip install "
                              "'bubblemesh[shapely]'") from error
        geometry = list(getattr(frame, "geometry", frame))
        if not geometry:
            raise GeometryError("from_geopandas: no features")
        attribute = (np.arange(len(geometry), dtype=np.float64) if region is None
                     else np.asarray(frame[region], np.float64))
        bound = (np.zeros(len(geometry)) if max_area is None
                 else np.nan_to_num(np.asarray(frame[max_area], np.float64), nan=0.0))
        parts, rows = [], []
        for k, feature in enumerate(geometry):
            mine = _polygon_parts(feature, f"feature {k}")
            parts += mine
            rows += [k] * len(mine)
        loops = _rings(parts)
        coords = list(loops)
        segs, base = [], 0
        for ring in loops:
            ix = base + np.arange(len(ring))
            segs.append(np.column_stack([ix, np.roll(ix, -1)]))
            base += len(ring)
        vertices, S = _merged(coords, segs, "from_geopandas")
        union = union_all(parts)
        holes = [p.representative_point().coords[0]
                 for piece in _polygon_parts(union, "the union")
                 for ring in piece.interiors
                 for p in _polygon_parts(Polygon(ring).difference(union), "", strict=False)]
        anchors = [part.representative_point().coords[0] for part in parts]
        regions = np.column_stack([np.array(anchors, np.float64).reshape(-1, 2),
                                   attribute[rows], bound[rows]])
        # features that overlap are no partition: their crossing edges are refused
        domain = cls._from_graph(vertices, S, np.ones(len(S), np.int64), holes, regions, names,
                                 mode="enclosed", split_crossing=False)
        marks = np.where(domain.interior, 2, 1).astype(np.int64)
        return replace(domain, segment_markers=_read_only(marks))

    @classmethod
    def _from_graph(cls, vertices, segments, markers, holes, regions, names, *, mode,
                    flags=None, convex_hull=False, boundary_zero=None,
                    first_index=0, split_crossing=True) -> Domain:
        from bubblemesh._pslg import build

        graph = build(vertices, segments, markers, holes=holes, regions=regions, mode=mode,
                      flags=flags, convex_hull=convex_hull, first_index=first_index,
                      split_crossing=split_crossing)
        if len(graph.dropped):  # Triangle would keep it as a node of no triangle
            v = int(graph.dropped[0])
            x, y = np.asarray(vertices, np.float64)[v].tolist()
            raise GeometryError(f"vertex {v + first_index} at ({x!r}, {y!r}) is on no segment "
                                "of the domain and lies outside it (or in a hole)")
        marks = np.array(graph.markers, np.int64)
        if boundary_zero is not None:  # Triangle: a boundary segment marked 0 gets 1
            from bubblemesh._cdt import BOUNDARY
            from bubblemesh.triangulation import segment_flags

            marks[(marks == 0) & (segment_flags(graph.segments) == BOUNDARY)] = boundary_zero
        return cls(points=_read_only(graph.points),
                   segments=_read_only(np.asarray(graph.segments, np.int64)),
                   loops=tuple(_read_only(np.asarray(ix, np.int64)) for ix in graph.loops),
                   hole_points=_read_only(np.asarray(graph.holes, np.float64)),
                   area=graph.area, segment_markers=_read_only(marks),
                   marker_names=MappingProxyType(_checked_names(names)),
                   regions=_read_only(np.asarray(graph.regions, np.float64).reshape(-1, 4)))

    @classmethod
    def _from_loop_poly(cls, path: str | Path, poly) -> Domain:
        """A ``.poly`` file whose segments are closed loops (vertices, segments, holes).

        The segments must chain into closed loops; every vertex must lie on
        exactly two segments.  The loop of largest area is the outer one.
        Without hole points every other loop is a hole; with hole points each
        other loop must contain one (internal constraint loops are not
        supported).
        """
        chains = _chain_segments(poly.segments, poly.vertices, poly.first_index)
        if any(len(np.unique(chain)) < 3 for chain in chains):  # a segment given both ways
            raise GeometryError(f"{path}: segments must form closed loops of 3 nodes or more")
        offsets = np.cumsum([0] + [len(chain) for chain in chains])
        areas = _loop_areas(poly.vertices[np.concatenate(chains)], offsets)
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
        return _with_file_markers(domain, chains, poly)

    def to_poly(self, path: str | Path) -> None:
        """Write the domain as a Triangle ``.poly`` file that reads back as it.

        Vertices are numbered from 1.  Each segment carries its marker
        (:attr:`markers`), an interior constraint once; each vertex the marker
        of its first segment, as Triangle gives a vertex on a segment, and a
        free point 0.  Hole points, and the regions when there are any, follow.
        """
        from bubblemesh.io import write_poly

        segments = np.asarray(self.segments)
        markers = np.asarray(self.markers)
        # a constraint (both ways in segments) once
        _, first = np.unique(np.sort(segments, axis=1), axis=0, return_index=True)
        once = np.sort(first)
        vertex_markers = np.zeros(len(self.points), np.int64)
        nodes, at = np.unique(segments[once].ravel(), return_index=True)  # first segment of each
        vertex_markers[nodes] = np.repeat(markers[once], 2)[at]
        write_poly(path, self.points, segments[once], self.hole_points,
                   vertex_markers=vertex_markers, segment_markers=markers[once],
                   regions=self.regions)

    @classmethod
    def from_shapely(cls, polygon, spacing: float | None = None, *, size=None,
                     gradation: float = 0.25, constraints=(), points=(),
                     names: Mapping[str, int] | None = None) -> Domain:
        """Build a Domain from a shapely ``Polygon`` or ``MultiPolygon``.

        With ``spacing=None`` and ``size=None`` the ring vertices are the boundary
        nodes.  ``spacing``: each ring edge is split into ``ceil(length /
        spacing)`` equal pieces.  ``size`` (a number or a vectorised callable
        ``h(xy) -> (n,)``): the edges are sampled from the size field that
        :func:`bubblemesh.mesh` builds from the corners, the local feature size
        and ``size``, limited to ``gradation`` (so a narrow gap gets short
        pieces too), none longer than the field.  Either way the ring vertices
        are kept, so corners stay sharp.  ``constraints``
        (LineStrings, LinearRings or a MultiLineString) become interior
        constraints, ``points`` (Points, a MultiPoint or an (m, 2) array) free
        nodes; with either, several polygon parts, or rings that touch at a
        point (a hole on the outer ring or on another hole, valid to GEOS),
        the domain is a planar graph (:meth:`from_pslg`; ring k has marker
        k + 1, constraint j marker n_rings + j + 1).
        """
        try:
            import shapely  # noqa: F401
        except ImportError as error:
            raise ImportError(
                "Domain.from_shapely needs shapely: pip install 'bubblemesh[shapely]'"
            ) from error
        parts = _polygon_parts(polygon, "the polygon")
        loops = _rings(parts)
        lines = [np.asarray(g.coords, dtype=np.float64)[:, :2] for g in _geoms(constraints)]
        if spacing is not None and size is not None:
            raise ValueError("from_shapely: give spacing or size, not both")
        if spacing is not None:
            if not (math.isfinite(spacing) and spacing > 0):
                raise ValueError(f"spacing must be a positive finite number, got {spacing!r}")
            loops = [_split_edges(ring, spacing) for ring in loops]
            lines = [_split_polyline(line, spacing) for line in lines]
        free = _point_array(points)
        if len(parts) == 1 and not lines and not len(free) and not names \
                and not _rings_touch(parts[0]):
            domain = cls.from_loops(loops)  # as before: a polygon with holes
        else:
            domain = cls.from_pslg(loops=loops, constraints=lines, points=free, names=names)
        return domain if size is None else _sampled(domain, size, gradation)


def _sampled(domain: Domain, size, gradation: float) -> Domain:
    """``domain``'s segments split by the size field of ``size`` (bm.mesh's),
    rounded up: a user's size is a bound on every piece.  No ladders: the
    domain gets no nodes off its segments."""
    from .pipeline import refined_domain
    from .sizing import SizeField

    try:
        field = SizeField.from_domain(domain, size=size, gradation=gradation)
    except (TypeError, ValueError) as error:
        raise type(error)(f"from_shapely: {error}") from None
    return refined_domain(domain, field, rounding="up", ladders=False)


def _polygon_parts(geometry, what: str, strict: bool = True) -> list:
    """The non-empty Polygons of a shapely Polygon or MultiPolygon; TypeError
    for other geometries and GeometryError for an empty one, unless not
    ``strict`` (then the Polygons among any geometry's parts, maybe none)."""
    from shapely.geometry import MultiPolygon, Polygon

    parts = list(geometry.geoms) if isinstance(geometry, MultiPolygon) or (
        not strict and hasattr(geometry, "geoms")) else [geometry]
    if strict:
        for part in parts:
            if not isinstance(part, Polygon):
                raise TypeError(f"{what}: expected a shapely Polygon, got "
                                f"{type(part).__name__}")
    parts = [part for part in parts if isinstance(part, Polygon) and not part.is_empty]
    if not parts and strict:
        raise GeometryError(f"{what} is empty")
    return parts


def _rings(parts) -> list[np.ndarray]:
    """Every ring (exterior, then interiors) of the polygons as an open (n, 2) array."""
    return [_open_ring(_unrepeated(np.asarray(ring.coords, dtype=np.float64)[:, :2]))
            for part in parts for ring in (part.exterior, *part.interiors)]


def _rings_touch(polygon) -> bool:
    """Does a ring of a valid shapely polygon touch another (GEOS allows a
    hole to meet the outer ring or another hole at a point)?  An invalid
    polygon answers False: :meth:`Domain.from_loops` then names its fault."""
    from shapely import STRtree

    rings = [polygon.exterior, *polygon.interiors]
    if len(rings) < 2 or not polygon.is_valid:
        return False
    first, second = STRtree(rings).query(rings, predicate="intersects")
    return bool((first != second).any())


def _unrepeated(ring: np.ndarray) -> np.ndarray:
    """The ring without nodes that exactly repeat the one before: shapely
    holds such rings valid, a user's drawing often has them."""
    keep = np.ones(len(ring), dtype=bool)
    keep[1:] = (ring[1:] != ring[:-1]).any(axis=1)
    return ring[keep]


def _merged(coords, segs, what: str) -> tuple[np.ndarray, np.ndarray]:
    """The node arrays as one, exactly coincident nodes merged (first
    occurrence order), and the segments renumbered to it."""
    vertices = np.concatenate(coords) if coords else np.zeros((0, 2))
    if not len(vertices) or not np.isfinite(vertices).all():
        raise GeometryError(f"{what}: no nodes, or a non-finite coordinate")
    unique, first, inverse = np.unique(vertices, axis=0, return_index=True,
                                       return_inverse=True)
    rank = np.argsort(np.argsort(first))  # unique rows in order of first occurrence
    remap = rank[inverse.reshape(-1)]
    S = remap[np.concatenate(segs)] if segs else np.zeros((0, 2), np.int64)
    return unique[np.argsort(first)], S


def _geoms(geometry) -> list:
    """The parts of a shapely geometry or of a sequence of them."""
    if geometry is None:
        return []
    if hasattr(geometry, "geoms"):
        return list(geometry.geoms)
    if hasattr(geometry, "coords"):
        return [geometry]
    return [g for item in geometry for g in _geoms(item)]


def _point_array(points) -> np.ndarray:
    if hasattr(points, "geoms") or hasattr(points, "coords"):
        return np.array([g.coords[0][:2] for g in _geoms(points)], np.float64).reshape(-1, 2)
    items = list(points) if not isinstance(points, np.ndarray) else points
    if len(items) and hasattr(items[0], "coords"):
        return np.array([g.coords[0][:2] for g in items], np.float64).reshape(-1, 2)
    return np.asarray(items, np.float64).reshape(-1, 2)


def _split_polyline(line: np.ndarray, spacing: float) -> np.ndarray:
    """A polyline with each edge split into ceil(length / spacing) equal pieces."""
    if len(line) < 2:
        return line
    start, end = line[:-1], line[1:]
    lengths = np.hypot(*(end - start).T)
    pieces = np.maximum(1, np.ceil(lengths / spacing)).astype(np.int64)
    edge = np.repeat(np.arange(len(start)), pieces)
    first_piece = np.repeat(np.cumsum(pieces) - pieces, pieces)
    t = (np.arange(pieces.sum()) - first_piece) / pieces[edge]
    return np.vstack([start[edge] + (end[edge] - start[edge]) * t[:, None], line[-1:]])


# --- input checks -------------------------------------------------------------------

# what the closed-loop reading of a .poly file refuses and the planar-graph reading takes
_NOT_LOOPS = ("free vertices", "must form closed loops", "nested holes",
              "internal constraint loops", "hole point")


def _with_file_markers(domain: Domain, chains: list[np.ndarray], poly) -> Domain:
    """The file's segment markers (0 on a boundary segment becomes 1, as in
    Triangle) and regions on a domain read as closed loops."""
    regions = None if poly.regions is None else _read_only(np.asarray(poly.regions))
    if poly.segment_markers is None:
        return replace(domain, regions=regions)
    vertex = np.concatenate(chains)  # domain node -> file vertex
    n = len(poly.vertices)
    ends = np.sort(poly.segments, axis=1)
    keys = ends[:, 0] * n + ends[:, 1]
    order = np.argsort(keys)
    mine = np.sort(vertex[domain.segments], axis=1)
    at = order[np.searchsorted(keys[order], mine[:, 0] * n + mine[:, 1])]
    marks = np.array(poly.segment_markers[at], np.int64)
    marks[marks == 0] = 1
    return replace(domain, segment_markers=_read_only(marks), regions=regions)


def _checked_names(names) -> dict[str, int]:
    out = {}
    for name, marker in dict(names or {}).items():
        if not isinstance(name, str) or isinstance(marker, bool) or not isinstance(
                marker, (int, np.integer)):
            raise TypeError(f"names must map str to int markers, got {name!r}: {marker!r}")
        out[name] = int(marker)
    return out




def _loop_name(k: int) -> str:
    return "loop 0 (outer)" if k == 0 else f"loop {k} (hole {k})"


def _as_loop_list(loops) -> list:
    if isinstance(loops, np.ndarray) and loops.ndim == 2:
        raise GeometryError(
            "from_loops takes a sequence of loops; wrap a single outer loop as [loop]"
        )
    if isinstance(loops, (str, bytes, dict)) or not isinstance(loops, Iterable):
        raise TypeError(
            "from_loops takes a sequence of loops (outer first, then holes), "
            f"got {type(loops).__name__}"
        )
    loops = list(loops)
    if not loops:
        raise GeometryError("a domain needs at least one loop (the outer boundary)")
    return loops


def _node_of(flat_index: int) -> int:
    return flat_index // 2


def _coordinates(ring, name: str) -> np.ndarray:
    """One loop as an (n, 2) float64 array, refusing what would convert wrongly.

    Real numbers of any type (ints, floats, fractions, decimals) become the
    nearest float64; complex numbers, strings, booleans, masked entries,
    ragged rows and numbers beyond float64 are rejected naming the node.
    """
    if isinstance(ring, (str, bytes)):
        raise GeometryError(f"{name} is a string, not an array of nodes")
    if np.ma.isMaskedArray(ring) and np.ma.getmaskarray(ring).any():
        node = int(np.argmax(np.ma.getmaskarray(ring).reshape(len(ring), -1).any(axis=1)))
        raise GeometryError(f"{name} node {node} is masked")
    try:
        array = np.asarray(ring)
    except ValueError:  # rows of different lengths
        raise GeometryError(f"{name} {_ragged_row(ring)}") from None
    if array.ndim != 2 or array.shape[1] != 2:
        raise GeometryError(f"{name} must be an (n, 2) array of nodes, got shape {array.shape}")
    kind = array.dtype.kind
    if kind == "c":
        imaginary = np.flatnonzero((array.imag != 0).any(axis=1))
        node = int(imaginary[0]) if imaginary.size else 0
        raise GeometryError(
            f"{name} has complex coordinates (node {node} = {tuple(array[node].tolist())}); "
            "nodes are (x, y) pairs of real numbers"
        )
    if kind == "O":
        _check_objects(array, name)
    elif kind not in "iuf":
        raise GeometryError(
            f"{name} has coordinates of dtype {array.dtype}, not real numbers (node 0 = "
            f"{tuple(array[0].tolist()) if len(array) else ()})"
        )
    try:
        return array.astype(np.float64)
    except OverflowError:
        flat = array.ravel().tolist()
        bad = next(f for f, value in enumerate(flat) if not _fits_float(value))
        text = str(flat[bad])
        text = text if len(text) <= 24 else f"{text[:12]}... ({len(text)} characters)"
        raise GeometryError(
            f"{name} node {_node_of(bad)} has a coordinate too large for float64: {text}"
        ) from None


def _fits_float(value) -> bool:
    try:
        float(value)
    except OverflowError:
        return False
    return True


def _check_objects(array: np.ndarray, name: str) -> None:
    """An object array must hold real numbers only (a bool is not a coordinate)."""
    flat = array.ravel().tolist()
    for value_type in set(map(type, flat)):
        real = issubclass(value_type, (numbers.Real, Decimal)) and not issubclass(
            value_type, (bool, np.bool_)
        )
        if not real:
            bad = next(f for f, value in enumerate(flat) if type(value) is value_type)
            raise GeometryError(
                f"{name} node {_node_of(bad)} has a coordinate of type "
                f"{value_type.__name__}, not a real number: {flat[bad]!r}"
            )


def _ragged_row(ring) -> str:
    """Which row of a ragged loop is not an (x, y) pair."""
    for node, row in enumerate(ring):
        size = np.size(row) if np.ndim(row) <= 1 else -1
        if size != 2:
            what = f"{size} coordinate{'s' * (size != 1)}" if size >= 0 else "nested sequences"
            return f"node {node} has {what}; each node is an (x, y) pair"
    return "is not an (n, 2) array of nodes"


def _checked_rings(loop_list: list) -> tuple[np.ndarray, np.ndarray]:
    """All loops as one (N, 2) float64 array and loop offsets, closing repeats dropped.

    Errors name the loop and the node as given (a dropped closing repeat shifts
    no index).
    """
    rings = [_coordinates(ring, _loop_name(k)) for k, ring in enumerate(loop_list)]
    lengths = np.array([len(ring) for ring in rings], dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(lengths)])
    raw = flush_tiny(rings[0] if len(rings) == 1 else np.concatenate(rings))

    def where(q: int) -> tuple[str, int]:
        k = int(np.searchsorted(offsets, q, side="right") - 1)
        return _loop_name(k), q - int(offsets[k])

    finite = np.isfinite(raw).all(axis=1)
    if not finite.all():
        name, node = where(int(np.argmin(finite)))
        raise GeometryError(f"{name} has a non-finite coordinate at node {node}")
    outside = out_of_range(raw)
    if outside.any():
        q = int(np.argmax(outside))
        name, node = where(q)
        raise GeometryError(f"{name} node {node} = {out_of_range_message(raw[q])}")
    closing = _closing_repeats(raw, offsets)
    lengths = lengths - closing
    short = np.flatnonzero(lengths < 3)
    if short.size:
        k = int(short[0])
        raise GeometryError(
            f"{_loop_name(k)} has {lengths[k]} distinct nodes; a loop needs at least 3"
        )
    points = raw
    if closing.any():
        keep = np.ones(len(raw), dtype=bool)
        keep[(offsets[1:] - 1)[closing]] = False
        points = np.ascontiguousarray(raw[keep])
    offsets = np.concatenate([[0], np.cumsum(lengths)])
    following = np.arange(1, len(points) + 1)
    following[offsets[1:] - 1] = offsets[:-1]
    repeats = (points == points[following]).all(axis=1)
    if repeats.any():
        q = int(np.argmax(repeats))
        k = int(np.searchsorted(offsets, q, side="right") - 1)
        x, y = points[q]
        raise GeometryError(
            f"{_loop_name(k)} segment {q - offsets[k]} has zero length: nodes {q - offsets[k]} "
            f"and {(q - offsets[k] + 1) % lengths[k]} coincide at ({float(x)!r}, {float(y)!r})"
        )
    return points, offsets


def _closing_repeats(raw: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Which loops end with an exact repeat of their first node (closed rings)."""
    lengths = np.diff(offsets)
    closing = np.zeros(len(lengths), dtype=bool)
    long = np.flatnonzero(lengths >= 2)
    closing[long] = (raw[offsets[long + 1] - 1] == raw[offsets[long]]).all(axis=1)
    return closing


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


# --- exact kernels over all loops (flat points, loop k = offsets[k]:offsets[k+1]) -----


@njit(cache=True)
def _first_collinear_loop(points, offsets):
    """The first loop whose nodes all lie on one line (exact), -1 if none."""
    for k in range(offsets.shape[0] - 1):
        a, b = offsets[k], offsets[k] + 1
        collinear = True
        for c in range(offsets[k] + 2, offsets[k + 1]):
            if orient2d(points[a, 0], points[a, 1], points[b, 0], points[b, 1],
                        points[c, 0], points[c, 1]) != 0.0:  # fmt: skip
                collinear = False
                break
        if collinear:
            return k
    return -1


@njit(cache=True)
def _lowest_nodes(points, offsets):
    """Each loop's lexicographically smallest node (smallest x, then y; first if tied)."""
    n_loops = offsets.shape[0] - 1
    lowest = np.empty(n_loops, dtype=np.int64)
    for k in range(n_loops):
        best = offsets[k]
        for q in range(offsets[k] + 1, offsets[k + 1]):
            if precedes(points, q, best):
                best = q
        lowest[k] = best
    return lowest


@njit(cache=True)
def _counterclockwise(points, offsets, lowest):
    """Exact orientation of each simple loop, decided at its lowest node.

    That node is strictly convex, so the turn of its two neighbours gives the
    orientation (never zero once fold-backs are excluded).
    """
    n_loops = offsets.shape[0] - 1
    ccw = np.empty(n_loops, dtype=np.bool_)
    for k in range(n_loops):
        q = lowest[k]
        p = q - 1 if q > offsets[k] else offsets[k + 1] - 1
        r = q + 1 if q + 1 < offsets[k + 1] else offsets[k]
        ccw[k] = orient2d(points[p, 0], points[p, 1], points[q, 0], points[q, 1],
                          points[r, 0], points[r, 1]) > 0.0  # fmt: skip
    return ccw


@njit(cache=True)
def _oriented(offsets, flip):
    """Node order of each loop, reversed after its first node where ``flip``, and the
    segments joining consecutive nodes of that order."""
    order = np.arange(offsets[-1])
    segments = np.empty((offsets[-1], 2), dtype=np.int64)
    for k in range(offsets.shape[0] - 1):
        start, end = offsets[k], offsets[k + 1]
        if flip[k]:
            order[start + 1 : end] = order[start + 1 : end][::-1].copy()
        for q in range(start, end):
            segments[q, 0] = order[q]
            segments[q, 1] = order[q + 1] if q + 1 < end else order[start]
    return order, segments


@njit(cache=True)
def _enclosing_loops(points, offsets, segments, lowest, sweep_order, below, ccw):
    """For each loop: does loop 0 enclose it, and the nearest hole around it (-1: none).

    Loops taken in sweep order of their lowest nodes, so every enclosing loop
    comes first.  The segment t directly below a loop's lowest node bounds the
    face that holds the loop: the inside of t's loop m if that lies above t
    (m counter-clockwise and t directed rightwards, or neither), else the face
    around m.
    """
    n_loops = lowest.shape[0]
    parent = np.full(n_loops, -1, dtype=np.int64)
    in_outer = np.zeros(n_loops, dtype=np.bool_)
    hole_around = np.full(n_loops, -1, dtype=np.int64)
    for k in sweep_order:
        t = below[lowest[k]]
        if t < 0:
            continue
        m = np.searchsorted(offsets, t, side="right") - 1
        rightwards = precedes(points, segments[t, 0], segments[t, 1])
        p = m if ccw[m] == rightwards else parent[m]
        parent[k] = p
        if p >= 0:
            in_outer[k] = p == 0 or in_outer[p]
            hole_around[k] = p if p > 0 else hole_around[p]
    return in_outer, hole_around


@njit(cache=True)
def _on_closed_box(px, py, ax, ay, bx, by):
    """p within the bounding box of a-b; for p collinear with a-b: p on segment a-b."""
    return min(ax, bx) <= px <= max(ax, bx) and min(ay, by) <= py <= max(ay, by)


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
def _point_inside_ring(ring):
    """A point strictly inside a simple ring, verified with the exact crossing test.

    Scan lines halfway between consecutive distinct node ordinates, widest gap
    first; on each, the widest inside interval's midpoint.  Returns
    ``(found, x, y)``.
    """
    n = ring.shape[0]
    levels = np.unique(ring[:, 1])
    gaps = levels[1:] - levels[:-1]
    xs = np.empty(n)
    for g in np.argsort(-gaps, kind="mergesort"):
        y = 0.5 * (levels[g] + levels[g + 1])
        if not levels[g] < y < levels[g + 1]:
            continue
        count = 0
        for e in range(n):
            ax, ay = ring[e, 0], ring[e, 1]
            bx, by = ring[(e + 1) % n, 0], ring[(e + 1) % n, 1]
            if (ay > y) != (by > y):
                xs[count] = ax + (y - ay) * (bx - ax) / (by - ay)
                count += 1
        crossings = np.sort(xs[:count])
        w = np.argmax(crossings[1::2] - crossings[0::2])
        x = 0.5 * (crossings[2 * w] + crossings[2 * w + 1])
        if _point_in_ring(x, y, ring) == 1:
            return True, x, y
    return False, 0.0, 0.0


@njit(cache=True)
def _hole_points(points, offsets):
    """One point strictly inside each hole; the first hole without one, or -1."""
    n_holes = offsets.shape[0] - 2
    out = np.empty((n_holes, 2))
    for h in range(n_holes):
        found, x, y = _point_inside_ring(points[offsets[h + 1] : offsets[h + 2]])
        if not found:
            return out, h + 1
        out[h, 0], out[h, 1] = x, y
    return out, -1


# --- validation and derived quantities ----------------------------------------------


def _segment_name(global_index: int, offsets: np.ndarray) -> str:
    k = int(np.searchsorted(offsets, global_index, side="right") - 1)
    return f"{_loop_name(k)} segment {global_index - offsets[k]}"


def _check_layout(points: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Raise unless the loops are disjoint simple polygons, holes inside loop 0 only.

    One exact sweep (:mod:`bubblemesh._sweep`) finds any two segments that
    share a point other than a common end node; without one, the loops are
    nested or apart, and the segment below each loop's lowest node tells
    which loop directly encloses it.  Returns each loop's orientation (True:
    counter-clockwise).
    """
    collinear = _first_collinear_loop(points, offsets)
    if collinear >= 0:
        raise GeometryError(f"{_loop_name(collinear)} has zero area: all its nodes are collinear")
    index = np.arange(len(points), dtype=np.int64)
    following = index + 1
    following[offsets[1:] - 1] = offsets[:-1]
    segments = np.column_stack([index, following])
    lowest = _lowest_nodes(points, offsets)
    locate = np.zeros(len(points), dtype=np.bool_)
    locate[lowest] = True
    i, j, kind, below = sweep(points, segments, locate)
    if kind != NO_CONFLICT:
        raise GeometryError(
            f"{_segment_name(j, offsets)} {CONFLICT_VERB[kind]} {_segment_name(i, offsets)}"
        )
    ccw = _counterclockwise(points, offsets, lowest)
    sweep_order = np.lexsort((points[lowest, 1], points[lowest, 0]))
    in_outer, hole_around = _enclosing_loops(
        points, offsets, segments, lowest, sweep_order, below, ccw
    )
    bad = np.flatnonzero(~in_outer[1:] | (hole_around[1:] >= 0))
    if bad.size:
        k = int(bad[0]) + 1
        if not in_outer[k]:
            raise GeometryError(
                f"{_loop_name(k)} lies outside the outer loop "
                "(the first loop must be the outer boundary)"
            )
        raise GeometryError(
            f"{_loop_name(k)} lies inside {_loop_name(int(hole_around[k]))}; "
            "nested holes are not supported"
        )
    return ccw


def _loop_areas(points: np.ndarray, offsets: np.ndarray) -> list[float]:
    """Unsigned shoelace area of each loop, summed with math.fsum.

    Coordinates are taken relative to each loop's first node, so a domain far
    from the origin loses no digits to large products (the shift is exact for
    nodes within a factor of two of it).
    """
    lengths = np.diff(offsets)
    rel = points - np.repeat(points[offsets[:-1]], lengths, axis=0)
    following = np.arange(1, len(points) + 1)
    following[offsets[1:] - 1] = offsets[:-1]
    x, y = rel[:, 0], rel[:, 1]
    terms = np.empty(2 * len(points))
    terms[0::2] = x * y[following]
    terms[1::2] = -(x[following] * y)
    flat = terms.tolist()
    bounds = (2 * offsets).tolist()
    return [abs(0.5 * math.fsum(flat[a:b])) for a, b in zip(bounds[:-1], bounds[1:])]


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
