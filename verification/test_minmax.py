"""Joint min-max moves around the worst triangles (bubblemesh._minmax), the
step of bm.mesh before its last polish: the radius ratio and its gradient
against the classical formulas and central differences of them; on jittered
meshes, the triangles untouched, the fixed nodes unmoved bit for bit, every
triangle counter-clockwise and the mesh conforming, the minimum never
lowered nor any triangle taken below min(its ratio, KEEP), the mean within
the MEAN_DROP budget, the area bounds kept, the same bits on a second run; a
jittered equilateral lattice, whose optimum is known (every ratio 1), given
back; a solver that raises leaves the mesh as it was; a triangle no move can
lift (its nodes fixed, or its patch refused) does not stop the rounds for
the others.

Oracles: verification/oracles.py (exact orientation and conformity, the
radius ratio from the inradius and circumradius formulas), numpy areas."""

from __future__ import annotations

import numpy as np
import oracles as O
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st
from strategies import budget
from test_pipeline import corner_domains
from test_relaxed_flips import _areas, _jittered, _lattice_patch

from bubblemesh import _minmax
from bubblemesh._minmax import (
    CAPS,
    FIRST_ROUNDS,
    KEEP,
    LIFT_BELOW,
    MEAN_DROP,
    POOR,
    minmax_patches,
    ratio_rows,
)

coordinate = st.floats(-10.0, 10.0, allow_nan=False)


@given(st.lists(st.tuples(coordinate, coordinate), min_size=3, max_size=3),
       st.lists(st.booleans(), min_size=3, max_size=3))
def test_ratio_rows_match_the_classical_formula_and_its_differences(corners, moving):
    P = np.array(corners, float)
    u, v = P[1] - P[0], P[2] - P[0]
    if u[0] * v[1] - u[1] * v[0] < 0:
        P = P[[0, 2, 1]]
    scale = max(np.ptp(P, axis=0).max(), 1e-300)
    area2 = (P[1, 0] - P[0, 0]) * (P[2, 1] - P[0, 1]) - (P[1, 1] - P[0, 1]) * (P[2, 0] - P[0, 0])
    assume(area2 > 0.05 * scale * scale)  # differences need a triangle far from flat
    C = np.array([[0, 1, 2]])
    slot = np.where(moving, np.cumsum(moving) - 1, -1)[None, :]
    n = 2 * int(sum(moving)) + 1
    rho, a2, d_rho, d_a2 = np.empty(1), np.empty(1), np.empty((1, n)), np.empty((1, n))
    ratio_rows(P, C, slot, rho, a2, d_rho, d_a2)
    assert rho[0] == pytest.approx(O.radius_ratio_reference(P, C)[0], rel=1e-12)
    assert a2[0] == pytest.approx(area2, rel=1e-12)
    assert d_rho[0, -1] == 0.0 and d_a2[0, -1] == 0.0  # no derivative for t
    h = 1e-6 * scale
    for j in range(3):
        for axis in range(2):
            step = np.zeros_like(P)
            step[j, axis] = h
            up, down = O.radius_ratio_reference(P + step, C), O.radius_ratio_reference(P - step, C)
            central = (up[0] - down[0]) / (2 * h)
            got = d_rho[0, 2 * slot[0, j] + axis] if slot[0, j] >= 0 else None
            if got is None:
                continue
            assert got == pytest.approx(central, rel=1e-5, abs=1e-7 / scale)
            # 2A = (b - a) x (c - a): d/dx_a = y_b - y_c, d/dy_a = x_c - x_b, cyclically
            b, c = P[(j + 1) % 3], P[(j + 2) % 3]
            exact = b[1] - c[1] if axis == 0 else c[0] - b[0]
            assert d_a2[0, 2 * slot[0, j] + axis] == pytest.approx(exact, rel=1e-12, abs=1e-12)


def _run(X, tri, segments, n_b, limit, rounds=8):
    movable = np.arange(len(X)) >= n_b
    movable[np.unique(segments)] = False
    return minmax_patches(X, tri, movable, limit, rounds)


@budget(40)
@given(corner_domains(max_holes=2), st.sampled_from([0.3, 0.2]), st.booleans(),
       st.integers(0, 2**32 - 1))
