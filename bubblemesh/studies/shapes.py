"""A sweep of inputs a user would bring, given by their corners (and arcs as
polygons), each meshed by bm.mesh at several sizes against Gmsh
Frontal-Delaunay and Triangle -pq30 at matched counts.

    python -m bubblemesh.studies.shapes [--sizes 50 100 200 1000] [--out DIR]
    python -m bubblemesh.studies.shapes --set rectangles --sizes 60 150 400 1200
    python -m bubblemesh.studies.shapes --set triangle-examples --sizes 100 300 1000 3000
    python -m bubblemesh.studies.shapes --set planar-graphs --sizes 30 100 1000
    python -m bubblemesh.studies.shapes --set shapely --sizes 30 100 1000
    python -m bubblemesh.studies.shapes --set glyphs --sizes 30 100 1000
    python -m bubblemesh.studies.shapes --set more-shapely --sizes 30 100 1000

``--set rectangles`` sweeps long rectangles (channels 4 to 30 times longer
than wide) instead of the shapes; ``--set triangle-examples`` the ``.poly``
files that ship with the ``triangle`` package (Triangle's own examples:
holes, interior constraints, free points, a lake with islands), read by
:meth:`bubblemesh.Domain.from_poly`; ``--set planar-graphs`` planar graphs
of several materials (:func:`planar_graphs`, by
:meth:`bubblemesh.Domain.from_pslg`); ``--set shapely`` shapes drawn with
shapely (:func:`shapely_inputs`); ``--set glyphs`` letter outlines
(:func:`glyph_inputs`); ``--set more-shapely`` kinds of drawings the others
lack (:func:`more_shapely_inputs`).

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


def shapely_inputs():
    """(name, shapely Polygon): shapes drawn the way a CAD or GIS user draws
    them, with shapely's buffers, unions and differences; arcs come out as
    shapely's polygons (``quad_segs`` pieces a quarter circle)."""
    from shapely import affinity, ops  # optional, as in Domain.from_shapely
    from shapely import geometry as sg

    rng = np.random.default_rng(7)
    box = sg.box(-1.0, -1.0, 3.0, 1.0)
    foil = sg.Polygon(geometry.naca_airfoil(0.12, 30, sharp=True))
    elements = [affinity.rotate(affinity.scale(foil, f, f, origin=(0, 0)), a, origin=(0, 0))
                for f, a in ((0.25, -20.0), (1.0, 0.0), (0.35, 25.0))]
    elements = [affinity.translate(e, dx, dy)
                for e, (dx, dy) in zip(elements, ((-0.3, 0.08), (0.0, 0.0), (1.03, -0.06)))]
    yield "three-element airfoil", box.difference(ops.unary_union(elements))
    x, y = rng.uniform(0.3, 3.7, 40), rng.uniform(0.3, 2.7, 40)
    circles = [sg.Point(p).buffer(r, quad_segs=4)
               for p, r in zip(zip(x, y), rng.uniform(0.04, 0.2, 40))]
    yield "40 random circles in a box", sg.box(0, 0, 4, 3).difference(ops.unary_union(circles))
    bore = sg.Point(0, 0).buffer(0.6, quad_segs=12).union(sg.box(-0.12, 0.4, 0.12, 0.75))
    bolts = [sg.Point(1.4 * math.cos(a), 1.4 * math.sin(a)).buffer(0.15, quad_segs=4)
             for a in np.linspace(0, 2 * math.pi, 6, endpoint=False) + 0.3]
    yield "flange, bolt holes, keyway", sg.Point(0, 0).buffer(2.0, quad_segs=24).difference(
        ops.unary_union([bore] + bolts))
    yield "staircase", sg.Polygon([(0, 0), (5, 0)] + [
        p for k in range(5) for p in ((5 - k, k + 1), (4 - k, k + 1))])
    walk = np.cumsum(np.column_stack([np.ones(12), rng.uniform(-1, 1, 12)]), axis=0)
    yield "river, buffered random walk", sg.LineString(walk).buffer(0.35, quad_segs=6)
    ell = sg.box(0, 0, 6, 1).union(sg.box(0, 0, 1, 4))
    yield "long edges, fillet of 0.05", ell.buffer(0.05, quad_segs=20).buffer(
        -0.05, quad_segs=20)
    plate = sg.box(0, 0, 3, 0.6).union(sg.box(0, 0, 0.6, 2)).buffer(0.15, quad_segs=6)
    holes = [sg.Point(x, y).buffer(0.12, quad_segs=6) for x, y in ((2.4, 0.3), (0.3, 1.5))]
    yield "bracket", plate.difference(ops.unary_union(holes))
    t = np.linspace(0.5, 5.5 * math.pi, 200)
    yield "spiral channel", sg.LineString(np.column_stack(
        [0.12 * t * np.cos(t), 0.12 * t * np.sin(t)])).buffer(0.1, quad_segs=4)
    yield "hex nut", sg.Polygon(_regular(6)).difference(sg.Point(0, 0).buffer(0.5, quad_segs=8))
    yield "thin cross", sg.box(-1, -0.05, 1, 0.05).union(sg.box(-0.05, -1, 0.05, 1))
    small = [sg.Point(0.2 * i + 0.1, 0.2 * j + 0.1).buffer(0.04, quad_segs=2)
             for i in range(10) for j in range(10)]
    yield "100 small holes", sg.box(0, 0, 2, 2).difference(ops.unary_union(small))
    yield "1000-vertex circle", sg.Point(0, 0).buffer(1.0, quad_segs=250)
    pair = [sg.Point(x, 0.5).buffer(0.2, quad_segs=8) for x in (0.795, 1.205)]
    yield "two holes 0.01 apart", sg.box(0, 0, 2, 1).difference(ops.unary_union(pair))
    yield "annulus sector, 10 degrees", sg.Polygon(
        [(r * math.cos(a), r * math.sin(a)) for r, s in ((1.0, 1), (2.0, -1))
         for a in np.radians(np.linspace(0, 10, 6))[::s]])
    yield "gear, 40 teeth", sg.Polygon(geometry.gear(40, 1.0, 1.1, 10.0))


