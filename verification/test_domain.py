"""Domain: the validated refined boundary of paper §2.1 and its area A_geo (eq. 6).

Oracles here share nothing with bubblemesh.domain or bubblemesh._sweep:
rational arithmetic (fractions.Fraction) for orientation, segment contact and
point location, brute force over all pairs of segments and loops, and shapely
for areas and hole points.
"""

from __future__ import annotations

import math
import re
import sys
from decimal import Decimal
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st
from strategies import budget, domains

from bubblemesh import mesh as mesh_domain
from bubblemesh._sweep import find_crossing
from bubblemesh.domain import Domain
from bubblemesh.errors import GeometryError

SQUARE = [(0.0, 0.0), (4.0, 0.0), (4.0, 4.0), (0.0, 4.0)]
SMALL_HOLE = [(1.0, 1.0), (1.0, 2.0), (2.0, 2.0), (2.0, 1.0)]


# --- exact oracles ----------------------------------------------------------------


def orient(a, b, c) -> int:
    ax, ay, bx, by, cx, cy = (Fraction(v) for v in (*a, *b, *c))
    det = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
    return (det > 0) - (det < 0)


def on_segment(p, a, b) -> bool:
    return (
        orient(a, b, p) == 0
        and min(a[0], b[0]) <= p[0] <= max(a[0], b[0])
        and min(a[1], b[1]) <= p[1] <= max(a[1], b[1])
    )


def segments_meet(a, b, c, d) -> bool:
    """Closed segments a-b and c-d share at least one point."""
    o1, o2, o3, o4 = orient(a, b, c), orient(a, b, d), orient(c, d, a), orient(c, d, b)
    if o1 * o2 < 0 and o3 * o4 < 0:
        return True
    return on_segment(c, a, b) or on_segment(d, a, b) or on_segment(a, c, d) or on_segment(b, c, d)


def adjacent_overlap(p, q, r) -> bool:
    """Segments p-q and q-r share more than q: r on the ray from q through p."""
    if orient(p, q, r) != 0:
        return False
    dot = sum(
        (Fraction(pi) - Fraction(qi)) * (Fraction(ri) - Fraction(qi)) for pi, qi, ri in zip(p, q, r)
    )
    return dot > 0


def signed_area(ring) -> Fraction:
    pts = [(Fraction(x), Fraction(y)) for x, y in ring]
    return (
        sum(
            (
                pts[i][0] * pts[(i + 1) % len(pts)][1] - pts[(i + 1) % len(pts)][0] * pts[i][1]
                for i in range(len(pts))
            ),
            Fraction(0),
        )
        / 2
    )


def strictly_inside(p, ring) -> bool:
    """Exact crossing test; False on the boundary."""
    n = len(ring)
    inside = False
    for i in range(n):
        a, b = ring[i], ring[(i + 1) % n]
        if on_segment(p, a, b):
            return False
        if (a[1] > p[1]) != (b[1] > p[1]) and (orient(a, b, p) > 0) == (b[1] > a[1]):
            inside = not inside
    return inside


def loop_problem(ring) -> bool:
    """True if a single closed loop is not a simple polygon of positive area."""
    ring = [tuple(p) for p in ring]
    if len(ring) >= 2 and ring[-1] == ring[0]:
        ring = ring[:-1]
    n = len(ring)
    if n < 3 or any(ring[i] == ring[(i + 1) % n] for i in range(n)):
        return True
    if signed_area(ring) == 0:
        return True
    for i in range(n):
        for j in range(i + 1, n):
            a, b, c, d = ring[i], ring[(i + 1) % n], ring[j], ring[(j + 1) % n]
            if j == i + 1:
                if adjacent_overlap(a, b, d):
                    return True
            elif i == 0 and j == n - 1:
                if adjacent_overlap(b, a, c):
                    return True
            elif segments_meet(a, b, c, d):
                return True
    return False


def loops_meet(ring_a, ring_b) -> bool:
    na, nb = len(ring_a), len(ring_b)
    return any(
        segments_meet(ring_a[i], ring_a[(i + 1) % na], ring_b[j], ring_b[(j + 1) % nb])
        for i in range(na)
        for j in range(nb)
    )


def intersection_kind(a, b, c, d) -> str | None:
    """How closed segments a-b and c-d intersect, from a + t(b - a) = c + u(d - c) solved
    in rationals: None, "crosses" (one point inside both), "touches" (one point at an
    end of either) or "overlaps" (a common piece of positive length)."""
    a, b, c, d = ((Fraction(x), Fraction(y)) for x, y in (a, b, c, d))

    def cross(p, q):
        return p[0] * q[1] - p[1] * q[0]

    r, s, w = (b[0] - a[0], b[1] - a[1]), (d[0] - c[0], d[1] - c[1]), (c[0] - a[0], c[1] - a[1])
    denominator = cross(r, s)
    if denominator != 0:
        t, u = cross(w, s) / denominator, cross(w, r) / denominator
        if not (0 <= t <= 1 and 0 <= u <= 1):
            return None
        return "crosses" if 0 < t < 1 and 0 < u < 1 else "touches"
    if cross(w, r) != 0:
        return None  # parallel lines
    rr = r[0] * r[0] + r[1] * r[1]
    t0 = (w[0] * r[0] + w[1] * r[1]) / rr
    t1 = t0 + (s[0] * r[0] + s[1] * r[1]) / rr
    low, high = max(Fraction(0), min(t0, t1)), min(Fraction(1), max(t0, t1))
    if low > high:
        return None
    return "touches" if low == high else "overlaps"


def segment_conflict(points, first, second) -> str | None:
    """The oracle's verdict on two segments given as node-index pairs: sharing an end
    node (the same index) is allowed, any other common point is a conflict."""
    a, b = first
    c, d = second
    kind = intersection_kind(points[a], points[b], points[c], points[d])
    if kind == "touches" and {a, b} & {c, d}:
        return None  # they meet at their shared node only
    return kind


CONFLICT = re.compile(
    r"loop (\d+) \((?:outer|hole \d+)\) segment (\d+) (crosses|touches|overlaps) "
    r"loop (\d+) \((?:outer|hole \d+)\) segment (\d+)"
)


def assert_names_meeting_segments(message: str, loops) -> None:
    """The message names two segments of the input that really share a point."""
    match = CONFLICT.search(message)
    assert match, message
    k1, s1, _, k2, s2 = match.groups()
    rings = [[tuple(p) for p in np.asarray(r, dtype=float).tolist()] for r in loops]
    r1, r2 = rings[int(k1)], rings[int(k2)]
    s1, s2 = int(s1), int(s2)
    seg1 = (r1[s1], r1[(s1 + 1) % len(r1)])
    seg2 = (r2[s2], r2[(s2 + 1) % len(r2)])
    assert (k1, s1) != (k2, s2)
    assert segments_meet(*seg1, *seg2), f"{message}: {seg1} and {seg2} do not meet"


