"""Fuzz campaign: random domains a user might bring, each meshed in a worker
process with a time limit, so that a crash, a hang, a foreign exception or an
invalid mesh is counted, never fatal to the campaign.

    python verification/fuzz.py --cases 10000 --seed 0          # on demand
    python verification/fuzz.py --cases 200 --timeout 120       # a short run

Kinds of case: polygons with 0-3 holes on a decimal grid (0.1), the same
jittered by a few ulps, offset far from the origin (1e6 ... 1e15), scaled
(1e-8 ... 1e8), and mutated Triangle ``.poly`` texts.  A case passes when it
gives a valid, conforming mesh (the exact oracles) or a bubblemesh exception
(GeometryError, MeshingError; TypeError or ValueError for misuse), in paper
mode and with the default (refining) mesher.  The
worker is restarted after a crash or a time-out.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from collections import Counter
from fractions import Fraction

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
KINDS = ("grid", "ulp", "offset", "scale", "poly")


# --- case generation (plain numpy, no bubblemesh) ----------------------------------


def _star(rng, center, radius, n):
    angles = np.sort(rng.uniform(0.0, 2.0 * np.pi, n))
    radii = radius * rng.uniform(0.55, 1.0, n)
    return np.column_stack([center[0] + radii * np.cos(angles),
                            center[1] + radii * np.sin(angles)])


def _distinct(loop):
    """Drop nodes equal to their predecessor (rounding merges close ones)."""
    keep = np.any(loop != np.roll(loop, 1, axis=0), axis=1)
    return loop[keep] if keep.sum() >= 3 else loop


def make_case(seed: int) -> dict:
    """Case ``seed``: its kind and loops (lists of [x, y]) or .poly text."""
    rng = np.random.default_rng(seed)
    kind = KINDS[seed % len(KINDS)]
    loops = [_star(rng, (0.0, 0.0), 3.0, int(rng.integers(3, 40)))]
    centres = [(-1.2, 0.0), (1.2, 0.0), (0.0, 1.2)]
    for c in centres[: int(rng.integers(0, 4))]:
        loops.append(_star(rng, c, 0.5, int(rng.integers(3, 24))))
    loops = [_distinct(np.round(loop, 1)) for loop in loops]
    if kind == "ulp":  # zeros stay: their neighbours are subnormal, refused by design
        loops = [np.where(loop == 0.0, 0.0, np.nextafter(
            loop, loop + rng.choice([-1.0, 1.0], loop.shape))) for loop in loops]
    elif kind == "offset":
        offset = 10.0 ** int(rng.integers(6, 16))
        loops = [loop + offset for loop in loops]
    elif kind == "scale":
        factor = 10.0 ** int(rng.integers(-8, 9))
        loops = [loop * factor for loop in loops]
    if seed % 7 == 6:  # now and then one hole on its own scale (a strongly graded domain)
        loops[-1] = loops[-1] * 1e-6 if len(loops) > 1 else loops[-1]
    case = {"seed": seed, "kind": kind, "loops": [loop.tolist() for loop in loops]}
    if kind == "poly":
        case["poly"] = _mutated_poly(rng, loops)
    return case


def _mutated_poly(rng, loops) -> str:
    points = np.concatenate(loops)
    lines = [f"{len(points)} 2 0 0"]
    lines += [f"{i + 1} {x!r} {y!r}" for i, (x, y) in enumerate(points.tolist())]
    segments, start = [], 0
    for loop in loops:
        n = len(loop)
        segments += [(start + k + 1, start + (k + 1) % n + 1) for k in range(n)]
        start += n
    lines.append(f"{len(segments)} 0")
    lines += [f"{k + 1} {a} {b}" for k, (a, b) in enumerate(segments)]
    lines.append("0")
    tokens = "\n".join(lines).split(" ")
    for _ in range(int(rng.integers(0, 4))):
        k = int(rng.integers(0, len(tokens)))
        tokens[k] = str(rng.choice(["-3", "1e14", "99999999999999999999999", "nan", "x",
                                    "0", "", "#", "1000000000000", tokens[k][:1]]))
    return " ".join(tokens)


# --- the worker: one case per line on stdin, one JSON result per line on stdout -----


def _enclosed_area(domain) -> float:
    """Exact shoelace sum over the boundary segments (interior constraints
    left out), each oriented with the domain on its left, rounded once: it
    needs no chaining into loops, so loops touching at a node are fine."""
    p = domain.points
    twice = sum((Fraction(p[a, 0]) * Fraction(p[b, 1]) - Fraction(p[b, 0]) * Fraction(p[a, 1])
                 for a, b in domain.segments[~domain.interior].tolist()), Fraction(0))
    return float(twice / 2)


def check_against_input(mesh, domain) -> str:
    """'' if ``mesh`` is a valid, conforming mesh of ``domain`` (its boundary
    possibly refined: conformity to ``mesh.domain``, the input's area, every
    input node present bit for bit); else what is wrong.  AssertionError from
    the oracles propagates."""
    import oracles as O

    # across an interior constraint the mesh has no neighbour (-1, by design):
    # there the neighbours are checked against that rule instead
    interior = mesh.domain.interior
    O.check_valid(mesh.points, mesh.triangles, None if interior.any() else mesh.neighbors)
    if interior.any():
        t, i = np.nonzero(mesh.neighbors < 0)
        tri = mesh.triangles
        edges = {frozenset(e) for e in np.column_stack([tri[t, (i + 1) % 3],
                                                        tri[t, (i + 2) % 3]]).tolist()}
        allowed = {frozenset(e) for e in mesh.domain.segments.tolist()}
        if not edges <= allowed:
            return "a triangle has no neighbour across an edge that is no segment"
        mesh_edges = {frozenset(e) for e in np.concatenate(
            [tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]).tolist()}
        inner = {frozenset(e) for e in mesh.domain.segments[interior].tolist()}
        if not inner <= mesh_edges:
            return "an interior constraint is not an edge of the mesh"
    boundary_segments = mesh.domain.segments[~interior]
    if np.bincount(boundary_segments.ravel()).max() <= 2:
        O.check_conforming(mesh.points, mesh.triangles, boundary_segments, rel=1e-9)
    else:  # loops touching at a node: the oracle takes closed simple loops only
        tri = mesh.triangles
        t, i = np.nonzero(mesh.neighbors < 0)
        edges = {frozenset(e) for e in np.column_stack([tri[t, (i + 1) % 3],
                                                        tri[t, (i + 2) % 3]]).tolist()}
        if not edges <= {frozenset(e) for e in mesh.domain.segments.tolist()}:
            return "a boundary edge of the mesh is no segment"
        area = float(np.abs(O.triangle_areas(mesh.points, tri)).sum())
        enclosed = _enclosed_area(mesh.domain)
        if abs(area - enclosed) > 1e-9 * enclosed:
            return f"the triangles cover {area!r}, the boundary encloses {enclosed!r}"
    # a refined boundary node can sit within an ulp of its input segment (no
    # float point lies on it exactly): the enclosed area moves by at most that
    # much times the perimeter
    area = _enclosed_area(domain)
    refined = _enclosed_area(mesh.domain)
    ends = domain.points[domain.segments]
    perimeter = float(np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1).sum())
    slack = 2.0 * perimeter * float(np.spacing(np.abs(domain.points).max()))
    if abs(refined - area) > slack + 1e-12 * area:
        return f"the refined boundary encloses {refined!r}, the input {area!r}"
    boundary = {tuple(p) for p in mesh.points[: mesh.n_boundary].tolist()}
    missing = [i for i, p in enumerate(domain.points.tolist()) if tuple(p) not in boundary]
    return f"input nodes {missing[:5]} are not boundary nodes of the mesh" if missing else ""


def _run_case(case: dict) -> dict:
    import bubblemesh as bm

    try:
        if case["kind"] == "poly":
            import tempfile

            with tempfile.TemporaryDirectory() as tmp:
                path = os.path.join(tmp, "case.poly")
                with open(path, "w", encoding="utf-8") as f:
                    f.write(case["poly"])
                domain = bm.Domain.from_poly(path)
        else:
            domain = bm.Domain.from_loops([np.array(loop) for loop in case["loops"]])
        for paper in (True, False):
            mesh = bm.mesh(domain, paper=paper)
            problem = check_against_input(mesh, domain)
            if problem:
                return {"outcome": "invalid", "detail": f"paper={paper}: {problem}"}
        return {"outcome": "mesh", "triangles": len(mesh.triangles)}
    except AssertionError as error:  # an oracle found the mesh invalid
        return {"outcome": "invalid", "detail": str(error)[:300]}
    except (bm.GeometryError, bm.MeshingError) as error:
        return {"outcome": type(error).__name__, "detail": str(error)[:200]}
    except (TypeError, ValueError) as error:
        if type(error).__module__.startswith("bubblemesh"):
            return {"outcome": type(error).__name__, "detail": str(error)[:200]}
        return {"outcome": "foreign", "detail": f"{type(error).__name__}: {error}"[:300]}
    except Exception as error:  # noqa: BLE001 - counting foreign exceptions is the point
        return {"outcome": "foreign", "detail": f"{type(error).__name__}: {error}"[:300]}


def worker() -> None:
    sys.path.insert(0, HERE)
    print(json.dumps({"ready": True}), flush=True)
    for line in sys.stdin:
        print(json.dumps(_run_case(json.loads(line))), flush=True)


# --- the campaign --------------------------------------------------------------------


class _Worker:
    def __init__(self):
        self.proc = subprocess.Popen([sys.executable, __file__, "--worker"], text=True,
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     stderr=subprocess.DEVNULL)
        self._read(timeout=600)  # imports and numba's cache

    def _read(self, timeout: float):
        import selectors

        sel = selectors.DefaultSelector()
        sel.register(self.proc.stdout, selectors.EVENT_READ)
        if not sel.select(timeout):
            return None
        line = self.proc.stdout.readline()
        return json.loads(line) if line else None

    def run(self, case: dict, timeout: float) -> dict:
        self.proc.stdin.write(json.dumps(case) + "\n")
        self.proc.stdin.flush()
        result = self._read(timeout)
        if result is None:
            alive = self.proc.poll() is None
            self.proc.kill()
            self.proc.wait()
            return {"outcome": "hang" if alive else "crash",
                    "detail": f"exit {self.proc.returncode}"}
        return result

    def close(self):
        if self.proc.poll() is None:
            self.proc.stdin.close()
            self.proc.wait(timeout=60)


def campaign(cases: int, seed: int = 0, timeout: float = 60.0, log=None) -> Counter:
    """Run ``cases`` cases from ``seed`` on; returns outcome counts.  Failures
    (crash, hang, foreign, invalid) are written to ``log`` as JSON lines."""
    counts: Counter = Counter()
    w = _Worker()
    try:
        for s in range(seed, seed + cases):
            case = make_case(s)
            result = w.run(case, timeout)
            counts[result["outcome"]] += 1
            if result["outcome"] in ("crash", "hang", "foreign", "invalid"):
                if log is not None:
                    log.write(json.dumps({"case": case, **result}) + "\n")
                if result["outcome"] in ("crash", "hang"):
                    w = _Worker()
    finally:
        w.close()
    return counts


FAILURES = ("crash", "hang", "foreign", "invalid")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cases", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--timeout", type=float, default=60.0, help="seconds per case")
    parser.add_argument("--log", default="fuzz-failures.jsonl")
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        worker()
        return 0
    started = time.time()
    with open(args.log, "w") as log:
        counts = campaign(args.cases, args.seed, args.timeout, log)
    failed = sum(counts[k] for k in FAILURES)
    print(f"{args.cases} cases in {time.time() - started:.0f} s: "
          + ", ".join(f"{k} {v}" for k, v in sorted(counts.items())))
    print(f"failures (crash, hang, foreign exception, invalid mesh): {failed}"
          + (f", see {args.log}" if failed else ""))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
