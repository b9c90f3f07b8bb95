"""Quality study of the robust mesher bm.mesh against Triangle -pq30 and Gmsh
Frontal-Delaunay (Mesh.Algorithm=6) on the same input at matched element counts.

    python -m bubblemesh.studies.quality [--data DIR] [--out DIR] [--big]
                                         [--random N [--seed S]] [--timings]

Gmsh and Triangle get bm's refined boundary nodes; Gmsh also bm's size field
(scaled until the counts match within 1%).  ``--data``: a folder with
Triangle's example A.poly and double_hex3.poly (skipped if absent); ``--big``
adds the benchmark's 100k-element uniform disk (Gmsh with its own constant
size).  Prints, per case and mesher, the element count and its ratio to the
count the size field asks for (the integral of its element density over the
domain, :func:`predicted_count`), the minimum and mean radius ratio, the count
below 0.7 and how many of those do not touch an input corner too sharp for 0.7,
bubblemesh.verify's verdict, the winners, and on how many cases bm meets each
of the project's targets; ``--out`` writes that table as quality_vs_gmsh.csv.
Then the iteration sweeps, the size test, (``--random N``) N random
corner-only polygons against Gmsh and Triangle (random_vs_gmsh.csv with
``--out``), and (``--timings``) bm against Gmsh's time at 100k elements.
"""

from __future__ import annotations

import argparse
import math
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import bubblemesh as bm
from bubblemesh.domain import _loop_areas
from bubblemesh.pipeline import sharp_corner_flags
from bubblemesh.quality import radius_ratio
from bubblemesh.studies import geometry


def _square(side, spacing, lo=0.0):
    n = max(1, int(round(side / spacing)))
    s = lo + np.linspace(0, side, n + 1)[:-1]
    e = lo + side
    return np.concatenate([np.column_stack([s, 0 * s + lo]), np.column_stack([0 * s + e, s]),
                           np.column_stack([2 * lo + side - s + 0 * s, 0 * s + e])[::1],
                           np.column_stack([0 * s + lo, 2 * lo + side - s])])


def _circle(c, r, h):
    n = max(8, int(math.ceil(2 * math.pi * r / h)))
    t = np.linspace(0, 2 * math.pi, n, endpoint=False)
    return np.column_stack([c[0] + r * np.cos(t), c[1] + r * np.sin(t)])


def _random_polygon(rng, holes):
    n = int(rng.integers(4, 10))
    ang = 2 * math.pi * np.arange(n) / n + rng.uniform(-0.3, 0.3, n) * 2 * math.pi / n
    r = rng.uniform(0.6, 1.0, n)
    loops = [np.column_stack([r * np.cos(ang), r * np.sin(ang)])]
    for k in range(holes):
        c = (0.0, 0.0) if holes == 1 else (0.28 * math.cos(2 * math.pi * k / holes),
                                           0.28 * math.sin(2 * math.pi * k / holes))
        m = int(rng.integers(3, 5))
        a = 2 * math.pi * np.arange(m) / m + rng.uniform(0, 1)
        loops.append(np.column_stack([c[0] + 0.1 * np.cos(a), c[1] + 0.1 * np.sin(a)]))
    return loops


def _paper_loops():
    """The four paper cases' loops, as shipped with the package."""
    from .case import paper_cases

    return {name: [np.asarray(lp) for lp in case.loops] for name, case in paper_cases().items()}


def triangle_data() -> Path | None:
    """The folder of example .poly files that the ``triangle`` package ships
    (A.poly, double_hex3.poly, ...), or None without it."""
    try:
        import triangle
    except ImportError:
        return None
    folder = Path(triangle.__file__).parent / "data"
    return folder if folder.is_dir() else None


def cases(data: Path | None):
    """(name, loops, bm.mesh keyword arguments): corner-only inputs get
    max_area = area / 200 (the gear area / 1000), the others their own
    spacing.  ``data``: the folder of Triangle's A.poly and double_hex3.poly,
    by default the ``triangle`` package's (:func:`triangle_data`)."""
    data = data if data is not None else triangle_data()
    for name, loops in _paper_loops().items():
        yield name, loops, {}
    per200 = "per200"
    yield "L-shape", [np.array([(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)], float)], per200
    t = np.linspace(0, math.pi, 33)
    yield "half-disk", [np.column_stack([np.cos(t), np.sin(t)])], per200
    for name in ("A", "double_hex3"):
        path = None if data is None else data / f"{name}.poly"
        if path is not None and path.exists():
            d = bm.Domain.from_poly(path)
            yield f"{name}.poly", [np.asarray(d.points)[ix] for ix in d.loops], per200
    yield "square-square-hole", [np.array([(0, 0), (1, 0), (1, 1), (0, 1)], float),
                                 np.array([(.4, .4), (.6, .4), (.6, .6), (.4, .6)], float)], per200
    yield "graded square+hole", [_square(10.0, 0.5), _circle((5, 5), 0.05, 0.005)], {}
    yield "perforated plate", [_square(10.0, 0.25)] + [
        _circle((2 + 2 * i, 2 + 2 * j), 0.4, 0.05) for i in range(4) for j in range(4)], {}
    yield "channel+cylinder", [np.array([(0, 0), (20, 0), (20, 1), (0, 1)], float),
                               _circle((2.0, 0.5), 0.15, 0.02)], {}
    yield "airfoil in channel", [geometry.rectangle(-2.0, -1.5, 4.0, 1.5, 0.15),
                                 geometry.naca_airfoil(0.12, 120)], {}
    yield "gear", [geometry.gear(12, 1.0, 1.2, 0.02),
                   geometry.clockwise(_circle((0, 0), 0.35, 0.02))], {}
    teeth = geometry.gear(12, 1.0, 1.2, 10.0)  # corners only: the walls split finer than h
    yield "gear, corners only", [teeth], {"max_area": geometry.signed_area(teeth) / 1000}
    yield "slotted plate", [geometry.rectangle(0.0, 0.0, 6.0, 3.0, 0.1),
                            geometry.slot((1.5, 1.0), 1.0, 0.2, 0.04),
                            geometry.slot((4.5, 1.0), 1.0, 0.2, 0.04),
                            geometry.slot((3.0, 2.2), 2.0, 0.15, 0.03),
                            geometry.clockwise(geometry.rectangle(2.6, 0.5, 3.4, 0.9, 0.05))], {}
    yield "graded L-shape", [geometry.graded_polygon(
        [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)], (1, 1), 0.01, 0.1, 0.3)], {}
    yield "square+10 random holes", [_square(10.0, 0.5)] + _random_holes(10, seed=3), {}
    yield "20-degree sector", [geometry.sector(1.0, math.radians(20.0), 0.01)], {}


