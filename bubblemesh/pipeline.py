"""The robust default mesher behind :func:`bubblemesh.mesh` (the paper's §2 and §3
made safe for ordinary input; ``paper=True`` runs the paper unchanged).

1. Size: a graded :class:`~bubblemesh.sizing.SizeField` from the input spacing,
   the feature size and the user's ``size`` / ``max_area``; the boundary is
   split to it (:func:`~bubblemesh.refinement.refine_boundary`, input nodes kept
   bit for bit, each segment into the nearest whole number of pieces of
   length h), which makes the *refined boundary* §2.1 assumes; the walls
   of corners sharper than GRADE_ANGLE get nodes in geometric progression
   from the corner (:mod:`bubblemesh._wedges`), so the wedge fills with a
   zigzag of similar triangles instead of slivers.  Where the longest walls
   face each other across a straight channel (:mod:`bubblemesh._channel`),
   they are cut for whole rows across it instead, and the frontal lattice is
   laid in those rows.
2. §2 (:func:`~bubblemesh.generation.generate_sized`): eq. 1-6 with every
   element bubble taken from the field (not eq. 3), so the interior follows
   the field: the boundary spacing growing inward at the gradation rate.  The
   initial triangulation holds frontal seeds (:mod:`bubblemesh._seeds`): the
   apexes of equilateral triangles on the boundary edges where they have room,
   and a node on the bisector of each corner that two triangles fit best.
   Where eq. 6 is met while triangles still span the domain (fine walls
   grading to a far larger size inside: the first needles' bubbles are the
   inside's), §2 runs frontally instead (:func:`_stretched`).
3. A stable §3: the eq. 7-8 overlap forces with the node bubbles anchored at
   their §2 radii (amplified, §3.1; eq. 9 is not applied, so radii cannot
   drift; the frontal seeds hold still like the boundary), each step plus
   ``momentum`` times the node's last move (heavy ball),
   stopped when the largest move falls below ``tol`` times the radius;
   the §3.5 re-triangulation; then quality-guarded smoothing
   (:mod:`bubblemesh._smoothing`) alternating with re-triangulation; then
   settling: size-weighted ODT alternating with re-triangulation, valence and
   quality edge flips, corner splits, gradient steps on each star's mean radius
   ratio (a compass search where they are blocked).  Last (after the area
   bound's insertions, if any), edge flips judged after relaxing the nodes
   around them (:mod:`bubblemesh._relaxed_flips`: they move valence defects
   a single flip cannot pay for), the compass search, up to the mesh's
   minimum before them, on the stars they left below it, and gradient steps
   on the star means around them.  Very last, the patches around the
   triangles below REPAIR_BELOW are re-triangulated with a node inserted or
   removed where that lifts their worst ratio without lowering the mean
   (:mod:`bubblemesh._patch_repair`: a row one node short, as in a gap
   between a hole and a wall, has no good positions to move to); where the
   count window stops that, a node is in effect moved there from where the
   mesh is most crowded.  Once the mesh is chosen (step 4), in meshes of at
   most BALANCE_BELOW elements, nodes are swapped while that raises the
   mean: a point inserted where the mesh is sparsest, a node removed where
   it is most crowded, the count unchanged (:func:`_swapped`); then free
   nodes are removed while each raises the mean, the count kept within
   PRUNE_WINDOW under the field's and PRUNE_SHARE under its own
   (:func:`_pruned`); where its smallest ratio is below REPAIR_BELOW, the
   repair of the worst triangles runs once more, kept if it lifts it
   (:func:`_mended`).  In meshes of
   at most FINAL_BELOW elements the free nodes around the worst triangles
   move together to lift their smallest ratio (:mod:`bubblemesh._minmax`:
   one node alone is often held there by its neighbours), then a last sweep
   of gradient steps on every free node's star mean (:func:`_polished`).
   After the flips the mesh is valid and conforming (every segment an edge,
   boundary nodes unmoved) but in general no longer constrained-Delaunay.  Final
   guarantee: the result's smallest radius ratio is never below the §2
   mesh's; if it were, the nodes of the offending triangles go back to their
   §2 positions, and as a last resort the §2 mesh itself is smoothed.
4. With ``insertion="auto"`` a mesh of at most BOTH_BELOW elements is
   made twice more: one that took centroid insertion by frontal insertion
   and by centroid insertion without the frontal seeds, one that took
   frontal insertion by centroid insertion with and without them; the
   best of the three is returned (:func:`_better`: fewest elements below 0.7,
   then a count within COUNT_TOL of the size field's
   (:func:`~bubblemesh.sizing.field_count`), then a higher mean with no lower
   minimum, means within MEAN_TIE ranked by their minimum): on small
   domains either insertion can win by where its seams fall, and where walls
   dominate the seeds' first row can overshoot the field's count.  Where
   the mesh with the higher mean loses, it is judged again after the last
   steps of step 3 (:func:`_judged`: they often lift the minimum that held
   it back).  One of
   the other two, or a frontal first mesh, that loses with more than
   BOTH_COUNT more elements than the field's count or the winner's,
   whichever is fewer, is made again on the
   user's sizes scaled to bring it back to that (:func:`_matched`: a front
   fills a narrow strip two rows deep, more than the field's integral, and
   coarsens the rest to pay for it, as Gmsh tuned to a count does), under
   the user's area bounds, and taken if it ranks better the same way with a
   mean at least as high (within MEAN_TIE).  A
   channel's mesh of at most CHANNEL_BOTH_BELOW elements is made again on the
   plain walls, and kept only if better the same way.  A mesh of at most
   STEEPER_BELOW elements with more than COUNT_AIM over the field's count
   (walls graded from fine arcs or holes fill with more elements than the
   field's integral, the more the steeper they grade) is made again on the
   gradation whose field asks for that much fewer (:func:`_steeper_gradation`),
   its three meshes and it judged against the asked field's count.
5. Corners sharper than :data:`SHARP_ANGLE` (where no triangle can reach a
   radius ratio of 0.7) are reported: a :class:`QualityWarning` and the
   ``warnings`` field of the returned mesh's generation record; so are the
   finished mesh's triangles below 0.7 that touch no such corner
   (:func:`_reported`).
"""

from __future__ import annotations

import math
import numbers
import warnings
from dataclasses import dataclass, replace

import numpy as np

from ._area_bound import FILL, _areas, _walled, bound_areas, triangle_limits
from ._area_bound import MARGIN as AREA_MARGIN
from ._channel import straight_channel
from ._coincident import shared_positions
from ._corners import split_corners
from ._flips import (
    delaunay_flips,
    ideal_counts,
    improve_flips,
    lawson_flips,
    non_delaunay_mask,
    segment_keys,
    turned_over,
)
from ._forces import move
from ._inside import boundary_clearance
from ._lattice import lattice_points
from ._mesh import GenerationStats, Mesh, OptimizationStats, _half_mean_edge
from ._minmax import minmax_patches
from ._odt import mean_polish, odt_smooth
from ._patch_repair import MEAN_DROP, POOR_RATIO, RISE, balance_count, prune_nodes, repair_worst
from ._relaxed_flips import relaxed_flips
from ._rings import node_adjacency, ring_neighbors, vertex_triangles
from ._seeds import frontal_seeds, inside
from ._smoothing import compass_polish, guarded_smooth, stars, triangle_quality
from ._untangle import untangle
from ._verlet import VerletLists
from ._wedges import SHARP_ANGLE, best_corner_ratio, corner_angles, ladder_points, wedge_sources
from .domain import Domain, _read_only
from .errors import GeometryError, MeshingError
from .generation import generate_sized, refuse_beyond_memory
from .quality import radius_ratio
from .refinement import refine_boundary
from .sizing import _EQUILATERAL_RADIUS, SizeField, _float, as_size_function, field_count
from .timing import PhaseClock, stage_lines
from .topology import neighbors_of
from .triangulation import constrained_delaunay

__all__ = ["QualityWarning", "RobustGenerationStats", "RobustOptimizationStats", "robust_mesh",
           "size_field", "corner_angles", "best_corner_ratio", "sharp_corner_flags",
           "SHARP_ANGLE"]


