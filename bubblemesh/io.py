"""Files in and out: Triangle ``.poly`` boundaries and meshio mesh files.

The paper's generator starts from a refined boundary (§2.1); ``.poly`` is the
common plain-text form of one (Shewchuk's Triangle): a vertex list, a segment
list and hole points.  :func:`read_poly` and :func:`write_poly` only translate
that format; :class:`bubblemesh.Domain` turns the segments into validated
loops.  :func:`write_mesh` hands a finished mesh to meshio (VTU, Gmsh ``.msh``
in the 2.2 format, XDMF, ...), imported lazily since it is needed only here;
:func:`check_mesh_path` tells beforehand whether a path can be written.

Every problem with a file raises a bubblemesh exception: :class:`PolyFormatError`
(a :class:`~bubblemesh.errors.GeometryError`) for a ``.poly``/``.node`` file that
cannot be read, naming the file and line, and :class:`MeshFileError` for an
output path whose format or folder will not do.
"""

from __future__ import annotations

import math
import re
import tempfile
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from bubblemesh.errors import GeometryError
from bubblemesh.predicates import MAX_COORDINATE, out_of_range_message

__all__ = [
    "MeshFileError",
    "PolyFile",
    "PolyFormatError",
    "check_mesh_path",
    "read_poly",
    "write_mesh",
    "write_poly",
]


class PolyFormatError(GeometryError):
    """A ``.poly`` or ``.node`` file that cannot be read; the message names file and line."""


class MeshFileError(ValueError):
    """A mesh file that cannot be read or written: unknown format, missing folder or
    file, meshio failure."""


class PolyFile(NamedTuple):
    """The geometric content of a ``.poly`` file, indices 0-based."""

    vertices: np.ndarray  # (N, 2) float64
    segments: np.ndarray  # (K, 2) int64
    holes: np.ndarray  # (H, 2) float64
    first_index: int  # 0 or 1: how the file numbers its vertices
    segment_markers: np.ndarray | None = None  # (K,) int64 when the file gives them
    regions: np.ndarray | None = None  # (R, 4) x, y, attribute, max_area (-1: none)
    vertex_markers: np.ndarray | None = None  # (N,) int64 when the file gives them


# Numbers as C's strtol/strtod write them (what Triangle reads), nothing else:
# no '1_000', no 'nan', no digits outside ASCII.
_INTEGER = re.compile(r"[+-]?[0-9]+")
_REAL = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_NOT_FINITE = re.compile(r"[+-]?(?:nan|inf|infinity)", re.IGNORECASE)
_MAX_DIGITS = 18  # below 2**63: no count or index of a real file comes near


class _Lines:
    """The data lines of a Triangle file as token lists, with their line numbers.

    As in Triangle, '#' starts a comment anywhere, commas separate like blanks
    and blank lines are skipped.  Bytes are decoded as ASCII with every other
    byte replaced, so a Latin-1 or UTF-8 comment reads and a stray byte in a
    number is a bad number, not a decoding error.
    """

    def __init__(self, path: Path, text: str):
        self.path = path
        self._rows = []
        lines = text.splitlines()
        for number, line in enumerate(lines, start=1):
            tokens = line.split("#", 1)[0].replace(",", " ").split()
            if tokens:
                self._rows.append((number, tokens))
        self._last_line = max(len(lines), 1)
        self._next = 0

    @classmethod
    def read(cls, path: Path, why: str = "") -> _Lines:
        try:
            data = path.read_bytes()
        except OSError as error:
            reason = error.strerror or type(error).__name__
            raise PolyFormatError(f"{why}cannot read {path}: {reason}") from error
        data = data.removeprefix(b"\xef\xbb\xbf")  # a UTF-8 byte-order mark
        return cls(path, data.decode("ascii", errors="replace"))

    def fail(self, number: int, message: str) -> PolyFormatError:
        return PolyFormatError(f"{self.path} line {number}: {message}")

    def at_end(self) -> bool:
        return self._next >= len(self._rows)

    def take(self, what: str, min_tokens: int) -> tuple[int, list[str]]:
        """The next data line, which must hold at least ``min_tokens`` fields."""
        if self.at_end():
            raise self.fail(self._last_line, f"the file ends where {what} was expected")
        number, tokens = self._rows[self._next]
        self._next += 1
        if len(tokens) < min_tokens:
            raise self.fail(number, f"{what} needs {min_tokens} numbers, got {len(tokens)}")
        return number, tokens

    def integer(self, token: str, what: str, number: int) -> int:
        if not _INTEGER.fullmatch(token):
            raise self.fail(number, f"bad number in {what}: {_shown(token)} is not an integer")
        if len(token.lstrip("+-").lstrip("0")) > _MAX_DIGITS:
            raise self.fail(number, f"{what}: {_shown(token)} is out of range")
        return int(token)

    def real(self, token: str, what: str, number: int) -> float:
        if _REAL.fullmatch(token):
            value = float(token)
            if math.isfinite(value):
                return value
        elif not _NOT_FINITE.fullmatch(token):
            raise self.fail(number, f"bad number in {what}: {_shown(token)} is not a number")
        raise self.fail(number, f"{what}: {_shown(token)} is not a finite number")

    def count(self, token: str, items: str, number: int, item: str) -> int:
        """A section's item count, checked before anything is allocated from it:
        each item takes one line, so no more can follow than there are lines left."""
        n = self.integer(token, f"the number of {items}", number)
        if n < 0:
            raise self.fail(number, f"the number of {items} is negative: {n}")
        left = len(self._rows) - self._next
        if n > left:
            raise self.fail(
                number,
                f"the file ends where {item} was expected: {n} {items} announced, "
                f"{left} data line{' follows' if left == 1 else 's follow'}",
            )
        return n


