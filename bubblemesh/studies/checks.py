"""The cheap default for a study's ``verify`` column: is the mesh a valid mesh of the case?

A verify function is ``verify(case, points, triangles) -> str``: ``"ok"`` or
``"failed: <the first problem>"``.  A study takes any such function (the exact checkers
of ``bubblemesh.verify`` among them); ``None`` leaves the column empty.
"""

from __future__ import annotations

import numpy as np

from .case import Case

__all__ = ["basic_check", "exact_check"]


def _problem(case: Case, points: np.ndarray, triangles: np.ndarray) -> str | None:
    from bubblemesh.topology import _orientations

    p, t = np.asarray(points), np.asarray(triangles)
    if p.ndim != 2 or p.shape[1] < 2 or not np.isfinite(p[:, :2]).all():
        return f"points of shape {p.shape} are not (N, 2) finite coordinates"
    if t.ndim != 2 or t.shape[1] != 3 or len(t) == 0 or t.dtype.kind not in "iu":
        return f"triangles of shape {t.shape}, dtype {t.dtype}: not a non-empty (M, 3) int array"
    if t.min() < 0 or t.max() >= len(p):
        return f"a triangle refers to a node outside 0..{len(p) - 1}"
    p = np.ascontiguousarray(p[:, :2], dtype=np.float64)
    t = np.ascontiguousarray(t, dtype=np.int64)
    sign = _orientations(p, t)  # exact orient2d
    if (sign <= 0).any():
        return f"{int((sign <= 0).sum())} triangles are clockwise or flat (exact orientation)"
    directed = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    if len(np.unique(directed, axis=0)) != len(directed):
        return "an edge is used twice in the same direction (overlap or fold)"
    edges, uses = np.unique(np.sort(directed, axis=1), axis=0, return_counts=True)
    if uses.max() > 2:
        return "an edge is shared by more than two triangles"
    border = edges[uses == 1]
    given = case.boundary
    nodes = {tuple(q) for q in p[np.unique(border)].tolist()}
    missing = sum(tuple(q) not in nodes for q in given.tolist())
    if missing:
        return f"{missing} of the case's {len(given)} boundary nodes are not on the mesh boundary"
    if len(border) != len(given):
        return f"the mesh boundary has {len(border)} edges, the case {len(given)} segments"
    e1, e2 = p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]]
    area = 0.5 * float(np.sum(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]))
    expected = case.domain().area
    if abs(area - expected) > 1e-9 * expected:
        return f"the triangles cover area {area:.12g}, the case's region {expected:.12g}"
    return None


def basic_check(case: Case, points: np.ndarray, triangles: np.ndarray) -> str:
    """Counter-clockwise triangles (exact), edges shared at most twice and never twice the
    same way, the boundary edges exactly the case's segments in number with every boundary
    node on them, and the area of the region: ``"ok"`` or ``"failed: ..."``."""
    problem = _problem(case, points, triangles)
    return "ok" if problem is None else f"failed: {problem}"


def exact_check(case: Case, points: np.ndarray, triangles: np.ndarray) -> str:
    """The exact checks of :mod:`bubblemesh.verify` against the case's boundary:
    validity, conformity (split segments allowed), boundary nodes unmoved; not
    the Delaunay property, which not every mesher claims.  ``"ok"`` or
    ``"failed: <kinds and counts>"``."""
    from bubblemesh.verify import check

    domain = case.domain()
    report = check(points, triangles, domain.segments, domain.points, delaunay=False)
    if report.ok:
        return "ok"
    kinds = sorted({v.kind for v in report.violations})
    return "failed: " + ", ".join(f"{report.count(k)} {k}" for k in kinds)
