"""Exact geometric predicates: ``orient2d`` and ``incircle``.

Every combinatorial decision of the mesher (paper §2.2 cavity search, the
constrained Delaunay triangulation of §2.1 and §3.5, inside/outside tests)
rests on the *sign* of two determinants.  A wrong sign from floating-point
round-off gives crossing edges or non-Delaunay triangles, so both predicates
here return a value whose sign is exactly the sign of the real determinant of
the given float64 coordinates.

How: a floating-point filter first (the determinant in plain float64 with a
forward error bound; the bounds are the classical ones of Shewchuk's adaptive
predicates, ``(3 + 16 eps) eps`` and ``(10 + 96 eps) eps``).  Only when the
filter cannot decide, the determinant is evaluated *exactly* as a
floating-point expansion (a sum of non-overlapping doubles; error-free
``two_sum`` / ``two_product`` transformations), and the sign of its largest
component is returned.  That is exact as long as no product overflows or
underflows: every nonzero coordinate must lie in [MIN_COORDINATE,
MAX_COORDINATE] = [2**-100, 2**100] (about 7.9e-31 to 1.3e30).  Then the
smallest nonzero difference of two coordinates is 2**-152, whose 4th power (the
in-circle degree) and the error bounds stay far above the underflow threshold.
``out_of_range`` finds points that break this; the triangulation and the Domain
reject them with a GeometryError, after ``flush_tiny`` has read as 0 the
coordinates below the range in inputs whose largest coordinate is at least
2**52 times larger (``sin(pi)**3`` in a shape of size 17).

All functions are numba ``njit(cache=True)``; they are plain Python functions
when ``NUMBA_DISABLE_JIT=1``.
"""

import numpy as np
from numba import njit

__all__ = ["flush_tiny", "incircle", "orient2d", "out_of_range", "out_of_range_message"]

_EPS = 2.0**-53  # half an ulp of 1.0: the unit round-off of float64
_SPLITTER = 2.0**27 + 1.0  # Dekker's splitter for 53-bit doubles
CCW_ERRBOUND = (3.0 + 16.0 * _EPS) * _EPS
ICC_ERRBOUND = (10.0 + 96.0 * _EPS) * _EPS
MIN_COORDINATE = 2.0**-100
MAX_COORDINATE = 2.0**100


def out_of_range(points):
    """Boolean mask of the rows with a coordinate that is non-finite or nonzero
    but outside [MIN_COORDINATE, MAX_COORDINATE] in magnitude."""
    magnitude = np.abs(np.asarray(points, dtype=np.float64))
    bad = ~np.isfinite(magnitude) | (magnitude > MAX_COORDINATE)
    bad |= (magnitude != 0.0) & (magnitude < MIN_COORDINATE)
    return bad.any(axis=-1)


def flush_tiny(points, like=None):
    """``points`` (float64) with every nonzero coordinate below MIN_COORDINATE
    in magnitude read as 0, where the largest finite coordinate (of ``like``,
    by default of ``points``) is at least 2**52 times MIN_COORDINATE: such a
    coordinate is below one unit in the last place of that largest one, so no
    geometry the input can resolve moves.  Else (everything that small:
    rescaling helps) unchanged, to be rejected."""
    P = np.array(points, dtype=np.float64)
    magnitude = np.abs(P)
    scale = magnitude if like is None else np.abs(np.asarray(like, dtype=np.float64))
    finite = scale[np.isfinite(scale)]
    if finite.size and finite.max() >= 2.0**52 * MIN_COORDINATE:
        P[(magnitude != 0.0) & (magnitude < MIN_COORDINATE)] = 0.0
    return P


def out_of_range_message(point):
    """'(x, y) has a coordinate outside ...': the reason ``out_of_range`` flagged it."""
    return (
        f"{tuple(map(float, point))} has a coordinate outside the exact predicates' range "
        f"(0 or {MIN_COORDINATE:.3g} to {MAX_COORDINATE:.3g} in magnitude, finite); "
        "rescale the geometry"
    )


# --- error-free transformations -------------------------------------------------


@njit(cache=True, inline="always")
def two_sum(a, b):
    """x + y == a + b exactly, x = fl(a + b)."""
    x = a + b
    bv = x - a
    av = x - bv
    return x, (a - av) + (b - bv)


@njit(cache=True, inline="always")
def two_diff(a, b):
    """x + y == a - b exactly, x = fl(a - b)."""
    x = a - b
    bv = a - x
    av = x + bv
    return x, (a - av) + (bv - b)


@njit(cache=True, inline="always")
def _split(a):
    c = _SPLITTER * a
    hi = c - (c - a)
    return hi, a - hi


@njit(cache=True, inline="always")
def two_product(a, b):
    """x + y == a * b exactly, x = fl(a * b) (Dekker)."""
    x = a * b
    ahi, alo = _split(a)
    bhi, blo = _split(b)
    err = x - ahi * bhi
    err -= alo * bhi
    err -= ahi * blo
    return x, alo * blo - err


# --- expansion arithmetic (arrays of non-overlapping doubles, smallest first) -------


@njit(cache=True)
def expansion_sum(e, f):
    """Exact sum of two expansions; zero components are eliminated."""
    h = np.empty(e.size + f.size)
    n = 0
    i = 0
    j = 0
    q = 0.0
    first = True
    while i < e.size or j < f.size:
        # merge by increasing magnitude
        if j >= f.size or (i < e.size and abs(e[i]) <= abs(f[j])):
            g = e[i]
            i += 1
        else:
            g = f[j]
            j += 1
        if first:
            q = g
            first = False
            continue
        q, hh = two_sum(q, g)
        if hh != 0.0:
            h[n] = hh
            n += 1
    if not first and (q != 0.0 or n == 0):
        h[n] = q
        n += 1
    return h[:n]


