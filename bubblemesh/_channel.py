"""Whole rows across a straight channel (``bubblemesh.mesh``, not the paper).

A strip of width W between two parallel walls holds W / (sqrt(3)/2 h) rows
of equilateral triangles of size h, rarely a whole number: a lattice of
spacing h then meets the far wall in a squashed row, and the count of whole
rows can lie several percent off the field's count.  Where the domain's
longest walls face each other across such a strip, :func:`straight_channel`
takes m whole rows of height b = W / m and cuts both walls, where they
overlap, into pieces of about a = sqrt(3) h^2 / (2 b): a triangle of base a
and height b has the area of the field's equilateral one, so the count
stays near the field's; m and the pieces are the whole numbers whose
triangle has the best radius ratio (eq. 10).  The lattice of
:mod:`bubblemesh._lattice` is then laid in rows of height b from one wall's
nodes to the other's: the first wall's nodes shifted half a piece (the two
pieces at each end take up the half pieces, which would leave a right
triangle in the corners), the far wall's too when m is even; the walls
across the strip's ends get one node per row.  Walls that run past the
overlap (an L-shaped strip, a parallelogram) are cut there as the plain
refinement cuts them.  The default mesher keeps that mesh only where it
beats the plain walls' (``bubblemesh.pipeline``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["Channel", "straight_channel"]

TRIES = 8  # longest segments tried as a channel's wall
PARALLEL = 1e-9  # walls this close to antiparallel (sine of the angle) face each other
CLOSE = 1e-9  # extents and the strip's emptiness, to this share of the wall's length
LEAST_RATIO = 0.97  # the stretched triangle's radius ratio must reach this
ASPECT = 4.0  # a channel's walls are at least this many times longer than it is wide
SHARE = 0.5  # and it holds at least this share of the domain (the lattice's frame is one)
FEWER = 0.96  # a wall's pieces at least this share of the field's count's
CORNER_SPAN = 2  # pieces at each end of a shifted wall that take up its half pieces
LEAST_PIECES = 2 * CORNER_SPAN + 2  # walls in fewer have no shifted piece between those


@dataclass(frozen=True)
class Channel:
    """A strip between input segments ``wall`` and ``far`` (indices into the
    domain's segments): its lattice frame (origin, unit direction along
    ``wall``, piece a, row height b), the rows m, and the splits for
    :func:`~bubblemesh.refinement.refine_boundary` ({(i, j): t})."""

    wall: int
    far: int
    rows: int
    frame: tuple
    splits: dict


def isosceles_ratio(base: float, height: float) -> float:
    """Eq. 10's 2 r / R of the isosceles triangle of that base and height."""
    side = math.hypot(height, 0.5 * base)
    area = 0.5 * base * height
    return 2.0 * (2.0 * area / (base + 2.0 * side)) / (base * side * side / (4.0 * area))


def rows_for(width: float, length: float, h: float):
    """(m, n, a, b): m rows of height b = width / m across, n pieces of a =
    length / n along.  n0 = length / (sqrt(3) h^2 / (2 b)) pieces have the
    field's count; n is the best of those from FEWER n0 up to n0 (the ends
    of a strip add elements; below, the count leaves the field's), or
    floor(n0) where there is none, m the
    better of floor and ceil of width / (sqrt(3)/2 h) (the lower on a tie),
    each by the radius ratio of the isosceles triangle of base a, height b."""
    x = width / (0.5 * math.sqrt(3.0) * h)
    best, best_ratio = None, -1.0
    for m in sorted({max(1, math.floor(x)), max(1, math.ceil(x))}):
        b = width / m
        n0 = length / (0.5 * math.sqrt(3.0) * h * h / b)
        low, high = max(1, math.ceil(FEWER * n0)), max(1, math.floor(n0))
        for n in range(low, high + 1) if low <= high else (high,):
            ratio = isosceles_ratio(length / n, b)
            if ratio > best_ratio:
                best, best_ratio = (m, n, length / n, b), ratio
    return best


