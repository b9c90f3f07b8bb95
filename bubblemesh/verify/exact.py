"""Exact predicates on the floats' binary values, and their filtered vector forms.

Every float64 is ``m * 2**e`` exactly (``float.as_integer_ratio``).
:func:`exact_integers` multiplies all coordinates of one point set by the same
power of two so that they become Python integers; orientation, in-circle,
circumcentres and point-in-polygon are then plain integer or ``Fraction``
arithmetic with no rounding.

The vector forms (:func:`orient_signs`, :func:`incircle_signs`) evaluate the
determinant in float64 on coordinates scaled into [-1, 1] by a power of two
(exact, so the sign is unchanged) and accept a sign only when the value
exceeds Shewchuk's a-priori error bound ("Adaptive precision floating-point
arithmetic", 1997, bounds A) plus an absolute margin for underflow; every
other case is decided by the integer formula.  So their answers are exact.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np

_U = 2.0**-53  # unit round-off
_CCW_BOUND = (3.0 + 16.0 * _U) * _U
_ICC_BOUND = (10.0 + 96.0 * _U) * _U
_TINY = 1e-290  # covers underflow: a few 2**-1074 errors times factors below 100


def exact_integers(points) -> tuple[list[tuple[int, int]], int]:
    """Return ``(P, shift)`` with ``points[i] == P[i] / 2**shift`` exactly.

    All coordinates share one scale, so any polynomial predicate evaluated on
    ``P`` has exactly the sign it has on the real numbers the floats denote.
    """
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise ValueError(f"points must have shape (N, 2), got {pts.shape}")
    if not np.all(np.isfinite(pts)):
        raise ValueError("points contain NaN or infinity")
    ratios = [x.as_integer_ratio() for x in pts.ravel().tolist()]
    shift = max((d.bit_length() - 1 for _, d in ratios), default=0)
    ints = [n << (shift - (d.bit_length() - 1)) for n, d in ratios]
    return list(zip(ints[0::2], ints[1::2])), shift


def orient_int(a, b, c) -> int:
    """Twice the signed area of (a, b, c) on integer points: >0 iff CCW."""
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])


def incircle_int(a, b, c, d) -> int:
    """In-circle determinant on integer points: >0 iff d strictly inside the
    circle through CCW a, b, c; 0 iff cocircular (sign flips if abc is CW)."""
    adx, ady = a[0] - d[0], a[1] - d[1]
    bdx, bdy = b[0] - d[0], b[1] - d[1]
    cdx, cdy = c[0] - d[0], c[1] - d[1]
    alift = adx * adx + ady * ady
    blift = bdx * bdx + bdy * bdy
    clift = cdx * cdx + cdy * cdy
    return (
        alift * (bdx * cdy - cdx * bdy)
        + blift * (cdx * ady - adx * cdy)
        + clift * (adx * bdy - bdx * ady)
    )


def sign(x) -> int:
    return (x > 0) - (x < 0)


def orient2d_sign(ax, ay, bx, by, cx, cy) -> int:
    """Exact sign of orient2d on float inputs (via Fraction): +1 CCW, 0, -1."""
    f = Fraction
    return sign(orient_int((f(ax), f(ay)), (f(bx), f(by)), (f(cx), f(cy))))


def incircle_sign(ax, ay, bx, by, cx, cy, dx, dy) -> int:
    """Exact sign of the in-circle determinant on float inputs (via Fraction)."""
    f = Fraction
    return sign(incircle_int((f(ax), f(ay)), (f(bx), f(by)), (f(cx), f(cy)), (f(dx), f(dy))))


def circumcircle_exact(a, b, c) -> tuple[Fraction, Fraction, Fraction]:
    """Exact circumcentre (x, y) and squared radius of integer points a, b, c."""
    bx, by = b[0] - a[0], b[1] - a[1]
    cx, cy = c[0] - a[0], c[1] - a[1]
    d = 2 * (bx * cy - by * cx)
    if d == 0:
        raise ZeroDivisionError("collinear triangle has no circumcircle")
    b2, c2 = bx * bx + by * by, cx * cx + cy * cy
    ux = Fraction(cy * b2 - by * c2, d)
    uy = Fraction(bx * c2 - cx * b2, d)
    return a[0] + ux, a[1] + uy, ux * ux + uy * uy


def point_in_polygon(q, poly) -> int:
    """Exact location of integer point q w.r.t. the closed polygon ``poly``
    (list of integer points): +1 inside, 0 on the boundary, -1 outside.
    Crossing number with the half-open edge rule; all comparisons exact."""
    inside = False
    n = len(poly)
    for i in range(n):
        p1, p2 = poly[i], poly[(i + 1) % n]
        o = orient_int(p1, p2, q)
        if (
            o == 0
            and min(p1[0], p2[0]) <= q[0] <= max(p1[0], p2[0])
            and min(p1[1], p2[1]) <= q[1] <= max(p1[1], p2[1])
        ):
            return 0
        # edge crosses the horizontal line through q, to the right of q?
        if (p1[1] > q[1]) != (p2[1] > q[1]) and (o > 0) == (p2[1] > p1[1]):
            inside = not inside
    return 1 if inside else -1


def signed_area_exact(P, loop) -> Fraction:
    """Exact signed area (in the integer scale) of a closed polygon."""
    s = 0
    for i in range(len(loop)):
        p, q = P[loop[i]], P[loop[(i + 1) % len(loop)]]
        s += p[0] * q[1] - q[0] * p[1]
    return Fraction(s, 2)


class ExactPoints:
    """A point set with its exact integer image and a scaled float copy.

    ``scaled`` is ``points * 2**-k`` with max |coordinate| <= 1; points whose
    scaling is not exact (they would fall into the subnormals) are flagged in
    ``unsafe`` and every predicate touching them is decided exactly.
    """

    def __init__(self, points):
        self.points = np.asarray(points, dtype=np.float64)
        self.P, self.shift = exact_integers(self.points)
        mag = float(np.max(np.abs(self.points))) if self.points.size else 0.0
        k = int(np.frexp(mag)[1]) if mag > 0 else 0
        self.exponent = k  # points == scaled * 2**k
        self.scaled = np.ldexp(self.points, -k)
        self.unsafe = np.any(np.ldexp(self.scaled, k) != self.points, axis=1)


def orient_signs(E: ExactPoints, a, b, c) -> np.ndarray:
    """Exact signs of orient(a, b, c) for index arrays a, b, c (+1 CCW)."""
    s = E.scaled
    acx, acy = s[a, 0] - s[c, 0], s[a, 1] - s[c, 1]
    bcx, bcy = s[b, 0] - s[c, 0], s[b, 1] - s[c, 1]
    left, right = acx * bcy, acy * bcx
    det = left - right
    bound = _CCW_BOUND * (np.abs(left) + np.abs(right)) + _TINY
    out = np.sign(det).astype(np.int64)
    unsure = ~(np.abs(det) > bound) | E.unsafe[a] | E.unsafe[b] | E.unsafe[c]
    P = E.P
    for k in np.nonzero(unsure)[0].tolist():
        out[k] = sign(orient_int(P[a[k]], P[b[k]], P[c[k]]))
    return out


def incircle_signs(E: ExactPoints, a, b, c, d) -> np.ndarray:
    """Exact signs of incircle(a, b, c, d) for index arrays (>0: d strictly
    inside the circle through CCW a, b, c)."""
    s = E.scaled
    adx, ady = s[a, 0] - s[d, 0], s[a, 1] - s[d, 1]
    bdx, bdy = s[b, 0] - s[d, 0], s[b, 1] - s[d, 1]
    cdx, cdy = s[c, 0] - s[d, 0], s[c, 1] - s[d, 1]
    bc, cb = bdx * cdy, cdx * bdy
    ca, ac = cdx * ady, adx * cdy
    ab, ba = adx * bdy, bdx * ady
    alift, blift, clift = adx * adx + ady * ady, bdx * bdx + bdy * bdy, cdx * cdx + cdy * cdy
    det = alift * (bc - cb) + blift * (ca - ac) + clift * (ab - ba)
    perm = (
        (np.abs(bc) + np.abs(cb)) * alift
        + (np.abs(ca) + np.abs(ac)) * blift
        + (np.abs(ab) + np.abs(ba)) * clift
    )
    out = np.sign(det).astype(np.int64)
    unsure = ~(np.abs(det) > _ICC_BOUND * perm + _TINY)
    unsure |= E.unsafe[a] | E.unsafe[b] | E.unsafe[c] | E.unsafe[d]
    P = E.P
    for k in np.nonzero(unsure)[0].tolist():
        out[k] = sign(incircle_int(P[a[k]], P[b[k]], P[c[k]], P[d[k]]))
    return out
