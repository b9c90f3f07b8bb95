"""The finite-element bridges.  scikit-fem: named boundary markers carry
Dirichlet and Neumann conditions, and the P1 error against a manufactured
solution falls at the expected order (the oracle is the closed-form
solution, not the mesher).  pyvista: the grid's points, triangles and data
against the mesh, its radius ratio against VTK's own quality measure.
dolfinx's XDMF pair: read back with meshio (and h5py for any HDF5 part),
each facet tag against the side it lies on."""

import numpy as np
import pytest

import bubblemesh as bm
from bubblemesh.interop import to_skfem

try:
    import skfem
    from skfem import Basis, ElementTriP1, FacetBasis, LinearForm, solve
    from skfem.models.poisson import laplace
except ImportError:
    skfem = None
needs_skfem = pytest.mark.skipif(skfem is None, reason="needs scikit-fem")

DIRICHLET, NEUMANN, HOLE = 1, 2, 3


def exact(x, y):
    return np.sin(np.pi * x) * np.exp(y)


def grad_exact(x, y):
    return np.pi * np.cos(np.pi * x) * np.exp(y), np.sin(np.pi * x) * np.exp(y)


def source(x, y):  # -Δu for u = sin(pi x) e^y
    return (np.pi**2 - 1.0) * np.sin(np.pi * x) * np.exp(y)


def plate() -> bm.Domain:
    """An L-shaped plate [0,2]^2 minus [1,2]^2 with a circular hole: the left
    side x = 0 'clamped' (Dirichlet), the other outer sides 'loaded' and the
    hole 'hole' (both Neumann)."""
    from dataclasses import replace

    outer = np.array([(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)], float)
    t = np.linspace(0, 2 * np.pi, 16, endpoint=False)
    hole = np.column_stack([0.5 + 0.2 * np.cos(t), 0.5 + 0.2 * np.sin(t)])
    domain = bm.Domain.from_pslg(loops=[outer, hole], markers=[NEUMANN, HOLE],
                                 names={"clamped": DIRICHLET, "loaded": NEUMANN, "hole": HOLE})
    ends = domain.points[domain.segments]
    marks = np.array(domain.markers)
    marks[(ends[:, 0, 0] == 0.0) & (ends[:, 1, 0] == 0.0)] = DIRICHLET
    return replace(domain, segment_markers=marks)


def solve_on(mesh):
    m, facets = to_skfem(mesh)
    assert set(facets) == {"clamped", "loaded", "hole"}
    e = ElementTriP1()
    basis = Basis(m, e)

    @LinearForm
    def rhs(v, w):
        return source(w.x[0], w.x[1]) * v

    @LinearForm
    def flux(v, w):
        gx, gy = grad_exact(w.x[0], w.x[1])
        return (gx * w.n[0] + gy * w.n[1]) * v

    A = laplace.assemble(basis)
    b = rhs.assemble(basis)
    for name in ("loaded", "hole"):
        b = b + flux.assemble(FacetBasis(m, e, facets=facets[name]))
    dofs = basis.get_dofs(facets["clamped"])
    x = np.zeros(basis.N)
    x[dofs.all()] = exact(*m.p[:, dofs.all()])
    u = solve(*skfem.condense(A, b, x=x, D=dofs))
    return basis, u, len(dofs.all())


def l2_error(basis, u):
    from skfem import Functional

    @Functional
    def err(w):
        return (w["u"] - exact(w.x[0], w.x[1])) ** 2

    return float(np.sqrt(err.assemble(basis, u=basis.interpolate(u))))


@needs_skfem
def test_markers_reach_skfem_as_named_facets():
    mesh = bm.mesh(plate(), size=0.2)
    m, facets = to_skfem(mesh)
    left = m.p[:, m.facets[:, facets["clamped"]]]
    assert np.all(left[0] == 0.0)  # every clamped facet lies on x = 0
    on_left = np.all(m.p[0, m.facets] == 0.0, axis=0) & (m.f2t[1] < 0)
    assert set(np.flatnonzero(on_left)) == set(facets["clamped"])  # and every one on x = 0
    boundary = set(m.boundary_facets())
    assert set(np.concatenate(list(facets.values()))) == boundary


@needs_skfem
def test_p1_error_falls_at_order_two():
    errors, sizes = [], []
    for h in (0.1, 0.05, 0.025):
        mesh = bm.mesh(plate(), size=h)
        basis, u, n_dirichlet = solve_on(mesh)
        assert n_dirichlet > 0
        errors.append(l2_error(basis, u))
        sizes.append(np.sqrt(mesh.domain.area / len(mesh.triangles)))  # mean element size
    rates = np.log(np.array(errors[:-1]) / errors[1:]) / np.log(np.array(sizes[:-1]) / sizes[1:])
    assert np.all(rates > 1.7), (errors, rates)
    assert np.all(rates < 2.5), (errors, rates)


# --- pyvista -----------------------------------------------------------------------


def two_materials():
    """The plate with an interface x = 0.2 from side to side (marker 4; its ends
    split the bottom and top sides) between two regions."""
    from dataclasses import replace

    d = plate()
    wall = bm.Domain.from_pslg(
        loops=[d.points[ix] for ix in d.loops], constraints=[[(0.2, 0.0), (0.2, 2.0)]],
        markers=[NEUMANN, HOLE, 4], regions=[(0.1, 0.1, 10.0, 0.0), (1.5, 0.5, 20.0, 0.0)])
    ends = wall.points[wall.segments]
    marks = np.array(wall.markers)
    marks[(ends[:, 0, 0] == 0.0) & (ends[:, 1, 0] == 0.0)] = DIRICHLET
    return replace(wall, segment_markers=marks, marker_names=d.marker_names)


