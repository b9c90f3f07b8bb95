"""The settling operations of bm.mesh: valence/quality flips (bubblemesh._flips),
ODT smoothing and the mean compass search (bubblemesh._odt), and the settled
pipeline: validity, conformity, the never-worse minimum, fixed boundary nodes,
determinism at any thread count.

Oracles: verification/oracles.py (exact orientation and conformity, the radius
ratio from the classical formulas), numpy valence counts and angle sums, not
the kernels themselves."""

from __future__ import annotations

import os
import subprocess
import sys
import warnings
from fractions import Fraction

import numpy as np
import oracles as O
import pytest
import strategies as S
from hypothesis import given
from hypothesis import strategies as st
from test_pipeline import corner_domains

import bubblemesh as bm
from bubblemesh import pipeline
from bubblemesh._corners import split_corners
from bubblemesh._flips import delaunay_flips, ideal_counts, improve_flips, segment_keys
from bubblemesh._odt import mean_polish, odt_smooth
from bubblemesh._smoothing import gather_star, gathered_stats, guarded_smooth, star_buffer, stars
from bubblemesh.generation import generate_sized
from bubblemesh.refinement import refine_boundary
from bubblemesh.sizing import SizeField


def _sized(loops, size):
    domain = bm.Domain.from_loops(loops)
    field = SizeField.from_domain(domain, size=size)
    return generate_sized(refine_boundary(domain, field).to_domain(), field), field


def _valence_energy(X, tri):
    """sum_v (triangles at v - round(angle sum / 60 degrees))^2, in numpy."""
    count = np.bincount(tri.ravel(), minlength=len(X))
    total = np.zeros(len(X))
    for k in range(3):
        i, j, m = tri[:, k], tri[:, (k + 1) % 3], tri[:, (k + 2) % 3]
        u, v = X[j] - X[i], X[m] - X[i]
        cos = (u * v).sum(1) / np.hypot(*u.T) / np.hypot(*v.T)
        np.add.at(total, i, np.arccos(np.clip(cos, -1, 1)))
    ideal = np.maximum(1, np.round(total / (np.pi / 3)))
    return float(((count - ideal) ** 2).sum())


@given(corner_domains(max_holes=2), st.sampled_from([0.3, 0.2]), st.floats(0.0, 1.0),
       st.integers(0, 2**32 - 1))
def test_flips_keep_the_mesh_valid_conforming_and_never_lower_the_minimum(loops, size, relax,
                                                                          seed):
    m, _ = _sized(loops, size)
    X = np.array(m.points)
    rng = np.random.default_rng(seed)
    inner = slice(m.n_boundary, None)  # jitter so that flips are worth making
    X[inner] += rng.uniform(-0.15, 0.15, X[inner].shape) * m.radii[inner, None]
    tri, nbr = bm.constrained_delaunay(X, m.segments)
    tri, nbr = np.array(tri), np.array(nbr)
    before_q = O.radius_ratio_reference(X, tri).min()
    before_e = _valence_energy(X, tri)
    relax = max(relax, before_q)  # at least the minimum: the minimum must survive
    improve_flips(X, tri, nbr, segment_keys(np.asarray(m.segments), len(X)),
                  ideal_counts(X, tri, len(X)), 20, relax)
    O.check_valid(X, tri, nbr)
    O.check_conforming(X, tri, m.segments, area=m.domain.area, rel=1e-9)
    assert O.radius_ratio_reference(X, tri).min() >= before_q * (1 - 1e-12)
    assert _valence_energy(X, tri) <= before_e


