"""check(), check_file() and the command-line entry main_check()."""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

from bubblemesh.errors import GeometryError

from .conform import (
    check_area,
    check_boundary_edges,
    check_inside,
    map_boundary_nodes,
    segment_chains,
)
from .delaunay import check_delaunay
from .domain import Boundary, pslg_sides
from .exact import ExactPoints
from .measures import population_bubble_area, quality_summary, triangle_areas
from .report import Report
from .topology import as_points, as_triangles, check_validity, euler_characteristic


def check(points, triangles, segments=None, boundary_points=None, radii=None, *,
          holes=None, sides=None, neighbors=None, oriented=False, split_tol=1e-12,
          allow_splits=True, delaunay=True, area_rel=1e-12, limit=1000) -> Report:
    """Check any 2-D triangle mesh against its input boundary; return a Report.

    points (N, 2), or (N, 3) with z = 0; triangles (M, 3) node ids.
    segments (K, 2): the input boundary, as closed loops of node pairs into
    ``boundary_points`` (B, 2) if given, else into ``points``; loops may
    touch at nodes, not cross.  Without
    segments the mesh's own boundary edges are the boundary (then
    conformity only checks that they form loops and the Euler count).
    radii (N,): node bubble radii; adds the population criterion (eq. 6).
    holes: hole points (as in a .poly file), checked against the even-odd rule.
    sides (K,): on how many sides of each segment the domain lies: 1 a
    boundary segment (the default for all), 2 an interior constraint (a
    chain of mesh edges with triangles on both sides, an obstacle to the
    Delaunay test, not part of the loops), 0 one in a hole or outside (not
    checked); or "pslg" for Triangle's reading of the segments and hole
    points (:func:`bubblemesh.verify.domain.pslg_sides`).
    neighbors (M, 3): an adjacency array to check (neighbors[t, i] across the
    edge opposite vertex i, -1 on the boundary).  oriented: segments run with
    the domain on their left, and the mesh must agree.  split_tol: a mesh node
    splits a segment if within split_tol * length of it, or a few ulps of its
    end points' coordinates where that is more (map coordinates far from the
    origin: :mod:`bubblemesh.verify.conform`; 0: exactly on it).
    allow_splits=False reports every split segment.  delaunay=False skips the
    constrained Delaunay test.  limit: violations kept per kind.
    """
    clock = time.perf_counter()
    pts = as_points(points)
    tri = as_triangles(triangles)
    n = len(pts)
    report = Report(limit=limit)
    report.facts.update(nodes=n, triangles=len(tri))
    bpts = None if boundary_points is None else as_points(boundary_points)
    E = ExactPoints(pts if bpts is None else np.vstack([pts, bpts]))
    H, positive = check_validity(E, tri, report, neighbors, n_nodes=n)
    report.checks["validity"] = "done" if H is not None else "stopped: bad indices or empty"
    if H is None:
        return report
    report.facts["edges"] = len(H.keys)
    domain, obstacles = _conformity(E, H, tri, report, segments, bpts, holes, sides, oriented,
                                    split_tol, allow_splits, area_rel, n)
    if delaunay:
        facts = check_delaunay(E, H, positive, obstacles, report)
        note = f"; {facts['untested']} pairs untested past the limit" if facts["untested"] else ""
        report.checks["delaunay"] = (
            f"constrained by {len(obstacles)} segment edges, exact; "
            f"{facts['hidden_inside']} in-circle nodes hidden by segments{note}"
        )
    else:
        report.checks["delaunay"] = "skipped (delaunay=False)"
    good = tri[positive] if positive.any() else tri
    report.quality = quality_summary(pts, good)
    if radii is not None:
        _population(pts, tri, radii, domain, report)
    report.facts["seconds"] = round(time.perf_counter() - clock, 3)
    return report


def _sides(sides, seg, bpts, holes):
    """The (K,) sides array of :func:`check` (all 1 by default)."""
    if sides is None:
        return np.ones(len(seg), np.int64)
    if isinstance(sides, str):
        if sides != "pslg":
            raise ValueError(f"sides must be an array or 'pslg', got {sides!r}")
        return pslg_sides(bpts, seg, holes)
    out = np.asarray(sides)
    if out.shape != (len(seg),) or not np.isin(out, (0, 1, 2)).all():
        raise ValueError(f"sides must hold 0, 1 or 2 for each of the {len(seg)} segments")
    return out.astype(np.int64)