def assert_names_a_true_conflict(message: str, loops) -> None:
    """The message names two segments that the oracle says conflict, with its verb."""
    match = CONFLICT.search(message)
    assert match, message
    k1, s1, verb, k2, s2 = (int(g) if g.isdigit() else g for g in match.groups())
    rings = [[tuple(p) for p in np.asarray(r, dtype=float).tolist()] for r in loops]
    points = [p for ring in rings for p in ring]
    start = np.cumsum([0] + [len(ring) for ring in rings]).tolist()

    def segment(k, s):
        return start[k] + s, start[k] + (s + 1) % len(rings[k])

    assert (k1, s1) != (k2, s2)
    assert segment_conflict(points, segment(k1, s1), segment(k2, s2)) == verb, message


def raises_geometry(loops) -> str:
    with pytest.raises(GeometryError) as info:
        Domain.from_loops(loops)
    return str(info.value)


# --- validation: one case per error -------------------------------------------------


def test_too_few_nodes_names_the_loop():
    message = raises_geometry([SQUARE, [(1.0, 1.0), (2.0, 2.0)]])
    assert message.startswith("loop 1 (hole 1) has 2 distinct nodes")


def test_closing_repeat_is_dropped_but_too_short_loop_still_rejected():
    domain = Domain.from_loops([SQUARE + [SQUARE[0]]])
    assert len(domain.points) == 4
    message = raises_geometry([[(0.0, 0.0), (1.0, 0.0), (0.0, 0.0)]])
    assert "loop 0 (outer) has 2 distinct nodes" in message


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_non_finite_coordinate_names_loop_and_node(bad):
    hole = [(1.0, 1.0), (1.0, 2.0), (2.0, bad), (2.0, 1.0)]
    assert (
        raises_geometry([SQUARE, hole]) == "loop 1 (hole 1) has a non-finite coordinate at node 2"
    )


def test_coordinate_out_of_safe_range_is_rejected():
    message = raises_geometry([[(0.0, 0.0), (1e200, 0.0), (0.0, 1.0)]])
    assert message.startswith("loop 0 (outer) node 1 = (1e+200, 0.0) has a coordinate outside")
    # everything below the range: rescaling would help, and the message says so
    message = raises_geometry([[(0.0, 0.0), (1e-40, 0.0), (0.0, 1e-40)]])
    assert message.startswith("loop 0 (outer) node 1 = (1e-40, 0.0) has a coordinate outside")
    assert message.endswith("rescale the geometry")


@pytest.mark.parametrize("tiny", [1e-308, -2.9e-47, 2.0**-101, 5e-324])
def test_coordinates_below_the_resolution_of_the_largest_read_as_zero(tiny):
    """sin(pi)**3 in a shape of size 17: below one ulp of the largest
    coordinate, so it is read as 0 (no scaling could bring both into range)."""
    square = [(0.0, 0.0), (17.0, tiny), (17.0, 17.0), (tiny, 17.0)]
    domain = Domain.from_loops([square])
    assert domain.points.tolist() == [[0.0, 0.0], [17.0, 0.0], [17.0, 17.0], [0.0, 17.0]]
    # a hole point wholly below the range is judged at the scale of the vertices
    outer = [(-17.0, -17.0), (17.0, -17.0), (17.0, 17.0), (-17.0, 17.0)]
    hole = [(-1.0, -1.0), (-1.0, 1.0), (1.0, 1.0), (1.0, -1.0)]
    pslg = Domain.from_pslg([outer, hole], holes=[(tiny, tiny)], points=[(8.0, tiny)])
    assert [8.0, 0.0] in pslg.points.tolist()
    assert pslg.area == 34.0**2 - 4.0
    # coordinates in range are kept bit for bit
    kept = [(0.0, 0.0), (17.0, 2.0**-100), (17.0, 17.0), (1e-30, 17.0)]
    assert Domain.from_loops([kept]).points.tolist() == [list(p) for p in kept]


def test_wrong_shape_and_empty_input():
    assert "must be an (n, 2) array" in raises_geometry([np.zeros((4, 3))])
    assert "at least one loop" in raises_geometry([])
    assert "wrap a single outer loop" in raises_geometry(np.array(SQUARE))


TRIANGLE = [(0.0, 0.0), (3.0, 0.0), (0.0, 3.0)]


@pytest.mark.parametrize(
    ("hole", "expected"),
    [
        (np.array(SMALL_HOLE) + 1j,
         "loop 1 (hole 1) has complex coordinates (node 0 = ((1+1j), (1+1j)))"),
        ([(1.0, 1.0), (1.0, 2.0), (2.0 + 0.5j, 2.0), (2.0, 1.0)],
         "loop 1 (hole 1) has complex coordinates (node 2 = ((2+0.5j), (2+0j)))"),
        (np.array(SMALL_HOLE, dtype=complex),  # even a zero imaginary part: say .real
         "loop 1 (hole 1) has complex coordinates (node 0 = ((1+0j), (1+0j)))"),
        ([(1, 1), (1, 2), (2, 10**400), (2, 1)],
         "loop 1 (hole 1) node 2 has a coordinate too large for float64: 100000000000..."),
        (np.array([(1, 1), (1, 2), (2, None), (2, 1)], dtype=object),
         "loop 1 (hole 1) node 2 has a coordinate of type NoneType, not a real number: None"),
        (np.array([(1, 1), (1, 2), (2, "2"), (2, 1)], dtype=object),
         "loop 1 (hole 1) node 2 has a coordinate of type str, not a real number: '2'"),
        (np.array([(1, 1), (True, 2), (2, 2)], dtype=object),
         "loop 1 (hole 1) node 1 has a coordinate of type bool, not a real number: True"),
        ([("1", "1"), ("1", "2"), ("2", "2")],
         "loop 1 (hole 1) has coordinates of dtype <U1, not real numbers (node 0 = ('1', '1'))"),
        ([(b"1", b"1"), (b"1", b"2"), (b"2", b"2")],
         "loop 1 (hole 1) has coordinates of dtype |S1, not real numbers"),
        (np.ones((3, 2), dtype=bool), "loop 1 (hole 1) has coordinates of dtype bool"),
        ("abc", "loop 1 (hole 1) is a string, not an array of nodes"),
        ([(1.0, 1.0), (1.0, 2.0, 0.0), (2.0, 2.0)],
         "loop 1 (hole 1) node 1 has 3 coordinates; each node is an (x, y) pair"),
        ([(1.0, 1.0), (1.0, 2.0), (2.0,)],
         "loop 1 (hole 1) node 2 has 1 coordinate; each node is an (x, y) pair"),
        ([(1.0, 1.0), (1.0, 2.0), [(2.0, 2.0)]],
         "loop 1 (hole 1) node 2 has nested sequences; each node is an (x, y) pair"),
        (np.ma.masked_array(SMALL_HOLE, mask=[[0, 0], [0, 0], [0, 1], [0, 0]]),
         "loop 1 (hole 1) node 2 is masked"),
        ([(1.0, 1.0), (1.0, math.nan), (2.0, 2.0)],
         "loop 1 (hole 1) has a non-finite coordinate at node 1"),
        ([(1.0, 1.0), (2.0, 2.0), (1.0, 1.0)],
         "loop 1 (hole 1) has 2 distinct nodes; a loop needs at least 3"),
        ([(1.0, 1.0)], "loop 1 (hole 1) has 1 distinct nodes; a loop needs at least 3"),
        (np.zeros((0, 2)), "loop 1 (hole 1) has 0 distinct nodes; a loop needs at least 3"),
        ([], "loop 1 (hole 1) must be an (n, 2) array of nodes, got shape (0,)"),
        (None, "loop 1 (hole 1) must be an (n, 2) array of nodes, got shape ()"),
    ],
)  # fmt: skip
def test_bad_coordinates_name_the_loop_and_node(hole, expected):
    message = raises_geometry([SQUARE, hole])
    assert message.startswith(expected), message