def _shown(token: str) -> str:
    """A token as quoted in a message, cut short."""
    return repr(token if len(token) <= 24 else token[:20] + "...")


def read_poly(path: str | Path) -> PolyFile:
    """Read a Triangle ``.poly`` file: vertices, segments and holes.

    Vertices are numbered from 0 or 1, as the first vertex says, and must be
    consecutive.  A vertex count of 0 reads the vertices from the ``.node``
    file beside it, as Triangle does.  Vertex and segment boundary markers are
    kept when the headers announce them, vertex attributes are skipped; the
    holes and the regional-attributes sections (x y attribute max_area; a
    missing max_area is the attribute, as Triangle reads it, a negative one
    none) may be left out.  Any problem raises
    :class:`PolyFormatError` naming file and line.
    """
    path = Path(path)
    lines = _Lines.read(path)
    number, tokens = lines.take("the vertex header", 1)
    if _check_header(lines, tokens, number) == 0:
        node = path.with_suffix(".node")
        why = f"{path} line {number}: 0 vertices, so they come from {node}, but "
        vertices, first_index, vertex_markers = _read_vertices(_Lines.read(node, why))
    else:
        lines._next -= 1  # the header belongs to the vertex section
        vertices, first_index, vertex_markers = _read_vertices(lines)
    segments, segment_markers = _read_segments(lines, len(vertices), first_index)
    holes = np.empty((0, 2))
    if not lines.at_end():
        number, tokens = lines.take("the hole header", 1)
        n_holes = lines.count(tokens[0], "holes", number, "a hole")
        rows = [_read_point(lines, f"hole {h + first_index}") for h in range(n_holes)]
        holes = np.array([point for _, point in rows], dtype=np.float64).reshape(n_holes, 2)
        _check_range(lines, holes, [number for number, _ in rows], "hole", first_index)
    regions = _read_regions(lines, first_index) if not lines.at_end() else np.empty((0, 4))
    return PolyFile(vertices, segments, holes, first_index, segment_markers, regions,
                    vertex_markers)


def _read_regions(lines: _Lines, first_index: int) -> np.ndarray:
    """The optional regional attributes: (x, y, attribute, max_area) per region."""
    number, tokens = lines.take("the region header", 1)
    n = lines.count(tokens[0], "regions", number, "a region")
    out = np.full((n, 4), -1.0)
    for r in range(n):
        what = f"region {r + first_index}"
        number, tokens = lines.take(what, 3)
        values = [lines.real(token, what, number) for token in tokens[1:5]]
        out[r, : len(values)] = values
        if len(values) < 3:
            out[r, 2] = 0.0
        if len(values) < 4:  # as Triangle reads it: the area bound defaults to the attribute
            out[r, 3] = out[r, 2]
    _check_range(lines, out[:, :2], [number] * n, "region", first_index)
    return out


