"""Boundary nodes in geometric progression on the walls of sharp corners.

The refined boundary of paper §2.1 spaces a wall's nodes at the element size
h.  Beside a corner of angle theta the domain is then narrower than h for a
distance of about h / (2 sin(theta / 2)): no node fits inside, and the strips
between opposite wall nodes are triangles flattened towards the walls (eq. 10
ratio 0.49 next to a 20 degree corner, whatever the interior mesher does).
Here the nodes on a wall beside such a corner lie at distances r q^(k + s)
(k = 0, 1, ...) from it, with s = 0 on one wall and s = 1/2 on the other, so the
wedge fills with a zigzag of similar triangles, each with one edge on a wall
and its apex on the other.  r is the size at the corner (less where a wall is
so short that its first node would not fit in its first half, or its share), so the
corner's own triangle has legs r and r sqrt(q).  q maximises the zigzag's radius ratio
(eq. 10: 0.97 at 20 degrees) and, where an isosceles corner triangle could
reach 0.7 (SHARP_ANGLE and up), the corner triangle's too.  The progression
stops where its spacing would exceed the size field, or on a wall graded
from both ends where the two spacings meet (the middle between like corners,
the strip's widest point in a sliver triangle), else where its next node
would leave the wall;
but where the wall goes on nearly straight past its end (it turns by at most
ONWARD there), at the node from which that end is nearest q times as far, in
ratio (at least sqrt(q) times): the end stands in for the next node, and the
strip runs on.  The field splits the rest.  A corner of a few degrees or
less takes many nodes, all of them well shaped (q - 1 is about theta: some
190 on each wall at 1 degree); the field follows them (:func:`wedge_sources`).
Needles (corners under NEEDLE) are left alone: their progression would take
more than MAX_PER_WALL nodes.  Concentric shells around small input angles
play the same part in Ruppert-type refinement.

From SHARP_ANGLE to about 33 degrees the zigzag's corner triangle (legs r and
r sqrt(q)) stays below 0.7 (0.59 at 26.5 degrees), or meets it only with the
zigzag's own triangles near 0.7, though an isosceles one reaches it.  There a
boundary corner of two walls gets a ladder instead: s = 0 on both walls (the
corner's triangle isosceles), ratio g, and one node per layer on the bisector
(:func:`ladder_points`, fixed like the walls' nodes), so that each layer
between distances d and g d is four triangles around it; g and the node's
place maximise their worst ratio (0.79 at 26.5 degrees).  A ladder runs while
the wedge is narrower than LADDER_WIDTH h, on both walls alike; one without a
whole layer, or that would stop at a wall's far end or at anything else in its
wedge rather than where the wedge widens, is a zigzag again (its last layer
would meet the field's long pieces).
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np

from bubblemesh.domain import Domain
from bubblemesh.quality import radius_ratio

__all__ = ["corner_angles", "best_corner_ratio", "zigzag_ratio", "ladder_parameters",
           "wedge_parameters", "wedge_sources", "ladder_points", "SHARP_ANGLE"]

MAX_PER_WALL = 4096  # graded nodes at most on one wall beside one corner
CLEARANCE_BLOCK = 1 << 20  # corner-segment pairs per block of a ladder's clearance
LADDER_WIDTH = 1.3  # a ladder runs on while the wedge is narrower than this times the size
LADDER_TOP = math.radians(40.0)  # the ladder's table spans SHARP_ANGLE to this
NEEDLE = math.radians(0.1)  # sharper corners are needles: a progression would crowd them
ONWARD = math.radians(30.0)  # a wall whose far end turns by at most this goes on past it
_GOLDEN = 0.5 * (math.sqrt(5.0) - 1.0)


def corner_angles(domain: Domain) -> np.ndarray:
    """Interior angle (radians, in (0, 2 pi]) at every node of ``domain``, in
    the order of ``domain.points`` (the domain lies left of its segments).  A
    node a walk passes more than once gets its smallest wedge; the tip of a
    crack (the walk turns back) and a free point get 2 pi: no corner there."""
    P = np.asarray(domain.points)
    angles = np.full(len(P), 2 * np.pi)
    if not len(domain.loops):
        return angles
    ix = np.concatenate(domain.loops)
    lengths = np.array([len(loop) for loop in domain.loops])
    start = np.repeat(np.cumsum(lengths) - lengths, lengths)  # all loops at once
    local = np.arange(len(ix)) - start
    size = np.repeat(lengths, lengths)
    v = P[ix]
    to_prev = P[ix[start + (local - 1) % size]] - v
    to_next = P[ix[start + (local + 1) % size]] - v
    cross = to_next[:, 0] * to_prev[:, 1] - to_next[:, 1] * to_prev[:, 0]
    dot = (to_next * to_prev).sum(axis=1)
    wedge = np.mod(np.arctan2(cross, dot), 2 * np.pi)
    wedge[wedge == 0.0] = 2 * np.pi  # turned back along the same segment
    np.minimum.at(angles, ix, wedge)
    return angles


def best_corner_ratio(theta):
    """Eq. 10 of the isosceles triangle with apex angle theta (its best at a
    corner of angle theta): 8 sin(theta / 2) sin^2((pi - theta) / 4)."""
    theta = np.asarray(theta, dtype=np.float64)
    return 8.0 * np.sin(theta / 2) * np.sin((np.pi - theta) / 4) ** 2


def _sharp_angle(target: float = 0.7) -> float:
    """The apex angle below which best_corner_ratio < target (bisection)."""
    lo, hi = 1e-6, math.pi / 3
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if best_corner_ratio(mid) < target else (lo, mid)
    return hi


SHARP_ANGLE = _sharp_angle()  # ~26.1 degrees: no triangle at a sharper corner reaches 0.7


def _ratios(corners):
    """Eq. 10 of triangles given as (..., 3, 2) corner arrays."""
    flat = np.asarray(corners, dtype=np.float64).reshape(-1, 2)
    return radius_ratio(flat, np.arange(len(flat)).reshape(-1, 3)).reshape(corners.shape[:-2])


def _apexes(theta, q):
    """sqrt(q) (cos theta, sin theta), broadcast over theta and q."""
    s = np.sqrt(q)
    return np.stack(np.broadcast_arrays(s * np.cos(theta), s * np.sin(theta)), axis=-1)


def _zigzag_quality(theta, q):
    """Eq. 10 of the triangle (1, 0), (q, 0), sqrt(q) (cos theta, sin theta):
    every triangle of the zigzag is similar to it."""
    apex = _apexes(theta, q)
    one = np.broadcast_to([1.0, 0.0], apex.shape)
    far = np.stack([np.broadcast_to(q, apex.shape[:-1]), np.zeros(apex.shape[:-1])], axis=-1)
    return _ratios(np.stack([one, far, apex], axis=-2))


def _corner_quality(theta, q):
    """Eq. 10 of the corner's own triangle (0, 0), (1, 0), sqrt(q) (cos theta,
    sin theta) where a triangle there can reach 0.7, else 1 (it cannot)."""
    apex = _apexes(theta, q)
    one = np.broadcast_to([1.0, 0.0], apex.shape)
    ratio = _ratios(np.stack([np.zeros(apex.shape), one, apex], axis=-2))
    return np.where(theta < SHARP_ANGLE, 1.0, ratio)


def _golden(quality, theta, lo, hi, rounds=48):
    """argmax over x in (lo, hi) of quality(theta, x), which rises then falls
    in x (golden-section search, broadcast over theta)."""
    lo, hi = np.full(theta.shape, float(lo)), np.full(theta.shape, float(hi))
    for _ in range(rounds):  # 48 shrink the bracket to 0.618**48 of its width: far below any use
        a = hi - _GOLDEN * (hi - lo)
        b = lo + _GOLDEN * (hi - lo)
        left = quality(theta, a) >= quality(theta, b)
        hi, lo = np.where(left, b, hi), np.where(left, lo, a)
    return 0.5 * (lo + hi)


def _best_ratio(quality, theta):
    """argmax over q in (1, 4] of quality(theta, q)."""
    return _golden(quality, theta, 1.0 + 1e-6, 4.0)


def _both_quality(theta, q):
    return np.minimum(_zigzag_quality(theta, q), _corner_quality(theta, q))


def _ladder_triangles(theta, g, t):
    """The four triangles of the ladder's layer between distances 1 and g from
    a corner of angle theta, around its node at (1 + t (g - 1)) cos(theta / 2)
    on the bisector, as (..., 4, 3, 2) corners."""
    theta, g, t = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64) for v in (theta, g, t)))
    c, s = np.cos(theta / 2), np.sin(theta / 2)
    zero = np.zeros(theta.shape)
    a0, b0 = np.stack([c, s], axis=-1), np.stack([c, -s], axis=-1)
    a1, b1 = g[..., None] * a0, g[..., None] * b0
    x = np.stack([c * (1.0 + t * (g - 1.0)), zero], axis=-1)
    tris = [(a0, b0, x), (b0, b1, x), (b1, a1, x), (a1, a0, x)]
    return np.stack([np.stack(tri, axis=-2) for tri in tris], axis=-3)


def _ladder_layer(theta, g, t):
    """The worse eq. 10 ratio of the ladder layer's four triangles (as
    16 A^2 / (l1 l2 l3 (l1 + l2 + l3)), inline: the searches call it often)."""
    p = _ladder_triangles(theta, g, t)
    e = np.roll(p, -1, axis=-2) - p
    lengths = np.hypot(e[..., 0], e[..., 1])
    area = 0.5 * (e[..., 0, 0] * e[..., 1, 1] - e[..., 0, 1] * e[..., 1, 0])
    ratio = 16.0 * area * area / (lengths.prod(axis=-1) * lengths.sum(axis=-1))
    return ratio.min(axis=-1)


def _ladder_node(theta, g):
    """t of :func:`_ladder_triangles` that maximises the layer's worst ratio
    (to 1e-5: the ratios are flat at their best)."""
    return _golden(lambda th, t: _ladder_layer(th, g, t), theta, 0.0, 1.0, rounds=24)


def _ladder_quality(theta, g):
    return _ladder_layer(theta, g, _ladder_node(theta, g))


@functools.cache
def _ladder_table():
    """Per angle of a grid from SHARP_ANGLE to LADDER_TOP: the ratio g that
    maximises the ladder layers' worst ratio, the node's t there, and whether
    the ladder's worst (its layers' and the isosceles corner triangle's) beats
    the zigzag's (at the zigzag's own ratio).  Searched once, on first use: two
    nested golden sections over every angle cost a third of a second."""
    theta = np.linspace(SHARP_ANGLE, LADDER_TOP, 81)
    g = _golden(_ladder_quality, theta, 1.0 + 1e-6, 4.0, rounds=32)
    q = zigzag_ratio(theta)
    zigzag = np.minimum(_zigzag_quality(theta, q), _corner_quality(theta, q))
    better = np.minimum(_ladder_quality(theta, g), best_corner_ratio(theta)) > zigzag
    return theta, g, _ladder_node(theta, g), better


def ladder_parameters(theta):
    """(g, t, wanted) beside corners of angle theta: the ladder's progression
    ratio, where its node lies in a layer (:func:`_ladder_triangles`), and
    whether the corner gets a ladder rather than a zigzag: from SHARP_ANGLE,
    where an isosceles corner triangle reaches 0.7 but the zigzag's corner
    triangle does not (or only with the zigzag's own triangles near 0.7), up
    to where the zigzag's worst is as good as the ladder's.  Interpolated in
    the table of :func:`_ladder_table`."""
    grid, g, t, better = _ladder_table()
    theta = np.asarray(theta, dtype=np.float64)
    limit = grid[np.argmin(better)] if not better.all() else LADDER_TOP
    wanted = (theta >= SHARP_ANGLE) & (theta < limit)
    return np.interp(theta, grid, g), np.interp(theta, grid, t), wanted


def zigzag_ratio(theta) -> np.ndarray:
    """The progression ratio q beside a corner of angle theta: the one that
    maximises the worse of the zigzag's and the corner triangle's eq. 10
    ratios where that reaches 0.7, else the zigzag's alone (a corner of about
    26 to 27.5 degrees: one triangle below 0.7, not every one of the zigzag)."""
    theta = np.asarray(theta, dtype=np.float64)
    if not theta.size:  # no sharp corner: spare the searches' fixed cost
        return np.empty(theta.shape)
    both = _best_ratio(_both_quality, theta)
    alone = _best_ratio(_zigzag_quality, theta)
    return np.where(_both_quality(theta, both) >= 0.7, both, alone)


class _Walls(NamedTuple):
    """The graded walls of :func:`_progressions`, one row per wall end at a
    corner: its segment, whether the corner is the segment's start, the
    corner's node id and position, the vector from it along the wall, whether
    the corner gets a ladder, the progression's ratio, and per node (a column
    each, up to MAX_PER_WALL) its parameter u on the segment from the corner,
    the mask of those kept, its position, its distance and its spacing."""

    seg: np.ndarray
    at_start: np.ndarray
    node: np.ndarray
    corner: np.ndarray
    away: np.ndarray
    ladder: np.ndarray
    q: np.ndarray
    u: np.ndarray
    fits: np.ndarray
    where: np.ndarray
    dist: np.ndarray
    spacing: np.ndarray


def _progressions(a, b, node_a, node_b, theta, size, below, free, ladder_walls):
    """Per wall end at a corner sharper than ``below`` (and not a needle), the
    progression of its graded nodes (:class:`_Walls`).  A corner of exactly two
    walls, both ``ladder_walls`` (per segment; not an interior constraint's,
    whose other side would meet the ladder's small pieces), gets a ladder where
    :func:`ladder_parameters` wants one and it holds a layer: both walls in
    phase, as far as both go and no farther than the nearest of the ``free``
    points or of the segments not at the corner, so that the ladder's layers
    stay in the wedge.  Elsewhere the zigzag."""
    n = len(a)
    ends = np.concatenate([node_a, node_b])
    graded = (theta[ends] < below) & (theta[ends] >= NEEDLE)
    seg = np.concatenate([np.arange(n), np.arange(n)])[graded]
    at_start = np.arange(2 * n)[graded] < n
    node = ends[graded]
    far = np.concatenate([node_b, node_a])[graded]
    corner = np.where(at_start[:, None], a[seg], b[seg])
    away = np.where(at_start[:, None], b[seg], a[seg]) - corner
    ladder = (ladder_parameters(theta[node])[2] & (_walls_at(node, far) == 2)
              & _all_at(node, np.asarray(ladder_walls, bool)[seg]))
    clearance = _clearance(corner, node, a, b, node_a, node_b, free, ladder)
    *graded, open_end = _graded(theta, size, below, node, far, corner, away, ladder, clearance)
    walls = _Walls(seg, at_start, node, corner, away, *graded)
    # a ladder needs a layer, two nodes on each wall, and room past its last one (it
    # stops where the wedge is wide, not at a wall's end or an obstacle): else the zigzag
    unfit = walls.ladder & ((walls.fits.sum(axis=1) < 2) | ~open_end)
    if not unfit.any():
        return walls
    at = np.unique(node, return_inverse=True)[1]
    dropped = np.zeros(at.max() + 1, bool)
    dropped[at[unfit]] = True
    ladder &= ~dropped[at]
    graded = _graded(theta, size, below, node, far, corner, away, ladder, clearance)[:-1]
    return _Walls(seg, at_start, node, corner, away, *graded)


def _graded(theta, size, below, node, far, corner, away, ladder, clearance):
    """The rest of :class:`_Walls` for the wall ends of :func:`_progressions`
    (``away`` from the corner along the wall), with the ``ladder`` mask, and
    per wall end whether it ends open: its first node not kept short of the
    clearance, with room for a piece past it on the wall (or past the split
    of a wall graded from both ends), or, for a ladder of at least two
    layers, on the wall where the wedge is wider than LADDER_WIDTH times the
    size."""
    length = np.hypot(away[:, 0], away[:, 1])
    # a wall graded from both ends is shared where the two progressions' spacings meet
    # (the middle if its corners are alike), so the strip between them widens to there
    # and not past it; else the progression may run on while its next node is on the wall
    shared = (theta[far] < below) & (theta[far] >= NEEDLE)
    zigzag = zigzag_ratio(theta[node])
    split = np.ones(len(node))
    theirs = zigzag_ratio(theta[far[shared]]) - 1.0
    split[shared] = theirs / (zigzag[shared] - 1.0 + theirs)
    # the walls at a corner alternate by direction: the zigzag's half-step offset
    order = np.lexsort((np.arctan2(away[:, 1], away[:, 0]), node))
    first = np.searchsorted(node[order], node[order], side="left")
    offset = np.empty(len(node))
    offset[order] = 0.5 * ((np.arange(len(node)) - first) % 2)
    offset[ladder] = 0.0
    q = np.where(ladder, ladder_parameters(theta[node])[0], zigzag)
    # the corner's r: its size, but small enough that every wall there gets its first node
    # (and a ladder its first layer)
    first = np.minimum(np.minimum(split, 0.5) * length / q**offset,
                       np.where(ladder, clearance / q**2, np.inf))
    if len(corner):
        first = np.minimum(first, size(corner))
    at = np.unique(node, return_inverse=True)[1]
    r = np.full(at.max(initial=-1) + 1, np.inf)
    np.minimum.at(r, at, first)
    r = r[at]
    # as many columns as the longest progression can use: one node past its wall's end
    steps = np.log(np.maximum(length / r, 1.0)) / np.log(q) if len(r) else np.zeros(1)
    k = np.arange(min(MAX_PER_WALL, int(steps.max()) + 2))
    dist = r[:, None] * q[:, None] ** (k[None, :] + offset[:, None])
    u = dist / length[:, None]
    where = corner[:, None, :] + u[:, :, None] * away[:, None, :]
    h = size(where.reshape(-1, 2)).reshape(u.shape) if len(corner) else u
    # where the wall goes on nearly straight past its end, a zigzag's last node is the
    # one whose step to that end is nearest q (in ratio); a ladder's last layer, and a
    # wall that ends at a corner (the short piece would crowd it), keep a whole step
    onward = ~ladder & (np.abs(theta[far] - np.pi) <= ONWARD)
    last = np.where(onward, np.sqrt(q), q)[:, None]
    inside = np.where(shared[:, None], u <= split[:, None], u * last <= 1.0)
    # a zigzag runs while its spacing is below the field's size, a ladder while the
    # wedge is narrower than LADDER_WIDTH times it
    wide = np.where(ladder[:, None], 2.0 * np.sin(0.5 * theta[node])[:, None] / LADDER_WIDTH,
                    q[:, None] - 1.0) * dist
    fits = np.logical_and.accumulate(inside & (wide <= h), axis=1)
    if ladder.any():
        fits = _ladder_fits(fits, ladder, at, dist, clearance)
    count = fits.sum(axis=1)
    after = np.minimum(count, len(k) - 1)[:, None]
    # closed: the next node would pass a wall's far end (not the split of a wall the
    # other corner grades too) or the clearance
    middle = shared[:, None] & (u > split[:, None])
    beyond = dist >= clearance[:, None]
    closed = ~middle & ((u * last > 1.0) | beyond)
    open_end = (count == len(k)) | ~np.take_along_axis(closed, after, axis=1)[:, 0]
    # a ladder of two layers or more whose first node not kept lies on its wall where
    # the wedge is wide stops where the wedge widens, though its wall ends a layer later
    widened = ~middle & ((u > 1.0) | (wide <= h) | beyond)
    open_end |= ladder & (count >= 3) & ~np.take_along_axis(widened, after, axis=1)[:, 0]
    return ladder, q, u, fits, where, dist, (q[:, None] - 1.0) * dist, open_end


def _walls_at(node, far):
    """Per wall end: how many distinct walls (far ends) its corner has."""
    pairs = np.unique(np.column_stack([node, far]), axis=0)
    corners, count = np.unique(pairs[:, 0], return_counts=True)
    return count[np.searchsorted(corners, node)]


def _all_at(node, flag):
    """Per wall end: whether ``flag`` holds at every wall end of its corner."""
    corners, at = np.unique(node, return_inverse=True)
    every = np.ones(len(corners), bool)
    np.logical_and.at(every, at, flag)
    return every[at]


def _clearance(corner, node, a, b, node_a, node_b, free, rows):
    """For the ``rows`` of the wall ends: the distance from their corner to the
    nearest of the ``free`` points and of the segments a -> b not at it (inf
    elsewhere).  Corner by segment, in blocks of about CLEARANCE_BLOCK pairs."""
    out = np.full(len(node), np.inf)
    corners, first = np.unique(node[rows], return_index=True)
    where = corner[rows][first]
    e = b - a
    ee = np.maximum((e * e).sum(axis=1), 1e-300)
    step = max(1, CLEARANCE_BLOCK // max(len(a), 1))
    near = np.empty(len(corners))
    for lo in range(0, len(corners), step):
        c = where[lo:lo + step, None, :]
        t = np.clip(((c - a) * e).sum(axis=2) / ee, 0.0, 1.0)
        d = np.hypot(*np.moveaxis(a + t[:, :, None] * e - c, 2, 0))
        at = (node_a == corners[lo:lo + step, None]) | (node_b == corners[lo:lo + step, None])
        d[at] = np.inf
        points = np.hypot(*np.moveaxis(free - c, 2, 0))
        near[lo:lo + step] = np.minimum(d.min(axis=1, initial=np.inf),
                                        points.min(axis=1, initial=np.inf))
    out[rows] = near[np.searchsorted(corners, node[rows])]
    return out


def _ladder_fits(fits, ladder, at, dist, clearance):
    """``fits`` with each ladder's walls cut to the nodes both walls keep and
    that lie nearer their corner than its clearance: a layer needs a node on
    each wall."""
    count = np.where(ladder, (fits & (dist < clearance[:, None])).sum(axis=1), MAX_PER_WALL)
    common = np.full(at.max(initial=-1) + 1, MAX_PER_WALL)
    np.minimum.at(common, at, count)
    kept = np.arange(fits.shape[1])[None, :] < common[at][:, None]
    return np.where(ladder[:, None], fits & kept, fits)


def ladder_points(domain: Domain, size, below) -> np.ndarray:
    """The ladders' interior nodes (the module docstring), one per layer: on
    the corner's bisector, at (1 + t (g - 1)) cos(theta / 2) times the layer's
    inner distance.  (m, 2) float64, in the order of the domain's nodes."""
    node_a, node_b = _segment_nodes(domain)
    P = np.asarray(domain.points)
    theta = corner_angles(domain)
    w = _progressions(P[node_a], P[node_b], node_a, node_b, theta, size, below,
                      free_points(domain), ~np.asarray(domain.interior, bool))
    rows = np.flatnonzero(w.ladder)
    if not len(rows):
        return np.zeros((0, 2))
    rows = rows[np.unique(w.node[rows], return_index=True)[1]]  # one wall per corner
    bisector = _bisectors(w.node, w.away)[0][rows]  # a ladder's corner has two walls
    half = 0.5 * theta[w.node[rows]]
    g, t, _ = ladder_parameters(theta[w.node[rows]])
    layers = np.maximum(w.fits[rows].sum(axis=1) - 1, 0)
    inner = w.dist[rows][:, :-1]
    step = (1.0 + t * (g - 1.0)) * np.cos(half)
    where = w.corner[rows][:, None, :] + (inner * step[:, None])[:, :, None] * bisector[:, None, :]
    keep = np.arange(inner.shape[1])[None, :] < layers[:, None]
    return where[keep]


def wedge_parameters(a, b, node_a, node_b, theta, size, below, free, ladder_walls):
    """Graded node parameters on segments a -> b beside corners sharper than
    ``below`` (module docstring).

    ``node_a``, ``node_b`` are the node ids of the segments' ends, ``theta`` the
    corner angle per node id, ``size`` the element size (n, 2) -> (n,),
    ``free`` the domain's free points (a ladder stays nearer its corner),
    ``ladder_walls`` per segment whether a ladder may stand on it.
    Returns (seg, t, lo, hi): parameters t in (0, 1) of the graded nodes of
    segment seg (sorted by segment, then t), and per segment the interval
    [lo, hi] of t left to split to the size field."""
    n = len(a)
    lo, hi = np.zeros(n), np.ones(n)
    w = _progressions(a, b, node_a, node_b, theta, size, below, free, ladder_walls)
    seg, at_start, u, fits = w.seg, w.at_start, w.u, w.fits
    count = fits.sum(axis=1)
    last = np.where(count > 0, u[np.arange(len(u)), np.maximum(count - 1, 0)], 0.0)
    np.maximum.at(lo, seg[at_start], last[at_start])
    np.minimum.at(hi, seg[~at_start], 1.0 - last[~at_start])
    owner = np.repeat(seg, count)
    t = np.where(np.repeat(at_start, count), u[fits], 1.0 - u[fits])
    order = np.lexsort((t, owner))
    return owner[order], t[order], lo, hi


def _segment_nodes(domain: Domain):
    """The node ids at the start and the end of every segment of the loops."""
    node_a = np.concatenate(domain.loops)
    node_b = np.concatenate([np.roll(ix, -1) for ix in domain.loops])
    return node_a, node_b


def free_points(domain: Domain) -> np.ndarray:
    """The domain's nodes on no segment, (m, 2)."""
    P = np.asarray(domain.points)
    on_loops = np.zeros(len(P), bool)
    on_loops[np.concatenate(domain.loops)] = True
    return P[~on_loops]


def wedge_sources(domain: Domain, size, below, outer_below=None):
    """The graded nodes of ``domain``'s walls (where :func:`wedge_parameters`
    puts them) and their spacing (q - 1) times the distance to the corner:
    size sources that make the field follow the zigzag, so the element bubbles
    there (eq. 3-4) are the zigzag's and not the far larger field's.  At a
    corner of two walls the same spacings also lie on its bisector, level
    with each node: else the field inside the wedge is a wall's spacing grown
    by the gradation over half the wedge's width, and its integral asks for
    fewer triangles than the zigzag holds.  With ``outer_below`` only those
    beside corners sharper than it on the boundary's walls, not on interior
    constraints (whose other side they would refine too)."""
    node_a, node_b = _segment_nodes(domain)
    P = np.asarray(domain.points)
    theta = corner_angles(domain)
    w = _progressions(P[node_a], P[node_b], node_a, node_b, theta, size, below,
                      free_points(domain), ~np.asarray(domain.interior, bool))
    fits = w.fits
    if outer_below is not None:
        kept = ~np.asarray(domain.interior, bool)[w.seg] & (theta[w.node] < outer_below)
        fits = fits & kept[:, None]
    bisector, two = _bisectors(w.node, w.away)
    level = w.dist * np.cos(0.5 * theta[w.node])[:, None]
    axis = w.corner[:, None, :] + level[:, :, None] * bisector[:, None, :]
    on = fits & two[:, None]
    return (np.vstack([w.where[fits], axis[on]]),
            np.concatenate([w.spacing[fits], w.spacing[on]]))


def _bisectors(node, away):
    """Per wall end: the unit bisector of its corner's walls, and whether the
    corner has exactly two walls (elsewhere the bisector is meaningless)."""
    if not len(node):
        return np.zeros((0, 2)), np.zeros(0, bool)
    at = np.unique(node, return_inverse=True)[1]
    total = np.zeros((at.max() + 1, 2))
    np.add.at(total, at, away / np.hypot(*away.T)[:, None])
    length = np.hypot(*total.T)
    two = (np.bincount(at) == 2) & (length > 0)
    return total[at] / np.where(two, length, 1.0)[at][:, None], two[at]