def test_big_int_in_the_outer_loop_is_a_geometry_error_not_an_overflow():
    message = raises_geometry([[(0, 0), (10**400, 0), (0, 1)]])
    assert message == (
        "loop 0 (outer) node 1 has a coordinate too large for float64: "
        "100000000000... (401 characters)"
    )


@pytest.mark.parametrize("loops", [None, 3.5, "loops", b"loops", {"outer": [(0, 0), (1, 0)]}])
def test_loops_that_are_no_sequence_are_a_type_error(loops):
    with pytest.raises(TypeError, match="from_loops takes a sequence of loops"):
        Domain.from_loops(loops)


def test_real_numbers_of_any_type_become_the_nearest_float():
    third, big = Fraction(1, 3), 2**60 + 1  # neither is a float: both round
    loops = [
        np.array([(0, 0), (Decimal("3.5"), 0), (0, big)], dtype=object),
        [(third, third), (1, third), (third, np.float32(1.5))],
    ]
    domain = Domain.from_loops(loops)
    expected = [[0.0, 0.0], [3.5, 0.0], [0.0, float(big)],
                [float(third), float(third)], [1.0, float(third)], [float(third), 1.5]]  # fmt: skip
    assert domain.points.tolist() == expected
    ints = Domain.from_loops([np.array(TRIANGLE, dtype=np.int16), [(1, 1), (1, 0.5), (0.5, 1)]])
    assert ints.points[:3].tolist() == [list(p) for p in TRIANGLE]


def test_repeated_consecutive_node_names_the_zero_length_segment():
    outer = [(0.0, 0.0), (4.0, 0.0), (4.0, 4.0), (4.0, 4.0), (0.0, 4.0)]
    message = raises_geometry([outer])
    assert message.startswith("loop 0 (outer) segment 2 has zero length: nodes 2 and 3 coincide")


def test_collinear_loop_has_zero_area():
    assert raises_geometry([[(0.0, 0.0), (1.0, 1.0), (3.0, 3.0)]]) == (
        "loop 0 (outer) has zero area: all its nodes are collinear"
    )


def test_bow_tie_names_the_two_crossing_segments():
    bow_tie = [(0.0, 0.0), (1.0, 1.0), (1.0, 0.0), (0.0, 1.0)]
    assert raises_geometry([bow_tie]) == "loop 0 (outer) segment 2 crosses loop 0 (outer) segment 0"


def test_fold_back_overlap():
    loop = [(0.0, 0.0), (2.0, 0.0), (1.0, 0.0), (1.0, 1.0)]
    message = raises_geometry([loop])
    assert "overlaps" in message
    assert_names_meeting_segments(message, [loop])


def test_loop_touching_itself():
    loop = [(0.0, 0.0), (4.0, 0.0), (4.0, 4.0), (2.0, 0.0), (0.0, 4.0)]
    message = raises_geometry([loop])
    assert "touches" in message
    assert_names_meeting_segments(message, [loop])


def test_hole_crossing_outer_names_both_loops():
    hole = [(3.0, 1.0), (5.0, 2.0), (3.0, 3.0)]
    message = raises_geometry([SQUARE, hole])
    assert message in {
        "loop 1 (hole 1) segment 0 crosses loop 0 (outer) segment 1",
        "loop 1 (hole 1) segment 1 crosses loop 0 (outer) segment 1",
    }


def test_hole_touching_outer_at_a_vertex():
    hole = [(4.0, 2.0), (3.0, 1.0), (3.0, 3.0)][::-1]
    message = raises_geometry([SQUARE, hole])
    assert "touches" in message
    assert_names_meeting_segments(message, [SQUARE, hole])


def test_hole_outside_outer():
    far = [(10.0, 10.0), (11.0, 10.0), (11.0, 11.0)]
    assert raises_geometry([SQUARE, SMALL_HOLE, far]).startswith(
        "loop 2 (hole 2) lies outside the outer loop"
    )


def test_outer_given_after_its_hole_is_reported():
    message = raises_geometry([SMALL_HOLE, SQUARE])
    assert message.startswith("loop 1 (hole 1) lies outside the outer loop")
    assert "first loop must be the outer boundary" in message


def test_hole_inside_another_hole():
    big = [(0.5, 0.5), (3.5, 0.5), (3.5, 3.5), (0.5, 3.5)]
    message = raises_geometry([SQUARE, big, SMALL_HOLE])
    assert message == "loop 2 (hole 2) lies inside loop 1 (hole 1); nested holes are not supported"


def test_overlapping_holes():
    other = [(1.5, 1.5), (3.0, 1.5), (3.0, 3.0), (1.5, 3.0)]
    message = raises_geometry([SQUARE, SMALL_HOLE, other])
    assert message.startswith("loop 2 (hole 2) segment")
    assert "loop 1 (hole 1) segment" in message
    assert_names_meeting_segments(message, [SQUARE, SMALL_HOLE, other])


def test_holes_sharing_a_vertex_touch():
    first = [(1.0, 1.0), (2.0, 1.0), (2.0, 2.0)]
    second = [(2.0, 2.0), (3.0, 2.0), (3.0, 3.0)]
    message = raises_geometry([SQUARE, first, second])
    assert "touches" in message
    assert_names_meeting_segments(message, [SQUARE, first, second])


def test_crossing_far_along_a_long_boundary_is_found():
    n = 12_000
    t = 2 * np.pi * np.arange(n) / n
    circle = np.column_stack([np.cos(t), np.sin(t)])
    i = 7_321
    circle[[i, i + 1]] = circle[[i + 1, i]]
    message = raises_geometry([circle])
    assert message == f"loop 0 (outer) segment {i + 1} crosses loop 0 (outer) segment {i - 1}"


# --- validation against the exact oracle on a small grid (many degeneracies) --------

grid_loop = st.lists(
    st.tuples(st.integers(0, 4), st.integers(0, 4)).map(lambda p: (float(p[0]), float(p[1]))),
    min_size=3,
    max_size=7,
)


@budget(300)
@given(grid_loop)
def test_single_loop_accepted_iff_simple(loop):
    invalid = loop_problem(loop)
    if invalid:
        message = raises_geometry([loop])
        assert message.startswith("loop 0 (outer)")
        if CONFLICT.search(message):
            assert_names_meeting_segments(message, [loop])
        return
    domain = Domain.from_loops([loop])
    assert signed_area(domain.points[domain.loops[0]].tolist()) > 0
    assert domain.area == pytest.approx(float(abs(signed_area(loop))), rel=1e-15)


def star_ordered(points):
    """Distinct points sorted by angle around their mean: usually a simple loop."""
    points = sorted(set(points))
    cx = sum(p[0] for p in points) / len(points)
    cy = sum(p[1] for p in points) / len(points)
    return sorted(points, key=lambda p: math.atan2(p[1] - cy, p[0] - cx))


def star_loop(low, high, offset):
    coordinate = st.integers(low, high).map(lambda v: v + offset)
    return st.lists(st.tuples(coordinate, coordinate), min_size=3, max_size=8).map(star_ordered)


