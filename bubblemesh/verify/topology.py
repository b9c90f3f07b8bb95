"""Validity of a triangle mesh as a combinatorial and geometric object.

Half-edge ``h = 3*t + i`` is the edge of triangle ``t`` opposite its vertex
``i``, directed ``(tri[t, (i+1)%3], tri[t, (i+2)%3])``: counter-clockwise
when the triangle is, and the convention of a ``neighbors`` array
(``neighbors[t, i]`` = the triangle across that edge, -1 on the boundary).
"""

from __future__ import annotations

import numpy as np

from .exact import ExactPoints, orient_signs
from .report import Report


def as_triangles(triangles, n_points: int | None = None) -> np.ndarray:
    """An (M, 3) int64 copy-free view; misuse (shape, dtype) is a TypeError/ValueError."""
    tri = np.asarray(triangles)
    if tri.ndim != 2 or tri.shape[1] != 3:
        raise ValueError(f"triangles must have shape (M, 3), got {tri.shape}")
    if tri.size and not np.issubdtype(tri.dtype, np.integer):
        raise TypeError(f"triangles must be integers, got {tri.dtype}")
    return tri.astype(np.int64, copy=False)


def as_points(points) -> np.ndarray:
    """(N, 2) float64; (N, 3) is accepted when z is 0 everywhere (2-D files)."""
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim == 2 and pts.shape[1] == 3:
        if np.any(pts[:, 2] != 0):
            k = int(np.argmax(pts[:, 2] != 0))
            raise ValueError(f"points are 3-D: node {k} has z = {float(pts[k, 2])!r} "
                             "(2-D needs z = 0)")
        pts = pts[:, :2]
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise ValueError(f"points must have shape (N, 2), got {pts.shape}")
    if not np.all(np.isfinite(pts)):
        k = int(np.argmax(~np.isfinite(pts).all(axis=1)))
        raise ValueError(f"node {k} has a NaN or infinite coordinate: {pts[k].tolist()}")
    return np.ascontiguousarray(pts)


class HalfEdges:
    """Edge tables of a non-empty triangle array (vectorised: sorts, no loop per element)."""

    def __init__(self, tri: np.ndarray, n_points: int):
        self.tri = tri
        self.n = max(int(n_points), 1)
        self.u = tri[:, [1, 2, 0]].ravel()  # half-edge 3t+i goes u -> v, opposite vertex i
        self.v = tri[:, [2, 0, 1]].ravel()
        lo, hi = np.minimum(self.u, self.v), np.maximum(self.u, self.v)
        keys, self.edge, self.count = np.unique(
            lo * self.n + hi, return_inverse=True, return_counts=True
        )
        self.edge = self.edge.ravel()
        self.keys = keys
        directed = self.u * self.n + self.v
        order = np.argsort(directed, kind="stable")
        self._dsorted, self._dorder = directed[order], order
        self.reverse = self.find_directed(self.v, self.u)  # twin half-edge or -1

    def find_directed(self, a, b) -> np.ndarray:
        """Half-edge a -> b (the first one if repeated), or -1."""
        want = np.asarray(a, dtype=np.int64) * self.n + np.asarray(b, dtype=np.int64)
        pos = np.minimum(np.searchsorted(self._dsorted, want), len(self._dsorted) - 1)
        return np.where(self._dsorted[pos] == want, self._dorder[pos], -1)

    def edge_count(self, a, b) -> np.ndarray:
        """Triangles using the undirected edge {a, b} (0 if it is no edge)."""
        a, b = np.asarray(a, dtype=np.int64), np.asarray(b, dtype=np.int64)
        want = np.minimum(a, b) * self.n + np.maximum(a, b)
        pos = np.minimum(np.searchsorted(self.keys, want), len(self.keys) - 1)
        return np.where(self.keys[pos] == want, self.count[pos], 0)

    def boundary(self) -> np.ndarray:
        """Half-edges whose undirected edge is used once."""
        return np.nonzero(self.count[self.edge] == 1)[0]


