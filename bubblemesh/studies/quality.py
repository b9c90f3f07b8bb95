"""Quality study of the robust mesher bm.mesh against Triangle -pq30 and Gmsh
Frontal-Delaunay (Mesh.Algorithm=6) on the same input at matched element counts.

    python -m bubblemesh.studies.quality [--data DIR] [--big]

``--data``: a folder with Triangle's example A.poly and double_hex3.poly (from
Triangle's distribution; skipped if absent).  Prints one table row per case
and mesher, then the iteration sweeps on graded domains, the size test and
(``--big``) timings at 100k and 1M elements against the paper's path.
"""

from __future__ import annotations

import argparse
import math
import time
import warnings
from pathlib import Path

import numpy as np

import bubblemesh as bm
from bubblemesh.quality import radius_ratio


def _square(side, spacing, lo=0.0):
    n = max(1, int(round(side / spacing)))
    s = lo + np.linspace(0, side, n + 1)[:-1]
    e = lo + side
    return np.concatenate([np.column_stack([s, 0 * s + lo]), np.column_stack([0 * s + e, s]),
                           np.column_stack([2 * lo + side - s + 0 * s, 0 * s + e])[::1],
                           np.column_stack([0 * s + lo, 2 * lo + side - s])])


def _circle(c, r, h):
    n = max(8, int(math.ceil(2 * math.pi * r / h)))
    t = np.linspace(0, 2 * math.pi, n, endpoint=False)
    return np.column_stack([c[0] + r * np.cos(t), c[1] + r * np.sin(t)])


def _random_polygon(rng, holes):
    n = int(rng.integers(4, 10))
    ang = 2 * math.pi * np.arange(n) / n + rng.uniform(-0.3, 0.3, n) * 2 * math.pi / n
    r = rng.uniform(0.6, 1.0, n)
    loops = [np.column_stack([r * np.cos(ang), r * np.sin(ang)])]
    for k in range(holes):
        c = (0.0, 0.0) if holes == 1 else (0.28 * math.cos(2 * math.pi * k / holes),
                                           0.28 * math.sin(2 * math.pi * k / holes))
        m = int(rng.integers(3, 5))
        a = 2 * math.pi * np.arange(m) / m + rng.uniform(0, 1)
        loops.append(np.column_stack([c[0] + 0.1 * np.cos(a), c[1] + 0.1 * np.sin(a)]))
    return loops


def cases(data: Path | None):
    yield "L-shape", [np.array([(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)], float)]
    t = np.linspace(0, math.pi, 33)
    yield "half-disk", [np.column_stack([np.cos(t), np.sin(t)])]
    for name in ("A", "double_hex3"):
        path = None if data is None else data / f"{name}.poly"
        if path is not None and path.exists():
            d = bm.Domain.from_poly(path)
            yield f"{name}.poly", [np.asarray(d.points)[ix] for ix in d.loops]
    yield "square-square-hole", [np.array([(0, 0), (1, 0), (1, 1), (0, 1)], float),
                                 np.array([(.4, .4), (.6, .4), (.6, .6), (.4, .6)], float)]
    rng = np.random.default_rng(7)
    for k in range(8):
        loops = _random_polygon(rng, k % 4)
        try:
            bm.Domain.from_loops(loops)
        except bm.GeometryError:
            continue  # a hole crossed the outer loop: not a valid input
        yield f"random-{k}-holes{k % 4}", loops


def _stats(points, triangles):
    q = radius_ratio(np.asarray(points), np.asarray(triangles))
    return len(triangles), float(q.min()), float(q.mean()), float(np.mean(q < 0.5))


def run_triangle(domain, count):
    import triangle

    area = domain.area / max(count, 2) * 1.0
    pts = dict(vertices=np.array(domain.points), segments=np.array(domain.segments))
    if len(domain.hole_points):
        pts["holes"] = np.array(domain.hole_points)
    for _ in range(4):  # match the element count
        out = triangle.triangulate(pts, f"pq30a{area:.17g}Q")
        n = len(out["triangles"])
        if abs(n - count) < 0.05 * count:
            break
        area *= n / count
    return out["vertices"], out["triangles"]


def run_gmsh(domain, count):
    import gmsh

    h = math.sqrt(4 * domain.area / (math.sqrt(3) * max(count, 2)))
    P = np.asarray(domain.points)
    for _ in range(4):
        gmsh.initialize()
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("m")
        loops = []
        for ix in domain.loops:
            tags = [gmsh.model.geo.addPoint(*P[i], 0.0, h) for i in ix]
            lines = [gmsh.model.geo.addLine(tags[k], tags[(k + 1) % len(tags)])
                     for k in range(len(tags))]
            loops.append(gmsh.model.geo.addCurveLoop(lines))
        gmsh.model.geo.addPlaneSurface(loops)
        gmsh.model.geo.synchronize()
        gmsh.option.setNumber("Mesh.Algorithm", 6)
        gmsh.option.setNumber("Mesh.MeshSizeMax", h)
        gmsh.model.mesh.generate(2)
        tags, xyz, _ = gmsh.model.mesh.getNodes()
        _, _, conn = gmsh.model.mesh.getElements(2)
        gmsh.finalize()
        index = np.zeros(int(tags.max()) + 1, np.int64)
        index[tags.astype(np.int64)] = np.arange(len(tags))
        tri = index[np.asarray(conn[0], np.int64).reshape(-1, 3)]
        pts = xyz.reshape(-1, 3)[:, :2]
        if abs(len(tri) - count) < 0.05 * count:
            break
        h *= math.sqrt(len(tri) / count)
    return pts, tri