GRADE_ANGLE = math.radians(40.0)  # walls of sharper corners are split in geometric progression
POOR = 0.875  # stars whose worst radius ratio is below this get the compass search
KEEP = 0.8  # the settling passes may lower a star's worst ratio to max(mesh minimum, KEEP)
ODT_ROUNDS = {"centroid": 1, "frontal": 0}  # each then the CDT; a front starts regular
ODT_SWEEPS = 2
FLIP_PASSES = 20
MAX_SCALE = 1e12  # largest domain extent over the smallest size that bm.mesh takes
MEAN_SWEEPS, MEAN_HALVINGS = 3, 4
MEAN_BELOW = {"centroid": 1.0, "frontal": 0.999}  # stars polished for their mean (1.0: all)
MEAN_STEPS = 3  # gradient steps per star visit before any compass search
RELAXED_PASSES, RELAXED_SWEEPS = 8, 3  # flips judged after relaxing (_relaxed_flips)
RELAXED_KEEP = 0.8  # they may lower a triangle's ratio to min(its value, this)
REPAIR_ROUNDS = 3  # compass passes on the stars the relaxed flips left below the minimum
RELAXED_POLISH = 3  # then mean-ratio sweeps over the nodes they changed and their neighbours
REPAIR_BELOW = 0.9  # patches around triangles below this ratio are re-triangulated
REPAIR_OPS = 16  # at most this many of them
REPAIR_SPARE = 4  # or this many nodes past it, when a balance elsewhere then takes them back
REPAIR_WINDOW = 0.035  # they keep the element count this close to the field's (or bring it closer)
MEND_WINDOW = 0.048  # the repair once more may take it this far (COUNT_TOL less a margin)
MEND_BELOW = 2.0 * (math.sqrt(2.0) - 1.0) + 1e-3  # where a triangle may hold a whole right angle
REPAIR_REACH = 0.01  # or, for triangles below POOR_RATIO, this close to its own (_repair_counts)
POOR_SUM_DROP = 1.0  # then the repair may lower the summed ratio by this (small meshes)
BALANCE_WINDOW = 0.03  # a count further off the field's gets nodes removed or inserted
BALANCE_OPS = 32  # at most this many
BALANCE_SHARE = 0.05  # nor when the count is further off than this share of the field's
BALANCE_BELOW = 20_000  # and only in meshes this small (in larger, 32 nodes are < 0.4%)
SWAP_ROUNDS = 6  # node swaps (a point inserted, then a node removed) on the chosen mesh
SWAP_GAIN = 1e-5  # each kept only if the mesh mean rises by more than this
PRUNE_ROUNDS = 32  # free nodes removed at most, each for a rise of the mean over SWAP_GAIN
PRUNE_WINDOW = 0.03  # while the count stays within this share under the field's
PRUNE_SHARE = 0.01  # and within this share under its own: the ranking chose the mesh at it
WIDE_GAIN, WIDE_WINDOW, WIDE_SHARE = 1e-3, 0.04, 0.02  # then for this gain each, this far
FINE_WALL = 0.8  # the balance takes nodes last from the first row of walls finer than this
BOTH_BELOW, BOTH_COUNT = 5000, 0.03  # both insertions up to this many elements (auto)
NEITHER_COUNT, NEITHER_GAIN = 0.1, 0.5  # no count fits: a mean gain may buy a few elements
CHANNEL_BOTH_BELOW = 200_000  # a channel's walls and the plain ones both up to this many
OTHERS = ((True, True), (False, False))  # the other (frontal, seeded) meshes tried then
FRONTAL_OTHERS = ((False, True), (False, False))  # those where frontal insertion is wanted
FINAL_SWEEPS, FINAL_BELOW = 10, 20_000  # the last mean polish: sweeps, largest mesh
MINMAX_ROUNDS = 256  # worst patches moved jointly (_minmax)
FINAL_TRIES = 3  # runs of it, each holding the nodes of the triangles the last put over bounds
COUNT_TOL = 0.05  # a count this close to the size field's fits it
COUNT_AIM = 0.04  # a mesh further over it is made again on a steeper gradation
STEEPER_BELOW = 200_000  # up to this many elements
STEEPER_MAX, STEEPER_STEPS = 4.0, 12  # the gradation searched up to this factor, in steps
STEEPER_TOL = 1e-3  # ... until the log of its count over the goal's is this close below 0
MEAN_TIE = 1e-4  # means closer than this are a tie, broken by the minimum
MIN_ENOUGH = 0.9  # a mesh whose minimum stays above this is ranked by its mean
MIN_TRADE, MIN_TRADE_MAX = 1.5, 0.005  # a mean gain may cost the minimum this times it (at most)
CLEAR_GAIN, CLEAR_FLOOR = 0.005, 0.80  # a gain this large, the minimum kept above this,
CLEAR_TRADE, CLEAR_TRADE_MAX = 3.0, 0.04  # may cost the minimum this times it (at most)
UNTANGLE = 64  # at most this many triangles turned over by the frontal §2's forces are mended
STRETCHED = 6.0  # a §2 triangle this many sizes long was never refined (_stretched)
FRONTAL_ELEMENTS = 1000  # frontal insertion from this many elements of the cap size up
ITERATIONS = {"centroid": 200, "frontal": 30}  # §3 force iterations by default
ROUNDS = {"centroid": 3, "frontal": 1}  # smoothing rounds by default (the front starts regular)
RADII_REFRESH = 10  # §3's radii follow the size field at the nodes' positions this often
ALIGN_PIECES, ALIGN_SLACK = 4, 0.02  # the lattice along a wall cut this finely (_wall_frame)
ALIGN_OVER = 0.03  # pieces up to this much over the cap still set the lattice (_wall_frame)
ALIGN_TRIES = 8  # longest input segments tried (each pass is over every boundary node)
LATTICE_MARGIN = 4.0  # the lattice keeps this many sizes off every boundary node
WALL_LATTICE_MARGIN = 0.5  # but only this far off walls made of its own edges


class QualityWarning(UserWarning):
    """The input boundary cannot support a mesh of the usual quality."""


@dataclass(frozen=True)
class RobustGenerationStats(GenerationStats):
    """§2's record plus what the robust pipeline adds: ``warnings`` (one line
    per corner too sharp for a radius ratio of 0.7), how §2 inserted
    (``insertion``: "frontal" or "centroid"), the input and refined boundary
    node counts, the size field's smallest and largest source, the number of
    frontal seeds, or of the front's first row (nodes n_boundary ...
    n_boundary + seeds - 1, held still by §3's forces)."""

    warnings: tuple[str, ...] = ()
    insertion: str = "centroid"
    input_boundary_nodes: int = 0
    refined_boundary_nodes: int = 0
    size_range: tuple[float, float] = (0.0, 0.0)
    seeds: int = 0


@dataclass(frozen=True)
class RobustOptimizationStats(OptimizationStats):
    """§3's record plus: ``converged`` (the ``tol`` test fired),
    ``smoothing_moves`` (guarded moves taken), ``min_ratio_generation`` and
    ``min_ratio`` (eq. 10, before and after), ``fallback`` ("none",
    "reverted" or "generation"), ``settling_moves`` (ODT and mean-polish
    moves) and ``flips`` (valence and quality flips) of the settling step,
    ``repairs`` (patches re-triangulated by :mod:`bubblemesh._patch_repair`)
    and ``repair_nodes`` (the nodes they added, net)."""

    converged: bool = False
    smoothing_moves: int = 0
    min_ratio_generation: float = 0.0
    min_ratio: float = 0.0
    fallback: str = "none"
    settling_moves: int = 0
    flips: int = 0
    repairs: int = 0
    repair_nodes: int = 0


def _sharp_corner_warnings(domain: Domain) -> tuple[str, ...]:
    out = []
    theta = corner_angles(domain)
    node_loop = np.full(len(theta), -1, np.int64)
    for k, ix in enumerate(domain.loops):
        node_loop[ix] = k
    for i in np.flatnonzero(theta < SHARP_ANGLE):
        x, y = domain.points[i]
        out.append(
            f"input node {i} at ({x:.6g}, {y:.6g}) (loop {node_loop[i]}) has an angle of "
            f"{math.degrees(theta[i]):.3g} degrees: no triangle there can have a radius ratio "
            f"above {float(best_corner_ratio(theta[i])):.3g}")
    return tuple(out)


def _user_size(size, max_area):
    """The user size as a number, a callable or None: ``size`` combined by min
    with the side of the equilateral triangle of area FILL times ``max_area``
    (the areas spread about +-35% around the field's, so that mean keeps
    nearly every triangle below the bound; the bound pass splits the rest)."""
    if max_area is None:
        return size
    area = _float(max_area, "mesh: max_area", "a positive number")
    if not (math.isfinite(area) and area > 0):
        raise ValueError(f"mesh: max_area must be finite and > 0, got {max_area!r}")
    side = math.sqrt(4.0 * FILL * min(area, 1e300) / math.sqrt(3.0))  # no overflow to inf
    if size is None:
        return side
    if callable(size):
        user = as_size_function(size)
        return lambda xy: np.minimum(user(xy), side)
    return min(float(as_size_function(size)(np.zeros((1, 2)))[0]), side)


def _with_regions(domain, user):
    """The user size combined by min with the regions' max_area sizes
    (:meth:`Domain.region_size`), as Triangle applies them with -a."""
    regions = domain.regions
    if regions is None or not (np.asarray(regions)[:, 3] > 0).any():
        return user
    regional = domain.region_size()
    if user is None:
        return regional
    own = as_size_function(user)
    return lambda xy: np.minimum(own(xy), regional(xy))


def _check(name, value, ok, expected):
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not ok(value):
        raise ValueError(f"mesh: {name} must be {expected}, got {value!r}")


def robust_mesh(domain, *, size=None, max_area=None, gradation=0.25, insertion="auto",
                max_iterations=None, tol=1e-3, amplification=1.7, alpha=0.2, momentum=0.7,
                rings=3, smoothing_rounds=None, smoothing_sweeps=2, progress=False) -> Mesh:
    """The robust mesher (module docstring); :func:`bubblemesh.mesh` documents
    the arguments."""
    if not isinstance(domain, Domain):
        raise TypeError(f"mesh: domain must be a bubblemesh.Domain, got {type(domain).__name__}")
    if insertion not in ("auto", "frontal", "centroid"):
        raise ValueError(f"mesh: insertion must be 'auto', 'frontal' or 'centroid', "
                         f"got {insertion!r}")
    _check("amplification", amplification, lambda v: 0 < v <= 2.0, "in (0, 2]")
    _check("alpha", alpha, lambda v: 0 < v <= 0.3, "in (0, 0.3]")
    _check("momentum", momentum, lambda v: 0 <= v < 1, "in [0, 1)")
    _check("tol", tol, lambda v: math.isfinite(v) and v >= 0, "finite and >= 0")
    for name, value, top in (("max_iterations", 0 if max_iterations is None else max_iterations,
                              None), ("rings", rings, 6),
                             ("smoothing_rounds",
                              0 if smoothing_rounds is None else smoothing_rounds, None),
                             ("smoothing_sweeps", smoothing_sweeps, None)):
        least = 1 if name == "rings" else 0
        if isinstance(value, bool) or not isinstance(value, numbers.Integral) or not (
                least <= int(value) <= (top if top is not None else int(value))):
            raise ValueError(f"mesh: {name} must be an integer >= "
                             f"{1 if name == 'rings' else 0}{f' and <= {top}' if top else ''}, "
                             f"got {value!r}")
    clock, say = PhaseClock(), stage_lines(progress)
    field, channel, fine = _sized(domain, size, max_area, gradation)
    clock.lap("sizing")
    say(f"size field, {len(fine.points)} boundary nodes")
    notes = _sharp_corner_warnings(domain)
    for note in notes:
        warnings.warn(note, QualityWarning, stacklevel=3)
    options = dict(max_iterations=max_iterations, tol=float(tol),
                   amplification=float(amplification), alpha=float(alpha),
                   momentum=float(momentum), rings=int(rings),
                   smoothing_rounds=smoothing_rounds,
                   smoothing_sweeps=int(smoothing_sweeps))
    finish = _finisher(max_area, field)
    run = dict(insertion=insertion, notes=notes, max_area=max_area, progress=progress,
               clock=clock, options=options, finish=finish)

    def rescaled(scale):
        if _with_regions(domain, _user_size(size, max_area)) is None:
            return None  # the input alone sets the field: nothing to scale
        return _sized(domain, size, max_area, gradation, scale)

    mesh = _chosen(domain, field, channel, fine, rescaled=rescaled, **run)
    say(f"meshed and repaired, {len(mesh.triangles)} elements")
    steeper = _steeper_gradation(domain, size, max_area, field, mesh)
    if steeper is not None:
        say(f"the walls' grading is over-full: again at gradation {steeper:.4g}")
        s_field, s_channel, s_fine = _sized(domain, size, max_area, steeper)
        other = _chosen(domain, s_field, s_channel, s_fine, rescaled=None, counted=field, **run)
        mesh = _judged(other, mesh, field_count(field, mesh.points, mesh.triangles), finish)[0]
        say(f"the better of the two kept, {len(mesh.triangles)} elements")
    mesh = finish(mesh)
    if progress:
        q = mesh.quality()
        say(f"last steps, {len(mesh.triangles)} elements, radius ratio mean {q.mean():.4f}, "
            f"min {q.min():.4f}")
    return _reported(domain, mesh)


