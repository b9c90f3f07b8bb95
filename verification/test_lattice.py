"""The close-packed start of the frontal §2 (bubblemesh._lattice) against an
independent construction: the triangular lattice of spacing h anchored at
the boundary's lower left corner, filtered with the exact point location of
verification/oracles.py (strictly inside the domain), brute-force distances
(at least margin h from every boundary node) and the size field (at its
cap); the returned nodes must be exactly those, each within its 1e-9 h
offset.  In a frame (origin, direction, spacing), the same filters on the
lattice through the origin along that direction.  With ``on_lattice_margin``
a boundary node whose segments are all lattice edges (both ends within 1e-6
of a step of the oracle's lattice nodes, one step apart) needs only that
margin; on a triangle and a hexagon whose walls are lattice edges the
lattice then holds every node strictly inside (counted by formula)."""

from __future__ import annotations

import math

import numpy as np
import oracles as O
from hypothesis import given
from hypothesis import strategies as st
from test_pipeline import corner_domains

import bubblemesh as bm
from bubblemesh._lattice import JITTER, lattice_points
from bubblemesh.refinement import refine_boundary
from bubblemesh.sizing import SizeField


def _expected(P, loops, h, margin, field, frame=None, segments=None, wall_margin=None):
    if frame is None:
        lo, hi = P.min(axis=0), P.max(axis=0)
        dy = math.sqrt(3) / 2 * h
        nodes = [(lo[0] + i * h + (0.5 * h if j % 2 else 0.0), lo[1] + j * dy)
                 for j in range(int((hi[1] - lo[1]) / dy) + 1)
                 for i in range(-1, int((hi[0] - lo[0]) / h) + 2)]
        nodes = np.array(nodes)
    else:  # every i a + j b through the origin, a = s u, b = s u / 2 + rise u_left
        o, u, step = frame[:3]
        rise = frame[3] if len(frame) > 3 else math.sqrt(3) / 2 * step
        a = step * np.asarray(u)
        b = step * 0.5 * np.asarray(u) + rise * np.array([-u[1], u[0]])
        reach = int(np.hypot(*(P - o).T).max() / (0.5 * step)) + 2
        i, j = np.meshgrid(np.arange(-2 * reach, 2 * reach + 1), np.arange(-reach, reach + 1))
        nodes = o + i.ravel()[:, None] * a + j.ravel()[:, None] * b
        nodes = nodes[np.all((nodes >= P.min(axis=0) - step) & (nodes <= P.max(axis=0) + step),
                             axis=1)]
    D = np.sqrt(((nodes[:, None, :] - P[None, :, :]) ** 2).sum(-1))
    need = np.full(len(P), margin * h)
    if wall_margin is not None:
        step = h if frame is None else frame[2]
        on = D.min(axis=0) <= 1e-6 * step
        S = np.asarray(segments)
        length = np.hypot(*(P[S[:, 1]] - P[S[:, 0]]).T)
        edge = on[S[:, 0]] & on[S[:, 1]] & (np.abs(length - step) <= 1e-6 * step)
        exempt = np.zeros(len(P), bool)
        exempt[S.ravel()] = True
        exempt[S[~edge].ravel()] = False
        need[exempt] = wall_margin * h
    gap = D - need[None, :]
    sure = np.abs(gap).min(axis=1) > 1e-6 * h  # skip nodes on a margin's edge
    keep = [k for k in np.flatnonzero(sure & (gap.min(axis=1) >= 0))
            if O.domain_location(P, loops, tuple(nodes[k])) > 0]
    keep = [k for k in keep if field(nodes[k:k + 1])[0] >= h * (1 - 1e-12)]
    return nodes[keep], nodes[~sure]


@given(corner_domains(max_holes=2), st.sampled_from([0.3, 0.15]), st.floats(1.0, 3.0))
def test_lattice_is_the_filtered_triangular_lattice(loops, h, margin):
    domain = bm.Domain.from_loops(loops)
    field = SizeField.from_domain(domain, size=h)
    fine = refine_boundary(domain, field).to_domain()
    P = np.asarray(fine.points)
    got = lattice_points(P, fine.segments, h, margin, field)
    want, unsure = _expected(P, fine.loops, h, margin, field)
    for x in got:  # each returned node is a wanted one (or one on the margin's edge)
        near = np.hypot(*(np.concatenate([want, unsure]) - x).T).min() if len(want) + len(
            unsure) else np.inf
        assert near <= 2 * JITTER * h * math.sqrt(2), f"{x} is not a lattice node kept"
    for y in want:  # and each wanted node is returned
        assert len(got) and np.hypot(*(got - y).T).min() <= 2 * JITTER * h * math.sqrt(2), y


@given(corner_domains(max_holes=1), st.sampled_from([0.3, 0.15]), st.floats(0.0, 2 * math.pi),
       st.integers(0, 20), st.floats(0.9, 1.0), st.one_of(st.none(), st.floats(0.7, 1.1)))