def check_validity(E: ExactPoints, tri: np.ndarray, report: Report, neighbors=None,
                   n_nodes: int | None = None):
    """Indices, orientation, duplicates, manifold edges, neighbours, node use.

    The mesh's nodes are the first ``n_nodes`` points of ``E`` (default all;
    the input boundary's nodes may follow them, to share one integer scale).

    Returns the HalfEdges (None when indices are out of range: nothing else
    can be checked) and the boolean mask of strictly CCW triangles.
    """
    n = len(E.points) if n_nodes is None else n_nodes
    m = len(tri)
    if m == 0:
        report.add("empty", "the mesh has no triangles")
        return None, np.zeros(0, bool)
    bad = np.nonzero(((tri < 0) | (tri >= n)).any(axis=1))[0]
    for t in bad.tolist():
        report.add("bad_index", f"triangle {t} {tri[t].tolist()}: index outside [0, {n})",
                   triangle=t)
    if len(bad):
        return None, np.zeros(m, bool)
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    repeated = (a == b) | (b == c) | (a == c)
    for t in np.nonzero(repeated)[0].tolist():
        report.add("repeated_vertex", f"triangle {t} {tri[t].tolist()} repeats a vertex",
                   triangle=t)
    o = np.zeros(m, np.int64)
    ok = np.nonzero(~repeated)[0]
    o[ok] = orient_signs(E, a[ok], b[ok], c[ok])
    for t in np.nonzero(~repeated & (o < 0))[0].tolist():
        report.add("orientation", f"triangle {t} {tri[t].tolist()} is clockwise: "
                   f"points {E.points[tri[t]].tolist()}", triangle=t)
    for t in np.nonzero(~repeated & (o == 0))[0].tolist():
        report.add("degenerate", f"triangle {t} {tri[t].tolist()} has zero area "
                   f"(collinear vertices): points {E.points[tri[t]].tolist()}", triangle=t)
    _duplicates(tri, report)
    H = HalfEdges(tri, n)
    _manifold(H, report)
    if neighbors is not None:
        _neighbors(H, np.asarray(neighbors), report)
    _node_use(E, n, tri, report)
    return H, o > 0


def _duplicates(tri, report):
    rows = np.sort(tri, axis=1)
    _, first, inverse = np.unique(rows, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.ravel()
    for t in np.nonzero(first[inverse] != np.arange(len(tri)))[0].tolist():
        report.add("duplicate_triangle", f"triangle {t} {tri[t].tolist()} duplicates "
                   f"triangle {int(first[inverse[t]])}", triangle=t)


def _manifold(H: HalfEdges, report):
    directed = H.u * H.n + H.v
    order = np.argsort(directed, kind="stable")
    same = np.nonzero(directed[order][1:] == directed[order][:-1])[0]
    for k in same.tolist():
        h0, h1 = int(order[k]), int(order[k + 1])
        e = (int(H.u[h1]), int(H.v[h1]))
        report.add("non_manifold_edge", f"directed edge {e} used by triangles {h0 // 3} and "
                   f"{h1 // 3} (same direction: the triangles overlap)", triangle=h1 // 3, edge=e)
    for k in np.nonzero(H.count > 2)[0].tolist():
        lo, hi = divmod(int(H.keys[k]), H.n)
        users = sorted({int(h) // 3 for h in np.nonzero(H.edge == k)[0].tolist()})
        report.add("non_manifold_edge", f"edge {(lo, hi)} used by {int(H.count[k])} triangles "
                   f"{users}", edge=(lo, hi), triangle=users[0])


def _neighbors(H: HalfEdges, nb, report):
    if nb.shape != H.tri.shape:
        raise ValueError(f"neighbors shape {nb.shape} != triangles shape {H.tri.shape}")
    expect = np.where(H.reverse >= 0, H.reverse // 3, -1)
    got = nb.astype(np.int64).ravel()
    for h in np.nonzero(got != expect)[0].tolist():
        t, i = divmod(h, 3)
        e = (int(H.u[h]), int(H.v[h]))
        if expect[h] < 0:
            why = f"but edge {e} is a boundary edge (expected -1)"
        else:
            why = f"expected {int(expect[h])} (across edge {e})"
        report.add("neighbors", f"neighbors[{t},{i}] = {int(got[h])}, {why}", triangle=t, edge=e)


def _node_use(E: ExactPoints, n, tri, report):
    used = np.zeros(n, bool)
    used[tri.ravel()] = True
    for v in np.nonzero(~used)[0].tolist():
        report.add("unused_node", f"node {v} {E.points[v].tolist()} is in no triangle", node=v)
    idx = np.nonzero(used)[0]
    _, first, inverse = np.unique(E.points[idx] + 0.0, axis=0, return_index=True,
                                  return_inverse=True)
    inverse = inverse.ravel()
    for k in np.nonzero(first[inverse] != np.arange(len(idx)))[0].tolist():
        v, w = int(idx[k]), int(idx[first[inverse[k]]])
        report.add("duplicate_node", f"node {v} is at the position of node {w}: "
                   f"{E.points[v].tolist()}", node=v)


def euler_characteristic(tri: np.ndarray, H: HalfEdges | None = None) -> int:
    """V - E + F counting only the vertices the triangles use."""
    if H is None:
        H = HalfEdges(tri, int(tri.max()) + 1 if tri.size else 1)
    return len(np.unique(tri)) - len(H.keys) + len(tri)
