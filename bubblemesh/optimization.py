"""Physically-based mesh optimisation: paper §3, steps (a)-(e) of §3.6.

(a) §3.1 initial node bubbles: every radius of the §2 mesh times
    ``amplification`` (1.7), so that neighbouring bubbles overlap; §3.3 nearby
    bubbles: the nodes within ``rings`` (3) topological rings of the §2 mesh,
    fixed for all iterations (a CSR list built once).
(b) §3.2 position adjustment of interior nodes, eq. 7-8:
    x_i <- x_i + alpha * sum_j (r_i + r_j - l_ij) n_ji  over nearby j with
    r_i + r_j > l_ij, where n_ji is the unit vector from j to i: the overlap
    pushes i away from j (the paper's repulsive force).
(c) §3.4 size adjustment of interior nodes, eq. 9: r_p is the
    reciprocal-distance mean of the radii of the nearby bubbles that overlap it
    (r_i + r_p > l_pi); unchanged if none overlaps.
(d) repeat until the largest move relative to its node's radius is below
    ``tol``, or ``max_iterations``.
(e) §3.5 constrained Delaunay re-triangulation of the moved nodes.

Speed without changing the result: overlaps are looked for only among the
3-ring nodes within (1 + skin)(r_i + r_j) of each node (a Verlet list, as in
molecular dynamics), rebuilt as soon as some node's displacement plus radius
growth since the last build exceeds 0.9 skin r_i.  No pair outside the list can
overlap before that, and the list keeps the ring order, so every sum has the
same terms in the same order: ``skin=inf`` (no pruning) gives the same bits.

Boundary nodes and their radii never change.  Interior nodes never leave the
domain: a move is accepted only if an exact visibility walk in the (fixed) §2
mesh reaches the target without touching the boundary; otherwise the step is
halved, up to 4 times, and the node stays if none fits.  A target closer to
the node's §2 position than half a lower bound on that position's distance to
the boundary is inside without a walk (the disc of that radius is).  Updates are Jacobi
(every node reads the previous iterate), so the parallel kernel gives the same
bits as a serial run.
"""

import math
import numbers
from typing import Any

import numpy as np

from ._forces import move, resize
from ._inside import boundary_clearance
from ._mesh import Mesh, OptimizationStats
from ._rings import node_adjacency, ring_neighbors, vertex_triangles
from ._verlet import VerletLists
from .compiling import maybe_notice
from .errors import GeometryError, MeshingError
from .timing import PhaseClock
from .triangulation import constrained_delaunay

_NO_MOMENTUM = np.zeros((1, 2))  # the paper's step: move() never reads it

__all__ = ["optimize"]


def optimize(mesh, *, amplification=1.7, rings=3, alpha=0.1, max_iterations=200, tol=1e-3,
             skin=0.3, progress=False):
    """Paper §3: move interior nodes by bubble overlap forces, adjust their
    bubbles, then re-triangulate (constrained Delaunay).

    Parameters are the paper's: ``amplification`` 1.7 (§3.1), ``rings`` 3
    (§3.3), ``alpha`` 0.1 (eq. 7).  The iterations stop when every node moved
    less than ``tol`` times its radius, or after ``max_iterations``.  Returns a
    new :class:`Mesh`; ``stats`` gains ``iterations``, ``max_displacement``
    (relative to the radius, last iteration), ``blocked_moves`` (node moves,
    summed over iterations, that found no step inside the domain),
    ``list_builds``, ``list_layouts``, ``optimize_seconds`` and
    ``optimize_phases`` (seconds in rings, setup, lists, move, resize,
    retriangulation).  ``skin`` only trades Verlet-list rebuilds against list
    length; the result does not depend on it (module
    docstring).  The returned ``radii`` are the §3 bubbles: every radius
    amplified (§3.1), the boundary ones then fixed, the interior ones from
    eq. 9 (the paper's panel (d), "optimised node bubbles")."""
    if not isinstance(mesh, Mesh):
        raise TypeError(f"optimize: mesh must be a bubblemesh.Mesh, got {type(mesh).__name__}")
    _check_parameters(amplification=amplification, alpha=alpha, skin=skin, rings=rings,
                      max_iterations=max_iterations, tol=tol)
    mesh.check()
    with maybe_notice(progress):
        return _optimize(mesh, amplification, rings, alpha, max_iterations, tol, skin, progress)


