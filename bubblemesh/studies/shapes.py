"""A sweep of inputs a user would bring, given by their corners (and arcs as
polygons), each meshed by bm.mesh at several sizes against Gmsh
Frontal-Delaunay and Triangle -pq30 at matched counts.

    python -m bubblemesh.studies.shapes [--sizes 50 100 200 1000] [--out DIR]
    python -m bubblemesh.studies.shapes --set rectangles --sizes 60 150 400 1200
    python -m bubblemesh.studies.shapes --set triangle-examples --sizes 100 300 1000 3000
    python -m bubblemesh.studies.shapes --set planar-graphs --sizes 30 100 1000

``--set rectangles`` sweeps long rectangles (channels 4 to 30 times longer
than wide) instead of the shapes; ``--set triangle-examples`` the ``.poly``
files that ship with the ``triangle`` package (Triangle's own examples:
holes, interior constraints, free points, a lake with islands), read by
:meth:`bubblemesh.Domain.from_poly`; ``--set planar-graphs`` planar graphs
of several materials (:func:`planar_graphs`, by
:meth:`bubblemesh.Domain.from_pslg`).

Every shape is meshed with max_area = area / k for each k of ``--sizes``; the
rows are :func:`bubblemesh.studies.quality.case_rows` (Gmsh on bm's refined
boundary with bm's size field).  Prints every pair where bm misses a target
(mean or min below Gmsh's, an element below 0.7 away from a too-sharp input
corner, N off the predicted count by more than 5%) and writes
shapes_vs_gmsh.csv to ``--out``.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

import bubblemesh as bm
from bubblemesh.studies import geometry
from bubblemesh.studies.quality import case_rows, print_case, sweep_table

SIZES = (50, 100, 200, 1000)


def _regular(n, radius=1.0, center=(0.0, 0.0), phase=0.0):
    """A regular n-gon: n nodes on a circle about the origin by default."""
    return geometry.circle(center, radius, n, phase)


def _hole(loop):
    return geometry.clockwise(np.asarray(loop, dtype=np.float64))


def _comb(teeth, width, height, base):
    """A comb: a ``base``-high bar with ``teeth`` teeth ``width`` wide and
    ``height`` high, gaps as wide as the teeth, counter-clockwise."""
    right = (2 * teeth + 1) * width
    top = [q for k in reversed(range(teeth))
           for q in (((2 * k + 2) * width, base), ((2 * k + 2) * width, base + height),
                     ((2 * k + 1) * width, base + height), ((2 * k + 1) * width, base))]
    return np.array([(0, 0), (right, 0), (right, base)] + top + [(0, base)], float)


def _star(points, inner):
    a = math.pi / 2 + math.pi * np.arange(2 * points) / points
    r = np.where(np.arange(2 * points) % 2 == 0, 1.0, inner)
    return np.column_stack([r * np.cos(a), r * np.sin(a)])


def shapes():
    """(name, loops): corner-only polygons and polygonal arcs, outer loop
    first, holes after."""
    square = [(0, 0), (1, 0), (1, 1), (0, 1)]
    yield "rectangle 5x2", [np.array([(0, 0), (5, 0), (5, 2), (0, 2)], float)]
    yield "strip 10x0.5", [np.array([(0, 0), (10, 0), (10, 0.5), (0, 0.5)], float)]
    yield "triangle", [_regular(3, phase=math.pi / 2)]
    yield "right triangle 30-60", [np.array([(0, 0), (math.sqrt(3), 0), (0, 1)])]
    yield "trapezoid", [np.array([(0, 0), (4, 0), (3, 1), (1, 1)], float)]
    yield "hexagon", [_regular(6)]
    yield "hexagon, hexagonal hole", [_regular(6), _hole(_regular(6, 0.4, phase=0.3))]
    yield "square, square hole", [np.array(square, float),
                                  _hole([(.4, .4), (.6, .4), (.6, .6), (.4, .6)])]
    yield "L-shape", [np.array([(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)], float)]
    yield "U-shape", [np.array([(0, 0), (3, 0), (3, 3), (2, 3), (2, 1), (1, 1), (1, 3), (0, 3)],
                               float)]
    yield "T-shape", [np.array([(1, 0), (2, 0), (2, 2), (3, 2), (3, 3), (0, 3), (0, 2), (1, 2)],
                               float)]
    yield "plus", [np.array([(1, 0), (2, 0), (2, 1), (3, 1), (3, 2), (2, 2), (2, 3), (1, 3),
                             (1, 2), (0, 2), (0, 1), (1, 1)], float)]
    yield "comb, 6 teeth", [_comb(6, 0.4, 2.0, 0.5)]
    yield "star, 5 points", [_star(5, 0.5)]
    yield "disk, 64 nodes", [_regular(64)]
    yield "thin ring", [_regular(64), _hole(_regular(64, 0.9))]
    yield "hole near a wall", [np.array(square, float),
                               _hole(_regular(48, 0.2, center=(0.5, 0.23)))]
    yield "plate, three holes", [np.array([(0, 0), (4, 0), (4, 1.5), (0, 1.5)], float)]\
        + [_hole(_regular(32, 0.3, center=(x, 0.75))) for x in (1.0, 2.0, 3.0)]
    yield "sharp airfoil in channel", [np.array([(-2, -1.5), (4, -1.5), (4, 1.5), (-2, 1.5)],
                                                float), geometry.naca_airfoil(0.12, 60, sharp=True)]
    yield "gear, corners only", [geometry.gear(12, 1.0, 1.2, 10.0)]


def rectangles():
    """(name, loops): rectangles 4 to 30 times longer than wide, the
    channels of :mod:`bubblemesh._channel`."""
    for length, width in ((4, 1), (6, 1), (8, 1), (20, 1), (10, 0.3), (30, 1), (5, 0.7)):
        yield f"rectangle {length}x{width}", [np.array([(0, 0), (length, 0), (length, width),
                                                        (0, width)], float)]


def _box(x0, y0, x1, y1):
    return np.array([(x0, y0), (x1, y0), (x1, y1), (x0, y1)], float)


def _turned(loop, degrees, center):
    a = math.radians(degrees)
    c, s = math.cos(a), math.sin(a)
    d = loop - center
    return np.column_stack([c * d[:, 0] - s * d[:, 1], s * d[:, 0] + c * d[:, 1]]) + center


def _closed(line):
    return np.vstack([line, line[:1]])


def planar_graph_inputs():
    """(name, keywords of :meth:`bubblemesh.Domain.from_pslg`): planar graphs
    of several materials, the inputs of FEM users: interfaces, cracks,
    layers, inclusions, a wake line, free points, regions, and interfaces
    that cross without a node at the crossing."""
    yield "circle interface", dict(loops=[_box(0, 0, 4, 3)], constraints=[
        _closed(geometry.circle((2, 1.5), 0.8, 48))])
    yield "crack", dict(loops=[_box(0, 0, 4, 3)], constraints=[[(1, 1.5), (2.5, 1.5)]])
    yield "layers", dict(loops=[_box(0, 0, 5, 2)],
                         constraints=[[(0, y), (5, y)] for y in (0.4, 0.9, 1.6)])
    turns = np.random.default_rng(3).uniform(0, 90, 5)
    yield "rotated inclusions", dict(loops=[_box(0, 0, 4, 4)], constraints=[
        _closed(_turned(_box(x - 0.25, y - 0.25, x + 0.25, y + 0.25), a, np.array([x, y])))
        for (x, y), a in zip(((1, 1), (3, 1), (2, 2), (1, 3), (3, 3)), turns)])
    yield "cracks crossing at a node", dict(loops=[_box(0, 0, 4, 4)], constraints=[
        [(1, 2), (2, 2), (3, 2)], [(2, 1), (2, 2), (2, 3)]])
    slant = math.radians(35)
    yield "constraints from a wall", dict(loops=[_box(0, 0, 6, 2)], constraints=[
        [(2, 0), (2, 1.2)], [(4, 0), (4 + 1.5 * math.cos(slant), 1.5 * math.sin(slant))]])
    yield "zigzag interface", dict(loops=[_box(0, 0, 6, 2)], constraints=[
        np.column_stack([np.linspace(0, 6, 9), 1 + 0.4 * (-1.0) ** np.arange(9)])])
    foil = geometry.naca_airfoil(0.12, 30, sharp=True)
    edge = foil[np.argmax(foil[:, 0])]
    yield "airfoil with a wake line", dict(loops=[_box(-1, -1, 3, 1), foil],
                                           constraints=[[edge, (3, edge[1])]],
                                           holes=[(0.3, 0.0)])
    yield "free points", dict(loops=[_box(0, 0, 3, 3)],
                              points=np.random.default_rng(5).uniform(0.3, 2.7, (20, 2)))
    yield "checkerboard", dict(loops=[_box(0, 0, 3, 3)], constraints=[
        [(x, 0), (x, 3)] for x in (1, 2)] + [[(0, y), (3, y)] for y in (1, 2)])
    outer, inner = geometry.circle((0, 0), 2, 72), geometry.circle((0, 0), 1, 36)
    yield "annulus with spokes", dict(loops=[outer, inner], constraints=[
        [inner[6 * k], outer[12 * k]] for k in range(6)], holes=[(0.0, 0.0)])
    yield "skewed grid of interfaces", dict(loops=[_box(0, 0, 5, 3)], constraints=[
        [(0.2, 0.3 + 0.5 * k), (4.8, 0.9 + 0.45 * k)] for k in range(4)] + [
        [(0.4 + 1.1 * k, 0.1), (0.9 + 0.9 * k, 2.9)] for k in range(4)])
    yield "two materials with regions", dict(loops=[_box(0, 0, 4, 2)],
                                             constraints=[[(2, 0), (2, 2)]],
                                             regions=[(1, 1, 1, 0), (3, 1, 2, 0)])


def planar_graphs():
    """(name, domain) for each of :func:`planar_graph_inputs`."""
    for name, given in planar_graph_inputs():
        yield name, bm.Domain.from_pslg(**given)


def triangle_examples():
    """(name, domain): every ``.poly`` file in the ``triangle`` package's
    data directory, by name."""
    import triangle  # a peer, as the sweep's Triangle rows

    for path in sorted((Path(triangle.__file__).parent / "data").glob("*.poly")):
        yield path.name, bm.Domain.from_poly(path)


SETS = {"shapes": shapes, "rectangles": rectangles, "triangle-examples": triangle_examples,
        "planar-graphs": planar_graphs}


def sweep(sizes=SIZES, out_dir=None, names=None, which="shapes"):
    """bm.mesh, Gmsh and Triangle on every shape of :func:`shapes` (or of
    another of SETS, ``which``) at
    max_area = area / k for k in ``sizes``: the table (a DataFrame, one row
    per shape, size and mesher, case named "<shape> /k"), the pairs bm misses
    a target on printed, written as <which>_vs_gmsh.csv to ``out_dir``."""
    rows = []
    for name, given in SETS[which]():
        if names and name not in names:
            continue
        domain = given if isinstance(given, bm.Domain) else bm.Domain.from_loops(given)
        for k in sizes:
            case = case_rows(f"{name} /{k}", domain, {"max_area": domain.area / k})
            print_case(f"{name} /{k}", case)
            rows += case
    return sweep_table(rows, out_dir, f"{which}_vs_gmsh.csv")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=list(SIZES),
                        help="mesh each shape with max_area = area / k for each k")
    parser.add_argument("--only", nargs="+", default=None, help="only these shapes")
    parser.add_argument("--set", choices=sorted(SETS), default="shapes", dest="which",
                        help="the shapes a user would bring, long rectangles, "
                        "Triangle's example files or planar graphs")
    parser.add_argument("--out", type=Path, default=None,
                        help="write shapes_vs_gmsh.csv (rectangles_vs_gmsh.csv) here")
    args = parser.parse_args()
    sweep(args.sizes, args.out, args.only, args.which)


if __name__ == "__main__":
    main()