def _check_header(lines: _Lines, tokens: list[str], number: int) -> int:
    """The vertex header (count, dimension 2, attributes, markers): its first number."""
    header = [lines.integer(token, "the vertex header", number) for token in tokens]
    if len(header) > 1 and header[1] != 2:
        raise lines.fail(number, f"dimension {header[1]}, expected 2")
    return header[0]


def _read_vertices(lines: _Lines) -> tuple[np.ndarray, int, np.ndarray | None]:
    number, tokens = lines.take("the vertex header", 1)
    _check_header(lines, tokens, number)
    header = [lines.integer(token, "the vertex header", number) for token in tokens]
    n_attributes = header[2] if len(header) > 2 else 0
    with_markers = len(header) > 3 and header[3] != 0
    n_vertices = lines.count(tokens[0], "vertices", number, "a vertex")
    if n_vertices == 0:
        raise lines.fail(number, "no vertices")
    vertices = np.empty((n_vertices, 2))
    markers = np.zeros(n_vertices, dtype=np.int64)
    line_of = np.empty(n_vertices, dtype=np.int64)
    first_index = 0
    for v in range(n_vertices):
        number, tokens = lines.take("a vertex", 3)
        line_of[v] = number
        index = lines.integer(tokens[0], "a vertex number", number)
        if v == 0:
            if index not in (0, 1):
                raise lines.fail(number, "vertices must be numbered from 0 or 1")
            first_index = index
        elif index != v + first_index:
            raise lines.fail(
                number,
                f"vertex {index} where {v + first_index} was expected; "
                "vertices must be numbered consecutively",
            )
        vertices[v] = [lines.real(token, "a vertex", number) for token in tokens[1:3]]
        if with_markers and len(tokens) > 3 + n_attributes:
            markers[v] = lines.integer(tokens[3 + n_attributes], "a vertex marker", number)
    _check_range(lines, vertices, line_of, "vertex", first_index)
    return vertices, first_index, markers if with_markers else None


def _check_range(lines: _Lines, points: np.ndarray, line_of, what: str, first_index: int) -> None:
    """No coordinate above the exact predicates' range, where the line is still known:
    such values overflow the loop areas before Domain checks its ranges.  Tiny ones
    are left to Domain, so every file read before still reads."""
    outside = (np.abs(points) > MAX_COORDINATE).any(axis=1)
    if outside.any():
        k = int(np.argmax(outside))
        message = out_of_range_message(points[k])
        raise lines.fail(int(line_of[k]), f"{what} {k + first_index} = {message}")


def _read_segments(lines: _Lines, n_vertices: int, first_index: int
                   ) -> tuple[np.ndarray, np.ndarray | None]:
    number, tokens = lines.take("the segment header", 1)
    n_segments = lines.count(tokens[0], "segments", number, "a segment")
    with_markers = len(tokens) > 1 and lines.integer(tokens[1], "the segment header", number) != 0
    segments = np.empty((n_segments, 2), dtype=np.int64)
    markers = np.zeros(n_segments, dtype=np.int64)
    for s in range(n_segments):
        name = f"segment {s + first_index}"
        number, tokens = lines.take(name, 3)
        ends = [lines.integer(token, name, number) - first_index for token in tokens[1:3]]
        for end in ends:
            if not 0 <= end < n_vertices:
                raise lines.fail(
                    number,
                    f"{name} names a vertex that does not exist: vertex {end + first_index} "
                    f"({n_vertices} vertices numbered from {first_index})",
                )
        segments[s] = ends
        if with_markers and len(tokens) > 3:
            markers[s] = lines.integer(tokens[3], f"{name}'s marker", number)
    return segments, markers if with_markers else None


def _read_point(lines: _Lines, what: str) -> tuple[int, list[float]]:
    number, tokens = lines.take(what, 3)
    return number, [lines.real(token, what, number) for token in tokens[1:3]]


