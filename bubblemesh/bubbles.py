"""Node bubbles and element bubbles: paper §2.3, eq. 1-5 (and eq. 9's interpolation).

* eq. 1-2: a boundary node's bubble has the mean area of the two equilateral
  triangles on its neighbouring boundary edges, r_n = sqrt(sqrt(3)/(8 pi) (l1^2 + l2^2)).
* eq. 3: an element bubble sits at the triangle's centroid e; its radius is the
  reciprocal-distance interpolation r_e = sum(r_k / l_ke) / sum(1 / l_ke) of the
  vertex radii, l_ke = |x_k - x_e|.
* eq. 4: A_e = pi r_e^2.      * eq. 5: D_e = A_e / A_m, A_m the triangle's area
  (applied per triangle inside the §2 kernel, generation._bubble).
"""

import math
from collections.abc import Sequence

import numpy as np
from numba import njit

__all__ = ["boundary_radii", "element_radius", "triangle_area"]

BOUNDARY_FACTOR = math.sqrt(3.0) / (8.0 * math.pi)  # eq. 2


def boundary_radii(points: np.ndarray, loops: Sequence[np.ndarray]) -> np.ndarray:
    """Eq. 1-2 for every boundary node: l1, l2 are the lengths of the loop's
    segments arriving at and leaving the node.  A node on no segment (a free
    point of a planar graph) takes l1 = l2 = the distance to its nearest other
    node.  Returns (N,) float64, in the order of ``points``."""
    radii = np.zeros(len(points))
    for loop in loops:
        ring = points[loop]
        leaving = np.linalg.norm(np.roll(ring, -1, axis=0) - ring, axis=1)
        arriving = np.roll(leaving, 1)
        radii[loop] = np.sqrt(BOUNDARY_FACTOR * (arriving**2 + leaving**2))
    free = np.flatnonzero(radii == 0.0)
    if len(free) and len(points) > 1:
        from scipy.spatial import cKDTree

        nearest, _ = cKDTree(points).query(points[free], k=2)
        radii[free] = np.sqrt(2.0 * BOUNDARY_FACTOR) * nearest[:, 1]
    return radii


@njit(cache=True, inline="always")
def element_radius(ax, ay, ra, bx, by, rb, cx, cy, rc):
    """Eq. 3: reciprocal-distance interpolation of the vertex radii at the centroid.
    Returns (r_e, centroid x, centroid y).  Where the rounded centroid of a
    sliver falls on a vertex, r_e is that vertex's radius (eq. 3's limit)."""
    ex = (ax + bx + cx) / 3.0
    ey = (ay + by + cy) / 3.0
    la = (ax - ex) ** 2 + (ay - ey) ** 2
    lb = (bx - ex) ** 2 + (by - ey) ** 2
    lc = (cx - ex) ** 2 + (cy - ey) ** 2
    if la == 0.0 or lb == 0.0 or lc == 0.0:
        return (ra if la == 0.0 else (rb if lb == 0.0 else rc)), ex, ey
    wa = 1.0 / math.sqrt(la)  # sqrt: hypot is far slower here
    wb = 1.0 / math.sqrt(lb)
    wc = 1.0 / math.sqrt(lc)
    return (ra * wa + rb * wb + rc * wc) / (wa + wb + wc), ex, ey


@njit(cache=True, inline="always")
def triangle_area(ax, ay, bx, by, cx, cy):
    """A_m of eq. 5 (positive for counter-clockwise triangles)."""
    return 0.5 * ((bx - ax) * (cy - ay) - (by - ay) * (cx - ax))
