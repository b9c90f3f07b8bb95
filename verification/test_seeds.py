"""Frontal seeds of bm.mesh (bubblemesh._seeds) against independent checks:
brute-force numpy distances for the room rule, GEOS (shapely) for "inside the
domain", and the exact oracles for the seeded §2 mesh."""

from __future__ import annotations

import numpy as np
import oracles as O
import shapely
from hypothesis import given
from hypothesis import strategies as st
from test_pipeline import corner_domains

import bubblemesh as bm
from bubblemesh._seeds import ROOM, frontal_seeds, inside
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


@given(corner_domains(max_holes=2), st.sampled_from([0.3, 0.15]))
def test_seeds_are_apexes_with_room_inside_the_domain(loops, size):
    fine, _ = _refined(loops, size)
    P, S = np.asarray(fine.points), np.asarray(fine.segments)
    seeds = frontal_seeds(P, S, fine.interior)
    apexes = [_apex(P, s) for s in S]
    polygon = shapely.Polygon(P[fine.loops[0]], [P[ix] for ix in fine.loops[1:]])
    mids = 0.5 * (P[S[:, 0]] + P[S[:, 1]])
    for x in seeds:
        own = [i for i, (p, _) in enumerate(apexes) if np.array_equal(p, x)]
        assert own, "a seed is no segment's apex"
        i = own[0]
        length = apexes[i][1]
        others = np.delete(P, S[i], axis=0)
        assert np.hypot(*(others - x).T).min() >= ROOM * length
        assert np.hypot(*(mids - x).T).min() >= ROOM * length
        assert polygon.contains(shapely.Point(x))  # GEOS: inside, off the boundary
    if len(seeds):
        d = np.hypot(*(seeds[:, None] - seeds[None]).T)
        np.fill_diagonal(d, np.inf)
        assert d.min() >= ROOM * min(L for _, L in apexes) * (1 - 1e-12)


def test_inside_is_exact_about_points_outside_and_in_holes():
    square = np.array([(0, 0), (4, 0), (4, 4), (0, 4)], float)
    hole = np.array([(1, 1), (1, 3), (3, 3), (3, 1)], float)
    fine = bm.Domain.from_loops([square, hole])
    seeds = np.array([(0.5, 0.5), (2.0, 2.0), (5.0, 1.0), (3.5, 3.5)])
    np.testing.assert_array_equal(inside(fine.points, fine.segments, seeds),
                                  [True, False, False, True])


@given(corner_domains(max_holes=2), st.sampled_from([0.3, 0.15]))
def test_a_seeded_generation_is_valid_and_keeps_its_seeds(loops, size):
    fine, field = _refined(loops, size)
    seeds = frontal_seeds(fine.points, fine.segments, fine.interior)
    seeds = seeds[inside(fine.points, fine.segments, seeds)]
    m = generate_sized(fine, field, seeds=seeds)
    O.check_valid(m.points, m.triangles, m.neighbors)
    O.check_conforming(m.points, m.triangles, m.segments, area=fine.area, rel=1e-9)
    interior = {tuple(p) for p in np.asarray(m.points)[m.n_boundary:].tolist()}
    assert {tuple(p) for p in seeds.tolist()} <= interior
    np.testing.assert_array_equal(m.points[: m.n_boundary], fine.points)
