"""The Mesh object: identity equality, per-stage records, meshio round trips,
and meshes from outside (files of other meshers) checked and oriented.

Oracles: a written-and-read bubblemesh mesh must give back the same arrays
bit for bit; a foreign mesh (scipy's Qhull Delaunay, written clockwise) must
come back valid by ``oracles.check_valid`` with the same triangle set and
its boundary edges exactly ``oracles.boundary_edges``."""

from __future__ import annotations

import numpy as np
import oracles as O
import pytest
import strategies as S

import bubblemesh as bm


@pytest.fixture(scope="module")
def optimised():
    # coarse: bm.mesh's polish takes minutes as plain Python (tox -e nojit) on the fine one
    return bm.mesh(bm.Domain.from_loops(list(S.square_with_hole(5, 12).loops)))


def test_equality_is_identity(optimised):
    other = bm.optimize(bm.generate(optimised.domain))
    assert optimised == optimised
    assert (optimised == other) is False
    assert len({optimised: 1, other: 2}) == 2


def test_stage_records_are_set_at_construction(optimised):
    gen, opt = optimised.generation, optimised.optimization
    assert isinstance(gen, bm.GenerationStats) and isinstance(opt, bm.OptimizationStats)
    assert gen.stop == "population" and gen.insertions + getattr(gen, "seeds", 0) + getattr(
        opt, "repair_nodes", 0) == len(optimised.points) - optimised.n_boundary
    # the nodes: boundary, seeds, insertions and the last step's repairs
    assert 1 <= opt.iterations <= 200 and opt.amplification == 1.7
    assert optimised.stats["iterations"] == opt.iterations
    assert optimised.stats["insertions"] == gen.insertions
    with pytest.raises(TypeError):
        optimised.stats["iterations"] = 0  # a read-only view


@pytest.mark.parametrize("suffix", [".vtu", ".msh", ".xdmf"])
def test_read_round_trips_a_written_mesh(optimised, tmp_path, suffix):
    path = tmp_path / f"m{suffix}"
    optimised.write(path, point_data={"id": np.arange(len(optimised.points))})
    back = bm.read(path)
    assert np.array_equal(back.points, optimised.points)
    assert np.array_equal(back.triangles, optimised.triangles)
    assert np.array_equal(back.neighbors, optimised.neighbors)
    assert np.array_equal(back.radii, optimised.radii)
    assert back.n_boundary == optimised.n_boundary
    assert set(map(tuple, back.segments.tolist())) == set(map(tuple, optimised.segments.tolist()))


def test_to_meshio_carries_the_given_data(optimised):
    m = optimised.to_meshio(cell_data={"area": np.ones(len(optimised.triangles))})
    assert np.array_equal(m.points[:, :2], optimised.points) and not m.points[:, 2].any()
    assert np.array_equal(m.cells_dict["triangle"], optimised.triangles)
    assert np.array_equal(m.cell_data["radius_ratio"][0], optimised.quality())
    with pytest.raises(ValueError, match="expected"):
        optimised.to_meshio(cell_data={"short": np.ones(3)})


def test_a_foreign_mesh_is_oriented_and_boundary_first(tmp_path):
    spatial = pytest.importorskip("scipy.spatial")
    rng = np.random.default_rng(7)
    pts = rng.random((60, 2))
    clockwise = spatial.Delaunay(pts).simplices[:, ::-1].copy()
    import meshio

    meshio.write(tmp_path / "q.vtu", meshio.Mesh(pts, [("triangle", clockwise)]))
    back = bm.read(tmp_path / "q.vtu")
    O.check_valid(back.points, back.triangles, back.neighbors)
    # the same triangles, renumbered: map each back to the original node ids
    old_of_new = np.array([np.flatnonzero((pts == p).all(axis=1))[0] for p in back.points])
    assert O.canonical_triangles(old_of_new[back.triangles]) == \
        O.canonical_triangles(clockwise[:, ::-1])
    boundary = {v for e in O.boundary_edges(back.triangles) for v in e}
    assert boundary == set(range(back.n_boundary)), "boundary nodes are not first"
    assert set(map(tuple, back.segments.tolist())) == O.boundary_edges(back.triangles)


@pytest.mark.parametrize("triangles, words", [
    (np.array([[0, 1, 6]]), r"triangle 0 = \(0, 1, 6\) refers to a node out of range 0\.\.5"),
    (np.array([[0, 1, 2], [0, 1, 5]]), "same way"),  # overlapping
    (np.array([[0, 1, 2], [1, 0, 3], [0, 1, 3]]), "more than two"),
    (np.array([[0, 1, 4]]), "zero area"),
    (np.array([[0.0, 1.0, 2.0]]), "integers"),
])
def test_inconsistent_triangles_are_refused(triangles, words):
    from bubblemesh._mesh import from_arrays

    pts = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.2, -1.0], [2.0, 0.0],
                    [1.0, 1.0]])
    with pytest.raises(bm.GeometryError, match=words):
        from_arrays(pts, triangles)


