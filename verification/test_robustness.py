"""Inputs that once crashed the interpreter or escaped as foreign exceptions:
each must now give a valid mesh or a bubblemesh exception naming what and
where.  Oracles: the exact validity and conformity checks of ``oracles``."""

from __future__ import annotations

import math
import subprocess
import sys
import warnings
from fractions import Fraction

import numpy as np
import oracles as O
import pytest
import strategies as S

import bubblemesh as bm

# polygons whose rounded centroids land exactly on a vertex (eq. 3 divided by 0)
_ON_VERTEX = {
    "decimal grid": [[(0.6000000000000001, 0.7000000000000001), (0.5, 0.9),
                      (0.7000000000000001, 0.5), (0.5, 1.1)]],
    "sliver": [[(5.0, 6.0), (3.0, 3.0), (7.000000000000001, 9.0)]],
}


def _offset_square():
    """An 8x8 square spaced 0.5 at offset 1e15: neighbours 4 ulps apart."""
    x = np.arange(0.0, 8.0, 0.5)
    zero, eight = np.zeros_like(x), np.full_like(x, 8.0)
    ring = np.concatenate([np.column_stack([x, zero]), np.column_stack([eight, x]),
                           np.column_stack([8.0 - x, eight]), np.column_stack([zero, 8.0 - x])])
    return [ring + 1e15]


@pytest.mark.parametrize("loops", [pytest.param(_ON_VERTEX["decimal grid"],
                                                marks=pytest.mark.heavy),
                                   _ON_VERTEX["sliver"],
                                   pytest.param(_offset_square(), marks=pytest.mark.heavy)],
                         ids=[*_ON_VERTEX, "offset 1e15"])
def test_centroids_on_a_vertex_give_a_valid_mesh(loops):
    domain = bm.Domain.from_loops(loops)
    for mesh in (bm.generate(domain), bm.mesh(domain, paper=True), bm.mesh(domain)):
        O.check_valid(mesh.points, mesh.triangles, mesh.neighbors)
        # the areas exactly (a sliver's float area is all rounding), then the rest
        # against the mesh's own boundary (the default mesher refines it)
        segments = mesh.domain.segments
        assert _exact_area(mesh.points, mesh.triangles) == \
            _exact_polygon_area(mesh.domain.points, segments)
        O.check_conforming(mesh.points, mesh.triangles, segments, rel=1.0)
        inputs = {tuple(p) for p in domain.points.tolist()}
        assert inputs <= {tuple(p) for p in mesh.points[: mesh.n_boundary].tolist()}


def _fractions(points):
    return [(Fraction(float(x)), Fraction(float(y))) for x, y in points]