def write_poly(
    path: str | Path,
    vertices: np.ndarray,
    segments: np.ndarray,
    holes: np.ndarray | None = None,
    *,
    vertex_markers: np.ndarray | None = None,
    segment_markers: np.ndarray | None = None,
    regions: np.ndarray | None = None,
) -> None:
    """Write a Triangle ``.poly`` file, vertices numbered from 1, with a
    regions section (x, y, attribute, max_area per row) when ``regions`` has
    rows.

    Coordinates are written with ``repr`` so they read back bit for bit.
    """
    vertices = np.asarray(vertices, dtype=np.float64)
    segments = np.asarray(segments, dtype=np.int64)
    holes = np.empty((0, 2)) if holes is None else np.asarray(holes, dtype=np.float64)
    with_vm = vertex_markers is not None
    with_sm = segment_markers is not None
    out = ["# Triangle .poly file written by bubblemesh"]
    out.append(f"{len(vertices)} 2 0 {int(with_vm)}")
    for v, (x, y) in enumerate(vertices.tolist()):
        marker = f" {int(vertex_markers[v])}" if with_vm else ""  # type: ignore[index]
        out.append(f"{v + 1} {x!r} {y!r}{marker}")
    out.append(f"{len(segments)} {int(with_sm)}")
    for s, (a, b) in enumerate(segments.tolist()):
        marker = f" {int(segment_markers[s])}" if with_sm else ""  # type: ignore[index]
        out.append(f"{s + 1} {a + 1} {b + 1}{marker}")
    out.append(f"{len(holes)}")
    for h, (x, y) in enumerate(holes.tolist()):
        out.append(f"{h + 1} {x!r} {y!r}")
    rows = np.empty((0, 4)) if regions is None else np.asarray(regions, np.float64).reshape(-1, 4)
    if len(rows):
        out.append(f"{len(rows)}")
        out += [f"{r + 1} {x!r} {y!r} {a!r} {m!r}" for r, (x, y, a, m) in enumerate(rows.tolist())]
    Path(path).write_text("\n".join(out) + "\n")


# meshio's first choice for these suffixes is not the one wanted (.msh would be ANSYS)
_FORMAT_BY_SUFFIX = {".msh": "gmsh22", ".xdmf": "xdmf", ".xmf": "xdmf"}
# formats meshio knows but that keep no triangles (it skips them with a warning)
_NO_TRIANGLES = {"tetgen": "tetrahedra", "flac3d": "3-D cells"}
_NO_LINES = {"xdmf", "obj", "stl", "off", "ply", "wkt", "tecplot", "avsucd", "hmf",
             "dolfin-xml"}  # written with the triangles alone: meshio cannot read lines back
_NO_CELL_DATA = {"dolfin-xml"}  # meshio writes numpy 2 scalars there as "np.float64(1.0)"


def _meshio():
    try:
        import meshio
    except ImportError as error:
        raise ImportError("writing meshes needs meshio: pip install meshio") from error
    return meshio


def _gmsh41_entities(n, triangles, tags, edges, marks, cells):
    """Gmsh 4.1 blocks for meshio: the triangles of each region tag and the
    edges of each marker as one entity each (entity tag = its rank + 1 in its
    dimension, physical tag = the region or marker), the cell data split the
    same way (NaN / 0 on lines) and each node's (dimension, entity)."""
    blocks, data = [], {name: [] for name in cells}
    physical, geometrical = [], []
    dim_tags = np.zeros((n, 2), np.int64)
    for kind, dim, cell, tag in (("triangle", 2, triangles, tags), ("line", 1, edges, marks)):
        for rank, value in enumerate(np.unique(tag)):
            pick = tag == value
            blocks.append((kind, cell[pick]))
            physical.append(np.full(int(pick.sum()), value, np.int32))
            geometrical.append(np.full(int(pick.sum()), rank + 1, np.int32))
            dim_tags[cell[pick].ravel()] = (dim, rank + 1)  # a node on a line: the curve's
            for name, (values,) in cells.items():
                values = np.asarray(values)
                data[name].append(values[pick] if kind == "triangle" else np.full(
                    int(pick.sum()), np.nan if values.dtype.kind == "f" else 0, values.dtype))
    data.update({"gmsh:physical": physical, "gmsh:geometrical": geometrical})
    return blocks, data, dim_tags


