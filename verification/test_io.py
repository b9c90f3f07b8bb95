"""bubblemesh.io: .poly files and mesh files written through meshio, read back by meshio."""

from __future__ import annotations

import re

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from bubblemesh.errors import GeometryError
from bubblemesh.io import (
    MeshFileError,
    PolyFormatError,
    check_mesh_path,
    read_poly,
    write_mesh,
    write_poly,
)

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


# --- .poly files that cannot be read: one PolyFormatError naming file and line ----------

TRIANGLE = "3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n3 0\n1 1 2\n2 2 3\n3 3 1\n"
TRIANGLE_LINES = TRIANGLE.splitlines()


def with_line(number: int, text: str) -> str:
    """TRIANGLE with its line ``number`` (1-based) replaced by ``text``."""
    lines = list(TRIANGLE_LINES)
    lines[number - 1] = text
    return "\n".join(lines) + "\n"


def read_error(path, text: str | bytes) -> str:
    if isinstance(text, str):
        text = text.encode()
    path.write_bytes(text)
    with pytest.raises(PolyFormatError) as info:
        read_poly(path)
    message = str(info.value)
    assert "\n" not in message
    return message


def assert_names(message: str, path, line: int, *words: str) -> None:
    assert message.startswith(f"{path} line {line}: "), message
    for word in words:
        assert word in message, (word, message)


def test_poly_format_error_is_a_geometry_error():
    assert issubclass(PolyFormatError, GeometryError)


@pytest.mark.parametrize(
    ("line", "text", "words"),
    [
        (1, "1000000000000 2 0 0", ["1000000000000 vertices", "7 data lines"]),
        (5, "100000000000000 0", ["100000000000000 segments", "3 data lines"]),
        (5, "4 0", ["4 segments", "3 data lines"]),
        (1, "-3 2 0 0", ["negative", "-3"]),
        (5, "-3 0", ["negative", "-3"]),
        (5, "1e14 0", ["'1e14'", "not an integer"]),
        (1, "99999999999999999999999 2 0 0", ["out of range"]),
        (6, "1 1 99999999999999999999999", ["segment 1", "out of range"]),
        (6, "1 -99999999999999999999999 2", ["segment 1", "out of range"]),
        (3, "99999999999999999999999 1 0", ["out of range"]),
        (6, "1 1 4", ["segment 1 names a vertex that does not exist", "vertex 4"]),
        (7, "2 0 3", ["segment 2 names a vertex that does not exist", "vertex 0"]),
        (3, "2 1 zero", ["bad number in a vertex", "'zero'"]),
        (3, "2 1_0 0", ["bad number in a vertex", "'1_0'"]),
        (7, "2 2 three", ["segment 2", "'three'"]),
        (1, "3 x 0 0", ["vertex header", "'x'"]),
        (1, "3 3 0 0", ["dimension 3"]),
        (3, "2 nan 0", ["'nan'", "not a finite number"]),
        (3, "2 0 -inf", ["'-inf'", "not a finite number"]),
        (4, "3 1e999 1", ["'1e999'", "not a finite number"]),
        (3, "2 1e308 0", ["vertex 2 = (1e+308, 0.0)", "outside the exact predicates' range"]),
        (4, "3 0 -1.3e30", ["vertex 3", "outside the exact predicates' range"]),
        (3, "2 1", ["a vertex needs 3 numbers, got 2"]),
        (8, "3 3", ["segment 3 needs 3 numbers, got 2"]),
        (3, "3 1 0", ["vertex 3 where 2 was expected"]),
        (2, "2 0 0", ["numbered from 0 or 1"]),
    ],
)  # fmt: skip
def test_poly_bad_numbers_are_located(tmp_path, line, text, words):
    path = tmp_path / "bad.poly"
    assert_names(read_error(path, with_line(line, text)), path, line, *words)


@pytest.mark.parametrize(
    ("holes", "line", "words"),
    [
        ("1\n1 0.2\n", 10, ["hole 1 needs 3 numbers, got 2"]),
        ("2\n1 0.2 0.2\n", 9, ["a hole was expected", "2 holes"]),
        ("-1\n", 9, ["negative"]),
        ("1\n1 0.2 nan\n", 10, ["hole 1", "'nan'", "not a finite"]),
        ("1\n1 0.2 1e400\n", 10, ["hole 1", "not a finite"]),
        ("1\n1 0.2 0.2x\n", 10, ["hole 1", "'0.2x'"]),
        ("2\n1 0.2 0.2\n2 1e300 0.2\n", 11, ["hole 2 =", "exact predicates' range"]),
    ],
)
def test_poly_bad_hole_sections_are_located(tmp_path, holes, line, words):
    path = tmp_path / "bad.poly"
    assert_names(read_error(path, TRIANGLE + holes), path, line, *words)