@budget(300)
@given(star_loop(0, 8, 0.0), star_loop(1, 6, 0.5))
def test_outer_and_hole_accepted_iff_valid(outer, hole):
    assume(not loop_problem(outer) and not loop_problem(hole))
    meet = loops_meet(outer, hole)
    valid = not meet and strictly_inside(hole[0], outer)
    if not valid:
        message = raises_geometry([outer, hole])
        if meet:
            assert_names_meeting_segments(message, [outer, hole])
        else:
            assert message.startswith("loop 1 (hole 1) lies outside the outer loop")
        return
    domain = Domain.from_loops([outer, hole])
    expected = abs(signed_area(outer)) - abs(signed_area(hole))
    assert domain.area == pytest.approx(float(expected), rel=1e-14)
    assert strictly_inside(tuple(domain.hole_points[0]), hole)


# --- the sweep against brute force over all pairs -------------------------------------


def brute_force_conflicts(points, segments) -> dict:
    points = [tuple(map(float, p)) for p in points]
    found = {}
    for i in range(len(segments)):
        for j in range(i + 1, len(segments)):
            kind = segment_conflict(points, segments[i], segments[j])
            if kind:
                found[i, j] = kind
    return found


def assert_find_crossing_agrees(points, segments) -> None:
    """Yes/no as brute force, and a reported pair is a true conflict of that kind."""
    conflicts = brute_force_conflicts(points, segments)
    result = find_crossing(np.array(points, dtype=float), np.array(segments).reshape(-1, 2))
    if result is None:
        assert not conflicts
        return
    i, j, verb = result
    assert i < j
    assert conflicts.get((i, j)) == verb, (result, conflicts)


grid_coordinate = st.integers(0, 4).map(float)


@st.composite
def arbitrary_segments(draw):
    """Segments between points of a 5 x 5 grid; points may repeat (distinct indices
    at one place), segments may share ends, repeat or run along each other."""
    points = draw(st.lists(st.tuples(grid_coordinate, grid_coordinate), min_size=2, max_size=9))
    pairs = [(i, j) for i in range(len(points)) for j in range(len(points))]
    pairs = [(i, j) for i, j in pairs if points[i] != points[j]]
    assume(pairs)
    return points, draw(st.lists(st.sampled_from(pairs), min_size=1, max_size=8))


@st.composite
def mostly_planar_segments(draw):
    """A subset of the edges of a triangulated grid (they never cross; many share ends
    and lie along one line) in random directions, plus up to two arbitrary segments
    (often long): conflict-free sets are common, and one segment can spoil them."""
    k = draw(st.integers(2, 5))
    points = [(float(i), float(j)) for i in range(k) for j in range(k)]
    edges = []
    for i in range(k):
        for j in range(k):
            here = i * k + j
            if i + 1 < k:
                edges.append((here, here + k))
            if j + 1 < k:
                edges.append((here, here + 1))
            if i + 1 < k and j + 1 < k:
                edges.append((here, here + k + 1) if (i + j) % 2 else (here + 1, here + k))
    chosen = draw(st.lists(st.sampled_from(edges), unique=True, min_size=1, max_size=12))
    node = st.integers(0, k * k - 1)
    extra = draw(st.lists(st.tuples(node, node).filter(lambda e: e[0] != e[1]), max_size=2))
    segments = [e[::-1] if draw(st.booleans()) else e for e in chosen + extra]
    order = draw(st.permutations(range(len(segments))))
    return points, [segments[s] for s in order]


@budget(300)
@given(arbitrary_segments())
def test_find_crossing_agrees_with_brute_force(case):
    assert_find_crossing_agrees(*case)


@budget(300)
@given(mostly_planar_segments())
def test_find_crossing_agrees_with_brute_force_on_nearly_planar_sets(case):
    assert_find_crossing_agrees(*case)


def test_find_crossing_examples():
    square = [(0.0, 0.0), (2.0, 0.0), (2.0, 2.0), (0.0, 2.0)]
    assert find_crossing(square, [(0, 1), (1, 2), (2, 3), (3, 0)]) is None
    assert find_crossing(square, [(0, 2), (1, 3)]) == (0, 1, "crosses")
    assert find_crossing(square, [(0, 1), (1, 0)]) == (0, 1, "overlaps")
    assert find_crossing(square, [(0, 1), (2, 3)]) is None
    points = [(0.0, 0.0), (2.0, 0.0), (1.0, 0.0), (1.0, 3.0)]
    assert find_crossing(points, [(0, 1), (2, 3)]) == (0, 1, "touches")
    # a free point at an end node's place is no segment's business
    assert find_crossing(square + [(0.0, 0.0)], [(0, 1), (1, 2)]) is None


@pytest.mark.parametrize("swap", [False, True])
@pytest.mark.parametrize("flip_x", [1.0, -1.0])
@pytest.mark.parametrize("flip_y", [1.0, -1.0])
def test_crossing_hidden_behind_a_short_segment_is_found(swap, flip_x, flip_y):
    """Two long segments that cross only after a short one between them has ended:
    they are never neighbours at an insertion, only after that removal."""
    points = [(0, 0), (8, 8), (2, 8), (8, 0), (1, 4), (3, 4)]
    points = [((y, x) if swap else (x, y)) for x, y in points]
    points = [(flip_x * x, flip_y * y) for x, y in points]
    segments = [(4, 5), (0, 1), (2, 3)]
    assert brute_force_conflicts(points, segments) == {(1, 2): "crosses"}
    assert find_crossing(points, segments) == (1, 2, "crosses")


def test_find_crossing_rejects_bad_segments():
    square = [(0.0, 0.0), (2.0, 0.0), (2.0, 2.0), (0.0, 2.0)]
    with pytest.raises(GeometryError, match=r"segment 1 = \(2, 2\) has zero length"):
        find_crossing(square, [(0, 1), (2, 2)])
    with pytest.raises(GeometryError, match="index out of range"):
        find_crossing(square, [(0, 4)])
    with pytest.raises(GeometryError, match="point 1 = .* outside the exact predicates"):
        find_crossing([(0.0, 0.0), (1e200, 0.0)], [(0, 1)])


@st.composite
def rectangle_layouts(draw):
    """Axis-parallel rectangles and right triangles on a 25 x 25 grid, each in a random
    orientation from a random node, most drawn within the box of an earlier one
    (loop 0 is often the whole grid): nested several deep, apart, touching,
    crossing, overlapping."""
    loops, boxes = [], []
    for _ in range(draw(st.integers(1, 7))):
        host = draw(st.sampled_from([None, *boxes, *boxes[-1:] * 4]))  # mostly the last one
        low, high = (0, 24) if host is None else (host[0] + 1, host[1] - 1)
        low_y, high_y = (0, 24) if host is None else (host[2] + 1, host[3] - 1)
        if high - low < 1 or high_y - low_y < 1:
            low, high, low_y, high_y = 0, 24, 0, 24
        x0, x1 = sorted(draw(st.lists(st.integers(low, high), min_size=2, max_size=2, unique=True)))
        y0, y1 = sorted(
            draw(st.lists(st.integers(low_y, high_y), min_size=2, max_size=2, unique=True))
        )
        if not boxes and draw(st.booleans()):
            x0, x1, y0, y1 = 0, 24, 0, 24
        boxes.append((x0, x1, y0, y1))
        corners = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
        cut = draw(st.integers(-6, 3))  # a rectangle, or a triangle without corner `cut`
        if cut >= 0:
            del corners[cut]
        if draw(st.booleans()):
            corners.reverse()
        start = draw(st.integers(0, len(corners) - 1))
        loops.append([(float(x), float(y)) for x, y in corners[start:] + corners[:start]])
    if len(loops) > 1 and draw(st.booleans()):  # the largest loop first, as a user would
        biggest = max(range(len(loops)), key=lambda k: abs(signed_area(loops[k])))
        loops.insert(0, loops.pop(biggest))
    return loops


