"""Frontal seeds of bm.mesh (bubblemesh._seeds) against independent checks:
brute-force numpy distances for the room rule, the exact point location of
verification/oracles.py for "inside the domain", and the exact oracles for the
seeded §2 mesh."""

from __future__ import annotations

import warnings

import numpy as np
import oracles as O
from hypothesis import given
from hypothesis import strategies as st
from test_pipeline import corner_domains

import bubblemesh as bm
from bubblemesh._seeds import CORNER_HIGH, CORNER_LOW, ROOM, frontal_seeds, inside
from bubblemesh.generation import generate_sized
from bubblemesh.refinement import refine_boundary
from bubblemesh.sizing import SizeField


def _refined(loops, size):
    domain = bm.Domain.from_loops(loops)
    field = SizeField.from_domain(domain, size=size)
    return refine_boundary(domain, field).to_domain(), field


def _apex(P, s):
    a, b = P[s[0]], P[s[1]]
    e = b - a
    return 0.5 * (a + b) + np.sqrt(3) / 2 * np.array([-e[1], e[0]]), float(np.hypot(*e))


def _owners(P, S):
    """Every point a seed may be, with (own nodes, own segments, length):
    segment apexes, and the bisector points of corners in the seeded range."""
    owners = [(x, list(s), [i], L) for i, s in enumerate(S) for x, L in [_apex(P, s)]]
    for i, (u, v) in enumerate(S):
        j = int(np.nonzero(S[:, 0] == v)[0][0])
        w = S[j, 1]
        to_w, to_u = P[w] - P[v], P[u] - P[v]
        theta = np.arctan2(to_w[0] * to_u[1] - to_w[1] * to_u[0], to_w @ to_u) % (2 * np.pi)
        if CORNER_LOW <= theta < CORNER_HIGH:
            reach = 0.5 * (np.hypot(*to_w) + np.hypot(*to_u))
            direction = np.array([np.cos(np.arctan2(to_w[1], to_w[0]) + theta / 2),
                                  np.sin(np.arctan2(to_w[1], to_w[0]) + theta / 2)])
            owners.append((P[v] + reach * direction, [u, v, w], [i, j], reach))
    return owners


@given(corner_domains(max_holes=2), st.sampled_from([0.3, 0.15]))
def test_seeds_are_apexes_or_corner_bisectors_with_room_inside_the_domain(loops, size):
    fine, _ = _refined(loops, size)
    P, S = np.asarray(fine.points), np.asarray(fine.segments)
    seeds, _ = frontal_seeds(P, S, fine.interior)
    owners = _owners(P, S)
    mids = 0.5 * (P[S[:, 0]] + P[S[:, 1]])
    for x in seeds:
        match = [o for o in owners if np.allclose(o[0], x, rtol=0, atol=1e-12)]
        assert match, "a seed is neither an apex nor a corner's bisector point"
        _, nodes, segs, length = match[0]
        others = np.delete(P, nodes, axis=0)
        assert np.hypot(*(others - x).T).min() >= ROOM * length * (1 - 1e-12)
        assert np.hypot(*(np.delete(mids, segs, axis=0) - x).T).min() >= ROOM * length * (
            1 - 1e-12)
        assert O.domain_location(P, fine.loops, tuple(x)) > 0  # exact: inside, off the loops
    if len(seeds) > 1:
        d = np.hypot(*(seeds[:, None] - seeds[None]).T)
        np.fill_diagonal(d, np.inf)
        assert d.min() >= ROOM * min(o[3] for o in owners) * (1 - 1e-12)


@given(corner_domains(max_holes=2), st.sampled_from([0.3, 0.15]))
def test_no_seed_is_missing_where_one_has_room(loops, size):
    """Every apex or corner point clear of the nodes and segment midpoints that
    is not a seed crowds one: seeds that crowd each other keep one of them."""
    fine, _ = _refined(loops, size)
    P, S = np.asarray(fine.points), np.asarray(fine.segments)
    seeds, _ = frontal_seeds(P, S, fine.interior)
    owners = _owners(P, S)
    lengths = np.array([next(L for y, _, _, L in owners if np.allclose(y, x, rtol=0, atol=1e-12))
                        for x in seeds])
    mids = 0.5 * (P[S[:, 0]] + P[S[:, 1]])
    for x, nodes, segs, length in owners:
        room = ROOM * length
        if (np.hypot(*(np.delete(P, nodes, axis=0) - x).T).min() < room
                or np.hypot(*(np.delete(mids, segs, axis=0) - x).T).min() < room
                or O.domain_location(P, fine.loops, tuple(x)) <= 0):
            continue
        d = np.hypot(*(seeds - x).T) if len(seeds) else np.zeros(0)
        assert (d < ROOM * np.maximum(length, lengths)).any(), ("no seed near", x)


