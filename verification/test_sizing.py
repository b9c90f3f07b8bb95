"""The size field (bubblemesh.sizing) against brute force.

Oracles: the cone field min_k h_k + g |x - x_k| over *all* sources by numpy
broadcasting; input spacing from the node's two segment lengths; feature size
as shapely's distance to the segments that do not share a node with the
point's own segment (all computed here, not by the library).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from strategies import budget, domains

import bubblemesh as bm
from bubblemesh.sizing import FEATURE_SLACK, SizeField

shapely = pytest.importorskip("shapely")

REL = 1e-12  # float rounding of h_k + g |x - x_k|


def brute_field(sources, values, g, xy, cap=math.inf):
    d = np.linalg.norm(xy[:, None, :] - sources[None, :, :], axis=2)
    return np.minimum(cap, (values[None, :] + g * d).min(axis=1))


@st.composite
def source_sets(draw):
    n = draw(st.integers(1, 60))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    pts = rng.uniform(-1, 1, (n, 2)) * 10.0 ** rng.integers(-3, 3)
    vals = 10.0 ** rng.uniform(-4, 0, n)
    g = draw(st.sampled_from([0.0, 0.1, 0.25, 1.0, 3.0]))
    return pts, vals, g, rng


@given(source_sets())
def test_field_is_the_brute_force_cone_minimum(case):
    pts, vals, g, rng = case
    field = SizeField(pts, vals, gradation=g)
    lo, hi = pts.min(axis=0) - 1, pts.max(axis=0) + 1
    xy = np.vstack([pts, rng.uniform(lo, hi, (200, 2))])
    got = field(xy)
    want = brute_field(pts, vals, g, xy)
    np.testing.assert_allclose(got, want, rtol=REL, atol=0)
    # the gradation bound for every source, at every evaluated point
    bound = vals[None, :] + g * np.linalg.norm(xy[:, None] - pts[None], axis=2)
    assert (got[:, None] <= bound * (1 + REL)).all()
    # kept sources carry their own value exactly
    np.testing.assert_array_equal(field(field.points), field.values)


@given(source_sets())
def test_only_dominated_sources_are_dropped(case):
    """A source is dropped only where another's cone is at or below its
    value there, and kept only where none is clearly below (brute force)."""
    pts, vals, g, _ = case
    field = SizeField(pts, vals, gradation=g)
    kept = {tuple(p) for p in field.points.tolist()}
    d = np.linalg.norm(pts[:, None, :] - pts[None, :, :], axis=2)
    others = np.where(np.eye(len(pts), dtype=bool), np.inf, vals[None, :] + g * d).min(axis=1)
    for k, p in enumerate(pts.tolist()):
        if tuple(p) in kept:
            assert others[k] >= vals[k] * (1 - REL)
        else:
            assert others[k] <= vals[k] * (1 + REL)


@budget(25)
@given(source_sets(), st.integers(0, 2**32 - 1))
def test_warm_starts_change_no_bit(case, seed):
    """Each search starts from the previous answer's source, and a large
    query is answered in Morton order: whatever the start, the value must be
    the cold search's, bit for bit, and the brute-force minimum."""
    from bubblemesh.sizing import _HINT, SORTED_QUERIES, STACK_SIZE, cone_at

    pts, vals, g, rng = case
    field = SizeField(pts, vals, gradation=g)
    lo, hi = pts.min(axis=0) - 1, pts.max(axis=0) + 1
    xy = rng.uniform(lo, hi, (SORTED_QUERIES + 7, 2))
    got = field(xy)
    np.testing.assert_allclose(got, brute_field(pts, vals, g, xy), rtol=REL, atol=0)
    np.testing.assert_array_equal(field(xy[::-1]), got[::-1])
    tree = field.kernel_args()[2:]
    starts = np.random.default_rng(seed).integers(-2, len(field.values) + 2, 60)
    for j, start in enumerate(starts):
        stack = np.full(STACK_SIZE, -1, np.int64)
        cold = cone_at(*xy[j], stack, *tree)
        stack[_HINT] = start
        assert cone_at(*xy[j], stack, *tree) == cold == got[j]
        assert 0 <= stack[_HINT] < len(field.values)


@given(source_sets())
def test_graded_inputs_are_reproduced_at_the_sources(case):
    pts, vals, g, _ = case
    graded = brute_field(pts, vals, g, pts)  # inputs that satisfy the gradation
    field = SizeField(pts, graded, gradation=g)
    np.testing.assert_allclose(field(pts), graded, rtol=REL, atol=0)


