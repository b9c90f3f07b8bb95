"""Quality and bubble measures from classical formulas, not from the mesher's.

Radius ratio 2r/R (paper §4, eq. 10's quantity), interior angles, and the
population criterion of §2.3 (eq. 1-4 and 6) recomputed from node radii.
"""

from __future__ import annotations

import math

import numpy as np

_PI = math.pi


def triangle_areas(points, triangles) -> np.ndarray:
    """Signed areas (positive for CCW), from the cross product."""
    pts = np.asarray(points, dtype=np.float64)
    tri = np.asarray(triangles, dtype=np.int64)
    a, b, c = pts[tri[:, 0]], pts[tri[:, 1]], pts[tri[:, 2]]
    return 0.5 * (
        (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    )


def _edge(points, triangles):
    """edge(i, j): each triangle's vector p_j - p_i, (M, 2), times a power of two
    per triangle where the triangle's largest such component is below 2^-100
    or above 2^100 (then brought into [0.5, 1)): the measures below are
    scale-invariant, but their products of lengths would underflow or overflow
    there.  Elsewhere no bit changes."""
    pts = np.asarray(points, dtype=np.float64)
    tri = np.asarray(triangles, dtype=np.int64)
    p = [pts[tri[:, k]] for k in range(3)]
    spans = np.abs(np.hstack([p[1] - p[0], p[2] - p[0], p[1] - p[2]]))
    largest = spans.max(axis=1) if len(tri) else np.zeros(0)
    far = (largest > 0) & ((largest < 2.0**-100) | (largest > 2.0**100))
    shift = np.where(far, -np.frexp(largest)[1], 0)[:, None] if far.any() else None

    def edge(i: int, j: int) -> np.ndarray:
        d = p[j] - p[i]
        return d if shift is None else np.ldexp(d, shift)

    return edge


def radius_ratio_reference(points, triangles) -> np.ndarray:
    """2r/R from the classical formulas, not from eq. 10:
    inradius r = 2A / perimeter, circumradius R = abc / (4A), A from the cross
    product.  So 2r/R = 16 A^2 / (perimeter * a * b * c).  0 for zero area."""
    edge = _edge(points, triangles)
    u, w = edge(0, 1), edge(0, 2)
    A = np.abs(0.5 * (u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0]))
    la = np.hypot(*edge(2, 1).T)
    lb = np.hypot(*w.T)
    lc = np.hypot(*u.T)
    perimeter = la + lb + lc
    with np.errstate(divide="ignore", invalid="ignore"):
        r_in = 2 * A / perimeter
        R_circ = la * lb * lc / (4 * A)
        rho = np.where(A > 0, 2 * r_in / R_circ, 0.0)
    return rho


def angles_reference(points, triangles) -> np.ndarray:
    """Interior angles in degrees at each triangle vertex, from atan2 of the
    cross and dot products of the two incident edge vectors."""
    edge = _edge(points, triangles)
    out = np.empty((len(np.asarray(triangles)), 3))
    for i in range(3):
        u, w = edge(i, (i + 1) % 3), edge(i, (i + 2) % 3)
        cross = u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0]
        dot = u[:, 0] * w[:, 0] + u[:, 1] * w[:, 1]
        out[:, i] = np.degrees(np.arctan2(np.abs(cross), dot))
    return out


def quality_summary(points, triangles) -> dict:
    """min/mean 2r/R, counts below 0.5 and 0.7, extreme angles."""
    rho = radius_ratio_reference(points, triangles)
    ang = angles_reference(points, triangles)
    return {
        "min_radius_ratio": float(rho.min()),
        "mean_radius_ratio": float(rho.mean()),
        "below_0.5": int((rho < 0.5).sum()),
        "below_0.7": int((rho < 0.7).sum()),
        "min_angle": float(ang.min()),
        "max_angle": float(ang.max()),
    }


def boundary_radii_reference(points, segments) -> dict[int, float]:
    """Eq. 1-2: radius of each boundary node's bubble from the lengths l1, l2
    of its two boundary edges: r = sqrt(sqrt(3)/(8 pi) (l1^2 + l2^2))."""
    pts = np.asarray(points, dtype=np.float64)
    incident: dict[int, list[float]] = {}
    for a, b in np.asarray(segments, dtype=np.int64).reshape(-1, 2).tolist():
        length = math.hypot(pts[b, 0] - pts[a, 0], pts[b, 1] - pts[a, 1])
        incident.setdefault(a, []).append(length)
        incident.setdefault(b, []).append(length)
    out = {}
    for node, lengths in incident.items():
        if len(lengths) != 2:
            raise ValueError(f"boundary node {node} has {len(lengths)} boundary edges, expected 2")
        out[node] = math.sqrt(math.sqrt(3) / (8 * _PI) * (lengths[0] ** 2 + lengths[1] ** 2))
    return out


def element_bubble_radii(points, triangles, radii) -> np.ndarray:
    """Eq. 3: r_e at each triangle's centroid e by reciprocal-distance
    interpolation of the node radii: sum(r_i / l_ie) / sum(1 / l_ie)."""
    pts = np.asarray(points, dtype=np.float64)
    tri = np.asarray(triangles, dtype=np.int64)
    r = np.asarray(radii, dtype=np.float64)
    corners = pts[tri]  # (M, 3, 2)
    e = corners.sum(axis=1) / 3
    with np.errstate(divide="ignore"):
        w = 1.0 / np.hypot(*(corners - e[:, None, :]).transpose(2, 0, 1))
    return (r[tri] * w).sum(axis=1) / w.sum(axis=1)


def population_bubble_area(points, triangles, radii) -> float:
    """Eq. 4 summed: sum over triangles of A_e = pi r_e^2 (the left side of eq. 6)."""
    re = element_bubble_radii(points, triangles, radii)
    return math.fsum((_PI * re * re).tolist())