def test_moves_keep_the_mesh_valid_conforming_and_within_its_bounds(loops, size, bounded, seed):
    m, X, tri, _ = _jittered(loops, size, seed)
    X0, tri0, q0 = X.copy(), tri.copy(), O.radius_ratio_reference(X, tri)
    # a bound every triangle meets now, some just: moved triangles must keep it
    limit = np.full(len(tri), _areas(X, tri).max() * (1.0 + 1e-9) if bounded else np.inf)
    kept = _run(X, tri, m.segments, m.n_boundary, limit)
    np.testing.assert_array_equal(tri, tri0)
    fixed = np.ones(len(X), bool)
    fixed[m.n_boundary:] = False
    fixed[np.unique(m.segments)] = True
    np.testing.assert_array_equal(X[fixed], X0[fixed])
    O.check_valid(X, tri)
    O.check_conforming(X, tri, m.segments, area=m.domain.area, rel=1e-9)
    q = O.radius_ratio_reference(X, tri)
    assert q.min() >= q0.min() * (1 - 1e-12)
    assert np.all(q >= np.minimum(q0, KEEP) - 1e-12)
    assert q.mean() >= q0.mean() - MEAN_DROP - 1e-12
    assert np.all(_areas(X, tri) <= limit * (1 + 1e-12))
    if not kept:
        np.testing.assert_array_equal(X, X0)
    again = X0.copy()
    assert _run(again, tri0, m.segments, m.n_boundary, limit) == kept
    np.testing.assert_array_equal(again, X)


@pytest.mark.parametrize("seed", range(4))
def test_a_jittered_lattice_is_given_back(seed):
    """The interior of an equilateral lattice in a hexagon of 3 rings, each
    node moved by up to 0.15 of the spacing: with the hexagon fixed, the
    lattice is the one placement with every ratio 1, and joint moves of the
    worst patches must find it (single-node moves stop short where two
    neighbours are off together)."""
    X, tri, segments, n_b = _lattice_patch(3)
    lattice = X.copy()
    rng = np.random.default_rng(seed)
    X[n_b:] += rng.uniform(-0.15, 0.15, X[n_b:].shape)
    q0 = O.radius_ratio_reference(X, tri)
    assert q0.min() < 0.95
    assert _run(X, tri, segments, n_b, np.full(len(tri), np.inf), rounds=64) > 0
    assert O.radius_ratio_reference(X, tri).min() >= 1 - 1e-5
    np.testing.assert_allclose(X, lattice, atol=1e-2)  # rho is flat to second order there


@pytest.mark.parametrize("error", [ValueError, ZeroDivisionError])
def test_a_failing_solver_leaves_the_mesh_as_it_was(monkeypatch, error):
    """scipy raising inside a solve, or the ratio kernel dividing by zero at a
    flat trial point, refuses that move, never the mesh."""
    from bubblemesh import _minmax

    def broken(*args, **kwargs):
        raise error("solver failure")

    monkeypatch.setattr(_minmax, "minimize", broken)
    X, tri, segments, n_b = _lattice_patch(3)
    X[n_b:] += np.random.default_rng(0).uniform(-0.15, 0.15, X[n_b:].shape)
    X0 = X.copy()
    assert _run(X, tri, segments, n_b, np.full(len(tri), np.inf)) == 0
    np.testing.assert_array_equal(X, X0)


def _checked(X, tri, X0, q0, movable):
    """The invariants of every run: fixed nodes unmoved, valid, no triangle
    below min(its ratio, KEEP), the mean within its budget."""
    np.testing.assert_array_equal(X[~movable], X0[~movable])
    O.check_valid(X, tri)
    q = O.radius_ratio_reference(X, tri)
    assert np.all(q >= np.minimum(q0, KEEP) - 1e-12)
    assert q.mean() >= q0.mean() - MEAN_DROP - 1e-12
    return q