def test_cap_and_radius():
    pts = np.array([[0.0, 0.0], [3.0, 0.0]])
    field = SizeField(pts, np.array([0.1, 2.0]), gradation=0.5, cap=0.6)
    xy = np.array([[0.0, 0.0], [0.5, 0.0], [3.0, 0.0], [10.0, 4.0]])
    np.testing.assert_allclose(field(xy), [0.1, 0.35, 0.6, 0.6])
    r = field.radius(xy[:1])  # eq. 2 with l1 = l2 = h: pi r^2 = sqrt(3)/4 h^2
    np.testing.assert_allclose(math.pi * r**2, math.sqrt(3) / 4 * 0.1**2)


# --- from_domain: inputs recomputed independently ------------------------------------------


def _segments(domain):
    a = domain.points[domain.segments[:, 0]]
    b = domain.points[domain.segments[:, 1]]
    prev, nxt = np.empty(len(a), int), np.empty(len(a), int)
    start = 0
    for loop in domain.loops:
        idx = np.arange(start, start + len(loop))
        prev[idx], nxt[idx] = np.roll(idx, 1), np.roll(idx, -1)
        start += len(loop)
    lines = shapely.linestrings(np.stack([a, b], axis=1))
    return a, b, prev, nxt, lines


def _distance_excluding(lines, xy, excluded):
    """Brute-force: distance from each point to every line not in its excluded set."""
    d = shapely.distance(shapely.points(xy)[:, None], lines[None, :])
    rows = np.arange(len(xy))[:, None]
    d[rows, excluded] = np.inf
    return d.min(axis=1)


def _reference_inputs(domain, xy, size=None):
    """Each source's input value, recomputed: nodes get min(spacing, node feature
    size), points inside segment s the feature size excluding s and its
    neighbours, both capped by the user size; points off the boundary (the
    quadtree of a callable size) the user size alone."""
    a, b, prev, nxt, lines = _segments(domain)
    length = np.linalg.norm(b - a, axis=1)
    on = shapely.distance(shapely.points(xy)[:, None], lines[None, :])
    s = on.argmin(axis=1)
    boundary = on[np.arange(len(xy)), s] <= 1e-12 * (1 + np.abs(xy).max())
    assert boundary.all() or callable(size), "a source off the boundary without a size function"
    node_of = {tuple(p): k for k, p in enumerate(a.tolist())}  # a[k] is node k's position
    is_node = np.array([tuple(p) in node_of for p in xy.tolist()])
    k = np.array([node_of.get(tuple(p), 0) for p in xy.tolist()])
    excl_node = np.column_stack([k, prev[k], k])
    excl_seg = np.column_stack([s, prev[s], nxt[s]])
    value = np.where(
        is_node,
        np.minimum(
            np.sqrt(0.5 * (length[k] ** 2 + length[prev[k]] ** 2)),
            _distance_excluding(lines, xy, excl_node),
        ),
        _distance_excluding(lines, xy, excl_seg),
    )
    if size is not None:
        value = np.minimum(value, size(xy) if callable(size) else size)
    return np.where(boundary, value, size(xy) if callable(size) else np.nan)


def _boundary_probe(domain, rng, per_segment=7):
    a, b, prev, nxt, lines = _segments(domain)
    t = rng.uniform(0, 1, (len(a), per_segment))
    xy = (a[:, None, :] + t[..., None] * (b - a)[:, None, :]).reshape(-1, 2)
    s = np.repeat(np.arange(len(a)), per_segment)
    return xy, _distance_excluding(lines, xy, np.column_stack([s, prev[s], nxt[s]]))


def _check_field(domain, field, rng, size=None):
    g = field.gradation
    # every source's input value is what the definition gives
    ref = _reference_inputs(domain, field.sample_points, size)
    np.testing.assert_allclose(field.sample_values, ref, rtol=1e-9)
    # gradation against every source, at the sources and at random points
    lo, hi = domain.points.min(axis=0), domain.points.max(axis=0)
    xy = np.vstack([field.sample_points, rng.uniform(lo, hi, (300, 2))])
    got = field(xy)
    want = brute_field(field.sample_points, field.sample_values, g, xy, field.cap)
    np.testing.assert_allclose(got, want, rtol=REL, atol=0)
    # feature-size response all along the boundary
    probe, feature = _boundary_probe(domain, rng)
    assert (field(probe) <= FEATURE_SLACK * feature * (1 + 1e-9)).all()
    return got


