"""Automatic Delaunay mesh generation: paper §2, steps (a)-(f) of §2.4.

(a) constrained Delaunay triangulation of the refined boundary (§2.1);
(b) node bubbles on the boundary (eq. 1-2), element bubbles at the centroids
    (eq. 3-4) and bubble densities D_e = A_e / A_m (eq. 5);
(c) take the triangle of smallest density from a priority queue (a 4-ary heap
    of (D_e, triangle id) with lazy invalidation: an entry is live only while
    its key equals the current density of its triangle slot; a re-used slot
    leaves its old entries to be skipped when popped (an old entry whose key
    happens to equal the new density stands for the new triangle exactly);
    ties are broken by the smaller triangle id, so the run is deterministic);
(d) create a node at its centroid, with the element bubble's radius r_e;
(e) insert it by Bowyer-Watson (§2.2): the cavity grows from that triangle
    through neighbours whose circumcircle contains the node, never across the
    boundary; the new triangles get their bubbles and enter the queue;
(f) stop the first time the total element-bubble area reaches the domain area,
    sum A_e >= A_geo (eq. 6); sum A_e is kept incrementally with an error-free
    (two-sum) accumulator.

A bound that always holds: every r_e interpolates radii that are >= the
smallest boundary radius r_min, each insertion adds two triangles, so eq. 6
holds after at most A_geo / (2 pi r_min^2) + 1 insertions.  Going past that
bound raises MeshingError instead of looping.
"""

import math
import numbers
import os
from typing import Any

import numpy as np

from ._frontal import frontal_loop, init_front
from ._insertion import S_CAVITY, S_HEAP, S_INSERTIONS, S_NPTS, S_NTRI, init_queue, insertion_loop
from ._mesh import GenerationStats, Mesh
from ._renumber import spatial_renumbering
from ._status import CHUNK_DONE, NEED_CAPACITY, STOP_MAX_INSERTIONS, STOP_POPULATION, raise_for
from ._workspace import Workspace, fits_int32
from .bubbles import boundary_radii
from .compiling import maybe_notice
from .domain import Domain
from .errors import MeshingError
from .timing import PhaseClock
from .triangulation import constrained_delaunay

__all__ = ["generate", "generate_sized"]

# initial triangle capacity, as a multiple of the expected count (arrays double
# when full, so this only trades memory against copies), and at most
INITIAL_CAPACITY = 1.1
MAX_INITIAL_TRIANGLES = 1 << 24
# memory per triangle: the §2 records, queue and scratch, and the returned arrays
BYTES_PER_TRIANGLE = 256


def _physical_memory() -> int | None:
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):
        return None


def refuse_beyond_memory(count: float, asker: str, bound: str, advice: str) -> None:
    """MeshingError when ``count`` triangles would not fit in physical memory."""
    memory = _physical_memory()
    if memory is not None and count * BYTES_PER_TRIANGLE > memory:
        raise MeshingError(
            f"generation: {asker} asks for {bound} {count:.3g} triangles "
            f"(~{count * BYTES_PER_TRIANGLE / 2**30:.3g} GiB, this machine has "
            f"{memory / 2**30:.3g} GiB): {advice}")


def _check_fits(area_geo: float, radii: np.ndarray) -> None:
    """MeshingError before allocating when even the fewest triangles eq. 6 could
    stop at (each bubble is at most pi r_max^2) do not fit in memory."""
    refuse_beyond_memory(
        area_geo / (math.pi * float(radii.max()) ** 2), "the boundary", "at least",
        f"its spacing (largest node bubble {float(radii.max()):.3g}) is far finer than the "
        f"domain (area {area_geo:.3g}); coarsen the boundary or pass max_insertions")


def _check_field_fits(points: np.ndarray, tri: np.ndarray, size_field) -> None:
    """MeshingError before §2 when the triangles a size field asks for do not
    fit in memory.  The count is estimated on the initial triangulation, each
    triangle's area over the equilateral area of the largest h at its corners
    and centroid: an underestimate wherever h varies inside a triangle, so a
    mesh that fits is never refused."""
    corners = points[tri]
    u, v = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    area = 0.5 * np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0])
    samples = np.concatenate([corners, corners.mean(axis=1, keepdims=True)], axis=1)
    h = size_field(samples.reshape(-1, 2)).reshape(len(tri), 4).max(axis=1)
    refuse_beyond_memory(
        float(np.sum(area / (math.sqrt(3.0) / 4.0 * h * h))), "the size field", "about",
        f"its sizes (smallest {float(size_field.values.min()):.3g}) are far finer than the "
        "domain; pass a larger size")


def _insertion_bound(domain_area, radii):
    """The a-priori bound on insertions (module docstring)."""
    r_min = float(radii.min())
    bound = domain_area / (2.0 * math.pi * r_min * r_min)
    return int(math.ceil(min(bound, 2.0**62))) + 1  # no run gets near; the kernel's int64