def test_a_truncated_tip_gets_one_seed():
    """Two 110 degree corners at the ends of a short segment, as at the top of
    Triangle's A.poly: their seeds crowd each other, one is kept, so the tip is
    not one blunt triangle (radius ratio about 0.6)."""
    tip = np.array([(0, -1), (0.35, -1), (0.008, 0), (-0.008, 0), (-0.35, -1)], float)
    domain = bm.Domain.from_loops([tip])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", bm.QualityWarning)
        m = bm.mesh(domain, max_area=domain.area / 200)
    corners = [int(np.nonzero((m.points == c).all(axis=1))[0][0]) for c in tip[2:4]]
    shared = [t for t in np.asarray(m.triangles).tolist() if set(corners) <= set(t)]
    assert len(shared) == 1
    apex = (set(shared[0]) - set(corners)).pop()
    assert apex >= m.n_boundary  # an interior node, not the next wall node
    assert O.radius_ratio_reference(m.points, m.triangles).min() >= 0.7


def test_a_hexagon_gets_a_seed_on_each_corner_bisector():
    """120 degree corners: a seed toward the centre at the segment length."""
    corners = np.array([(np.cos(a), np.sin(a)) for a in np.arange(6) * np.pi / 3])
    fine, _ = _refined([corners], 0.1)
    seeds, _ = frontal_seeds(fine.points, fine.segments, fine.interior)
    first = np.linalg.norm(fine.points[1] - fine.points[0])  # the refined spacing
    for c in corners:
        want = c - first * c  # the centre is at the origin, |c| = 1
        assert np.isclose(np.hypot(*(seeds - want).T), 0, atol=1e-9).any(), c


def test_inside_is_exact_about_points_outside_in_holes_and_on_edges():
    square = np.array([(0, 0), (4, 0), (4, 4), (0, 4)], float)
    hole = np.array([(1, 1), (1, 3), (3, 3), (3, 1)], float)
    fine = bm.Domain.from_loops([square, hole])
    tri, nbr = bm.constrained_delaunay(fine.points, fine.segments)
    seeds = np.array([(0.5, 0.25), (2.0, 2.0), (5.0, 1.0), (3.5, 3.2), (0.5, 0.5), (4.0, 2.0)])
    segments = np.asarray(fine.segments)
    bottom = int(np.nonzero((fine.points[segments[:, 0], 1] == 0)
                            & (fine.points[segments[:, 1], 1] == 0))[0][0])
    rows = np.full(len(seeds), bottom)
    expected = [O.domain_location(fine.points, fine.loops, x) > 0 for x in seeds.tolist()]
    assert expected == [True, False, False, True, True, False]
    # a seed on an edge of the triangulation is dropped too: (0.5, 0.5) is on
    # the diagonal from (0, 0) to (1, 1), inside the domain but not strictly in a triangle
    corner, inner = 0, 4  # (0, 0) and (1, 1)
    on_edge = any({corner, inner} <= set(t) for t in np.asarray(tri).tolist())
    got = inside(fine.points, fine.segments, tri, nbr, seeds, rows)
    assert got.tolist() == expected[:4] + [not on_edge, False]


@given(corner_domains(max_holes=2), st.sampled_from([0.3, 0.15]))
def test_a_seeded_generation_is_valid_and_keeps_its_seeds(loops, size):
    fine, field = _refined(loops, size)
    seeds, rows = frontal_seeds(fine.points, fine.segments, fine.interior)
    tri, nbr = bm.constrained_delaunay(fine.points, fine.segments)
    seeds = seeds[inside(fine.points, fine.segments, tri, nbr, seeds, rows)]
    m = generate_sized(fine, field, seeds=seeds)
    O.check_valid(m.points, m.triangles, m.neighbors)
    O.check_conforming(m.points, m.triangles, m.segments, area=fine.area, rel=1e-9)
    interior = {tuple(p) for p in np.asarray(m.points)[m.n_boundary:].tolist()}
    assert {tuple(p) for p in seeds.tolist()} <= interior
    np.testing.assert_array_equal(m.points[: m.n_boundary], fine.points)