def _random_holes(count, seed):
    """``count`` disjoint circular holes (radius 0.2-0.8, spacing 0.03-0.2,
    at least 0.4 apart) in the square (1, 9)^2, clockwise."""
    rng = np.random.default_rng(seed)
    holes, placed = [], []
    while len(holes) < count:
        c, r = rng.uniform(1.0, 9.0, 2), rng.uniform(0.2, 0.8)
        if all(np.hypot(*(c - c2)) > r + r2 + 0.4 for c2, r2 in placed):
            placed.append((c, r))
            holes.append(geometry.clockwise(_circle(c, r, rng.uniform(0.03, 0.2))))
    return holes


def _stats(points, triangles):
    q = radius_ratio(np.asarray(points), np.asarray(triangles))
    return len(triangles), float(q.min()), float(q.mean()), int(np.sum(q < 0.7))


def measure(domain, points, triangles):
    """One mesh of ``domain``: element count N, min and mean radius ratio,
    count below 0.7, that count without the elements touching an input corner
    sharper than SHARP_ANGLE, and bubblemesh.verify's exact verdict on
    validity and conformity to the input boundary and its interior
    constraints (``valid``)."""
    from bubblemesh import verify

    p = np.asarray(points, dtype=np.float64)[:, :2]
    t = np.asarray(triangles, dtype=np.int64)
    q = radius_ratio(p, t)
    poor = q < 0.7
    at_sharp = sharp_corner_flags(domain, p)[t].any(axis=1)
    holes = domain.hole_points if len(domain.hole_points) else None
    seg, interior = np.asarray(domain.segments), np.asarray(domain.interior, bool)
    once = ~interior | (seg[:, 0] < seg[:, 1])  # a constraint is listed both ways
    report = verify.check(p, t, seg[once], domain.points, holes=holes,
                          sides=np.where(interior[once], 2, 1), delaunay=False)
    valid = report.ok
    return dict(N=len(t), min=float(q.min()), mean=float(q.mean()), below=int(poor.sum()),
                below_off_sharp=int((poor & ~at_sharp).sum()), valid=bool(valid))


# The element density of a size field: equilateral triangles of side h per area.
ELEMENT_DENSITY = 4.0 / math.sqrt(3.0)
_S15 = math.sqrt(15.0)
# Dunavant's degree-5 rule on a triangle: 7 interior points, positive weights summing to 1.
_RULE_POINTS = np.array(
    [[1 / 3, 1 / 3, 1 / 3]]
    + [np.roll([(9 + 2 * _S15) / 21, (6 - _S15) / 21, (6 - _S15) / 21], k) for k in range(3)]
    + [np.roll([(9 - 2 * _S15) / 21, (6 + _S15) / 21, (6 + _S15) / 21], k) for k in range(3)])
_RULE_WEIGHTS = np.array([9 / 40] + [(155 - _S15) / 1200] * 3 + [(155 + _S15) / 1200] * 3)
# A piece is "small against h" when its longest edge is at most h at its sample
# points: the field's gradation g < 1 bounds how far h can dip between them.
_PIECE_OVER_H = 1.0
_MAX_ROUNDS = 400
_MAX_PIECES = 2_000_000  # pieces cut in one round: bounds a round's arrays
COUNT_TOL = 1e-3  # the counts judged against a 5% target: a thousandth is ample


@dataclass(frozen=True)
class CountPrediction:
    """The element count a size field asks for on a domain: ``count`` =
    integral of 4 / (sqrt(3) h(x)^2) over the domain, ``error`` the estimated
    absolute error (sum over the pieces of |one-piece rule - two-halves rule|,
    the error of the coarser rule, so an upper estimate), ``pieces`` how many
    triangles the domain was cut into."""

    count: float
    error: float
    pieces: int


def _rule(corners, size):
    """The degree-5 rule of the element density over each triangle of
    ``corners`` (M, 3, 2): (integrals (M,), smallest h at the rule's points (M,))."""
    xy = np.einsum("qk,mkd->mqd", _RULE_POINTS, corners).reshape(-1, 2)
    h = np.asarray(size(xy), dtype=np.float64).reshape(len(corners), len(_RULE_WEIGHTS))
    u, v = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    area = 0.5 * np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0])
    return area * (ELEMENT_DENSITY * _RULE_WEIGHTS / h**2).sum(axis=1), h.min(axis=1)


