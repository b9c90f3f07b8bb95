"""Whole rows across a straight channel (bubblemesh._channel, bm.mesh only).

The stretched triangle's ratio against eq. 10 computed here from its side
lengths (Heron); the rows and pieces against a brute-force search over every
whole-row choice; the channel found on rectangles in any position, and not
where the walls are not a strip (a hole between them, walls that overlap
too little or tilted, a graded field); L-shaped strips and parallelograms a
channel over the overlap of their walls; refine_boundary's splits at exactly the parameters
asked; and bm.mesh on strips, level and turned: a valid mesh within 5% of
the field's count, its walls cut as planned, the nodes of its middle half
on the m + 1 lines across it; with ``auto``, the plain walls' mesh kept
unless the channel's is better."""

from __future__ import annotations

import math

import numpy as np
import oracles as O
import pytest
from hypothesis import given
from hypothesis import strategies as st

import bubblemesh as bm
from bubblemesh._channel import (
    ASPECT,
    CORNER_SPAN,
    FEWER,
    LEAST_PIECES,
    LEAST_RATIO,
    SHARE,
    isosceles_ratio,
    rows_for,
    straight_channel,
)
from bubblemesh.pipeline import size_field
from bubblemesh.refinement import refine_boundary
from bubblemesh.sizing import SizeField


def _heron_ratio(P):
    a, b, c = (math.dist(P[i], P[(i + 1) % 3]) for i in range(3))
    s = 0.5 * (a + b + c)
    area = math.sqrt(max(s * (s - a) * (s - b) * (s - c), 0.0))
    return 2 * (area / s) / (a * b * c / (4 * area))


@given(st.floats(0.01, 100.0), st.floats(0.01, 100.0))
def test_the_stretched_triangle_ratio_is_eq10_of_that_triangle(base, height):
    want = _heron_ratio([(0.0, 0.0), (base, 0.0), (0.5 * base, height)])
    assert isosceles_ratio(base, height) == pytest.approx(want, rel=1e-9, abs=1e-12)


@given(st.floats(0.05, 5.0), st.floats(1.0, 50.0), st.floats(0.02, 1.0))
def test_rows_are_the_best_whole_choice_not_over_the_fields_count(width, length, h):
    """m of floor and ceil of the rows an equilateral size h gives, the
    2 m n triangles of base a and height b never more than the field's
    count (the area over sqrt(3) h^2 / 4); no other m, and no n with 2 m n
    between FEWER times that count and it, makes a better triangle."""
    m, n, a, b = rows_for(width, length, h)
    x = width / (math.sqrt(3) / 2 * h)
    rows = {max(1, math.floor(x)), max(1, math.ceil(x))}
    assert m in rows
    assert m * b == pytest.approx(width, rel=1e-12) and n * a == pytest.approx(length, rel=1e-12)
    count = length * width / (math.sqrt(3) / 4 * h * h)
    assert 2 * m * n <= count * (1 + 1e-12) or n == 1
    best = isosceles_ratio(a, b)
    for mm in rows:
        for nn in range(1, int(count) + 2):
            if FEWER * count <= 2 * mm * nn <= count:
                assert isosceles_ratio(length / nn, width / mm) <= best + 1e-12, (mm, nn)


def _rectangle(length, width, angle, origin):
    u = np.array([math.cos(angle), math.sin(angle)])
    v = np.array([-u[1], u[0]])
    return np.array([origin, origin + length * u, origin + length * u + width * v,
                     origin + width * v])


@given(st.floats(3.0, 20.0), st.floats(0.3, 1.0), st.integers(0, 359),
       st.integers(-50, 50), st.floats(0.1, 0.3))
