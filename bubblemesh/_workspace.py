"""The growable arrays of one §2 run, laid out as cache-line records.

Each insertion visits a few triangles and nodes at random places of arrays far
larger than the cache, so a triangle's vertex and neighbour ids, constraint
flags, cavity stamp, density and element bubble share one cache line, and a
node's position, radius and ids half of one; the kernels see them as strided
views.
"""

import numpy as np

from ._queue import heap_arrays
from .errors import MeshingError

INT32_MAX = int(np.iinfo(np.int32).max)  # above it, ids are int64


# Records: per triangle, every field the insertion loop touches shares one
# cache line (64 bytes with int32 ids); per node, its position, radius and the
# two id fields share half a line.  (name, dtype, byte offset, width).
_TRIANGLE_FIELDS = {
    np.int32: (64, [("tri", "i4", 0, 3), ("nbr", "i4", 12, 3), ("con", "i4", 24, 3),
                    ("mark", "i4", 36, 1), ("density", "f8", 40, 1), ("r_e", "f8", 48, 1)]),
    np.int64: (128, [("tri", "i8", 0, 3), ("nbr", "i8", 24, 3), ("con", "i8", 48, 3),
                     ("mark", "i8", 72, 1), ("density", "f8", 80, 1), ("r_e", "f8", 88, 1)]),
}
_NODE_FIELDS = {
    np.int32: (32, [("P", "f8", 0, 2), ("R", "f8", 16, 1), ("vt", "i4", 24, 1),
                    ("vstart", "i4", 28, 1)]),
    np.int64: (64, [("P", "f8", 0, 2), ("R", "f8", 16, 1), ("vt", "i8", 24, 1),
                    ("vstart", "i8", 32, 1)]),
}
_UNSET = {"nbr": -1, "vt": -1, "vstart": -1}  # initial value if not 0


def _records(rows: int, record_bytes: int, fields: list) -> dict[str, np.ndarray]:
    """Zeroed, cache-line-aligned records; returns {name: strided view}."""
    buf = np.zeros(rows * record_bytes + 64, np.uint8)
    skip = -buf.ctypes.data % 64
    table = buf[skip:skip + rows * record_bytes].reshape(rows, record_bytes)
    views = {}
    for name, dtype, offset, width in fields:
        words = table.view(dtype)
        col = offset // words.itemsize
        views[name] = words[:, col:col + width] if width > 1 else words[:, col]
        if name in _UNSET:
            views[name][:] = _UNSET[name]
    return views


class Workspace:
    """The growable arrays of one generation run (capacity doubles on demand).

    The loop waits on memory: each insertion visits a few triangles and nodes
    at random places of arrays far larger than the cache.  So a triangle's
    vertex and neighbour ids, constraint flags, cavity stamp, density and
    element bubble are one record (one cache line), and a node's position,
    radius and ids another; the kernels see them as strided views.  Ids and
    stamps are int32 (widened to int64 in the returned mesh); runs that could
    pass 2**31 - 1 use int64 records."""

    # strided views into the records, set by _allocate
    P: np.ndarray
    R: np.ndarray
    vt: np.ndarray
    vstart: np.ndarray
    tri: np.ndarray
    nbr: np.ndarray
    con: np.ndarray
    mark: np.ndarray
    density: np.ndarray
    r_e: np.ndarray

    def __init__(self, points: np.ndarray, radii: np.ndarray, tri: np.ndarray, nbr: np.ndarray,
                 n_cap: int, t_cap: int, wide: bool = False) -> None:
        self.index = np.int64 if wide else np.int32
        self._allocate(n_cap, t_cap)
        n0, m0 = len(points), len(tri)
        self.P[:n0] = points
        self.R[:n0] = radii
        self.tri[:m0] = tri
        self.nbr[:m0] = nbr
        self.keys, self.ids = heap_arrays(2 * t_cap, self.index)

    def _allocate(self, n_cap: int, t_cap: int) -> None:
        nodes = _records(n_cap + 1, *_NODE_FIELDS[self.index])  # + the ghost's vstart slot
        nodes["P"], nodes["R"], nodes["vt"] = (nodes[k][:n_cap] for k in ("P", "R", "vt"))
        triangles = _records(t_cap, *_TRIANGLE_FIELDS[self.index])
        for name, view in {**nodes, **triangles}.items():
            setattr(self, name, view)
        self.cav = np.zeros(t_cap, self.index)
        self.bnd = np.zeros((t_cap + 2, 4), self.index)
        self.newt = np.zeros(t_cap + 2, self.index)

    def grow(self) -> None:
        """Double every capacity, keeping contents (heap entries included)."""
        if self.index == np.int32 and not fits_int32(2 * len(self.tri)):
            raise MeshingError("generation: more triangles than the id type holds")
        names = ("P", "R", "vt", "tri", "nbr", "con", "r_e", "density")
        old = {name: getattr(self, name) for name in names}
        self._allocate(2 * len(self.P), 2 * len(self.tri))
        for name in names:
            getattr(self, name)[: len(old[name])] = old[name]
        keys, ids = heap_arrays(2 * len(self.keys), self.index)
        keys[: len(self.keys)] = self.keys
        ids[: len(self.ids)] = self.ids
        self.keys, self.ids = keys, ids

    def kernel_args(self) -> tuple[np.ndarray, ...]:
        return (self.P, self.R, self.tri, self.nbr, self.con, self.vt, self.r_e, self.density,
                self.keys, self.ids)


def fits_int32(t_cap):
    """Ids, cavity stamps (one per insertion) and heap rows (2 t_cap) all stay
    below 4 t_cap."""
    return 4 * t_cap <= INT32_MAX
