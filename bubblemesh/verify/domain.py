"""The input boundary as a domain: loops, nesting, exact area, point location.

The domain is the set of points enclosed by an odd number of boundary loops
(the even-odd rule): loops at even nesting depth are outer boundaries, at odd
depth hole boundaries.  This is Triangle's domain when every hole has a hole
point.  Loops may touch at nodes (two squares sharing a corner, a hole whose
corner is on the outer boundary): where more than two segments meet, the
loops are traced as the faces' boundaries, each leaving a node by the first
segment clockwise from the one it came in on (exact angles), and cut into
simple loops wherever a walk meets its own node; every node is on an even
number of their segments.  Interior constraints (the domain on both sides)
are not loops: :func:`pslg_sides` reads any planar straight-line graph as
Triangle does and tells them apart.
"""

from __future__ import annotations

import functools
import math
from fractions import Fraction

import numpy as np

from bubblemesh.errors import GeometryError

from .exact import ExactPoints, orient_int, orient_signs, point_in_polygon, signed_area_exact

_EPS = np.finfo(np.float64).eps
_MAX_PAIRS = 4_000_000  # (query, segment) pairs evaluated per numpy batch


def chain_loops(segments: np.ndarray, oriented: bool, first: int = 0,
                points=None) -> list[list[int]]:
    """Closed simple loops of node ids from segments (K, 2).

    ``oriented``: each segment runs a -> b and every node starts as many
    segments as it ends; otherwise every node is on an even number of
    segments.  Where a node is on more than two, ``points`` (exact integer
    points, indexed by node id) order its segments by angle: a walk arriving
    at a node leaves by the first unused segment clockwise from the one it
    came in on, and a walk that meets a node already on it closes a loop
    there, so loops touch at such nodes but do not cross.  Raises
    GeometryError naming the node where the segments do not close (its id
    less ``first``: the caller's numbering).
    """
    seg = np.asarray(segments, dtype=np.int64).reshape(-1, 2).tolist()
    for a, b in seg:
        if a == b:
            raise GeometryError(f"segment ({a}, {b}) has zero length")
    ends = _ends(seg)  # node -> ids of the segments at it
    for node, at in ends.items():
        starts = sum(seg[k][0] == node for k in at)
        if oriented and 2 * starts != len(at):
            raise GeometryError(f"segments do not form closed loops: node {node - first} "
                                f"starts {starts} segments and ends {len(at) - starts}")
        if len(at) % 2 or (len(at) > 2 and points is None):
            raise GeometryError(
                f"segments do not form closed loops: node {node - first} is on {len(at)} "
                "segments (interior constraints and open chains are not supported)")
    turn = _turns(seg, ends, points)
    used = [False] * len(seg)
    loops: list[list[int]] = []
    for k in range(len(seg)):
        if not used[k]:
            loops += _walk_loops(k, seg, ends, turn, used, oriented, first)
    return loops


def _turns(seg, ends, points):
    """{node: its segment ids counter-clockwise} where more than two meet."""
    return {node: _by_angle(node, at, seg, points) for node, at in ends.items() if len(at) > 2}


def _ends(seg):
    ends: dict[int, list[int]] = {}
    for k, (a, b) in enumerate(seg):
        ends.setdefault(a, []).append(k)
        ends.setdefault(b, []).append(k)
    return ends


def _other(seg, k, node):
    a, b = seg[k]
    return b if a == node else a


def _by_angle(node, at, seg, points):
    """The segment ids at ``node`` in counter-clockwise order of direction (exact)."""
    x0, y0 = points[node]

    def direction(k):
        x, y = points[_other(seg, k, node)]
        return x - x0, y - y0

    def before(j, k):
        (ax, ay), (bx, by) = direction(j), direction(k)
        ha, hb = (ay < 0 or (ay == 0 and ax < 0)), (by < 0 or (by == 0 and bx < 0))
        if ha != hb:
            return -1 if hb else 1
        cross = ax * by - ay * bx
        return -1 if cross > 0 else (1 if cross < 0 else 0)

    order = sorted(at, key=functools.cmp_to_key(before))
    for j, k in zip(order, order[1:] + order[:1]):
        if before(j, k) == 0 and j != k:
            raise GeometryError(f"segments {j} and {k} leave node {node} in the same "
                                "direction: they overlap")
    return order