def _meshed_nodes(E, domain, bpts, seg, side, n):
    """The input nodes a mesh must hold: those of the meshed segments, and
    those on no segment (free points) not outside the domain (exact)."""
    needed = np.zeros(len(bpts), bool)
    needed[seg[side > 0].ravel()] = True
    free = np.setdiff1d(np.arange(len(bpts)), seg.ravel())
    if len(free):
        where = domain.locate(bpts[free], lambda k: (*E.P[n + int(free[k])], 1), 0.0,
                              exact=True)
        needed[free[where >= 0]] = True
    return needed


def _conformity(E, H, tri, report, segments, bpts, holes, sides, oriented, split_tol,
                allow_splits, area_rel, n):
    """Boundary loops, node mapping, segment chains, boundary edges, inside, area, Euler."""
    if segments is None:
        b = H.boundary()
        own = np.column_stack([H.u[b], H.v[b]])
        try:
            domain = Boundary(E, own, oriented=True)
        except GeometryError as error:
            report.add("non_manifold_vertex", f"the mesh boundary is not simple loops: {error}")
            report.checks["conformity"] = "skipped: the mesh boundary is not simple loops"
            return None, own
        seg_mesh, source = own, "the mesh's own boundary edges"
    else:
        seg = np.asarray(segments)
        if seg.ndim != 2 or seg.shape[1] != 2 or (seg.size and not np.issubdtype(seg.dtype,
                                                                                 np.integer)):
            raise ValueError(f"segments must be an (K, 2) integer array, got {seg.dtype} "
                             f"{seg.shape}")
        seg = seg.astype(np.int64)
        top = n if bpts is None else len(bpts)
        if seg.size and (seg.min() < 0 or seg.max() >= top):
            k = int(np.argmax(((seg < 0) | (seg >= top)).any(axis=1)))
            raise GeometryError(f"segment {k} {seg[k].tolist()} names a node outside [0, {top})")
        side = _sides(sides, seg, E.points[:n] if bpts is None else bpts, holes)
        outer, inner = np.flatnonzero(side == 1), np.flatnonzero(side == 2)
        if bpts is None:
            domain, seg_mesh = Boundary(E, seg[outer], holes, oriented), seg
            source = f"{len(seg)} input segments over the mesh nodes"
        else:
            domain = Boundary(E, seg[outer] + n, holes, oriented, first=n)
            needed = _meshed_nodes(E, domain, bpts, seg, side, n)
            seg_mesh = map_boundary_nodes(E.points[:n], bpts, report, needed)[seg]
            source = f"{len(seg)} input segments over {len(bpts)} boundary nodes"
        if len(inner):
            source += f", {len(inner)} of them interior constraints"
        report.facts.update(constraints=len(inner), segments_unmeshed=int((side == 0).sum()))
    if segments is None:
        outer, inner = np.arange(len(seg_mesh)), np.zeros(0, np.int64)
    sub, owner = segment_chains(E, H, seg_mesh[outer], report, split_tol, allow_splits, outer)
    pieces, whose = (segment_chains(E, H, seg_mesh[inner], report, split_tol, allow_splits,
                                    inner) if len(inner) else (sub[:0], owner[:0]))
    check_boundary_edges(E, H, sub, owner, report, oriented or segments is None, pieces, whose)
    obstacles = np.vstack([sub, pieces])
    check_inside(E, tri, domain, report)
    total, expected, _ = check_area(E, tri, domain, report, area_rel)
    chi = euler_characteristic(tri, H)
    try:
        want = domain.euler()
    except GeometryError as error:  # the mesh's own boundary edges overlap: its fault
        if segments is not None:
            raise
        report.add("non_manifold_vertex", f"the mesh boundary is not simple loops: {error}")
        want = chi
    if chi != want:
        report.add("euler", f"V - E + F = {chi}, the domain's components - holes = {want}")
    report.facts.update(loops=len(domain.loops), euler=chi, area=total, domain_area=expected)
    report.checks["conformity"] = f"done against {source}"
    return domain, obstacles


