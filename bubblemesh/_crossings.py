"""Segments of a planar straight-line graph split where they cross (the input
of §2.1, generalised as Triangle's ``-p`` does).

Triangle inserts a vertex where two input segments cross; a user drawing a
grid of material interfaces, or a constraint across a wall, expects the same.
:func:`split_crossings` finds every pair of segments that cross properly
(each one's ends strictly on both sides of the other's line, by exact
orientation; a sweep along x prunes the pairs), computes the crossing point
exactly in rationals and rounds it to the nearest float, and splits both
segments there: the pieces keep their segment's marker and flag, and the new
vertices follow the input's.  A crossing point within TOUCH of the longer
segment's length from an end is that end: the other segment is split at the
end (a constraint drawn to a wall but a rounding error past it joins the
wall, no sliver piece); where it is that near ends of both segments, the two
nodes were meant to be one and GeometryError names them.  Loops (``BOUNDARY``
segments of a parity domain) that cross each other are an error too: the
domain's inside would depend on the crossing.  A rounded crossing point bends
its pieces by an ulp, which can make a new crossing; the rounds repeat, at
most ROUNDS times.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
from numba import njit

from ._cdt import BOUNDARY
from .errors import GeometryError
from .predicates import orient2d

__all__ = ["crossing_pairs", "segment_text", "split_crossings"]

TOUCH = 1e-9  # a crossing this close to an end (share of the longer segment) is at it
ROUNDS = 8  # rounds of splits: a rounded crossing point may make another crossing


@njit(cache=True)
def _crossing_pairs(P, S, out):
    """Fill ``out`` (k, 2) with the pairs (i, j), i < j, of segments that cross
    properly, sweeping segments in order of their lower x (a pair whose x
    ranges do not overlap cannot cross); returns how many there are (more than
    k: ``out`` was too small and holds the first k)."""
    n = S.shape[0]
    lo = np.minimum(P[S[:, 0], 0], P[S[:, 1], 0])
    hi = np.maximum(P[S[:, 0], 0], P[S[:, 1], 0])
    order = np.argsort(lo, kind="mergesort")
    count = 0
    for ii in range(n):
        i = order[ii]
        a, b = S[i, 0], S[i, 1]
        ylo = min(P[a, 1], P[b, 1])
        yhi = max(P[a, 1], P[b, 1])
        for jj in range(ii + 1, n):
            j = order[jj]
            if lo[j] > hi[i]:
                break
            c, d = S[j, 0], S[j, 1]
            if max(P[c, 1], P[d, 1]) < ylo or min(P[c, 1], P[d, 1]) > yhi:
                continue
            if c == a or c == b or d == a or d == b:
                continue
            if not _opposite(orient2d(P[a, 0], P[a, 1], P[b, 0], P[b, 1], P[c, 0], P[c, 1]),
                             orient2d(P[a, 0], P[a, 1], P[b, 0], P[b, 1], P[d, 0], P[d, 1])):
                continue
            if not _opposite(orient2d(P[c, 0], P[c, 1], P[d, 0], P[d, 1], P[a, 0], P[a, 1]),
                             orient2d(P[c, 0], P[c, 1], P[d, 0], P[d, 1], P[b, 0], P[b, 1])):
                continue
            if count < out.shape[0]:
                out[count, 0], out[count, 1] = min(i, j), max(i, j)
            count += 1
    return count


@njit(cache=True, inline="always")
def _opposite(u, v):
    """Strictly opposite signs (no product: two tiny values would underflow)."""
    return (u > 0.0 and v < 0.0) or (u < 0.0 and v > 0.0)


def crossing_pairs(P: np.ndarray, S: np.ndarray) -> np.ndarray:
    """(k, 2) int64: every pair of segments of S (indices into P) that cross
    properly, exact, sorted."""
    P = np.ascontiguousarray(P, np.float64)
    S = np.ascontiguousarray(S, np.int64)
    out = np.empty((max(16, len(S)), 2), np.int64)
    count = _crossing_pairs(P, S, out)
    if count > len(out):
        out = np.empty((count, 2), np.int64)
        _crossing_pairs(P, S, out)
    pairs = out[:count]
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]


def crossing_point(p: np.ndarray, q: np.ndarray, r: np.ndarray, s: np.ndarray) -> np.ndarray:
    """The crossing of segments pq and rs (they cross properly), computed in
    rationals and rounded to the nearest float in each coordinate."""
    px, py, qx, qy, rx, ry, sx, sy = (Fraction(float(v)) for v in (*p, *q, *r, *s))
    side_p = (sx - rx) * (py - ry) - (sy - ry) * (px - rx)
    side_q = (sx - rx) * (qy - ry) - (sy - ry) * (qx - rx)
    t = side_p / (side_p - side_q)
    return np.array([float(px + t * (qx - px)), float(py + t * (qy - py))])


def segment_text(P: np.ndarray, s) -> str:
    """Segment s (two indices into P) as "(x0, y0)-(x1, y1)", for messages."""
    (x0, y0), (x1, y1) = P[s[0]].tolist(), P[s[1]].tolist()
    return f"({x0!r}, {y0!r})-({x1!r}, {y1!r})"


def split_crossings(P: np.ndarray, S: np.ndarray, markers: np.ndarray, flags: np.ndarray,
                    parity: bool):
    """(points, segments, markers, flags) with every proper crossing split
    (module docstring): the points P and then the new crossing vertices; a
    split segment's first piece in its place and the others appended.
    ``parity``: S's ``BOUNDARY`` segments are loops, which may not cross."""
    for _ in range(ROUNDS):
        pairs = crossing_pairs(P, S)
        if not len(pairs):
            return P, S, markers, flags
        P, cuts = _crossing_vertices(P, S, flags, pairs, parity)
        S, markers, flags = _cut(P, S, markers, flags, cuts)
    raise GeometryError(f"segments still cross after {ROUNDS} rounds of splits at their "
                        f"crossings (first: {segment_text(P, S[crossing_pairs(P, S)[0, 0]])})")


