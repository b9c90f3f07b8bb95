"""Graded walls at sharp corners (bubblemesh._wedges) against independent checks.

Oracles: the radius ratio from the triangle's angles, 2r/R = 8 sin(A/2)
sin(B/2) sin(C/2) (law of cosines, not the code's area formula), maximised
over a dense grid of progression ratios; the progression rule of the module
docstring rebuilt here node by node; radius_ratio_reference and the exact
validity checks on the final meshes.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from oracles import check_valid, radius_ratio_reference
from strategies import budget
from test_refinement import check_refinement

import bubblemesh as bm
from bubblemesh._frontal import frontal_point
from bubblemesh._wedges import (
    LADDER_WIDTH,
    MAX_PER_WALL,
    NEEDLE,
    SHARP_ANGLE,
    corner_angles,
    ladder_parameters,
    ladder_points,
    zigzag_ratio,
)
from bubblemesh.pipeline import GRADE_ANGLE
from bubblemesh.refinement import refine_boundary

GRID = np.linspace(1.0005, 4.0, 6000)


def _ratio_from_angles(p, q, r):
    """2r/R of triangles p q r (arrays of points) from their angles."""
    a, b, c = (np.hypot(*(u - v).T) for u, v in ((q, r), (r, p), (p, q)))
    A = np.arccos(np.clip((b * b + c * c - a * a) / (2 * b * c), -1, 1))
    B = np.arccos(np.clip((a * a + c * c - b * b) / (2 * a * c), -1, 1))
    return 8 * np.sin(A / 2) * np.sin(B / 2) * np.sin((np.pi - A - B) / 2)


def _zigzag_and_corner(theta, q):
    """The zigzag's triangle (1, 0), (q, 0), sqrt(q) e_theta and the corner's
    (0, 0), (1, 0), sqrt(q) e_theta, for an array of q."""
    q = np.atleast_1d(q)
    one, origin = np.tile([1.0, 0.0], (len(q), 1)), np.zeros((len(q), 2))
    apex = np.sqrt(q)[:, None] * [math.cos(theta), math.sin(theta)]
    along = np.column_stack([q, np.zeros(len(q))])
    return _ratio_from_angles(one, along, apex), _ratio_from_angles(origin, one, apex)


@given(st.floats(math.radians(3), math.radians(45)))
@budget(60)
def test_the_progression_ratio_is_the_best_one(theta):
    zig, corner = _zigzag_and_corner(theta, GRID)
    got_zig, got_corner = (float(v[0]) for v in _zigzag_and_corner(theta, zigzag_ratio(theta)))
    both = np.minimum(zig, corner)
    if theta >= SHARP_ANGLE and both.max() >= 0.7:  # the corner's triangle can reach 0.7: kept
        assert min(got_zig, got_corner) >= both.max() - 1e-6
    else:  # it cannot: the zigzag alone
        assert got_zig >= zig.max() - 1e-6


def _ladder_layer_oracle(theta, g, t):
    """The worst ratio of a ladder layer's four triangles (the module docstring:
    walls in phase at distances 1 and g, the node at (1 + t (g - 1)) cos(theta/2)
    on the bisector), from their angles, for arrays g and t."""
    c, s = math.cos(theta / 2), math.sin(theta / 2)
    g, t = np.broadcast_arrays(np.asarray(g, float), np.asarray(t, float))
    a0 = np.tile([c, s], (g.size, 1))
    b0 = np.tile([c, -s], (g.size, 1))
    a1, b1 = g.reshape(-1, 1) * a0, g.reshape(-1, 1) * b0
    x = np.column_stack([c * (1 + t.reshape(-1) * (g.reshape(-1) - 1)), np.zeros(g.size)])
    return np.min([_ratio_from_angles(*tri) for tri in
                   ((a0, b0, x), (b0, b1, x), (b1, a1, x), (a1, a0, x))], axis=0)


@given(st.floats(math.radians(26.2), math.radians(40)))
@budget(30)
def test_the_ladder_is_the_best_one_and_taken_where_it_beats_the_zigzag(theta):
    G, T = np.meshgrid(np.linspace(1.05, 3.0, 400), np.linspace(0.01, 0.99, 200))
    best = float(_ladder_layer_oracle(theta, G, T).max())
    g, t, wanted = (float(v) for v in ladder_parameters(theta))
    got = float(_ladder_layer_oracle(theta, g, t)[0])
    assert got >= best - 2e-3  # the grid's step; the table is interpolated
    isosceles = 8 * math.sin(theta / 2) * math.sin((math.pi - theta) / 4) ** 2
    ladder = min(got, isosceles)
    zig, corner = _zigzag_and_corner(theta, GRID)
    zigzag = float(np.minimum(zig, corner).max())
    if wanted:
        assert ladder >= zigzag - 2e-3
    else:
        assert zigzag >= ladder - 2e-3


def _kite(theta, length=3.0):
    """A kite with a corner of angle theta at the origin, its other corners blunt."""
    tip = (length * (1 + 0.3 * math.sin(theta / 2)), 0.5 * length * math.tan(theta / 2))
    return [np.array([(0.0, 0.0), (length, 0.0), tip,
                      (length * math.cos(theta), length * math.sin(theta))])]


def _expected_distances(theta, h, length, offset, ladders):
    """The graded nodes' distances from the corner (module docstring), rebuilt,
    on a wall whose far end is blunt: nodes while the next one is on the wall,
    a zigzag's while its spacing is below h, a ladder's (in phase: no offset)
    while the wedge is narrower than LADDER_WIDTH h, if ``ladders``."""
    g, _, wanted = (float(v) for v in ladder_parameters(theta))
    ladder = ladders and bool(wanted)
    q, out, k = g if ladder else float(zigzag_ratio(theta)), [], 0
    offset = 0.0 if ladder else offset
    while k < MAX_PER_WALL:
        d = h * q ** (k + offset)
        wide = 2 * math.sin(theta / 2) * d > LADDER_WIDTH * h if ladder else (q - 1) * d > h
        if d * q > length or wide:
            break
        out.append(d)
        k += 1
    return np.array(out)


# walls of 3 end where the spacing reaches h; walls of 1 at 5 and 12 degrees run past
# their middle (their far ends are blunt)
# (at 27 and 30 degrees a ladder's in-phase walls only if asked for)
@pytest.mark.parametrize("ladders", [True, False])
@pytest.mark.parametrize("length", [3.0, 1.0])
@pytest.mark.parametrize("degrees", [0.2, 1, 2, 5, 12, 20, 27, 30, 38])
def test_walls_of_a_sharp_corner_are_graded_by_the_rule(degrees, length, ladders):
    theta, h = math.radians(degrees), 0.1
    loops = _kite(theta, length)
    result = refine_boundary(loops, h, sharp_angle=GRADE_ANGLE, ladders=ladders)
    check_refinement([np.asarray(loops[0])], result)
    loop = result.loops[0]
    if not ladders:  # the default: a direct caller has no rungs for in-phase walls
        np.testing.assert_array_equal(
            refine_boundary(loops, h, sharp_angle=GRADE_ANGLE).loops[0], loop)
    out_wall = np.hypot(*loop[1:result.input_index[0][1]].T)  # corner -> (3, 0)
    in_wall = np.hypot(*loop[result.input_index[0][3] + 1:][::-1].T)  # corner -> the 4th node
    expected = [_expected_distances(theta, h, length, s, ladders) for s in (0.0, 0.5)]
    assert len(expected[0]) >= 1
    got = sorted((out_wall, in_wall), key=lambda w: w[0])  # the half-step wall starts farther
    for wall, want in zip(got, expected):
        # placement may round t to 20 bits for a node exactly on the segment
        np.testing.assert_allclose(wall[:len(want)], want, rtol=0, atol=2.0**-21 * length)
        # then the field's pieces, if any (at 1 and 2 degrees the zigzag runs to the end)
        assert np.diff(wall[len(want) - 1:]).max(initial=0.0) <= 1.2 * h


@pytest.mark.parametrize("degrees", [1, 10, 20])
def test_the_field_inside_a_wedge_is_its_walls_spacing(degrees):
    """Inside the wedge, on the corner's bisector level with each graded node
    (distance d from the corner, rebuilt by the rule), the field is no larger
    than the zigzag's spacing (q - 1) d: the walls' sources alone would let it
    grow by the gradation over half the wedge's width, and the field's
    integral would ask for fewer triangles than the zigzag holds.  (Under a
    size cap, as here, only corners sharper than SHARP_ANGLE have sources;
    the rebuilt distances match the nodes' to 2e-7.)"""
    from bubblemesh.pipeline import size_field

    theta, h = math.radians(degrees), 0.1
    domain = bm.Domain.from_loops(_kite(theta))
    field = size_field(domain, size=h)
    q = float(zigzag_ratio(theta))
    d = np.concatenate([_expected_distances(theta, h, 3.0, s, False) for s in (0.0, 0.5)])
    assert len(d) >= 2
    half = theta / 2
    axis = (d * math.cos(half))[:, None] * np.array([math.cos(half), math.sin(half)])
    assert np.all(field(axis) <= (q - 1) * d * (1 + 1e-5))


@pytest.mark.parametrize("tips", [(1.1, 0.46), (3.0, 1.0), (8.5, 1.1)])
def test_a_wall_graded_from_two_unlike_corners_has_no_jump_where_they_meet(tips):
    """A sliver triangle whose long wall runs between corners of two different
    sharp angles (the third corner nearly straight): the strip is widest
    where the two wedges meet, so the two progressions must meet there too,
    their spacings alike.  Each piece of that wall but the corners' own is at
    most twice its neighbours (the ratios q are 1.008-1.16; the gap left
    between the two progressions is one piece the field cuts, at worst some
    0.6 of theirs).  Split at the middle instead, neighbouring pieces
    differed by 2.4-4.6 times where the progressions met."""
    a, b = (math.radians(t) for t in tips)
    far = 3.5 * math.sin(a) / math.sin(a + b)  # from the first corner to the third
    loops = [np.array([(0.0, 0.0), (3.5, 0.0), (3.5 - far * math.cos(b), far * math.sin(b))])]
    # h above the spacing where they meet: both progressions run to it
    result = refine_boundary(loops, 0.1, sharp_angle=GRADE_ANGLE)
    check_refinement([np.asarray(loops[0])], result)
    loop = result.loops[0]
    wall = loop[:result.input_index[0][1] + 1]  # (0, 0) -> (3.5, 0)
    pieces = np.diff(wall[:, 0])[1:-1]  # less the corners' own legs, r
    assert len(pieces) > 20 and np.all(pieces > 0)
    assert np.max(np.maximum(pieces[1:] / pieces[:-1], pieces[:-1] / pieces[1:])) <= 2.0


def test_short_walls_each_get_their_first_node():
    # walls cut at 0.1 by the input next to a 36-degree corner, h = 0.05: the
    # half-step wall's first node must fit in its first half too, so r shrinks
    theta, h, cut = math.radians(36), 0.05, 0.1
    kite = _kite(theta)[0]
    loop = np.array([kite[0], (cut, 0.0), *kite[1:], cut * np.array(kite[3]) / 3.0])
    result = refine_boundary([loop], h, sharp_angle=GRADE_ANGLE)
    check_refinement([loop], result)
    near = np.sort(np.hypot(*result.loops[0].T))[1:3]
    q = float(zigzag_ratio(theta))
    np.testing.assert_allclose(near, [0.5 * cut / math.sqrt(q), 0.5 * cut], rtol=0,
                               atol=2.0**-21 * 3.0)


@pytest.mark.parametrize("cut", np.linspace(0.2, 0.4, 9))
def test_a_wall_that_goes_on_straight_ends_its_zigzag_nearest_in_ratio(cut):
    # the 20-degree corner's wall is cut at ``cut`` by an input node where it goes on
    # straight: the cut stands in for the zigzag's next node, so it lies sqrt(q) to
    # q^1.5 times as far as the last graded node (a whole step past it: q to q^2)
    theta, h = math.radians(20), 0.5
    kite = _kite(theta)[0]
    loop = np.array([kite[0], (cut, 0.0), *kite[1:]])
    result = refine_boundary([loop], h, sharp_angle=GRADE_ANGLE)
    check_refinement([loop], result)
    graded = np.hypot(*result.loops[0][1:result.input_index[0][1]].T)
    q = float(zigzag_ratio(theta))
    np.testing.assert_allclose(graded[1:] / graded[:-1], q, rtol=1e-9)
    assert math.sqrt(q) <= cut / graded[-1] < q ** 1.5


def test_no_grading_above_the_angle_or_below_the_needle():
    for degrees in (50.0, math.degrees(NEEDLE) / 2):
        loops = _kite(math.radians(degrees))
        graded = refine_boundary(loops, 0.1, sharp_angle=GRADE_ANGLE)
        plain = refine_boundary(loops, 0.1)
        np.testing.assert_array_equal(graded.loops[0], plain.loops[0])


def _off_corner_minimum(mesh):
    """The smallest radius ratio over triangles without a vertex at an input corner
    too sharp for 0.7, and the smallest over all."""
    q = radius_ratio_reference(mesh.points, mesh.triangles)
    sharp = np.flatnonzero(corner_angles(mesh.domain) < SHARP_ANGLE)
    sharp_points = np.asarray(mesh.domain.points)[sharp]
    at = np.zeros(len(mesh.points), bool)
    for p in sharp_points:
        at |= (mesh.points == p).all(axis=1)
    touching = at[mesh.triangles].any(axis=1)
    return float(q[~touching].min()), float(q.min())


@pytest.mark.filterwarnings("ignore::bubblemesh.pipeline.QualityWarning")
@pytest.mark.parametrize("degrees", [10, 15, 20, *(
    pytest.param(d, marks=pytest.mark.heavy) for d in (0.2, 1, 2, 5, 25, 26.5, 27.4, 30, 34, 38))])
# the finer share is minutes as plain Python; the jitted environments run it
@pytest.mark.parametrize("share", [100, pytest.param(1000, marks=pytest.mark.heavy)])
def test_meshes_beside_sharp_corners_stay_above_0_7(degrees, share):
    domain = bm.Domain.from_loops(_kite(math.radians(degrees)))
    mesh = bm.mesh(domain, max_area=domain.area / share)
    check_valid(mesh.points, mesh.triangles, mesh.neighbors)
    off_corner, overall = _off_corner_minimum(mesh)
    assert off_corner >= 0.7
    if degrees >= math.degrees(SHARP_ANGLE):
        assert overall >= 0.7


def _ladder_nodes(mesh):
    """The nodes bm.mesh added as free points of its refined domain."""
    domain = mesh.domain
    on_loops = np.concatenate(domain.loops)
    free = np.setdiff1d(np.arange(len(domain.points)), on_loops)
    return np.asarray(domain.points)[free]


@pytest.mark.heavy
@pytest.mark.filterwarnings("ignore::bubblemesh.pipeline.QualityWarning")
@pytest.mark.parametrize("degrees", [26.5, 30])
def test_a_ladder_corner_has_an_isosceles_triangle_and_nodes_on_its_bisector(degrees):
    theta = math.radians(degrees)
    domain = bm.Domain.from_loops(_kite(theta))
    mesh = bm.mesh(domain, max_area=domain.area / 300)
    check_valid(mesh.points, mesh.triangles, mesh.neighbors)
    rungs = _ladder_nodes(mesh)
    assert len(rungs) >= 1
    bisector = np.array([math.cos(theta / 2), math.sin(theta / 2)])
    np.testing.assert_allclose(rungs @ np.array([-bisector[1], bisector[0]]), 0.0, atol=1e-12)
    corner = np.flatnonzero((mesh.points == 0.0).all(axis=1))
    assert len(corner) == 1
    at_corner = mesh.triangles[(mesh.triangles == corner[0]).any(axis=1)]
    assert len(at_corner) == 1  # the corner's own triangle, isosceles
    legs = np.sort(np.hypot(*mesh.points[at_corner[0]].T))[1:]
    assert legs[0] == pytest.approx(legs[1], rel=1e-9)
    assert _off_corner_minimum(mesh)[1] >= 0.7


@pytest.mark.parametrize("length", [0.45, 0.5, 0.6])
def test_a_ladder_on_short_walls_ends_where_the_wedge_widens(length):
    """A kite's 26.5-degree corner with walls 4.5-6 sizes long: the ladder
    stops where the wedge widens, and the walls end a layer further on.  It
    is a ladder all the same (rungs on the bisector, an isosceles corner
    triangle), so no triangle is below 0.7 (the zigzag's corner triangle
    is 0.59 at this angle)."""
    theta = math.radians(26.5)
    domain = bm.Domain.from_loops(_kite(theta, length))
    assert len(ladder_points(domain, lambda p: np.full(len(p), 0.1), GRADE_ANGLE)) >= 1
    mesh = bm.mesh(domain, size=0.1)
    check_valid(mesh.points, mesh.triangles, mesh.neighbors)
    assert len(_ladder_nodes(mesh)) >= 1
    assert _off_corner_minimum(mesh)[1] >= 0.7


@pytest.mark.parametrize("obstacle", ["point", "hole"])
def test_a_ladder_that_would_reach_what_lies_in_its_wedge_is_a_zigzag(obstacle):
    # a free point or a small hole on the bisector of a 30-degree corner, 0.3
    # from it, where a ladder of h = 0.5 would run to 1.2: no rung, the walls
    # out of phase (the zigzag's half step)
    theta = math.radians(30)
    kite = _kite(theta)[0]
    u = np.array([math.cos(theta / 2), math.sin(theta / 2)])
    if obstacle == "point":
        domain = bm.Domain.from_pslg(loops=[kite], points=[0.3 * u])
    else:
        square = 0.3 * u + 0.01 * np.array([(0, 0), (1, 0), (1, 1), (0, 1)])
        domain = bm.Domain.from_loops([kite, square])

    def h(p):
        return np.full(len(p), 0.5)

    assert len(ladder_points(domain, h, GRADE_ANGLE)) == 0
    loop = refine_boundary(domain, h, sharp_angle=GRADE_ANGLE, ladders=True).loops[0]
    near = np.sort(np.hypot(*loop.T))[1:3]
    assert near[1] / near[0] == pytest.approx(math.sqrt(float(zigzag_ratio(theta))), rel=1e-6)
    # without an obstacle the same corner's ladder runs past it
    assert np.hypot(*ladder_points(bm.Domain.from_loops([kite]), h, GRADE_ANGLE).T).max() > 0.3


def _star(tips, degrees):
    """A star of ``tips`` tips of the given angle on the unit circle."""
    half, phi = math.radians(degrees) / 2, math.pi / tips
    inner = math.sin(half) / math.sin(half + phi)
    out = []
    for k in range(tips):
        t = 2 * math.pi * k / tips
        out += [(math.cos(t), math.sin(t)), (inner * math.cos(t + phi), inner * math.sin(t + phi))]
    return np.array(out)


@pytest.mark.heavy
@pytest.mark.filterwarnings("ignore::bubblemesh.pipeline.QualityWarning")
def test_short_tips_keep_the_zigzag_where_a_ladder_would_end_at_their_walls():
    # 40 tips of 30 degrees, 0.23 long, at an h of 0.24: a ladder would stop at the
    # wall's end and leave 0.43 beside it; the zigzag keeps every element >= 0.7
    domain = bm.Domain.from_loops([_star(40, 30)])
    mesh = bm.mesh(domain, max_area=domain.area / 100)
    check_valid(mesh.points, mesh.triangles, mesh.neighbors)
    assert len(_ladder_nodes(mesh)) == 0
    assert _off_corner_minimum(mesh)[1] >= 0.7


def test_a_sampled_shapely_domain_gets_no_ladder_nodes():
    # Domain.from_shapely(size=...) splits segments only: a 30-degree corner keeps
    # its zigzag (walls out of phase) and no node lies off the segments
    shapely = pytest.importorskip("shapely")
    theta = math.radians(30)
    domain = bm.Domain.from_shapely(shapely.Polygon(_kite(theta)[0]), size=0.1)
    assert len(domain.points) == sum(len(loop) for loop in domain.loops)
    near = np.sort(np.hypot(*np.asarray(domain.points).T))[1:3]
    assert near[1] / near[0] == pytest.approx(math.sqrt(float(zigzag_ratio(theta))), rel=1e-6)


@pytest.mark.heavy
@pytest.mark.filterwarnings("ignore::bubblemesh.pipeline.QualityWarning")
def test_two_sharp_corners_on_one_wall():
    # a 20-20-140 triangle: the base is graded from both ends, each up to its middle
    A = math.radians(20)
    apex = (1.5, 1.5 * math.tan(A))
    domain = bm.Domain.from_loops([np.array([(0.0, 0.0), (3.0, 0.0), apex])])
    mesh = bm.mesh(domain, max_area=domain.area / 300)
    check_valid(mesh.points, mesh.triangles, mesh.neighbors)
    assert _off_corner_minimum(mesh)[0] >= 0.7


@pytest.mark.filterwarnings("ignore::bubblemesh.pipeline.QualityWarning")
@pytest.mark.parametrize("degrees", [8, *(pytest.param(d, marks=pytest.mark.heavy)
                                         for d in (4, 6, 12))])
def test_a_wedge_whose_first_walls_are_short_stays_above_0_7(degrees):
    # the corner's walls bend after 0.5, far shorter than h / (q - 1): the zigzag must
    # run to their ends, where the next walls' feature size takes over
    t = math.tan(math.radians(degrees))
    loop = np.array([(0.0, 0.0), (0.5, -0.5 * t), (3.0, -3.0 * t - 0.3), (3.0, 0.5),
                     (1.5, 0.5), (1.5, 0.0)])
    mesh = bm.mesh(bm.Domain.from_loops([loop]), max_area=0.02)
    check_valid(mesh.points, mesh.triangles, mesh.neighbors)
    assert _off_corner_minimum(mesh)[0] >= 0.7


def _crescent(n_outer, n_inner, radius=0.8, centre=0.4):
    """The unit disk less the disk of ``radius`` about (``centre``, 0): a
    crescent with two 22-degree cusps, its arcs drawn with n_outer and
    n_inner nodes from cusp to cusp, so that each cusp's walls are short
    pieces of nearly straight walls."""
    x = (1.0 + centre * centre - radius * radius) / (2.0 * centre)
    a, b = math.acos(x), math.atan2(math.sqrt(1.0 - x * x), x - centre)
    t = np.linspace(a, 2.0 * math.pi - a, n_outer)
    s = np.linspace(2.0 * math.pi - b, b, n_inner)[1:-1]
    return np.vstack([np.column_stack([np.cos(t), np.sin(t)]),
                      np.column_stack([centre + radius * np.cos(s), radius * np.sin(s)])])


@pytest.mark.heavy
@pytest.mark.filterwarnings("ignore::bubblemesh.pipeline.QualityWarning")
@pytest.mark.parametrize("n_outer, n_inner", [(40, 30), (60, 45)])
def test_cusps_whose_walls_are_short_pieces_stay_above_0_7(n_outer, n_inner):
    # the zigzag on each wall ends at the wall's end; a rule that keeps a whole step
    # past its last node leaves one wall a piece too long, two nodes of the other
    # wall face it and the strip between holds triangles of 0.53-0.66
    domain = bm.Domain.from_loops([_crescent(n_outer, n_inner)])
    assert (np.degrees(corner_angles(domain)) < math.degrees(SHARP_ANGLE)).sum() == 2
    mesh = bm.mesh(domain, max_area=domain.area / 100)
    check_valid(mesh.points, mesh.triangles, mesh.neighbors)
    assert _off_corner_minimum(mesh)[0] >= 0.7


def _saw(teeth, depth):
    """A unit square whose top is a saw of ``teeth`` sharp teeth ``depth`` tall."""
    w = 1.0 / teeth
    top = [(j * w + 0.5 * w * s, 1.0 + depth * s) for j in range(teeth) for s in (0, 1)]
    return np.array([(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), *top[::-1]])


@pytest.mark.heavy
@pytest.mark.filterwarnings("ignore::bubblemesh.pipeline.QualityWarning")
@pytest.mark.parametrize("teeth, depth", [(5, 1.29), (9, 0.67)])
def test_sharp_teeth_under_a_max_area_get_the_count_their_field_asks_for(teeth, depth):
    # teeth of 11 and 8.5 degrees: their zigzags are the whole tooth; the field
    # bm.mesh (and the study) count from must hold them, or the count is 1.4-1.7
    # times what it asks for
    from bubblemesh.pipeline import size_field
    from bubblemesh.studies.quality import predicted_count

    domain = bm.Domain.from_loops([_saw(teeth, depth)])
    max_area = domain.area / 100
    mesh = bm.mesh(domain, max_area=max_area)
    check_valid(mesh.points, mesh.triangles, mesh.neighbors)
    asked = predicted_count(domain, size_field(domain, max_area=max_area), 1e-3).count
    assert abs(len(mesh.triangles) / asked - 1) <= 0.05
    assert _off_corner_minimum(mesh)[0] >= 0.7


def test_a_flat_triangle_gets_a_frontal_node_without_dividing_by_zero():
    # seen from node 2, 1e17 - 1 rounds to 1e17: the circumcentre's denominator is 0
    P = np.array([[0.0, 0.0], [1.0, 0.0], [1e17, 1e-3]])
    tri = np.array([[0, 1, 2]], np.int64)
    x, y = frontal_point(P, 0, tri, 2, 1.0)  # the front edge 0-1, opposite node 2
    assert math.isfinite(x) and math.isfinite(y)
    assert y > 0.0  # on the triangle's side of the edge


@pytest.mark.heavy
@pytest.mark.filterwarnings("ignore::bubblemesh.pipeline.QualityWarning")
def test_a_sector_with_a_fine_arc_gets_its_count():
    # no cap: the field grows to a quarter of the radius at the tip, far above
    # the zigzag's triangles; their bubbles must not end §2 early (eq. 6)
    from bubblemesh.sizing import SizeField
    from bubblemesh.studies.quality import predicted_count

    t = np.linspace(0.0, math.radians(15), 53)
    domain = bm.Domain.from_loops([np.vstack([[(0.0, 0.0)],
                                              np.column_stack([np.cos(t), np.sin(t)])])])
    mesh = bm.mesh(domain)
    check_valid(mesh.points, mesh.triangles, mesh.neighbors)
    predicted = predicted_count(domain, SizeField.from_domain(domain)).count
    assert abs(len(mesh.triangles) / predicted - 1) <= 0.05
    assert _off_corner_minimum(mesh)[0] >= 0.7