def _exact_area(points, triangles):
    """Twice the area of all triangles, exactly."""
    P = _fractions(points)
    total = Fraction(0)
    for a, b, c in triangles:
        (ax, ay), (bx, by), (cx, cy) = P[a], P[b], P[c]
        total += (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
    return total


def _exact_polygon_area(points, segments):
    """Twice the area enclosed by the oriented segments (shoelace), exactly."""
    P = _fractions(points)
    return sum((P[v][0] * P[w][1] - P[w][0] * P[v][1] for v, w in segments), Fraction(0))


@pytest.fixture(scope="module")
def square():
    return bm.generate(bm.Domain.from_loops(list(S.square_with_hole().loops)))


_BROKEN = {  # kind: (how the generated mesh is broken, words of the message)
    "node id out of range": ("t = m.triangles.copy(); t[5, 1] = len(m.points) + 10; "
                             "b = replace(m, triangles=t)", "out of range"),
    "garbage neighbours": ("b = replace(m, neighbors=np.random.default_rng(0).integers("
                           "-5, 10**6, m.neighbors.shape))", "neighbour"),
    "last triangle dropped": ("b = replace(m, triangles=m.triangles[:-1])", "shape"),
    "both dropped": ("b = replace(m, triangles=m.triangles[:-1], neighbors=m.neighbors[:-1])",
                     "neighbour"),
    "clockwise": ("b = replace(m, triangles=m.triangles[:, [0, 2, 1]])", "neighbour"),
    "nan point": ("p = m.points.copy(); p[9] = np.nan; b = replace(m, points=p)", "finite"),
    "zero radius": ("b = replace(m, radii=0 * m.radii)", "radii"),
    "n_boundary": ("b = replace(m, n_boundary=len(m.points) + 1)", "n_boundary"),
}


def test_a_broken_mesh_is_refused_before_any_kernel_reads_it():
    """In a child process, so that a kernel reading out of bounds is a failed
    test (the child's signal), not a crashed test run."""
    script = [
        "import numpy as np, bubblemesh as bm", "from dataclasses import replace",
        "t = np.linspace(0, 2 * np.pi, 40, endpoint=False)",
        "m = bm.generate(bm.Domain.from_loops([np.column_stack([np.cos(t), np.sin(t)])]))",
    ]
    for breaking, _ in _BROKEN.values():
        script += [f"{breaking}", "try:", "    bm.optimize(b); print('accepted')",
                   "except Exception as e: print(type(e).__name__, '|', e, flush=True)"]
    run = subprocess.run([sys.executable, "-c", "\n".join(script)], capture_output=True,
                         text=True, timeout=600)
    assert run.returncode == 0, f"the child died ({run.returncode}): {run.stderr[-2000:]}"
    lines = run.stdout.splitlines()
    assert len(lines) == len(_BROKEN), run.stdout
    for (kind, (_, words)), line in zip(_BROKEN.items(), lines):
        assert line.startswith("GeometryError |") and words in line, f"{kind}: {line}"


def test_a_generated_mesh_passes_the_check(square):
    square.check()  # must not raise: the check accepts what generate makes


@pytest.mark.parametrize("thing", [None, "mesh.vtu", 3.0])
def test_optimize_and_generate_want_their_own_types(thing, square):
    with pytest.raises(TypeError, match="must be a bubblemesh.Mesh"):
        bm.optimize(thing)
    with pytest.raises(TypeError, match="must be a bubblemesh.Domain"):
        bm.generate(thing)
    with pytest.raises(TypeError, match="must be a bubblemesh.Mesh"):
        bm.optimize(square.domain)


@pytest.mark.heavy
def test_a_boundary_finer_than_memory_allows_is_refused_up_front():
    t = np.linspace(0.0, 2.0 * np.pi, 100_000, endpoint=False)
    domain = bm.Domain.from_loops([np.column_stack([np.cos(t), np.sin(t)])])
    with pytest.raises(bm.MeshingError, match=r"at least .* triangles .*GiB"):
        bm.generate(domain)
    only_boundary = bm.generate(domain, max_insertions=0)  # sized for what it builds
    assert len(only_boundary.points) == 100_000 and only_boundary.insertions == 0


def test_a_domain_beyond_double_precision_s_range_is_refused_in_one_line():
    """A triangle of base 1 reaching 1e14 away: a graded mesh over 14 orders
    of magnitude is refused by bm.mesh (quickly, naming the span and the
    short segment); 1e4 is meshed, valid."""
    far = bm.Domain.from_loops([[(0.0, 0.0), (1.0, 0.0), (0.5, 1e14)]])
    with pytest.raises(bm.MeshingError,
                       match=r"^mesh: the domain spans 1e\+14 but its segment from \(0\.0, 0\.0\) "
                       r"to \(1\.0, 0\.0\) is 1 long[^\n]*$"):
        bm.mesh(far)
    near = bm.Domain.from_loops([[(0.0, 0.0), (1.0, 0.0), (0.5, 1e4)]])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", bm.QualityWarning)
        m = bm.mesh(near)
    O.check_valid(m.points, m.triangles, m.neighbors)


def test_nearly_coincident_nodes_are_named_where_they_break_the_scale():
    """A channel wall with a half-circle bump made with cos/sin: sin(pi) is
    3.7e-17, not 0, so the bump's end and the wall's corner are two nodes
    3.7e-17 apart.  bm.mesh refuses it naming both nodes, not only a size."""
    t = np.linspace(0.0, np.pi, 40)
    bump = np.column_stack([2.0 + 0.3 * np.cos(t), 0.3 * np.sin(t)])[::-1]
    loop = np.vstack([[(-6.0, 0.0), (1.7, 0.0)], bump, [(6.0, 0.0), (6.0, 3.0), (-6.0, 3.0)]])
    apart = math.hypot(*(loop[1] - loop[2]))
    assert 0.0 < apart < 1e-16
    with pytest.raises(bm.MeshingError) as refused:
        bm.mesh(bm.Domain.from_loops([loop]))
    message = str(refused.value)
    assert "\n" not in message
    a, b = (f"({x!r}, {y!r})" for x, y in loop[1:3].tolist())
    assert f"{a} to {b}" in message or f"{b} to {a}" in message
    assert f"is {apart:.3g} long" in message


@pytest.mark.heavy
@pytest.mark.parametrize("exponent", [-40, 40])
def test_meshes_of_a_domain_scaled_by_a_power_of_two_are_scaled_bit_for_bit(exponent):
    """Scaling a domain and its sizes by 2^k scales every float of the
    computation exactly, so no absolute tolerance may tell the two apart:
    bm.mesh (a constant and a graded callable size) and the paper's
    bm.generate + bm.optimize give the same triangles, and points that are
    those of the unscaled mesh times 2^k bit for bit."""
    square = np.array([(0, 0), (1, 0), (1, 1), (0, 1)], float)
    hole = np.array([(0.3, 0.3), (0.3, 0.6), (0.6, 0.6), (0.6, 0.3)], float)

    def meshes(k):
        s = 2.0**k
        domain = bm.Domain.from_loops([square * s, hole * s])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", bm.QualityWarning)
            return [bm.mesh(domain, size=0.1 * s),
                    bm.mesh(domain, size=lambda xy: s * (0.04 + 0.2 * np.ldexp(xy[:, 0], -k))),
                    bm.optimize(bm.generate(domain))]

    for plain, scaled in zip(meshes(0), meshes(exponent), strict=True):
        assert np.array_equal(plain.triangles, scaled.triangles)
        assert np.array_equal(np.ldexp(plain.points, exponent), scaled.points)