def test_write_passes_meshio_options(optimised, tmp_path):
    path = tmp_path / "ascii.vtu"
    optimised.write(path, binary=False)
    assert b"<DataArray" in path.read_bytes() and b'format="ascii"' in path.read_bytes()
    assert np.array_equal(bm.read(path).triangles, optimised.triangles)


# --- Gmsh .msh: the triangles' cell data beside the line cells ---------------------


@pytest.fixture(scope="module")
def marked():
    """Two regions split by a wall, a crack, named markers."""
    square = np.array([(0, 0), (8, 0), (8, 8), (0, 8)], float)
    d = bm.Domain.from_pslg(loops=[square], constraints=[[(1, 4), (3, 4)], [(4, 0), (4, 8)]],
                            markers=[7, 9, 11], names={"wall": 7, "crack": 9},
                            regions=[(1, 1, 5, 0), (7, 7, 6, 0)])
    return bm.mesh(d, size=2.0)


def corner_key(points, triangle):
    return tuple(sorted(map(tuple, np.asarray(points)[triangle, :2].tolist())))


def test_msh_keeps_the_triangle_data_beside_the_lines(marked, tmp_path):
    meshio = pytest.importorskip("meshio")
    path = tmp_path / "m.msh"
    ratio = marked.quality()
    marked.write(path, cell_data={"id": np.arange(len(marked.triangles))})
    m = meshio.read(path)
    kinds = {c.type for c in m.cells}
    assert kinds == {"triangle", "line"}
    seen = []
    for block, rr, ids in zip(m.cells, m.cell_data["radius_ratio"], m.cell_data["id"]):
        if block.type == "line":
            assert np.isnan(rr).all() and not ids.any()  # the fill value on lines
            continue
        ids = ids.astype(np.int64)
        assert np.array_equal(rr, ratio[ids])  # bit for bit, matched by the id column
        for row, t in zip(block.data, ids):  # ... and the id names the same corners
            assert corner_key(m.points, row) == corner_key(marked.points, marked.triangles[t])
        seen.extend(ids.tolist())
    assert sorted(seen) == list(range(len(marked.triangles)))
    back = bm.read(path)  # regions and markers survive too
    mine = {corner_key(marked.points, t): r for t, r in zip(marked.triangles,
                                                             marked.region_ids())}
    assert all(mine[corner_key(back.points, t)] == r
               for t, r in zip(back.triangles, back.region_ids()))
    assert set(back.boundary_edges()[1].tolist()) == {7, 9, 11}
    assert dict(back.marker_names) == {"wall": 7, "crack": 9}


def test_gmsh_reads_the_triangle_data_as_a_view(marked, tmp_path):
    gmsh = pytest.importorskip("gmsh")
    path = tmp_path / "m.msh"
    marked.write(path)
    ratio = {corner_key(marked.points, t): q for t, q in zip(marked.triangles, marked.quality())}
    gmsh.initialize(["-v", "0"])
    try:
        gmsh.open(str(path))
        names = {gmsh.view.option.getString(v, "Name"): v for v in gmsh.view.getTags()}
        kind, tags, data, _, _ = gmsh.view.getModelData(names["radius_ratio"], 0)
        value = dict(zip(tags.tolist(), np.asarray(data).ravel().tolist()))
        node_tags, coords, _ = gmsh.model.mesh.getNodes()
        xy = dict(zip(node_tags.tolist(), coords.reshape(-1, 3)[:, :2].tolist()))
        tri_tags, tri_nodes = gmsh.model.mesh.getElementsByType(2)
        line_tags, _ = gmsh.model.mesh.getElementsByType(1)
        groups = {tag: gmsh.model.getPhysicalName(dim, tag)
                  for dim, tag in gmsh.model.getPhysicalGroups(1)}
    finally:
        gmsh.finalize()
    assert kind == "ElementData" and groups == {7: "wall", 9: "crack", 11: ""}
    assert len(tri_tags) == len(marked.triangles)
    for tag, nodes in zip(tri_tags.tolist(), tri_nodes.reshape(-1, 3).tolist()):
        assert value[tag] == ratio[tuple(sorted(tuple(xy[v]) for v in nodes))]
    assert all(np.isnan(value[tag]) for tag in line_tags.tolist())


def test_gmsh22_is_still_written_on_request(marked, tmp_path):
    meshio = pytest.importorskip("meshio")
    marked.write(tmp_path / "m.msh", file_format="gmsh22")
    assert (tmp_path / "m.msh").read_bytes().startswith(b"$MeshFormat\n2.2")
    m = meshio.read(tmp_path / "m.msh")
    assert {c.type for c in m.cells} == {"triangle", "line"}
