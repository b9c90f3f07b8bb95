"""bubblemesh.optimize (paper §3) invariants, on random domains.

- node count unchanged; boundary nodes (bitwise) and their radii unchanged;
- interior nodes strictly inside the domain (exact point in polygon);
- the re-triangulation is valid, conforming and constrained Delaunay
  (the same oracles as for §2, see checks.check_mesh_geometry);
- on the paper's disk the mean radius ratio improves.
"""

from __future__ import annotations

import numpy as np
import oracles as O
import pytest
import strategies as S
from checks import check_mesh_geometry
from hypothesis import given, note
from hypothesis.errors import InvalidArgument

import bubblemesh as bm


def _note(text):
    try:
        note(text)
    except InvalidArgument:  # called from a plain (non-hypothesis) test
        pass


def _optimize_pair(case, **kw):
    dom = bm.Domain.from_loops(list(case.loops))
    before = bm.generate(dom)
    after = bm.optimize(before, **kw)
    _note(f"{len(after.points)} nodes, {after.stats.get('iterations')} iterations")
    return before, after


def check_optimization_invariants(case, before, after, amplification=1.7):
    n_b = before.n_boundary
    assert len(after.points) == len(before.points), "node count changed"
    assert after.n_boundary == n_b
    assert np.array_equal(after.points[:n_b], before.points[:n_b]), "a boundary node moved"
    # §3.1: every bubble is amplified, then the boundary ones stay fixed (eq. 9
    # adjusts only interior ones), so each returned boundary radius is exactly
    # its §2 radius times the amplification
    r0, r1 = before.radii[:n_b], after.radii[:n_b]
    assert np.array_equal(r1, r0 * amplification), "a boundary radius is not r_2 x amplification"
    assert np.array_equal(after.segments, before.segments)
    assert np.all(np.isfinite(after.points)) and np.all(np.isfinite(after.radii))
    assert np.all(after.radii > 0)
    check_mesh_geometry(case, after)


@given(S.domains(min_spacing=0.06))
def test_optimize_invariants(case):
    before, after = _optimize_pair(case)
    check_optimization_invariants(case, before, after)


@S.budget(40)
@given(S.domains(max_holes=2))
def test_optimize_invariants_with_short_runs(case):
    """A single iteration and a few iterations with a large step: the
    invariants hold after any number of iterations, not only at convergence."""
    dom = bm.Domain.from_loops(list(case.loops))
    before = bm.generate(dom)
    for kw in ({"max_iterations": 1}, {"max_iterations": 5, "alpha": 0.3}):
        after = bm.optimize(before, **kw)
        check_optimization_invariants(case, before, after)


@pytest.mark.peers
@S.budget(30)
@given(S.domains(max_holes=2))
def test_optimize_agrees_with_trimesh(case):
    pytest.importorskip("trimesh")
    _, after = _optimize_pair(case)
    area = O.domain_area(case.points, O.loops_from_segments(case.segments()))
    O.check_trimesh(after.points, after.triangles, case.segments(), area=area)