def _optimize(mesh, amplification, rings, alpha, max_iterations, tol, skin, progress):
    clock = PhaseClock()
    n_b = mesh.n_boundary
    P0 = np.ascontiguousarray(mesh.points)
    tri0 = np.ascontiguousarray(mesh.triangles)
    nbr0 = np.ascontiguousarray(mesh.neighbors)
    n = len(P0)
    ring_ptr, ring_idx = ring_neighbors(*node_adjacency(tri0, nbr0, n), n, int(rings))
    clock.lap("rings")
    X = P0.copy()
    R = np.asarray(mesh.radii, dtype=np.float64) * amplification
    home = vertex_triangles(tri0, n)
    clearance = boundary_clearance(P0, np.asarray(mesh.segments), n_b,
                                   reach=4.0 * float(R.max(initial=0.0)))
    Xn, Rn = X.copy(), R.copy()
    iterations, largest, blocked = 0, 0.0, 0
    bar = _progress_bar(progress, max_iterations)
    lists = VerletLists(ring_ptr, ring_idx, n_b, skin)
    expired = True  # no lists yet
    reuse = False  # 1 / l stored for these lists and positions?
    clock.lap("setup")
    while iterations < max_iterations:
        iterations += 1
        if expired:
            lists.build(X, R)
            reuse = False
            clock.lap("lists")
        expired, stuck, largest = move(X, R, Xn, home, *lists.arrays, reuse, n_b, alpha, P0,
                                        tri0, nbr0, clearance, lists.X0, lists.R0, lists.skin,
                                        _NO_MOMENTUM, 0.0)
        blocked += stuck
        clock.lap("move")
        if expired:
            lists.build(Xn, R)
            clock.lap("lists")
        expired = resize(Xn, R, Rn, *lists.arrays, n_b, lists.X0, lists.R0, lists.skin) > 0
        reuse = True
        clock.lap("resize")
        X, Xn, R, Rn = Xn, X, Rn, R
        if bar is not None:
            bar.update(1)
            bar.set_postfix(max_move=f"{largest:.2e}")
        if largest < tol:
            break
    if bar is not None:
        bar.close()
    builds, layouts = lists.builds, lists.layouts
    # not needed by the re-triangulation: freed to lower the peak memory
    del lists, ring_ptr, ring_idx, Xn, Rn, home, clearance
    triangles, neighbors = _retriangulate(X, mesh.segments)
    clock.lap("retriangulation")
    stats = OptimizationStats(
        iterations=iterations, max_displacement=float(largest), blocked_moves=int(blocked),
        list_builds=builds, list_layouts=layouts, amplification=amplification, rings=rings,
        alpha=alpha, seconds=clock.total(), phases=dict(clock.seconds))
    return Mesh(points=X, triangles=triangles, neighbors=neighbors, radii=R,
                segments=mesh.segments, n_boundary=n_b, domain=mesh.domain,
                generation=mesh.generation, optimization=stats)


# Accepted ranges: beyond them two nodes can be pushed onto one point (alpha
# 0.4 and more) or nearly every mesh degenerates (amplification above 2).
MAX_ALPHA, MAX_AMPLIFICATION, MAX_RINGS = 0.3, 2.0, 6


def _real(value: Any) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def _check_parameters(*, amplification: Any, alpha: Any, skin: Any, rings: Any,
                      max_iterations: Any, tol: Any) -> None:
    """ValueError naming the first parameter outside its accepted range."""
    rules = [
        ("amplification", amplification, lambda v: 0 < v <= MAX_AMPLIFICATION,
         f"in (0, {MAX_AMPLIFICATION}]"),
        ("alpha", alpha, lambda v: 0 < v <= MAX_ALPHA, f"in (0, {MAX_ALPHA}]"),
        ("skin", skin, lambda v: v > 0, "> 0 (inf disables the lists)"),
        ("rings", rings, lambda v: isinstance(v, numbers.Integral) and 1 <= int(v) <= MAX_RINGS,
         f"an integer in 1..{MAX_RINGS}"),
        ("max_iterations", max_iterations,
         lambda v: isinstance(v, numbers.Integral) and int(v) >= 0, "an integer >= 0"),
        ("tol", tol, lambda v: math.isfinite(v) and v >= 0, "finite and >= 0"),
    ]
    for name, value, ok, expected in rules:
        if not (_real(value) and ok(value)):
            raise ValueError(f"optimize: {name} must be {expected}, got {value!r}")


def _retriangulate(points, segments):
    """(e) §3.5; a failure here means two nodes met, which is reported."""
    try:
        return constrained_delaunay(points, segments)
    except GeometryError as error:
        raise MeshingError(f"re-triangulation after optimisation failed: {error}") from error


def _progress_bar(progress, total):
    if not progress:
        return None
    from tqdm.auto import tqdm

    return tqdm(total=total, desc="optimize (§3)", unit="it")
