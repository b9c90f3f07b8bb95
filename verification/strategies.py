"""Hypothesis strategies for bubblemesh's verification suite.

Two families:

- :func:`domains`: random simple polygonal domains (a star-shaped outer loop
  with 0-4 non-overlapping holes: circles, convex and non-convex polygons),
  with uniform or strongly graded boundary spacing (hole spacing 1/10 to 2x the
  outer spacing).  Loops are given in "user order" (either orientation, no
  closing repeat), ready for ``Domain.from_loops``.
- :func:`kernel_points`: point sets for the triangulation kernel, including
  the degenerate inputs that break triangulators (grids, rotated grids, the
  integer points on x^2 + y^2 = 325^2, collinear runs, exact and 1-ulp
  duplicates, clusters, huge offsets and tiny extents).

Every strategy returns a small frozen case object whose ``repr`` prints the
exact coordinates (``float.__repr__`` round-trips) so a shrunk counterexample
can be pasted into an ``@example`` as is.  Nothing here imports bubblemesh.
"""

from __future__ import annotations

import math

import numpy as np
from hypothesis import settings
from hypothesis import strategies as st

# ---------------------------------------------------------------------------
# budget helper
# ---------------------------------------------------------------------------


def budget(n: int) -> settings:
    """Settings for an expensive test: ``n`` examples under the ``ci`` profile
    (max_examples=100), scaled in proportion under the other profiles
    (``nojit``: a fifth, ``thorough``: ten times)."""
    return settings(max_examples=max(1, round(n * settings.default.max_examples / 100)))


# ---------------------------------------------------------------------------
# case objects with exact reprs
# ---------------------------------------------------------------------------


def _exact(a: np.ndarray) -> str:
    return f"np.array({np.asarray(a).tolist()!r})"


class _Case:
    """Base for case objects: hypothesis prints them with their own repr."""

    def _repr_pretty_(self, p, cycle):  # used by hypothesis' pretty printer
        p.text(repr(self))


class PointCase(_Case):
    """A point set for the kernel; ``kind`` says how it was made."""

    def __init__(self, points, kind: str = ""):
        self.points = np.asarray(points, dtype=np.float64)
        self.kind = kind

    def __repr__(self) -> str:
        return f"PointCase({_exact(self.points)}, kind={self.kind!r})"


class DomainCase(_Case):
    """A random domain: ``loops[0]`` outer, then holes, each (n, 2) in the
    order a user would pass them; ``hole_points`` one point strictly inside
    each hole (its centre: holes are star-shaped around it)."""

    def __init__(self, loops, hole_points=None, kind: str = ""):
        self.loops = tuple(np.asarray(lp, dtype=np.float64) for lp in loops)
        hp = np.zeros((0, 2)) if hole_points is None else hole_points
        self.hole_points = np.asarray(hp, dtype=np.float64).reshape(-1, 2)
        self.kind = kind

    @property
    def points(self) -> np.ndarray:
        return np.vstack(self.loops)

    @property
    def n_holes(self) -> int:
        return len(self.loops) - 1

    def segments(self, ccw_outer: bool = True) -> np.ndarray:
        """Segments oriented with the domain on the left (outer CCW, holes
        CW), computed here from the loops and their exact signed areas; used
        to check the library's orientation independently."""
        out, offset = [], 0
        for k, loop in enumerate(self.loops):
            n = len(loop)
            idx = [(offset + i, offset + (i + 1) % n) for i in range(n)]
            area2 = _signed_area2_exact(loop)
            want_ccw = k == 0
            if (area2 > 0) != want_ccw:
                idx = [(b, a) for a, b in idx]
            out.extend(idx)
            offset += n
        return np.array(out, dtype=np.int64)

    def __repr__(self) -> str:
        loops = ", ".join(_exact(lp) for lp in self.loops)
        holes = _exact(self.hole_points)
        return f"DomainCase(loops=({loops},), hole_points={holes}, kind={self.kind!r})"