def sharp_corner_flags(domain, points):
    """True at the ``points`` that are input corners sharper than
    SHARP_ANGLE (input nodes keep their coordinates bit for bit): a triangle
    there cannot reach a radius ratio of 0.7."""
    corners = np.asarray(domain.points)[corner_angles(domain) < SHARP_ANGLE]
    points = np.asarray(points)
    return np.isin(points[:, 0] + 1j * points[:, 1], corners[:, 0] + 1j * corners[:, 1])


def _reported(domain, mesh):
    """The mesh, with a QualityWarning (also in its generation record's
    ``warnings``) where triangles that touch no input corner sharper than
    SHARP_ANGLE have a radius ratio below POOR_RATIO: no corner rules those
    out, so the mesh does not pass them over in silence.  The usual cause is
    a gap the size field does not resolve (walls closer than FEATURE_FLOOR
    of their segments' length) or a steep change of spacing."""
    q = radius_ratio(mesh.points, mesh.triangles)
    at_sharp = sharp_corner_flags(domain, mesh.points)[mesh.triangles].any(axis=1)
    poor = np.flatnonzero((q < POOR_RATIO) & ~at_sharp)
    if not len(poor):
        return mesh
    worst = poor[np.argmin(q[poor])]
    x, y = mesh.points[mesh.triangles[worst]].mean(axis=0)
    note = (f"{len(poor)} triangles that touch no input corner sharper than "
            f"{math.degrees(SHARP_ANGLE):.3g} degrees have a radius ratio below {POOR_RATIO} "
            f"(the worst, {q[worst]:.3g}, at ({x:.6g}, {y:.6g})): the boundary there has a gap "
            f"or a change of spacing the size field does not resolve; give a smaller size "
            f"there, or split the segments nearby")
    warnings.warn(note, QualityWarning, stacklevel=4)
    record = replace(mesh.generation, warnings=(*mesh.generation.warnings, note))
    return replace(mesh, generation=record)


def _finisher(max_area, field):
    """The last steps on a chosen mesh (step 3: the node swaps, the
    removals that pay, the repair once more, the joint min-max moves, the
    last mean polish) as a
    function of the mesh, each mesh finished once: a finished mesh is its
    own finish."""
    done = {}

    def finish(mesh):
        if id(mesh) not in done:
            made = _pruned(_swapped(mesh, max_area, field), max_area, field)
            made = _polished(_minmaxed(_mended(made, max_area, field), max_area), max_area)
            done[id(mesh)] = (mesh, made)  # the mesh held so that its id stays its own
            done[id(made)] = (made, made)
        return done[id(mesh)][1]

    return finish


def _mended(mesh, max_area, field):
    """In a mesh of at most BALANCE_BELOW elements whose smallest ratio off the
    sharp corners (:func:`sharp_corner_flags`: no repair lifts the triangles
    there) is below REPAIR_BELOW, the repair of its worst triangles once more
    (:func:`~bubblemesh._patch_repair.repair_worst`, the count within
    REPAIR_WINDOW of the field's, no new triangle below POOR_RATIO), kept where
    it lifts that smallest ratio and the smallest of all does not fall (where
    that is a sharp corner's, which no repair raises, and the one lifted was at
    least POOR_RATIO, the mean must not fall either): the first repair spent its
    MEAN_DROP on other patches, and the swaps and removals since changed the
    worst one's surroundings.  Below MEND_BELOW, where a triangle may hold a
    whole right angle and only a point inserted splits it, the count may go to
    MEND_WINDOW."""
    X, T = mesh.points, mesh.triangles
    off = ~sharp_corner_flags(mesh.domain, X)[T].any(axis=1)
    if len(T) > BALANCE_BELOW or not off.any():
        return mesh
    least, before = _smallest_ratio(X, T), _smallest_ratio(X, T[off])
    if before >= REPAIR_BELOW:
        return mesh
    segments = np.asarray(mesh.segments)
    movable = np.arange(len(X)) >= mesh.n_boundary
    movable[np.unique(segments)] = False
    limit = triangle_limits(X, T, mesh.neighbors, getattr(mesh.domain, "regions", None),
                            max_area) / (1.0 + AREA_MARGIN)
    asked = field_count(field, X, T)
    share = MEND_WINDOW if before < MEND_BELOW else REPAIR_WINDOW  # one point splits it
    window = asked * (1.0 - share), asked * (1.0 + share)
    Y, U, old, taken = repair_worst(X, T, segments, movable, limit, REPAIR_BELOW, REPAIR_OPS,
                                    window, MEAN_HALVINGS, MEAN_STEPS, MEAN_DROP, None, None,
                                    True)
    off = ~sharp_corner_flags(mesh.domain, Y)[U].any(axis=1)
    if not taken or _smallest_ratio(Y, U[off]) <= before + RISE or _smallest_ratio(Y, U) < least:
        return mesh
    # where a sharp corner holds the minimum, which no mend raises, one that lifts no
    # triangle from below POOR_RATIO must pay in the mean
    if least < before and before >= POOR_RATIO and (
            triangle_quality(Y, U).mean() < triangle_quality(X, T).mean()):
        return mesh
    return _rebuilt(mesh, Y, U, _walled(U, neighbors_of(U), segments, len(Y)), old,
                    mesh.optimization.repairs + taken)


def _judged(a, b, asked, finish):
    """(the better of meshes a and b by :func:`_better`, whether it is a),
    the one with the higher mean finished first where it loses: the last
    steps often lift the minimum that held it back, and only then is it the
    mesh the user gets.  (The other is left as it is: its minimum lifted
    would tip the ranking against the mean, whose margin over Gmsh's is
    the thinner.)"""
    won = _better(a, b, asked)
    gain = float(a.quality().mean() - b.quality().mean())
    if gain > MEAN_TIE and not won:
        a = finish(a)
        won = _better(a, b, asked)
    elif gain < -MEAN_TIE and won:
        b = finish(b)
        won = _better(a, b, asked)
    return (a, True) if won else (b, False)


def _sized(domain, size, max_area, gradation, scale=1.0):
    """(size field, straight channel or None, refined domain): step 1 (the
    user's sizes times ``scale``)."""
    field = _plain_field(domain, size, max_area, gradation, scale)
    try:
        _check_scale(domain, field)
        channel = straight_channel(domain, field, float(field.cap))
        fine = refined_domain(domain, field, splits=None if channel is None else channel.splits)
        field = _with_wedges(domain, field)
    except (TypeError, ValueError) as error:
        raise type(error)(f"mesh: {error}") from None
    return field, channel, fine


def size_field(domain, *, size=None, max_area=None, gradation=0.25) -> SizeField:
    """The size field :func:`robust_mesh` meshes ``domain`` to (step 1): the
    user's ``size`` and ``max_area``, the regions' max_area, the input
    spacing and the feature size, graded, with the sharp corners' wedge
    sources (:func:`_with_wedges`).  What a study predicts counts from and
    hands a peer mesher."""
    if not isinstance(domain, Domain):
        raise TypeError(f"size_field: domain must be a bubblemesh.Domain, "
                        f"got {type(domain).__name__}")
    return _with_wedges(domain, _plain_field(domain, size, max_area, gradation))


def _plain_field(domain, size, max_area, gradation, scale=1.0):
    """The size field of step 1 before the sharp corners' wedges, the user's
    sizes (``size``, ``max_area``'s and the regions') times ``scale``."""
    user = _with_regions(domain, _user_size(size, max_area))
    if scale != 1.0 and user is not None:
        user = _times(user, scale)
    try:
        return SizeField.from_domain(domain, size=user, gradation=gradation)
    except (TypeError, ValueError) as error:
        raise type(error)(f"mesh: {error}") from None


def _times(user, scale):
    """A user size (a number or a callable) times ``scale``."""
    if callable(user):
        return lambda xy: scale * user(xy)
    return scale * float(user)


def _chosen(domain, field, channel, fine, insertion, notes, max_area, progress, clock,
            options, rescaled, finish, counted=None):
    """The best of the meshes step 4 makes on one size field (and, where
    ``rescaled`` gives the step 1 of the user's sizes times a factor, on the
    one that brings an over-full loser's count back to the field's or the
    winner's, whichever is fewer; a mesh made so is not made again)."""
    frontal = _frontal_wanted(insertion, domain, field)

    def portfolio(fine, channel):
        mesh = _mesh_with(domain, fine, field, frontal, True, notes, max_area, progress, clock,
                          options, channel)
        kind = (frontal, True)  # the insertion that made mesh, None once rescaled
        if insertion == "auto" and len(mesh.triangles) <= BOTH_BELOW:
            asked = field_count(counted or field, mesh.points, mesh.triangles)
            for other_frontal, seeded in (FRONTAL_OTHERS if frontal else OTHERS):
                other = _mesh_with(domain, fine, field, other_frontal, seeded, notes, max_area,
                                   progress, clock, options, channel)
                loser, lost = mesh, kind
                mesh, won = _judged(other, mesh, asked, finish)
                if won:  # only a front's first mesh: its rows overfill narrow parts
                    lost, kind = (lost if lost and lost[0] else None), (other_frontal, seeded)
                else:
                    loser, lost = other, (other_frontal, seeded)
                goal = min(asked, len(mesh.triangles))  # the count the loser must not exceed
                if lost and len(loser.triangles) > (1.0 + BOTH_COUNT) * goal and rescaled:
                    other = _matched(domain, loser, goal, *lost, rescaled, notes, max_area,
                                     progress, clock, options, field)
                    if other is not None:
                        judged, won = _judged(other, mesh, asked, finish)
                        if won and _as_good(judged, mesh):
                            mesh, kind = judged, None
        return mesh

    mesh = portfolio(fine, channel)
    if channel is not None and insertion == "auto" and len(mesh.triangles) <= CHANNEL_BOTH_BELOW:
        # where the plain walls' rows nearly fit, their lattice's one seam costs less
        # than stretching every row, and a short channel's corners weigh more: both tried
        plain = portfolio(refined_domain(domain, field), None)
        mesh = _judged(mesh, plain, field_count(counted or field, plain.points, plain.triangles),
                       finish)[0]
    return mesh


def _matched(domain, mesh, goal, frontal, seeded, rescaled, notes, max_area, progress,
             clock, options, counted):
    """``mesh``'s insertion again on the user's sizes scaled by the share
    ``mesh`` is over the count ``goal``, so that its count falls to about
    ``goal``, or None.  A narrow strip filled two rows deep, as fronts fill
    it, holds more elements than the field's integral (which does not see
    the rows); Gmsh tuned to the same count coarsens the rest: so does this,
    under the same area bounds (``max_area``, the user's), its repairs'
    count windows those of the asked field ``counted``."""
    made = rescaled(math.sqrt(len(mesh.triangles) / goal))
    if made is None:
        return None
    field, channel, fine = made
    return _mesh_with(domain, fine, field, frontal, seeded, notes, max_area, progress, clock,
                      options, channel, counted)