def _population(pts, tri, radii, domain, report):
    """Eq. 6: the element bubbles' areas (eq. 3-4) sum to at least A_geo."""
    r = np.asarray(radii, dtype=np.float64).ravel()
    if len(r) != len(pts):
        raise ValueError(f"radii has {len(r)} values for {len(pts)} nodes")
    bubbles = population_bubble_area(pts, tri, r)
    if domain is not None:
        a_geo = domain.area()
    else:
        a_geo = math.fsum(np.abs(triangle_areas(pts, tri)).tolist())
    report.facts.update(bubble_area=bubbles)
    if not bubbles >= a_geo:
        report.add("population", f"sum of element bubble areas {bubbles!r} < domain area "
                   f"{a_geo!r} (eq. 6)")
    report.checks["population"] = f"sum A_e / A_geo = {bubbles / a_geo:.4f}"


def read_mesh(path):
    """(points, triangles) of every 'triangle' block of a meshio-readable file.

    A missing or unreadable file is a ValueError (``io.MeshFileError``)."""
    from bubblemesh.io import read_meshio

    mesh = read_meshio(path)
    blocks = [c.data for c in mesh.cells if c.type == "triangle"]
    tri = np.concatenate(blocks) if blocks else np.zeros((0, 3), np.int64)
    return np.asarray(mesh.points, dtype=np.float64), tri.astype(np.int64)


def check_file(mesh_path, boundary=None, **options) -> Report:
    """Check a mesh file (any meshio format; 3-D points need z = 0).

    ``boundary``: a Triangle .poly path (its vertices, segments and holes are
    the input, read as Triangle reads them: ``sides="pslg"``), a tuple
    (boundary_points, segments[, holes]), or None (the mesh's own boundary
    edges).  Other options go to :func:`check`."""
    points, triangles = read_mesh(mesh_path)
    if boundary is None:
        return check(points, triangles, **options)
    if isinstance(boundary, (str, Path)):
        from bubblemesh.io import read_poly

        poly = read_poly(boundary)
        options.setdefault("sides", "pslg")
        return check(points, triangles, poly.segments, poly.vertices, holes=poly.holes,
                     **options)
    bpts, seg, *rest = boundary
    return check(points, triangles, seg, bpts, holes=rest[0] if rest else None, **options)


CHECK_DESCRIPTION = ("Check a triangle mesh exactly: validity, conformity to a boundary, "
                     "constrained Delaunay, boundary nodes unmoved, quality.")


def add_check_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``bubblemesh check``."""
    parser.add_argument("mesh", help="mesh file readable by meshio (.msh, .vtu, .xdmf, ...)")
    parser.add_argument("--boundary", help="Triangle .poly file with the input boundary")
    parser.add_argument("--limit", type=int, default=1000, help="violations kept per kind")
    parser.add_argument("--split-tol", type=float, default=1e-12,
                        help="relative distance for a node to split a segment (0: exact)")
    parser.add_argument("--no-delaunay", action="store_true", help="skip the Delaunay test")
    parser.add_argument("--csv", help="write one row per violation to this CSV file")


def run_check(args: argparse.Namespace) -> int:
    """Check, print the summary (and the CSV); 0 when clean, 1 when anything is
    violated.  An unreadable input raises (OSError, ValueError, TypeError)."""
    report = check_file(args.mesh, args.boundary, limit=args.limit,
                        split_tol=args.split_tol, delaunay=not args.no_delaunay)
    print(report.summary())
    if args.csv:
        report.to_frame().to_csv(args.csv, index=False)
    return 0 if report.ok else 1


def main_check(argv=None) -> int:
    """``bubblemesh check MESHFILE [--boundary B.poly] [--limit N] [--split-tol T]
    [--no-delaunay] [--csv OUT]``: print the summary; exit status 0 when
    clean, 1 when anything is violated, 2 when the input cannot be read."""
    parser = argparse.ArgumentParser(prog="bubblemesh check", description=CHECK_DESCRIPTION)
    add_check_arguments(parser)
    args = parser.parse_args(argv)
    try:
        return run_check(args)
    except (OSError, ValueError, TypeError, ImportError) as error:
        print(f"bubblemesh check: cannot read the input: {error}", file=sys.stderr)
        return 2
