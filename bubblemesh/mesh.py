"""The Mesh: plain arrays plus what produced them (paper §2 and §3 outputs).

``points`` (N,2) float64 with the domain's boundary nodes first, unmoved and
in the domain's order; ``triangles`` (M,3) int64 counter-clockwise;
``neighbors`` (M,3) int64, the triangle across the edge opposite each vertex,
-1 on the boundary; ``radii`` (N,) node-bubble radii; ``segments`` the
domain's boundary segments.  Arrays are read-only: every stage returns a new
Mesh instead of changing one.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np


def _frozen(array, dtype):
    out = np.ascontiguousarray(array, dtype=dtype)
    out.flags.writeable = False
    return out


@dataclass(frozen=True)
class Mesh:
    points: np.ndarray
    triangles: np.ndarray
    neighbors: np.ndarray
    radii: np.ndarray
    segments: np.ndarray
    n_boundary: int
    domain: Any = field(repr=False)
    stats: dict = field(default_factory=dict)

    def __post_init__(self):
        object.__setattr__(self, "points", _frozen(self.points, np.float64))
        object.__setattr__(self, "triangles", _frozen(self.triangles, np.int64))
        object.__setattr__(self, "neighbors", _frozen(self.neighbors, np.int64))
        object.__setattr__(self, "radii", _frozen(self.radii, np.float64))
        object.__setattr__(self, "segments", _frozen(self.segments, np.int64))

    def __repr__(self) -> str:
        return (f"Mesh(nodes={len(self.points)}, triangles={len(self.triangles)}, "
                f"boundary_nodes={self.n_boundary})")

    @property
    def insertions(self) -> int:
        """Interior nodes inserted by §2."""
        return int(self.stats["insertions"])

    @property
    def bubble_area(self) -> float:
        """Sum of element-bubble areas when §2 stopped (left side of eq. 6)."""
        return float(self.stats["bubble_area"])

    @property
    def domain_area(self) -> float:
        """A_geo (right side of eq. 6)."""
        return float(self.stats["domain_area"])

    def quality(self) -> np.ndarray:
        """Radius ratio of every triangle (eq. 10)."""
        from .quality import radius_ratio

        return radius_ratio(self.points, self.triangles)

    def write(self, path, file_format=None):
        """Write with meshio (VTU, Gmsh .msh, XDMF, ...): radius ratio as cell data,
        node-bubble radius and a boundary flag as point data."""
        from .io import write_mesh

        boundary = np.zeros(len(self.points), np.int64)
        boundary[: self.n_boundary] = 1
        write_mesh(path, self.points, self.triangles,
                   point_data={"radius": np.asarray(self.radii), "boundary": boundary},
                   cell_data={"radius_ratio": self.quality()}, file_format=file_format)