def test_a_rectangle_is_a_channel_along_its_long_walls(length, width, degrees, shift, h):
    """Channels are found in any position; where the stretched triangle is
    too poor, the walls in too few pieces or too short for the width, none."""
    angle = math.radians(degrees)
    domain = bm.Domain.from_loops([_rectangle(length, width, angle, np.array([shift, -shift]))])
    field = SizeField.from_domain(domain, size=h)
    channel = straight_channel(domain, field, float(field.cap))
    m, n, a, b = rows_for(width, length, float(field.cap))
    if abs(length - ASPECT * width) <= 1e-9 * length:
        return  # on the edge: the turned corners' rounding decides
    if n < LEAST_PIECES or isosceles_ratio(a, b) < LEAST_RATIO or length < ASPECT * width:
        assert channel is None
        return
    assert channel is not None and channel.rows == m
    P, S = np.asarray(domain.points), np.asarray(domain.segments)
    lengths = np.hypot(*(P[S[:, 1]] - P[S[:, 0]]).T)
    assert lengths[channel.wall] == pytest.approx(length, rel=1e-9)
    assert lengths[channel.far] == pytest.approx(length, rel=1e-9)
    assert set(S[channel.wall]).isdisjoint(S[channel.far])
    assert len(channel.splits) == (4 if m > 1 else 2)


@pytest.mark.parametrize("loops", [
    # a hole between the long walls
    [np.array([(0, 0), (10, 0), (10, 1), (0, 1)], float),
     np.array([(5, 0.4), (5.2, 0.6), (5.4, 0.4)], float)],
    # the far wall shifted so far along that the walls overlap too little
    [np.array([(0, 0), (10, 0), (16.5, 1), (6.5, 1)], float)],
    # the far wall tilted: a trapezoid
    [np.array([(0, 0), (10, 0), (10, 1.02), (0, 1)], float)],
    # the far wall broken by a notch
    [np.array([(0, 0), (10, 0), (10, 1), (6, 1), (5, 0.5), (4, 1), (0, 1)], float)],
])
def test_no_channel_where_the_walls_are_not_a_strip(loops):
    domain = bm.Domain.from_loops(loops)
    field = SizeField.from_domain(domain, size=0.15)
    assert straight_channel(domain, field, float(field.cap)) is None


def test_no_channel_where_the_field_is_graded():
    domain = bm.Domain.from_loops([np.array([(0, 0), (10, 0), (10, 1), (0, 1)], float)])
    field = SizeField.from_domain(domain, size=lambda p: 0.1 + 0.01 * p[:, 0])
    assert straight_channel(domain, field, float(field.cap)) is None


def _overlapping(kind, length, extra, angle, origin):
    """An L-shaped strip (its arm ``extra`` tall) or a parallelogram (its far
    wall shifted ``extra`` along), 1 wide, its bottom wall ``length`` long
    from ``origin`` turned by ``angle``: (corners, u, [lo, hi]) with the
    bottom wall's direction and the walls' overlap along it."""
    if kind == "L":
        corners, overlap = [(0, 0), (length, 0), (length, 1), (1, 1), (1, extra), (0, extra)], (
            1.0, length)
    else:
        corners, overlap = [(0, 0), (length, 0), (length + extra, 1), (extra, 1)], (
            max(0.0, extra), min(length, length + extra))
    u = np.array([math.cos(angle), math.sin(angle)])
    turn = np.array([u, [-u[1], u[0]]])
    return origin + np.array(corners, float) @ turn, u, overlap


@given(st.sampled_from(["L", "parallelogram"]), st.floats(6.0, 12.0), st.floats(-1.5, 4.0),
       st.integers(0, 359), st.integers(-50, 50), st.floats(0.08, 0.3))