def test_a_flip_fixes_a_valence_defect_and_never_flips_a_segment():
    """A square split along its diagonal 0-2 by four nodes around it: with the
    diagonal a segment nothing may flip it; without, the flip to 1-3 is taken
    exactly when the quadrilateral is convex."""
    X = np.array([(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)])
    tri = np.array([[0, 1, 2], [0, 2, 3]])
    nbr = np.array([[-1, 1, -1], [-1, -1, 0]])
    ideal = np.array([1, 2, 1, 2])  # 1 and 3 "want" a second triangle: a strict gain
    segs = np.array([[0, 1], [1, 2], [2, 3], [3, 0], [0, 2]])
    t2, n2 = tri.copy(), nbr.copy()
    assert improve_flips(X, t2, n2, segment_keys(segs, 4), ideal, 5, 0.0) == 0
    np.testing.assert_array_equal(t2, tri)
    assert improve_flips(X, tri, nbr, segment_keys(segs[:4], 4), ideal, 5, 0.0) == 1
    O.check_valid(X, tri, nbr)
    assert {frozenset(t) for t in tri.tolist()} == {frozenset((0, 1, 3)), frozenset((1, 2, 3))}
    Y = np.array([(0.7, 0.5), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)])  # reflex at 0: no flip
    tri = np.array([[0, 1, 2], [0, 2, 3]])
    nbr = np.array([[-1, 1, -1], [-1, -1, 0]])
    assert improve_flips(Y, tri, nbr, segment_keys(segs[:4], 4), ideal, 5, 0.0) == 0


@given(corner_domains(max_holes=2), st.sampled_from([0.3, 0.2]), st.integers(0, 2**32 - 1))
def test_corner_splits_keep_the_mesh_valid_conforming_and_never_lower_the_minimum(loops, size,
                                                                                  seed):
    m, _ = _sized(loops, size)
    X = np.array(m.points)
    rng = np.random.default_rng(seed)
    inner = slice(m.n_boundary, None)
    X[inner] += rng.uniform(-0.15, 0.15, X[inner].shape) * m.radii[inner, None]
    tri, nbr = bm.constrained_delaunay(X, m.segments)
    tri, nbr = np.array(tri), np.array(nbr)
    before_q = O.radius_ratio_reference(X, tri).min()
    fixed = np.zeros(len(X), np.bool_)
    fixed[np.asarray(m.segments).ravel()] = True
    movable = ~fixed
    P = X.copy()
    split_corners(X, tri, nbr, segment_keys(np.asarray(m.segments), len(X)),
                  ideal_counts(X, tri, len(X)), fixed, movable)
    O.check_valid(X, tri, nbr)
    O.check_conforming(X, tri, m.segments, area=m.domain.area, rel=1e-9)
    assert O.radius_ratio_reference(X, tri).min() >= before_q * (1 - 1e-12)
    np.testing.assert_array_equal(X[fixed], P[fixed])  # boundary nodes never move


def test_a_corner_split_gives_a_wide_corner_its_second_triangle():
    """A 120 degree corner v = 0 with one triangle (0, 1, 2) and the node 3
    across 1-2: the split flips 1-2 to 0-3 and moves 3 toward the bisector,
    raising the worst ratio from the single triangle's (0.46); with 1-2 a
    segment nothing changes."""
    c, s = np.cos(np.radians(30)), np.sin(np.radians(30))
    X = np.array([(0.0, 0.0), (c, -s), (c, s), (1.2, 0.0)])
    tri = np.array([[0, 1, 2], [2, 1, 3]])
    nbr = np.array([[1, -1, -1], [-1, -1, 0]])
    ideal = np.array([2, 1, 1, 1])
    fixed = np.array([True, True, True, False])
    segs = np.array([[0, 1], [1, 3], [3, 2], [2, 0]])
    before = O.radius_ratio_reference(X, tri).min()
    t2, n2, X2 = tri.copy(), nbr.copy(), X.copy()
    assert split_corners(X2, t2, n2, segment_keys(np.vstack([segs, [[1, 2]]]), 4), ideal,
                         fixed, ~fixed) == 0
    np.testing.assert_array_equal(t2, tri)
    assert split_corners(X, tri, nbr, segment_keys(segs, 4), ideal, fixed, ~fixed) == 1
    O.check_valid(X, tri, nbr)
    assert {frozenset(t) for t in tri.tolist()} == {frozenset((0, 1, 3)), frozenset((0, 3, 2))}
    assert O.radius_ratio_reference(X, tri).min() > before + 0.1