def _bisect(corners):
    """Each triangle of ``corners`` (M, 3, 2) cut at the midpoint of its longest
    edge (longest-edge bisection keeps the pieces' angles bounded and shortens
    slivers fastest): (halves (2M, 3, 2), pairs adjacent; longest edges (M,))."""
    edges = np.stack([np.linalg.norm(corners[:, (k + 1) % 3] - corners[:, (k + 2) % 3], axis=1)
                      for k in range(3)], axis=1)
    k = edges.argmax(axis=1)  # the vertex opposite the longest edge
    rows = np.arange(len(corners))
    apex, b, c = (corners[rows, (k + j) % 3] for j in range(3))
    mid = 0.5 * (b + c)
    halves = np.stack([np.stack([apex, b, mid], 1), np.stack([apex, mid, c], 1)], axis=1)
    return halves.reshape(-1, 3, 2), edges.max(axis=1)


def predicted_count(domain, size, tol=1e-4) -> CountPrediction:
    """The elements a size field asks for on ``domain``: the integral of the
    element density 4 / (sqrt(3) h(x)^2) over the domain, independent of any
    mesh being judged.

    The domain's constrained Delaunay triangulation is cut by longest-edge
    bisection, each piece integrated by a degree-5 rule and again as its two
    halves; pieces are cut, largest difference first, until every piece is
    small against h and the differences sum to at most ``tol`` of the total.
    ``size`` maps (n, 2) points to (n,) sizes (a SizeField, any h(xy)).
    Raises RuntimeError if that does not happen in a bounded number of rounds
    with at most _MAX_PIECES pieces cut in each (a field far finer than the
    domain somewhere, say a boundary segment a thousandth of the size)."""
    from bubblemesh.triangulation import constrained_delaunay

    points = np.asarray(domain.points, dtype=np.float64)
    triangles, _ = constrained_delaunay(points, domain.segments)
    pieces = points[triangles]
    whole, hmin = _rule(pieces, size)
    settled_value = settled_error = 0.0
    settled = 0
    for _ in range(_MAX_ROUNDS):
        halves, longest = _bisect(pieces)
        half_values, half_hmin = _rule(halves, size)
        split = half_values.reshape(-1, 2).sum(axis=1)
        difference = np.abs(split - whole)
        total = settled_value + float(split.sum())
        error = settled_error + float(difference.sum())
        cut = longest > _PIECE_OVER_H * hmin
        if error <= tol * total and not cut.any():
            return CountPrediction(total, error, settled + 2 * len(pieces))
        if error > tol * total:  # once within, more cuts by error only chase the settled part
            cut |= _largest_differences(difference, error - 0.5 * tol * total)
        if 2 * int(cut.sum()) > _MAX_PIECES:
            raise RuntimeError(f"predicted_count: over {_MAX_PIECES} pieces to cut (estimate "
                               f"{total:.6g} +- {error:.3g})")
        settled_value += float(split[~cut].sum())
        settled_error += float(difference[~cut].sum())
        settled += 2 * int((~cut).sum())
        pieces = halves.reshape(-1, 2, 3, 2)[cut].reshape(-1, 3, 2)
        whole = half_values.reshape(-1, 2)[cut].reshape(-1)
        hmin = half_hmin.reshape(-1, 2)[cut].reshape(-1)
    raise RuntimeError(f"predicted_count: not within {tol:g} after {_MAX_ROUNDS} rounds "
                       f"(estimate {total:.6g} +- {error:.3g})")


def _largest_differences(difference, excess):
    """Mask of the fewest pieces, largest difference first, whose differences
    sum to at least ``excess`` (none when excess <= 0)."""
    mask = np.zeros(len(difference), dtype=bool)
    if excess <= 0.0:
        return mask
    order = np.argsort(difference)[::-1]
    k = int(np.searchsorted(np.cumsum(difference[order]), excess)) + 1
    mask[order[:k]] = True
    return mask


def run_triangle(mesh, hole_points, count):
    """Triangle -pq30 on bm's refined boundary, the area bound tuned to count."""
    import triangle

    area = mesh.domain.area / max(count, 2) * 1.0
    pts = dict(vertices=np.array(mesh.domain.points), segments=np.array(mesh.domain.segments))
    if len(hole_points):
        pts["holes"] = np.array(hole_points)
    for _ in range(5):  # match the element count
        # positional: Triangle would read the "e" of 3e-05 as its -e switch
        out = triangle.triangulate(pts, f"pq30a{np.format_float_positional(area)}Q")
        n = len(out["triangles"])
        if abs(n - count) < 0.03 * count:
            break
        area *= n / count
    return out["vertices"], out["triangles"]


# a peer's count is matched this closely where its steps allow: on small meshes its
# mean moves with the count
COUNT_MATCH = 0.01

# Gmsh's Laplacian smoothing steps after meshing (its default is 1; more lifts its
# mean radius ratio by up to 0.005 on the table's domains: the stronger peer)
GMSH_SMOOTHING = 10


