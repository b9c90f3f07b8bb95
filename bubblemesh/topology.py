"""Adjacency of a triangle list: neighbours, boundary edges, and the checks a
mesh from outside (a file, a user's arrays) must pass before a kernel reads
it.  Not in the paper: §2 and §3 build these arrays themselves."""

from __future__ import annotations

import numpy as np
from numba import njit

from .errors import GeometryError
from .predicates import orient2d

__all__ = ["boundary_first", "check_mesh", "neighbors_of", "oriented_neighbors"]


@njit(cache=True)
def _orientations(P: np.ndarray, T: np.ndarray) -> np.ndarray:
    out = np.empty(T.shape[0], np.int8)
    for t in range(T.shape[0]):
        a, b, c = T[t, 0], T[t, 1], T[t, 2]
        o = orient2d(P[a, 0], P[a, 1], P[b, 0], P[b, 1], P[c, 0], P[c, 1])
        out[t] = 1 if o > 0.0 else (-1 if o < 0.0 else 0)
    return out


def _as_triangles(triangles: np.ndarray, n_points: int) -> np.ndarray:
    T = np.asarray(triangles)
    if T.ndim != 2 or T.shape[1] != 3:
        raise GeometryError(f"triangles must be an (M, 3) array, got shape {T.shape}")
    if T.dtype.kind not in "iu":
        raise GeometryError(f"triangles must hold integers, got dtype {T.dtype}")
    T = np.ascontiguousarray(T, dtype=np.int64)
    if T.size and (T.min() < 0 or T.max() >= n_points):
        t = int(np.flatnonzero(((T < 0) | (T >= n_points)).any(axis=1))[0])
        raise GeometryError(f"triangle {t} = {tuple(T[t].tolist())} refers to a node out of range "
                            f"0..{n_points - 1}")
    return T


def neighbors_of(triangles: np.ndarray) -> np.ndarray:
    """(M, 3) int64: the triangle across the edge opposite each vertex, -1 on the
    boundary.  GeometryError where an edge is shared by more than two triangles
    or two triangles run an edge the same way (not an oriented 2-manifold)."""
    m = len(triangles)
    a = triangles[:, [1, 2, 0]].ravel()  # edge opposite vertex i: (tri[i+1], tri[i+2])
    b = triangles[:, [2, 0, 1]].ravel()
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    order = np.lexsort((hi, lo))
    same = (lo[order][1:] == lo[order][:-1]) & (hi[order][1:] == hi[order][:-1])
    if np.any(same[1:] & same[:-1]):
        k = order[int(np.flatnonzero(same[1:] & same[:-1])[0]) + 1]
        raise GeometryError(f"edge ({lo[k]}, {hi[k]}) is shared by more than two triangles")
    first, second = order[:-1][same], order[1:][same]
    clash = a[first] == a[second]
    if np.any(clash):
        k = int(first[np.flatnonzero(clash)[0]])
        raise GeometryError(f"triangles {k // 3} and {int(second[np.flatnonzero(clash)[0]]) // 3}"
                            f" run edge ({a[k]}, {b[k]}) the same way")
    nbr = np.full(3 * m, -1, np.int64)
    nbr[first], nbr[second] = second // 3, first // 3
    return nbr.reshape(m, 3)


def oriented_neighbors(points: np.ndarray, triangles: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray]:
    """Triangles checked (indices in range, no zero area by the exact orient2d)
    and made counter-clockwise, and their neighbours."""
    P = np.ascontiguousarray(points, dtype=np.float64)
    if P.ndim != 2 or P.shape[1] != 2:
        raise GeometryError(f"points must be an (N, 2) array, got shape {P.shape}")
    if not np.isfinite(P).all():
        raise GeometryError("points must be finite")
    T = _as_triangles(triangles, len(P)).copy()
    signs = _orientations(P, T)
    if np.any(signs == 0):
        t = int(np.flatnonzero(signs == 0)[0])
        raise GeometryError(f"triangle {t} = {tuple(int(v) for v in T[t])} has zero area")
    T[signs < 0] = T[signs < 0][:, [0, 2, 1]]
    return T, neighbors_of(T)