@given(domains(max_holes=2, max_corners=6, min_spacing=0.3), st.integers(0, 2**32 - 1))
@budget(25)
def test_from_domain_against_brute_force(case, seed):
    domain = bm.Domain.from_loops(case.loops)
    field = SizeField.from_domain(domain)
    _check_field(domain, field, np.random.default_rng(seed))


@st.composite
def corner_polygons(draw):
    """Star polygons given by their corners only (long edges, no refinement)."""
    n = draw(st.integers(3, 9))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    ang = np.sort(rng.uniform(0, 2 * np.pi, n))
    ang = np.linspace(0, 2 * np.pi, n, endpoint=False) + 0.3 * (ang - ang.mean()) / n
    r = rng.uniform(0.2, 1.0, n)
    return np.column_stack([r * np.cos(ang), r * np.sin(ang)])


@given(corner_polygons(), st.sampled_from([None, 0.05, "callable"]), st.integers(0, 2**16))
@budget(40)
def test_corner_polygons_with_user_sizes(corners, size, seed):
    domain = bm.Domain.from_loops([corners])
    if size == "callable":
        size = lambda xy: 0.02 + 0.2 * np.abs(xy[:, 0])  # noqa: E731
    field = SizeField.from_domain(domain, size=size)
    got = _check_field(domain, field, np.random.default_rng(seed), size)
    if isinstance(size, float):
        assert (got <= size).all()


def test_thin_slot_gets_small_elements():
    # a 4 x 2 rectangle with a 0.01-wide slot cut 1.5 deep into its top edge
    w = 0.01
    outer = [(0, 0), (4, 0), (4, 2), (2 + w / 2, 2), (2 + w / 2, 0.5), (2 - w / 2, 0.5),
             (2 - w / 2, 2), (0, 2)]  # fmt: skip
    domain = bm.Domain.from_loops([np.array(outer, float)])
    field = SizeField.from_domain(domain)
    ys = np.linspace(0.5, 2.0, 301)
    walls = np.column_stack([np.full_like(ys, 2 - w / 2), ys])
    assert field(walls).max() <= FEATURE_SLACK * w * (1 + 1e-9)
    assert field(np.array([[1.0, 1.0]]))[0] > 10 * w  # far from the slot it grows


def test_bad_user_sizes_and_gradations():
    domain = bm.Domain.from_loops([np.array([(0, 0), (1, 0), (0, 1)], float)])
    for size, error, words in [
        (-1.0, ValueError, "size must be finite and > 0"),
        (math.nan, ValueError, "size must be finite and > 0"),
        ("big", TypeError, "size must be a positive number or a callable"),
        ("0.1", TypeError, "size must be a positive number or a callable, got str"),
        (True, TypeError, "size must be a positive number or a callable, got bool"),
        (lambda xy: np.zeros(len(xy)), ValueError, r"> 0; at \(0\.0, 0\.0\) it is 0\.0$"),
        (lambda xy: np.ones((len(xy), 2)), ValueError, "must return shape"),
        (lambda xy: np.full(len(xy), np.inf), ValueError, "finite and > 0"),
        (lambda xy: ["a"] * len(xy), ValueError, "did not return numbers"),
    ]:
        with pytest.raises(error, match=words):
            SizeField.from_domain(domain, size=size)
    with pytest.raises(ValueError, match="gradation must be finite and >= 0"):
        SizeField.from_domain(domain, gradation=-0.1)
    with pytest.raises(TypeError, match="gradation must be a number, got str"):
        SizeField.from_domain(domain, gradation="0.3")
    for area in ("0.1", True):  # float() would take both
        with pytest.raises(TypeError, match="max_area must be a positive number, got "):
            bm.mesh(domain, max_area=area)
    with pytest.raises(TypeError, match="expected a Domain"):
        SizeField.from_domain([np.zeros((3, 2))])
    with pytest.raises(bm.MeshingError, match="boundary samples"):
        SizeField.from_domain(domain, size=lambda xy: np.full(len(xy), 1e-9), max_sources=1000)


def test_sizes_far_beyond_the_domain_give_its_coarsest_mesh():
    """A unit square meshed with size 1e300, 1.7e308, max_area 1e308 (whose
    squares overflow) or a callable of 1e300: the same mesh as with size 10,
    ten times its diagonal, i.e. its two triangles on its four corners (no
    node added, nothing refused)."""
    domain = bm.Domain.from_loops([np.array([(0, 0), (1, 0), (1, 1), (0, 1)], float)])
    coarse = bm.mesh(domain, size=10.0)
    assert len(coarse.triangles) == 2 and len(coarse.points) == 4
    for options in (dict(size=1e300), dict(size=1.7e308), dict(max_area=1e308),
                    dict(size=lambda xy: np.full(len(xy), 1e300))):
        m = bm.mesh(domain, **options)
        assert np.array_equal(m.points, coarse.points), options
        assert np.array_equal(m.triangles, coarse.triangles), options