@given(corner_domains(max_holes=1), st.integers(0, 2**32 - 1), st.sampled_from([0, 3]))
def test_odt_and_mean_polish_never_lower_the_minimum_nor_invert(loops, seed, steps):
    m, field = _sized(loops, 0.2)
    X = np.array(m.points)
    tri = np.array(m.triangles)
    rng = np.random.default_rng(seed)
    movable = rng.random(len(X)) < 0.7
    before = O.radius_ratio_reference(X, tri).min()
    ptr, idx = stars(tri, len(X))
    odt_smooth(X, tri, ptr, idx, field(X), m.n_boundary, 4, movable, before, 0.0)
    O.check_valid(X, tri)
    mid = O.radius_ratio_reference(X, tri).min()
    assert mid >= before * (1 - 1e-12)
    mean_before = O.radius_ratio_reference(X, tri).mean()
    mean_polish(X, tri, ptr, idx, m.n_boundary, 2, movable, mid, 3, 1.0, steps)
    O.check_valid(X, tri)
    q = O.radius_ratio_reference(X, tri)
    assert q.min() >= before * (1 - 1e-12)
    assert q.mean() >= mean_before - 1e-12  # each step raises its star's mean
    np.testing.assert_array_equal(X[~movable], np.asarray(m.points)[~movable])
    np.testing.assert_array_equal(X[: m.n_boundary], np.asarray(m.points)[: m.n_boundary])


@given(corner_domains(max_holes=2), st.integers(0, 2**32 - 1))
def test_delaunay_flips_turn_a_valid_mesh_into_the_constrained_delaunay_one(loops, seed):
    """Nodes moved validly (guarded smoothing) and edges flipped away from
    Delaunay (quality flips, relaxed): Lawson's flips must give a valid,
    conforming, constrained-Delaunay mesh (exact oracle), the very triangles
    of bm.constrained_delaunay when that one is unique."""
    m, _ = _sized(loops, 0.2)
    X = np.array(m.points)
    tri, nbr = np.array(m.triangles), np.array(m.neighbors)
    rng = np.random.default_rng(seed)
    ptr, idx = stars(tri, len(X))
    guarded_smooth(X, tri, ptr, idx, m.n_boundary, 2, rng.random(len(X)) < 0.8)
    keys = segment_keys(np.asarray(m.segments), len(X))
    improve_flips(X, tri, nbr, keys, np.full(len(X), 1), 3, 0.0)  # valences pushed off
    delaunay_flips(X, tri, nbr, keys, 4 * len(tri))
    O.check_valid(X, tri, nbr)
    O.check_conforming(X, tri, m.segments, area=m.domain.area, rel=1e-9)
    O.check_constrained_delaunay(X, tri, m.segments)
    if O.delaunay_is_unique(X, tri, m.segments):
        ref, _ = bm.constrained_delaunay(X, m.segments)
        assert O.canonical_triangles(tri) == O.canonical_triangles(ref)


@given(corner_domains(max_holes=2), st.integers(0, 2**32 - 1))
def test_the_non_delaunay_mask_is_the_exact_local_test(loops, seed):
    """non_delaunay_mask (each edge once, in parallel) marks the interior
    non-segment edges the exact oracle finds not locally Delaunay: none on the
    CDT, some after relaxed quality flips.  Lawson's flips seeded with just
    those edges reach a constrained Delaunay triangulation (exact oracle), the
    same triangles as the flips that look at every edge when it is unique."""
    from bubblemesh._flips import lawson_flips, non_delaunay_mask
    from bubblemesh.verify import delaunay as exact_delaunay
    from bubblemesh.verify.exact import ExactPoints
    from bubblemesh.verify.topology import HalfEdges

    m, _ = _sized(loops, 0.2)
    X = np.array(m.points)
    tri, nbr = np.array(m.triangles), np.array(m.neighbors)
    keys = segment_keys(np.asarray(m.segments), len(X))
    rng = np.random.default_rng(seed)
    for relax in (False, True):
        if relax:
            improve_flips(X, tri, nbr, keys, rng.integers(1, 8, len(X)), 3, 0.0)
        H = HalfEdges(tri, len(X))
        bad = exact_delaunay.local_violations(ExactPoints(X), H, np.ones(len(tri), bool),
                                              np.asarray(m.segments).reshape(-1, 2))
        want = {(min(int(H.u[h]), int(H.v[h])), max(int(H.u[h]), int(H.v[h]))) for h in bad}
        marked = np.argwhere(non_delaunay_mask(X, tri, nbr, keys))
        got = [tuple(sorted((int(tri[t, (k + 1) % 3]), int(tri[t, (k + 2) % 3]))))
               for t, k in marked]
        assert len(got) == len(set(got)) and set(got) == want
    seeded, s_nbr = tri.copy(), nbr.copy()
    first = np.flatnonzero(non_delaunay_mask(X, tri, nbr, keys))
    assert lawson_flips(X, seeded, s_nbr, keys, 4 * len(tri), first) >= len(want) > 0
    O.check_valid(X, seeded, s_nbr)
    O.check_constrained_delaunay(X, seeded, m.segments)
    delaunay_flips(X, tri, nbr, keys, 4 * len(tri))
    if O.delaunay_is_unique(X, tri, m.segments):
        assert O.canonical_triangles(seeded) == O.canonical_triangles(tri)