@njit(cache=True)
def scale_expansion(e, b):
    """Exact product of an expansion and a double; zero components eliminated."""
    h = np.empty(2 * e.size)
    n = 0
    if e.size == 0:
        return h[:0]
    q, hh = two_product(e[0], b)
    if hh != 0.0:
        h[n] = hh
        n += 1
    for i in range(1, e.size):
        p1, p0 = two_product(e[i], b)
        s, hh = two_sum(q, p0)
        if hh != 0.0:
            h[n] = hh
            n += 1
        q, hh = two_sum(p1, s)
        if hh != 0.0:
            h[n] = hh
            n += 1
    if q != 0.0 or n == 0:
        h[n] = q
        n += 1
    return h[:n]


@njit(cache=True)
def expansion_product(e, f):
    """Exact product of two expansions (sum of scalings; rare slow path only)."""
    acc = np.zeros(1)
    for k in range(f.size):
        acc = expansion_sum(acc, scale_expansion(e, f[k]))
    return acc


@njit(cache=True)
def _diff_expansion(a, b):
    x, y = two_diff(a, b)
    out = np.empty(2)
    out[0] = y
    out[1] = x
    return out


@njit(cache=True)
def _negate(e):
    return -e


@njit(cache=True)
def _sign_value(e):
    """The most significant component: it carries the expansion's sign."""
    for k in range(e.size - 1, -1, -1):
        if e[k] != 0.0:
            return float(e[k])
    return 0.0


# --- orient2d ---------------------------------------------------------------------


@njit(cache=True)
def orient2d_exact(ax, ay, bx, by, cx, cy):
    """Exact (ax-cx)(by-cy) - (ay-cy)(bx-cx) as an expansion's leading term."""
    acx = _diff_expansion(ax, cx)
    bcy = _diff_expansion(by, cy)
    acy = _diff_expansion(ay, cy)
    bcx = _diff_expansion(bx, cx)
    left = expansion_product(acx, bcy)
    right = expansion_product(acy, bcx)
    return _sign_value(expansion_sum(left, _negate(right)))


@njit(cache=True)
def orient2d(ax, ay, bx, by, cx, cy):
    """Positive if a, b, c are counter-clockwise, negative if clockwise, zero if
    collinear.  The sign is exact; the magnitude approximates twice the signed
    area."""
    acx = ax - cx
    bcy = by - cy
    acy = ay - cy
    bcx = bx - cx
    detleft = acx * bcy
    detright = acy * bcx
    det = detleft - detright
    detsum = abs(detleft) + abs(detright)
    if abs(det) > CCW_ERRBOUND * detsum:
        return float(det)
    # A float difference is zero only if the coordinates are equal, so a product
    # with a zero factor is exactly zero; both zero means exactly collinear.
    if (acx == 0.0 or bcy == 0.0) and (acy == 0.0 or bcx == 0.0):
        return 0.0
    return orient2d_exact(ax, ay, bx, by, cx, cy)


# --- incircle ---------------------------------------------------------------------


@njit(cache=True)
def incircle_exact(ax, ay, bx, by, cx, cy, dx, dy):
    """Exact in-circle determinant (lifted to the paraboloid, relative to d)."""
    adx = _diff_expansion(ax, dx)
    ady = _diff_expansion(ay, dy)
    bdx = _diff_expansion(bx, dx)
    bdy = _diff_expansion(by, dy)
    cdx = _diff_expansion(cx, dx)
    cdy = _diff_expansion(cy, dy)
    bc = expansion_sum(expansion_product(bdx, cdy), _negate(expansion_product(cdx, bdy)))
    ca = expansion_sum(expansion_product(cdx, ady), _negate(expansion_product(adx, cdy)))
    ab = expansion_sum(expansion_product(adx, bdy), _negate(expansion_product(bdx, ady)))
    alift = expansion_sum(expansion_product(adx, adx), expansion_product(ady, ady))
    blift = expansion_sum(expansion_product(bdx, bdx), expansion_product(bdy, bdy))
    clift = expansion_sum(expansion_product(cdx, cdx), expansion_product(cdy, cdy))
    det = expansion_sum(expansion_product(alift, bc), expansion_product(blift, ca))
    det = expansion_sum(det, expansion_product(clift, ab))
    return _sign_value(det)


@njit(cache=True)
def incircle(ax, ay, bx, by, cx, cy, dx, dy):
    """Positive if d lies strictly inside the circle through the counter-clockwise
    points a, b, c; negative if outside; zero if the four are cocircular.  The
    sign is exact (reversed when a, b, c are clockwise)."""
    adx = ax - dx
    bdx = bx - dx
    cdx = cx - dx
    ady = ay - dy
    bdy = by - dy
    cdy = cy - dy
    bdxcdy = bdx * cdy
    cdxbdy = cdx * bdy
    alift = adx * adx + ady * ady
    cdxady = cdx * ady
    adxcdy = adx * cdy
    blift = bdx * bdx + bdy * bdy
    adxbdy = adx * bdy
    bdxady = bdx * ady
    clift = cdx * cdx + cdy * cdy
    det = alift * (bdxcdy - cdxbdy) + blift * (cdxady - adxcdy) + clift * (adxbdy - bdxady)
    permanent = (
        (abs(bdxcdy) + abs(cdxbdy)) * alift
        + (abs(cdxady) + abs(adxcdy)) * blift
        + (abs(adxbdy) + abs(bdxady)) * clift
    )
    if abs(det) > ICC_ERRBOUND * permanent:
        return float(det)
    return incircle_exact(ax, ay, bx, by, cx, cy, dx, dy)
