"""Mesh measures used by the reports, written from the definitions.

``radius_ratio`` is the paper's eq. (10); ``summary`` has the keys of
``bubblemesh.quality.summary`` (the API contract) so either can feed a report.
The report prefers the package's own ``bubblemesh.quality.summary`` once it
exists and says which one it used; this module is the fallback and is also
what the boundary checks of the peers use.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "radius_ratio",
    "angles",
    "summary",
    "boundary_edges",
    "boundary_nodes",
    "boundary_shift",
]


def _sides(points: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    p = np.asarray(points, dtype=np.float64)[:, :2]
    t = np.asarray(triangles, dtype=np.int64)
    a, b, c = p[t[:, 0]], p[t[:, 1]], p[t[:, 2]]
    la = np.hypot(*(c - b).T)  # opposite vertex a
    lb = np.hypot(*(a - c).T)
    lc = np.hypot(*(b - a).T)
    return la, lb, lc


def radius_ratio(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """ρ = 2r/R = (lc+lb−la)(lc+la−lb)(la+lb−lc) / (la·lb·lc), eq. (10); 1 for equilateral."""
    la, lb, lc = _sides(points, triangles)
    with np.errstate(divide="ignore", invalid="ignore"):
        rho = (lc + lb - la) * (lc + la - lb) * (la + lb - lc) / (la * lb * lc)
    return np.nan_to_num(rho, nan=0.0)


def angles(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Interior angles in degrees, (M, 3), column i at vertex i (law of cosines)."""
    la, lb, lc = _sides(points, triangles)

    def ang(opp, s1, s2):
        with np.errstate(divide="ignore", invalid="ignore"):
            c = (s1 * s1 + s2 * s2 - opp * opp) / (2.0 * s1 * s2)
        return np.degrees(np.arccos(np.clip(np.nan_to_num(c, nan=1.0), -1.0, 1.0)))

    return np.column_stack([ang(la, lb, lc), ang(lb, lc, la), ang(lc, la, lb)])


def summary(points: np.ndarray, triangles: np.ndarray) -> dict:
    rho = radius_ratio(points, triangles)
    ang = angles(points, triangles)
    n = len(rho)
    if n == 0:
        nan = float("nan")
        return dict(
            count=0,
            min=nan,
            mean=nan,
            median=nan,
            frac_below_0_5=nan,
            frac_below_0_7=nan,
            count_below_0_5=0,
            count_below_0_7=0,
            min_angle_deg=nan,
            max_angle_deg=nan,
        )
    return dict(
        count=n,
        min=float(rho.min()),
        mean=float(rho.mean()),
        median=float(np.median(rho)),
        frac_below_0_5=float((rho < 0.5).mean()),
        frac_below_0_7=float((rho < 0.7).mean()),
        count_below_0_5=int((rho < 0.5).sum()),
        count_below_0_7=int((rho < 0.7).sum()),
        min_angle_deg=float(ang.min()),
        max_angle_deg=float(ang.max()),
    )


def boundary_edges(triangles: np.ndarray) -> np.ndarray:
    """Edges used by exactly one triangle, (K, 2) sorted index pairs."""
    t = np.asarray(triangles, dtype=np.int64)
    e = np.sort(np.vstack([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1)
    u, cnt = np.unique(e, axis=0, return_counts=True)
    return u[cnt == 1]


def boundary_nodes(triangles: np.ndarray) -> np.ndarray:
    return np.unique(boundary_edges(triangles))


def boundary_shift(
    boundary: np.ndarray, points: np.ndarray, triangles: np.ndarray
) -> tuple[float, int]:
    """How far the given boundary nodes moved in a mesh, and how many boundary nodes it has.

    Returns ``(shift, n_boundary)``: ``shift`` is the largest distance from a
    given boundary node to the nearest node on the mesh's boundary (0 when every
    boundary node is kept), ``n_boundary`` the mesh's count of boundary nodes
    (equal to ``len(boundary)`` when none were added or removed).
    """
    from scipy.spatial import cKDTree

    p = np.asarray(points, dtype=np.float64)[:, :2]
    bn = boundary_nodes(triangles)
    if len(bn) == 0:
        return float("inf"), 0
    d, _ = cKDTree(p[bn]).query(np.asarray(boundary, dtype=np.float64)[:, :2])
    return float(d.max()), int(len(bn))