def _crossing_vertices(P, S, flags, pairs, parity):
    """(points with the new crossing vertices, {segment: [vertex, ...]}) for
    the crossing ``pairs``: each pair's point, an end it touches, or a new
    vertex (one per point: three segments through one point share it)."""
    new = {tuple(p): k for k, p in enumerate(P.tolist())}  # a point already a vertex is it
    cuts: dict[int, list] = {}
    added = []
    lengths = np.hypot(*(P[S[:, 1]] - P[S[:, 0]]).T)
    for i, j in pairs.tolist():
        if parity and flags[i] == BOUNDARY and flags[j] == BOUNDARY:
            raise GeometryError(f"loops cross: segment {segment_text(P, S[i])} crosses segment "
                                f"{segment_text(P, S[j])}")
        x = crossing_point(P[S[i, 0]], P[S[i, 1]], P[S[j, 0]], P[S[j, 1]])
        reach = TOUCH * max(lengths[i], lengths[j])
        near = [(int(e), k) for k in (i, j) for e in S[k]
                if np.hypot(*(P[e] - x)) <= reach]
        if {k for _, k in near} == {i, j}:
            (e, _), (f, _) = near[0], near[-1]
            raise GeometryError(
                f"nodes {tuple(P[e].tolist())} and {tuple(P[f].tolist())} are "
                f"{np.hypot(*(P[e] - P[f])):.3g} apart and their segments cross: give them "
                "the same coordinates")
        if near:
            e, k = near[0]
            cuts.setdefault(j if k == i else i, []).append(e)
            continue
        key = tuple(x.tolist())
        if key not in new:
            new[key] = len(P) + len(added)
            added.append(x)
        for k in (i, j):
            cuts.setdefault(k, []).append(new[key])
    if added:
        P = np.vstack([P, np.array(added)])
    return P, cuts


def _cut(P, S, markers, flags, cuts):
    """Each segment in ``cuts`` split at its vertices, in order along it."""
    S, markers, flags = S.copy(), list(markers), list(flags)
    extra = []
    for s in sorted(cuts):
        a, b = S[s]
        d = P[b] - P[a]
        inner = sorted(set(cuts[s]), key=lambda v: float((P[v, 0] - P[a, 0]) * d[0]
                                                          + (P[v, 1] - P[a, 1]) * d[1]))
        chain = [a, *inner, b]
        S[s] = chain[:2]
        extra += [(chain[k], chain[k + 1], markers[s], flags[s]) for k in range(1, len(chain) - 1)]
    if not extra:
        return S, np.asarray(markers), np.asarray(flags, np.uint8)
    pieces = np.array([e[:2] for e in extra], np.int64)
    return (np.vstack([S, pieces]), np.asarray(markers + [e[2] for e in extra]),
            np.asarray(flags + [e[3] for e in extra], np.uint8))
