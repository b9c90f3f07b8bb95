"""Element quality: the radius ratio of paper §4, eq. 10, and angles.

rho = 2 r / R = (b + c - a)(c + a - b)(a + b - c) / (a b c), with a, b, c the
side lengths, r the inradius and R the circumradius: 1 for an equilateral
triangle, tending to 0 as the triangle degenerates.
"""

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["angles", "radius_ratio", "summary"]


def _side_lengths(points: ArrayLike, triangles: ArrayLike
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    p = np.asarray(points, dtype=np.float64)[np.asarray(triangles)]
    a = np.linalg.norm(p[:, 2] - p[:, 1], axis=1)  # opposite vertex 0
    b = np.linalg.norm(p[:, 0] - p[:, 2], axis=1)  # opposite vertex 1
    c = np.linalg.norm(p[:, 1] - p[:, 0], axis=1)  # opposite vertex 2
    return a, b, c


def radius_ratio(points: ArrayLike, triangles: ArrayLike) -> np.ndarray:
    """Eq. 10 for every triangle, (M,) float64 in [0, 1]."""
    a, b, c = _side_lengths(points, triangles)
    rho = (b + c - a) * (c + a - b) * (a + b - c) / (a * b * c)
    return np.clip(rho, 0.0, 1.0)


def angles(points: ArrayLike, triangles: ArrayLike) -> np.ndarray:
    """Interior angles in degrees, (M, 3): column i is the angle at vertex i.

    atan2(|cross|, dot) of the two edge vectors stays accurate on needles, where
    arccos of the law of cosines loses every digit."""
    p = np.asarray(points, dtype=np.float64)[np.asarray(triangles)]
    out = np.empty(p.shape[:2])
    for i in range(3):
        u = p[:, (i + 1) % 3] - p[:, i]
        v = p[:, (i + 2) % 3] - p[:, i]
        cross = np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0])
        dot = u[:, 0] * v[:, 0] + u[:, 1] * v[:, 1]
        out[:, i] = np.degrees(np.arctan2(cross, dot))
    return out


def summary(points: ArrayLike, triangles: ArrayLike) -> dict[str, float]:
    """Radius-ratio and angle statistics as a flat dict (one pandas row)."""
    rho = radius_ratio(points, triangles)
    ang = angles(points, triangles)
    return {
        "count": int(rho.size),
        "min": float(rho.min()),
        "mean": float(rho.mean()),
        "median": float(np.median(rho)),
        "count_below_0_5": int((rho < 0.5).sum()),
        "frac_below_0_5": float((rho < 0.5).mean()),
        "count_below_0_7": int((rho < 0.7).sum()),
        "frac_below_0_7": float((rho < 0.7).mean()),
        "min_angle_deg": float(ang.min()),
        "max_angle_deg": float(ang.max()),
    }