def run_gmsh(mesh, field, count, algorithm=6, runs=None):
    """Gmsh (Frontal-Delaunay by default, GMSH_SMOOTHING smoothing steps) on
    bm's refined boundary nodes, no further boundary splits, sizes from bm's
    size field (a Python callback) times a factor tuned until the element
    count is within COUNT_MATCH of count (else the closest of 12 runs).  Returns
    (points, triangles, seconds of that run); every run is appended to
    ``runs`` when it is a list."""
    return _tuned(count, lambda scale: _gmsh_once(mesh, field, scale, algorithm), runs)


def run_gmsh_uniform(mesh, size, count, algorithm=6, runs=None):
    """:func:`run_gmsh` for a constant size: Gmsh's own Mesh.MeshSizeMin =
    MeshSizeMax = size times the tuned factor (a Python callback costs more
    than the meshing at 100k elements)."""
    return _tuned(count, lambda scale: _gmsh_once(mesh, float(size), scale, algorithm), runs)


def _tuned(count, run, runs=None):
    """The run(scale) -> (points, triangles, seconds) whose count is within
    COUNT_MATCH of ``count`` (else the closest of 12): scale by the square
    root of the count's ratio, bisecting once the target is bracketed.
    Every run is appended to ``runs`` when it is a list."""
    scale, low, high, best = 1.0, 0.0, math.inf, None
    for _ in range(12):
        pts, tri, seconds = run(scale)
        if runs is not None:
            runs.append((pts, tri, seconds))
        if best is None or abs(len(tri) - count) < abs(len(best[1]) - count):
            best = (pts, tri, seconds)
        if abs(len(tri) - count) <= COUNT_MATCH * count:
            break
        # more elements than asked: a larger scale; bisect once bracketed
        if len(tri) > count:
            low = scale
        else:
            high = scale
        scale *= math.sqrt(len(tri) / count)
        if low > 0.0 and high < math.inf and not low < scale < high:
            scale = 0.5 * (low + high)
    assert best is not None
    return best


def _gmsh_once(mesh, size, scale, algorithm):
    """One Gmsh run on ``mesh.domain``'s nodes with ``size`` (a number, or a
    callable h(xy)) times ``scale``."""
    import gmsh

    t0 = time.perf_counter()
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("m")
    _gmsh_domain(gmsh, mesh.domain)
    for _, tag in gmsh.model.getEntities(1):
        gmsh.model.mesh.setTransfiniteCurve(tag, 2)  # keep the given boundary nodes
    if callable(size):
        gmsh.model.mesh.setSizeCallback(
            lambda dim, tag, x, y, z, lc: float(size(np.array([[x, y]]))[0]) * scale)
    else:
        gmsh.option.setNumber("Mesh.MeshSizeMin", size * scale)
        gmsh.option.setNumber("Mesh.MeshSizeMax", size * scale)
    for option in ("MeshSizeExtendFromBoundary", "MeshSizeFromPoints", "MeshSizeFromCurvature"):
        gmsh.option.setNumber(f"Mesh.{option}", 0)
    gmsh.option.setNumber("Mesh.Algorithm", algorithm)
    gmsh.option.setNumber("Mesh.Smoothing", GMSH_SMOOTHING)
    gmsh.model.mesh.generate(2)
    tags, xyz, _ = gmsh.model.mesh.getNodes()
    _, _, conn = gmsh.model.mesh.getElements(2)
    gmsh.finalize()
    seconds = time.perf_counter() - t0
    if not conn:
        raise RuntimeError("Gmsh made no triangles on this domain")
    index = np.zeros(int(tags.max()) + 1, np.int64)
    index[tags.astype(np.int64)] = np.arange(len(tags))
    tri = index[np.asarray(conn[0], np.int64).reshape(-1, 3)]
    pts = xyz.reshape(-1, 3)[:, :2]
    return pts, tri, seconds


def _gmsh_domain(gmsh, domain):
    """``domain`` as Gmsh geometry: a plane surface bounded by the closed
    chains of its boundary segments (the largest the outer one), its interior
    constraints embedded as lines and its free points as points, so that
    Gmsh keeps every node and segment bm keeps."""
    P = np.asarray(domain.points)
    segments = np.asarray(domain.segments)
    interior = np.asarray(domain.interior)
    points, lines = {}, {}

    def point(i):
        if i not in points:
            points[i] = gmsh.model.geo.addPoint(*P[i], 0.0)
        return points[i]

    def line(a, b):  # the signed tag of the line a -> b, made a -> b if new
        if (b, a) in lines:
            return -lines[(b, a)]
        if (a, b) not in lines:
            lines[(a, b)] = gmsh.model.geo.addLine(point(a), point(b))
        return lines[(a, b)]

    loops = _cycles(segments[~interior])
    offsets = np.cumsum([0] + [len(c) for c in loops])
    areas = _loop_areas(np.vstack([P[c] for c in loops]), offsets)
    outer = int(np.argmax(areas))
    loops.insert(0, loops.pop(outer))  # the others keep the domain's order
    curve_loops = [gmsh.model.geo.addCurveLoop([line(c[k], c[(k + 1) % len(c)])
                                                for k in range(len(c))]) for c in loops]
    surface = gmsh.model.geo.addPlaneSurface(curve_loops)
    embedded = [line(int(a), int(b)) for a, b in segments[interior] if a < b]
    free = np.setdiff1d(np.arange(len(P)), segments.ravel())
    free_tags = [point(int(i)) for i in free]
    gmsh.model.geo.synchronize()
    if embedded:
        gmsh.model.mesh.embed(1, [abs(t) for t in embedded], 2, surface)
    if free_tags:
        gmsh.model.mesh.embed(0, free_tags, 2, surface)