def holes_inside(loops, k) -> list[int]:
    """The holes whose inside holds loop k (the loops are known to be disjoint)."""
    return [j for j in range(1, len(loops)) if j != k and strictly_inside(loops[k][0], loops[j])]


def assert_layout_verdict(loops) -> None:
    """Accepted iff valid by brute force; a rejection names a true fault, the first one."""
    meet = any(loops_meet(loops[i], loops[j]) for i in range(len(loops)) for j in range(i))
    outside = [k for k in range(1, len(loops)) if not strictly_inside(loops[k][0], loops[0])]
    nested = [k for k in range(1, len(loops)) if holes_inside(loops, k)]
    if not (meet or outside or nested):
        domain = Domain.from_loops(loops)
        expected = abs(signed_area(loops[0])) - sum(abs(signed_area(r)) for r in loops[1:])
        assert domain.area == float(expected)
        for k, point in enumerate(domain.hole_points.tolist(), start=1):
            assert strictly_inside(tuple(point), loops[k])
        return
    message = raises_geometry(loops)
    if meet:
        assert_names_a_true_conflict(message, loops)
        return
    first_bad = min(outside + nested)
    if first_bad in outside:
        assert message == (
            f"loop {first_bad} (hole {first_bad}) lies outside the outer loop "
            "(the first loop must be the outer boundary)"
        )
        return
    match = re.fullmatch(
        rf"loop {first_bad} \(hole {first_bad}\) lies inside loop (\d+) \(hole \d+\); "
        "nested holes are not supported",
        message,
    )
    assert match, message
    around = holes_inside(loops, first_bad)
    j = int(match.group(1))
    assert j in around
    # the hole named is the nearest around it: no other hole sits between them
    assert not [m for m in around if m != j and strictly_inside(loops[m][0], loops[j])]


@budget(300)
@given(rectangle_layouts())
def test_nesting_and_contact_of_many_loops_against_brute_force(loops):
    assert_layout_verdict(loops)