def _as_good(a, b):
    """Has mesh a fewer triangles below a radius ratio (eq. 10) of 0.7 than b,
    or a mean ratio at least b's, to MEAN_TIE?  A mesh made on rescaled sizes
    must pay for itself in quality: fitting the field's count is no reason
    to take it."""
    qa, qb = a.quality(), b.quality()
    poor_a, poor_b = int((qa < 0.7).sum()), int((qb < 0.7).sum())
    if poor_a != poor_b:
        return poor_a < poor_b
    return bool(qa.mean() >= qb.mean() - MEAN_TIE)


def _steeper_gradation(domain, size, max_area, field, mesh):
    """The gradation on which to mesh again when ``mesh`` has more than
    COUNT_AIM over the count ``field`` asks for (graded walls fill with more
    elements than the field's integral, the more the steeper they grade):
    the one whose field asks for that count shrunk by the same share, found
    by regula falsi (:func:`_falsi`), or None (no gradation, a mesh above STEEPER_BELOW
    elements, or one within COUNT_AIM)."""
    count, g = len(mesh.triangles), field.gradation
    if g <= 0.0 or count > STEEPER_BELOW:
        return None
    asked = field_count(field, mesh.points, mesh.triangles)
    if not asked > 0.0 or count <= (1.0 + COUNT_AIM) * asked:
        return None
    goal = asked * asked / count

    def asks(gradation):
        steeper = _with_wedges(domain, _plain_field(domain, size, max_area, gradation))
        return field_count(steeper, mesh.points, mesh.triangles)

    high = STEEPER_MAX * g
    over_high = math.log(asks(high) / goal)
    if over_high > 0.0:
        return high
    return _falsi(lambda x: math.log(asks(x) / goal), g, high, math.log(asked / goal),
                  over_high)


def _falsi(f, low, high, f_low, f_high):
    """The root of a decreasing ``f`` with f(low) = f_low > 0 >= f_high = f(high),
    by regula falsi with the Illinois rule (an end kept twice has its value
    halved, so both ends move): the high end once its value is within
    STEEPER_TOL below zero, or after STEEPER_STEPS evaluations."""
    kept = 0  # +1: the low end was kept last time, -1: the high end
    for _ in range(STEEPER_STEPS):
        if f_high >= -STEEPER_TOL:
            break
        margin = 1e-3 * (high - low)
        x = min(max(high - f_high * (high - low) / (f_high - f_low), low + margin), high - margin)
        f_x = f(x)
        if f_x > 0.0:
            low, f_low = x, f_x
            f_high *= 0.5 if kept < 0 else 1.0
            kept = -1
        else:
            high, f_high = x, f_x
            f_low *= 0.5 if kept > 0 else 1.0
            kept = 1
    return high


def _better(a, b, asked):
    """Is mesh a better than b: fewer triangles below a radius ratio (eq. 10)
    of 0.7; or as many, and a's count within COUNT_TOL of ``asked`` (the
    field's) where b's is not; or both or neither within it, a's count within
    BOTH_COUNT of b's (quality is not bought with elements; below it too
    where both are within COUNT_TOL; where neither is, within NEITHER_COUNT
    if the mean gain is at least NEITHER_GAIN times the count's excess, as
    where the domain's rows force a count the field cannot have) and a mean
    ratio higher by more than MEAN_TIE with a minimum at least b's (or at
    least MIN_ENOUGH) less MIN_TRADE of the gain, at most MIN_TRADE_MAX (a
    minimum a hair lower, or both at a sharp corner's bound, does not
    outweigh the mean; a gain of at least CLEAR_GAIN with a minimum of at
    least CLEAR_FLOOR may cost CLEAR_TRADE of it, at most CLEAR_TRADE_MAX),
    or a mean within MEAN_TIE of b's and a higher minimum?  (A perfect
    lattice whose walls are cut a little longer than the field's size has a
    few percent fewer elements than a centroid mesh, both within COUNT_TOL
    of the field's.)"""
    qa, qb = a.quality(), b.quality()
    poor_a, poor_b = int((qa < 0.7).sum()), int((qb < 0.7).sum())
    if poor_a != poor_b:
        return poor_a < poor_b
    fits_a, fits_b = (abs(len(q) / asked - 1.0) <= COUNT_TOL for q in (qa, qb))
    if fits_a != fits_b:
        return fits_a
    fewer = fits_a and fits_b and len(qa) < len(qb)  # fewer elements buy no quality
    gain = float(qa.mean() - qb.mean())
    excess = abs(len(qa) / len(qb) - 1.0)
    if not fewer and excess > BOTH_COUNT and (
            fits_a or excess > NEITHER_COUNT or gain < NEITHER_GAIN * excess):
        return False
    if abs(gain) <= MEAN_TIE:
        return bool(qa.min() > qb.min())
    slack = min(MIN_TRADE_MAX, MIN_TRADE * gain)
    if gain >= CLEAR_GAIN and qa.min() >= CLEAR_FLOOR:
        slack = max(slack, min(CLEAR_TRADE_MAX, CLEAR_TRADE * gain))
    return bool(gain > 0.0 and qa.min() >= min(qb.min(), MIN_ENOUGH) - slack)


def _mesh_with(domain, fine, field, frontal, seeded, notes, max_area, progress, clock,
               options, channel=None, counted=None):
    """§2 by frontal or centroid insertion on the refined domain ``fine`` (with
    ``seeded`` its frontal seeds or lattice, in the ``channel``'s rows where
    there is one), then the stable §3, the area bounds and the relaxed flips
    (module docstring); the repairs keep the count near that of ``counted``
    (default ``field``)."""
    seeds = (None if not seeded else _lattice(fine, field, domain, channel) if frontal
             else _frontal_seeds(fine))
    try:
        generated = generate_sized(fine, field, progress=progress, seeds=seeds, frontal=frontal)
    except MemoryError:  # sizes far finer than the domain's extent
        raise MeshingError("mesh: not enough memory for the mesh this size field asks for "
                           "(sizes far finer than the domain)") from None
    if not frontal and _stretched(generated, field):
        return _mesh_with(domain, fine, field, True, True, notes, max_area, progress, clock,
                          options, channel, counted)
    gen = RobustGenerationStats(
        **{k: getattr(generated.generation, k) for k in GenerationStats.__dataclass_fields__},
        warnings=notes, input_boundary_nodes=len(domain.points),
        refined_boundary_nodes=len(fine.points),
        size_range=(float(field.values.min()), float(field.values.max())),
        seeds=0 if seeds is None else len(seeds), insertion="frontal" if frontal else "centroid")
    generated = replace(generated, generation=gen)
    if frontal:
        generated = _first_row_first(generated)
    options = dict(options)
    for name, default in (("max_iterations", ITERATIONS), ("smoothing_rounds", ROUNDS)):
        given = options[name]
        options[name] = int(default[gen.insertion] if given is None else given)
    clock.lap("generation")
    try:
        mesh = stable_optimize(generated, size_field=field, clock=clock, **options)

        def settle(X, T, N, segments, n_b, movable):
            return _settle(X, T, N, segments, n_b, _node_sizes(mesh, X, field), movable,
                           mean_below=MEAN_BELOW[gen.insertion],
                           odt_rounds=ODT_ROUNDS[gen.insertion])[:2]

        # Triangle's -a, global and regional: hard bounds
        return _polished(_repaired(_relaxed(bound_areas(mesh, max_area, settle=settle),
                                            max_area), max_area, counted or field), max_area)
    except MemoryError:  # sizes far finer than the domain's extent
        raise MeshingError("mesh: not enough memory to optimise the mesh this size field "
                           "asks for (sizes far finer than the domain)") from None


def _stretched(generated, field):
    """Did eq. 6 stop §2 on triangles that span the domain?  Where fine walls
    grade the field up to a far larger size inside, the first triangulation's
    needles between the walls have their centroids, and so their bubbles, where
    the field is large: the bubbles' sum passes the domain's area before any
    insertion.  True if some triangle's longest edge exceeds STRETCHED times
    the field at its centroid (a finished §2 mesh stays well below) while
    that centroid has room: it is more than half that size off every wall (a
    domain thinner than its walls' pieces, a sliver, has no room to refine)."""
    P, T = generated.points, generated.triangles
    longest = np.max([np.hypot(*(P[T[:, (k + 1) % 3]] - P[T[:, k]]).T) for k in range(3)],
                     axis=0)
    centres = P[T].mean(axis=1)
    h = field(centres)
    long = longest > STRETCHED * h
    if not long.any():
        return False
    room = boundary_clearance(np.vstack([P, centres[long]]), np.asarray(generated.segments),
                              len(P), float(h[long].max()))[len(P):]
    return bool((room > 0.5 * h[long]).any())


def refined_domain(domain, field, rounding="nearest", splits=None, ladders=True):
    """``domain`` with its segments split where ``field`` asks for it
    (:func:`bubblemesh.refinement.refine_boundary`: the input nodes first and
    unmoved, the new ones on their segments; the piece count rounded to the
    nearest by default, so the walls' first rows are as dense as the field;
    ``splits`` as it takes them), as a Domain; with ``ladders`` the ladders'
    nodes (:func:`bubblemesh._wedges.ladder_points`) as free points after
    the input's."""
    refined = refine_boundary(domain, field, sharp_angle=GRADE_ANGLE, rounding=rounding,
                              splits=splits, ladders=ladders)
    try:
        fine = refined.to_domain()
    except GeometryError:  # a node an ulp off its segment touches a part a few ulps away
        fine = refined.exact_only().to_domain()
    rungs = ladder_points(domain, field, GRADE_ANGLE) if ladders else ()
    if not len(rungs):
        return fine
    # the ladders' nodes are free points: fixed, like the walls' nodes they pair with
    return replace(fine, points=_read_only(np.vstack([fine.points, rungs])))


def _with_wedges(domain, field):
    """``field`` with sources on the graded walls of sharp corners
    (:func:`~bubblemesh._wedges.wedge_sources`).  Without a cap the field
    beside a corner can grow far beyond the zigzag's triangles, their element
    bubbles with it, and eq. 6 would stop §2 early.  Under a cap only those on
    the boundary's walls beside corners sharper than SHARP_ANGLE: there the
    zigzag is the whole wedge, and a field without it asks for far fewer
    elements than the wedge holds; on an interior constraint's walls their
    cones would refine the other side too, and at blunter corners frontal
    insertion would split the corner's own triangle."""
    capped = math.isfinite(field.cap)
    points, values = wedge_sources(domain, field, GRADE_ANGLE,
                                   outer_below=SHARP_ANGLE if capped else None)
    if not len(points):
        return field
    return SizeField(np.vstack([field.points, points]), np.concatenate([field.values, values]),
                     gradation=field.gradation, cap=field.cap)


