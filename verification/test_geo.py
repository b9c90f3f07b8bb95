"""Domains from GeoDataFrames: each feature a region, shared edges interior
constraints, holes kept.  Oracles: shapely's containment of each triangle's
centroid in the features, exact Fraction areas, and the nodes lying exactly
on each shared edge (axis-parallel, so equality is exact)."""

from fractions import Fraction

import numpy as np
import pytest
from test_area_bound import exact_areas, region_of_centroids

import bubblemesh as bm
from bubblemesh.errors import GeometryError

gpd = pytest.importorskip("geopandas", reason="Domain.from_geopandas is tested with geopandas")
shapely = pytest.importorskip("shapely")

LEFT, RIGHT = shapely.box(0, 0, 4, 4), shapely.box(4, 0, 8, 4)
HOLED = shapely.Polygon([(0, 4), (8, 4), (8, 8), (0, 8)], [[(2, 5), (6, 5), (6, 7), (2, 7)]])


def frame():
    return gpd.GeoDataFrame({"material": [10, 20, 30], "max_area": [0.05, np.nan, 0.2]},
                            geometry=[LEFT, RIGHT, HOLED])


def edges_of(triangles):
    e = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    return set(map(tuple, np.sort(e, axis=1).tolist()))


def assert_chain(mesh, axis, level, lo, hi):
    """The nodes with coordinate ``axis`` == level and the other in [lo, hi],
    in order, are joined pairwise by mesh edges (the segment is a chain)."""
    P = mesh.points
    other = 1 - axis
    on = np.flatnonzero((P[:, axis] == level) & (P[:, other] >= lo) & (P[:, other] <= hi))
    on = on[np.argsort(P[on, other])]
    assert P[on[0], other] == lo and P[on[-1], other] == hi
    edges = edges_of(mesh.triangles)
    assert all(tuple(sorted((int(u), int(v)))) in edges for u, v in zip(on[:-1], on[1:]))
    return on


@pytest.mark.parametrize("paper", [False, True])
def test_features_are_regions_with_interfaces_and_holes(paper):
    d = bm.Domain.from_geopandas(frame(), region="material", max_area="max_area")
    union = shapely.union_all([LEFT, RIGHT, HOLED])
    assert d.area == union.area == 56.0
    mesh = bm.mesh(d, paper=True) if paper else bm.mesh(d)
    owner = region_of_centroids(mesh, [LEFT, RIGHT, HOLED])
    assert (owner >= 0).all()  # every triangle in a feature, none in the hole
    assert np.array_equal(mesh.region_attributes(), np.array([10.0, 20.0, 30.0])[owner])
    assert sum(exact_areas(mesh)) == 56
    # the shared edges: x = 4 between LEFT and RIGHT, y = 4 under HOLED (LEFT's and
    # RIGHT's top sides meet HOLED's one bottom side, split at (4, 4))
    vertical = assert_chain(mesh, 0, 4.0, 0.0, 4.0)
    horizontal = assert_chain(mesh, 1, 4.0, 0.0, 8.0)
    edges, marks = mesh.boundary_edges()
    shared = {tuple(sorted(e)) for on in (vertical, horizontal)
              for e in zip(on[:-1].tolist(), on[1:].tolist())}
    is_shared = np.array([tuple(sorted(e)) in shared for e in edges.tolist()])
    assert np.all(marks[is_shared] == 2) and np.all(marks[~is_shared] == 1)
    if not paper:  # the max_area column is a hard bound, NaN none
        bound = {0: Fraction(0.05), 2: Fraction(0.2)}
        assert all(a <= bound[k] for a, k in zip(exact_areas(mesh), owner.tolist())
                   if k in bound)


def test_a_geoseries_takes_row_positions_and_multipolygons():
    twin = shapely.MultiPolygon([shapely.box(0, 0, 1, 1), shapely.box(2, 0, 3, 1)])
    series = gpd.GeoSeries([twin, shapely.box(1, 0, 2, 1)])
    d = bm.Domain.from_geopandas(series)
    mesh = bm.mesh(d, size=0.25)
    owner = region_of_centroids(mesh, list(series))
    assert np.array_equal(mesh.region_attributes(), owner.astype(float))
    assert sorted(set(owner.tolist())) == [0, 1]
    assert_chain(mesh, 0, 1.0, 0.0, 1.0)
    assert_chain(mesh, 0, 2.0, 0.0, 1.0)


def test_a_gap_between_features_stays_a_hole():
    ring = [shapely.box(0, 0, 3, 1), shapely.box(0, 2, 3, 3), shapely.box(0, 1, 1, 2),
            shapely.box(2, 1, 3, 2)]  # four features around an empty square
    d = bm.Domain.from_geopandas(gpd.GeoSeries(ring))
    assert d.area == 8.0
    mesh = bm.mesh(d, size=0.3)
    c = mesh.points[mesh.triangles].mean(axis=1)
    assert not np.any((c[:, 0] > 1) & (c[:, 0] < 2) & (c[:, 1] > 1) & (c[:, 1] < 2))
    assert sum(exact_areas(mesh)) == 8


def test_bad_features_are_named():
    with pytest.raises(TypeError, match="feature 1"):
        bm.Domain.from_geopandas(gpd.GeoSeries([LEFT, shapely.LineString([(0, 0), (1, 1)])]))
    with pytest.raises(GeometryError, match="cross"):
        bm.Domain.from_geopandas(gpd.GeoSeries([LEFT, shapely.box(2, 2, 6, 6)]))
    with pytest.raises(GeometryError, match="no features"):
        bm.Domain.from_geopandas(gpd.GeoSeries([], dtype="geometry"))