@st.composite
def nested_boxes(draw):
    """Rectangles nested as a random tree, no two meeting: each child lies in its own
    quarter of its parent's box.  In random order, holes end up inside holes, outside
    the first loop, or all valid; the lowest nodes often sit straight above others."""
    boxes = []

    def grow(x0, y0, size, depth):
        boxes.append((x0, y0, size))
        half = size // 2
        if depth == 3 or half < 3:
            return
        for qx, qy in ((x0, y0), (x0 + half, y0), (x0, y0 + half), (x0 + half, y0 + half)):
            if draw(st.booleans()):
                margin = draw(st.integers(1, max(1, half // 4)))
                grow(qx + margin, qy + margin, half - 2 * margin, depth + 1)

    grow(0, 0, 64, 0)
    order = draw(st.permutations(range(len(boxes))))
    if draw(st.booleans()):
        order = [0] + [k for k in order if k != 0]
    loops = []
    for k in order:
        x0, y0, size = boxes[k]
        corners = [(x0, y0), (x0 + size, y0), (x0 + size, y0 + size), (x0, y0 + size)]
        if draw(st.booleans()):
            corners.reverse()
        start = draw(st.integers(0, 3))
        loops.append([(float(x), float(y)) for x, y in corners[start:] + corners[:start]])
    return loops


@budget(150)
@given(nested_boxes())
def test_nesting_of_disjoint_loops_against_brute_force(loops):
    assert_layout_verdict(loops)


@budget(60)
@given(
    st.integers(2, 5),
    st.integers(0, 24),
    st.lists(st.integers(0, 10), min_size=4, max_size=4),
    st.booleans(),
)
def test_grid_of_holes_with_one_displaced(side, which, box, reverse):
    """Many holes: one is replaced by a rectangle anywhere (it may swallow, touch or
    cross others, or leave the domain)."""
    outer = [(0.0, 0.0), (2.0 * side, 0.0), (2.0 * side, 2.0 * side), (0.0, 2.0 * side)]
    holes = [
        [(2.0 * i + 0.5, 2.0 * j + 0.5), (2.0 * i + 1.5, 2.0 * j + 0.5),
         (2.0 * i + 1.5, 2.0 * j + 1.5), (2.0 * i + 0.5, 2.0 * j + 1.5)]
        for i in range(side) for j in range(side)
    ]  # fmt: skip
    x0, x1 = sorted(box[:2])
    y0, y1 = sorted(box[2:])
    assume(x0 < x1 and y0 < y1)
    moved = [(x0 + 0.5, y0 + 0.5), (x1 + 0.5, y0 + 0.5), (x1 + 0.5, y1 + 0.5), (x0 + 0.5, y1 + 0.5)]
    holes[which % len(holes)] = moved[::-1] if reverse else moved
    assert_layout_verdict([outer, *holes])


@budget(60)
@given(st.integers(2, 20), st.data())
def test_comb_of_long_teeth_with_one_node_moved(teeth, data):
    """Long horizontal segments spanning the sweep (the quadratic shape of a naive
    sweep); one node moved anywhere may make them cross, touch or overlap."""
    length = 64
    comb = []
    for k in range(teeth):
        comb += [(0, 2 * k), (length, 2 * k), (length, 2 * k + 1), (0, 2 * k + 1)]
    comb[0], comb[-1] = (-1, 0), (-1, 2 * teeth - 1)
    node = data.draw(st.integers(0, len(comb) - 1))
    comb[node] = (
        data.draw(st.integers(-1, length + 1)),
        data.draw(st.integers(0, 2 * teeth)),
    )
    loop = [(float(x), float(y)) for x, y in comb]
    if loop_problem(loop):
        message = raises_geometry([loop])
        assert message.startswith("loop 0 (outer)")
        if CONFLICT.search(message):
            assert_names_a_true_conflict(message, [loop])
        return
    assert Domain.from_loops([loop]).area == float(abs(signed_area(loop)))


def test_deep_nesting_names_the_directly_enclosing_hole():
    def square(c, r):
        return [(c - r, c - r), (c + r, c - r), (c + r, c + r), (c - r, c + r)]

    loops = [square(10.0, 10.0), square(10.0, 8.0), square(10.0, 6.0), square(10.0, 4.0)]
    message = raises_geometry([loops[0], loops[3], loops[1], loops[2]])
    assert message == "loop 1 (hole 1) lies inside loop 3 (hole 3); nested holes are not supported"


# --- orientation, layout and derived quantities ----------------------------------------


@budget(60)
@given(domains(), st.data())
def test_orientation_is_normalised_whatever_the_input_orientation(case, data):
    flips = data.draw(st.lists(st.booleans(), min_size=len(case.loops), max_size=len(case.loops)))
    loops = [ring[::-1] if flip else ring for ring, flip in zip(case.loops, flips)]
    domain = Domain.from_loops(loops)
    np.testing.assert_array_equal(domain.points, np.vstack(loops))
    for k, index in enumerate(domain.loops):
        area = signed_area(domain.points[index].tolist())
        assert (area > 0) if k == 0 else (area < 0)
        # each loop starts at the node the user gave first
        assert index[0] == sum(len(ring) for ring in loops[:k])
        assert sorted(index.tolist()) == list(range(index[0], index[0] + len(loops[k])))
    # segments chain each loop's nodes in the loop's oriented order
    expected = np.concatenate([np.column_stack([ix, np.roll(ix, -1)]) for ix in domain.loops])
    np.testing.assert_array_equal(domain.segments, expected)


@budget(40)
@given(domains())
def test_segments_agree_with_an_independent_orientation(case):
    domain = Domain.from_loops(case.loops)
    np.testing.assert_array_equal(
        np.sort(domain.segments, axis=0), np.sort(case.segments(), axis=0)
    )


@budget(40)
@given(domains(), st.sampled_from([1e6, -3e7]))
def test_area_does_not_depend_on_where_the_domain_lies(case, offset):
    domain = Domain.from_loops(case.loops)
    shifted = Domain.from_loops([ring + offset for ring in case.loops])
    # coordinates near 1e7 carry ~1e-9 of rounding: the area may move that much, no more
    assert shifted.area == pytest.approx(domain.area, rel=1e-7)


def test_arrays_are_read_only_and_typed():
    domain = Domain.from_loops([SQUARE, SMALL_HOLE])
    assert domain.points.dtype == np.float64 and domain.points.shape == (8, 2)
    assert domain.segments.dtype == np.int64 and domain.segments.shape == (8, 2)
    assert domain.hole_points.shape == (1, 2)
    with pytest.raises(ValueError):
        domain.points[0, 0] = 1.0
    assert repr(domain) == "Domain(nodes=8, holes=1, area=15)"


@budget(60)
@given(domains())
def test_area_and_hole_points_against_shapely(case):
    pytest.importorskip("shapely")
    from shapely.geometry import Point, Polygon

    domain = Domain.from_loops(case.loops)
    polygon = Polygon(case.loops[0], case.loops[1:])
    assert polygon.is_valid
    assert domain.area == pytest.approx(polygon.area, rel=1e-12)
    assert len(domain.hole_points) == len(case.loops) - 1
    for ring, point in zip(case.loops[1:], domain.hole_points):
        assert Polygon(ring).contains(Point(point))
        assert not polygon.intersects(Point(point))


def test_hole_point_of_a_thin_non_convex_hole():
    # a comb: the vertex centroid lies outside it, the scan line finds a tooth
    comb = [
        (1.0, 1.0),
        (3.0, 1.0),
        (3.0, 3.0),
        (2.9, 3.0),
        (2.9, 1.1),
        (1.1, 1.1),
        (1.1, 3.0),
        (1.0, 3.0),
    ]
    domain = Domain.from_loops([SQUARE, comb])
    assert strictly_inside(tuple(domain.hole_points[0]), comb)


@pytest.mark.slow
def test_large_boundary_validates_quickly():
    import time

    n = 50_000
    t = 2 * np.pi * np.arange(n) / n
    circle = np.column_stack([np.cos(t), np.sin(t)])
    Domain.from_loops([circle[::500], 0.5 * circle[::500]])  # compile outside the timing
    start = time.perf_counter()
    domain = Domain.from_loops([circle, 0.5 * circle])
    assert time.perf_counter() - start < 5.0
    assert domain.area == pytest.approx(0.75 * np.pi, rel=1e-6)


# --- .poly ------------------------------------------------------------------------------


POLY_ONE_BASED = """\
# a square with a square hole; numbered from 1, attributes and markers present
8 2 1 1
1 0 0   0.5 1
2 4 0   0.5 1
3 4 4   0.5 1  # trailing comment
4 0 4   0.5 1

5 1 1   0.5 2
6 2 1   0.5 2
7 2 2   0.5 2
8 1 2   0.5 2
8 1
1 1 2 1
2 3 2 1
3 3 4 1
4 1 4 1
5 5 6 2
6 7 6 2
7 7 8 2
8 5 8 2
1
1 1.5 1.5
"""


def test_from_poly_one_based_with_attributes_markers_and_comments(tmp_path):
    path = tmp_path / "square.poly"
    path.write_text(POLY_ONE_BASED)
    domain = Domain.from_poly(path)
    np.testing.assert_array_equal(domain.points[:4], SQUARE)
    assert domain.area == 15.0
    assert [ix.tolist() for ix in domain.loops] == [[0, 1, 2, 3], [4, 7, 6, 5]]


def test_from_poly_zero_based_hole_loop_listed_first(tmp_path):
    path = tmp_path / "zero.poly"
    path.write_text(
        "8 2 0 0\n0 1 1\n1 2 1\n2 2 2\n3 1 2\n4 0 0\n5 4 0\n6 4 4\n7 0 4\n"
        "8 0\n0 0 1\n1 1 2\n2 2 3\n3 3 0\n4 4 5\n5 5 6\n6 6 7\n7 7 4\n0\n"
    )
    domain = Domain.from_poly(path)  # no hole points: the nested loop is the hole
    np.testing.assert_array_equal(domain.points[:4], SQUARE)
    assert domain.area == 15.0
    assert strictly_inside(tuple(domain.hole_points[0]), SMALL_HOLE)


def test_from_poly_reads_a_node_file_when_vertex_count_is_zero(tmp_path):
    (tmp_path / "t.node").write_text("3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n")
    (tmp_path / "t.poly").write_text("0 2 0 0\n3 0\n1 1 2\n2 2 3\n3 3 1\n0\n")
    assert Domain.from_poly(tmp_path / "t.poly").area == 0.5


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("4 2 0 0\n1 0 0\n2 1 0\n3 0 1\n4 5 5\n3 0\n1 1 2\n2 2 3\n3 3 1\n",
         "vertex 4 at (5.0, 5.0) is on no segment of the domain and lies outside it"),
        ("4 2 0 0\n1 0 0\n2 1 0\n3 0 1\n4 1 1\n4 0\n1 1 2\n2 2 3\n3 3 1\n4 1 4\n",
         "vertex 4 at (1.0, 1.0) is on no segment of the domain and lies outside it"),
        ("3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n3 0\n1 1 2\n2 2 2\n3 3 1\n",
         "segment 2 joins vertex 2 at (1.0, 0.0) to itself"),
        ("3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n3 0\n1 1 2\n2 2 4\n3 3 1\n",
         "segment 2 names a vertex that does not exist"),
        ("3 2 0 0\n1 0 0\n3 1 0\n4 0 1\n", "vertex 3 where 2 was expected"),
        ("3 2 0 0\n1 0 0\n2 1 0\n", "file ends where a vertex was expected"),
        ("3 2 0 0\n1 0 0\n2 one 0\n3 0 1\n", "line 3: bad number in a vertex"),
    ],
)  # fmt: skip
def test_from_poly_file_errors(tmp_path, text, expected):
    path = tmp_path / "bad.poly"
    path.write_text(text)
    with pytest.raises(GeometryError, match=re.escape(expected)):
        Domain.from_poly(path)


def test_from_poly_splits_crossing_segments_as_triangle_does(tmp_path):
    (tmp_path / "x.poly").write_text("4 2 0 0\n1 0 0\n2 2 0\n3 2 2\n4 0 2\n"
                                     "6 0\n1 1 2\n2 2 3\n3 3 4\n4 4 1\n5 1 3\n6 2 4\n0\n")
    domain = Domain.from_poly(tmp_path / "x.poly")
    assert domain.area == 4.0 and domain.points[-1].tolist() == [1.0, 1.0]
    assert int(domain.interior.sum()) == 2 * 4  # both diagonals, split at the centre


def test_from_poly_inner_loop_without_hole_point_is_a_constraint_loop(tmp_path):
    second = [(2.5, 2.5), (3.5, 2.5), (3.5, 3.5), (2.5, 3.5)]
    Domain.from_loops([SQUARE, SMALL_HOLE, second]).to_poly(tmp_path / "three.poly")
    text = (tmp_path / "three.poly").read_text()
    head, _holes = text.rsplit("\n2\n", 1)  # keep only the first hole point
    (tmp_path / "three.poly").write_text(head + "\n1\n1 1.5 1.5\n")
    domain = Domain.from_poly(tmp_path / "three.poly")  # Triangle's -p: an interface loop
    assert domain.area == 15.0
    assert int(domain.interior.sum()) == 2 * len(second)  # both sides of each of its segments


def test_from_poly_hole_point_in_the_domain_is_rejected(tmp_path):
    path = tmp_path / "h.poly"
    path.write_text(POLY_ONE_BASED.replace("1 1.5 1.5", "1 3.0 3.0"))
    with pytest.raises(GeometryError):  # as in Triangle it eats its face: nothing valid is left
        Domain.from_poly(path)


def test_from_poly_hole_point_on_a_hole_boundary_is_rejected(tmp_path):
    path = tmp_path / "h.poly"
    path.write_text(POLY_ONE_BASED.replace("1 1.5 1.5", "1 1.5 2.0"))
    with pytest.raises(
        GeometryError, match=r"hole point 1 at \(1.5, 2.0\) lies on a segment"
    ):
        Domain.from_poly(path)


def test_from_poly_names_file_loop_starts_on_geometry_errors(tmp_path):
    path = tmp_path / "x.poly"
    path.write_text(POLY_ONE_BASED.replace("6 2 1   0.5 2", "6 5 1.5 0.5 2"))
    with pytest.raises(GeometryError) as info:
        Domain.from_poly(path)
    message = str(info.value)
    assert re.search(r"loop 1 \(hole 1\) segment [01] crosses loop 0 \(outer\) segment 1", message)
    assert message.startswith(str(path))
    assert message.endswith("(loop 0 starts at vertex 1, loop 1 starts at vertex 5)")


@budget(40)
@given(domains())
def test_poly_round_trip_is_exact(tmp_path_factory, case):
    path = tmp_path_factory.mktemp("poly") / "d.poly"
    domain = Domain.from_loops(case.loops)
    domain.to_poly(path)
    again = Domain.from_poly(path)
    np.testing.assert_array_equal(again.points, domain.points)
    np.testing.assert_array_equal(again.segments, domain.segments)
    np.testing.assert_array_equal(again.hole_points, domain.hole_points)
    assert again.area == domain.area


def _segment_set(domain):
    """{((a, b), marker)} of a domain's segments, by node coordinates."""
    P = np.asarray(domain.points).tolist()
    return {((tuple(P[a]), tuple(P[b])), int(m))
            for (a, b), m in zip(np.asarray(domain.segments).tolist(), domain.markers.tolist())}


def _assert_poly_keeps(domain, path):
    """``domain`` written to ``path`` reads back with the same nodes, holes,
    regions and area, the same segments with the same markers, and as
    Triangle's own reader sees the file: each undirected segment once,
    vertex markers 0 exactly on the nodes of no segment, else one of the
    markers of their segments."""
    triangle = pytest.importorskip("triangle")
    domain.to_poly(path)
    again = Domain.from_poly(path)
    np.testing.assert_array_equal(again.points, domain.points)
    np.testing.assert_array_equal(again.hole_points, domain.hole_points)
    assert again.area == domain.area
    assert _segment_set(again) == _segment_set(domain)
    if domain.regions is None:
        assert again.regions is None
    else:
        np.testing.assert_array_equal(again.regions, domain.regions)
    read = triangle.load(str(path.parent), path.stem)
    pairs = np.sort(read["segments"], axis=1)
    assert len(np.unique(pairs, axis=0)) == len(pairs)
    assert {tuple(p) for p in pairs.tolist()} == {
        tuple(sorted(s)) for s in np.asarray(domain.segments).tolist()}
    marks = read["vertex_markers"].ravel()
    for v in range(len(domain.points)):
        on = [int(m) for s, m in zip(np.asarray(domain.segments).tolist(),
                                     domain.markers.tolist()) if v in s]
        assert (marks[v] in on) if on else marks[v] == 0, (v, marks[v], on)


@pytest.mark.parametrize("name", ["la", "box.2", "face", "double_hex3"])
def test_poly_round_trip_keeps_constraints_markers_regions_and_free_points(tmp_path, name):
    """Triangle's examples: interior constraints (la, double_hex3), regions
    with areas (la), free points (box.2), markers (face).  The file's own
    markers and regions were lost before and free points got stray markers."""
    triangle = pytest.importorskip("triangle")
    source = Path(triangle.__file__).parent / "data" / f"{name}.poly"
    _assert_poly_keeps(Domain.from_poly(source), tmp_path / "out.poly")


def test_a_poly_segment_given_both_ways_reads_as_triangle_reads_it(tmp_path):
    """A crack inside a 4 x 4 square written as 5 -> 6 and 6 -> 5 (as
    bubblemesh itself wrote constraints before): Triangle meshes it as one
    constraint; it was refused as a loop of 2 nodes."""
    triangle = pytest.importorskip("triangle")
    path = tmp_path / "twice.poly"
    path.write_text("6 2 0 0\n1 0 0\n2 4 0\n3 4 4\n4 0 4\n5 1 2\n6 3 2\n"
                    "6 0\n1 1 2\n2 2 3\n3 3 4\n4 4 1\n5 5 6\n6 6 5\n0\n")
    domain = Domain.from_poly(path)
    file_points = [(0, 0), (4, 0), (4, 4), (0, 4), (1, 2), (3, 2)]
    assert sorted(map(tuple, domain.points.tolist())) == sorted(file_points)
    crack = {(1.0, 2.0), (3.0, 2.0)}
    inner = [{tuple(domain.points[a]), tuple(domain.points[b])}
             for (a, b), i in zip(domain.segments.tolist(), domain.interior) if i]
    assert inner == [crack, crack] and domain.area == 16.0
    mesh = triangle.triangulate(triangle.load(str(tmp_path), "twice"), "p")
    P, T = mesh["vertices"], mesh["triangles"]
    edges = [{tuple(P[a]), tuple(P[b])} for t in T.tolist() for a, b in zip(t, t[1:] + t[:1])]
    assert edges.count(crack) == 2  # Triangle's reading: one constraint, a triangle each side


def test_poly_round_trip_of_a_pslg_with_every_kind_of_item(tmp_path):
    """A constraint, a free point, a region with an area bound and markers
    of the user's own: all read back as given."""
    domain = Domain.from_pslg(loops=[[(0, 0), (4, 0), (4, 2), (0, 2)]],
                              constraints=[[(2, 0), (2, 2)]], points=[(1, 1)],
                              markers=[7, 9], regions=[(3, 1, 2.0, 0.05)])
    _assert_poly_keeps(domain, tmp_path / "pslg.poly")


# --- shapely ----------------------------------------------------------------------------


def test_from_shapely_keeps_ring_vertices_and_holes():
    pytest.importorskip("shapely")
    from shapely.geometry import Polygon

    domain = Domain.from_shapely(Polygon(SQUARE, [SMALL_HOLE]))
    assert len(domain.points) == 8  # shapely's closing repeats dropped
    assert domain.area == 15.0


def test_from_shapely_drops_repeated_vertices_shapely_holds_valid():
    """A ring that names a vertex twice in a row is valid to shapely (GEOS);
    the domain has each vertex once and shapely's area."""
    pytest.importorskip("shapely")
    from shapely.geometry import Polygon

    ring = [(0, 0), (2, 0), (2, 0), (2, 1), (1, 1), (1, 1), (1, 2), (0, 2), (0, 0)]
    shape = Polygon(ring, [[(0.2, 0.2), (0.4, 0.2), (0.4, 0.2), (0.4, 0.4)]])
    assert shape.is_valid
    domain = Domain.from_shapely(shape)
    assert len(domain.points) == len({*ring, (0.2, 0.2), (0.4, 0.2), (0.4, 0.4)})
    assert domain.area == pytest.approx(shape.area, rel=1e-15)


@pytest.mark.parametrize("holes", [
    pytest.param([[(2, 0), (3, 1), (1, 1)]], marks=pytest.mark.heavy),  # a corner on its edge
    [[(1, 1), (2, 1), (2, 2), (1, 2)], [(2, 2), (3, 2), (3, 3), (2, 3)]],  # two share a corner
])
def test_from_shapely_takes_holes_that_touch_a_ring_at_a_point(holes):
    """GEOS holds a hole that meets the outer ring or another hole at one
    point valid; the mesh covers exactly the polygon: GEOS's area, every
    triangle inside it (GEOS), the touching point a node."""
    pytest.importorskip("shapely")
    from shapely.geometry import Point, Polygon

    shape = Polygon([(0, 0), (4, 0), (4, 4), (0, 4)], holes)
    assert shape.is_valid
    mesh = mesh_domain(Domain.from_shapely(shape), max_area=0.5)
    P, T = mesh.points, mesh.triangles
    u, v = P[T[:, 1]] - P[T[:, 0]], P[T[:, 2]] - P[T[:, 0]]
    cross = u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]
    assert (cross > 0).all()
    assert 0.5 * cross.sum() == pytest.approx(shape.area, rel=1e-12)
    assert all(shape.contains(Point(c)) for c in P[T].mean(axis=1))
    touch = (2, 0) if len(holes) == 1 else (2, 2)
    assert (P == touch).all(axis=1).any()