def _cycles(segments):
    """The closed chains of directed ``segments`` (each used once), as node lists."""
    leaving = {}
    for k, (a, _) in enumerate(segments.tolist()):
        leaving.setdefault(a, []).append(k)
    used = np.zeros(len(segments), bool)
    cycles = []
    for first in range(len(segments)):
        if used[first]:
            continue
        chain, k = [], first
        while not used[k]:
            used[k] = True
            a, b = segments[k]
            chain.append(int(a))
            k = next((j for j in leaving.get(int(b), ()) if not used[j]), first)
        cycles.append(chain)
    return cycles


def _other_side(runs, closest, count):
    """Where Gmsh's closest count misses ``count`` by more than MATCHED: of
    ``runs``, the one closest to count on its other side (its count jumped
    across count as the scale changed), else None."""
    if abs(closest - count) <= MATCHED * count:
        return None
    side = [r for r in runs if (len(r[1]) - count) * (closest - count) < 0]
    return min(side, key=lambda r: abs(len(r[1]) - count)) if side else None


def _winners(rows, key, best):
    value = best(r[key] for r in rows)
    return "+".join(r["mesher"] for r in rows if r[key] == value)


def big_disk(target=100_000):
    """The benchmark's unit disk for ``target`` elements with bm.mesh's size
    there, its boundary spacing (bubblemesh.studies.benchmark): a large,
    uniform row set beside the small graded cases.  Returns (name, domain,
    bm.mesh keyword arguments, uniform=True)."""
    from .benchmark import _disk, boundary_nodes_for

    n = boundary_nodes_for(target)
    return (f"disk {target // 1000}k uniform", bm.Domain.from_loops(_disk(n)),
            {"size": 2 * math.pi / n}, True)


def table_cases(data, big=False):
    """(name, domain, bm.mesh keyword arguments, uniform) for every case of
    :func:`cases` (max_area = area / 200 for the corner-only ones), then with
    ``big`` the :func:`big_disk`."""
    for name, loops, kwargs in cases(data):
        domain = bm.Domain.from_loops(loops)
        yield name, domain, {"max_area": domain.area / 200} if kwargs == "per200" else kwargs, False
    if big:
        yield big_disk()


def case_rows(name, domain, kwargs, uniform=False):
    """bm.mesh(domain, **kwargs), then Gmsh Frontal-Delaunay and Triangle -pq30
    on its refined boundary at its count (Gmsh with bm's size field, or with
    ``uniform`` Gmsh's own constant size ``kwargs["size"]``): one row per
    mesher, :func:`measure` plus the predicted count, N over it, and the
    winners of mean, min and below 0.7."""
    from bubblemesh.pipeline import size_field

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", bm.QualityWarning)
        m = bm.mesh(domain, **kwargs)
    field = size_field(domain, size=kwargs.get("size"), max_area=kwargs.get("max_area"),
                       gradation=kwargs.get("gradation", 0.25))
    count = len(m.triangles)
    try:
        predicted = predicted_count(domain, field, COUNT_TOL).count
    except RuntimeError as error:  # the count target is then not judged
        print(f"{name}: {error}")
        predicted = math.nan
    runs: list = []
    gmsh = (run_gmsh_uniform(m, kwargs["size"], count, runs=runs) if uniform
            else run_gmsh(m, field, count, runs=runs))
    meshes = [("bm", (m.points, m.triangles)), ("gmsh", gmsh[:2])]
    beyond = _other_side(runs, len(gmsh[1]), count)
    if beyond is not None:
        meshes.append(("gmsh_beyond", beyond[:2]))
    meshes.append(("triangle", run_triangle(m, domain.hole_points, count)))
    rows = []
    for mesher, (p, t) in meshes:
        r = measure(domain, p, t)
        rows.append(dict(case=name, mesher=mesher, N=r["N"], predicted=round(predicted, 1),
                         ratio=round(r["N"] / predicted, 4), min=round(r["min"], 6),
                         mean=round(r["mean"], 6), below=r["below"],
                         below_off_sharp=r["below_off_sharp"], valid=r["valid"]))
    wins = (_winners(rows, "mean", max), _winners(rows, "min", max),
            _winners(rows, "below", min))
    for r in rows:
        r.update(wins_mean=wins[0], wins_min=wins[1], wins_below=wins[2])
    return rows


# quality_vs_gmsh.csv's columns, and the row keys they hold
COLUMNS = {"case": "case", "mesher": "mesher", "N": "N", "predicted": "predicted",
           "N/predicted": "ratio", "min": "min", "mean": "mean", "below_0.7": "below",
           "below_0.7_off_sharp": "below_off_sharp", "valid": "valid",
           "wins_mean": "wins_mean", "wins_min": "wins_min", "wins_below_0.7": "wins_below"}