def _walk_loops(k, seg, ends, turn, used, oriented, first):
    """The simple loops of the closed walk that starts with segment k."""
    start = seg[k][0]
    path, on_path, loops = [start], {start: 0}, []
    node, came = start, -1
    for _ in range(len(seg)):  # bounded: each step uses one segment
        nxt = k if came < 0 else _leave(node, came, seg, ends, turn, used, oriented)
        if nxt < 0:
            raise GeometryError(f"segments do not form closed loops at node {node - first}")
        used[nxt] = True
        node, came = _other(seg, nxt, node), nxt
        if node in on_path:  # a loop closes: cut it off the walk
            cut = on_path[node]
            loops.append(path[cut:])
            for x in path[cut + 1:]:
                del on_path[x]
            del path[cut + 1:]
            if node == start and len(path) == 1 and not any(
                    not used[j] for j in ends[start]):
                return loops
        else:
            on_path[node] = len(path)
            path.append(node)
    raise GeometryError(f"segments do not form closed loops at node {start - first}")


def _leave(node, came, seg, ends, turn, used, oriented):
    """The segment a walk that reached ``node`` by segment ``came`` leaves by:
    the first unused one clockwise from ``came`` (the only other one where
    ``node`` is on two); -1 if none."""
    order = turn.get(node, ends[node])
    i = order.index(came)
    for step in range(1, len(order)):
        j = order[(i - step) % len(order)]
        if not used[j] and (not oriented or seg[j][0] == node):
            return j
    return -1


def _band_pairs(qy_sorted, lo_y, hi_y):
    """(query position, segment) pairs with the query's y in the segment's band."""
    lo = np.searchsorted(qy_sorted, lo_y, side="left")
    hi = np.searchsorted(qy_sorted, hi_y, side="right")
    counts = hi - lo
    seg = np.repeat(np.arange(len(lo_y)), counts)
    start = np.repeat(lo - np.concatenate([[0], np.cumsum(counts)[:-1]]), counts)
    return np.arange(len(seg)) + start, seg