def _coast(rng, corners=12, levels=4, rough=0.25):
    """An island: ``corners`` random points about a unit circle, each edge
    split ``levels`` times at its midpoint moved across it by up to
    ``rough`` of its length (a fractal coastline), the largest valid part."""
    from shapely import geometry as sg  # optional, as in Domain.from_shapely

    a = np.sort(rng.uniform(0.0, 2.0 * math.pi, corners))
    p = np.column_stack([np.cos(a), np.sin(a)]) * rng.uniform(0.7, 1.2, (corners, 1))
    for _ in range(levels):
        d = np.roll(p, -1, axis=0) - p
        middle = p + 0.5 * d + np.column_stack([-d[:, 1], d[:, 0]]) * rng.uniform(
            -rough, rough, (len(p), 1))
        p = np.column_stack([p, middle]).reshape(-1, 2)
    island = sg.Polygon(p).buffer(0)
    return max(getattr(island, "geoms", [island]), key=lambda part: part.area)


def _spiky_star(points, tip_degrees):
    """A star of ``points`` tips of ``tip_degrees`` on the unit circle."""
    half, tip = math.pi / points, math.radians(tip_degrees)
    inner = math.sin(tip / 2) / math.sin(tip / 2 + half)
    return _star(points, inner)


def more_shapely_inputs():
    """(name, shapely Polygon): drawings of kinds the other sets lack: fractal
    coastlines with a lake, a 10:1 ellipse, random convex hulls, stars of 10-
    and 20-degree tips, a crescent (22-degree cusps), an eccentric annulus, a
    grid of square holes, a channel junction, thin fins and teeth, a half-round
    bump on a long wall, a thin triangle, a maze, a slot, an airfoil in a far
    field 20 chords out, a hole 1e-3 across, a fillet of 0.01 on long edges,
    one wall drawn in 80 pieces beside three in one."""
    from shapely import affinity, ops
    from shapely import geometry as sg

    rng = np.random.default_rng(21)
    for k in range(3):
        coast = _coast(rng)
        lake = coast.centroid.buffer(0.15, quad_segs=6)
        yield f"coast {k}", coast.difference(lake) if coast.contains(lake) else coast
    t = np.linspace(0.0, 2.0 * math.pi, 120, endpoint=False)
    yield "ellipse 10:1", sg.Polygon(np.column_stack([5.0 * np.cos(t), 0.5 * np.sin(t)]))
    for k in range(3):
        yield f"convex hull {k}", sg.MultiPoint(rng.uniform(0.0, 1.0, (9, 2))).convex_hull
    for tip in (10, 20):
        yield f"star, 6 tips of {tip} degrees", sg.Polygon(_spiky_star(6, tip))
    disk = sg.Point(0, 0).buffer(1.0, quad_segs=16)
    yield "crescent", disk.difference(sg.Point(0.4, 0).buffer(0.8, quad_segs=16))
    yield "eccentric annulus, gap 0.02", disk.difference(sg.Point(0.28, 0).buffer(0.7,
                                                                                   quad_segs=16))
    holes = [sg.box(0.2 + 0.4 * i, 0.2 + 0.4 * j, 0.35 + 0.4 * i, 0.35 + 0.4 * j)
             for i in range(6) for j in range(3)]
    yield "grid of square holes", sg.box(0, 0, 2.6, 1.4).difference(ops.unary_union(holes))
    arms = [affinity.rotate(sg.box(0, -0.1, 2, 0.1), a, origin=(0, 0)) for a in (0, 70, 160, 250)]
    yield "channel junction", ops.unary_union(arms + [sg.Point(0, 0).buffer(0.25, quad_segs=8)])
    teeth = [sg.box(0.1 + 0.4 * i, 0.3, 0.2 + 0.4 * i, 1.5) for i in range(10)]
    yield "comb of thin teeth", sg.box(0, 0, 4, 0.3).union(ops.unary_union(teeth))
    fins = [sg.box(0.1 + 0.25 * i, 0.2, 0.15 + 0.25 * i, 1.2) for i in range(12)]
    yield "heat sink", sg.box(0, 0, 3.05, 0.2).union(ops.unary_union(fins))
    bump = 2.0 + 0.3 * np.exp(1j * np.linspace(math.pi, 0.0, 40))
    bump = np.column_stack([bump.real, bump.imag])
    bump[[0, -1], 1] = 0.0  # sin(pi) is 1.2e-16, not 0: the wall's own nodes
    yield "long walls, half-round bump", sg.Polygon(
        [(-6, 0), *bump, (6, 0), (6, 3), (-6, 3)])
    yield "triangle 30-60-90", sg.Polygon([(0, 0), (3, 0), (0, math.sqrt(3))])
    eight = math.radians(8)
    yield "triangle of 8 degrees", sg.Polygon([(0, 0), (4, 0),
                                                (4 * math.cos(eight), 4 * math.sin(eight))])
    yield "trapezoid", sg.Polygon([(0, 0), (5, 0), (4, 1), (1, 1)])
    yield "U channel", sg.box(0, 0, 3, 2).difference(sg.box(0.4, 0.4, 2.6, 2.0))
    yield "plate, hole near its edge", sg.box(0, 0, 3, 2).difference(
        sg.Point(1.5, 0.45).buffer(0.4, quad_segs=10))
    foil = sg.Polygon(geometry.naca_airfoil(0.12, 60, sharp=False))
    yield "airfoil in a far field", sg.Point(0.5, 0).buffer(20, quad_segs=16).difference(foil)
    yield "square, hole 1e-3 across", sg.box(0, 0, 1, 1).difference(
        sg.Point(0.5, 0.5).buffer(5e-4, quad_segs=8))
    bracket = sg.box(0, 0, 4, 0.5).union(sg.box(0, 0, 0.5, 3))
    yield "bracket, fillet 0.01", bracket.buffer(-0.01, quad_segs=8).buffer(0.01, quad_segs=8)
    corridors = [(0, 0, 5, 0.3), (4.7, 0, 5, 3), (0, 2.7, 5, 3), (0, 1.35, 3.5, 1.65),
                 (0, 0, 0.3, 1.65), (3.2, 1.35, 3.5, 2.7)]
    yield "maze", ops.unary_union([sg.box(*c) for c in corridors])
    yield "one wall in 80 pieces", sg.Polygon(
        [(x, 0.0) for x in np.linspace(0, 2, 81)] + [(2, 1), (0, 1)])
    a = np.linspace(0, 2 * math.pi, 400, endpoint=False)
    r = 1 + 0.3 * np.sin(5 * a) + 0.1 * np.sin(17 * a)
    yield "wavy blob", sg.Polygon(np.column_stack([r * np.cos(a), r * np.sin(a)]))
    yield "slot from the edge", sg.box(0, 0, 2, 1).difference(sg.box(0.9, 0.4, 2.1, 0.6))
    hexagon = sg.Polygon(_regular(6))
    yield "hexagon, pentagon hole", hexagon.difference(sg.Polygon(_regular(5, 0.4, phase=0.3)))