def _signed_area2_exact(loop) -> int:
    from fractions import Fraction

    pts = [(Fraction(x), Fraction(y)) for x, y in np.asarray(loop, dtype=float).tolist()]
    s = Fraction(0)
    for i in range(len(pts)):
        (x1, y1), (x2, y2) = pts[i], pts[(i + 1) % len(pts)]
        s += x1 * y2 - x2 * y1
    return (s > 0) - (s < 0)


# ---------------------------------------------------------------------------
# domains
# ---------------------------------------------------------------------------


def _refine(corners: np.ndarray, spacing: float) -> np.ndarray:
    """Subdivide each edge of the closed polygon into pieces <= spacing."""
    out = []
    n = len(corners)
    for i in range(n):
        p, q = corners[i], corners[(i + 1) % n]
        k = max(1, math.ceil(math.hypot(*(q - p)) / spacing))
        for j in range(k):
            out.append(p + (q - p) * (j / k))
    return np.array(out, dtype=np.float64)


def _star(center, radius, angles, factors) -> np.ndarray:
    a = np.asarray(angles, dtype=float)
    r = radius * np.asarray(factors, dtype=float)
    ring = np.column_stack([center[0] + r * np.cos(a), center[1] + r * np.sin(a)])
    # an angle of 1e-308 gives sin = 1e-308: nonzero coordinates below 2**-100 are
    # refused by design (test_domain/test_triangulation check that), so snap them
    ring[np.abs(ring) < 1e-30] = 0.0
    return ring


@st.composite
def _angles(draw, n: int):
    """n increasing angles: regular plus a jitter of at most 0.35 of a gap,
    limited so that every gap stays <= 0.8 pi (a star polygon around the
    centre then keeps the centre well inside)."""
    jitter = min(0.35, (0.4 * n - 1) / 2)
    phase = draw(st.floats(0, 2 * math.pi, allow_nan=False))
    jit = draw(st.lists(st.floats(-jitter, jitter), min_size=n, max_size=n))
    gap = 2 * math.pi / n
    return [phase + gap * (i + j) for i, j in enumerate(jit)]


def _min_edge_distance(poly: np.ndarray, c=(0.0, 0.0)) -> float:
    c = np.asarray(c, dtype=float)
    best = math.inf
    for i in range(len(poly)):
        p, q = poly[i], poly[(i + 1) % len(poly)]
        d = q - p
        t = min(1.0, max(0.0, float(np.dot(c - p, d) / np.dot(d, d))))
        best = min(best, float(np.hypot(*(p + t * d - c))))
    return best


@st.composite
def _hole(draw, center, radius, spacing):
    shape = draw(st.sampled_from(["circle", "convex", "star"]))
    if shape == "circle":
        m = max(6, math.ceil(2 * math.pi * radius / spacing))
        ang = [2 * math.pi * i / m for i in range(m)]
        pts = _star(center, radius, ang, [1.0] * m)
    else:
        n = draw(st.integers(3, 8))
        ang = draw(_angles(n))
        lo = 1.0 if shape == "convex" else 0.35
        fac = draw(st.lists(st.floats(lo, 1.0), min_size=n, max_size=n))
        pts = _refine(_star(center, radius, ang, fac), spacing)
    return shape, pts


