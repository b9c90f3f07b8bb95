"""Files in and out: Triangle ``.poly`` boundaries and meshio mesh files.

The paper's generator starts from a refined boundary (§2.1); ``.poly`` is the
common plain-text form of one (Shewchuk's Triangle): a vertex list, a segment
list and hole points.  :func:`read_poly` and :func:`write_poly` only translate
that format; :class:`bubblemesh.Domain` turns the segments into validated
loops.  :func:`write_mesh` hands a finished mesh to meshio (VTU, Gmsh ``.msh``
in the 2.2 format, XDMF, ...), imported lazily since it is needed only here.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from bubblemesh.errors import GeometryError

__all__ = ["PolyFile", "read_poly", "write_poly", "write_mesh"]


class PolyFile(NamedTuple):
    """The geometric content of a ``.poly`` file, indices 0-based."""

    vertices: np.ndarray  # (N, 2) float64
    segments: np.ndarray  # (K, 2) int64
    holes: np.ndarray  # (H, 2) float64
    first_index: int  # 0 or 1: how the file numbers its vertices


class _Lines:
    """Non-empty lines of a Triangle file as token lists, comments ('#') removed."""

    def __init__(self, path: Path):
        self.path = path
        self._rows = []
        for number, line in enumerate(path.read_text().splitlines(), start=1):
            tokens = line.split("#", 1)[0].split()
            if tokens:
                self._rows.append((number, tokens))
        self._next = 0

    def at_end(self) -> bool:
        return self._next >= len(self._rows)

    def take(self, what: str, min_tokens: int) -> tuple[int, list[str]]:
        if self.at_end():
            raise GeometryError(f"{self.path}: file ends where {what} was expected")
        number, tokens = self._rows[self._next]
        self._next += 1
        if len(tokens) < min_tokens:
            raise GeometryError(
                f"{self.path} line {number}: {what} needs {min_tokens} numbers, got {len(tokens)}"
            )
        return number, tokens

    def numbers(self, what: str, tokens: list[str], number: int, kind=float) -> list:
        try:
            return [kind(token) for token in tokens]
        except ValueError:
            raise GeometryError(f"{self.path} line {number}: bad number in {what}") from None


def read_poly(path: str | Path) -> PolyFile:
    """Read a Triangle ``.poly`` file: vertices, segments and holes.

    Vertices are numbered from 0 or 1, as the first vertex says, and must be
    consecutive.  A vertex count of 0 reads the vertices from the ``.node``
    file beside it, as Triangle does.  Attributes, boundary markers and the
    optional regional-attributes section are ignored.
    """
    path = Path(path)
    lines = _Lines(path)
    number, tokens = lines.take("the vertex header", 1)
    (n_vertices,) = lines.numbers("the vertex header", tokens[:1], number, int)
    if n_vertices == 0:
        vertices, first_index = _read_vertices(_Lines(path.with_suffix(".node")))
    else:
        lines._next -= 1  # the header belongs to the vertex section
        vertices, first_index = _read_vertices(lines)

    number, tokens = lines.take("the segment header", 1)
    (n_segments,) = lines.numbers("the segment header", tokens[:1], number, int)
    segments = np.empty((n_segments, 2), dtype=np.int64)
    for s in range(n_segments):
        number, tokens = lines.take(f"segment {s + first_index}", 3)
        segments[s] = lines.numbers("a segment", tokens[1:3], number, int)
    segments -= first_index
    outside = (segments < 0) | (segments >= len(vertices))
    if outside.any():
        s = int(np.argmax(outside.any(axis=1)))
        raise GeometryError(
            f"{path}: segment {s + first_index} names a vertex that does not exist "
            f"({len(vertices)} vertices numbered from {first_index})"
        )

    holes = np.empty((0, 2))
    if not lines.at_end():
        number, tokens = lines.take("the hole header", 1)
        (n_holes,) = lines.numbers("the hole header", tokens[:1], number, int)
        holes = np.empty((n_holes, 2))
        for h in range(n_holes):
            number, tokens = lines.take(f"hole {h + first_index}", 3)
            holes[h] = lines.numbers("a hole", tokens[1:3], number)
    return PolyFile(vertices, segments, holes, first_index)


def _read_vertices(lines: _Lines) -> tuple[np.ndarray, int]:
    number, tokens = lines.take("the vertex header", 1)
    header = lines.numbers("the vertex header", tokens, number, int)
    n_vertices, dimension = header[0], header[1] if len(header) > 1 else 2
    if dimension != 2:
        raise GeometryError(f"{lines.path} line {number}: dimension {dimension}, expected 2")
    if n_vertices < 1:
        raise GeometryError(f"{lines.path} line {number}: no vertices")
    vertices = np.empty((n_vertices, 2))
    first_index = 0
    for v in range(n_vertices):
        number, tokens = lines.take("a vertex", 3)
        (index,) = lines.numbers("a vertex number", tokens[:1], number, int)
        if v == 0:
            if index not in (0, 1):
                raise GeometryError(
                    f"{lines.path} line {number}: vertices must be numbered from 0 or 1"
                )
            first_index = index
        elif index != v + first_index:
            raise GeometryError(
                f"{lines.path} line {number}: vertex {index} where {v + first_index} was "
                "expected; vertices must be numbered consecutively"
            )
        vertices[v] = lines.numbers("a vertex", tokens[1:3], number)
    return vertices, first_index


def write_poly(
    path: str | Path,
    vertices: np.ndarray,
    segments: np.ndarray,
    holes: np.ndarray | None = None,
    *,
    vertex_markers: np.ndarray | None = None,
    segment_markers: np.ndarray | None = None,
) -> None:
    """Write a Triangle ``.poly`` file, vertices numbered from 1.

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
    Path(path).write_text("\n".join(out) + "\n")