def float_crossings(q, p1, p2, delta):
    """Rightward-ray crossings in float, with the uncertain queries flagged.

    q (Q, 2) query points known within ``delta`` per coordinate; segments
    p1 -> p2 (S, 2) exact.  Returns (crossing query ids, crossing segment ids,
    uncertain mask over Q).  A query is certain when every decision about it
    clears its error bound (the bound of oracles' centroid locator)."""
    order = np.argsort(q[:, 1], kind="stable")
    qy_sorted = q[order, 1]
    uncertain = np.zeros(len(q), bool)
    hits_q, hits_s = [], []
    lo_y = np.minimum(p1[:, 1], p2[:, 1]) - 2 * delta
    hi_y = np.maximum(p1[:, 1], p2[:, 1]) + 2 * delta
    counts = np.searchsorted(qy_sorted, hi_y, "right") - np.searchsorted(qy_sorted, lo_y, "left")
    bounds = np.searchsorted(np.cumsum(counts), np.arange(1, counts.sum() // _MAX_PAIRS + 1)
                             * _MAX_PAIRS)
    for chunk in np.split(np.arange(len(p1)), np.unique(bounds)):
        if not len(chunk):
            continue
        pos, s = _band_pairs(qy_sorted, lo_y[chunk], hi_y[chunk])
        s = chunk[s]
        k = order[pos]
        a, b = p1[s], p2[s]
        qx, qy = q[k, 0], q[k, 1]
        dy1, dy2 = a[:, 1] - qy, b[:, 1] - qy
        unsure = (np.abs(dy1) <= delta) | (np.abs(dy2) <= delta)
        straddle = (a[:, 1] > qy) != (b[:, 1] > qy)
        ex, ey = b[:, 0] - a[:, 0], b[:, 1] - a[:, 1]
        u, w = ex * (qy - a[:, 1]), ey * (qx - a[:, 0])
        o = u - w
        err = 2 * (np.abs(ex) + np.abs(ey)) * delta + 4 * _EPS * (np.abs(u) + np.abs(w)) + 1e-300
        unsure |= straddle & (np.abs(o) <= err)
        uncertain[k[unsure]] = True
        cross = straddle & ((o > 0) == (b[:, 1] > a[:, 1]))
        hits_q.append(k[cross])
        hits_s.append(s[cross])
    empty = np.zeros(0, np.int64)
    return (np.concatenate(hits_q) if hits_q else empty,
            np.concatenate(hits_s) if hits_s else empty, uncertain)


def exact_crossings(Q, segs) -> tuple[list[int], bool]:
    """Exact: indices of segments (pairs of integer points) the rightward ray
    from integer point Q crosses, and whether Q lies on one of them."""
    out: list[int] = []
    for s, (p1, p2) in enumerate(segs):
        o = orient_int(p1, p2, Q)
        if (o == 0 and min(p1[0], p2[0]) <= Q[0] <= max(p1[0], p2[0])
                and min(p1[1], p2[1]) <= Q[1] <= max(p1[1], p2[1])):
            return out, True
        if (p1[1] > Q[1]) != (p2[1] > Q[1]) and (o > 0) == (p2[1] > p1[1]):
            out.append(s)
    return out, False


class Boundary:
    """Closed boundary loops over the nodes of an ExactPoints array.

    ``segments`` (K, 2) index ``E``'s points.  ``holes`` (optional hole
    points, as in a .poly file) are checked against the even-odd rule.
    Errors name nodes less ``first`` (the caller's numbering of ``E``'s
    points from there on).
    """

    def __init__(self, E: ExactPoints, segments, holes=None, oriented=False, first=0):
        self.E = E
        self.first = int(first)
        self.segments = np.asarray(segments, dtype=np.int64).reshape(-1, 2)
        self.oriented = oriented
        if len(self.segments) < 3:
            raise GeometryError(f"a boundary needs at least 3 segments, got {len(self.segments)}")
        self.loops = chain_loops(self.segments, oriented, self.first, E.P)
        self.depth = self._depths()
        self._check_holes(holes)

    # -- location -------------------------------------------------------
    def segment_points(self, scale: int = 1):
        P = self.E.P
        return [((scale * P[a][0], scale * P[a][1]), (scale * P[b][0], scale * P[b][1]))
                for a, b in self.segments.tolist()]

    def locate(self, q, exact_query, delta, exact=False) -> np.ndarray:
        """Even-odd location of points: +1 in the domain, 0 on a segment, -1 out.

        ``q`` (Q, 2) float positions within ``delta`` of the exact ones;
        ``exact_query(k) -> (X, Y, scale)`` the exact point k as integers in
        the integer scale of ``E`` times ``scale``."""
        # on E's scaled points (times a power of two: no product overflows)
        pts, k = self.E.scaled, self.E.exponent
        p1, p2 = pts[self.segments[:, 0]], pts[self.segments[:, 1]]
        q, delta = np.ldexp(q, -k), float(np.ldexp(delta, -k))
        hq, _, uncertain = float_crossings(q, p1, p2, delta)
        exact = exact or bool(self.E.unsafe.any())  # a scaled node off by its rounding
        uncertain |= ~np.isfinite(q).all(axis=1)
        odd = np.bincount(hq, minlength=len(q)) % 2 == 1
        out = np.where(odd, 1, -1).astype(np.int64)
        todo = range(len(q)) if exact else np.nonzero(uncertain)[0].tolist()
        cache: dict[int, list] = {}
        for k in todo:
            X, Y, scale = exact_query(k)
            segs = cache.setdefault(scale, self.segment_points(scale))
            near = self._band(q[k, 1], delta, p1, p2)
            hits, on = exact_crossings((X, Y), [segs[s] for s in near])
            out[k] = 0 if on else (1 if len(hits) % 2 else -1)
        return out

    @staticmethod
    def _band(y, delta, p1, p2):
        lo = np.minimum(p1[:, 1], p2[:, 1]) - 4 * delta
        hi = np.maximum(p1[:, 1], p2[:, 1]) + 4 * delta
        return np.nonzero((lo <= y) & (y <= hi))[0].tolist()

    def _depths(self) -> list[int]:
        """Nesting depth of each loop: how many other loops enclose it (exact),
        judged at the middle of its first segment (loops may share nodes, not
        segments)."""
        P = self.E.P
        polys = [[(2 * P[i][0], 2 * P[i][1]) for i in lp] for lp in self.loops]
        depth = []
        for i, lp in enumerate(self.loops):
            a, b = P[lp[0]], P[lp[1]]
            middle = (a[0] + b[0], a[1] + b[1])  # in the doubled scale of polys
            d = 0
            for j, poly in enumerate(polys):
                if i == j:
                    continue
                w = point_in_polygon(middle, poly)
                if w == 0:
                    raise GeometryError(f"boundary loops overlap: segment ({lp[0] - self.first}, "
                                        f"{lp[1] - self.first}) of loop {i} lies on loop {j}")
                d += w > 0
            depth.append(d)
        return depth

    def _check_holes(self, holes):
        if holes is None or len(holes) == 0:
            return
        holes = np.asarray(holes, dtype=np.float64).reshape(-1, 2)
        nodes = np.concatenate([np.asarray(lp) for lp in self.loops])
        H = ExactPoints(np.vstack([self.E.points[nodes], holes]))  # one scale for both
        ends = np.cumsum([len(lp) for lp in self.loops])
        polys = [H.P[e - len(lp):e] for e, lp in zip(ends.tolist(), self.loops)]
        inside = [[point_in_polygon(H.P[len(nodes) + h], poly) for poly in polys]
                  for h in range(len(holes))]
        for h, where in enumerate(inside):
            if 0 in where or sum(w > 0 for w in where) % 2 == 1:
                raise GeometryError(f"hole point {h} at {tuple(holes[h].tolist())} lies in the "
                                    "domain or on its boundary (by the even-odd rule)")
        for i, d in enumerate(self.depth):
            if d % 2 == 1 and not any(where[i] > 0 for where in inside):
                raise GeometryError(
                    f"loop {i} (node {self.loops[i][0] - self.first}) bounds a hole by the "
                    "even-odd rule but contains no hole point: meshed-on-both-sides loops are "
                    "not supported"
                )

    # -- global facts ---------------------------------------------------
    def area_exact(self) -> Fraction:
        """Domain area in the integer scale: outer loops minus holes (exact)."""
        return sum(
            (abs(signed_area_exact(self.E.P, lp)) * (1 if d % 2 == 0 else -1)
             for lp, d in zip(self.loops, self.depth)),
            Fraction(0),
        )

    def area(self) -> float:
        """The domain area as a float (inf past the float range)."""
        try:
            return float(self.area_exact() / (1 << (2 * self.E.shift)))
        except OverflowError:
            return math.inf

    def euler(self) -> int:
        """Euler characteristic of the closed domain (V - E + F of any mesh of
        it).  With the segments turned so that the domain is on their left,
        the walks around its faces are each one boundary of a face that has
        its touching nodes pulled apart: +1 for an outer one (counter-
        clockwise), -1 for a hole's.  Joining the copies of a node again
        takes one vertex per extra copy: K segments over V nodes, K - V in
        all."""
        P = self.E.P
        directed = []
        for lp, d in zip(self.loops, self.depth):
            ring = list(zip(lp, lp[1:] + lp[:1]))
            if (signed_area_exact(P, lp) > 0) != (d % 2 == 0):
                ring = [(b, a) for a, b in reversed(ring)]
            directed += [list(e) for e in ring]
        nodes = len(set(np.asarray(self.segments).ravel().tolist()))
        walks, walk_of = _half_walks(directed + [[b, a] for a, b in directed], P)
        inside = {walk_of[j] for j in range(len(directed))}  # the domain's side of each
        sides = sum(1 if signed_area_exact(P, walks[w]) > 0 else -1 for w in inside)
        return sides - (len(directed) - nodes)


def pslg_sides(points, segments, holes=None) -> np.ndarray:
    """Triangle's reading of a planar straight-line graph: how many sides of
    each segment (K,) the domain lies on (2: an interior constraint, 1: the
    boundary, 0: in a hole or outside).

    The domain is every bounded face of the segments' arrangement that holds
    no hole point (Triangle eats a hole point's face and, without -c,
    everything outside).  The faces are traced exactly: each side of a
    segment is followed by the first segment clockwise at its end; a walk
    with positive area bounds a face from inside, any other walk is the
    outline of a connected part, whose face is the smallest positive walk
    around it.  GeometryError names repeated, crossing or overlapping
    segments, a node inside a segment, and a hole point on one."""
    seg = np.asarray(segments, dtype=np.int64).reshape(-1, 2)
    hole = np.asarray(holes if holes is not None else [], np.float64).reshape(-1, 2)
    E = ExactPoints(np.vstack([np.asarray(points, np.float64).reshape(-1, 2), hole]))
    P, n = E.P, len(E.points) - len(hole)
    halves = [[int(a), int(b)] for a, b in seg.tolist()] + [[int(b), int(a)]
                                                          for a, b in seg.tolist()]
    for a, b in halves[:len(seg)]:
        if a == b:
            raise GeometryError(f"segment ({a}, {b}) has zero length")
    _, first, count = np.unique(np.sort(seg, axis=1), axis=0, return_index=True,
                                return_counts=True)
    if (count > 1).any():
        k = int(first[np.argmax(count > 1)])
        raise GeometryError(f"segment {k} {seg[k].tolist()} is given more than once")
    _refuse_crossings(E, seg)
    walks, face_of = _half_walks(halves, P)
    areas = [signed_area_exact(P, w) for w in walks]
    bounded = [k for k, area in enumerate(areas) if area > 0]

    box = {k: (min(P[i][0] for i in walks[k]), max(P[i][0] for i in walks[k]),
               min(P[i][1] for i in walks[k]), max(P[i][1] for i in walks[k])) for k in bounded}

    def around(q):  # the smallest positive walk with q strictly inside, -1: outside all
        near = [k for k in bounded
                if box[k][0] < q[0] < box[k][1] and box[k][2] < q[1] < box[k][3]]
        inside = [k for k in near if point_in_polygon(q, [P[i] for i in walks[k]]) > 0]
        return min(inside, key=lambda k: areas[k]) if inside else -1

    face = list(range(len(walks)))
    for k, area in enumerate(areas):
        if area <= 0:  # an outline: its face is the one around any of its nodes
            face[k] = around(P[walks[k][0]])  # its own walks have that node on them
    eaten = {-1}
    for h in range(len(hole)):
        q = P[n + h]
        if any(point_in_polygon(q, [P[i] for i in walks[k]]) == 0 for k in bounded
               if box[k][0] <= q[0] <= box[k][1] and box[k][2] <= q[1] <= box[k][3]):
            raise GeometryError(f"hole point {h} at {tuple(hole[h].tolist())} lies on a segment")
        eaten.add(around(q))
    domain = [face[face_of[j]] not in eaten for j in range(len(halves))]
    return (np.array(domain[:len(seg)], np.int64) + np.array(domain[len(seg):], np.int64))


def _refuse_crossings(E: ExactPoints, seg):
    """GeometryError naming two segments that cross, or a node strictly inside
    a segment (exact): the faces are traced only on a planar graph."""
    p = E.points
    lo_x, hi_x = np.minimum(p[seg[:, 0], 0], p[seg[:, 1], 0]), np.maximum(p[seg[:, 0], 0],
                                                                          p[seg[:, 1], 0])
    lo_y, hi_y = np.minimum(p[seg[:, 0], 1], p[seg[:, 1], 1]), np.maximum(p[seg[:, 0], 1],
                                                                          p[seg[:, 1], 1])
    order = np.argsort(lo_x, kind="stable")
    reach = np.searchsorted(lo_x[order], hi_x[order], side="right")  # x-overlapping, sorted
    for start in range(0, len(order), 4096):  # bounded blocks of pairs
        rows = np.arange(start, min(start + 4096, len(order)))
        counts = np.maximum(reach[rows] - rows - 1, 0)
        i = order[np.repeat(rows, counts)]
        j = order[np.repeat(rows + 1 - np.cumsum(counts) + counts, counts)
                  + np.arange(counts.sum())]
        keep = (lo_y[i] <= hi_y[j]) & (lo_y[j] <= hi_y[i])
        i, j = i[keep], j[keep]
        a, b, c, d = seg[i, 0], seg[i, 1], seg[j, 0], seg[j, 1]
        abc, abd = orient_signs(E, a, b, c), orient_signs(E, a, b, d)
        cda, cdb = orient_signs(E, c, d, a), orient_signs(E, c, d, b)
        cross = (abc * abd < 0) & (cda * cdb < 0)
        inside = np.zeros(len(i), bool)
        for (s, t), (u, o) in (((a, b), (c, abc)), ((a, b), (d, abd)),
                               ((c, d), (a, cda)), ((c, d), (b, cdb))):
            between = ((np.minimum(p[s], p[t]) <= p[u]) & (p[u] <= np.maximum(p[s], p[t]))).all(1)
            inside |= (o == 0) & between & (u != s) & (u != t)
        bad = np.flatnonzero(cross | inside)
        if len(bad):
            k = bad[0]
            what = "cross" if cross[k] else "overlap or meet inside one of them"
            raise GeometryError(f"segments {int(i[k])} and {int(j[k])} {what}: split them at "
                                "their common points first")


def _half_walks(halves, points):
    """The face walks of directed half-segments (every segment both ways) and
    the walk of each half: after a -> b the first half leaving b clockwise
    from b -> a (itself at a dangling end)."""
    ends: dict[int, list[int]] = {}
    for j, (a, _) in enumerate(halves):
        ends.setdefault(a, []).append(j)
    twin = len(halves) // 2
    order = {node: _by_angle(node, out, halves, points) if len(out) > 1 else out
             for node, out in ends.items()}
    walk_of = [-1] * len(halves)
    walks: list[list[int]] = []
    for start in range(len(halves)):
        j, walk = start, []
        while walk_of[j] < 0:  # bounded: each step claims one half
            walk_of[j] = len(walks)
            walk.append(halves[j][0])
            back = (j + twin) % len(halves)  # b -> a, leaving b
            at = order[halves[j][1]]
            j = at[(at.index(back) - 1) % len(at)]
        if walk:
            walks.append(walk)
    return walks, walk_of