def straight_channel(domain, size, h: float) -> Channel | None:
    """The channel of :mod:`bubblemesh._channel` along the longest of the
    TRIES longest segments of ``domain`` (a Domain without interior
    constraints or regions) that has one: an antiparallel segment across the
    interior overlapping it along its direction, the overlap ASPECT times
    longer than the distance between them, nothing in the rectangle between
    them over the overlap and that rectangle at least SHARE of the domain's
    area, ``size`` (a callable h(xy)) equal to ``h`` along both walls, and a
    stretched triangle of ratio at least LEAST_RATIO with at least
    LEAST_PIECES pieces over the overlap; else None."""
    if not math.isfinite(h) or np.asarray(domain.interior).any() or (
            domain.regions is not None and len(domain.regions)):
        return None
    P, S = np.asarray(domain.points, np.float64), np.asarray(domain.segments, np.int64)
    d = P[S[:, 1]] - P[S[:, 0]]
    lengths = np.hypot(d[:, 0], d[:, 1])
    for k in np.argsort(-lengths, kind="stable")[:TRIES]:
        found = _facing(P, S, d, lengths, int(k), domain.area)
        if found is None:
            continue
        far, width, lo, hi = found
        if not _uniform(size, P[S[k]], P[S[far]], h):
            continue
        length = hi - lo
        m, n, a, b = rows_for(width, length, h)
        if n < LEAST_PIECES or isosceles_ratio(a, b) < LEAST_RATIO:
            continue
        u = d[k] / float(lengths[k])
        return Channel(int(k), far, m, (P[S[k, 0]] + (lo + 0.5 * a) * u, u, a, b),
                       _splits(P, S, int(k), far, m, n, (lo, hi), h))
    return None


def _facing(P, S, d, lengths, k, area):
    """(far, width, lo, hi): the segment antiparallel to segment k on its
    left (the interior's side, both loops oriented so) whose overlap with it
    along its direction, [lo, hi] from its first node, is ASPECT times
    longer than the distance between them and holds a rectangle of at least
    SHARE of ``area`` that no other segment enters (the longest such
    overlap, then the nearest); else None."""
    length = float(lengths[k])
    u = d[k] / length
    rel = P - P[S[k, 0]]
    along = rel[:, 0] * u[0] + rel[:, 1] * u[1]  # not `@`: BLAS's bits vary with its threads
    off = rel[:, 1] * u[0] - rel[:, 0] * u[1]
    tol = CLOSE * length
    sine = (d[:, 0] * u[1] - d[:, 1] * u[0]) / np.maximum(lengths, 1e-300)
    lo = np.maximum(along[S[:, 1]], 0.0)
    hi = np.minimum(along[S[:, 0]], length)
    lo = np.where(lo <= tol, 0.0, lo)  # a wall ending within tol of the other's end
    hi = np.where(hi >= length - tol, length, hi)  # shares that end
    width = off[S[:, 0]]
    cands = np.flatnonzero((np.abs(sine) <= PARALLEL) & (d[:, 0] * u[0] + d[:, 1] * u[1] < 0)
                           & (width > tol) & (hi - lo >= ASPECT * width)
                           & ((hi - lo) * width >= SHARE * area))
    for j in cands[np.lexsort((width[cands], lo[cands] - hi[cands]))]:
        others = np.ones(len(S), bool)
        others[[k, j]] = False
        if not _crosses_box(along[S[others]] - lo[j], off[S[others]], hi[j] - lo[j],
                            width[j], tol):
            return int(j), float(width[j]), float(lo[j]), float(hi[j])
    return None


def _crosses_box(x, y, length, width, tol):
    """Does any segment (x[:, 0], y[:, 0]) - (x[:, 1], y[:, 1]) reach into the
    open box (tol, length - tol) x (tol, width - tol)?  Liang-Barsky
    clipping, all segments at once."""
    lo_x, hi_x, lo_y, hi_y = tol, length - tol, tol, width - tol
    t0, t1 = np.zeros(len(x)), np.ones(len(x))
    for p, q in ((x[:, 0] - x[:, 1], x[:, 0] - lo_x), (x[:, 1] - x[:, 0], hi_x - x[:, 0]),
                 (y[:, 0] - y[:, 1], y[:, 0] - lo_y), (y[:, 1] - y[:, 0], hi_y - y[:, 0])):
        flat = p == 0
        outside = flat & (q <= 0)
        t0 = np.where(outside, 2.0, t0)
        r = np.where(flat, 0.0, q / np.where(flat, 1.0, p))
        t0 = np.where(~flat & (p < 0), np.maximum(t0, r), t0)
        t1 = np.where(~flat & (p > 0), np.minimum(t1, r), t1)
    return bool(np.any(t0 < t1))