def quality_table(data, out_dir=None, big=False):
    """bm.mesh, Gmsh Frontal-Delaunay and Triangle -pq30 at matched counts on
    every case of :func:`table_cases` (:func:`case_rows`): printed with the
    winners and :func:`target_summary`, written as quality_vs_gmsh.csv to
    ``out_dir`` if given; returns that table (a DataFrame)."""
    print(f"{'case':26s} {'mesher':11s} {'N':>7s} {'N/pred':>6s} {'min':>6s} {'mean':>7s} "
          f"{'<0.7':>5s} {'off':>4s} {'valid':>5s}  winners (mean / min / <0.7)")
    rows = []
    for name, domain, kwargs, uniform in table_cases(data, big):
        case = case_rows(name, domain, kwargs, uniform)
        for r in case:
            wins = f"{r['wins_mean']} / {r['wins_min']} / {r['wins_below']}"
            print(f"{name:26s} {r['mesher']:11s} {r['N']:7d} {r['ratio']:6.3f} {r['min']:6.4f} "
                  f"{r['mean']:7.4f} {r['below']:5d} {r['below_off_sharp']:4d} "
                  f"{str(r['valid']):>5s}  {wins if r is case[0] else ''}")
        rows += case
    table = _frame(rows)
    print(target_summary(table))
    if out_dir is not None:
        out_dir.mkdir(parents=True, exist_ok=True)
        table.to_csv(out_dir / "quality_vs_gmsh.csv", index=False)
    return table


# the counts a comparison of quality needs: Gmsh's within this fraction of bm's
MATCHED = 0.03


def unmatched_cases(table) -> list:
    """The cases of ``table`` (with an N column) where Gmsh's count is more
    than MATCHED off bm's and no Gmsh run lies on its other side
    (:func:`bracketed_cases`): their qualities are not compared."""
    if "N" not in table:
        return []
    ours = table[table.mesher == "bm"].set_index("case")["N"]
    gmsh = table[table.mesher == "gmsh"].set_index("case")["N"].loc[ours.index]
    off = ours.index[(gmsh / ours - 1).abs() > MATCHED]
    return [case for case in off if case not in bracketed_cases(table)]


def bracketed_cases(table) -> list:
    """The cases of ``table`` with a gmsh_beyond row: Gmsh's count jumped
    across bm's as its size scale changed, so bm is judged against its
    closest meshes on both sides, interpolated to bm's count."""
    if "N" not in table:
        return []
    return list(dict.fromkeys(table.case[table.mesher == "gmsh_beyond"]))


def _gmsh_at_count(table):
    """Gmsh's mean and min per case of ``table``: its row's, or where its
    count jumped across bm's (a gmsh_beyond row), the two rows' values
    interpolated linearly in the element count to bm's."""
    ours = table[table.mesher == "bm"].set_index("case")["N"]
    near = table[table.mesher == "gmsh"].set_index("case")
    out = near[["mean", "min"]].copy()
    for case, row in table[table.mesher == "gmsh_beyond"].set_index("case").iterrows():
        share = (ours[case] - near.at[case, "N"]) / (row["N"] - near.at[case, "N"])
        for key in ("mean", "min"):
            out.at[case, key] = near.at[case, key] + share * (row[key] - near.at[case, key])
    return out


def target_verdicts(table):
    """The project's targets for bm.mesh on each case of ``table``
    (quality_vs_gmsh.csv as a DataFrame): {target: (cases met, cases missed)}.
    The targets: mean and min radius ratio >= Gmsh Frontal's (where Gmsh's
    count jumped across bm's, >= its values interpolated to bm's count
    between its meshes on both sides; not judged where its counts miss bm's
    on one side only, :func:`unmatched_cases`), no element below 0.7 except those touching an
    input corner sharper than SHARP_ANGLE (no element there can reach 0.7), N
    within 5% of the predicted count (where there is a prediction)."""
    from bubblemesh.pipeline import SHARP_ANGLE

    ours = table[table.mesher == "bm"].set_index("case")
    best = _gmsh_at_count(table).loc[ours.index]
    compared = ~ours.index.isin(unmatched_cases(table))
    met = {"mean >= Gmsh's": ours["mean"] >= best["mean"],
           "min >= Gmsh's": ours["min"] >= best["min"],
           f"no element below 0.7 off corners under {math.degrees(SHARP_ANGLE):.1f} degrees":
               ours["below_0.7_off_sharp"] == 0,
           "N within 5% of the predicted count": (ours["N/predicted"] - 1).abs() <= 0.05}
    judged = {target: compared if target.endswith("Gmsh's") else np.ones(len(ours), bool)
              for target in met}
    judged["N within 5% of the predicted count"] = ours["N/predicted"].notna().to_numpy()
    return {target: (list(ok.index[ok & judged[target]]), list(ok.index[~ok & judged[target]]))
            for target, ok in met.items()}


def print_case(label, case):
    """One line for a sweep's case: bm's count (over the predicted) and its
    mean, min and elements below 0.7 off sharp corners against Gmsh's."""
    ours, gmsh = case[0], case[1]
    print(f"{label:34s} N {ours['N']:6d} ({ours['ratio']:.3f}) "
          f"mean {ours['mean']:.4f} vs {gmsh['mean']:.4f}  min {ours['min']:.4f} vs "
          f"{gmsh['min']:.4f}  <0.7 off-corner {ours['below_off_sharp']}", flush=True)


def _frame(rows):
    """The rows of :func:`case_rows` as a DataFrame in the COLUMNS of
    quality_vs_gmsh.csv (the columns even with no rows)."""
    import pandas as pd

    return pd.DataFrame([{column: r[key] for column, key in COLUMNS.items()} for r in rows],
                        columns=list(COLUMNS))


