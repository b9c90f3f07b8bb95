"""One-call bridges from a :class:`~bubblemesh.Mesh` to finite-element and
plotting libraries, keeping the boundary markers: scikit-fem (``to_skfem``),
dolfinx/FEniCS (``write_xdmf``: the mesh and its facet tags as two XDMF
files) and pyvista (``to_pyvista``).  Each library is imported only when its
bridge is called."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["facet_markers", "to_pyvista", "to_skfem", "write_xdmf"]


def facet_markers(mesh) -> dict[str, np.ndarray]:
    """{name: (E_k, 2) edges}: the boundary and interface edges of each marker,
    under its name (``mesh.marker_names``) or its number as a string."""
    edges, marks = mesh.boundary_edges()
    names = {marker: name for name, marker in mesh.marker_names.items()}
    return {names.get(int(m), str(int(m))): edges[marks == m] for m in np.unique(marks)}


def to_skfem(mesh) -> tuple[Any, dict[str, np.ndarray]]:
    """(``skfem.MeshTri``, {name: facet indices}) for ``mesh``: the facets of
    each marker as indices into ``MeshTri.facets`` (ready for
    ``basis.get_dofs(facets)`` and ``FacetBasis(m, e, facets=...)``)."""
    try:
        import skfem
    except ImportError as error:
        raise ImportError("to_skfem needs scikit-fem: pip install scikit-fem") from error
    m = skfem.MeshTri(np.ascontiguousarray(mesh.points.T, dtype=np.float64),
                      np.ascontiguousarray(mesh.triangles.T, dtype=np.int64))
    n = len(mesh.points)
    facets = np.sort(m.facets.T, axis=1)
    fkey = facets[:, 0] * n + facets[:, 1]
    order = np.argsort(fkey)
    out = {}
    for name, edges in facet_markers(mesh).items():
        e = np.sort(edges, axis=1)
        key = e[:, 0] * n + e[:, 1]
        pos = order[np.searchsorted(fkey[order], key)]
        out[name] = np.sort(pos)
    return m, out


def write_xdmf(mesh, path: str | Path) -> tuple[Path, Path]:
    """Write ``path`` (the triangles, cell data ``regions``: region index plus
    one) and ``<stem>_facets.xdmf`` beside it (the boundary and interface edges
    as line cells, cell data ``markers``), the pair dolfinx reads with
    ``XDMFFile.read_mesh`` and ``read_meshtags``.  Returns both paths."""
    import meshio

    path = Path(path)
    facets_path = path.with_name(f"{path.stem}_facets{path.suffix or '.xdmf'}")
    xyz = np.column_stack([mesh.points, np.zeros(len(mesh.points))])
    regions = (mesh.region_ids() + 1).astype(np.int32)
    edges, marks = mesh.boundary_edges()
    meshio.write(path, meshio.Mesh(xyz, [("triangle", np.asarray(mesh.triangles))],
                                   cell_data={"regions": [regions]}),
                 file_format="xdmf", data_format="XML")
    meshio.write(facets_path, meshio.Mesh(xyz, [("line", np.asarray(edges))],
                                          cell_data={"markers": [marks.astype(np.int32)]}),
                 file_format="xdmf", data_format="XML")
    return path, facets_path


def to_pyvista(mesh, point_data=None, cell_data=None) -> Any:
    """A ``pyvista.UnstructuredGrid`` of the triangles (points with z = 0, in
    the mesh's order): point data ``radius`` and ``boundary``, cell data
    ``radius_ratio`` and ``region`` (region index plus one, 0 for none), plus
    any given (one value per node / per triangle)."""
    try:
        import pyvista
    except ImportError as error:
        raise ImportError("to_pyvista needs pyvista: pip install pyvista") from error
    points, cells = mesh._data(point_data, {"region": mesh.region_ids() + 1, **(cell_data or {})})
    xyz = np.column_stack([mesh.points, np.zeros(len(mesh.points))])
    grid = pyvista.UnstructuredGrid({pyvista.CellType.TRIANGLE: np.asarray(mesh.triangles)}, xyz)
    for name, values in points.items():
        grid.point_data[name] = np.asarray(values)
    for name, values in cells.items():
        grid.cell_data[name] = np.asarray(values)
    return grid