def generate(domain, *, max_insertions=None, progress=False):
    """Paper §2: the Delaunay mesh of ``domain`` with bubble-controlled node
    insertion, stopped by eq. 6.

    ``max_insertions`` stops earlier (after at most that many insertions), so the
    population criterion can be checked from outside.  ``progress`` shows a tqdm
    bar.  Returns a :class:`Mesh` whose ``stats`` hold ``insertions``,
    ``bubble_area`` (sum A_e), ``domain_area`` (A_geo) and ``stop`` ("population"
    or "max_insertions") and ``phases`` (seconds in boundary_cdt, setup,
    insertion, renumbering)."""
    _check_arguments("generate", domain, max_insertions)
    with maybe_notice(progress):
        return _generate(domain, max_insertions, progress, None)


def _check_arguments(name: str, domain: Any, max_insertions: Any) -> None:
    if not isinstance(domain, Domain):
        raise TypeError(f"{name}: domain must be a bubblemesh.Domain, got "
                        f"{type(domain).__name__}")
    if max_insertions is not None and not (
            isinstance(max_insertions, numbers.Integral) and int(max_insertions) >= 0):
        raise ValueError(f"{name}: max_insertions must be an integer >= 0 or None, "
                         f"got {max_insertions!r}")


def generate_sized(domain, size_field, *, max_insertions=None, progress=False, seeds=None,
                   frontal=False):
    """§2 driven by a size field as well as by the boundary (``bubblemesh.mesh``,
    not the paper): each element bubble is the eq. 2 radius of an equilateral
    triangle of side h(centroid) instead of eq. 3's interpolation, so eq. 6
    fills the domain to the field.  ``size_field`` is a :class:`bubblemesh.sizing.SizeField`;
    ``seeds`` (S, 2), points strictly inside the domain, are nodes of the
    initial triangulation with the field's bubbles (movable, numbered right
    after the boundary nodes, in order).  ``frontal``: insert frontally
    (:mod:`bubblemesh._frontal`) until every triangle meets its bubble,
    instead of at centroids until eq. 6."""
    from .sizing import SizeField

    _check_arguments("generate_sized", domain, max_insertions)
    if not isinstance(size_field, SizeField):
        raise TypeError(f"generate_sized: size_field must be a SizeField, got "
                        f"{type(size_field).__name__}")
    return _generate(domain, max_insertions, progress, size_field, seeds, frontal)


def _kernel_field(size_field):
    """(capped, field arrays, eq. 2 factor, scratch stack, smallest radius) for
    the kernel; a small dummy field when there is none (the paper's §2)."""
    from .sizing import _EQUILATERAL_RADIUS, STACK_SIZE, SizeField

    stack = np.full(STACK_SIZE, -1, np.int64)
    if size_field is None:
        dummy = SizeField(np.zeros((1, 2)), np.ones(1), gradation=0.0)
        return False, dummy.kernel_args(), 0.0, stack, math.inf
    r_min = _EQUILATERAL_RADIUS * float(size_field.values.min())
    return True, size_field.kernel_args(), _EQUILATERAL_RADIUS, stack, r_min