def test_every_truncation_reads_or_is_located(tmp_path):
    # cut after each line: the file is complete once the segments are in (holes are optional)
    text = TRIANGLE + "1\n1 0.2 0.2\n"
    lines = text.splitlines(keepends=True)
    path = tmp_path / "cut.poly"
    # kept lines -> the line blamed: the header whose count is short, else the last line
    blamed = {0: 1, 1: 1, 2: 1, 3: 1, 4: 4, 5: 5, 6: 5, 7: 5, 9: 9}
    for kept in range(len(lines)):
        if kept not in blamed:
            path.write_text("".join(lines[:kept]))
            assert len(read_poly(path).segments) == 3
            continue
        message = read_error(path, "".join(lines[:kept]))
        assert_names(message, path, blamed[kept], "the file ends where")
        # and cut inside a line, mid-number: still located (or, for "3 3 1" -> "3 3", a count)
        if kept:
            message = read_error(path, "".join(lines[:kept]) + lines[kept][:2])
            assert message.startswith(f"{path} line "), message


def test_latin1_and_utf8_comments_read_like_plain_ones(tmp_path):
    expected = read_poly(write(tmp_path / "plain.poly", TRIANGLE.encode()))
    for comment in [b"# caf\xe9 \xb0C \x85", "# café – °C".encode(), b"\xef\xbb\xbf#"]:
        text = comment + b"\n" + TRIANGLE.replace("1 1 2\n", "1 1 2 # \xe9\n").encode("latin-1")
        poly = read_poly(write(tmp_path / "c.poly", text))
        np.testing.assert_array_equal(poly.vertices, expected.vertices)
        np.testing.assert_array_equal(poly.segments, expected.segments)


def test_a_stray_byte_in_a_number_is_located(tmp_path):
    path = tmp_path / "bad.poly"
    message = read_error(path, with_line(4, "3 0 1\xe9").encode("latin-1"))
    assert_names(message, path, 4, "bad number in a vertex")


def test_triangle_separators_and_line_ends(tmp_path):
    # Triangle reads commas as blanks and '#' anywhere as the start of a comment
    expected = read_poly(write(tmp_path / "plain.poly", TRIANGLE.encode()))
    variants = [
        TRIANGLE.replace(" ", ","),
        TRIANGLE.replace("\n", "\r\n"),
        TRIANGLE.replace("\n", "\r"),
        TRIANGLE.replace("\n", "  # note\n\n\t\n"),
        "\ufeff" + TRIANGLE,
    ]
    for text in variants:
        poly = read_poly(write(tmp_path / "v.poly", text.encode()))
        np.testing.assert_array_equal(poly.vertices, expected.vertices)
        np.testing.assert_array_equal(poly.segments, expected.segments)


def write(path, data: bytes):
    path.write_bytes(data)
    return path


def test_missing_node_file_is_named(tmp_path):
    path = tmp_path / "t.poly"
    message = read_error(path, "0 2 0 0\n3 0\n1 1 2\n2 2 3\n3 3 1\n")
    assert_names(message, path, 1, str(tmp_path / "t.node"), "cannot read")


def test_node_file_errors_name_the_node_file(tmp_path):
    node = write(tmp_path / "t.node", b"3 2 0 0\n1 0 0\n2 1 0\n3 0 one\n")
    path = tmp_path / "t.poly"
    assert_names(read_error(path, "0 2 0 0\n3 0\n1 1 2\n2 2 3\n3 3 1\n"), node, 4, "'one'")
    write(node, b"0 2 0 0\n")
    assert_names(read_error(path, "0 2 0 0\n3 0\n1 1 2\n2 2 3\n3 3 1\n"), node, 1, "no vertices")


def test_missing_or_unreadable_poly_is_a_poly_format_error(tmp_path):
    for path in [tmp_path / "none.poly", tmp_path]:
        with pytest.raises(PolyFormatError, match=re.escape(f"cannot read {path}")):
            read_poly(path)


# --- output paths: MeshFileError before anything is written ----------------------------