def _frontal_wanted(insertion, domain, field):
    """Frontal insertion (:mod:`bubblemesh._frontal`) or the paper's centroids
    for §2.  ``auto``: frontal where the field has a finite cap (a size the user
    gave) and the domain holds at least FRONTAL_ELEMENTS equilateral triangles
    of that size.  A front lays down rows of nearly equilateral triangles that
    meet in a few seams, the lattice §3 can only approach from centroid
    insertions; but every seam and corner costs a little, and in small domains,
    or where the field grows all the way (no cap), the centroids relaxed by
    §3's bubble forces mostly do better (docs/performance.md has the
    measurements; :func:`robust_mesh` tries both on small domains)."""
    if insertion != "auto":
        return insertion == "frontal"
    cap = float(field.cap)
    return math.isfinite(cap) and domain.area >= FRONTAL_ELEMENTS * math.sqrt(3) / 4 * cap * cap


def _check_scale(domain, field):
    """MeshingError when the domain spans more than MAX_SCALE times its
    smallest size: §3 and the smoothing move nodes in floating point, and a
    graded mesh over that range is beyond double precision's reach."""
    P = np.asarray(domain.points)
    extent = float(np.max(P.max(axis=0) - P.min(axis=0)))
    smallest = float(field.values.min())
    if extent <= MAX_SCALE * smallest:
        return
    S = np.asarray(domain.segments)
    length = np.hypot(*(P[S[:, 0]] - P[S[:, 1]]).T) if len(S) else np.full(1, np.inf)
    k = int(np.argmin(length))
    if not extent <= MAX_SCALE * length[k]:  # mostly two nearly coincident nodes
        a, b = (tuple(float(c) for c in P[v]) for v in S[k])
        raise MeshingError(f"mesh: the domain spans {extent:.3g} but its segment from {a} "
                           f"to {b} is {length[k]:.3g} long, more than {MAX_SCALE:.0e} times "
                           "shorter: merge its ends, or rescale or split the domain")
    raise MeshingError(f"mesh: the domain spans {extent:.3g} but its smallest size is "
                       f"{smallest:.3g}, more than {MAX_SCALE:.0e} times smaller: rescale "
                       "or split the domain, or use paper=True")


def _lattice(domain, field, source, channel=None):
    """The close-packed lattice of the field's cap over the bulk of the domain
    (:mod:`bubblemesh._lattice`), refused in one line when it would not fit in
    memory; None without a finite cap.  In the ``channel``'s rows
    (:mod:`bubblemesh._channel`) where there is one, else aligned with the
    longest segment of ``source`` (the input domain) where :func:`_wall_frame`
    says so."""
    cap = float(field.cap)
    if not math.isfinite(cap):
        return None
    refuse_beyond_memory(domain.area / (math.sqrt(3) / 4 * cap * cap), "the size cap",
                         "about", f"the cap {cap:.3g} is far finer than the domain; pass a "
                         "larger size")
    frame = channel.frame if channel is not None else _wall_frame(source, domain, cap)
    return lattice_points(domain.points, domain.segments, cap, LATTICE_MARGIN, field, frame,
                          WALL_LATTICE_MARGIN)


def _wall_frame(source, fine, cap):
    """(origin, direction, spacing) of a lattice through the first node of
    an input segment, along it, as fine as its refined pieces: the longest
    of the ALIGN_TRIES longest segments cut into at least ALIGN_PIECES equal
    pieces (to 1e-6 of a piece; a wall graded toward a sharp corner is not)
    at most ALIGN_SLACK shorter or ALIGN_OVER longer than the cap (the
    nearest piece count makes them up to 1.3 times the cap).  Then a domain
    whose walls lie on one lattice (a regular hexagon, an equilateral
    triangle) is filled by it seamlessly; else None (the lattice along x)."""
    P, S = np.asarray(source.points), np.asarray(source.segments)
    d = P[S[:, 1]] - P[S[:, 0]]
    lengths = np.hypot(d[:, 0], d[:, 1])
    F = np.asarray(fine.points)
    for k in np.argsort(-lengths, kind="stable")[:ALIGN_TRIES]:  # ties: the first first
        a, length = P[S[k, 0]], float(lengths[k])
        if length < ALIGN_PIECES * (1 - ALIGN_SLACK) * cap:
            return None
        u = d[k] / length
        rel = F - a
        along = rel[:, 0] * u[0] + rel[:, 1] * u[1]  # not `@`: BLAS's bits vary with its threads
        off = np.abs(rel[:, 1] * u[0] - rel[:, 0] * u[1])
        inner = (off <= 1e-9 * length) & (along > 1e-9 * length) & (along < (1 - 1e-9) * length)
        pieces = int(inner.sum()) + 1
        step = length / pieces
        equal = np.abs(np.sort(along[inner]) / step - np.arange(1, pieces)).max(initial=0.0)
        if (pieces >= ALIGN_PIECES and equal <= 1e-6
                and (1 - ALIGN_SLACK) * cap <= step <= cap * (1 + ALIGN_OVER)):
            return a, u, step
    return None


def _frontal_seeds(domain):
    """The first row off the walls (:mod:`bubblemesh._seeds`), those strictly
    inside the domain (by a walk in the boundary's triangulation)."""
    tri, nbr = _triangulate(np.asarray(domain.points), domain.segments)
    seeds, rows = frontal_seeds(domain.points, domain.segments, domain.interior)
    if not len(seeds):
        return None
    return seeds[inside(domain.points, domain.segments, tri, nbr, seeds, rows)]


def _forces(mesh, R, max_iterations, tol, alpha, rings, momentum, radius_of=None):
    """Eq. 7-8 with radii R (eq. 9 not run) until the largest relative move <
    tol; with ``radius_of`` (the size field's amplified radius at a position)
    the movable nodes' radii are read from it every RADII_REFRESH iterations,
    so a node that drifts up or down a graded field takes the local size
    along (with fixed radii the nodes round a hundredfold grading never
    settle).  The frontal seeds hold still like the boundary: released, the
    forces push seeds out of their pockets between boundary nodes and leave
    boundary nodes with two triangles, right-angled at best (the smoothing and
    settling move them later, under their quality guards).
    Returns (positions, iterations, last largest move, blocked moves, builds)."""
    n_b = mesh.n_boundary
    fixed = n_b + int(getattr(mesh.generation, "seeds", 0))
    P0 = np.ascontiguousarray(mesh.points)
    tri0 = np.ascontiguousarray(mesh.triangles)
    nbr0 = np.ascontiguousarray(mesh.neighbors)
    n = len(P0)
    ring_ptr, ring_idx = ring_neighbors(*node_adjacency(tri0, nbr0, n), n, rings)
    X, Xn = P0.copy(), P0.copy()
    V = np.zeros_like(P0)  # each node's last move, for the momentum
    home = vertex_triangles(tri0, n)
    clearance = boundary_clearance(P0, np.asarray(mesh.segments), n_b,
                                   reach=4.0 * float(R.max(initial=0.0)))
    iterations, largest, blocked = 0, 0.0, 0
    lists = VerletLists(ring_ptr, ring_idx, fixed, 0.3)
    expired = True
    while iterations < max_iterations:
        iterations += 1
        if radius_of is not None and RADII_REFRESH and iterations % RADII_REFRESH == 1:
            R[fixed:] = radius_of(X[fixed:])
            expired = True
        if expired:
            lists.build(X, R)
        expired, stuck, largest = move(X, R, Xn, home, *lists.arrays, False, fixed, alpha,
                                       P0, tri0, nbr0, clearance, lists.X0, lists.R0,
                                       lists.skin, V, momentum)
        expired = expired > 0
        blocked += stuck
        X, Xn = Xn, X
        if largest < tol:
            break
    return X, iterations, float(largest), int(blocked), lists.builds


def _free_points(n_b, segments):
    """The boundary nodes on no segment (a planar graph's free points)."""
    on = np.zeros(n_b, np.bool_)
    on[np.asarray(segments, np.int64).ravel()] = True
    return np.flatnonzero(~on)


def _separate(X, P0):
    """Nodes that the forces moved onto another node's coordinates (far from
    the origin, where floats are coarse) go back to their distinct §2
    positions; each round reverts at least one node, so it ends."""
    for _ in range(len(X)):
        back = shared_positions(X) & np.any(X != P0, axis=1)
        if not back.any():
            return
        X[back] = P0[back]


def _triangulate(X, segments):
    try:
        return constrained_delaunay(X, segments)
    except GeometryError as error:
        raise MeshingError(f"mesh: re-triangulation failed: {error}") from error


def _retriangulate_moved(X, mesh, segments):
    """§3.5's re-triangulation after the forces: Lawson's flips from the §2
    connectivity when the forces turned no triangle over (exact orientation;
    the boundary nodes stay, so it is still a valid triangulation of the
    domain, and the flips reach its constrained Delaunay triangulation, the
    triangles a fresh build gives when that is unique), or, after the frontal
    §2, turned over only a few that a local re-triangulation mends
    (:mod:`bubblemesh._untangle`); else a fresh CDT.  After the frontal §2
    and its few force iterations hardly an edge flips.  (Centroid insertion
    runs on small domains or turns many triangles over in its longer force
    run; a mended patch renumbers triangles, which the greedy valence flips
    follow, and on small meshes that can cost some of the mean for no time
    worth having.)"""
    tri, nbr = np.array(mesh.triangles), np.array(mesh.neighbors)
    turned = turned_over(X, tri)
    few = 0 < turned.sum() <= UNTANGLE
    if _insertion(mesh) == "frontal" and few and untangle(X, tri, nbr, segments, turned):
        turned = turned_over(X, tri)
    if not turned.any():
        keys = segment_keys(segments, len(X))
        first = np.flatnonzero(non_delaunay_mask(X, tri, nbr, keys))
        if lawson_flips(X, tri, nbr, keys, 4 * len(tri), first) >= 0:
            return tri, nbr
    return _triangulate(X, segments)