def test_walls_that_overlap_in_part_are_a_channel_over_the_overlap(kind, length, extra,
                                                                   degrees, shift, h):
    """An L-shaped strip or a parallelogram, in any position: the channel is
    the overlap of its long walls, in the rows and pieces :func:`rows_for`
    gives for the overlap; cut with its splits, each wall's nodes away from
    the overlap's ends lie exactly on its lattice row (row 0 half a piece
    in, row m another half piece per row) and none is missing; past the
    overlap, a wall is cut into equal pieces of about h (0.5 to 1.5 h, or
    one shorter piece)."""
    if kind == "L":  # an arm shorter than the channel: the channel holds half the area
        extra = min(2.0 + abs(extra), length - 1.5)
    corners, u, (lo, hi) = _overlapping(kind, length, extra, math.radians(degrees),
                                        np.array([shift, -shift], float))
    domain = bm.Domain.from_loops([corners])
    field = SizeField.from_domain(domain, size=h)
    cap = float(field.cap)
    channel = straight_channel(domain, field, cap)
    m, n, a, b = rows_for(1.0, hi - lo, cap)
    if min(abs(hi - lo - ASPECT), abs(hi - lo - SHARE * domain.area)) <= 1e-9 * length:
        return  # on the edge: the turned corners' rounding decides
    if (n < LEAST_PIECES or isosceles_ratio(a, b) < LEAST_RATIO or hi - lo < ASPECT
            or hi - lo < SHARE * domain.area):
        assert channel is None
        return
    assert channel is not None and channel.rows == m
    assert b == pytest.approx(1.0 / m) and a == pytest.approx((hi - lo) / n)
    P, S = np.asarray(domain.points), np.asarray(domain.segments)
    ends = P[S[[channel.wall, channel.far]]] - corners[0]
    offsets = np.sort(ends @ np.array([-u[1], u[0]]), axis=1)
    assert np.allclose(offsets[np.argsort(offsets[:, 0])], [[0, 0], [1, 1]], atol=1e-9)
    start, end = P[S[channel.wall]]
    u = (end - start) / np.linalg.norm(end - start)  # the lattice's frame: along row 0's wall
    far_ends = (P[S[channel.far]] - start) @ u
    lo, hi = max(0.0, far_ends.min()), min(float(np.linalg.norm(end - start)), far_ends.max())
    fine = np.asarray(refine_boundary(domain, cap, splits=channel.splits).to_domain().points)
    rel = fine - start
    along = rel @ u
    across = rel @ np.array([-u[1], u[0]])
    for line, shift_pieces in ((0.0, 0.5), (1.0, 0.5 * (m + 1))):
        wall = np.sort(along[np.abs(across - line) <= 1e-9])
        x = (wall - lo) / a - shift_pieces
        inner = (wall > lo + (CORNER_SPAN + 1) * a) & (wall < hi - (CORNER_SPAN + 1) * a)
        assert np.abs(x[inner] - np.round(x[inner])).max() <= 1e-6, line
        assert inner.sum() == len(np.unique(np.round(x[inner]))) >= n - 2 * CORNER_SPAN - 4
        want = np.arange(math.ceil(x[inner].min() - 1e-6), math.floor(x[inner].max() + 1e-6) + 1)
        assert len(want) == inner.sum(), line  # no lattice node left out
        for past in (wall <= lo + 1e-9, wall >= hi - 1e-9):
            pieces = np.diff(wall[past])
            if len(pieces) > 1:
                assert np.allclose(pieces, pieces[0], rtol=1e-6), line
                assert 0.5 * cap <= pieces[0] <= 1.5 * cap, line


@given(st.lists(st.floats(0.01, 0.99), min_size=1, max_size=12, unique=True),
       st.integers(0, 3))
def test_splits_put_the_nodes_at_exactly_those_parameters(ts, side):
    """The split segment's new nodes are a + t (b - a) for the given t (to
    the refinement's rounding of t), the other segments refined as without
    splits."""
    domain = bm.Domain.from_loops([np.array([(0, 0), (4, 0), (4, 3), (0, 3)], float)])
    S = np.asarray(domain.segments)
    i, j = (int(v) for v in S[side])
    t = np.sort(np.asarray(ts))
    fine = refine_boundary(domain, 0.5, splits={(i, j): t}).to_domain()
    plain = refine_boundary(domain, 0.5).to_domain()
    P = np.asarray(domain.points)
    want = P[i] + t[:, None] * (P[j] - P[i])
    new = np.asarray(fine.points)
    for w in want:  # t rounded to 40 bits puts a node exactly on its segment
        assert np.abs(new - w).sum(axis=1).min() <= 2.0 ** -38, w
    for a, b in S.tolist():
        want_pieces = len(t) + 1 if (a, b) == (i, j) else _pieces_on(plain, P, a, b)
        assert _pieces_on(fine, P, a, b) == want_pieces, (a, b)


