"""Hard area bounds (Triangle's -a, global and regional) of bubblemesh.mesh.
Oracles: each triangle's area in exact Fractions, the region of each triangle
by shapely's point-in-polygon test of its centroid (not the mesher's flood
fill)."""

from dataclasses import replace
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from strategies import budget

import bubblemesh as bm
import bubblemesh.pipeline as pipeline
from bubblemesh._area_bound import bound_areas
from bubblemesh.errors import MeshingError

LEFT, RIGHT = (1.0, 4.0, 0.0, 0.02), (7.0, 4.0, 1.0, 0.5)
SQUARE = np.array([(0, 0), (4, 0), (8, 0), (8, 8), (4, 8), (0, 8)], float)
WALL = np.array([(4, 0), (4, 8)], float)


def exact_areas(mesh):
    P = [[Fraction(float(v)) for v in p] for p in mesh.points.tolist()]
    out = []
    for a, b, c in mesh.triangles.tolist():
        (ax, ay), (bx, by), (cx, cy) = P[a], P[b], P[c]
        out.append(((bx - ax) * (cy - ay) - (by - ay) * (cx - ax)) / 2)
    return out


def two_regions():
    return bm.Domain.from_pslg(loops=[SQUARE], constraints=[WALL], regions=[LEFT, RIGHT])


def region_of_centroids(mesh, boxes):
    """Index of the shapely box holding each centroid (-1: none)."""
    shapely = pytest.importorskip("shapely")
    c = mesh.points[mesh.triangles].mean(axis=1)
    out = np.full(len(c), -1)
    for r, box in enumerate(boxes):
        out[shapely.contains_xy(box, c[:, 0], c[:, 1])] = r
    return out


@pytest.fixture
def seen(monkeypatch):
    """The meshes bound_areas got in the next bm.mesh call, by their §2 record
    (on small domains bm.mesh makes several and returns one: look up its own
    with ``seen[mesh.generation]``; the finished record may carry one more
    warning)."""

    class Seen(list):
        def __getitem__(self, generation):
            quiet = replace(generation, warnings=())
            return next(m for m in self
                        if replace(m.generation, warnings=()) == quiet)

    seen = Seen()

    def spy(mesh, max_area=None, **kw):
        seen.append(mesh)
        return bound_areas(mesh, max_area, **kw)

    monkeypatch.setattr(pipeline, "bound_areas", spy)
    return seen


@pytest.mark.slow  # ~35 s each as plain Python (nojit); the bound is also checked below
@pytest.mark.parametrize("sized", [True, False])
def test_regional_max_area_is_a_hard_bound(sized):
    shapely = pytest.importorskip("shapely")
    d = two_regions()
    mesh = bm.mesh(d, size=d.region_size() if sized else None)
    region = region_of_centroids(mesh, [shapely.box(0, 0, 4, 8), shapely.box(4, 0, 8, 8)])
    assert (region >= 0).all()
    bound = [Fraction(LEFT[3]), Fraction(RIGHT[3])]
    areas = exact_areas(mesh)
    assert all(0 < a <= bound[r] for a, r in zip(areas, region.tolist()))
    assert sum(areas) == 64  # the bound is reached inside the same domain
    assert np.array_equal(mesh.region_ids(), region)  # the new nodes keep the regions apart


@pytest.mark.slow
def test_global_and_regional_bounds_combine_by_min():
    shapely = pytest.importorskip("shapely")
    d = two_regions()
    mesh = bm.mesh(d, size=d.region_size(), max_area=0.1)
    region = region_of_centroids(mesh, [shapely.box(0, 0, 4, 8), shapely.box(4, 0, 8, 8)])
    bound = [Fraction(LEFT[3]), Fraction(0.1)]
    assert all(a <= bound[r] for a, r in zip(exact_areas(mesh), region.tolist()))


@budget(6)
@given(st.integers(3, 9), st.integers(3, 9), st.sampled_from([0.05, 0.13, 0.4]))
def test_global_max_area_is_a_hard_bound(w, h, max_area):
    outer = np.array([(0, 0), (w, 0), (w, h), (0, h)], float)
    hole = np.array([(1, 1), (2, 1), (1.5, 2)], float)
    mesh = bm.mesh(bm.Domain.from_loops([outer, hole]), max_area=max_area)
    areas = exact_areas(mesh)
    assert max(areas) <= Fraction(max_area)
    assert sum(areas) == w * h - Fraction(1, 2)