def read_meshio(path: str | Path, file_format: str | None = None) -> Any:
    """``meshio.read`` without its side effects: a file no reader accepts (meshio
    prints and exits) or a reader's own error is a :class:`MeshFileError`."""
    import contextlib
    import io as _io

    meshio = _meshio()
    if not Path(path).is_file():
        raise MeshFileError(f"{path}: no such file")
    quiet = _io.StringIO()
    try:
        with contextlib.redirect_stdout(quiet), contextlib.redirect_stderr(quiet):
            return meshio.read(path, file_format=file_format)
    except SystemExit:
        raise MeshFileError(f"{path}: meshio cannot read this file") from None
    except Exception as error:  # noqa: BLE001 - every reader raises its own kinds
        raise MeshFileError(f"{path}: meshio cannot read it: {error}") from error


def _mesh_format(path: Path, file_format: str | None) -> str:
    """The meshio format for ``path``: ``file_format``, else from the suffix as meshio
    reads it (compound suffixes such as ``.vol.gz`` included)."""
    meshio = _meshio()
    if file_format:
        return file_format
    if path.suffix.lower() in _FORMAT_BY_SUFFIX:
        return _FORMAT_BY_SUFFIX[path.suffix.lower()]
    table = meshio.extension_to_filetypes
    ending = ""
    for suffix in reversed(path.suffixes):
        ending = (suffix + ending).lower()
        if table.get(ending):
            return table[ending][0]
    known = ", ".join(sorted(table))
    raise MeshFileError(
        f"{path}: cannot tell the mesh format from the suffix {path.suffix or '(none)'!r}; "
        f"use one of {known}"
    )


def check_mesh_path(path: str | Path, file_format: str | None = None) -> str:
    """Check that a triangle mesh can be written to ``path``; return the meshio format.

    Raises :class:`MeshFileError` when the format is unknown or keeps no
    triangles, when ``path`` is a folder or its folder is missing, or when
    meshio fails to write a one-triangle mesh with point and cell data in that
    format (into a temporary folder; some writers need optional packages or
    cannot store cell data).  Meant to run before a long meshing job.
    """
    import contextlib
    import io as text_io
    import os

    path = Path(path)
    if path.is_dir():
        raise MeshFileError(f"{path} is a folder, not a mesh file name")
    file_format = _mesh_format(path, file_format)
    if file_format in _NO_TRIANGLES:
        raise MeshFileError(
            f"{path}: meshio's {file_format} format keeps only {_NO_TRIANGLES[file_format]}, "
            "no triangles"
        )
    folder = path.parent
    if not folder.is_dir():
        missing = "is not a folder" if folder.exists() else "does not exist"
        raise MeshFileError(f"{path}: the folder {folder} {missing}")
    if not os.access(folder, os.W_OK):
        raise MeshFileError(f"{path}: the folder {folder} is not writable")
    with tempfile.TemporaryDirectory() as scratch:
        try:
            with contextlib.redirect_stderr(text_io.StringIO()):  # meshio's own warnings
                write_mesh(  # as Mesh.write does: data, marked boundary lines, a region
                    Path(scratch) / path.name,
                    np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]),
                    np.array([[0, 1, 2]]),
                    point_data={"real": np.zeros(3), "flag": np.zeros(3, dtype=np.int64)},
                    cell_data={"quality": np.ones(1)},
                    file_format=file_format,
                    lines=(np.array([[0, 1], [1, 2], [2, 0]]), np.array([1, 1, 2])),
                    regions=np.ones(1, np.int64),
                    names={"wall": 1},
                )
        except Exception as error:  # any failure of meshio's writer: say it now
            cause = (error.__cause__ if isinstance(error, MeshFileError) else None) or error
            raise MeshFileError(
                f"{path}: meshio cannot write a triangle mesh as {file_format!r}: "
                f"{type(cause).__name__}: {cause}"
            ) from error
    return file_format