def more_shapely_shapes():
    """(name, domain) for each of :func:`more_shapely_inputs`."""
    for name, polygon in more_shapely_inputs():
        yield name, bm.Domain.from_shapely(polygon)


def shapely_shapes():
    """(name, domain) for each of :func:`shapely_inputs`, its ring vertices
    the boundary nodes (:meth:`bubblemesh.Domain.from_shapely`)."""
    for name, polygon in shapely_inputs():
        yield name, bm.Domain.from_shapely(polygon)


GLYPHS = (("DejaVu Sans", "B8&@gaQRkM%"), ("DejaVu Serif", "BgaR&5"))


def glyph_inputs():
    """(name, shapely Polygon): the outlines of the GLYPHS in matplotlib's
    own DejaVu fonts (a text path at size 1, its curves flattened by
    matplotlib), one polygon per connected part (the rings nested even-odd):
    curves in many short pieces beside long stems, serifs, strokes a few
    elements wide and counters (holes), as a logo or a label comes."""
    from matplotlib.font_manager import FontProperties  # optional: the plot extra
    from matplotlib.textpath import TextPath
    from shapely import geometry as sg

    for family, characters in GLYPHS:
        for character in characters:
            path = TextPath((0.0, 0.0), character, size=1.0, prop=FontProperties(family=family))
            rings = sorted((sg.Polygon(ring) for ring in path.to_polygons(closed_only=True)),
                           key=lambda ring: -ring.area)
            shape = rings[0]
            for ring in rings[1:]:
                shape = shape.symmetric_difference(ring)
            parts = getattr(shape, "geoms", [shape])
            for k, part in enumerate(parts):
                tail = f" {k + 1}" if len(parts) > 1 else ""
                yield f"{family.split()[-1].lower()} {character}{tail}", sg.polygon.orient(part)


def glyphs():
    """(name, domain) for each of :func:`glyph_inputs`."""
    for name, polygon in glyph_inputs():
        yield name, bm.Domain.from_shapely(polygon)


SETS = {"shapes": shapes, "rectangles": rectangles, "triangle-examples": triangle_examples,
        "planar-graphs": planar_graphs, "shapely": shapely_shapes, "glyphs": glyphs,
        "more-shapely": more_shapely_shapes}


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
                        "Triangle's example files, planar graphs, shapely drawings or letter "
                        "outlines")
    parser.add_argument("--out", type=Path, default=None,
                        help="write shapes_vs_gmsh.csv (rectangles_vs_gmsh.csv) here")
    args = parser.parse_args()
    sweep(args.sizes, args.out, args.only, args.which)


if __name__ == "__main__":
    main()