def test_from_shapely_spacing_splits_edges_and_keeps_corners():
    pytest.importorskip("shapely")
    from shapely.geometry import Polygon

    outer = [(0.0, 0.0), (3.0, 0.0), (3.0, 1.0), (0.0, 1.0)]
    domain = Domain.from_shapely(Polygon(outer), spacing=0.4)
    # ceil(3/0.4) = 8 pieces on the long edges, ceil(1/0.4) = 3 on the short ones
    assert len(domain.points) == 2 * 8 + 2 * 3
    for corner in outer:
        assert (domain.points == corner).all(axis=1).any()
    lengths = np.hypot(
        *np.diff(domain.points[np.r_[domain.loops[0], domain.loops[0][0]]], axis=0).T
    )
    assert lengths.max() <= 0.4
    assert sorted(set(np.round(lengths, 12))) == [pytest.approx(1 / 3), pytest.approx(3 / 8)]


def test_from_shapely_multipolygon():
    pytest.importorskip("shapely")
    from shapely.geometry import MultiPolygon, Polygon

    assert Domain.from_shapely(MultiPolygon([Polygon(SQUARE)])).area == 16.0
    two = MultiPolygon([Polygon(SMALL_HOLE), Polygon([(5, 5), (6, 5), (6, 6)])])
    assert Domain.from_shapely(two).area == two.area  # several parts: one planar-graph domain
    with pytest.raises(ValueError, match="spacing"):
        Domain.from_shapely(Polygon(SQUARE), spacing=0.0)