def _uniform(size, wall, far, h):
    """Is the size h all along both walls (at 9 points on each)?"""
    t = np.linspace(0.0, 1.0, 9)[:, None]
    xy = np.vstack([wall[0] + t * (wall[1] - wall[0]), far[0] + t * (far[1] - far[0])])
    return bool(np.all(np.asarray(size(xy)) >= h * (1.0 - 1e-12)))


def _shifted(n):
    """Parameters of n pieces shifted half a piece (on the rows of a lattice
    whose origin is half a piece in): the half pieces at the ends would
    leave a right triangle of legs a / 2 and b in the corners, so the
    CORNER_SPAN pieces from each end take them up."""
    inner = (np.arange(CORNER_SPAN, n - CORNER_SPAN) + 0.5) / n
    tail = (CORNER_SPAN + 0.5) / n * np.arange(1, CORNER_SPAN + 1) / (CORNER_SPAN + 1)
    return np.concatenate([tail, inner, 1.0 - tail[::-1]])


def _splits(P, S, k, far, m, n, overlap, h):
    """The wall's nodes shifted half a piece (:func:`_shifted`, on row 0 of
    the lattice whose origin is half a piece into the overlap), the far
    wall's on row m: n equal pieces when m is odd, shifted too when m is
    even; a wall running past the overlap is cut to ``h`` beyond it
    (:func:`_run_on`); the segments joining their ends, if any, in m."""
    length = float(np.hypot(*(P[S[k, 1]] - P[S[k, 0]])))
    u = (P[S[k, 1]] - P[S[k, 0]]) / length
    rel = P[S[far]] - P[S[k, 0]]
    far_end, far_start = rel[:, 0] * u[0] + rel[:, 1] * u[1]  # not `@`: BLAS's bits
    lo, hi = overlap
    a, tol = (hi - lo) / n, CLOSE * length
    splits = {}
    for wall, shift, start, end in ((k, 0.5, 0.0, length),
                                    (far, 0.5 * ((m + 1) % 2), far_start, far_end)):
        start = lo if abs(start - lo) <= tol else float(start)
        end = hi if abs(end - hi) <= tol else float(end)
        if start >= lo and end <= hi:  # the wall spans the overlap
            t = _shifted(n) if shift else np.arange(1, n) / n
        else:
            x = _run_on(0.0 if start == lo else (start - lo) / a,
                        float(n) if end == hi else (end - lo) / a, n, shift, h / a)
            t = (lo + x * a - start) / (end - start)
            t = t if wall == k else 1.0 - t[::-1]  # the far wall runs against u
        splits[(int(S[wall, 0]), int(S[wall, 1]))] = t
    if m > 1:
        rows = np.arange(1, m) / m
        for start, end in ((S[k, 1], S[far, 0]), (S[far, 1], S[k, 0])):
            hit = np.flatnonzero((S[:, 0] == start) & (S[:, 1] == end))
            if len(hit):
                splits[(int(start), int(end))] = rows
    return splits


def _run_on(start, end, n, shift, h):
    """Nodes (in pieces from the overlap's start) of a wall from ``start`` to
    ``end`` (start <= 0, end >= n) whose n pieces over the overlap lie on a
    lattice row shifted by ``shift`` pieces: where the wall ends with the
    overlap and the row is shifted, the CORNER_SPAN pieces there take up the
    half piece (:func:`_shifted`); where it runs past, the rest from the
    row's last node is cut into the nearest whole number of pieces of ``h``
    (in pieces), as the plain refinement cuts a wall."""
    x = np.arange(n + 1) + shift
    x = x[(x > start) & (x < end)]
    tail = (CORNER_SPAN + 0.5) * np.arange(1, CORNER_SPAN + 1) / (CORNER_SPAN + 1)
    if start < 0.0:
        k = max(1, round((x[0] - start) / h))
        x = np.concatenate([start + (x[0] - start) * np.arange(1, k) / k, x])
    elif shift:
        x = np.concatenate([tail, x[x > CORNER_SPAN]])
    if end > n:
        k = max(1, round((end - x[-1]) / h))
        x = np.concatenate([x, x[-1] + (end - x[-1]) * np.arange(1, k) / k])
    elif shift:
        x = np.concatenate([x[x < n - CORNER_SPAN], n - tail[::-1]])
    return x
