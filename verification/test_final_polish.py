"""The last mean polish of bm.mesh (bubblemesh.pipeline._polished): the
triangles and the boundary nodes unchanged, the mesh valid and conforming,
its smallest radius ratio and its mean never lowered, no triangle taken below
KEEP and those below it left alone, the area bounds kept,
the same bits on a second run; and a mesh whose interior nodes were pushed off
their optimum gets its mean back up.

Oracles: verification/oracles.py (exact orientation and conformity, the radius
ratio from the classical formulas), numpy areas."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import oracles as O
import pytest
from hypothesis import given
from hypothesis import strategies as st
from test_pipeline import corner_domains
from test_relaxed_flips import _areas

import bubblemesh as bm
from bubblemesh import pipeline
from bubblemesh._area_bound import MARGIN


def _unpolished(monkeypatch, domain, **kwargs):
    """bm.mesh without its last polish (the input the polish gets)."""
    with monkeypatch.context() as patch:
        patch.setattr(pipeline, "FINAL_SWEEPS", 0)
        return bm.mesh(domain, **kwargs)


def _check_polish(before, after, max_area):
    np.testing.assert_array_equal(after.triangles, before.triangles)
    fixed = np.zeros(len(before.points), bool)
    fixed[: before.n_boundary] = True
    fixed[np.unique(before.segments)] = True
    np.testing.assert_array_equal(after.points[fixed], before.points[fixed])
    O.check_valid(after.points, after.triangles, after.neighbors)
    O.check_conforming(after.points, after.triangles, after.segments,
                       area=before.domain.area, rel=1e-9)
    q0 = O.radius_ratio_reference(before.points, before.triangles)
    q = O.radius_ratio_reference(after.points, after.triangles)
    assert q.min() >= q0.min() - 1e-12
    assert q.mean() >= q0.mean() - 1e-12
    floor = max(q0.min(), pipeline.KEEP)  # triangles below it stay, none falls below it
    below = q0 < floor
    np.testing.assert_array_equal(q[below], q0[below])
    assert np.all(q[~below] >= floor - 1e-9)
    if max_area is not None:
        assert np.all(_areas(after.points, after.triangles) <= max_area * (1 + 1e-12))
    return q0, q


@pytest.mark.slow
@given(corner_domains(max_holes=2), st.sampled_from([100, 300]), st.booleans())
def test_the_polish_moves_only_free_nodes_and_lowers_neither_minimum_nor_mean(
        loops, share, bounded):
    """Corner-only polygons with holes, bounded by max_area or sized: the
    triangles and the boundary nodes unchanged, valid, conforming, the
    minimum and the mean not lowered, the triangles below KEEP (or the
    minimum, the larger) unchanged and no other falling below it, every
    triangle within max_area (and within a bound set at the largest triangle
    before), the same bits twice."""
    domain = bm.Domain.from_loops(loops)
    max_area = domain.area / share if bounded else None
    kwargs = {"max_area": max_area} if bounded else {"size": np.sqrt(domain.area / share)}
    with pytest.MonkeyPatch.context() as monkeypatch:
        before = _unpolished(monkeypatch, domain, **kwargs)
    after = pipeline._polished(before, max_area)
    _check_polish(before, after, max_area)
    again = pipeline._polished(before, max_area)
    np.testing.assert_array_equal(again.points, after.points)
    # a bound at the largest triangle (plus the area bound's margin): none may grow past it
    tight = float(_areas(before.points, before.triangles).max()) * (1 + MARGIN)
    _check_polish(before, pipeline._polished(before, tight), tight)


def test_a_pushed_mesh_gets_its_mean_back(monkeypatch):
    """Interior nodes of a square's mesh pushed by a tenth of their spacing:
    the polish raises the mean radius ratio (it falls with the push), the
    minimum not lowered."""
    domain = bm.Domain.from_loops([np.array([(0, 0), (1, 0), (1, 1), (0, 1)], float)])
    mesh = _unpolished(monkeypatch, domain, size=0.1)
    X = np.array(mesh.points)
    free = np.arange(len(X)) >= mesh.n_boundary
    free[np.unique(mesh.segments)] = False
    rng = np.random.default_rng(5)
    X[free] += rng.uniform(-0.01, 0.01, (int(free.sum()), 2))
    pushed = replace(mesh, points=X)
    O.check_valid(pushed.points, pushed.triangles, pushed.neighbors)
    q0, q = _check_polish(pushed, pipeline._polished(pushed, None), None)
    mean_unpushed = O.radius_ratio_reference(mesh.points, mesh.triangles).mean()
    assert q0.mean() < mean_unpushed
    assert q.mean() > q0.mean() + 1e-3


# the sharpest corner is the slowest as plain Python; the jitted environments run it
@pytest.mark.parametrize("angle", [pytest.param(15.0, marks=pytest.mark.heavy), 20.0, 25.0])
def test_beside_a_sharp_corner_the_polish_takes_no_triangle_below_keep(monkeypatch, angle):
    """A circular sector with its arc given at 0.01 and no size: its tip
    triangle is far below KEEP.  The polish leaves it and every other
    triangle below KEEP as they are and takes none below KEEP (nor the
    minimum, nor the mean, down)."""
    from bubblemesh.studies.geometry import sector

    domain = bm.Domain.from_loops([sector(1.0, np.radians(angle), 0.01)])
    before = _unpolished(monkeypatch, domain)
    q0 = O.radius_ratio_reference(before.points, before.triangles)
    assert q0.min() < pipeline.KEEP  # the test's premise
    _check_polish(before, pipeline._polished(before, None), None)


@pytest.mark.heavy
def test_beside_a_narrow_gap_the_polish_leaves_the_poor_triangles_alone(monkeypatch):
    """A 2 x 1 rectangle with a hole of radius 0.47 (48 segments) in its
    middle, 0.03 off both long walls, at area / 150: triangles below KEEP
    with free nodes crowd the gaps.  They stay as they are, and the polish
    takes no other below KEEP (it would, moving their free nodes for their
    stars' means against their worst triangles)."""
    t = 2 * np.pi * np.arange(48) / 48
    hole = np.column_stack([1 + 0.47 * np.cos(t), 0.5 + 0.47 * np.sin(t)])[::-1]
    domain = bm.Domain.from_loops([np.array([(0, 0), (2, 0), (2, 1), (0, 1)], float), hole])
    before = _unpolished(monkeypatch, domain, max_area=domain.area / 150)
    q0 = O.radius_ratio_reference(before.points, before.triangles)
    free = np.arange(len(before.points)) >= before.n_boundary
    assert free[before.triangles[q0 < pipeline.KEEP]].any()  # the test's premise
    _check_polish(before, pipeline._polished(before, domain.area / 150), domain.area / 150)


def test_the_nodes_of_a_triangle_below_keep_stay_where_they_are(monkeypatch):
    """A free node of a square's mesh pulled halfway to a neighbour makes
    triangles below KEEP: the polish does not move it (moving it for its
    star's mean could take its other triangles below KEEP), and it leaves
    every triangle below KEEP as it is."""
    domain = bm.Domain.from_loops([np.array([(0, 0), (1, 0), (1, 1), (0, 1)], float)])
    mesh = _unpolished(monkeypatch, domain, size=0.1)
    X = np.array(mesh.points)
    free = np.arange(len(X)) >= mesh.n_boundary
    free[np.unique(mesh.segments)] = False
    t = next(t for t in range(len(mesh.triangles)) if free[mesh.triangles[t]].all())
    v, w = mesh.triangles[t, :2]
    X[v] += 0.5 * (X[w] - X[v])
    pulled = replace(mesh, points=X)
    O.check_valid(pulled.points, pulled.triangles, pulled.neighbors)
    q0 = O.radius_ratio_reference(X, mesh.triangles)
    assert (q0[(mesh.triangles == v).any(axis=1)] < pipeline.KEEP).any()  # the premise
    after = pipeline._polished(pulled, None)
    np.testing.assert_array_equal(after.points[v], X[v])
    _check_polish(pulled, after, None)


@pytest.mark.slow
def test_a_polish_that_breaks_an_area_bound_is_run_again_without_those_nodes(monkeypatch):
    """A corners-only gear of 10 teeth at area / 500, meshed without the
    removals before the polish: the first polish takes a triangle over
    max_area; run again with that triangle's nodes held, it keeps every
    bound and still raises the mean."""
    from bubblemesh.studies.geometry import gear

    domain = bm.Domain.from_loops([gear(10, 1.0, 1.2, 10.0)])
    max_area = domain.area / 500
    monkeypatch.setattr(pipeline, "PRUNE_ROUNDS", 0)  # they give a mesh the first polish fits
    before = _unpolished(monkeypatch, domain, max_area=max_area)
    with monkeypatch.context() as patch:
        patch.setattr(pipeline, "FINAL_TRIES", 1)
        assert pipeline._polished(before, max_area) is before  # the test's premise
    after = pipeline._polished(before, max_area)
    q0, q = _check_polish(before, after, max_area)
    assert q.mean() > q0.mean() + 1e-4