@st.composite
def domains(
    draw, max_holes: int = 4, max_corners: int = 12, graded: bool = True, min_spacing: float = 0.15
):
    """A random simple domain as a :class:`DomainCase`.

    Outer loop: star-shaped around the origin (3..max_corners corners at
    jittered angles, radii 0.55..1), edges refined to spacing h.  Holes: up to
    ``max_holes`` disjoint ones, each inside its own disk placed in the
    outer loop's inscribed disk (so they cannot touch each other or the outer
    loop), refined to spacing h * g with g in [0.1, 2] when ``graded``.
    """
    n = draw(st.integers(3, max_corners))
    ang = draw(_angles(n))
    fac = draw(st.lists(st.floats(0.55, 1.0), min_size=n, max_size=n))
    corners = _star((0.0, 0.0), 1.0, ang, fac)
    h = draw(st.floats(min_spacing, 0.5))
    outer = _refine(corners, h)
    rho = 0.95 * _min_edge_distance(corners)
    k = draw(st.integers(0, max_holes))
    loops, centers, kinds = [outer], [], [f"outer n={n} h={h:.3g}"]
    if k:
        phase = draw(st.floats(0, 2 * math.pi))
        if k == 1:
            ring_r, r_max = 0.0, 0.6 * rho
        else:  # centres on a ring: neighbours are rho*sin(pi/k) apart
            ring_r = rho / 2
            r_max = 0.85 * min(rho / 2, 0.5 * rho * math.sin(math.pi / k))
        for i in range(k):
            c = (
                ring_r * math.cos(phase + 2 * math.pi * i / k),
                ring_r * math.sin(phase + 2 * math.pi * i / k),
            )
            r = r_max * draw(st.floats(0.4, 1.0))
            g = draw(st.floats(0.1, 2.0)) if graded else 1.0
            shape, pts = draw(_hole(c, r, h * g))
            loops.append(pts)
            centers.append(c)
            kinds.append(f"{shape} hole r={r:.3g} g={g:.3g}")
    # user order: each loop in either orientation, starting anywhere
    out = []
    for lp in loops:
        if draw(st.booleans()):
            lp = lp[::-1]
        s = draw(st.integers(0, len(lp) - 1))
        out.append(np.ascontiguousarray(np.roll(lp, -s, axis=0)))
    return DomainCase(
        loops=tuple(out),
        hole_points=np.array(centers, dtype=np.float64).reshape(-1, 2),
        kind="; ".join(kinds),
    )


def disk(n: int = 48, radius: float = 1.0) -> DomainCase:
    """A disk with n equally spaced boundary nodes (the paper's Fig. 3)."""
    ang = [2 * math.pi * i / n for i in range(n)]
    return DomainCase(loops=(_star((0.0, 0.0), radius, ang, [1.0] * n),), kind=f"disk n={n}")


def square_with_hole(n_side: int = 10, n_hole: int = 24) -> DomainCase:
    """Unit square [-1,1]^2 with a circular hole of radius 0.4 (paper Fig. 4)."""
    t = np.arange(n_side) / n_side * 2 - 1
    one = np.ones(n_side)
    sq = np.vstack(
        [
            np.column_stack([t, -one]),
            np.column_stack([one, t]),
            np.column_stack([-t, one]),
            np.column_stack([-one, -t]),
        ]
    )
    ang = [-2 * math.pi * i / n_hole for i in range(n_hole)]
    hole = _star((0.0, 0.0), 0.4, ang, [1.0] * n_hole)
    return DomainCase(loops=(sq, hole), hole_points=np.zeros((1, 2)), kind="square with hole")


# ---------------------------------------------------------------------------
# kernel point sets
# ---------------------------------------------------------------------------

#: every integer point on the circle x^2 + y^2 = 325^2 (many cocircular points)
CIRCLE_325 = np.array(
    sorted(
        {
            (x, s * y)
            for x in range(-325, 326)
            for y in [math.isqrt(325**2 - x * x)]
            for s in (1, -1)
            if x * x + y * y == 325**2
        }
    ),
    dtype=np.float64,
)

_coord = st.integers(-(2**20), 2**20)


@st.composite
def general_points(draw, min_size: int = 3, max_size: int = 60):
    """Random dyadic points (k / 1024, |k| <= 2^20): in general position almost
    surely; exact under translation by 2^k (k <= 30) and scaling by 2^k."""
    n = draw(st.integers(min_size, max_size))
    xy = draw(st.lists(st.tuples(_coord, _coord), min_size=n, max_size=n, unique=True))
    return PointCase(np.array(xy, dtype=np.float64) / 1024.0, kind="general")