_FORMAT_BY_SUFFIX = {".msh": "gmsh22", ".xdmf": "xdmf", ".xmf": "xdmf"}


def write_mesh(
    path: str | Path,
    points: np.ndarray,
    triangles: np.ndarray,
    point_data: dict[str, np.ndarray] | None = None,
    cell_data: dict[str, np.ndarray] | None = None,
    file_format: str | None = None,
    **meshio_kwargs: Any,
) -> None:
    """Write a triangle mesh with meshio; the format follows the file suffix.

    ``.msh`` is written as binary Gmsh 2.2 (the most widely read version) and
    XDMF with its data inline as XML (one file, no ``.h5`` beside it); pass
    ``file_format`` (a meshio format name) to choose otherwise.  Points are
    padded to 3-D with z = 0 (VTU and Gmsh store 3-D points).
    ``cell_data`` maps a name to one value per triangle; ``meshio_kwargs`` go
    to ``meshio.write`` (e.g. ``binary=False`` for Gmsh).
    """
    try:
        import meshio
    except ImportError as error:
        raise ImportError("write_mesh needs meshio: pip install meshio") from error
    points = np.asarray(points, dtype=np.float64)
    triangles = np.asarray(triangles, dtype=np.int64)
    points3 = np.column_stack([points, np.zeros(len(points))])
    cells = {name: [np.asarray(values)] for name, values in (cell_data or {}).items()}
    file_format = file_format or _FORMAT_BY_SUFFIX.get(Path(path).suffix.lower())
    if file_format == "gmsh22":
        # Gmsh elements carry physical and geometrical tags; tag every triangle 1.
        ones = np.ones(len(triangles), dtype=np.int32)
        cells.setdefault("gmsh:physical", [ones])
        cells.setdefault("gmsh:geometrical", [ones])
    mesh = meshio.Mesh(
        points3,
        [("triangle", triangles)],
        point_data={name: np.asarray(v) for name, v in (point_data or {}).items()},
        cell_data=cells,
    )
    # (Gmsh stays binary: meshio's ASCII writer prints numpy 2 scalars as "np.float64(...)")
    options = {"data_format": "XML"} if file_format == "xdmf" else {}
    meshio.write(path, mesh, file_format=file_format, **{**options, **meshio_kwargs})