@given(corner_domains(max_holes=1), st.integers(0, 2**32 - 1))
def test_turned_over_counts_the_triangles_not_counter_clockwise(loops, seed):
    """turned_over (a flag per triangle) against exact rational orientation,
    with nodes moved at random (some triangles turned over, some made flat)."""
    from bubblemesh._flips import turned_over

    m, _ = _sized(loops, 0.2)
    tri = np.asarray(m.triangles)
    rng = np.random.default_rng(seed)
    for scale in (0.0, 0.3, 1.5):
        X = np.array(m.points)
        X[m.n_boundary:] += rng.normal(scale=scale * float(np.median(m.radii)),
                                       size=(len(X) - m.n_boundary, 2))
        if len(tri) > 1 and scale > 1:
            a, b, c = tri[0]
            X[c] = X[a] + 0.5 * (X[b] - X[a]) if c >= m.n_boundary else X[c]  # flat, maybe
        want = [not _ccw_exact(X[a], X[b], X[c]) for a, b, c in tri]
        assert turned_over(X, tri).tolist() == want


def test_delaunay_flips_stop_at_their_bound():
    """A square split along the wrong diagonal needs one flip: with a bound of
    0 the kernel reports -1 and leaves the mesh as it was."""
    X = np.array([(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.1, 0.9)])
    tri = np.array([[0, 1, 2], [0, 2, 3]])
    nbr = np.array([[-1, 1, -1], [-1, -1, 0]])
    keys = segment_keys(np.array([[0, 1], [1, 2], [2, 3], [3, 0]]), 4)
    t2, n2 = tri.copy(), nbr.copy()
    assert delaunay_flips(X, t2, n2, keys, 0) == -1
    np.testing.assert_array_equal(t2, tri)
    assert delaunay_flips(X, tri, nbr, keys, 10) == 1
    assert O.canonical_triangles(tri) == O.canonical_triangles(np.array([[0, 1, 3], [1, 2, 3]]))


def _ccw_exact(a, b, c):
    """Strictly counter-clockwise, in exact rational arithmetic."""
    (ax, ay), (bx, by), (cx, cy) = ([Fraction(float(v)) for v in p] for p in (a, b, c))
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax) > 0


def _star_samples(loops, seed):
    """A sized mesh of ``loops``, its stars, a star buffer, a generator from
    ``seed`` and up to 10 of its interior nodes drawn from it."""
    m, _ = _sized(loops, 0.2)
    X, tri = np.asarray(m.points), np.asarray(m.triangles)
    ptr, idx = stars(tri, len(X))
    rng = np.random.default_rng(seed)
    nodes = rng.integers(m.n_boundary, len(X), 10) if len(X) > m.n_boundary else ()
    return m, X, tri, ptr, idx, star_buffer(ptr), rng, nodes


@given(corner_domains(max_holes=1), st.integers(0, 2**32 - 1))
def test_a_gathered_star_rates_a_moved_node_like_the_reference(loops, seed):
    """(smallest, mean) ratio of a star with its node moved, from the gathered
    star, against the classical formula; -1 exactly when a triangle of the
    star is not counter-clockwise by exact orientation."""
    m, X, tri, ptr, idx, buf, rng, nodes = _star_samples(loops, seed)
    for i in nodes:
        deg = gather_star(X, tri, ptr, idx, int(i), buf)
        star = tri[idx[ptr[i]:ptr[i + 1]]]
        for p in X[i] + rng.uniform(-0.3, 0.3, (5, 2)) * m.radii[i]:
            Y = X.copy()
            Y[i] = p
            worst, mean = gathered_stats(buf, deg, p[0], p[1])
            if not all(_ccw_exact(Y[a], Y[b], Y[c]) for a, b, c in star):
                assert (worst, mean) == (-1.0, -1.0)
                continue
            q = O.radius_ratio_reference(Y, star)
            np.testing.assert_allclose([worst, mean], [q.min(), q.mean()], rtol=1e-12, atol=1e-12)