@st.composite
def grid_points(draw):
    """A regular n x m grid (all unit squares are cocircular quadruples),
    optionally rotated: exactly by the Pythagorean rotation (3/5, 4/5) of the
    integer lattice (still exactly cocircular) or by a float angle (nearly
    cocircular: the exact predicates must decide)."""
    n, m = draw(st.integers(2, 7)), draw(st.integers(2, 7))
    i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
    i, j = i.ravel().astype(float), j.ravel().astype(float)
    rot = draw(st.sampled_from(["none", "pythagorean", "float"]))
    if rot == "none":
        xy = np.column_stack([i, j])
    elif rot == "pythagorean":
        xy = np.column_stack([3 * i - 4 * j, 4 * i + 3 * j])
    else:
        th = draw(st.floats(0.01, 1.5))
        xy = np.column_stack(
            [i * math.cos(th) - j * math.sin(th), i * math.sin(th) + j * math.cos(th)]
        )
    s = draw(st.sampled_from([1.0, 0.1, 2.0**-3]))
    return PointCase(xy * s, kind=f"grid {n}x{m} rot={rot} s={s}")


@st.composite
def circle_lattice_points(draw):
    """A subset (>= 3) of the integer points on x^2 + y^2 = 325^2, possibly
    with the centre and a few random interior lattice points."""
    k = len(CIRCLE_325)
    idx = draw(st.lists(st.integers(0, k - 1), min_size=3, max_size=k, unique=True))
    pts = [CIRCLE_325[sorted(idx)]]
    if draw(st.booleans()):
        pts.append(np.zeros((1, 2)))
    extra = draw(st.lists(st.tuples(st.integers(-200, 200), st.integers(-200, 200)), max_size=5))
    if extra:
        pts.append(np.array(extra, dtype=float))
    return PointCase(np.vstack(pts), kind=f"circle 325 ({len(idx)} on circle)")


@st.composite
def collinear_points(draw, off_line: bool = True):
    """A run of points a + i*d on one line (integer a, d), plus 0-3 points off
    it (none when off_line=False: then the input is degenerate)."""
    k = draw(st.integers(2, 12))
    a = np.array(draw(st.tuples(st.integers(-50, 50), st.integers(-50, 50))), dtype=float)
    d = np.array(
        draw(st.tuples(st.integers(-5, 5), st.integers(-5, 5)).filter(lambda t: t != (0, 0))),
        dtype=float,
    )
    pts = [a + d * i for i in range(k)]
    if off_line:
        extra = draw(st.lists(st.tuples(st.integers(-60, 60), st.integers(-60, 60)), max_size=3))
        pts += [np.array(e, dtype=float) for e in extra]
    return PointCase(np.array(pts), kind=f"collinear run of {k}")


@st.composite
def clustered_points(draw):
    """A few clusters of points 1e-9..1e-6 apart around far-apart centres."""
    c = draw(st.integers(1, 4))
    size = draw(st.sampled_from([1e-9, 1e-7, 1e-6]))
    pts = []
    for _ in range(c):
        cx, cy = draw(_coord) / 1024.0, draw(_coord) / 1024.0
        m = draw(st.integers(1, 8))
        offs = draw(
            st.lists(
                st.tuples(st.integers(-1000, 1000), st.integers(-1000, 1000)),
                min_size=m,
                max_size=m,
            )
        )
        pts += [(cx + size * u / 1000, cy + size * v / 1000) for u, v in offs]
    return PointCase(np.array(pts, dtype=np.float64), kind=f"{c} clusters of size {size}")


