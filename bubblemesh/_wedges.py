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
so short that its first node would not fit in its first half), so the
corner's own triangle has legs r and r sqrt(q).  q maximises the zigzag's radius ratio
(eq. 10: 0.97 at 20 degrees) and, where an isosceles corner triangle could
reach 0.7 (SHARP_ANGLE and up), the corner triangle's too.  The progression
stops where its spacing would exceed the size field, or at the middle of a
wall graded from both ends (else where its next node would leave the wall);
the field splits the rest.  Needles (corners under NEEDLE) are
left alone: their progression would take more than MAX_PER_WALL nodes of
nearly one position.  Concentric shells around small input angles play the
same part in Ruppert-type refinement.
"""

from __future__ import annotations

import math

import numpy as np

from bubblemesh.domain import Domain
from bubblemesh.quality import radius_ratio

__all__ = ["corner_angles", "best_corner_ratio", "zigzag_ratio", "wedge_parameters",
           "wedge_sources", "SHARP_ANGLE"]

MAX_PER_WALL = 64  # graded nodes at most on one wall beside one corner
NEEDLE = math.radians(3.0)  # sharper corners are needles: a progression would crowd them
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


def _best_ratio(quality, theta):
    """argmax over q in (1, 4] of quality(theta, q), which rises then falls in q
    (golden-section search)."""
    lo, hi = np.full(theta.shape, 1.0 + 1e-6), np.full(theta.shape, 4.0)
    for _ in range(48):  # the bracket shrinks to 0.618**48 of 3: far below any use
        a = hi - _GOLDEN * (hi - lo)
        b = lo + _GOLDEN * (hi - lo)
        left = quality(theta, a) >= quality(theta, b)
        hi, lo = np.where(left, b, hi), np.where(left, lo, a)
    return 0.5 * (lo + hi)


def _both_quality(theta, q):
    return np.minimum(_zigzag_quality(theta, q), _corner_quality(theta, q))


def zigzag_ratio(theta) -> np.ndarray:
    """The progression ratio q beside a corner of angle theta: the one that
    maximises the worse of the zigzag's and the corner triangle's eq. 10
    ratios where that reaches 0.7, else the zigzag's alone (a corner of about
    26 to 27.5 degrees: one triangle below 0.7, not every one of the zigzag)."""
    theta = np.asarray(theta, dtype=np.float64)
    both = _best_ratio(_both_quality, theta)
    alone = _best_ratio(_zigzag_quality, theta)
    return np.where(_both_quality(theta, both) >= 0.7, both, alone)


def _progressions(a, b, node_a, node_b, theta, size, below):
    """Per wall end at a corner sharper than ``below`` (and not a needle): its
    segment, whether the corner is the segment's start, the parameters u of
    the progression's nodes from the corner (MAX_PER_WALL columns) with the
    mask of those kept, their distances and the ratio q."""
    n = len(a)
    ends = np.concatenate([node_a, node_b])
    graded = (theta[ends] < below) & (theta[ends] >= NEEDLE)
    seg = np.concatenate([np.arange(n), np.arange(n)])[graded]
    at_start = np.arange(2 * n)[graded] < n
    node = ends[graded]
    far = np.concatenate([node_b, node_a])[graded]
    # a wall graded from both ends is shared at its middle; else the progression may run
    # on while its next node still lies on the wall
    shared = (theta[far] < below) & (theta[far] >= NEEDLE)
    corner = np.where(at_start[:, None], a[seg], b[seg])
    away = np.where(at_start[:, None], b[seg], a[seg]) - corner
    length = np.hypot(away[:, 0], away[:, 1])
    # the walls at a corner alternate by direction: the zigzag's half-step offset
    order = np.lexsort((np.arctan2(away[:, 1], away[:, 0]), node))
    first = np.searchsorted(node[order], node[order], side="left")
    offset = np.empty(len(node))
    offset[order] = 0.5 * ((np.arange(len(node)) - first) % 2)
    q = zigzag_ratio(theta[node])
    # the corner's r: its size, but small enough that every wall there gets its first node
    first = 0.5 * length / q**offset
    if len(corner):
        first = np.minimum(first, size(corner))
    at = np.unique(node, return_inverse=True)[1]
    r = np.full(at.max(initial=-1) + 1, np.inf)
    np.minimum.at(r, at, first)
    r = r[at]
    k = np.arange(MAX_PER_WALL)
    dist = r[:, None] * q[:, None] ** (k[None, :] + offset[:, None])
    u = dist / length[:, None]
    where = corner[:, None, :] + u[:, :, None] * away[:, None, :]
    h = size(where.reshape(-1, 2)).reshape(u.shape) if len(corner) else u
    inside = np.where(shared[:, None], u <= 0.5, u * q[:, None] <= 1.0)
    fits = np.logical_and.accumulate(inside & ((q[:, None] - 1.0) * dist <= h), axis=1)
    return seg, at_start, u, fits, where, (q[:, None] - 1.0) * dist


def wedge_parameters(a, b, node_a, node_b, theta, size, below):
    """Graded node parameters on segments a -> b beside corners sharper than
    ``below`` (module docstring).

    ``node_a``, ``node_b`` are the node ids of the segments' ends, ``theta`` the
    corner angle per node id, ``size`` the element size (n, 2) -> (n,).
    Returns (seg, t, lo, hi): parameters t in (0, 1) of the graded nodes of
    segment seg (sorted by segment, then t), and per segment the interval
    [lo, hi] of t left to split to the size field."""
    n = len(a)
    lo, hi = np.zeros(n), np.ones(n)
    seg, at_start, u, fits, _, _ = _progressions(a, b, node_a, node_b, theta, size, below)
    count = fits.sum(axis=1)
    last = np.where(count > 0, u[np.arange(len(u)), np.maximum(count - 1, 0)], 0.0)
    np.maximum.at(lo, seg[at_start], last[at_start])
    np.minimum.at(hi, seg[~at_start], 1.0 - last[~at_start])
    owner = np.repeat(seg, count)
    t = np.where(np.repeat(at_start, count), u[fits], 1.0 - u[fits])
    order = np.lexsort((t, owner))
    return owner[order], t[order], lo, hi


def wedge_sources(domain: Domain, size, below, outer_below=None):
    """The graded nodes of ``domain``'s walls (where :func:`wedge_parameters`
    puts them) and their spacing (q - 1) times the distance to the corner:
    size sources that make the field follow the zigzag, so the element bubbles
    there (eq. 3-4) are the zigzag's and not the far larger field's.  With
    ``outer_below`` only those beside corners sharper than it on the
    boundary's walls, not on interior constraints (whose other side they
    would refine too)."""
    node_a = np.concatenate(domain.loops)
    node_b = np.concatenate([np.roll(ix, -1) for ix in domain.loops])
    P = np.asarray(domain.points)
    theta = corner_angles(domain)
    seg, at_start, _, fits, where, spacing = _progressions(P[node_a], P[node_b], node_a,
                                                           node_b, theta, size, below)
    if outer_below is not None:
        corner = np.where(at_start, node_a[seg], node_b[seg])
        kept = ~np.asarray(domain.interior, bool)[seg] & (theta[corner] < outer_below)
        fits &= kept[:, None]
    return where[fits], spacing[fits]
