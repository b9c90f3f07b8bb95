"""The Mesh: plain arrays plus what produced them (the output of paper §2 and §3).

``points`` (N,2) float64 with the boundary nodes first, unmoved and in the
domain's order; ``triangles`` (M,3) int64 counter-clockwise; ``neighbors``
(M,3) int64, the triangle across the edge opposite each vertex, -1 on the
boundary; ``radii`` (N,) node-bubble radii; ``segments`` (S,2) the boundary
segments.  Arrays are read-only: every stage returns a new Mesh.  Each stage
leaves a small record of what it did (``generation``, ``optimization``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from .errors import GeometryError

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
        (one value per node / per triangle)."""
        import meshio

        points, cells = self._data(point_data, cell_data)
        xyz = np.column_stack([self.points, np.zeros(len(self.points))])
        return meshio.Mesh(xyz, [("triangle", np.asarray(self.triangles))],
                           point_data={k: np.asarray(v) for k, v in points.items()},
                           cell_data={k: [np.asarray(v)] for k, v in cells.items()})

    def write(self, path: str | Path, file_format: str | None = None, *,
              point_data: Mapping[str, Any] | None = None,
              cell_data: Mapping[str, Any] | None = None, **meshio_kwargs: Any) -> None:
        """Write with meshio (VTU, Gmsh .msh, XDMF, ...) as ``to_meshio`` does;
        ``meshio_kwargs`` go to ``meshio.write``."""
        from .io import write_mesh

        points, cells = self._data(point_data, cell_data)
        write_mesh(path, self.points, self.triangles, point_data=points, cell_data=cells,
                   file_format=file_format, **meshio_kwargs)

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
        return from_arrays(points, triangles,
                           None if radius is None else np.asarray(radius, np.float64))


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