def boundary_first(triangles: np.ndarray, neighbors: np.ndarray, n_points: int
                   ) -> tuple[np.ndarray, int, np.ndarray]:
    """(order, n_boundary, segments): a stable node order with the nodes on
    boundary edges first, their count, and the boundary edges (S, 2) in the
    old numbering, oriented with the mesh on their left."""
    t, i = np.nonzero(neighbors < 0)
    segments = np.column_stack([triangles[t, (i + 1) % 3], triangles[t, (i + 2) % 3]])
    on_boundary = np.zeros(n_points, bool)
    on_boundary[segments.ravel()] = True
    order = np.concatenate([np.flatnonzero(on_boundary), np.flatnonzero(~on_boundary)])
    return order, int(on_boundary.sum()), segments


_FAULTS = {
    1: "refers to a node out of range",
    2: "has a neighbour id out of range",
    3: "has a neighbour that does not share that edge back",
    4: "is not counter-clockwise (or has zero area)",
}


@njit(cache=True)
def _first_fault(P: np.ndarray, T: np.ndarray, N: np.ndarray) -> tuple[int, int]:
    """(fault code, triangle) of the first inconsistency, (0, -1) if none: node
    ids in range, neighbour ids in range and reciprocal across the same edge,
    positive exact orientation.  Every read is checked before it is made."""
    n, m = P.shape[0], T.shape[0]
    for t in range(m):
        for i in range(3):
            if T[t, i] < 0 or T[t, i] >= n:
                return 1, t
    for t in range(m):
        for i in range(3):
            s = N[t, i]
            if s < -1 or s >= m:
                return 2, t
            if s >= 0:
                u, w = T[t, (i + 1) % 3], T[t, (i + 2) % 3]
                back = False
                for j in range(3):
                    if T[s, (j + 1) % 3] == w and T[s, (j + 2) % 3] == u and N[s, j] == t:
                        back = True
                if not back:
                    return 3, t
    for t in range(m):
        a, b, c = T[t, 0], T[t, 1], T[t, 2]
        if orient2d(P[a, 0], P[a, 1], P[b, 0], P[b, 1], P[c, 0], P[c, 1]) <= 0.0:
            return 4, t
    return 0, -1


def check_mesh(points: np.ndarray, triangles: np.ndarray, neighbors: np.ndarray,
               radii: np.ndarray, segments: np.ndarray, n_boundary: int) -> None:
    """GeometryError naming the first array, triangle or value that a kernel
    could not safely read: shapes and dtypes, finite points, positive radii,
    index ranges, reciprocal neighbours, counter-clockwise triangles.  O(M)."""
    n = len(points)
    shapes = {"points": (points, (n, 2), "f"), "triangles": (triangles, (None, 3), "iu"),
              "neighbors": (neighbors, (len(triangles), 3), "iu"),
              "radii": (radii, (n,), "f"), "segments": (segments, (None, 2), "iu")}
    for name, (array, shape, kinds) in shapes.items():
        if array.ndim != len(shape) or any(s is not None and s != a
                                          for s, a in zip(shape, array.shape)):
            want = "(" + ", ".join("M" if s is None else str(s) for s in shape) + ")"
            raise GeometryError(f"mesh {name} has shape {array.shape}, expected {want}")
        if array.dtype.kind not in kinds:
            raise GeometryError(f"mesh {name} has dtype {array.dtype}")
    if not np.isfinite(points).all():
        raise GeometryError("mesh points must be finite")
    if not (np.isfinite(radii).all() and (radii > 0).all()):
        raise GeometryError("mesh radii must be finite and > 0")
    if not 0 <= n_boundary <= n:
        raise GeometryError(f"mesh n_boundary = {n_boundary} is outside 0..{n}")
    if segments.size and (segments.min() < 0 or segments.max() >= n):
        raise GeometryError("a mesh segment refers to a node out of range")
    code, t = _first_fault(points, np.asarray(triangles, np.int64),
                           np.asarray(neighbors, np.int64))
    if code:
        raise GeometryError(f"mesh triangle {t} {_FAULTS[code]}")