def sweep_table(rows, out_dir=None, filename=None):
    """The sweep's rows (:func:`case_rows`) as a DataFrame in the COLUMNS of
    quality_vs_gmsh.csv, :func:`target_summary` and each missed target
    printed, written as ``filename`` to ``out_dir`` when that is given."""
    table = _frame(rows)
    print(target_summary(table))
    for target, (_, missed) in target_verdicts(table).items():
        for case in missed:
            print(f"  misses {target}: {case}")
    if out_dir is not None:
        out_dir.mkdir(parents=True, exist_ok=True)
        table.to_csv(out_dir / filename, index=False)
    return table


def target_summary(table) -> str:
    """One line: on how many cases bm meets each of :func:`target_verdicts`,
    naming the cases where it does not, and those not compared with Gmsh."""
    parts = []
    for target, (met, missed) in target_verdicts(table).items():
        note = f" (not {', '.join(missed)})" if missed else ""
        parts.append(f"{target} on {len(met)} of {len(met) + len(missed)}{note}")
    unmatched, bracketed = unmatched_cases(table), bracketed_cases(table)
    tail = (f"; not compared with Gmsh, whose count missed bm's by over {MATCHED:.0%}: "
            f"{', '.join(unmatched)}" if unmatched else "")
    tail += (f"; against Gmsh interpolated between its meshes on both sides of bm's count, "
             f"where its count jumped across it: {', '.join(bracketed)}" if bracketed else "")
    return "bm meets: " + "; ".join(parts) + tail


def sweeps():
    graded = [_square(10.0, 0.5), _circle((5, 5), 0.05, 0.005)]
    plate = [_square(10.0, 0.25)] + [_circle((2 + 2 * i, 2 + 2 * j), 0.4, 0.05)
                                     for i in range(4) for j in range(4)]
    for name, loops in (("graded square+hole", graded), ("perforated plate", plate)):
        domain = bm.Domain.from_loops(loops)
        for it in (100, 200, 400, 1000):
            m = bm.mesh(domain, max_iterations=it)
            n, qmin, qmean, _ = _stats(m.points, m.triangles)
            o = m.optimization
            print(f"{name:20s} max_iterations {it:5d}: N {n} min {qmin:.4f} mean {qmean:.4f} "
                  f"(iterations {o.iterations}, converged {o.converged})")
        p = bm.mesh(domain, paper=True)
        n, qmin, qmean, _ = _stats(p.points, p.triangles)
        print(f"{name:20s} paper: N {n} min {qmin:.4f} mean {qmean:.4f}")


def size_test():
    square = bm.Domain.from_loops([[(0, 0), (1, 0), (1, 1), (0, 1)]])

    def h(xy):
        return 0.02 + 0.1 * np.hypot(xy[:, 0] - 0.5, xy[:, 1] - 0.5)

    for label, size in (("h=0.02", 0.02), ("h(x)", h)):
        m = bm.mesh(square, size=size)
        e = np.vstack([m.triangles[:, [0, 1]], m.triangles[:, [1, 2]], m.triangles[:, [2, 0]]])
        e = np.unique(np.sort(e, axis=1), axis=0)
        p = np.asarray(m.points)
        length = np.hypot(*(p[e[:, 0]] - p[e[:, 1]]).T)
        target = size if not callable(size) else size(0.5 * (p[e[:, 0]] + p[e[:, 1]]))
        r = length / target
        print(f"size {label}: {len(m.triangles)} elements, edges in [0.8, 1.25] h: "
              f"{np.mean((r >= 0.8) & (r <= 1.25)):.3f}, median {np.median(r):.3f}")


def _random_domains(count, seed):
    """``count`` random corner-only polygons with 0-3 holes, drawn from ``seed``
    (self-touching draws skipped)."""
    rng = np.random.default_rng(seed)
    made = 0
    while made < count:
        try:
            domain = bm.Domain.from_loops(_random_polygon(rng, int(rng.integers(0, 4))))
        except bm.GeometryError:
            continue
        made += 1
        yield domain


def _random_row(domain):
    """bm.mesh (max_area = area / 200), Gmsh Frontal-Delaunay and Triangle
    -pq30 (both on bm's refined boundary at bm's count, Gmsh with bm's size
    field) on one polygon: :func:`measure` of each as ``<key>_<mesher>``, the
    predicted count and N over it for bm and Gmsh, the sharpest corner."""
    from bubblemesh.pipeline import corner_angles, size_field

    max_area = domain.area / 200
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", bm.QualityWarning)
        m = bm.mesh(domain, max_area=max_area)
    field = size_field(domain, max_area=max_area)
    count = len(m.triangles)
    predicted = predicted_count(domain, field, COUNT_TOL).count
    row = dict(holes=len(domain.loops) - 1, predicted=predicted,
               sharpest=math.degrees(float(corner_angles(domain).min())))
    for mesher, (p, t) in (("bm", (m.points, m.triangles)),
                           ("gmsh", run_gmsh(m, field, count)[:2]),
                           ("triangle", run_triangle(m, domain.hole_points, count))):
        row.update({f"{k}_{mesher}": v for k, v in measure(domain, p, t).items()})
    row["ratio_bm"] = row["N_bm"] / predicted
    row["ratio_gmsh"] = row["N_gmsh"] / predicted
    return row