def _pieces_on(refined, P, i, j):
    """The pieces the plain refinement cut segment i-j into."""
    Q = np.asarray(refined.points)
    a, b = P[i], P[j]
    d = b - a
    off = np.abs((Q[:, 0] - a[0]) * d[1] - (Q[:, 1] - a[1]) * d[0])
    along = ((Q - a) @ d) / (d @ d)
    return int(np.sum((off <= 1e-12) & (along > 1e-12) & (along < 1 - 1e-12))) + 1


@pytest.mark.parametrize("bad", [{(0, 2): [0.5]}, {(0, 1): [0.5, 0.4]}, {(0, 1): [0.0, 0.5]},
                                 {(0, 1): [float("nan")]}, {(0, 1): [1.0]}, {(0, 1): None},
                                 {(0, 1): ["x"]}, {"ab": [0.5]}, {(0,): [0.5]},
                                 {(0, 1, 2): [0.5]}])
def test_bad_splits_are_value_errors(bad):
    domain = bm.Domain.from_loops([np.array([(0, 0), (4, 0), (4, 3), (0, 3)], float)])
    with pytest.raises(ValueError, match="splits"):
        refine_boundary(domain, 0.5, splits=bad)


@pytest.mark.parametrize("k", [70, 100, 200, 300, 500, 1000])
@pytest.mark.parametrize("angle", [0.0, 0.7])
def test_a_strip_is_meshed_in_whole_rows(k, angle):
    """A 10 x 0.5 strip at max_area = area / k, turned by ``angle``, by
    frontal insertion (its lattice in the channel's rows; ``auto`` may keep
    the plain walls' mesh, the next test): a valid,
    conforming mesh within 5% of the field's count; its long walls cut
    into the n pieces of the m rows (:func:`rows_for`); in the middle half
    of the strip its nodes lie within 5% of a row's height of the m + 1
    lines across it and its triangles' ratios within 0.01 of the stretched
    lattice's; no triangle below 0.8."""
    length, width = 10.0, 0.5
    corners = _rectangle(length, width, angle, np.array([1.0, 2.0]))
    domain = bm.Domain.from_loops([corners])
    mesh = bm.mesh(domain, max_area=length * width / k, insertion="frontal")
    P, T = mesh.points, mesh.triangles
    O.check_valid(P, T, mesh.neighbors)
    O.check_conforming(P, T, mesh.segments, area=domain.area, rel=1e-9)
    h = float(SizeField.from_domain(domain, size=mesh_size(length * width / k)).cap)
    asked = length * width / (math.sqrt(3) / 4 * h * h)
    assert abs(len(T) / asked - 1) <= 0.05
    m, n, a, b = rows_for(width, length, h)
    u = (corners[1] - corners[0]) / length
    along = (P - corners[0]) @ u
    across = (P - corners[0]) @ np.array([-u[1], u[0]])
    nodes = []
    for line in (0.0, width):  # one wall shifted half a piece, the other too if m is even
        wall = np.sort(along[np.abs(across - line) <= 1e-9])
        nodes.append(len(wall))
        pieces = np.diff(wall)
        middle = (wall[:-1] > 3 * a) & (wall[1:] < length - 3 * a)
        assert np.allclose(pieces[middle], a, rtol=1e-9)
    assert sorted(nodes) == ([n + 1, n + 2] if m % 2 else [n + 2, n + 2])
    bulk = (along > 0.25 * length) & (along < 0.75 * length)
    rows = across[bulk] / b
    assert np.abs(rows - np.round(rows)).max() <= 0.05
    q = np.array([_heron_ratio(P[t]) for t in T])
    inner = bulk[T].all(axis=1)
    assert inner.sum() >= 0.4 * len(T)
    assert np.abs(q[inner] - isosceles_ratio(a, b)).max() <= 0.01
    assert q.min() >= 0.8


def mesh_size(max_area):
    from bubblemesh.pipeline import _user_size

    return _user_size(None, max_area)