def _retriangulate_unless_worse(X, segments, triangles, neighbors):
    """The CDT of the moved nodes, unless it lowers the smallest radius ratio
    (then the current connectivity stays: valid, since every move kept it so).
    The CDT comes from Lawson's flips on the current, valid connectivity (the
    nodes moved a little, so few edges flip, often none); a full CDT if they
    run long."""
    keys = segment_keys(segments, len(X))
    if not non_delaunay_mask(X, triangles, neighbors, keys).any():
        return triangles, neighbors  # already the CDT
    tri, nbr = np.array(triangles), np.array(neighbors)
    flips = delaunay_flips(X, tri, nbr, keys, 4 * len(tri))
    if flips == 0:
        return triangles, neighbors
    if flips < 0:
        tri, nbr = _triangulate(X, segments)
    if triangle_quality(X, tri).min() >= triangle_quality(X, triangles).min():
        return tri, nbr
    return triangles, neighbors


class _Stars:
    """:func:`stars` of the triangles array last asked for, kept by identity: a
    re-triangulation that changes nothing returns the very array it was
    given.  Only for arrays that nothing changes in place."""

    def __init__(self):
        self.triangles = None

    def __call__(self, triangles, n):
        if triangles is not self.triangles:
            self.ptr, self.idx = stars(triangles, n)
            self.triangles = triangles
        return self.ptr, self.idx


def _polish(X, triangles, neighbors, segments, n_b, rounds, sweeps, movable, star_of=None):
    """Guarded smoothing alternating with re-triangulation; a re-triangulation
    that would lower the smallest radius ratio is not taken (the smoothed
    connectivity stays, valid by construction).  X is updated in place.
    ``star_of``: a :class:`_Stars` to share with the next step."""
    star_of = star_of or _Stars()
    moves = 0
    for _ in range(rounds):
        ptr, idx = star_of(triangles, len(X))
        taken = guarded_smooth(X, triangles, ptr, idx, n_b, sweeps, movable)
        taken += compass_polish(X, triangles, ptr, idx, n_b, POOR, movable)
        moves += taken
        if taken == 0:
            break
        triangles, neighbors = _retriangulate_unless_worse(X, segments, triangles, neighbors)
    return triangles, neighbors, moves


def _node_sizes(mesh, X, size_field):
    """The target edge length at every node: the size field, else the §2 radii
    read back through eq. 2 of the equilateral triangle."""
    if size_field is not None:
        return np.ascontiguousarray(size_field(X), dtype=np.float64)
    return np.asarray(mesh.radii, dtype=np.float64) / _EQUILATERAL_RADIUS


def _settle(X, triangles, neighbors, segments, n_b, h, movable, star_of=None,
            mean_below=1.0, odt_rounds=1):
    """Settle the nodes and the valences, never lowering the smallest radius
    ratio (each pass keeps every star at least min(its worst, max(mesh minimum,
    KEEP)); X in place): ``odt_rounds`` of ODT (:mod:`bubblemesh._odt`), each
    followed by the CDT, then valence and quality flips
    (:mod:`bubblemesh._flips`; the mesh stays valid and conforming but need
    not be constrained-Delaunay) and corner
    splits (:mod:`bubblemesh._corners`), then gradient steps on each star's
    mean ratio (a compass search where they are blocked) for the stars whose
    worst ratio is below ``mean_below``.  Returns (triangles, neighbors, moves,
    flips).  ``star_of``: a :class:`_Stars` from the smoothing."""
    star_of = star_of or _Stars()
    moves = 0
    for _ in range(odt_rounds):
        floor = max(float(triangle_quality(X, triangles).min(initial=1.0)), KEEP)
        ptr, idx = star_of(triangles, len(X))
        taken, _ = odt_smooth(X, triangles, ptr, idx, h, n_b, ODT_SWEEPS, movable, floor, 1e-3)
        moves += taken
        if taken == 0:
            break
        triangles, neighbors = _retriangulate_unless_worse(X, segments, triangles, neighbors)
    triangles, neighbors = np.array(triangles), np.array(neighbors)
    floor = max(float(triangle_quality(X, triangles).min(initial=1.0)), KEEP)
    keys = segment_keys(segments, len(X))
    flips = improve_flips(X, triangles, neighbors, keys, ideal_counts(X, triangles, len(X)),
                          FLIP_PASSES, floor)
    on_segment = np.zeros(len(X), np.bool_)
    on_segment[segments.ravel()] = True
    flips += split_corners(X, triangles, neighbors, keys, ideal_counts(X, triangles, len(X)),
                           on_segment, movable)
    ptr, idx = stars(triangles, len(X))
    floor = max(float(triangle_quality(X, triangles).min(initial=1.0)), KEEP)
    moves += mean_polish(X, triangles, ptr, idx, n_b, MEAN_SWEEPS, movable, floor,
                         MEAN_HALVINGS, mean_below, MEAN_STEPS)
    return triangles, neighbors, moves, int(flips)


def stable_optimize(mesh, *, max_iterations=200, tol=1e-3, amplification=1.7, alpha=0.1,
                    momentum=0.0, rings=3, smoothing_rounds=3, smoothing_sweeps=4, settle=True,
                    size_field=None, clock=None) -> Mesh:
    """Step 3 of the module docstring on a §2 mesh; the result's smallest eq. 10
    radius ratio is never below ``mesh``'s.  ``settle``: run :func:`_settle`
    (sizes from ``size_field``, else from the §2 radii).  With ``size_field``
    the free points' bubbles take its radius, not eq. 1-2's."""
    clock = clock or PhaseClock()
    n_b, n = mesh.n_boundary, len(mesh.points)
    segments = np.asarray(mesh.segments)
    P0 = np.array(mesh.points)
    q0 = float(triangle_quality(P0, np.asarray(mesh.triangles)).min(initial=1.0))
    R = np.asarray(mesh.radii, dtype=np.float64) * amplification
    radius_of = None if size_field is None else (
        lambda xy: amplification * size_field.radius(np.ascontiguousarray(xy)))
    free = _free_points(n_b, segments)
    if radius_of is not None and len(free):
        # eq. 1-2 give a free point its distance to the nearest input node, a bubble
        # that can span many sizes and push its neighbours into clumps and holes
        R[free] = radius_of(P0[free])
    X, iterations, largest, blocked, builds = _forces(mesh, R, max_iterations, tol, alpha, rings,
                                                      momentum, radius_of)
    _separate(X, P0)
    clock.lap("forces")
    triangles, neighbors = _retriangulate_moved(X, mesh, segments)
    movable = np.ones(n, dtype=np.bool_)
    movable[np.unique(segments)] = False  # segment endpoints never move
    movable[:n_b] = False  # nor boundary nodes and free points
    star_of = _Stars()
    triangles, neighbors, moves = _polish(X, triangles, neighbors, segments, n_b,
                                          smoothing_rounds, smoothing_sweeps, movable, star_of)
    settled, flips = 0, 0
    if settle:
        clock.lap("smoothing")
        triangles, neighbors, settled, flips = _settle(
            X, triangles, neighbors, segments, n_b, _node_sizes(mesh, X, size_field), movable,
            star_of, MEAN_BELOW[_insertion(mesh)], ODT_ROUNDS[_insertion(mesh)])
        clock.lap("settling")
    fallback = "none"
    for _ in range(8):  # the guarantee: revert the nodes of triangles below q0
        q = triangle_quality(X, triangles)
        bad = q < q0
        if not bad.any():
            break
        fallback = "reverted"
        nodes = np.unique(triangles[bad])
        nodes = nodes[nodes >= n_b]
        if not len(nodes) or not movable[nodes].any():
            break
        X[nodes] = P0[nodes]
        movable[nodes] = False
        _separate(X, P0)  # a moved node may sit on a reverted one's §2 position
        triangles, neighbors = _triangulate(X, segments)
        q = None  # the ratios of the mesh before this revert
    q_final = float((q if q is not None else triangle_quality(X, triangles)).min(initial=1.0))
    if q_final < q0:
        fallback = "generation"  # the §2 mesh, smoothed: never worse by construction
        X = P0.copy()
        triangles = np.array(mesh.triangles)
        neighbors = np.array(mesh.neighbors)
        movable[:] = True
        movable[np.unique(segments)] = False
        movable[:n_b] = False
        triangles, neighbors, moves = _polish(X, triangles, neighbors, segments, n_b,
                                              smoothing_rounds, smoothing_sweeps, movable)
        q_final = float(triangle_quality(X, triangles).min(initial=1.0))
    clock.lap("smoothing")
    stats = RobustOptimizationStats(
        iterations=iterations, max_displacement=largest, blocked_moves=blocked,
        list_builds=builds, list_layouts=0, amplification=amplification, rings=rings,
        alpha=alpha, seconds=clock.total(), phases=dict(clock.seconds),
        converged=largest < tol, smoothing_moves=int(moves), min_ratio_generation=q0,
        min_ratio=q_final, fallback=fallback, settling_moves=int(settled), flips=flips)
    return Mesh(points=X, triangles=triangles, neighbors=neighbors, radii=R, segments=segments,
                n_boundary=n_b, domain=mesh.domain, generation=mesh.generation,
                optimization=stats)


def _relaxed(mesh, max_area):
    """The last step: edge flips judged after relaxing the nodes around them
    (:mod:`bubblemesh._relaxed_flips`), within the area bounds (every changed
    triangle at most its bound, as :func:`bound_areas` leaves them) and never
    below the §2 mesh's smallest radius ratio; then the compass search on the
    stars they left below the mesh's minimum before them, each up to that
    minimum (so the result's minimum follows what the earlier steps
    reached); then gradient steps on the star means of the nodes they
    changed and their neighbours (the flips relaxed a few rings; the rest of
    the mesh had settled around the old connectivity), never below the
    mesh's minimum; each of the two kept if it breaks no area bound."""
    if not RELAXED_PASSES:
        return mesh
    X, T = np.array(mesh.points), np.array(mesh.triangles)
    N, segments = np.array(mesh.neighbors), np.asarray(mesh.segments)
    movable = np.arange(len(X)) >= mesh.n_boundary
    movable[np.unique(segments)] = False
    limit = triangle_limits(X, T, N, getattr(mesh.domain, "regions", None),
                            max_area) / (1.0 + AREA_MARGIN)
    stats = mesh.optimization
    before = float(triangle_quality(X, T).min(initial=1.0))
    keep = max(RELAXED_KEEP, getattr(stats, "min_ratio_generation", 0.0))
    changed = np.zeros(len(X), np.bool_)
    flips = relaxed_flips(X, T, N, segment_keys(segments, len(X)), movable,
                          ideal_counts(X, T, len(X)), limit, keep, RELAXED_PASSES,
                          RELAXED_SWEEPS, MEAN_HALVINGS, MEAN_STEPS, changed)
    if not flips:
        return mesh
    relaxed = X.copy()
    ptr, idx = stars(T, len(X))
    repaired = 0
    for _ in range(REPAIR_ROUNDS):
        taken = compass_polish(X, T, ptr, idx, mesh.n_boundary, before, movable, before)
        repaired += taken
        if not taken:
            break
    if repaired and (_areas(X, T) > limit).any():
        X = relaxed
    if RELAXED_POLISH:
        settled = X.copy()
        floor = float(triangle_quality(X, T).min(initial=1.0))
        near = np.zeros(len(X), np.bool_)  # the changed nodes and their neighbours
        near[np.unique(T[changed[T].any(axis=1)])] = True
        mean_polish(X, T, ptr, idx, mesh.n_boundary, RELAXED_POLISH, movable & near, floor,
                    MEAN_HALVINGS, 1.0, MEAN_STEPS)
        if (_areas(X, T) > limit).any():
            X = settled
    stats = replace(stats, flips=stats.flips + flips, min_ratio=_smallest_ratio(X, T))
    return replace(mesh, points=X, triangles=T, neighbors=N, optimization=stats)