def quality_table(data):
    print(f"{'case':24s} {'mesher':12s} {'N':>6s} {'min':>6s} {'mean':>6s} {'<0.5':>6s}")
    for name, loops in cases(data):
        domain = bm.Domain.from_loops(loops)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", bm.QualityWarning)
            default = bm.mesh(domain)
            # a mesh of some size: at least ~200 elements
            area = domain.area / 200
            m = bm.mesh(domain, max_area=area)
        note = f"  ({len(caught) // 2} sharp-corner warnings)" if caught else ""
        rows = [("bm default", default.points, default.triangles),
                ("bm max_area", m.points, m.triangles)]
        count = len(m.triangles)
        rows.append(("triangle", *run_triangle(domain, count)))
        rows.append(("gmsh", *run_gmsh(domain, count)))
        for mesher, p, t in rows:
            n, qmin, qmean, low = _stats(p, t)
            print(f"{name:24s} {mesher:12s} {n:6d} {qmin:6.3f} {qmean:6.4f} {low:6.3f}{note}")


def sweeps():
    graded = [_square(10.0, 0.5), _circle((5, 5), 0.05, 0.005)]
    plate = [_square(10.0, 0.25)] + [_circle((2 + 2 * i, 2 + 2 * j), 0.4, 0.05)
                                     for i in range(4) for j in range(4)]
    for name, loops in (("graded square+hole", graded), ("perforated plate", plate)):
        domain = bm.Domain.from_loops(loops)
        for it in (100, 200, 400, 1000):
            m = bm.mesh(domain, max_iterations=it)
            n, qmin, qmean, _ = _stats(m.points, m.triangles)
            o = m.optimization
            print(f"{name:20s} max_iterations {it:5d}: N {n} min {qmin:.4f} mean {qmean:.4f} "
                  f"(iterations {o.iterations}, converged {o.converged})")
        p = bm.mesh(domain, paper=True)
        n, qmin, qmean, _ = _stats(p.points, p.triangles)
        print(f"{name:20s} paper: N {n} min {qmin:.4f} mean {qmean:.4f}")


def size_test():
    square = bm.Domain.from_loops([[(0, 0), (1, 0), (1, 1), (0, 1)]])

    def h(xy):
        return 0.02 + 0.1 * np.hypot(xy[:, 0] - 0.5, xy[:, 1] - 0.5)

    for label, size in (("h=0.02", 0.02), ("h(x)", h)):
        m = bm.mesh(square, size=size)
        e = np.vstack([m.triangles[:, [0, 1]], m.triangles[:, [1, 2]], m.triangles[:, [2, 0]]])
        e = np.unique(np.sort(e, axis=1), axis=0)
        p = np.asarray(m.points)
        length = np.hypot(*(p[e[:, 0]] - p[e[:, 1]]).T)
        target = size if not callable(size) else size(0.5 * (p[e[:, 0]] + p[e[:, 1]]))
        r = length / target
        print(f"size {label}: {len(m.triangles)} elements, edges in [0.8, 1.25] h: "
              f"{np.mean((r >= 0.8) & (r <= 1.25)):.3f}, median {np.median(r):.3f}")


def timings(sizes=(100_000, 1_000_000), repeats=3):
    for n in sizes:
        k = int(math.sqrt(n / 2.3))  # a disk of that many elements in paper mode
        t = np.linspace(0, 2 * math.pi, int(2 * math.pi * math.sqrt(n / 2.3) * 0.9),
                        endpoint=False)
        domain = bm.Domain.from_loops([np.column_stack([np.cos(t), np.sin(t)])])
        best = {"paper": math.inf, "robust": math.inf}
        counts = {}
        for _ in range(repeats):  # alternating
            for label in ("paper", "robust"):
                t0 = time.perf_counter()
                m = bm.mesh(domain, paper=(label == "paper"))
                best[label] = min(best[label], time.perf_counter() - t0)
                counts[label] = len(m.triangles)
        print(f"disk ~{n} ({k}): paper {counts['paper']} el {best['paper']:.2f} s, robust "
              f"{counts['robust']} el {best['robust']:.2f} s, ratio "
              f"{best['robust'] / best['paper']:.2f}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=None)
    parser.add_argument("--big", action="store_true")
    parser.add_argument("--skip-table", action="store_true")
    args = parser.parse_args()
    if not args.skip_table:
        quality_table(args.data)
    sweeps()
    size_test()
    if args.big:
        timings()


if __name__ == "__main__":
    main()