@given(corner_domains(max_holes=1), st.integers(0, 2**32 - 1))
def test_the_early_exit_rating_decides_like_the_full_one(loops, seed):
    """gathered_beats (stops at the first deciding triangle) says whether the
    star's smallest ratio beats a bar exactly as the full rating does: bars
    around that ratio, 0, 1, and moves that turn triangles over."""
    from bubblemesh._smoothing import gathered_beats

    m, X, tri, ptr, idx, buf, rng, nodes = _star_samples(loops, seed)
    for i in nodes:
        deg = gather_star(X, tri, ptr, idx, int(i), buf)
        for p in X[i] + rng.uniform(-0.6, 0.6, (5, 2)) * m.radii[i]:
            worst = gathered_stats(buf, deg, p[0], p[1])[0]
            for bar in (0.0, 1.0, worst, np.nextafter(worst, 0.0), np.nextafter(worst, 1.0),
                        rng.uniform(0.3, 1.0)):
                assert gathered_beats(buf, deg, p[0], p[1], bar) == (worst > bar)


def _star_rows(X, tri, star, i):
    """Far corners (u, v) of node i's triangles, counter-clockwise."""
    rows = []
    for t in star:
        k = list(tri[t]).index(i)
        rows.append((tri[t, (k + 1) % 3], tri[t, (k + 2) % 3]))
    return rows


@given(corner_domains(max_holes=1), st.integers(0, 2**32 - 1))
def test_the_shortest_edge_of_a_gathered_star_is_the_nearest_neighbours_hypot(loops, seed):
    """shortest_edge (hypot only for near-shortest candidates) against the
    kernels' hypot over every neighbour, bit for bit (and Python's within an
    ulp), with the node moved, and at the centre of a regular hexagon (six
    edges within rounding)."""
    import math

    from numba import njit

    from bubblemesh._smoothing import shortest_edge

    hypot = njit(lambda x, y: math.hypot(x, y))  # compiled: libm's, as in the kernel

    m, X, tri, ptr, idx, buf, rng, nodes = _star_samples(loops, seed)
    for i in nodes:
        deg = gather_star(X, tri, ptr, idx, int(i), buf)
        neighbours = {int(v) for t in idx[ptr[i]:ptr[i + 1]] for v in tri[t] if v != i}
        for p in (X[i], *(X[i] + rng.uniform(-0.3, 0.3, (3, 2)) * m.radii[i])):
            want = min(hypot(X[v, 0] - p[0], X[v, 1] - p[1]) for v in neighbours)
            got = shortest_edge(buf, deg, p[0], p[1])
            assert got == want
            assert math.isclose(got, min(math.hypot(*(X[v] - p)) for v in neighbours),
                                rel_tol=4e-16)
    angles = np.arange(6) * np.pi / 3
    hexagon = np.vstack([[0.1, 0.7], 0.1 + np.c_[np.cos(angles), 0.6 + np.sin(angles)]])
    hexagon[0] = hexagon[1:].mean(axis=0)
    fan = np.array([[0, k, k % 6 + 1] for k in range(1, 7)])
    ptr, idx = stars(fan, 7)
    deg = gather_star(hexagon, fan, ptr, idx, 0, buf)
    want = min(hypot(*(hexagon[v] - hexagon[0])) for v in range(1, 7))
    assert shortest_edge(buf, deg, hexagon[0, 0], hexagon[0, 1]) == want


def _star_total(X, triangles, i, p):
    """Sum of eq. 10 over ``triangles`` with node i at p (numpy reference)."""
    Y = X.copy()
    Y[i] = p
    return O.radius_ratio_reference(Y, triangles).sum()