def _repaired(mesh, max_area, field):
    """The repair before the last polish (:func:`_repaired_once`), its
    first balance's removals ranked by the mesh mean they leave; where that
    balance ran and the result keeps a triangle below REPAIR_BELOW, again
    with them ranked by their smallest ratio, and the better
    (:func:`_better`) kept: a removal that pays in the mean can take the
    node a corner's repair needed."""
    repaired, balanced = _repaired_once(mesh, max_area, field, True)
    if balanced and _smallest_ratio(repaired.points, repaired.triangles) < REPAIR_BELOW:
        other, _ = _repaired_once(mesh, max_area, field, False)
        if _better(other, repaired, field_count(field, mesh.points, mesh.triangles)):
            return other
    return repaired


def _repaired_once(mesh, max_area, field, by_mean):
    """The repair before the last polish (:mod:`bubblemesh._patch_repair`).

    In a mesh of at most BALANCE_BELOW elements, while the element count is
    more than BALANCE_WINDOW off the count ``field`` asks for
    (:func:`~bubblemesh.sizing.field_count`) and BALANCE_OPS nodes can bring
    it into that window (it is at most BALANCE_SHARE of that count outside),
    a node is removed where the mesh is most crowded (inserted where it is
    sparsest) without lowering its minimum or taking a triangle below
    POOR_RATIO (where a sharp corner sets the minimum, that bars nothing).
    Then the patches around the worst triangles are re-triangulated with
    one or two points inserted or a node removed where that raises their
    smallest ratio, the count within REPAIR_WINDOW of the field's or brought
    closer to it (first, for those below POOR_RATIO where no balance
    follows, within REPAIR_REACH of its own: :func:`_repair_counts`); both
    within the area bounds.  Where triangles below POOR_RATIO touching no
    sharp corner remain in a mesh of at most BALANCE_BELOW elements, they get
    a second try whose variants must lift every changed triangle to
    POOR_RATIO and may lower the summed ratio by POOR_SUM_DROP (the mean of a
    small mesh moves by O(1/m) with any local change, past MEAN_DROP).  The
    repair of the triangles below REPAIR_BELOW after it adds no triangle below
    POOR_RATIO (past a poor triangle its smallest ratio rising is no reason to
    make more of them).  In meshes of
    at most BALANCE_BELOW elements the repair then goes on with the count
    free to go REPAIR_SPARE nodes further (a node inserted where a corner or
    a row lacks one), is balanced back into BALANCE_WINDOW
    by removals where the mesh is most crowded that keep the smallest ratio
    above the plain repair's, and is kept if it ends better
    (:func:`_spare_kept`): a node moved, in effect, from where the field has
    one too many to where the worst triangle needs one.  An inserted node's
    radius is half its mean edge (as the area bound's).  With ``by_mean``
    the first balance takes the nodes of the first row of walls finer than
    FINE_WALL times the field's size last (:func:`_fine_walls_first_row`)
    and ranks its removals and insertions by the mesh mean they leave,
    else by their smallest ratio (:func:`~bubblemesh._patch_repair.balance_count`); the
    balance after the spare repair, whose floor keeps the minimum, always
    the first way.  Returns (mesh, whether the first balance ran)."""
    X, T = mesh.points, mesh.triangles
    poor = REPAIR_OPS and triangle_quality(X, T).min(initial=1.0) < REPAIR_BELOW
    if not poor and len(T) > BALANCE_BELOW:
        return mesh, False
    asked = field_count(field, X, T)
    miss = abs(len(T) - min(max(len(T), asked * (1.0 - BALANCE_WINDOW)),
                            asked * (1.0 + BALANCE_WINDOW)))
    # beyond, BALANCE_OPS nodes cannot mend it, or mending it would remake the mesh
    off = 0 < miss <= min(2 * BALANCE_OPS, BALANCE_SHARE * asked)
    if not off and not poor:
        return mesh, False
    segments = np.asarray(mesh.segments)
    regions = getattr(mesh.domain, "regions", None)
    N, old, operations = mesh.neighbors, np.arange(len(X)), 0

    def run(step, *args):  # boundary nodes stay first: only free nodes are removed
        nonlocal X, T, N, old, operations
        movable = np.arange(len(X)) >= mesh.n_boundary
        movable[np.unique(segments)] = False
        limit = triangle_limits(X, T, N, regions, max_area) / (1.0 + AREA_MARGIN)
        X, T, now, taken = step(X, T, segments, movable, limit, *args)
        old = np.where(now >= 0, old[np.maximum(now, 0)], -1)
        operations += taken
        if taken:
            N = _walled(T, neighbors_of(T), segments, len(X))

    def window(share):
        return asked * (1.0 - share), asked * (1.0 + share)

    if off:
        shielded = _fine_walls_first_row(X, T, segments, field) if by_mean else None
        run(balance_count, window(BALANCE_WINDOW), field, BALANCE_OPS, MEAN_HALVINGS,
            MEAN_STEPS, None, shielded, by_mean, POOR_RATIO)
    if poor:
        before = len(T)
        if triangle_quality(X, T).min(initial=1.0) < POOR_RATIO:
            run(repair_worst, POOR_RATIO, REPAIR_OPS, _repair_counts(len(T), asked),
                MEAN_HALVINGS, MEAN_STEPS)
            sharp = sharp_corner_flags(mesh.domain, X)
            if _poor_off(X, T, sharp) and len(T) <= BALANCE_BELOW:
                # a small mesh's mean moves by O(1/m) with any local change: no repair of
                # a poor triangle fits in MEAN_DROP there
                run(repair_worst, POOR_RATIO, REPAIR_OPS, _repair_counts(len(T), asked),
                    MEAN_HALVINGS, MEAN_STEPS, max(MEAN_DROP, POOR_SUM_DROP / len(T)), sharp,
                    POOR_RATIO)
        run(repair_worst, REPAIR_BELOW, REPAIR_OPS, window(REPAIR_WINDOW), MEAN_HALVINGS,
            MEAN_STEPS, MEAN_DROP, None, None, True)
        low, high = window(REPAIR_WINDOW)
        blocked = not low + 2 <= len(T) <= high - 4  # two points add four triangles
        if (REPAIR_SPARE and blocked and before <= BALANCE_BELOW
                and abs(len(T) / asked - 1.0) <= COUNT_TOL):
            plain = (X, T, N, old, operations)
            plain_min = float(triangle_quality(X, T).min(initial=1.0))
            plain_fits = abs(len(T) / asked - 1.0) <= REPAIR_WINDOW
            floor = plain_min if plain_fits else min(plain_min, REPAIR_BELOW)
            run(repair_worst, REPAIR_BELOW, REPAIR_OPS, (low - 2 * REPAIR_SPARE,
                                                           high + 2 * REPAIR_SPARE),
                MEAN_HALVINGS, MEAN_STEPS, MEAN_DROP, None, None, True)
            if not window(BALANCE_WINDOW)[0] <= len(T) <= window(BALANCE_WINDOW)[1]:
                run(balance_count, window(BALANCE_WINDOW), field, BALANCE_OPS, MEAN_HALVINGS,
                    MEAN_STEPS, floor + RISE, _fine_walls_first_row(X, T, segments, field))
            if not _spare_kept(X, T, plain[:2], asked, floor):
                X, T, N, old, operations = plain
    if not operations:
        return mesh, off
    return _rebuilt(mesh, X, T, N, old, operations), off


def _rebuilt(mesh, X, T, N, old, operations):
    """``mesh`` with the repaired nodes X, triangles T and neighbours N;
    ``old`` each node's number in ``mesh`` (-1: inserted, its radius half
    its mean edge, as the area bound's); ``operations`` the repairs in all."""
    radii = np.where(old >= 0, np.asarray(mesh.radii)[np.maximum(old, 0)],
                     _half_mean_edge(X, T))
    stats = replace(mesh.optimization, repairs=operations,
                    repair_nodes=mesh.optimization.repair_nodes + len(X) - len(mesh.points),
                    min_ratio=_smallest_ratio(X, T))
    return replace(mesh, points=X, triangles=T, neighbors=N, radii=radii, optimization=stats)


def _poor_off(X, T, sharp):
    """Are there triangles below POOR_RATIO touching no ``sharp`` node?"""
    return bool(((triangle_quality(X, T) < POOR_RATIO) & ~sharp[T].any(axis=1)).any())


def _repair_counts(count, asked):
    """The element counts the repair of triangles below POOR_RATIO may leave:
    within REPAIR_WINDOW of the ``asked`` count; where no balance brings the
    count back (a mesh of more than BALANCE_BELOW elements, or a count
    already outside that window) also within REPAIR_REACH of its own
    ``count``, at most 4 REPAIR_OPS elements (two points add four
    triangles).  Else a count past the window forbids every insertion, and a
    narrow gap keeps its triangles below 0.7."""
    low, high = asked * (1.0 - REPAIR_WINDOW), asked * (1.0 + REPAIR_WINDOW)
    if count <= BALANCE_BELOW and low <= count <= high:
        return low, high
    reach = min(4 * REPAIR_OPS, REPAIR_REACH * count)
    return min(low, count - reach), max(high, count + reach)


