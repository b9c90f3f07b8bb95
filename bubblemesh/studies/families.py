"""Random families of domains the tree's tables do not hold, each meshed by
bm.mesh against Gmsh Frontal-Delaunay and Triangle -pq30 at matched counts:
domains nobody tuned for, reproducible from a seed.

    python -m bubblemesh.studies.families --family plates --n 30 --seed 1 [--out DIR]

Families (every draw from one ``numpy`` generator seeded with ``--seed``):

- ``plates``: CAD-like plates drawn in shapely: 2-5 by 0.5-1.5, some with a
  second arm (an L or a T), most with fillets (a negative, then a positive
  buffer), up to three round or slot holes; sampled by
  ``Domain.from_shapely(g, size=h)`` and meshed with ``size=h``, h the side
  for area / 100-2000 (needs shapely);
- ``graded``: the same plates with a graded size function (a point source, a
  ramp along x or a band along a line; needs shapely);
- ``narrow``: corner-only L-shaped strips, parallelograms and trapezoids 1
  wide, 2-8 long, meshed with max_area = area / 40-600;
- ``sharp``: corner-only stars of 4-12 spikes, saw-tooth combs of 3-9 teeth
  (5-20 degrees) on a square, and NACA 00xx airfoils with a sharp trailing
  edge (20-120 nodes, cosine spaced) turned up to 17 degrees in a box; meshed
  with max_area = area / 100-1000;
- ``needles``: a corner of 0.3-3 degrees: sliver triangles, a spike on a
  square, crescents (two cusps, arcs of 30-80 nodes); meshed with max_area =
  area / 30-1000.

The rows are :func:`bubblemesh.studies.quality.case_rows`; prints each case
and the targets bm misses, and writes <family>_vs_gmsh.csv to ``--out``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import bubblemesh as bm
from bubblemesh.studies.quality import case_rows, print_case, sweep_table


def plate(rng):
    """A shapely polygon: a plate, maybe with an arm, maybe filleted, with 0-3
    holes (round or slots) at least 0.05 inside it."""
    from shapely.geometry import LineString, Point, box

    length, height = rng.uniform(2, 5), rng.uniform(0.5, 1.5)
    kind = rng.integers(3)
    g = box(0, 0, length, height)
    if kind == 1:
        g = g.union(box(0, 0, rng.uniform(0.4, 1.0), rng.uniform(1.5, 3)))
    elif kind == 2:
        c, w = length / 2, rng.uniform(0.3, 0.8)
        g = g.union(box(c - w / 2, 0, c + w / 2, rng.uniform(1.8, 3)))
    r = rng.uniform(0.02, 0.2)
    if rng.random() < 0.7:
        g = g.buffer(-r, join_style=1).buffer(r, join_style=1)
    for _ in range(int(rng.integers(0, 4))):
        for _try in range(50):
            p = Point(rng.uniform(*g.bounds[0::2]), rng.uniform(*g.bounds[1::2]))
            if rng.random() < 0.6:
                hole = p.buffer(rng.uniform(0.05, 0.2), quad_segs=16)
            else:
                a, s = rng.uniform(0, np.pi), rng.uniform(0.2, 0.6)
                hole = LineString([(p.x, p.y), (p.x + s * np.cos(a), p.y + s * np.sin(a))]
                                  ).buffer(rng.uniform(0.04, 0.12), quad_segs=16)
            if g.buffer(-0.05).contains(hole):
                g = g.difference(hole)
                break
    return g


def plates(n, seed):
    """(name, domain, bm.mesh keywords) for ``n`` plates with a constant size."""
    rng = np.random.default_rng(seed)
    for i in range(n):
        g = plate(rng)
        h = float(np.sqrt(g.area / rng.integers(100, 2000)))
        yield f"plate {seed}.{i}", bm.Domain.from_shapely(g, size=h), {"size": h}


def _graded_size(rng, bounds, h0):
    """One of three graded size functions over ``bounds``, h0 at its coarsest."""
    x0, y0, x1, y1 = bounds
    kind = int(rng.integers(3))
    if kind == 0:
        c, s = rng.uniform([x0, y0], [x1, y1]), rng.uniform(0.2, 0.5)
        return lambda xy: h0 * (s + (1 - s) * np.minimum(1, np.hypot(*(xy - c).T)))
    if kind == 1:
        s = rng.uniform(0.2, 0.5)
        return lambda xy: h0 * (s + (1 - s) * (xy[:, 0] - x0) / (x1 - x0))
    yc, s = rng.uniform(y0, y1), rng.uniform(0.15, 0.4)
    return lambda xy: h0 * np.minimum(1, s + np.abs(xy[:, 1] - yc))


def graded(n, seed):
    """(name, domain, bm.mesh keywords) for ``n`` plates with a graded size."""
    rng = np.random.default_rng(seed)
    for i in range(n):
        g = plate(rng)
        h0 = float(np.sqrt(g.area / rng.integers(100, 800)))
        size = _graded_size(rng, g.bounds, h0)
        yield f"graded {seed}.{i}", bm.Domain.from_shapely(g, size=size), {"size": size}


def narrow(n, seed):
    """(name, domain, bm.mesh keywords) for ``n`` corner-only strips 1 wide."""
    rng = np.random.default_rng(seed)
    for i in range(n):
        kind, length = int(rng.integers(3)), rng.uniform(2, 8)
        if kind == 0:
            arm = rng.uniform(2, 6)
            corners = [(0, 0), (length, 0), (length, 1), (1, 1), (1, arm), (0, arm)]
        elif kind == 1:
            s = rng.uniform(-1.5, 1.5)
            corners = [(0, 0), (length, 0), (length + s, 1), (s, 1)]
        else:
            t = rng.uniform(0.3, 1.5)
            t = t if 2 * t < length else 0.45 * length  # a top that does not cross itself
            corners = [(0, 0), (length, 0), (length - t, 1), (t, 1)]
        domain = bm.Domain.from_loops([np.array(corners, float)])
        yield (f"narrow {seed}.{i}", domain,
               {"max_area": domain.area / int(rng.integers(40, 600))})


def _star(rng):
    """A star of 4-12 spikes, its radii jittered by up to 20%."""
    spikes, inner = int(rng.integers(4, 13)), rng.uniform(0.2, 0.7)
    angle = np.arange(2 * spikes) * np.pi / spikes + rng.uniform(0, 0.3)
    radius = np.where(np.arange(2 * spikes) % 2 == 0, 1.0, inner)
    radius = radius * rng.uniform(0.8, 1.2, 2 * spikes)
    return [np.column_stack([radius * np.cos(angle), radius * np.sin(angle)])]


def _saw(rng):
    """A unit square whose top is a saw of 3-9 teeth 0.3-1.5 tall."""
    teeth, depth = int(rng.integers(3, 10)), rng.uniform(0.3, 1.5)
    w = 1.0 / teeth
    top = [(j * w + 0.5 * w * s, 1.0 + depth * s) for j in range(teeth) for s in (0, 1)]
    return [np.array([(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), *top[::-1]])]


def _airfoil(rng):
    """A NACA 00xx section of chord 1 (the closed-trailing-edge thickness
    formula), its two sides meeting at a sharp trailing edge, in a box."""
    thickness, nodes = rng.uniform(0.06, 0.2), int(rng.integers(20, 120))
    x = 0.5 * (1 - np.cos(np.linspace(0, np.pi, nodes)))
    y = 5 * thickness * (0.2969 * np.sqrt(x) - 0.126 * x - 0.3516 * x**2
                         + 0.2843 * x**3 - 0.1036 * x**4)
    y[-1] = 0.0
    foil = np.vstack([np.column_stack([x, y])[::-1], np.column_stack([x, -y])[1:-1]])
    a = rng.uniform(-0.3, 0.3)
    foil = foil @ np.array([[np.cos(a), np.sin(a)], [-np.sin(a), np.cos(a)]])
    return [np.array([(-1.0, -1.0), (2.5, -1.0), (2.5, 1.0), (-1.0, 1.0)]), foil]


def sharp(n, seed):
    """(name, domain, bm.mesh keywords) for ``n`` domains with sharp corners."""
    rng = np.random.default_rng(seed)
    for i in range(n):
        kind = int(rng.integers(3))
        loops = (_star, _saw, _airfoil)[kind](rng)
        domain = bm.Domain.from_loops(loops)
        yield (f"{('star', 'saw', 'airfoil')[kind]} {seed}.{i}", domain,
               {"max_area": domain.area / int(rng.integers(100, 1000))})


def _sliver(rng, tip):
    """A triangle with a corner of ``tip`` radians at the origin, its walls 1-4
    long."""
    a, b = rng.uniform(1, 4, 2)
    return [np.array([(0.0, 0.0), (a, 0.0), (b * np.cos(tip), b * np.sin(tip))])]


def _spike(rng, tip):
    """A unit square with a spike of angle ``tip`` on its top, 1-3 long."""
    length, x = rng.uniform(1, 3), rng.uniform(0.3, 0.7)
    half = length * np.tan(tip / 2)
    return [np.array([(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (x + half, 1.0),
                      (x, 1.0 + length), (x - half, 1.0), (0.0, 1.0)])]


def _crescent(rng, tip):
    """The unit disk less a disk of radius 0.5-0.9 that cuts its circle at the
    angle ``tip``: two cusps of about that angle, 30-80 nodes on each arc,
    cosine-spaced so that the chords at a cusp nearly keep its angle."""
    r = rng.uniform(0.5, 0.9)
    d = np.sqrt(1 + r * r - 2 * r * np.cos(tip))
    x = (1 + d * d - r * r) / (2 * d)  # the circles meet at (x, +-y)
    y = np.sqrt(1 - x * x)
    outer, inner = (int(k) for k in rng.integers(30, 81, 2))

    def spaced(start, nodes):
        s = 0.5 * (1 - np.cos(np.linspace(0, np.pi, nodes + 1)))
        return start + (2 * np.pi - 2 * start) * s

    big, small = spaced(np.arctan2(y, x), outer), spaced(np.arctan2(y, x - d), inner)
    arc = np.column_stack([np.cos(big), np.sin(big)])
    cut = np.column_stack([d + r * np.cos(small[::-1]), r * np.sin(small[::-1])])
    return [np.vstack([arc, cut[1:-1]])]


def needles(n, seed):
    """(name, domain, bm.mesh keywords) for ``n`` domains with a needle: a
    corner of 0.3-3 degrees (a sliver triangle, a spike on a square, a
    crescent's two cusps)."""
    rng = np.random.default_rng(seed)
    for i in range(n):
        kind, tip = int(rng.integers(3)), np.radians(rng.uniform(0.3, 3.0))
        loops = (_sliver, _spike, _crescent)[kind](rng, tip)
        domain = bm.Domain.from_loops(loops)
        yield (f"{('sliver', 'spike', 'crescent')[kind]} {seed}.{i}", domain,
               {"max_area": domain.area / int(rng.integers(30, 1000))})


FAMILIES = {"plates": plates, "graded": graded, "narrow": narrow, "sharp": sharp,
            "needles": needles}


def sweep(family, n, seed, out_dir=None):
    """bm.mesh, Gmsh and Triangle on ``n`` domains of ``family`` drawn with
    ``seed``: the table (a DataFrame, one row per domain and mesher), the
    targets bm misses printed, written as <family>_vs_gmsh.csv to ``out_dir``."""
    rows = []
    for name, domain, kwargs in FAMILIES[family](n, seed):
        case = case_rows(name, domain, kwargs)
        print_case(name, case)
        rows += case
    return sweep_table(rows, out_dir, f"{family}_vs_gmsh.csv")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--family", choices=sorted(FAMILIES), default="plates")
    parser.add_argument("--n", type=int, default=30, help="how many domains")
    parser.add_argument("--seed", type=int, default=1, help="numpy seed of the draws")
    parser.add_argument("--out", type=Path, default=None,
                        help="write <family>_vs_gmsh.csv here")
    args = parser.parse_args()
    sweep(args.family, args.n, args.seed, args.out)


if __name__ == "__main__":
    main()