def test_a_lattice_in_a_frame_is_that_lattice_filtered(loops, h, angle, node, shrink, stretch):
    """With a frame (origin, direction, spacing[, row height]): the nodes
    i a + j b through the origin (a = s u, b at 60 degrees to it, or half a
    step along and a row height across), filtered as without."""
    domain = bm.Domain.from_loops(loops)
    field = SizeField.from_domain(domain, size=h)
    fine = refine_boundary(domain, field).to_domain()
    P = np.asarray(fine.points)
    frame = (P[node % len(P)], np.array([math.cos(angle), math.sin(angle)]), h * shrink)
    if stretch is not None:
        frame += (stretch * math.sqrt(3) / 2 * h * shrink,)
    got = lattice_points(P, fine.segments, h, 1.5, field, frame)
    want, unsure = _expected(P, fine.loops, h, 1.5, field, frame)
    every = np.concatenate([want, unsure])
    for x in got:
        assert len(every) and np.hypot(*(every - x).T).min() <= 2 * JITTER * h * math.sqrt(2), x
    for y in want:
        assert len(got) and np.hypot(*(got - y).T).min() <= 2 * JITTER * h * math.sqrt(2), y


@given(corner_domains(max_holes=1), st.sampled_from([0.3, 0.15]), st.integers(0, 40),
       st.floats(1.0, 3.0))
def test_walls_made_of_lattice_edges_need_only_their_own_margin(loops, h, segment, margin):
    """A frame along one refined segment, as fine as it: that wall (and any
    other that happens to lie on the lattice) is made of lattice edges, and
    the lattice keeps only 0.5 h off its nodes, margin h off the others."""
    domain = bm.Domain.from_loops(loops)
    field = SizeField.from_domain(domain, size=h)
    fine = refine_boundary(domain, field).to_domain()
    P, S = np.asarray(fine.points), np.asarray(fine.segments)
    a, b = P[S[segment % len(S)]]
    step = float(np.hypot(*(b - a)))
    frame = (a, (b - a) / step, step)
    got = lattice_points(P, S, h, margin, field, frame, 0.5)
    want, unsure = _expected(P, fine.loops, h, margin, field, frame, S, 0.5)
    every = np.concatenate([want, unsure])
    for x in got:
        assert len(every) and np.hypot(*(every - x).T).min() <= 2 * JITTER * h * math.sqrt(2), x
    for y in want:
        assert len(got) and np.hypot(*(got - y).T).min() <= 2 * JITTER * h * math.sqrt(2), y


def _polygon_walls(corners, n):
    """The polygon's walls, each cut into n equal pieces: points, segments."""
    P = np.array([c + (d - c) * k / n for c, d in zip(corners, np.roll(corners, -1, axis=0))
                  for k in range(n)])
    return P, np.column_stack([np.arange(len(P)), (np.arange(len(P)) + 1) % len(P)])


def test_a_lattice_reaches_walls_made_of_its_edges():
    """An equilateral triangle of side n and a regular hexagon of side n
    (in steps), walls cut into steps, the frame along the first wall: the
    (n - 1)(n - 2) / 2 and 3 n^2 - 3 n + 1 lattice nodes strictly inside
    are all kept at any margin; walls cut in double steps are not lattice
    edges, and their margin holds."""
    h, n = 0.1, 12
    for corners, inside in (
            (n * h * np.array([(0, 0), (1, 0), (0.5, math.sqrt(3) / 2)]), (n - 1) * (n - 2) // 2),
            (n * h * np.array([(math.cos(k * math.pi / 3), math.sin(k * math.pi / 3))
                               for k in range(6)]), 3 * n * n - 3 * n + 1)):
        P, S = _polygon_walls(corners, n)
        field = SizeField(P, np.full(len(P), h), cap=h)
        u = (P[1] - P[0]) / h
        got = lattice_points(P, S, h, 3.0, field, (P[0], u, h), 0.5)
        assert len(got) == inside
        D = np.hypot(*(got[:, None, :] - P[None, :, :]).transpose(2, 0, 1))
        assert D.min() > 0.5 * h
        assert len(lattice_points(P, S, h, 3.0, field, (P[0], u, h))) < inside
        Q, R = _polygon_walls(corners, n // 2)  # pieces of 2 h: no lattice edges
        coarse = lattice_points(Q, R, h, 3.0, field, (Q[0], u, h), 0.5)
        assert np.hypot(*(coarse[:, None, :] - Q[None, :, :]).transpose(2, 0, 1)).min() >= 3 * h


def test_no_lattice_where_the_field_is_below_its_cap():
    """A fine hole makes the field grow from its spacing: no lattice node
    where the field is still below the cap."""
    t = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    hole = 0.1 * np.column_stack([np.cos(t), np.sin(t)])
    outer = np.array([(-2, -2), (2, -2), (2, 2), (-2, 2)], float)
    domain = bm.Domain.from_loops([outer, hole])
    field = SizeField.from_domain(domain, size=0.1)
    fine = refine_boundary(domain, field).to_domain()
    got = lattice_points(fine.points, fine.segments, 0.1, 1.0, field)
    assert len(got) > 1000
    assert np.all(field(got) >= 0.1 * (1 - 1e-12))
    # the field reaches the cap 0.1 only (0.1 - 0.0031) / 0.25 from the hole's nodes
    assert np.hypot(*got.T).min() > 0.1 + (0.1 - 2 * np.pi * 0.1 / 200) / 0.25 * 0.99
