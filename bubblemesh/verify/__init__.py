"""Exact checks for any 2-D triangle mesh and its input boundary.

    from bubblemesh import verify
    report = verify.check(points, triangles, segments, boundary_points)
    report.ok, report.summary(), report.to_frame()
    verify.check_file("mesh.msh", boundary="domain.poly")

What is checked (each failure a :class:`Violation` with its kind and location):

- validity: indices, no repeated vertex, every triangle strictly
  counter-clockwise (exact), no duplicate triangle, every edge on at most two
  triangles in opposite directions, optional neighbour array, every node
  used, no two nodes at one position;
- conformity: each input boundary node is a mesh node bit for bit; each
  segment is a mesh edge or a chain of mesh edges along it (a split, listed in
  ``report.splits``); the mesh boundary edges are exactly the boundary
  segments' pieces, and interior constraints' pieces have triangles on both
  sides (``sides``; a .poly is read as Triangle reads it); no
  triangle centroid outside the domain, in a hole or on a loop (exact
  even-odd rule); the areas sum to the exact domain area; V - E + F equals
  the domain's Euler number (components minus holes with the nodes where
  loops touch pulled apart, less one per extra pass through such a node);
- constrained Delaunay emptiness by definition: no node strictly inside a
  triangle's circumcircle and visible from it across the segments (exact);
- quality: radius ratio 2r/R, angles, counts below 0.5 and 0.7;
- with node radii: the population criterion of paper §2.3, eq. 6.

Nothing here imports the mesher: the decisions are exact integer / Fraction
arithmetic on the floats' binary values, so a bug in bubblemesh's predicates
cannot hide behind the same bug in its checker.  Floats serve only as
filters with proved error bounds (see :mod:`bubblemesh.verify.exact`).
"""

from .check import check, check_file, main_check, read_mesh
from .report import KINDS, Report, Violation

__all__ = ["KINDS", "Report", "Violation", "check", "check_file", "main_check", "read_mesh"]
