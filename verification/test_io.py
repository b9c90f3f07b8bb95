"""bubblemesh.io: .poly files and mesh files written through meshio, read back by meshio."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from bubblemesh.io import read_poly, write_mesh, write_poly

meshio = pytest.importorskip("meshio")

# two triangles of the unit square, counter-clockwise, with data on both
POINTS = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 1e-300]])
TRIANGLES = np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4]])
RADIUS = np.array([0.1, 0.2, 0.3, 0.4, 1.0 / 3.0])
RATIO = np.array([0.25, 0.5, 0.875])


@pytest.mark.parametrize("suffix", [".vtu", ".msh", ".xdmf"])
def test_write_mesh_round_trip(tmp_path, suffix):
    path = tmp_path / f"mesh{suffix}"
    write_mesh(
        path, POINTS, TRIANGLES, point_data={"radius": RADIUS}, cell_data={"radius_ratio": RATIO}
    )
    mesh = meshio.read(path)
    np.testing.assert_array_equal(mesh.points[:, :2], POINTS)
    assert not mesh.points[:, 2:].any()
    assert [block.type for block in mesh.cells] == ["triangle"]
    np.testing.assert_array_equal(mesh.cells[0].data, TRIANGLES)
    np.testing.assert_array_equal(mesh.point_data["radius"], RADIUS)
    np.testing.assert_array_equal(mesh.cell_data["radius_ratio"][0], RATIO)


def test_msh_is_gmsh_22(tmp_path):
    path = tmp_path / "mesh.msh"
    write_mesh(path, POINTS, TRIANGLES)
    assert path.read_bytes().startswith(b"$MeshFormat\n2.2 1 8\n")  # version 2.2, binary


def test_xdmf_is_one_self_contained_file(tmp_path):
    write_mesh(tmp_path / "mesh.xdmf", POINTS, TRIANGLES)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mesh.xdmf"]


def test_explicit_format_overrides_the_suffix(tmp_path):
    path = tmp_path / "mesh.dat"
    write_mesh(path, POINTS, TRIANGLES, file_format="vtu")
    mesh = meshio.read(path, file_format="vtu")
    np.testing.assert_array_equal(mesh.cells[0].data, TRIANGLES)


finite = st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False, allow_subnormal=False)


@given(arrays(np.float64, st.tuples(st.integers(3, 20), st.just(2)), elements=finite), st.data())
def test_poly_round_trip_is_bit_exact(tmp_path_factory, vertices, data):
    n = len(vertices)
    segments = np.column_stack([np.arange(n), np.roll(np.arange(n), -1)])
    holes = data.draw(arrays(np.float64, st.tuples(st.integers(0, 3), st.just(2)), elements=finite))
    path = tmp_path_factory.mktemp("poly") / "p.poly"
    write_poly(path, vertices, segments, holes)
    poly = read_poly(path)
    np.testing.assert_array_equal(poly.vertices, vertices)
    np.testing.assert_array_equal(poly.segments, segments)
    np.testing.assert_array_equal(poly.holes, holes.reshape(-1, 2))
    assert poly.first_index == 1


def test_read_poly_without_holes_section(tmp_path):
    path = tmp_path / "p.poly"
    path.write_text("3 2 0 0\n0 0 0\n1 1 0\n2 0 1\n3 0\n0 0 1\n1 1 2\n2 2 0\n")
    poly = read_poly(path)
    assert poly.first_index == 0 and poly.holes.shape == (0, 2)
    np.testing.assert_array_equal(poly.segments, [[0, 1], [1, 2], [2, 0]])


@pytest.mark.peers
def test_msh_opens_in_gmsh(tmp_path):
    gmsh = pytest.importorskip("gmsh")
    path = tmp_path / "mesh.msh"
    write_mesh(path, POINTS, TRIANGLES)
    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(path))
        tags, coords, _ = gmsh.model.mesh.getNodes()
        element_types, _, element_nodes = gmsh.model.mesh.getElements(2)
    finally:
        gmsh.finalize()
    np.testing.assert_array_equal(coords.reshape(-1, 3)[np.argsort(tags), :2], POINTS)
    assert list(element_types) == [2]  # 3-node triangles
    np.testing.assert_array_equal(element_nodes[0].reshape(-1, 3) - 1, TRIANGLES)