def _generate(domain, max_insertions, progress, size_field, seeds=None, frontal=False):
    """§2 of generate / generate_sized (the arguments checked)."""
    clock = PhaseClock()
    points = np.asarray(domain.points, dtype=np.float64)
    radii = boundary_radii(points, domain.loops)  # (b) eq. 1-2
    if seeds is not None and len(seeds):
        seeds = np.asarray(seeds, dtype=np.float64).reshape(-1, 2)
        points = np.concatenate([points, seeds])
        radii = np.concatenate([radii, size_field.radius(seeds)])
    tri, nbr = constrained_delaunay(points, domain.segments)  # (a)
    clock.lap("boundary_cdt")
    lattice = seeds is not None and len(seeds) > len(domain.points)  # the bulk is there
    if size_field is not None and max_insertions is None and not lattice:
        _check_field_fits(points, np.asarray(tri), size_field)
    capped, field, factor, stack, r_field = _kernel_field(size_field)
    area_geo = float(domain.area)
    bound = _insertion_bound(area_geo, radii if not capped else
                             np.minimum(radii, r_field))
    if frontal:  # no eq. 6: the front's nodes keep about h apart, a wide margin
        bound = 4 * bound
    limit = bound if max_insertions is None else min(int(max_insertions), bound)
    if max_insertions is None:
        _check_fits(area_geo, radii)
    expected = int(area_geo / float(np.mean(math.pi * radii**2))) + len(tri)
    expected = min(expected, len(tri) + 2 * limit)
    t_cap = max(64, min(int(INITIAL_CAPACITY * expected), MAX_INITIAL_TRIANGLES) + 2 * len(tri))
    if lattice:  # the mesh will be about the initial one
        t_cap = max(64, int(INITIAL_CAPACITY * len(tri)) + 2 * len(domain.points))
    wide = not fits_int32(t_cap)
    try:
        ws = Workspace(points, radii, tri, nbr, len(points) + t_cap // 2 + 16, t_cap, wide)
    except MemoryError as error:
        raise MeshingError(f"generation: no memory for {t_cap} triangles") from error
    acc = np.zeros(2)
    state = np.zeros(6, np.int64)
    state[S_NPTS] = len(points)
    state[S_NTRI] = len(tri)
    if frontal:
        state[S_HEAP] = init_front(ws.P, ws.tri, ws.nbr, len(tri), ws.r_e, ws.density, ws.keys,
                                   ws.ids, acc, factor, field, stack, _limits())
        step = _frontal_step(factor, field, stack, _limits())
    else:
        state[S_HEAP] = init_queue(ws.P, ws.R, ws.tri, len(tri), ws.r_e, ws.density,
                                   ws.keys, ws.ids, acc, capped, field, factor, stack)
        step = _centroid_step(area_geo, (capped, field, factor, stack))
    bar = _progress_bar(progress, None if lattice else expected // 2)  # seeds: no estimate
    clock.lap("setup")
    try:
        status = _run(ws, state, acc, limit, bar, step)
    finally:
        if bar is not None:
            bar.close()
    clock.lap("insertion")
    if status == STOP_MAX_INSERTIONS and (max_insertions is None or limit < max_insertions):
        raise MeshingError(f"generation reached its insertion bound {bound} without eq. 6")
    npts, ntri = int(state[S_NPTS]), int(state[S_NTRI])
    n_seeds = 0 if seeds is None else len(seeds)  # kept after the boundary nodes
    points, radii, triangles, neighbors = spatial_renumbering(
        ws.P[:npts], ws.R[:npts], ws.tri[:ntri], ws.nbr[:ntri], len(domain.points) + n_seeds)
    clock.lap("renumbering")
    stats = GenerationStats(
        insertions=int(state[S_INSERTIONS]), cavity_triangles=int(state[S_CAVITY]),
        bubble_area=float(acc[0] + acc[1]), domain_area=area_geo,
        stop=("front" if frontal else "population") if status == STOP_POPULATION
        else "max_insertions",
        seconds=clock.total(), phases=dict(clock.seconds))
    return Mesh(points=points, triangles=triangles, neighbors=neighbors, radii=radii,
                segments=np.asarray(domain.segments, dtype=np.int64),
                n_boundary=len(domain.points), domain=domain, generation=stats)


def _centroid_step(area_geo, sizing):
    """The paper's kernel (centroids until eq. 6) as ``step(ws, state, acc, limit, chunk)``."""
    def step(ws, state, acc, limit, chunk):
        return insertion_loop(*ws.kernel_args(), state, acc, area_geo, limit, chunk, ws.mark,
                              ws.cav, ws.bnd, ws.newt, ws.vstart, *sizing)
    return step


def _frontal_step(factor, field, stack, limits):
    """The frontal kernel (:mod:`bubblemesh._frontal`) as ``step``."""
    def step(ws, state, acc, limit, chunk):
        return frontal_loop(*ws.kernel_args(), state, acc, limit, chunk, ws.mark, ws.cav,
                            ws.bnd, ws.newt, ws.vstart, factor, field, stack, limits)
    return step


def _limits():
    """The frontal kernel's acceptance thresholds, inside and on the walls."""
    from . import _frontal

    return np.array([_frontal.ACCEPT, _frontal.WALL_ACCEPT,
                     math.cos(math.radians(_frontal.CORNER_OPEN))])


def _run(ws, state, acc, limit, bar, step):
    """Call the kernel until it stops; every call inserts at least one node or
    follows a growth that did, so the loop ends within ``limit`` insertions."""
    chunk = 20000 if bar is not None else 1 << 62
    grown_without_progress = False
    while True:
        before = int(state[S_INSERTIONS])
        status = step(ws, state, acc, limit, chunk)
        progressed = int(state[S_INSERTIONS]) > before
        if bar is not None:
            bar.update(int(state[S_INSERTIONS]) - before)
        if status == NEED_CAPACITY:
            if grown_without_progress and not progressed:
                raise MeshingError("generation: the arrays grew but no insertion followed")
            grown_without_progress = not progressed
            try:
                ws.grow()
            except MemoryError as error:
                raise MeshingError(f"generation: out of memory after {before} insertions, "
                                   f"growing to {2 * len(ws.tri)} triangles") from error
        elif status == CHUNK_DONE:
            continue
        elif status < 0:
            raise_for(status, "generation")
        else:
            return status


def _progress_bar(progress, total):
    if not progress:
        return None
    from tqdm.auto import tqdm

    return tqdm(total=total, desc="generate (§2)", unit="node")
