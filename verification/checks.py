"""Checks shared by the test modules: what every §2 or §3 mesh of a case must
satisfy, judged by the independent oracles of ``oracles``."""

from __future__ import annotations

import numpy as np
import oracles as O
import pytest


def check_mesh_geometry(case, mesh):
    """Everything a §2 or §3 mesh of ``case`` must satisfy ."""
    pts, tri = mesh.points, mesh.triangles
    seg = case.segments()
    n_b = len(case.points)
    # boundary nodes first, bitwise unmoved, in the user's order; segments
    # oriented domain-on-the-left as computed here from the loops
    assert mesh.n_boundary == n_b
    assert np.array_equal(pts[:n_b], case.points), "boundary nodes moved or reordered"
    got = sorted(map(tuple, np.asarray(mesh.segments).tolist()))
    assert got == sorted(map(tuple, seg.tolist())), "segments differ from the loops' oriented edges"
    assert pts.dtype == np.float64 and tri.dtype == np.int64 and mesh.neighbors.dtype == np.int64
    O.check_valid(pts, tri, mesh.neighbors)
    # conformity before Euler: its messages name the segment / triangle at fault
    O.check_conforming(pts, tri, seg)
    assert O.euler_ok(tri, case.n_holes), (
        f"V - E + F = {O.euler_characteristic(tri)}, expected {1 - case.n_holes}"
    )
    assert set(np.unique(tri).tolist()) == set(range(len(pts))), "a node is not in any triangle"
    O.check_constrained_delaunay(pts, tri, seg)
    # interior nodes strictly inside the domain (exact point in polygon)
    P, _ = O.exact_integers(pts)
    loops = O.split_outer(P, O.loops_from_segments(seg))
    outside = [i for i in range(n_b, len(pts)) if O.domain_location(P, loops, P[i]) <= 0]
    assert not outside, f"interior nodes not strictly inside the domain: {outside[:5]}"


def check_population(case, mesh):
    """Eq. 6 and the independent recomputation of eq. 1-4."""
    area = O.domain_area(case.points, O.loops_from_segments(case.segments()))
    assert mesh.domain_area == pytest.approx(area, rel=1e-12), "A_geo is not the domain area"
    # eq. 2 for the boundary nodes, from the boundary edge lengths
    ref = O.boundary_radii_reference(case.points, case.segments())
    r_b = np.array([ref[i] for i in range(len(case.points))])
    np.testing.assert_allclose(mesh.radii[: len(r_b)], r_b, rtol=1e-12)
    assert np.all(np.isfinite(mesh.radii)) and np.all(mesh.radii > 0)
    # eq. 3-4 summed over the returned mesh's elements
    recomputed = O.population_bubble_area(mesh.points, mesh.triangles, mesh.radii)
    assert mesh.bubble_area == pytest.approx(recomputed, rel=1e-9), (
        "stats bubble_area is not sum(pi r_e^2) of the returned mesh"
    )
    return area, recomputed