@st.composite
def _with_duplicates(draw, base):
    case = draw(base)
    p = case.points
    k = draw(st.integers(1, max(1, len(p) // 2)))
    idx = draw(st.lists(st.integers(0, len(p) - 1), min_size=k, max_size=k))
    out = np.vstack([p, p[idx]])
    perm = draw(st.permutations(range(len(out))))
    return PointCase(out[list(perm)], kind=case.kind + f" + {k} exact duplicates")


@st.composite
def _with_near_duplicates(draw, base):
    """Copies of some points moved by 1 ulp in x and/or y (np.nextafter).
    Zero coordinates are not moved (their next float is subnormal, outside
    the range where the library promises exact predicates; see
    test_triangulation.test_delaunay_refuses_coordinates_outside_the_exact_range)."""
    case = draw(base)
    p = case.points
    k = draw(st.integers(1, max(1, len(p) // 2)))
    idx = draw(st.lists(st.integers(0, len(p) - 1), min_size=k, max_size=k))
    near = p[idx].copy()
    for row in near:
        axis = draw(st.sampled_from([0, 1, 2]))
        towards = draw(st.sampled_from([math.inf, -math.inf]))
        for a in (0, 1):
            if axis in (a, 2) and row[a] != 0:
                row[a] = np.nextafter(row[a], towards)
    return PointCase(np.vstack([p, near]), kind=case.kind + f" + {k} near-duplicates (1 ulp)")


@st.composite
def _transformed(draw, base):
    """Huge offset (+1e8) or tiny extent (x 1e-8) applied to a base set."""
    case = draw(base)
    how = draw(st.sampled_from(["offset 1e8", "scale 1e-8", "scale 1e-8 offset 1"]))
    p = case.points
    if how == "offset 1e8":
        p = p + 1e8
    elif how == "scale 1e-8":
        p = p * 1e-8
    else:
        p = p * 1e-8 + 1.0
    return PointCase(p, kind=case.kind + f" then {how}")


def degenerate_points():
    """Degenerate families only (grids, lattice circle, collinear runs...)."""
    base = st.one_of(grid_points(), circle_lattice_points(), collinear_points(), clustered_points())
    return st.one_of(base, _with_duplicates(base), _with_near_duplicates(base), _transformed(base))


def kernel_points():
    """Any point set the kernel should handle (may be degenerate, may contain
    duplicates, may be all collinear or have < 3 distinct points: then the
    library must raise GeometryError)."""
    base = st.one_of(
        general_points(max_size=40),
        grid_points(),
        circle_lattice_points(),
        collinear_points(),
        clustered_points(),
    )
    return st.one_of(
        base,
        _with_duplicates(base),
        _with_near_duplicates(base),
        _transformed(base),
        collinear_points(off_line=False),
    )


# ---------------------------------------------------------------------------
# predicate inputs
# ---------------------------------------------------------------------------

finite = st.floats(allow_nan=False, allow_infinity=False, min_value=-1e30, max_value=1e30)


@st.composite
def near_collinear_triples(draw):
    """(a, b, c) with c moved a few ulps off the line through a and b: the
    classic input that defeats float orientation tests."""
    a = (draw(st.sampled_from([0.5, 0.1, 12.0, 1e8])), draw(st.sampled_from([0.5, 0.3, 12.0, 1e8])))
    t = draw(st.sampled_from([2.0, 3.0, 0.5, 1.5, 1e3]))
    d = (draw(st.sampled_from([1.0, 0.3, 7.0])), draw(st.sampled_from([1.0, 0.7, 7.0])))
    b = (a[0] + d[0], a[1] + d[1])
    c = [a[0] + t * d[0], a[1] + t * d[1]]
    for _ in range(draw(st.integers(0, 3))):
        axis = draw(st.integers(0, 1))
        c[axis] = float(np.nextafter(c[axis], draw(st.sampled_from([math.inf, -math.inf]))))
    order = draw(st.permutations([a, b, tuple(c)]))
    return tuple(order)


@st.composite
def cocircular_quadruples(draw, perturb: bool = True):
    """Four of the integer points on x^2 + y^2 = 325^2 (exactly cocircular),
    optionally the fourth moved by 1-3 ulps (nearly cocircular), optionally
    scaled by 2^-k (still exact).  A zero coordinate is not moved (its next
    float is subnormal, outside the predicates' documented range; that case
    is test_predicates.test_subnormal_quadruple_is_refused_by_the_kernel)."""
    idx = draw(st.lists(st.integers(0, len(CIRCLE_325) - 1), min_size=4, max_size=4, unique=True))
    pts = [list(CIRCLE_325[i]) for i in idx]
    if perturb and draw(st.booleans()):
        for _ in range(draw(st.integers(1, 3))):
            axis = draw(st.integers(0, 1))
            if pts[3][axis] == 0.0:
                axis = 1 - axis
            pts[3][axis] = float(
                np.nextafter(pts[3][axis], draw(st.sampled_from([math.inf, -math.inf])))
            )
    k = draw(st.integers(-12, 12))
    return tuple((math.ldexp(x, k), math.ldexp(y, k)) for x, y in pts)