@pytest.mark.parametrize("name", ["out.xyz", "out", "out.vtu.bak"])
def test_unknown_mesh_suffix(tmp_path, name):
    with pytest.raises(MeshFileError, match=re.escape(str(tmp_path / name))):
        check_mesh_path(tmp_path / name)
    with pytest.raises(MeshFileError, match="cannot tell the mesh format"):
        write_mesh(tmp_path / name, POINTS, TRIANGLES)
    assert list(tmp_path.iterdir()) == []


def test_mesh_path_folder_checks(tmp_path):
    with pytest.raises(MeshFileError, match="is a folder"):
        check_mesh_path(tmp_path)
    (tmp_path / "mesh.vtu").mkdir()
    with pytest.raises(MeshFileError, match="is a folder"):
        check_mesh_path(tmp_path / "mesh.vtu")
    with pytest.raises(MeshFileError, match="nodir does not exist"):
        check_mesh_path(tmp_path / "nodir" / "m.vtu")
    with pytest.raises(MeshFileError, match="nodir does not exist"):
        write_mesh(tmp_path / "nodir" / "m.vtu", POINTS, TRIANGLES)
    (tmp_path / "file").write_text("")
    with pytest.raises(MeshFileError, match="file is not a folder"):
        check_mesh_path(tmp_path / "file" / "m.vtu")


def test_mesh_format_follows_meshio_table(tmp_path):
    table = meshio.extension_to_filetypes
    assert check_mesh_path(tmp_path / "m.vtu") == table[".vtu"][0]
    assert check_mesh_path(tmp_path / "m.VTK") == table[".vtk"][0]
    assert check_mesh_path(tmp_path / "m.vol.gz") == table[".vol.gz"][0]
    assert check_mesh_path(tmp_path / "m.msh") == "gmsh22"  # meshio's first pick is ANSYS
    assert check_mesh_path(tmp_path / "m.dat", file_format="vtu") == "vtu"
    assert list(tmp_path.iterdir()) == []  # the check wrote nothing beside the target


@pytest.mark.parametrize("name", ["m.node", "m.ele", "m.f3grid"])
def test_formats_without_triangles_are_refused(tmp_path, name):
    with pytest.raises(MeshFileError, match="no triangles"):
        check_mesh_path(tmp_path / name)


def test_a_failing_meshio_writer_is_reported_before_meshing(tmp_path, monkeypatch):
    import bubblemesh.io

    def broken(*args, **kwargs):
        raise TypeError("cannot unpack")

    monkeypatch.setattr(bubblemesh.io, "write_mesh", broken)
    with pytest.raises(MeshFileError, match=r"m\.vtu: meshio cannot write .*TypeError: cannot"):
        check_mesh_path(tmp_path / "m.vtu")


def test_unknown_explicit_format(tmp_path):
    with pytest.raises(MeshFileError, match="nosuchformat"):
        write_mesh(tmp_path / "m.vtu", POINTS, TRIANGLES, file_format="nosuchformat")


def test_every_format_the_up_front_check_passes_is_written_and_read_back(tmp_path):
    """For each file suffix meshio knows, either check_mesh_path refuses it
    before any meshing, or Mesh.write (triangles, marked boundary lines, point
    and cell data) succeeds and meshio reads the same four triangles back
    (meshio as the independent reader; SVG is a picture, and meshio's own
    CGNS reader cannot read its CGNS writer's files)."""
    import contextlib
    import io
    import warnings

    from bubblemesh._mesh import from_arrays

    points = np.array([[0, 0], [2, 0], [2, 2], [0, 2], [1, 1]], float)
    mesh = from_arrays(points, np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]))

    def corners(p, triangles):  # each triangle as its sorted vertices, in sorted order
        return sorted(tuple(sorted(map(tuple, p[t, :2].tolist()))) for t in triangles)

    want = corners(points, mesh.triangles)
    written = 0
    for suffix in sorted(meshio.extension_to_filetypes):
        path = tmp_path / f"m{suffix}"
        with contextlib.redirect_stderr(io.StringIO()), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # meshio's STL size sniffing
            try:
                check_mesh_path(path)
            except MeshFileError:
                continue
            mesh.write(path)
            written += 1
            if suffix in (".svg", ".cgns"):
                continue
            back = meshio.read(path)
        tri = np.vstack([c.data for c in back.cells if c.type == "triangle"])
        assert corners(np.asarray(back.points, float), tri) == want, suffix
    assert written >= 25  # VTU, VTK, XDMF, Gmsh, OBJ, STL, OFF, PLY, ... with these packages