@pytest.mark.parametrize("seed", range(3))
def test_a_worst_triangle_of_fixed_nodes_does_not_stop_the_rest(seed):
    """A triangle whose three nodes are all fixed (as at a sharp corner, the
    wall nodes of its zigzag) cannot rise: a poor patch away from it must
    still be lifted, and it keeps its ratio bit for bit."""
    X, tri, segments, n_b = _lattice_patch(3)
    rng = np.random.default_rng(seed)
    X[n_b:] += rng.uniform(-0.2, 0.2, X[n_b:].shape)
    movable = np.arange(len(X)) >= n_b
    # a triangle of two hull nodes and an interior node, that node pushed out and fixed
    t0 = next(t for t in range(len(tri)) if (tri[t] < n_b).sum() == 2)
    w = int(tri[t0][tri[t0] >= n_b][0])
    hull = X[tri[t0][tri[t0] < n_b]]
    X[w] = hull.mean(axis=0) + 0.25 * (X[w] - hull.mean(axis=0))  # a flat triangle
    movable[w] = False
    v = n_b + int(np.argmax(np.hypot(*(X[n_b:] - X[w]).T)))  # and one far away pushed off
    X[v] += (0.4, 0.2)
    q0 = O.radius_ratio_reference(X, tri)
    O.check_valid(X, tri)
    assert int(np.argmin(q0)) == t0 and q0[t0] < 0.6
    X0 = X.copy()
    near = np.unique(tri[np.isin(tri, tri[t0]).any(axis=1)])  # t0's nodes and their ring
    far = np.flatnonzero(~np.isin(tri, near).any(axis=1))
    assert q0[far].min() < POOR  # past a held triangle only poor ones are lifted
    kept = minmax_patches(X, tri, movable, np.full(len(tri), np.inf), 64)
    q = _checked(X, tri, X0, q0, movable)
    assert kept > 0
    assert q[t0] == q0[t0]
    assert q[far].min() > q0[far].min() + 1e-6


def test_a_refused_patch_does_not_stop_the_rest(monkeypatch):
    """The worst patch refused (its solves fail): it is held, keeps its
    ratio, and the poor triangles elsewhere (below POOR) are lifted in turn."""
    X, tri, segments, n_b = _lattice_patch(4)
    X[n_b:] += np.random.default_rng(5).uniform(-0.3, 0.3, X[n_b:].shape)
    movable = np.arange(len(X)) >= n_b
    q0 = O.radius_ratio_reference(X, tri)
    O.check_valid(X, tri)
    worst = int(np.argmin(q0))
    solve, calls = _minmax._solve, []

    def refusing_the_first_patch(patch, start, cap):
        calls.append(cap)
        if len(calls) <= CAPS:
            return np.full((len(patch.free), 2), np.nan)
        return solve(patch, start, cap)

    monkeypatch.setattr(_minmax, "_solve", refusing_the_first_patch)
    X0 = X.copy()
    poor = np.flatnonzero(q0 < POOR)
    assert len(poor) > 3
    kept = minmax_patches(X, tri, movable, np.full(len(tri), np.inf), 64)
    q = _checked(X, tri, X0, q0, movable)
    assert len(calls) > CAPS and kept > 0
    assert q[worst] >= q0[worst]
    assert (q < POOR).sum() < len(poor)


def _pushed(rings, push, seed=0):
    """A lattice of ``rings`` rings with nodes at least 3 apart pushed by ``push``:
    that many separate patches, as a gear's teeth are."""
    X, tri, segments, n_b = _lattice_patch(rings)
    chosen = []
    for v in n_b + np.random.default_rng(seed).permutation(len(X) - n_b):
        if all(np.hypot(*(X[v] - X[c])) > 2.9 for c in chosen):
            chosen.append(v)
    X[chosen] += push * np.c_[np.cos(np.arange(len(chosen))), np.sin(np.arange(len(chosen)))]
    return X, tri, np.arange(len(X)) >= n_b, len(chosen)


@pytest.mark.parametrize("push, poor", [(0.1, False), (0.5, True)])
def test_past_the_first_rounds_only_patches_below_lift_below_are_lifted(push, poor):
    """Separate patches: all of them lifted when they are poorer than
    LIFT_BELOW, however many; above it only the first FIRST_ROUNDS."""
    X, tri, movable, patches = _pushed(10, push)
    q0 = O.radius_ratio_reference(X, tri)
    assert patches > FIRST_ROUNDS and (q0.min() < LIFT_BELOW) == poor
    X0 = X.copy()
    kept = minmax_patches(X, tri, movable, np.full(len(tri), np.inf), 256)
    q = _checked(X, tri, X0, q0, movable)
    if poor:
        assert kept >= patches and q.min() >= LIFT_BELOW
    else:
        assert kept == FIRST_ROUNDS and q.min() > q0.min()