@pytest.mark.slow
def test_the_bound_keeps_the_radius_ratio(monkeypatch):
    """Every mesh bm.mesh makes on the two regions (it makes several and
    keeps one) keeps its smallest radius ratio within 0.75 of itself through
    the area bound's insertions; one of them needs nodes."""
    pairs = []

    def spy(mesh, max_area=None, **kw):
        pairs.append((mesh, bound_areas(mesh, max_area, **kw)))
        return pairs[-1][1]

    monkeypatch.setattr(pipeline, "bound_areas", spy)
    d = two_regions()
    mesh = bm.mesh(d, size=d.region_size())
    grown = [(a, b) for a, b in pairs if len(b.points) > len(a.points)]
    assert grown  # nodes were needed
    for before, after in grown:
        assert after.quality().min() >= 0.75 * before.quality().min()
    assert mesh.optimization.min_ratio == mesh.quality().min()


def test_paper_mode_ignores_max_area():
    d = two_regions()
    free = replace(d, regions=None)
    for a, b in ((bm.generate(d), bm.generate(free)),
                 (bm.mesh(d, paper=True), bm.mesh(free, paper=True))):
        assert np.array_equal(a.points, b.points)
        assert np.array_equal(a.triangles, b.triangles)


@pytest.mark.heavy
def test_without_a_bound_the_mesh_is_returned_as_it_is():
    d = replace(two_regions(), regions=np.array([LEFT[:3] + (0.0,), RIGHT[:3] + (-1.0,)]))
    mesh = bm.mesh(d, size=1.0)
    assert bound_areas(mesh) is mesh
    loose = bm.mesh(d, size=1.0, max_area=100.0)
    assert bound_areas(loose, 100.0) is loose


def test_a_bound_not_reached_names_the_region():
    d = two_regions()
    coarse = bm.mesh(replace(d, regions=None))
    coarse = replace(coarse, domain=d)
    with pytest.raises(MeshingError, match=r"region 0 \(point \(1\.0, 4\.0\)\)"):
        bound_areas(coarse, rounds=1)


@pytest.mark.heavy
def test_split_segments_keep_the_boundary_first_and_their_markers(seen, monkeypatch):
    d = bm.Domain.from_pslg(loops=[SQUARE], constraints=[WALL], regions=[LEFT, RIGHT],
                            markers=[1, 5])
    monkeypatch.setattr(pipeline, "_with_regions", lambda domain, user: user)
    mesh = bm.mesh(d)  # the size field knows no region: the bound splits the segments
    n_b = mesh.n_boundary
    assert n_b > seen[mesh.generation].n_boundary
    P = mesh.points
    on = (P[:, 0] == 0) | (P[:, 0] == 8) | (P[:, 1] == 0) | (P[:, 1] == 8) | (P[:, 0] == 4)
    assert np.array_equal(np.flatnonzero(on), np.arange(n_b))  # exactly on them, first
    assert np.array_equal(mesh.domain.points, P[:n_b])
    assert np.array_equal(mesh.domain.segments, mesh.segments)
    assert mesh.domain.area == 64.0
    edges, marks = mesh.boundary_edges()
    wall = (P[edges][:, :, 0] == 4).all(axis=1)
    assert np.all(marks[wall] == 5) and np.all(marks[~wall] == 1)
    assert mesh.quality().min() > 0.1  # no sliver along the finely split wall
    before = seen[mesh.generation]
    first = before.n_boundary  # the old boundary nodes keep their places
    assert np.array_equal(mesh.radii[:first], before.radii[:first])


@pytest.mark.heavy
def test_the_bounded_mesh_conforms_to_the_input_boundary():
    verify = pytest.importorskip("bubblemesh.verify")
    outer = np.array([(0, 0), (5, 0), (5, 3), (0, 3)], float)
    hole = np.array([(1, 1), (2, 1), (1.5, 2)], float)
    d = bm.Domain.from_loops([outer, hole])
    mesh = bm.mesh(d, max_area=0.01)
    assert max(exact_areas(mesh)) <= Fraction(0.01)
    report = verify.check(mesh.points, mesh.triangles, d.segments, boundary_points=d.points,
                          delaunay=False)
    assert report.ok, report