def _swapped(mesh, max_area, field):
    """Node swaps on the chosen mesh, if it has at most BALANCE_BELOW
    elements: a point inserted where the count balance would insert one,
    then a node removed where it would remove one
    (:func:`~bubblemesh._patch_repair.balance_count`, both ranked by the
    mesh mean they leave, neither lowering the mesh's minimum nor taking a
    triangle below POOR_RATIO, both within the area bounds), the pair kept
    if the mesh mean rises by more than SWAP_GAIN; SWAP_ROUNDS pairs at
    most, the first that does not pay ends them.  A node moves, in effect,
    from where the mesh is crowded to where it is sparse, the element count
    unchanged: the balance and the repair change the count and stop once it
    is inside their window."""
    X, T = mesh.points, mesh.triangles
    if not SWAP_ROUNDS or len(T) > BALANCE_BELOW:
        return mesh
    segments = np.asarray(mesh.segments)
    regions = getattr(mesh.domain, "regions", None)
    N, old, swaps = mesh.neighbors, np.arange(len(X)), 0
    for _ in range(SWAP_ROUNDS):
        Y, U, M, kept = X, T, N, old
        for counts in ((len(T) + 2, math.inf), (0, len(T))):  # one point in, one node out
            movable = np.arange(len(Y)) >= mesh.n_boundary
            movable[np.unique(segments)] = False
            limit = triangle_limits(Y, U, M, regions, max_area) / (1.0 + AREA_MARGIN)
            Y, U, now, taken = balance_count(Y, U, segments, movable, limit, counts, field, 1,
                                             MEAN_HALVINGS, MEAN_STEPS, least=POOR_RATIO)
            if not taken:
                break
            kept = np.where(now >= 0, kept[np.maximum(now, 0)], -1)
            M = _walled(U, neighbors_of(U), segments, len(Y))
        else:
            q, r = triangle_quality(X, T), triangle_quality(Y, U)
            if (len(U) == len(T) and r.mean() > q.mean() + SWAP_GAIN
                    and r.min() >= q.min()):
                X, T, N, old, swaps = Y, U, M, kept, swaps + 1
                continue
        break
    if not swaps:
        return mesh
    radii = np.where(old >= 0, np.asarray(mesh.radii)[np.maximum(old, 0)],
                     _half_mean_edge(X, T))
    stats = replace(mesh.optimization, repairs=mesh.optimization.repairs + 2 * swaps,
                    min_ratio=_smallest_ratio(X, T))
    return replace(mesh, points=X, triangles=T, neighbors=N, radii=radii, optimization=stats)


def _pruned(mesh, max_area, field):
    """Free nodes removed from the chosen mesh, if it has at most
    BALANCE_BELOW elements, while each removal raises the mesh mean by more
    than SWAP_GAIN and leaves the count within PRUNE_WINDOW under the
    field's and PRUNE_SHARE under the mesh's own
    (:func:`~bubblemesh._patch_repair.prune_nodes`: of the nodes whose stars
    have the lowest mean, the removal leaving the highest mesh mean, no
    changed triangle below the mesh's minimum or POOR_RATIO, the area bounds
    kept); PRUNE_ROUNDS at most.  The removals pay most where input points
    are fixed inside the domain: §2 fills the gaps between them with nodes
    the field asks for but the points leave no good place for (three or six
    triangles near 0.78 around a node in one triangle of an otherwise
    regular set).  The share keeps the count near the one the ranking chose
    the mesh at: a mesh under 200 elements loses no node for a small gain.
    Where that floor stopped them, removals of a clear gain (over WIDE_GAIN
    each) go on down to WIDE_WINDOW under the field's count and WIDE_SHARE
    under the mesh's: one node too many at the end of a strip is worth a
    count a little further from the field's, still within its target."""
    X, T = mesh.points, mesh.triangles
    if not PRUNE_ROUNDS or len(T) > BALANCE_BELOW:
        return mesh
    segments = np.asarray(mesh.segments)
    regions = getattr(mesh.domain, "regions", None)
    asked, count = field_count(field, X, T), len(T)
    movable = np.arange(len(X)) >= mesh.n_boundary
    movable[np.unique(segments)] = False
    kept, N, taken = np.arange(len(X)), mesh.neighbors, 0
    for window, share, gain in ((PRUNE_WINDOW, PRUNE_SHARE, SWAP_GAIN),
                                (WIDE_WINDOW, WIDE_SHARE, WIDE_GAIN)):
        limit = triangle_limits(X, T, N, regions, max_area) / (1.0 + AREA_MARGIN)
        least = max(asked * (1.0 - window), count * (1.0 - share))
        X, T, old, took = prune_nodes(X, T, segments, movable, limit, least, PRUNE_ROUNDS,
                                      MEAN_HALVINGS, MEAN_STEPS, gain, POOR_RATIO)
        if took:
            kept, movable, taken = kept[old], movable[old], taken + took
            N = _walled(T, neighbors_of(T), segments, len(X))
        if len(T) - 2 >= least and took < PRUNE_ROUNDS:
            break  # no removal paid even the small gain: none pays the clear one
    if not taken:
        return mesh
    stats = replace(mesh.optimization, repairs=mesh.optimization.repairs + taken,
                    min_ratio=_smallest_ratio(X, T))
    return replace(mesh, points=X, triangles=T, neighbors=N,
                   radii=np.asarray(mesh.radii)[kept], optimization=stats)


def _fine_walls_first_row(X, T, segments, field):
    """The nodes of the triangles on the nodes of wall pieces shorter than
    FINE_WALL times the field's size: such a wall's first row follows its
    spacing, and a node taken out of it leaves a wall node with two
    triangles (:func:`~bubblemesh._patch_repair.balance_count` takes them
    last)."""
    S = np.asarray(segments)
    length = np.hypot(*(X[S[:, 1]] - X[S[:, 0]]).T)
    fine = np.zeros(len(X), np.bool_)
    fine[S[length < FINE_WALL * np.asarray(field(0.5 * (X[S[:, 0]] + X[S[:, 1]])))].ravel()] = True
    shielded = np.zeros(len(X), np.bool_)
    shielded[T[fine[T].any(axis=1)].ravel()] = True
    return shielded


def _minmaxed(mesh, max_area):
    """Joint min-max moves of the free nodes around the worst triangles
    (:mod:`bubblemesh._minmax`), MINMAX_ROUNDS patches at most, within the
    area bounds, in meshes of at most FINAL_BELOW elements (in larger ones a
    few triangles weigh little and their solves would cost a quarter of the
    meshing time)."""
    if not MINMAX_ROUNDS or len(mesh.triangles) > FINAL_BELOW:
        return mesh
    X, T = np.array(mesh.points), np.asarray(mesh.triangles)
    movable = np.arange(len(X)) >= mesh.n_boundary
    movable[np.unique(np.asarray(mesh.segments))] = False
    limit = triangle_limits(X, T, mesh.neighbors, getattr(mesh.domain, "regions", None),
                            max_area) / (1.0 + AREA_MARGIN)
    if not minmax_patches(X, T, movable, limit, MINMAX_ROUNDS):
        return mesh
    stats = replace(mesh.optimization, min_ratio=_smallest_ratio(X, T))
    return replace(mesh, points=X, optimization=stats)


def _polished(mesh, max_area):
    """The very last step: FINAL_SWEEPS sweeps of gradient steps on the star
    mean radius ratio (eq. 10; :func:`~bubblemesh._odt.mean_polish`) of every
    free node, in meshes of at most FINAL_BELOW elements.

    A star's worst ratio is never taken below the mesh's minimum or KEEP, the
    larger; the nodes of triangles below KEEP are held, so those triangles
    stay as they are and no other falls below KEEP.  The result is kept if
    every triangle keeps its area bound, else run again with the nodes of
    those that broke it held (FINAL_TRIES runs at most).  The steps before
    polish only the stars they changed, and the flips and repairs leave their
    surroundings short of the stars' optimum."""
    X, T = np.array(mesh.points), np.asarray(mesh.triangles)
    if not FINAL_SWEEPS or len(T) > FINAL_BELOW:
        return mesh
    movable = np.arange(len(X)) >= mesh.n_boundary
    movable[np.unique(np.asarray(mesh.segments))] = False
    q = triangle_quality(X, T)
    floor = max(float(q.min(initial=1.0)), KEEP)
    movable[T[q < floor].ravel()] = False
    ptr, idx = stars(T, len(X))
    limit = triangle_limits(X, T, mesh.neighbors, getattr(mesh.domain, "regions", None),
                            max_area) / (1.0 + AREA_MARGIN)
    for _ in range(FINAL_TRIES):
        Y = X.copy()
        if not mean_polish(Y, T, ptr, idx, mesh.n_boundary, FINAL_SWEEPS, movable, floor,
                           MEAN_HALVINGS, 1.0, MEAN_STEPS):
            break
        over = _areas(Y, T) > limit
        if not over.any():
            stats = replace(mesh.optimization, min_ratio=_smallest_ratio(Y, T))
            return replace(mesh, points=Y, optimization=stats)
        movable[T[over].ravel()] = False  # and again, those triangles' nodes held
    return mesh


def _spare_kept(X, T, plain, asked, floor):
    """Is the repair that went past REPAIR_WINDOW, then balanced, better than
    the ``plain`` (X, T) repair within it: its count within REPAIR_WINDOW of
    ``asked``, and a smallest ratio above the plain one's and a mean at least
    its; or, where the plain count is outside that window, a smallest ratio of
    at least ``floor``?"""
    if abs(len(T) / asked - 1.0) > REPAIR_WINDOW:
        return False
    q, q_plain = triangle_quality(X, T), triangle_quality(*plain)
    if abs(len(q_plain) / asked - 1.0) > REPAIR_WINDOW:
        return bool(q.min() >= floor)
    return bool(q.min() > q_plain.min() + RISE and q.mean() >= q_plain.mean())


def _smallest_ratio(X, T):
    """The smallest eq. 10 ratio as Mesh.quality gives it (radius_ratio's
    formula), computed only on the triangles the numba kernel puts within
    1e-9 of its minimum (the two formulas differ in the last bits)."""
    q = triangle_quality(X, T)
    near = q <= q.min(initial=1.0) + 1e-9
    return float(radius_ratio(X, T[near]).min(initial=1.0))


def _insertion(mesh):
    """How the §2 mesh was made: 'frontal' or 'centroid' (the paper's)."""
    return getattr(mesh.generation, "insertion", "centroid")


def _first_row_first(mesh):
    """The frontal §2 mesh renumbered so that its first row (the interior
    nodes of the triangles that touch the boundary) comes right after the
    boundary, counted as the record's seeds: §3's forces hold them still like
    the frontal seeds of centroid insertion, for the same reason (released,
    they leave boundary nodes with two right-angled triangles)."""
    T = np.asarray(mesh.triangles)
    n_b, n = mesh.n_boundary, len(mesh.points)
    row = np.zeros(n, bool)
    row[T[(T < n_b).any(axis=1)].ravel()] = True
    row[:n_b] = False
    rest = np.arange(n_b, n)[~row[n_b:]]
    order = np.concatenate([np.arange(n_b), np.flatnonzero(row), rest])
    new_id = np.empty(n, np.int64)
    new_id[order] = np.arange(n)
    return Mesh(points=np.asarray(mesh.points)[order], triangles=new_id[T],
                neighbors=mesh.neighbors, radii=np.asarray(mesh.radii)[order],
                segments=mesh.segments, n_boundary=n_b, domain=mesh.domain,
                generation=replace(mesh.generation, seeds=int(row.sum())))