def random_polygons(count=1000, seed=0, out_dir=None):
    """bm.mesh on ``count`` random corner-only polygons with 0-3 holes
    (max_area = area / 200) against Gmsh Frontal-Delaunay and Triangle -pq30
    at matched counts (:func:`_random_row`), every mesh checked exactly
    (bubblemesh.verify: validity and conformity).  Prints the wins of bm over
    Gmsh (mean, min) and every polygon bm loses with its margins; returns the
    table (one row per polygon), written as random_vs_gmsh.csv to ``out_dir``
    if given."""
    import pandas as pd

    df = pd.DataFrame([_random_row(d) for d in _random_domains(count, seed)])
    df.index.name = "polygon"
    _print_random_summary(df, seed)
    if out_dir is not None:
        out_dir.mkdir(parents=True, exist_ok=True)
        df.to_csv(out_dir / "random_vs_gmsh.csv")
    return df


def _print_random_summary(df, seed):
    """The random-polygon verdicts against Gmsh, then the polygons bm loses."""
    n = len(df)
    valid = ", ".join(f"{m} {int(df[f'valid_{m}'].sum())}" for m in ("bm", "gmsh", "triangle"))
    mean_wins = df.mean_bm >= df.mean_gmsh
    min_wins = df.min_bm >= df.min_gmsh
    within = {m: int((abs(df[f"ratio_{m}"] - 1) <= 0.05).sum()) for m in ("bm", "gmsh")}
    print(f"{n} random corner-only polygons (seed {seed}); valid and conforming: {valid}")
    print(f"bm against Gmsh Frontal: mean >= Gmsh's on {int(mean_wins.sum())} of {n} (average "
          f"{df.mean_bm.mean():.4f} against {df.mean_gmsh.mean():.4f}), min >= Gmsh's on "
          f"{int(min_wins.sum())} of {n} (average {df.min_bm.mean():.4f} against "
          f"{df.min_gmsh.mean():.4f}); min >= Triangle's on "
          f"{int((df.min_bm >= df.min_triangle).sum())}")
    print(f"no element below 0.7 away from corners sharper than the limit: bm "
          f"{int((df.below_off_sharp_bm == 0).sum())}, gmsh "
          f"{int((df.below_off_sharp_gmsh == 0).sum())} of {n}; N within 5% of the "
          f"prediction: bm {within['bm']}, gmsh {within['gmsh']} of {n} (median N/predicted "
          f"bm {df.ratio_bm.median():.3f}, gmsh {df.ratio_gmsh.median():.3f})")
    for i, r in df[~(mean_wins & min_wins)].iterrows():
        print(f"  polygon {i}: mean {r.mean_bm:.4f} vs {r.mean_gmsh:.4f} "
              f"({r.mean_bm - r.mean_gmsh:+.4f}), min {r.min_bm:.4f} vs {r.min_gmsh:.4f} "
              f"({r.min_bm - r.min_gmsh:+.4f}); N {r.N_bm} / {r.N_gmsh}, {r.holes} holes, "
              f"sharpest corner {r.sharpest:.1f} degrees")


def timings(n=100_000, repeats=3):
    """bm.mesh against Gmsh Frontal-Delaunay (same boundary nodes, same size)
    on a unit disk of about n elements: the minimum of ``repeats`` alternating
    runs each (the machine may be shared)."""
    from bubblemesh.sizing import SizeField

    h = math.sqrt(math.pi / (n * math.sqrt(3) / 4))
    t = np.linspace(0, 2 * math.pi, int(round(2 * math.pi / h)), endpoint=False)
    domain = bm.Domain.from_loops([np.column_stack([np.cos(t), np.sin(t)])])
    field = SizeField.from_domain(domain, size=h)
    bm.mesh(domain, size=20 * h)  # compile outside the clock
    best = {"bm": math.inf, "gmsh": math.inf}
    for _ in range(repeats):
        t0 = time.perf_counter()
        m = bm.mesh(domain, size=h)
        best["bm"] = min(best["bm"], time.perf_counter() - t0)
        _, tri, seconds = run_gmsh(m, field, len(m.triangles))
        best["gmsh"] = min(best["gmsh"], seconds)
    print(f"disk ~{n}: bm {len(m.triangles)} el {best['bm']:.2f} s, gmsh frontal {len(tri)} el "
          f"{best['gmsh']:.2f} s (min of {repeats}), gmsh / bm {best['gmsh'] / best['bm']:.2f}; "
          f"bm phases {dict((k, round(v, 3)) for k, v in m.optimization.phases.items())}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=None,
                        help="folder with Triangle's A.poly and double_hex3.poly (default: "
                             "the triangle package's examples)")
    parser.add_argument("--big", action="store_true",
                        help="add the benchmark's 100k-element uniform disk to the table")
    parser.add_argument("--timings", action="store_true",
                        help="time bm.mesh against Gmsh on a 100k-element disk")
    parser.add_argument("--random", type=int, default=0, metavar="N",
                        help="also mesh N random corner-only polygons against Gmsh and Triangle")
    parser.add_argument("--seed", type=int, default=0, help="seed of the random polygons")
    parser.add_argument("--skip-table", action="store_true")
    parser.add_argument("--out", type=Path, default=None,
                        help="write quality_vs_gmsh.csv (and random_vs_gmsh.csv) here")
    args = parser.parse_args()
    if not args.skip_table:
        quality_table(args.data, args.out, big=args.big)
    sweeps()
    size_test()
    if args.random:
        random_polygons(args.random, args.seed, args.out)
    if args.timings:
        timings()


if __name__ == "__main__":
    main()