@S.budget(30)
@given(S.domains(max_holes=2))
def test_optimize_is_deterministic(case):
    dom = bm.Domain.from_loops(list(case.loops))
    mesh = bm.generate(dom)
    a, b = bm.optimize(mesh), bm.optimize(mesh)
    for name in ("points", "triangles", "neighbors", "radii"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name



@S.budget(20)
@given(S.domains(max_holes=2))
def test_verlet_lists_change_no_bit(case):
    """The Verlet lists only skip pairs that cannot overlap yet: the unpruned
    3-ring sums (skin=inf, the paper's §3.3 as written) must give the same bits,
    with lists so thin they are rebuilt almost every iteration (skin=0.02) or
    rarely (skin=1)."""
    mesh = bm.generate(bm.Domain.from_loops(list(case.loops)))
    reference = bm.optimize(mesh, skin=np.inf, max_iterations=60)
    for skin in (0.02, 1.0):
        pruned = bm.optimize(mesh, skin=skin, max_iterations=60)
        _note(f"skin={skin}: {pruned.stats['list_builds']} builds")
        for name in ("points", "radii", "triangles"):
            assert np.array_equal(getattr(pruned, name), getattr(reference, name)), (
                f"skin={skin} changed {name}")

@pytest.mark.parametrize("beta", [0.0, 0.7])
def test_move_step_is_eq8(beta):
    """The eq. 8 step of the move kernel against the formula evaluated pair by
    pair in plain Python: the bits of the documented one-division form
    ((r_i + r_j) (1 / l) - 1, summed in list order) and, within rounding, the
    paper's (r_i + r_j - l) / l.  Lists of odd and even length (the kernel
    pairs entries up) and two coincident nodes (no force between them); no
    boundary in reach, so every step is taken whole."""
    import math

    from bubblemesh._forces import move
    from bubblemesh.optimization import node_adjacency, ring_neighbors

    mesh = bm.generate(bm.Domain.from_loops(S.disk(40).loops))
    n, n_b = len(mesh.points), mesh.n_boundary
    ptr, idx = ring_neighbors(*node_adjacency(mesh.triangles, mesh.neighbors, n), n, 3)
    X = np.array(mesh.points)
    X[n_b + 1] = X[idx[ptr[n_b + 1]]]  # coincident with its first listed neighbour
    R = np.asarray(mesh.radii) * 1.7
    start, count = ptr[:-1].copy(), np.diff(ptr)
    assert len(np.unique(count[n_b:] % 2)) == 2, "want lists of odd and even length"
    rng = np.random.default_rng(1)
    V = rng.normal(scale=1e-3, size=X.shape)
    Xn, V_kernel = np.empty_like(X), V.copy()
    home = np.zeros(n, np.int64)
    move(X, R, Xn, home, start, count, idx.astype(np.int32), np.zeros(len(idx)), False, n_b,
         0.2, X, mesh.triangles, mesh.neighbors, np.full(n, np.inf), X.copy(), R.copy(), 0.3,
         V_kernel, beta)
    for i in range(n_b, n):
        fx = fy = gx = gy = 0.0
        for j in idx[ptr[i]:ptr[i + 1]]:
            dx, dy = float(X[i, 0] - X[j, 0]), float(X[i, 1] - X[j, 1])
            length = math.sqrt(dx * dx + dy * dy)
            w = 1.0 / length if length > 0.0 else 0.0
            scale = max((R[i] + R[j]) * w - 1.0, 0.0)
            fx, fy = fx + scale * dx, fy + scale * dy
            paper = max((R[i] + R[j] - length) / length, 0.0) if length > 0.0 else 0.0
            gx, gy = gx + paper * dx, gy + paper * dy
        vx, vy = (beta * V[i, 0], beta * V[i, 1]) if beta > 0.0 else (0.0, 0.0)
        expected = (X[i, 0] + 0.2 * fx + (0.2 / 0.2) * vx, X[i, 1] + 0.2 * fy + (0.2 / 0.2) * vy)
        assert (Xn[i, 0], Xn[i, 1]) == expected, f"node {i}"
        assert np.allclose(Xn[i], (X[i, 0] + 0.2 * gx + vx, X[i, 1] + 0.2 * gy + vy),
                           rtol=0, atol=1e-12), f"node {i}"


def test_optimize_does_not_mutate_its_input():
    case = S.square_with_hole()
    mesh = bm.generate(bm.Domain.from_loops(list(case.loops)))
    copies = {k: np.array(getattr(mesh, k), copy=True) for k in ("points", "triangles", "radii")}
    bm.optimize(mesh)
    for k, v in copies.items():
        assert np.array_equal(getattr(mesh, k), v), f"optimize changed mesh.{k}"


@pytest.mark.parametrize("n", [24, 48, 96])
def test_optimize_improves_mean_radius_ratio_on_disk(n):
    """Paper Fig. 3: on a disk the optimised mesh has a higher mean radius
    ratio (reference 2r/R, not the library's eq. 10) than the §2 mesh."""
    case = S.disk(n)
    before, after = _optimize_pair(case)
    check_optimization_invariants(case, before, after)
    q0 = O.radius_ratio_reference(before.points, before.triangles).mean()
    q1 = O.radius_ratio_reference(after.points, after.triangles).mean()
    assert q1 > q0, f"mean radius ratio {q0:.4f} -> {q1:.4f}"


def test_optimize_square_with_hole():
    case = S.square_with_hole()
    before, after = _optimize_pair(case)
    check_optimization_invariants(case, before, after)


@pytest.mark.parametrize(
    "option, value",
    [("amplification", 0.0), ("alpha", -0.1), ("skin", 0.0), ("rings", 0), ("rings", 1.5),
     ("max_iterations", -1), ("tol", -1e-3),
     # beyond the accepted ranges, where nodes can meet or meshes degenerate
     ("alpha", 0.5), ("alpha", 1e300), ("alpha", float("inf")), ("amplification", 3.0),
     ("amplification", float("inf")), ("rings", 7),
     # not numbers, not finite
     ("alpha", float("nan")), ("tol", float("nan")), ("max_iterations", float("inf")),
     ("max_iterations", 2.5), ("alpha", "0.1"), ("rings", None), ("amplification", 1j)],
)
def test_optimize_rejects_meaningless_parameters(option, value):
    mesh = bm.generate(bm.Domain.from_loops(S.disk(24).loops))
    with pytest.raises(ValueError, match=f"optimize: {option} must be"):
        bm.optimize(mesh, **{option: value})


def test_generate_rejects_negative_max_insertions():
    with pytest.raises(ValueError, match="max_insertions must be an integer >= 0"):
        bm.generate(bm.Domain.from_loops(S.disk(24).loops), max_insertions=-1)


@pytest.mark.parametrize("per_node, sides", [(48, 160), (2, 160), (48, 5)])
def test_ring_neighbors_are_graph_balls(per_node, sides):
    """§3.3's nearby nodes: node i's list holds exactly the nodes at 1..3 edges
    from i (graph distances from scipy's csgraph, on edges taken from the
    triangles), each once, nearer rings first.  ~2,400 nodes, so the work is
    split into blocks; per_node=2 forces the overflow restart; a pentagon's
    few nodes all lie within 3 rings of each other."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import shortest_path

    from bubblemesh.optimization import node_adjacency, ring_neighbors

    mesh = bm.generate(bm.Domain.from_loops(S.disk(sides).loops))
    n = len(mesh.points)
    edges = np.concatenate([mesh.triangles[:, [0, 1]], mesh.triangles[:, [1, 2]],
                            mesh.triangles[:, [2, 0]]])
    graph = coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n, n))
    hops = shortest_path(graph.tocsr(), directed=False, unweighted=True)
    ptr, idx = ring_neighbors(*node_adjacency(mesh.triangles, mesh.neighbors, n), n, 3,
                              per_node=per_node)
    assert n > 2048 or sides < 10
    for i in range(n):
        ring = idx[ptr[i]:ptr[i + 1]]
        d = hops[i, ring]
        assert len(np.unique(ring)) == len(ring), f"node {i}: a neighbour twice"
        assert np.all((d >= 1) & (d <= 3)), f"node {i}: a neighbour {d.max()} edges away"
        assert np.all(np.diff(d) >= 0), f"node {i}: rings out of order"
        assert len(ring) == np.count_nonzero((hops[i] >= 1) & (hops[i] <= 3)), (
            f"node {i}: missing neighbours")


@pytest.mark.parametrize("reach", [0.01, 0.05, 10.0])
def test_boundary_clearance_is_the_nearest_midpoint_bound(reach):
    """The walk-free radius of each node (a grid search for the nearest segment
    midpoint, stopped at a horizon) against every midpoint in numpy: half of
    (min(nearest midpoint distance, L / 2 + 2 reach) - L / 2), at least 0,
    bit for bit; and a true lower bound on the distance to every segment."""
    from bubblemesh._inside import boundary_clearance

    mesh = bm.generate(bm.Domain.from_loops(S.square_with_hole().loops))
    P, seg, n_b = np.asarray(mesh.points), np.asarray(mesh.segments), mesh.n_boundary
    got = boundary_clearance(P, seg, n_b, reach)
    ends = P[seg]
    mid = ends.mean(axis=1)
    longest = float(np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1).max())
    dist = np.sqrt(((P[n_b:, None, :] - mid[None, :, :]) ** 2).sum(axis=-1)).min(axis=1)
    nearest = np.minimum(dist, 0.5 * longest + 2.0 * reach)
    assert np.array_equal(got[:n_b], np.zeros(n_b))
    assert np.array_equal(got[n_b:], 0.5 * np.maximum(nearest - 0.5 * longest, 0.0))
    a, b = ends[:, 0], ends[:, 1]
    t = np.clip((((P[n_b:, None] - a) * (b - a)).sum(-1)) / ((b - a) ** 2).sum(-1), 0, 1)
    to_segment = np.linalg.norm(P[n_b:, None] - (a + t[..., None] * (b - a)), axis=-1).min(1)
    assert np.all(2 * got[n_b:] <= to_segment + 1e-12)