@pytest.mark.parametrize("kind, extra, rows, angle", [
    ("L", 4.0, 3.4, 0.0), ("parallelogram", 0.7, 3.4, 0.7),
    pytest.param("L", 4.0, 4.4, 0.7, marks=pytest.mark.heavy),  # 15-40 s as plain Python
    pytest.param("parallelogram", -1.2, 4.4, 0.0, marks=pytest.mark.heavy)])
def test_the_overlap_of_an_l_or_a_parallelogram_is_meshed_in_whole_rows(kind, extra, rows,
                                                                        angle):
    """A 1-wide L-shaped strip or parallelogram 10 long, at a size giving
    ``rows`` rows of equilateral triangles across (not a whole number, but
    near enough for a stretched triangle of ratio LEAST_RATIO), by frontal
    insertion: a valid, conforming mesh whose nodes in the middle half of
    the walls' overlap lie (95% of them) within 5% of a row's height of the
    m + 1 lines of :func:`rows_for`'s rows."""
    max_area = (1.0 / (rows * math.sqrt(3) / 2) / mesh_size(1.0)) ** 2  # the cap that many rows
    corners, u, (lo, hi) = _overlapping(kind, 10.0, extra, angle, np.array([1.0, 2.0]))
    domain = bm.Domain.from_loops([corners])
    mesh = bm.mesh(domain, max_area=max_area, insertion="frontal")
    P, T = mesh.points, mesh.triangles
    O.check_valid(P, T, mesh.neighbors)
    O.check_conforming(P, T, mesh.segments, area=domain.area, rel=1e-9)
    cap = float(size_field(domain, max_area=max_area).cap)
    m, n, a, b = rows_for(1.0, hi - lo, cap)
    rel = P - corners[0]
    along = rel @ u
    across = rel @ np.array([-u[1], u[0]])
    middle = (along > lo + 0.25 * (hi - lo)) & (along < hi - 0.25 * (hi - lo))
    off_row = np.abs(across[middle] / b - np.round(across[middle] / b))
    assert middle.sum() >= 2 * (m + 1) and np.mean(off_row <= 0.05) >= 0.95


@pytest.mark.heavy  # nine meshes of a long strip: four minutes as plain Python
def test_auto_keeps_the_plain_walls_mesh_unless_the_channels_is_better(monkeypatch):
    """With ``insertion="auto"`` a channel's mesh is made on the plain walls
    too: the result is one of the two bit for bit, the channel's only where
    it has fewer elements below 0.7, a mean higher by more than a tie or a
    higher minimum; over the strip's sizes both are kept somewhere (the
    choice is made, not fixed)."""
    import bubblemesh.pipeline as pipeline

    domain = bm.Domain.from_loops([_rectangle(10.0, 0.5, 0.0, np.array([0.0, 0.0]))])
    kept = []
    for k in (100, 300, 1000):
        kwargs = dict(max_area=5.0 / k)
        with monkeypatch.context() as patch:
            got = bm.mesh(domain, **kwargs)
            patch.setattr(pipeline, "CHANNEL_BOTH_BELOW", 0)
            channel = bm.mesh(domain, **kwargs)
            patch.setattr(pipeline, "straight_channel", lambda *args: None)
            plain = bm.mesh(domain, **kwargs)
        assert len(channel.points) != len(plain.points) or not np.array_equal(channel.points,
                                                                              plain.points)
        same = [np.array_equal(got.points, m.points) and np.array_equal(got.triangles,
                                                                        m.triangles)
                for m in (channel, plain)]
        assert any(same), k
        kept.append(same[0])
        if same[0]:
            qc = np.array([_heron_ratio(channel.points[t]) for t in channel.triangles])
            qp = np.array([_heron_ratio(plain.points[t]) for t in plain.triangles])
            assert ((qc < 0.7).sum() < (qp < 0.7).sum() or qc.mean() > qp.mean() - 1e-4
                    or qc.min() > qp.min() - 1e-6), k
    assert any(kept) and not all(kept)