@given(corner_domains(max_holes=1), st.integers(0, 2**32 - 1))
def test_the_mean_gradient_is_the_derivative_of_the_star_ratios(loops, seed):
    """The gradient of the sum of a star's radius ratios (the polish's
    direction) against the analytic formula evaluated in plain Python, bit
    for bit, and against central differences of eq. 10 (numpy)."""
    from bubblemesh._odt import _mean_gradient

    m, X, tri, ptr, idx, buf, rng, nodes = _star_samples(loops, seed)
    for i in nodes:
        deg = gather_star(X, tri, ptr, idx, int(i), buf)
        star = idx[ptr[i]:ptr[i + 1]]
        p = X[i] + rng.uniform(-0.1, 0.1, 2) * m.radii[i]
        want = [0.0, 0.0]
        for e, (u, v) in enumerate(_star_rows(X, tri, star, i)):
            (ux, uy), (vx, vy) = X[u], X[v]
            assert tuple(buf[e, :4]) == (ux, uy, vx, vy)
            a = float(buf[e, 4])  # |uv|, gathered
            assert abs(a - np.hypot(ux - vx, uy - vy)) <= 1e-15 * a
            bx, by, cx, cy = p[0] - vx, p[1] - vy, p[0] - ux, p[1] - uy
            b, c = float(np.sqrt(bx * bx + by * by)), float(np.sqrt(cx * cx + cy * cy))
            area2 = (ux - p[0]) * (vy - p[1]) - (uy - p[1]) * (vx - p[0])
            if area2 <= 0.0:
                continue
            s = a + b + c
            r = 4.0 * area2 * area2 / (s * a * b * c)
            want[0] += r * (2.0 * (uy - vy) / area2 - (bx / b + cx / c) / s - bx / (b * b)
                            - cx / (c * c))
            want[1] += r * (2.0 * (vx - ux) / area2 - (by / b + cy / c) / s - by / (b * b)
                            - cy / (c * c))
        got = _mean_gradient(buf, deg, p[0], p[1])
        assert got == tuple(want)
        h = 1e-6 * m.radii[i]

        fd = [(_star_total(X, tri[star], i, p + d) - _star_total(X, tri[star], i, p - d)) / (2 * h)
              for d in (np.array([h, 0]), np.array([0, h]))]
        np.testing.assert_allclose(got, fd, rtol=1e-4, atol=1e-4 * np.abs(fd).max())


@S.budget(15)
@given(S.domains(max_holes=2, graded=True, min_spacing=0.2))
def test_settled_meshes_of_graded_domains_are_valid_conforming_and_never_worse(case):
    domain = bm.Domain.from_loops(list(case.loops))
    field = SizeField.from_domain(domain)
    generated = generate_sized(refine_boundary(domain, field).to_domain(), field)
    out = pipeline.stable_optimize(generated, max_iterations=40, size_field=field)
    O.check_valid(out.points, out.triangles, out.neighbors)
    O.check_conforming(out.points, out.triangles, out.segments, area=generated.domain.area,
                       rel=1e-9)
    before = O.radius_ratio_reference(generated.points, generated.triangles).min()
    assert O.radius_ratio_reference(out.points, out.triangles).min() >= before * (1 - 1e-12)
    np.testing.assert_array_equal(out.points[: out.n_boundary],
                                  generated.points[: generated.n_boundary])


def test_settling_raises_the_mean_on_a_corner_only_square_with_a_hole():
    loops = [np.array([(0, 0), (1, 0), (1, 1), (0, 1)], float),
             np.array([(.4, .4), (.4, .6), (.6, .6), (.6, .4)], float)]
    m, field = _sized(loops, 0.05)
    plain = pipeline.stable_optimize(m, settle=False)
    settled = pipeline.stable_optimize(m, size_field=field)
    q0 = O.radius_ratio_reference(plain.points, plain.triangles)
    q1 = O.radius_ratio_reference(settled.points, settled.triangles)
    assert q1.mean() > q0.mean() and q1.min() >= q0.min() * (1 - 1e-12)


_DIGEST = """
import hashlib, numpy as np, bubblemesh as bm
d = bm.Domain.from_loops([np.array([(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)], float),
                          np.array([(.3, .3), (.3, .6), (.6, .6), (.6, .3)], float)])
m = bm.mesh(d, size=0.08)
h = hashlib.sha256()
for a in (m.points, m.triangles, m.neighbors):
    h.update(np.ascontiguousarray(a).tobytes())
print(h.hexdigest())
"""


