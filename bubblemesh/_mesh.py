"""The Mesh: plain arrays plus what produced them (the output of paper §2 and §3).

``points`` (N,2) float64 with the boundary nodes first, unmoved and in the
domain's order; ``triangles`` (M,3) int64 counter-clockwise; ``neighbors``
(M,3) int64, the triangle across the edge opposite each vertex, -1 on the
boundary; ``radii`` (N,) node-bubble radii; ``segments`` (S,2) the boundary
segments.  Arrays are read-only: every stage returns a new Mesh.  Each stage
leaves a small record of what it did (``generation``, ``optimization``).

Markers and regions: every boundary and interface edge carries the marker of
the input segment it lies on (``boundary_edges``), every triangle the region
of its face (``region_ids``, flood-filled from the domain's region points
across edges that are no constraint); ``to_meshio`` and ``write`` put the
edges in as line cells with Gmsh physical tags and names.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np
from numba import njit

from .errors import GeometryError
from .predicates import orient2d

__all__ = ["GenerationStats", "Mesh", "OptimizationStats", "read"]


@dataclass(frozen=True)
class GenerationStats:
    """What §2 did: ``insertions`` interior nodes, ``bubble_area`` (sum A_e, the
    left side of eq. 6) against ``domain_area`` (A_geo), why it stopped
    (``stop``: "population" or "max_insertions"), seconds in total and per phase."""

    insertions: int
    cavity_triangles: int
    bubble_area: float
    domain_area: float
    stop: str
    seconds: float
    phases: Mapping[str, float]


@dataclass(frozen=True)
class OptimizationStats:
    """What §3 did: ``iterations`` run, ``max_displacement`` (largest move of the
    last iteration relative to its node's radius), ``blocked_moves`` (moves that
    found no step inside the domain), Verlet-list work, the parameters
    (``amplification``, ``rings``, ``alpha``), seconds in total and per phase."""

    iterations: int
    max_displacement: float
    blocked_moves: int
    list_builds: int
    list_layouts: int
    amplification: float
    rings: int
    alpha: float
    seconds: float
    phases: Mapping[str, float]


def _frozen(array: Any, dtype: Any) -> np.ndarray:
    out = np.ascontiguousarray(array, dtype=dtype)
    out.flags.writeable = False
    return out


@dataclass(frozen=True, eq=False)
class Mesh:
    """A triangle mesh; equality is identity (the arrays make value equality
    ambiguous), so a Mesh can be a dict key."""

    points: np.ndarray
    triangles: np.ndarray
    neighbors: np.ndarray
    radii: np.ndarray
    segments: np.ndarray
    n_boundary: int
    domain: Any = field(default=None, repr=False)
    generation: GenerationStats | None = None
    optimization: OptimizationStats | None = None
    lines: np.ndarray | None = field(default=None, repr=False)  # (E, 2) read from a file
    line_markers: np.ndarray | None = field(default=None, repr=False)
    names: Mapping[str, int] | None = field(default=None, repr=False)
    cell_regions: np.ndarray | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "points", _frozen(self.points, np.float64))
        object.__setattr__(self, "triangles", _frozen(self.triangles, np.int64))
        object.__setattr__(self, "neighbors", _frozen(self.neighbors, np.int64))
        object.__setattr__(self, "radii", _frozen(self.radii, np.float64))
        object.__setattr__(self, "segments", _frozen(self.segments, np.int64))
        object.__setattr__(self, "n_boundary", int(self.n_boundary))

    def __repr__(self) -> str:
        return (f"Mesh(nodes={len(self.points)}, triangles={len(self.triangles)}, "
                f"boundary_nodes={self.n_boundary})")

    @property
    def stats(self) -> Mapping[str, Any]:
        """Both stages' records as one flat read-only mapping (a table row):
        §2's fields by their names, §3's too, its seconds and phases as
        ``optimize_seconds`` and ``optimize_phases``."""
        row: dict[str, Any] = {}
        if self.generation is not None:
            row.update(asdict(self.generation))
        if self.optimization is not None:
            opt = asdict(self.optimization)
            opt["optimize_seconds"] = opt.pop("seconds")
            opt["optimize_phases"] = opt.pop("phases")
            row.update(opt)
        return MappingProxyType(row)

    @property
    def insertions(self) -> int:
        """Interior nodes inserted by §2."""
        return self._generation().insertions

    @property
    def bubble_area(self) -> float:
        """Sum of element-bubble areas when §2 stopped (left side of eq. 6)."""
        return self._generation().bubble_area

    @property
    def domain_area(self) -> float:
        """A_geo (right side of eq. 6)."""
        return self._generation().domain_area

    def _generation(self) -> GenerationStats:
        if self.generation is None:
            raise AttributeError("this mesh was not made by bubblemesh.generate")
        return self.generation

    def check(self) -> None:
        """GeometryError naming the first inconsistency a kernel could not
        safely read (shapes, dtypes, index ranges, neighbours, orientation);
        every function that runs a kernel on a Mesh calls it first.  O(M)."""
        from .topology import check_mesh

        check_mesh(self.points, self.triangles, self.neighbors, self.radii, self.segments,
                   self.n_boundary)

    def boundary_edges(self) -> tuple[np.ndarray, np.ndarray]:
        """(edges (E, 2), markers (E,)): every boundary and interface edge once
        (an interface's two sides are one edge), with the marker of the input
        segment it lies on (1 where none is known)."""
        if self.lines is not None:
            marks = (np.ones(len(self.lines), np.int64) if self.line_markers is None
                     else np.asarray(self.line_markers, np.int64))
            return np.asarray(self.lines), marks
        S = np.asarray(self.segments)
        domain = self.domain
        marks = (np.asarray(domain.markers, np.int64)
                 if domain is not None and len(domain.segments) == len(S)
                 else np.ones(len(S), np.int64))
        _, first = np.unique(np.sort(S, axis=1), axis=0, return_index=True)
        first = np.sort(first)
        return S[first], marks[first]

    @property
    def marker_names(self) -> Mapping[str, int]:
        """Marker names (name -> marker), from the domain or the file."""
        if self.names is not None:
            return self.names
        return getattr(self.domain, "marker_names", None) or {}

    def region_ids(self) -> np.ndarray:
        """(M,) int64: per triangle, the index of the region point whose face
        holds it (a later region point wins, as in Triangle), -1 for none."""
        if self.cell_regions is not None:
            return np.asarray(self.cell_regions, np.int64)
        regions = getattr(self.domain, "regions", None)
        out = np.full(len(self.triangles), -1, np.int64)
        if regions is None or not len(regions):
            return out
        from .topology import neighbors_of

        nbr = _cut_neighbors(self, neighbors_of(np.asarray(self.triangles)))
        for r, (x, y) in enumerate(np.asarray(regions)[:, :2].tolist()):
            _flood(np.ascontiguousarray(self.points), np.ascontiguousarray(self.triangles),
                   nbr, float(x), float(y), r, out)
        return out

    def region_attributes(self) -> np.ndarray:
        """(M,) float64: each triangle's regional attribute (0 outside every region)."""
        ids = self.region_ids()
        regions = getattr(self.domain, "regions", None)
        if regions is None or not len(regions):
            return ids.astype(np.float64) + 1.0 if self.cell_regions is not None else (
                np.zeros(len(ids)))
        return np.where(ids >= 0, np.asarray(regions)[np.maximum(ids, 0), 2], 0.0)

    def quality(self) -> np.ndarray:
        """Radius ratio of every triangle (eq. 10)."""
        from .quality import radius_ratio

        return radius_ratio(self.points, self.triangles)

    def _data(self, point_data: Mapping[str, Any] | None,
              cell_data: Mapping[str, Any] | None) -> tuple[dict, dict]:
        boundary = np.zeros(len(self.points), np.int64)
        boundary[: self.n_boundary] = 1
        points = {"radius": np.asarray(self.radii), "boundary": boundary, **(point_data or {})}
        cells = {"radius_ratio": self.quality(), **(cell_data or {})}
        for name, values in {**points, **cells}.items():
            expected = len(self.points) if name in points else len(self.triangles)
            if len(values) != expected:
                raise ValueError(f"data {name!r} has {len(values)} values, expected {expected}")
        return points, cells

    def to_meshio(self, point_data: Mapping[str, Any] | None = None,
                  cell_data: Mapping[str, Any] | None = None) -> Any:
        """A ``meshio.Mesh`` (3-D points with z = 0): node-bubble radius and a
        boundary flag as point data, radius ratio as cell data, plus any given
        (one value per node / per triangle).  A second block of ``line`` cells
        holds the boundary and interface edges; cell data ``marker`` (the
        edges' markers, the triangles' region index plus one) and Gmsh's
        ``gmsh:physical``/``gmsh:geometrical`` carry the same numbers, and
        ``field_data`` the marker names (``{name: [marker, 1]}``)."""
        import meshio

        points, cells = self._data(point_data, cell_data)
        xyz = np.column_stack([self.points, np.zeros(len(self.points))])
        blocks, data, field_data = self._blocks(cells)
        return meshio.Mesh(xyz, blocks,
                           point_data={k: np.asarray(v) for k, v in points.items()},
                           cell_data=data, field_data=field_data)

    def _blocks(self, cells: Mapping[str, Any]) -> tuple[list, dict, dict]:
        """Triangle and line cell blocks with per-block cell data (lines get 0
        for the triangles' data), and the physical names."""
        edges, marks = self.boundary_edges()
        region = self.region_ids() + 1
        tag = np.where(region > 0, region, 1).astype(np.int64)
        data = {k: [np.asarray(v), np.zeros(len(edges), np.asarray(v).dtype)]
                for k, v in cells.items()}
        data["marker"] = [region, marks]
        data["gmsh:physical"] = [tag, marks]
        data["gmsh:geometrical"] = [tag, marks]
        field_data = {name: np.array([marker, 1]) for name, marker in self.marker_names.items()}
        return ([("triangle", np.asarray(self.triangles)), ("line", np.asarray(edges))],
                data, field_data)

    def write(self, path: str | Path, file_format: str | None = None, *,
              point_data: Mapping[str, Any] | None = None,
              cell_data: Mapping[str, Any] | None = None, **meshio_kwargs: Any) -> None:
        """Write with meshio (VTU, Gmsh .msh, XDMF, ...) as ``to_meshio`` does;
        ``meshio_kwargs`` go to ``meshio.write``.  ``.msh`` is binary Gmsh 4.1,
        whose element data meshio and Gmsh read back on the triangle and the
        line blocks alike (the triangles' data is NaN or 0 on the lines; the
        triangles come back in region order); ``file_format="gmsh22"`` gives
        Gmsh 2.2, without the triangles' data when there are line cells (meshio's
        2.2 reader cannot split element data over two blocks)."""
        from .io import write_mesh

        points, cells = self._data(point_data, cell_data)
        edges, marks = self.boundary_edges()
        region = self.region_ids() + 1
        if file_format is None and Path(path).suffix.lower() == ".msh":
            file_format = "gmsh"
        write_mesh(path, self.points, self.triangles, point_data=points, cell_data=cells,
                   file_format=file_format, lines=(edges, marks),
                   regions=np.where(region > 0, region, 1),
                   names=dict(self.marker_names), **meshio_kwargs)

    @classmethod
    def from_meshio(cls, mesh: Any) -> Mesh:
        """A Mesh from a ``meshio.Mesh`` with triangle cells (any other cells are
        ignored).  Triangles are made counter-clockwise; nodes on the boundary
        come first (as bubblemesh writes them, or renumbered stably if not);
        ``radii`` come from point data ``radius`` if present, else half the mean
        length of each node's edges."""
        blocks = [c.data for c in mesh.cells if c.type == "triangle"]
        if not blocks:
            raise GeometryError("the mesh has no triangle cells")
        points = np.asarray(mesh.points, dtype=np.float64)
        if points.ndim != 2 or points.shape[1] not in (2, 3):
            raise GeometryError(f"points must be (N, 2) or (N, 3), got shape {points.shape}")
        if points.shape[1] == 3:
            if np.any(points[:, 2] != 0.0):
                raise GeometryError("the mesh is not planar: some points have z != 0")
            points = points[:, :2]
        triangles = np.concatenate([np.asarray(b, dtype=np.int64) for b in blocks])
        radius = mesh.point_data.get("radius")
        out = from_arrays(points, triangles,
                          None if radius is None else np.asarray(radius, np.float64))
        return _with_file_tags(out, mesh)


def from_arrays(points: np.ndarray, triangles: np.ndarray,
                radii: np.ndarray | None = None) -> Mesh:
    """A Mesh from a node array and a triangle array (checked, oriented, boundary
    nodes first); see ``Mesh.from_meshio``."""
    from .topology import boundary_first, oriented_neighbors

    points = np.ascontiguousarray(points, dtype=np.float64)
    triangles, neighbors = oriented_neighbors(points, triangles)
    order, n_boundary, segments = boundary_first(triangles, neighbors, len(points))
    new_of_old = np.empty(len(points), np.int64)
    new_of_old[order] = np.arange(len(points))
    triangles, segments = new_of_old[triangles], new_of_old[segments]
    points = points[order]
    if radii is None:
        radii = _half_mean_edge(points, triangles)
    else:
        radii = radii[order]
    return Mesh(points=points, triangles=triangles, neighbors=neighbors, radii=radii,
                segments=segments, n_boundary=n_boundary)


def _tags(mesh: Any, kind: str) -> np.ndarray | None:
    """The per-cell tags of the ``kind`` blocks: Gmsh physical tags, else ``marker``."""
    for key in ("gmsh:physical", "marker", "markers", "medit:ref"):
        if key in mesh.cell_data:
            parts = [np.asarray(d) for c, d in zip(mesh.cells, mesh.cell_data[key])
                     if c.type == kind]
            if parts:
                return np.concatenate(parts).astype(np.int64)
    return None


def _with_file_tags(out: Mesh, mesh: Any) -> Mesh:
    """Line cells (boundary and interface edges) with their markers, marker
    names (``field_data`` of dimension 1) and triangle tags as regions."""
    from dataclasses import replace

    lines = [np.asarray(c.data, np.int64) for c in mesh.cells if c.type == "line"]
    names = {str(k): int(np.asarray(v).ravel()[0]) for k, v in (mesh.field_data or {}).items()
             if np.asarray(v).size >= 2 and int(np.asarray(v).ravel()[1]) == 1}
    changes: dict[str, Any] = {"names": names}
    if lines:
        # from_arrays renumbered the nodes: map the file's indices the same way
        order = _order_of(out, mesh)
        changes["lines"] = order[np.concatenate(lines)]
        changes["line_markers"] = _tags(mesh, "line")
    tri_tags = _tags(mesh, "triangle")
    if tri_tags is not None and len(np.unique(tri_tags)) > 1:
        changes["cell_regions"] = _match_triangles(out, mesh, tri_tags)
    return replace(out, **changes)


def _order_of(out: Mesh, mesh: Any) -> np.ndarray:
    """New index of each file node: from_arrays keeps the (distinct) coordinates
    and reorders them, so matching lexicographic orders pairs them up."""
    P = np.asarray(mesh.points, np.float64)[:, :2]
    file_rank = np.lexsort((P[:, 1], P[:, 0]))
    out_rank = np.lexsort((out.points[:, 1], out.points[:, 0]))
    new = np.empty(len(P), np.int64)
    new[file_rank] = out_rank
    return new


def _match_triangles(out: Mesh, mesh: Any, tags: np.ndarray) -> np.ndarray:
    """File triangle tags in the order of ``out.triangles`` (region index = tag - 1)."""
    order = _order_of(out, mesh)
    blocks = [np.asarray(c.data, np.int64) for c in mesh.cells if c.type == "triangle"]
    file_tri = np.sort(order[np.concatenate(blocks)], axis=1)
    mine = np.sort(np.asarray(out.triangles), axis=1)
    n = len(out.points)
    fk = (file_tri[:, 0] * n + file_tri[:, 1]) * n + file_tri[:, 2]
    mk = (mine[:, 0] * n + mine[:, 1]) * n + mine[:, 2]
    idx = np.argsort(fk)
    return tags[idx[np.searchsorted(fk[idx], mk)]] - 1


def _cut_neighbors(mesh: Mesh, nbr: np.ndarray) -> np.ndarray:
    """Neighbours with -1 across every boundary and interface edge."""
    edges, _ = mesh.boundary_edges()
    T = np.asarray(mesh.triangles)
    n = len(mesh.points)
    a, b = T[:, [1, 2, 0]], T[:, [2, 0, 1]]
    key = np.minimum(a, b) * n + np.maximum(a, b)
    wall = np.isin(key, np.sort(edges, axis=1) @ np.array([n, 1]))
    return np.where(wall, -1, nbr)


@njit(cache=True)
def _flood(P, T, nbr, x, y, r, out):
    """Mark with r every triangle of the face holding (x, y) (across nbr >= 0)."""
    start = -1
    for t in range(T.shape[0]):
        u, v, w = T[t, 0], T[t, 1], T[t, 2]
        if (orient2d(P[u, 0], P[u, 1], P[v, 0], P[v, 1], x, y) >= 0.0
                and orient2d(P[v, 0], P[v, 1], P[w, 0], P[w, 1], x, y) >= 0.0
                and orient2d(P[w, 0], P[w, 1], P[u, 0], P[u, 1], x, y) >= 0.0):
            start = t
            break
    if start < 0:
        return
    seen = np.zeros(T.shape[0], np.bool_)
    stack = np.empty(T.shape[0], np.int64)
    stack[0] = start
    seen[start] = True
    top = 1
    while top > 0:
        top -= 1
        t = stack[top]
        out[t] = r
        for j in range(3):
            n = nbr[t, j]
            if n >= 0 and not seen[n]:
                seen[n] = True
                stack[top] = n
                top += 1


def _half_mean_edge(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    edges = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    length = np.linalg.norm(points[edges[:, 0]] - points[edges[:, 1]], axis=1)
    total = np.bincount(edges.ravel(), np.repeat(length, 2), minlength=len(points))
    count = np.bincount(edges.ravel(), minlength=len(points))
    return 0.5 * total / np.maximum(count, 1)


def read(path: str | Path, file_format: str | None = None) -> Mesh:
    """Read any meshio-readable triangle mesh file as a :class:`Mesh`
    (``Mesh.from_meshio``); a file bubblemesh wrote comes back with the same
    points, triangles and radii."""
    from .io import read_meshio

    return Mesh.from_meshio(read_meshio(path, file_format))