def test_from_shapely_without_shapely_says_how_to_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "shapely", None)
    monkeypatch.setitem(sys.modules, "shapely.geometry", None)
    with pytest.raises(ImportError, match=r"pip install 'bubblemesh\[shapely\]'"):
        Domain.from_shapely(object())


def _on_ring_edge_exactly(p, ring):
    """p lies on an edge of ``ring`` (shapely coordinates), by exact rationals."""
    x, y = Fraction(float(p[0])), Fraction(float(p[1]))
    for (ax, ay), (bx, by) in zip(ring[:-1], ring[1:]):
        ax, ay, bx, by = map(Fraction, (ax, ay, bx, by))
        if ((bx - ax) * (y - ay) == (by - ay) * (x - ax) and min(ax, bx) <= x <= max(ax, bx)
                and min(ay, by) <= y <= max(ay, by)):
            return True
    return False


def test_from_shapely_size_samples_the_rings_from_the_size_field():
    """With ``size``: the ring vertices kept bit for bit, every other node
    exactly on an input edge, no piece longer than the size, and a slot
    narrower than the size sampled at its width."""
    pytest.importorskip("shapely")
    from shapely.geometry import box

    shape = box(0, 0, 4, 4).difference(box(1.9, 1, 2.1, 4.5))  # a U, its slot 0.2 wide
    domain = Domain.from_shapely(shape, size=0.5)
    P, S = np.asarray(domain.points), np.asarray(domain.segments)
    ring = list(shape.exterior.coords)
    for corner in ring:
        assert (P == corner).all(axis=1).any()
    assert all(_on_ring_edge_exactly(p, ring) for p in P)
    length = np.hypot(*(P[S[:, 0]] - P[S[:, 1]]).T)
    mid = 0.5 * (P[S[:, 0]] + P[S[:, 1]])
    assert length.max() <= 0.5 * (1 + 1e-9)
    slot = (abs(mid[:, 0] - 2) < 0.15) & (mid[:, 1] > 1.5)
    assert slot.sum() >= 2 and length[slot].max() <= 0.2 * (1 + 1e-9)
    finer = Domain.from_shapely(shape, size=lambda xy: np.full(len(xy), 0.25))
    assert len(finer.points) > len(P)
    with pytest.raises(ValueError, match="spacing or size"):
        Domain.from_shapely(shape, 0.1, size=0.1)
    with pytest.raises(ValueError, match="from_shapely: size"):
        Domain.from_shapely(shape, size=-1.0)