@pytest.mark.heavy
def test_the_settled_mesh_is_the_same_bits_at_any_thread_count():
    digests = set()
    for threads in ("1", "2"):
        env = dict(os.environ, NUMBA_NUM_THREADS=threads)
        out = subprocess.run([sys.executable, "-c", _DIGEST], env=env, capture_output=True,
                             text=True, check=True)
        digests.add(out.stdout.strip())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scope: dict = {}
        exec(compile(_DIGEST.replace("print(h.hexdigest())", "digest = h.hexdigest()"),
                     "<digest>", "exec"), scope)
    digests.add(scope["digest"])
    assert len(digests) == 1, digests


@given(corner_domains(max_holes=2), st.sampled_from([0.3, 0.15]), st.integers(0, 2**32 - 1))
def test_the_colour_classes_are_a_proper_colouring_of_the_chosen_nodes(loops, size, seed):
    """The parallel sweeps visit one colour at a time: no edge may join two
    nodes of one colour (edges from the triangles in numpy), every chosen
    interior node is coloured exactly once, the others never, and each class
    is in index order."""
    from bubblemesh._colouring import colour_classes

    m, _ = _sized(loops, size)
    tri = np.asarray(m.triangles)
    ptr, idx = stars(tri, len(m.points))
    chosen = np.random.default_rng(seed).random(len(m.points)) < 0.8
    order, colour_ptr = colour_classes(tri, ptr, idx, m.n_boundary, chosen)
    expected = np.flatnonzero(chosen & (np.arange(len(chosen)) >= m.n_boundary)
                              & (np.bincount(tri.ravel(), minlength=len(chosen)) > 0))
    np.testing.assert_array_equal(np.sort(order), expected)
    colour = np.full(len(chosen), -1)
    for c in range(len(colour_ptr) - 1):
        members = order[colour_ptr[c]:colour_ptr[c + 1]]
        assert len(members) and np.all(np.diff(members) > 0)
        colour[members] = c
    edges = np.vstack([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    a, b = colour[edges[:, 0]], colour[edges[:, 1]]
    assert not np.any((a >= 0) & (a == b)), "an edge inside one colour class"


@given(corner_domains(max_holes=1), st.integers(0, 2**32 - 1), st.floats(0.6, 3.0))
def test_untangle_mends_triangles_turned_over_by_a_moved_node(loops, seed, reach):
    """A node pushed across its star (still inside the domain) turns triangles
    over; untangle either re-triangulates a patch around them, keeping every
    node and segment, with every triangle counter-clockwise (exact oracle),
    after which Lawson's flips give a constrained Delaunay triangulation, or
    reports False and changes nothing."""
    from bubblemesh._flips import lawson_flips, non_delaunay_mask, turned_over
    from bubblemesh._untangle import untangle

    m, _ = _sized(loops, 0.2)
    if len(m.points) == m.n_boundary:
        return
    X = np.array(m.points)
    tri, nbr = np.array(m.triangles), np.array(m.neighbors)
    rng = np.random.default_rng(seed)
    i = int(rng.integers(m.n_boundary, len(X)))
    j = [v for v in tri[(tri == i).any(axis=1)].ravel() if v != i][int(rng.integers(0, 6)) % 3]
    target = X[i] + reach * (X[j] - X[i])
    loops = O.loops_from_segments(m.segments)
    if O.domain_location(X, loops, target) <= 0:
        return  # the forces keep nodes strictly inside
    X[i] = target
    turned = turned_over(X, tri)
    if not turned.any():
        return
    before = tri.copy(), nbr.copy()
    if not untangle(X, tri, nbr, np.asarray(m.segments), turned):
        assert np.array_equal(tri, before[0]) and np.array_equal(nbr, before[1])
        return
    assert not turned_over(X, tri).any()
    assert len(np.unique(tri)) == len(X)
    O.check_valid(X, tri, nbr)
    O.check_conforming(X, tri, m.segments, area=m.domain.area, rel=1e-9)
    keys = segment_keys(np.asarray(m.segments), len(X))
    first = np.flatnonzero(non_delaunay_mask(X, tri, nbr, keys))
    lawson_flips(X, tri, nbr, keys, 4 * len(tri), first)
    O.check_constrained_delaunay(X, tri, m.segments)


@given(corner_domains(max_holes=1), st.integers(0, 2**32 - 1))
def test_the_smoothing_gather_is_the_star_its_neighbour_sum_and_the_active_set(loops, seed):
    """gather_for_smoothing's one pass against its three definitions: the rows
    of gather_star; the neighbours' coordinates summed in the star's triangle
    and corner order (plain Python); unchanged exactly when the node was seen
    and neither it nor a node of its star moved after that."""
    from bubblemesh._smoothing import gather_for_smoothing

    m, _ = _sized(loops, 0.2)
    X, tri = np.asarray(m.points), np.asarray(m.triangles)
    ptr, idx = stars(tri, len(X))
    buf, ref = star_buffer(ptr), star_buffer(ptr)
    rng = np.random.default_rng(seed)
    moved_at = rng.integers(-1, 6, len(X))
    for i in rng.integers(m.n_boundary, len(X), 10) if len(X) > m.n_boundary else ():
        for seen in (-1, 2, 4, 7):
            deg, sx, sy, unchanged = gather_for_smoothing(X, tri, ptr, idx, int(i), buf,
                                                          moved_at, seen)
            assert deg == gather_star(X, tri, ptr, idx, int(i), ref)
            assert np.array_equal(buf[:deg], ref[:deg])
            want_x = want_y = 0.0
            for t in idx[ptr[i]:ptr[i + 1]]:
                for v in tri[t]:
                    if v != i:
                        want_x += float(X[v, 0])
                        want_y += float(X[v, 1])
            assert (sx, sy) == (want_x, want_y)
            star = {int(v) for t in idx[ptr[i]:ptr[i + 1]] for v in tri[t]}
            assert unchanged == (seen >= 0 and moved_at[i] < seen
                                 and all(moved_at[v] <= seen for v in star))


@S.budget(20)
@given(corner_domains(max_holes=1), st.integers(0, 2**32 - 1))
def test_the_mean_polish_active_set_changes_no_bit(loops, seed):
    """mean_polish skips nodes whose last visit moved nothing and whose star
    has not moved since: the same positions, bit for bit, as visiting every
    node of every colour class in every sweep."""
    from bubblemesh._colouring import colour_classes
    from bubblemesh._odt import _mean_visit

    m, _ = _sized(loops, 0.2)
    X, tri = np.array(m.points), np.asarray(m.triangles)
    rng = np.random.default_rng(seed)
    X[m.n_boundary:] += rng.normal(scale=0.05 * float(np.median(m.radii)),
                                   size=(len(X) - m.n_boundary, 2))
    ptr, idx = stars(tri, len(X))
    movable = np.ones(len(X), bool)
    movable[: m.n_boundary] = False
    Y = X.copy()
    mean_polish(X, tri, ptr, idx, m.n_boundary, 3, movable, 0.5, 4, 1.0, 3)
    order, colour_ptr = colour_classes(tri, ptr, idx, m.n_boundary, movable)
    buf = star_buffer(ptr)
    for _ in range(3):
        moved = sum(_mean_visit(Y, tri, ptr, idx, i, buf, 0.5, 4, 1.0, 3) for i in order)
        if moved == 0:
            break
    assert np.array_equal(X, Y)


@given(corner_domains(max_holes=1), st.integers(0, 2**32 - 1))
def test_a_star_clearly_fine_by_its_triangles_is_fine_by_the_gathered_rating(loops, seed):
    """The compass search's pass-over test: where every triangle's ratio (in
    its own corner order) is at least poor + MARGIN and no node has moved,
    the star's smallest ratio rated from the node's corner is at least poor;
    bars at the mesh's own ratios, where the two roundings meet."""
    from bubblemesh._smoothing import MARGIN, _clearly_fine, triangle_quality

    m, _ = _sized(loops, 0.2)
    X, tri = np.array(m.points), np.asarray(m.triangles)
    rng = np.random.default_rng(seed)
    X[m.n_boundary:] += rng.normal(scale=0.1 * float(np.median(m.radii)),
                                   size=(len(X) - m.n_boundary, 2))
    ptr, idx = stars(tri, len(X))
    buf = star_buffer(ptr)
    q = triangle_quality(X, tri)
    touched = np.zeros(len(X), bool)
    for poor in (0.85, *(q[rng.integers(0, len(q), 3)] - MARGIN)):
        for i in range(m.n_boundary, len(X)):
            if _clearly_fine(tri, ptr, idx, i, q, touched, poor):
                deg = gather_star(X, tri, ptr, idx, i, buf)
                assert gathered_stats(buf, deg, X[i, 0], X[i, 1])[0] >= poor