def test_no_size_is_no_cap_and_a_huge_size_is_held_at_the_domains_reach():
    """Without a size, or with a callable one, the field has no cap (the
    mesher's capped paths, lattice and frontal insertion, stay off); a
    number far beyond the domain is held at CAP_REACH times its extent."""
    from bubblemesh.sizing import CAP_REACH

    domain = bm.Domain.from_loops([np.array([(0, 0), (3, 0), (3, 1), (0, 1)], float)])
    assert SizeField.from_domain(domain).cap == math.inf
    assert SizeField.from_domain(domain, size=lambda xy: np.full(len(xy), 1e300)).cap == math.inf
    assert SizeField.from_domain(domain, size=0.5).cap == 0.5
    assert SizeField.from_domain(domain, size=1e300).cap == CAP_REACH * 3.0


def test_an_unknown_option_is_named_as_the_caller_wrote_it():
    domain = bm.Domain.from_loops([np.array([(0, 0), (1, 0), (0, 1)], float)])
    with pytest.raises(TypeError, match=r"^mesh\(\) got an unexpected keyword argument 'bogus'$"):
        bm.mesh(domain, size=0.5, bogus=1)


@given(source_sets(), st.floats(0.05, 0.9))
def test_the_cap_grid_changes_no_bit(case, share):
    """Where the field is the cap all over a grid cell, the lookup answers
    without the tree search: it must give exactly the tree search's value, at
    random points, at the cells' corners and an ulp either side of them."""
    from bubblemesh.sizing import _cone_min

    pts, vals, g, rng = case
    cap = float(np.quantile(vals, share))
    field = SizeField(pts, vals, gradation=max(g, 0.05), cap=cap)
    grid, full = field.kernel_args()[:2]
    lo, hi = pts.min(axis=0) - 1, pts.max(axis=0) + 1
    side = 1.0 / grid[2]
    cols, rows = np.meshgrid(np.arange(int(grid[3]) + 1), np.arange(int(grid[4]) + 1))
    corners = np.column_stack([grid[0] + cols.ravel() * side, grid[1] + rows.ravel() * side])
    xy = np.vstack([rng.uniform(lo, hi, (500, 2)), corners, np.nextafter(corners, -np.inf),
                    np.nextafter(corners, np.inf)])
    no_grid = (np.array([0.0, 0.0, 1.0, 0.0, 0.0, 0.0]), np.zeros(0, np.bool_))
    want = _cone_min(xy, *no_grid, *field.kernel_args()[2:])
    np.testing.assert_array_equal(field(xy), want)
    np.testing.assert_allclose(want, brute_field(field.points, field.values, field.gradation,
                                                 xy, cap), rtol=REL, atol=0)


def test_a_constant_size_fills_the_cap_grid():
    """On a disk meshed at a constant size finer than its boundary, the grid
    answers for most of the interior (the cells away from the boundary)."""
    t = np.linspace(0, 2 * np.pi, 64, endpoint=False)
    field = SizeField.from_domain(bm.Domain.from_loops([np.column_stack([np.cos(t),
                                                                          np.sin(t)])]),
                                  size=0.01)
    grid, full = field.kernel_args()[:2]
    side = 1.0 / grid[2]
    centres = np.column_stack([grid[0] + (np.arange(len(full)) % int(grid[3]) + 0.5) * side,
                               grid[1] + (np.arange(len(full)) // int(grid[3]) + 0.5) * side])
    deep = np.hypot(*centres.T) < 1 - 2 * side
    assert full[deep].all() and deep.sum() > 0.5 * len(full)


@given(source_sets())
def test_morton_order_interleaves_the_grid_bits(case):
    """The tree's order sorts points by their 21-bit grid coordinates with
    the bits interleaved (y's above x's), here by strings of binary digits."""
    from bubblemesh.sizing import _morton_order

    pts, _, _, _ = case
    lo = pts.min(axis=0)
    extent = float((pts.max(axis=0) - lo).max())
    scale = (2**21 - 1) / extent if extent > 0 else 0.0
    cells = ((pts - lo) * scale).astype(np.int64)
    keys = ["".join(y + x for y, x in zip(f"{cy:021b}", f"{cx:021b}")) for cx, cy in cells]
    want = sorted(range(len(pts)), key=lambda k: (keys[k], k))
    assert _morton_order(pts).tolist() == want