def test_pyvista_grid_has_the_mesh_points_triangles_and_data():
    pyvista = pytest.importorskip("pyvista", reason="to_pyvista needs pyvista")
    mesh = bm.mesh(plate(), size=0.2)
    extra = np.arange(len(mesh.triangles), dtype=np.float64)
    grid = bm.to_pyvista(mesh, point_data={"x": mesh.points[:, 0]}, cell_data={"id": extra})
    assert np.array_equal(grid.points[:, :2], mesh.points) and not grid.points[:, 2].any()
    assert set(np.unique(grid.celltypes).tolist()) == {int(pyvista.CellType.TRIANGLE)}
    assert np.array_equal(grid.cells_dict[pyvista.CellType.TRIANGLE], mesh.triangles)
    assert np.array_equal(grid.cell_data["id"], extra)
    assert np.array_equal(grid.point_data["x"], mesh.points[:, 0])
    assert np.array_equal(grid.point_data["radius"], mesh.radii)
    assert grid.point_data["boundary"].sum() == mesh.n_boundary
    # VTK's radius ratio is R / (2 r), the inverse of eq. 10
    quality = (grid.cell_quality("radius_ratio") if hasattr(grid, "cell_quality")
               else grid.compute_cell_quality("radius_ratio"))
    vtk = np.asarray(quality.cell_data.get("radius_ratio", quality.cell_data.get("CellQuality")))
    np.testing.assert_allclose(grid.cell_data["radius_ratio"], 1.0 / vtk, rtol=1e-12)


def test_pyvista_regions_follow_the_interface():
    pytest.importorskip("pyvista", reason="to_pyvista needs pyvista")
    mesh = bm.mesh(two_materials(), size=0.1)
    grid = bm.to_pyvista(mesh)
    c = mesh.points[mesh.triangles].mean(axis=1)
    left = c[:, 0] < 0.2  # region 0 (here plus one), the rest region 1
    assert np.all(grid.cell_data["region"][left] == 1)
    assert np.all(grid.cell_data["region"][~left] == 2)


# --- the XDMF pair dolfinx reads ---------------------------------------------------


def xdmf_items(path):
    """{(grid element tag, Name or type): values} of an XDMF file's DataItems,
    inline XML or HDF5 (read with h5py), with the attributes dolfinx reads."""
    import xml.etree.ElementTree as ET

    out = {}
    for parent in ET.parse(path).getroot().iter():
        for item in parent.findall("DataItem"):
            dims = [int(v) for v in item.get("Dimensions").split()]
            if item.get("Format") == "HDF":
                h5py = pytest.importorskip("h5py")
                file, dataset = item.text.strip().split(":")
                with h5py.File(path.parent / file, "r") as h5:
                    values = np.asarray(h5[dataset])
            else:
                values = np.array(item.text.split(), float).reshape(dims)
            key = parent.get("Name") or parent.get("TopologyType") or parent.get("GeometryType")
            out[(parent.tag, key)] = values
    return out


@pytest.mark.heavy
def test_xdmf_pair_carries_regions_and_facet_tags(tmp_path):
    meshio = pytest.importorskip("meshio")
    mesh = bm.mesh(two_materials(), size=0.1)
    cells_path, facets_path = bm.write_xdmf(mesh, tmp_path / "plate.xdmf")
    cells, facets = meshio.read(cells_path), meshio.read(facets_path)
    assert np.array_equal(cells.points[:, :2], mesh.points)
    assert np.array_equal(facets.points, cells.points)  # one numbering, as read_meshtags needs
    assert np.array_equal(cells.cells_dict["triangle"], mesh.triangles)
    c = mesh.points[mesh.triangles].mean(axis=1)
    assert np.array_equal(cells.cell_data["regions"][0], np.where(c[:, 0] < 0.2, 1, 2))
    # the facets: every edge of one triangle (the boundary) and of the interface, once
    T = mesh.triangles
    e = np.sort(np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]]), axis=1)
    edges, count = np.unique(e, axis=0, return_counts=True)
    lines = facets.cells_dict["line"]
    P = mesh.points[lines]
    interface = (P[:, :, 0] == 0.2).all(axis=1)
    assert {tuple(x) for x in np.sort(lines, axis=1)[~interface].tolist()} == {
        tuple(x) for x in edges[count == 1].tolist()}
    assert {tuple(x) for x in np.sort(lines, axis=1)[interface].tolist()} <= {
        tuple(x) for x in edges[count == 2].tolist()}
    assert abs(P[interface][:, :, 1].max() - P[interface][:, :, 1].min() - 2.0) < 1e-12
    # each tag against the side it lies on
    tags = facets.cell_data["markers"][0]
    on_hole = (np.hypot(P[:, :, 0] - 0.5, P[:, :, 1] - 0.5) <= 0.2 + 1e-12).all(axis=1)
    clamped = (P[:, :, 0] == 0.0).all(axis=1)
    expected = np.where(clamped, DIRICHLET, np.where(interface, 4, np.where(on_hole, HOLE,
                                                                              NEUMANN)))
    assert np.array_equal(tags, expected)
    # the XDMF structure dolfinx's XDMFFile.read_mesh / read_meshtags read
    items = xdmf_items(cells_path)
    assert ("Topology", "Triangle") in items and ("Attribute", "regions") in items
    assert np.array_equal(items[("Topology", "Triangle")], mesh.triangles)
    f_items = xdmf_items(facets_path)
    assert np.array_equal(f_items[("Attribute", "markers")], tags)
    assert np.array_equal(f_items[("Topology", "Polyline")], lines)