def write_mesh(
    path: str | Path,
    points: np.ndarray,
    triangles: np.ndarray,
    point_data: dict[str, np.ndarray] | None = None,
    cell_data: dict[str, np.ndarray] | None = None,
    file_format: str | None = None,
    lines: tuple[np.ndarray, np.ndarray] | None = None,
    regions: np.ndarray | None = None,
    names: dict[str, int] | None = None,
    **meshio_kwargs: Any,
) -> None:
    """Write a triangle mesh with meshio; the format follows the file suffix.

    ``lines`` = (edges (E, 2), markers (E,)) adds the boundary and interface
    edges as a second block of line cells, tagged with their markers (Gmsh
    physical and geometrical tags, cell data ``marker``; 0 for the triangle
    data on lines), ``regions`` the triangles' tags (default 1) and ``names``
    the marker names as physical names.  XDMF keeps the triangles only (one
    cell type per file, as dolfinx reads it; ``bubblemesh.interop.write_xdmf``
    writes the facets beside it), and so do the formats that hold no line
    cells or whose lines meshio cannot read back (OBJ, STL, OFF, PLY, WKT,
    Tecplot, AVS-UCD, HMF, DOLFIN XML; the last without cell data).

    ``file_format="gmsh"`` writes binary Gmsh 4.1 with every cell datum on
    every block (lines get NaN, or 0 for integer data): one surface entity per
    region, one curve entity per marker, so the triangles come in region order.
    ``.msh`` is written as binary Gmsh 2.2 (the most widely read version) and
    XDMF with its data inline as XML (one file, no ``.h5`` beside it); pass
    ``file_format`` (a meshio format name) to choose otherwise.  Points are
    padded to 3-D with z = 0 (VTU and Gmsh store 3-D points).
    ``cell_data`` maps a name to one value per triangle; ``meshio_kwargs`` go
    to ``meshio.write`` (e.g. ``binary=False`` for VTU).  An unknown format, a
    missing folder or a meshio writer error raises :class:`MeshFileError`.
    """
    meshio = _meshio()
    path = Path(path)
    file_format = _mesh_format(path, file_format)
    if not path.parent.is_dir():
        raise MeshFileError(f"{path}: the folder {path.parent} does not exist")
    points = np.asarray(points, dtype=np.float64)
    triangles = np.asarray(triangles, dtype=np.int64)
    points3 = np.column_stack([points, np.zeros(len(points))])
    cells = {name: [np.asarray(values)] for name, values in (cell_data or {}).items()
             if file_format not in _NO_CELL_DATA}
    blocks = [("triangle", triangles)]
    tags = np.ones(len(triangles), np.int32) if regions is None else np.asarray(regions, np.int32)
    if file_format == "gmsh22":
        # Gmsh elements carry physical and geometrical tags (triangles: their region)
        cells.setdefault("gmsh:physical", [tags])
        cells.setdefault("gmsh:geometrical", [tags])
    field_data = {}
    point_data = {name: np.asarray(v) for name, v in (point_data or {}).items()}
    if file_format == "gmsh":
        edges, marks = (np.zeros((0, 2), np.int64), np.zeros(0, np.int32)) if lines is None \
            else (np.asarray(lines[0], np.int64), np.asarray(lines[1], np.int32))
        blocks, cells, point_data["gmsh:dim_tags"] = _gmsh41_entities(
            len(points), triangles, tags, edges, marks, cells)
        field_data = {name: np.array([marker, 1]) for name, marker in (names or {}).items()}
    elif lines is not None and len(lines[0]) and file_format not in _NO_LINES:
        edges, marks = np.asarray(lines[0], np.int64), np.asarray(lines[1], np.int32)
        blocks.append(("line", edges))
        if file_format == "gmsh22":  # meshio's Gmsh 2.2 reader splits other element data wrongly
            cells = {name: v for name, v in cells.items() if name.startswith("gmsh:")}
        for name, values in cells.items():
            values.append(marks if name.startswith("gmsh:") else
                          np.zeros(len(edges), values[0].dtype))
        if file_format != "gmsh22":
            cells["marker"] = [tags, marks]
        field_data = {name: np.array([marker, 1]) for name, marker in (names or {}).items()}
    mesh = meshio.Mesh(
        points3,
        blocks,
        point_data=point_data,
        cell_data=cells,
        field_data=field_data,
    )
    # (Gmsh stays binary: meshio's ASCII writer prints numpy 2 scalars as "np.float64(...)")
    options = {"data_format": "XML"} if file_format == "xdmf" else {}
    try:
        meshio.write(path, mesh, file_format=file_format, **{**options, **meshio_kwargs})
    except (meshio.WriteError, ImportError) as error:  # unknown format, missing optional package
        raise MeshFileError(f"{path}: meshio cannot write {file_format!r}: {error}") from error
    except (TypeError, ValueError, AttributeError, KeyError, IndexError) as error:
        raise MeshFileError(f"{path}: meshio's {file_format!r} writer failed on this mesh: "
                            f"{type(error).__name__}: {error}") from error
