"""Delaunay and constrained Delaunay triangulation of point sets (paper §2.1
initial boundary mesh and §3.5 re-triangulation, the steps the paper
delegates to MATLAB's ``delaunayTriangulation`` and ``isInterior``).

The kernels live in ``_cavity`` (insertion), ``_delaunay`` (incremental
construction), ``_cdt`` (segment recovery, parity, compaction) and
``_ordering`` (Hilbert order); this module checks the input and turns kernel
statuses into exceptions.
"""

import numpy as np
from numpy.typing import ArrayLike, DTypeLike

from ._cdt import BOUNDARY, INTERIOR, compact, interior_mask, recover_segments
from ._delaunay import delaunay_kernel
from ._ordering import hilbert_order
from ._status import ERR_SEGMENTS_CROSS, ERR_STACK, ERR_VERTEX_ON_SEGMENT, OK, raise_for
from .errors import GeometryError
from .predicates import orient2d, out_of_range, out_of_range_message

SMALL_SEGMENTS = 64  # up to this many segments are matched pairwise, not sorted

__all__ = ["constrained_delaunay", "delaunay"]


def _writable(array: ArrayLike, dtype: DTypeLike) -> np.ndarray:
    """A contiguous, writable array: numba compiles a separate copy of every
    kernel for read-only arrays (a frozen Mesh's), which doubled the cold
    compile time of the triangulation."""
    out = np.ascontiguousarray(array, dtype=dtype)
    return out if out.flags.writeable else out.copy()


def _as_points(points: ArrayLike) -> np.ndarray:
    P = _writable(points, np.float64)
    if P.ndim != 2 or P.shape[1] != 2:
        raise GeometryError(f"points must be an (N, 2) array, got shape {P.shape}")
    bad = out_of_range(P)
    if bad.any():
        k = int(np.argmax(bad))
        raise GeometryError(f"point {k} = {out_of_range_message(P[k])}")
    return P


def ghost_delaunay(points: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                               int, np.ndarray]:
    """Delaunay triangulation with ghost triangles: (tri, nbr, con, vt, ntri,
    dup_of), arrays sized to capacity with the first ntri rows in use."""
    P = _as_points(points)
    n = P.shape[0]
    if n < 3:
        raise GeometryError(f"need at least 3 points, got {n}")
    cap = 2 * n + 8
    tri = np.empty((cap, 3), np.int64)
    nbr = np.empty((cap, 3), np.int64)
    con = np.zeros((cap, 3), np.uint8)
    vt = np.full(n, -1, np.int64)
    dup_of = np.full(n, -1, np.int64)
    status, ntri, bad = delaunay_kernel(P, hilbert_order(P), tri, nbr, con, vt, dup_of)
    if status != OK:
        raise_for(status, "delaunay", f" (point {bad})" if bad >= 0 else "")
    return tri, nbr, con, vt, ntri, dup_of


def delaunay(points: ArrayLike) -> np.ndarray:
    """Unconstrained Delaunay triangulation of a point set, (M, 3) int64 CCW.

    Exact duplicates are left out of every triangle (as Qhull does).  Raises
    GeometryError for fewer than 3 points or when all points are collinear."""
    tri, _, _, _, ntri, _ = ghost_delaunay(points)
    real = (tri[:ntri] >= 0).all(axis=1)
    return np.ascontiguousarray(tri[:ntri][real])


def _crossing_at(P: np.ndarray, S: np.ndarray, s: int, v: int) -> str:
    """The segment at vertex ``v`` that segment ``s`` properly crosses (the
    kernel stopped at a constrained edge from ``v``), by exact orientation."""
    a, b = S[s]
    for k in np.flatnonzero((S == v).any(axis=1)):
        x, y = S[k]
        sides = [orient2d(*P[a], *P[b], *P[w]) for w in (x, y)]
        other = [orient2d(*P[x], *P[y], *P[w]) for w in (a, b)]
        if sides[0] * sides[1] < 0 and other[0] * other[1] < 0:
            return f"{int(k)} = {(int(x), int(y))}"
    return f"at vertex {v}"


def constrained_delaunay(points: ArrayLike, segments: ArrayLike
                         ) -> tuple[np.ndarray, np.ndarray]:
    """Constrained Delaunay triangulation of the region enclosed by ``segments``
    (paper §2.1 and §3.5): triangles outside the outer loop and inside holes are
    removed by the parity of segments crossed from infinity.

    A segment given in both directions, (a, b) and (b, a), is an interior
    constraint (a material interface, a crack): an edge of the result with the
    domain on both sides, not counted by the parity, and -1 in the neighbours
    across it, so every walk and cavity stops there as at the boundary.

    Returns (triangles (M,3) int64 CCW, neighbors (M,3) int64, -1 across the
    domain boundary and the interior constraints)."""
    P = _as_points(points)
    S = _writable(segments, np.int64).reshape(-1, 2)
    tri, nbr, con, ntri = ghost_constrained(P, S, segment_flags(S))
    keep = interior_mask(tri, nbr, con, ntri)
    return compact(tri[:ntri], nbr[:ntri], keep, con[:ntri])


def ghost_constrained(P: np.ndarray, S: np.ndarray, flags: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """The constrained triangulation with ghosts, before any removal: (tri, nbr,
    con, ntri), segment s's edge flagged ``flags[s]``; GeometryError naming
    the segments at fault."""
    if S.size and (S.min() < 0 or S.max() >= P.shape[0]):
        raise GeometryError("a segment refers to a point index out of range")
    # Stacks for a few thousand crossed edges per segment; a recovery that needs
    # more reruns the whole (deterministic) triangulation with 4x the room.
    capacity = min(4 * len(P) + 64, 1 << 16)
    for _ in range(8):
        tri, nbr, con, vt, ntri, dup_of = ghost_delaunay(P)
        dups = np.flatnonzero(dup_of >= 0)
        if dups.size:
            k = int(dups[0])
            raise GeometryError(f"point {k} duplicates point {int(dup_of[k])}")
        status, s, v = recover_segments(P, tri, nbr, con, vt, ntri, S, flags, capacity)
        if status != ERR_STACK or capacity >= 4 * len(P) + 64:
            break
        capacity *= 4
    if status != OK:
        where = f" (segment {s} = {tuple(int(x) for x in S[s])}"
        if status == ERR_VERTEX_ON_SEGMENT:
            where += f", vertex {v})"
        elif status == ERR_SEGMENTS_CROSS:
            where += f" and segment {_crossing_at(P, S, s, v)})"
        else:
            where += ")"
        raise_for(status, "constrained delaunay", where)
    return tri, nbr, con, ntri


def segment_flags(segments: np.ndarray) -> np.ndarray:
    """Per segment: INTERIOR if its reverse is also a segment, else BOUNDARY."""
    S = np.asarray(segments, dtype=np.int64).reshape(-1, 2)
    flags = np.full(len(S), BOUNDARY, np.uint8)
    if len(S):
        n = int(S.max()) + 1
        forward, backward = S[:, 0] * n + S[:, 1], S[:, 1] * n + S[:, 0]
        if len(S) <= SMALL_SEGMENTS:  # a patch's few: np.isin's sort costs more
            reversed_too = (forward[:, None] == backward[None, :]).any(axis=1)
        else:
            reversed_too = np.isin(forward, backward)
        flags[reversed_too] = INTERIOR
    return flags
