"""Local re-triangulation of the worst triangles (not in the paper; after §3).

§3's forces (eq. 7-9), the smoothing and the flips move nodes and edges but
never change how many nodes a neighbourhood holds.  Where a row has one node
too few (a gap between a hole and a wall one triangle high, its nodes
staggered badly) or one too many, no position of the nodes is good: Gmsh's
front puts a node in such a gap, and the paper's reason (2) for its elements
below 0.7 is this population defect.  So, worst triangle first:

- the *patch* is the triangles touching the worst triangle's corners (for
  the two-point variants, also those of its neighbours across its interior
  edges);
- variants: one point inserted (an edge's midpoint); two points inserted
  (the centroids of it and a neighbour; two apexes of the equilateral
  triangles on its edges, on either side, where a front would put its nodes;
  or, on a wall, two midpoints of its and a neighbour's interior edges: a gap
  one row high needs a second row);
  or one of its free nodes removed; the patch is re-triangulated
  constrained-Delaunay (:func:`~bubblemesh.triangulation.constrained_delaunay`,
  exact predicates) inside its own outline, which is kept edge for edge, so
  the mesh stays conforming and boundary nodes never move;
- the free nodes of the new triangles and their neighbours are relaxed: a
  compass search for each star's worst radius ratio (eq. 10), then gradient
  steps on the star means (:mod:`bubblemesh._smoothing`, :mod:`bubblemesh._odt`);
- the variant whose changed triangles have the highest smallest ratio (then
  the highest mesh mean) is kept if that smallest ratio is above theirs
  before, the mesh's mean ratio stays within MEAN_DROP of its value before
  the first repair, every changed triangle keeps its area bound and the
  element count stays in the window ``counts`` (or comes closer to it).

Where a triangle below POOR_RATIO must be mended and the mean may not bar
it, a variant may instead be required to lift every changed triangle to a
floor; where a rise of the smallest ratio alone would make more triangles
below POOR_RATIO (lifting a poor one step by step fills its row with them),
that can be barred.

Rounds stop when the worst triangle is at least ``below``, when no variant
of any triangle below it pays (FAILED triangles tried in vain at most: one
at a sharp corner cannot be mended, and must not hide the rest), or after
``rounds``.  Every round is deterministic (ties broken by index).

:func:`balance_count` uses the same re-triangulation and relaxation to bring
the element count into a window: a node removed where the mesh is most
crowded for the size field (if none of those can go, as when they are all
in the walls' first row, the most crowded off it, the mesh's mean kept
within INNER_DROP of its value before the balance), or inserted where it is
sparsest, never lowering the mesh's smallest ratio.  :func:`prune_nodes`
removes free nodes only where that raises the mesh mean, the count kept
above a floor: a node that §2 put between fixed points, where the field asked
for one but the points left no good place."""

import numpy as np
from numba import njit

from ._area_bound import _areas
from ._odt import _mean_visit
from ._smoothing import compass_polish, star_buffer, stars, triangle_quality
from .errors import GeometryError
from .triangulation import constrained_delaunay

POOR_RATIO = 0.7  # the ratio every element off a too-sharp corner should reach
FAILED = 16  # triangles none of whose variants pays, at most, before the rounds stop
RISE = 1e-9  # a smaller rise of the smallest ratio is rounding, not a repair
MEAN_DROP = 1e-3  # the repairs may lower the mesh's mean ratio by at most this in all
COMPASS_ROUNDS = 3
POLISH_SWEEPS = 3
INNER_DROP = 2e-3  # removals off the walls' first row may lower the mean by this in all
CANDIDATES = 8  # nodes (triangles: a quarter) tried per round by balance_count
MEAN_CANDIDATES = 24  # nodes tried per round when removals are ranked by the mean
MEAN_INSERTS = 8  # triangles tried per round when insertions are ranked by the mean


def repair_worst(X, T, segments, movable, limit, below, rounds, counts, halvings, steps,
                 drop=MEAN_DROP, held=None, floor=None, poor_kept=False):
    """Re-triangulate the patches around the worst triangles (module
    docstring).  X (n, 2), T (m, 3) CCW, ``movable`` (n,) free nodes,
    ``limit`` (m,) area bound of each triangle, ``counts`` (low, high) the
    element counts a variant may leave; ``halvings`` and ``steps`` as in
    :func:`~bubblemesh._odt.mean_polish`; ``drop`` how far the mesh mean may
    fall in all; triangles touching a ``held`` node (n,) are not picked;
    with a ``floor`` a variant's changed triangles must all reach it;
    with ``poor_kept`` they may not hold more below POOR_RATIO than before (a
    rise of their smallest ratio is no reason to make more of those).
    Returns (X, T, old, operations):
    the new arrays, with the removed nodes gone and the inserted ones after
    the old (node numbers below the first removed one unchanged), ``old``
    each node's number in X (-1: inserted) and the number of variants kept."""
    lowest = float(triangle_quality(np.asarray(X, np.float64), np.asarray(T, np.int64)).mean()
                   if len(T) else 1.0) - drop

    failed = set()  # vertex triples none of whose variants paid (nodes keep their numbers)

    def pick(X, T, q, ptr, idx, free, limit, walls):
        skipped = None if held is None else _padded(held, len(X))
        for t in _worst(q, below):
            if skipped is not None and skipped[T[t]].any():
                continue
            key = tuple(sorted(T[t].tolist()))
            if key in failed:
                continue
            best = _best_variant(X, T, q, ptr, idx, int(t), free, limit, walls, halvings,
                                 steps, counts, lowest, floor, poor_kept)
            if best is not None:
                return best
            failed.add(key)
            if len(failed) >= FAILED:
                break
        return None

    return _rounds(X, T, segments, movable, limit, rounds, pick)


def balance_count(X, T, segments, movable, limit, counts, size, rounds, halvings, steps,
                  floor=None, shielded=None, by_mean=True, least=0.0):
    """While the element count is above ``counts`` (low, high), remove the
    free node whose star is most crowded for the size field (smallest summed
    area over the areas ``size`` asks for) that can go, the ``shielded``
    nodes (n,) only when no other can, or failing that the most crowded
    whose triangles touch no wall node while the mean stays within
    INNER_DROP of its start; of the MEAN_CANDIDATES tried per round the
    removal leaving the highest mesh mean (then the highest smallest ratio
    of its changed triangles) is kept, or without ``by_mean`` of CANDIDATES
    the other way round.
    While the count is below, insert a point in one of the sparsest
    triangles (an edge midpoint or its centroid): of the MEAN_INSERTS
    sparsest the variant leaving the highest mesh mean (then the highest
    smallest ratio) kept, or without ``by_mean`` of the CANDIDATES / 4
    sparsest the other way round.  Either only if that ratio is not below
    the mesh's minimum (or ``floor``, where that is lower: removals may then
    lower the minimum down to it), nor below ``least`` (a sharp corner's
    triangle can hold the minimum far lower, which then bars nothing), and
    the area bounds hold.  ``size`` maps
    (k, 2) points to (k,) sizes; the rest and the result as
    :func:`repair_worst`."""
    count = MEAN_CANDIDATES if by_mean else CANDIDATES
    lowest = float(triangle_quality(np.asarray(X, np.float64), np.asarray(T, np.int64)).mean()
                   if len(T) else 1.0) - INNER_DROP
    size = _remembered(size)

    def pick(X, T, q, ptr, idx, free, limit, walls):
        m = len(T)
        if counts[0] <= m <= counts[1]:
            return None
        fill = _areas(X, T) / np.asarray(size(X[T].mean(axis=1)), np.float64) ** 2
        low = float(q.min(initial=1.0)) if floor is None else min(floor, q.min(initial=1.0))
        low = max(low, least)
        if m > counts[1]:
            crowd = np.bincount(T.ravel(), np.repeat(fill, 3), len(X))
            crowd[~free] = np.inf
            tiers = [crowd] if shielded is None else [
                np.where(_padded(shielded, len(X)), np.inf, crowd), crowd]
            for tier in tiers:
                best = _best_of(X, T, q, ptr, idx, _removals(T, ptr, idx, tier, count), free,
                                limit, walls, halvings, steps, low, None, by_mean)
                if best is not None:
                    return best
            # the most crowded are often a wall's first row, where no node can go:
            # then the most crowded of the nodes off it
            walled = np.zeros(len(X), np.bool_)
            walled[T[(~free[T]).any(axis=1)].ravel()] = True
            crowd[walled] = np.inf
            return _best_of(X, T, q, ptr, idx, _removals(T, ptr, idx, crowd, count), free,
                            limit, walls, halvings, steps, low, lowest, by_mean)
        else:
            order = np.lexsort((np.arange(m), -fill))[:MEAN_INSERTS if by_mean
                                                       else CANDIDATES // 4]
            tries = [(T[t], [point], -1) for t in order for point in
                     [X[T[t]].mean(axis=0)] + [0.5 * (X[T[t, k]] + X[T[t, (k + 1) % 3]])
                                               for k in range(3)]]
        return _best_of(X, T, q, ptr, idx, tries, free, limit, walls, halvings, steps,
                        low, None, by_mean)

    return _rounds(X, T, segments, movable, limit, rounds, pick)


def _remembered(size):
    """``size`` evaluated only at the points the last call did not have: a
    round changes a few triangles, and a point's size depends on it alone,
    so the values are the same bits (a graded field's search costs most)."""
    keys, values = np.zeros(0, np.complex128), np.zeros(0)

    def call(xy):
        nonlocal keys, values
        xy = np.asarray(xy, np.float64)
        now = xy[:, 0] + 1j * xy[:, 1]
        at = np.minimum(np.searchsorted(keys, now), max(len(keys) - 1, 0))
        known = keys[at] == now if len(keys) else np.zeros(len(now), np.bool_)
        out = np.empty(len(now))
        out[known] = values[at[known]]
        if not known.all():
            out[~known] = np.asarray(size(xy[~known]), np.float64)
        order = np.argsort(now, kind="stable")
        keys, values = now[order], out[order]
        return out

    return call


def _padded(mask, n):
    """``mask`` for the first nodes, False for the nodes inserted since."""
    return np.concatenate([np.asarray(mask, np.bool_), np.zeros(n - len(mask), np.bool_)])


def _removals(T, ptr, idx, crowd, count):
    """Variants removing each of the ``count`` nodes of least ``crowd``
    (finite), ties by index."""
    order = np.lexsort((np.arange(len(crowd)), crowd))[:count]
    return [(_unique(T[idx[ptr[v]:ptr[v + 1]]]), [], int(v))
            for v in order if np.isfinite(crowd[v])]


def _rounds(X, T, segments, movable, limit, rounds, pick):
    """At most ``rounds`` variants chosen by ``pick`` applied in turn."""
    X, T, limit = np.array(X, np.float64), np.array(T, np.int64), np.array(limit, np.float64)
    free = np.array(movable, np.bool_)
    alive = np.ones(len(X), np.bool_)
    old = np.arange(len(X))
    walls = _edge_keys(np.asarray(segments, np.int64).reshape(-1, 2))
    operations = 0
    for _ in range(rounds):
        q = triangle_quality(X, T)
        ptr, idx = stars(T, len(X))
        best = pick(X, T, q, ptr, idx, free, limit, walls)
        if best is None:
            break
        X, T, limit, free, alive, old = _apply(X, T, limit, free, alive, old, best)
        operations += 1
    new_id = np.cumsum(alive) - 1
    return X[alive], new_id[T], old[alive], operations


def _worst(q, below):
    """The triangles of smallest ratio below ``below``, worst first (ties by
    index)."""
    first = np.flatnonzero(q < below)
    return first[np.lexsort((first, q[first]))]


def _edge_keys(edges):
    """Undirected edges as a set of (low, high) pairs."""
    lo, hi = np.minimum(edges[:, 0], edges[:, 1]), np.maximum(edges[:, 0], edges[:, 1])
    return set(zip(lo.tolist(), hi.tolist()))


def _patch(ptr, idx, nodes):
    """The triangles touching ``nodes``, sorted."""
    return _unique(np.concatenate([idx[ptr[v]:ptr[v + 1]] for v in nodes]))


def _variants(X, T, N_of, t, free, walls):
    """(patch corner nodes, added points, removed node) of each variant for
    triangle t: an edge's midpoint; for each neighbour u, the centroids of t
    and u and, if t has a segment edge, two midpoints of the edges of t and u
    that are not segments (a gap one row high needs two nodes); one of its
    free corners removed;
    two of the apexes of the equilateral triangles on its edges (on its own
    side, and across each edge that is not a segment)."""
    tri = T[t]
    p = X[tri]
    near = N_of(t)
    out = [(tri, [0.5 * (p[k] + p[(k + 1) % 3])], -1) for k in range(3)]
    inner = _open_edges(T, (t,), walls)
    for u in near:
        pair = np.concatenate([tri, T[u]])
        out.append((pair, [p.mean(axis=0), X[T[u]].mean(axis=0)], -1))
        if len(inner) < 3:  # t on a wall
            mids = [0.5 * (X[a] + X[b]) for a, b in _open_edges(T, (t, u), walls)]
            out += [(pair, [mids[i], mids[j]], -1)
                    for i in range(len(mids)) for j in range(i + 1, len(mids))]
    out += [(tri, [], int(v)) for v in tri if free[v]]
    corners = np.concatenate([tri] + [T[u] for u in near])
    tops = [_apex(p[k], p[(k + 1) % 3]) for k in range(3)]
    tops += [_apex(p[(k + 1) % 3], p[k]) for k in range(3)
             if (min(tri[k], tri[(k + 1) % 3]), max(tri[k], tri[(k + 1) % 3])) in inner]
    out += [(corners, [tops[i], tops[j]], -1) for i in range(len(tops))
            for j in range(i + 1, len(tops))]
    return out


def _apex(a, b):
    """The apex of the equilateral triangle on the edge a -> b, left of it."""
    return 0.5 * (a + b) + 0.5 * np.sqrt(3.0) * np.array([a[1] - b[1], b[0] - a[0]])


def _open_edges(T, ts, walls):
    """The distinct edges of triangles ``ts`` that are not segments, sorted."""
    sub = T[list(ts)]
    return sorted(_edge_keys(np.concatenate([sub[:, [0, 1]], sub[:, [1, 2]], sub[:, [2, 0]]]))
                  - walls)


def _allowed(m, grown, counts):
    """May a variant take the element count from m to ``grown``: into the
    window ``counts`` or closer to it?"""
    low, high = counts
    return low <= grown <= high or abs(grown - min(max(grown, low), high)) < abs(
        m - min(max(m, low), high))


def _best_variant(X, T, q, ptr, idx, t, free, limit, walls, halvings, steps, counts,
                  lowest, floor=None, poor_kept=False):
    """The best kept variant for triangle t as (patch, new triangles, new
    points, removed node, relaxed nodes and their positions, score) that
    leaves a mesh mean of at least ``lowest``, or None."""
    def across(s):
        return _edge_neighbours(T, ptr, idx, s, walls)

    m = len(T)
    tries = [(corners, added, removed) for corners, added, removed
             in _variants(X, T, across, t, free, walls)
             if _allowed(m, m + 2 * len(added) - (2 if removed >= 0 else 0), counts)]
    return _best_of(X, T, q, ptr, idx, tries, free, limit, walls, halvings, steps, floor,
                    lowest, poor_kept=poor_kept)


def _best_of(X, T, q, ptr, idx, tries, free, limit, walls, halvings, steps, floor, mean,
             by_mean=False, poor_kept=False):
    """The best of the variants ``tries`` (patch corner nodes, added points,
    removed node) by (smallest ratio of the changed triangles, mesh mean),
    or ``by_mean`` the other way round: each must raise that smallest ratio
    (``floor`` None) or keep it at least ``floor``, keep every area bound
    and leave a mesh mean of at least ``mean`` (None: any); with
    ``poor_kept`` hold no more triangles below POOR_RATIO than before."""
    best, total, m = None, float(q.sum()), len(T)
    for corners, added, removed in tries:
        growth = 2 * len(added) - (2 if removed >= 0 else 0)
        patch = _patch(ptr, idx, corners)
        made = _retriangulate(X, T, patch, added, removed, walls)
        if made is None:
            continue
        tried = _relax(X, T, q, ptr, idx, patch, made, np.asarray(added).reshape(-1, 2), free,
                       limit, halvings, steps, floor, poor_kept)
        if tried is None:
            continue
        low, gain, nodes, positions = tried
        score = (low, (total + gain) / (m + growth))
        if mean is not None and score[1] < mean:
            continue
        if by_mean:
            score = score[::-1]
        if best is None or score > best[-1]:
            best = (patch, made, np.asarray(added).reshape(-1, 2), removed, nodes, positions,
                    score)
    return best


def _edge_neighbours(T, ptr, idx, t, walls):
    """The triangles sharing an edge with t that is not a segment."""
    out = []
    for k in range(3):
        a, b = int(T[t, k]), int(T[t, (k + 1) % 3])
        if (min(a, b), max(a, b)) in walls:
            continue
        around = idx[ptr[a]:ptr[a + 1]]
        for u in around[(T[around] == b).any(axis=1)]:
            if u != t:
                out.append(int(u))
    return out


def _outline(tris):
    """Directed edges of the triangles ``tris`` that bound their union."""
    e = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
    key = set(zip(e[:, 0].tolist(), e[:, 1].tolist()))
    return sorted((a, b) for a, b in key if (b, a) not in key)


def _retriangulate(X, T, patch, added, removed, walls):
    """The constrained Delaunay triangulation of the patch with ``added``
    points inserted (numbered len(X), len(X) + 1, ...) and node ``removed``
    taken out, in global node numbers; None unless it fills exactly the
    patch's outline with every added point used (a point off the patch or on
    its outline) and keeps every segment inside the patch."""
    sub = T[patch]
    outline = _outline(sub)
    nodes = _unique(sub)
    if removed >= 0:
        if any(removed in edge for edge in outline):
            return None
        nodes = nodes[nodes != removed]
    inner = [e for e in _edge_keys(np.concatenate([sub[:, [0, 1]], sub[:, [1, 2]],
                                                   sub[:, [2, 0]]])) & walls
             if e not in {(min(a, b), max(a, b)) for a, b in outline}]
    glob = np.concatenate([nodes, len(X) + np.arange(len(added))])  # sorted
    if inner and removed >= 0 and any(removed in e for e in inner):
        return None
    pairs = outline + inner + [(b, a) for a, b in inner]  # both ways: an interface
    P = np.vstack([X[nodes]] + [np.reshape(a, (1, 2)) for a in added])
    try:
        tri, _ = constrained_delaunay(P, np.searchsorted(glob, np.asarray(pairs, np.int64)))
    except GeometryError:
        return None
    made = glob[tri]
    expected = len(patch) + 2 * len(added) - (2 if removed >= 0 else 0)
    if len(made) != expected or _outline(made) != outline:
        return None
    if len(added) and not _member(glob[len(nodes):], _unique(made)).all():
        return None
    return made


def _relax(X, T, q, ptr, idx, patch, made, added, free, limit, halvings, steps,
           floor=None, poor_kept=False):
    """Relax the free nodes of ``made`` (the patch's new triangles) and
    their neighbours on a copy; (smallest ratio of the changed triangles,
    change of the summed ratio, relaxed global nodes, their positions), or
    None if the smallest ratio does not rise (is below ``floor``, if given),
    an area bound breaks or, with ``poor_kept``, more of them (not counting
    the neighbours none of whose nodes moved) are below POOR_RATIO."""
    n = len(X)
    ring = _unique(made)
    outside = _minus(_unique(np.concatenate([idx[ptr[v]:ptr[v + 1]]
                                               for v in ring[ring < n]])), patch)
    near = _unique(np.concatenate([ring, T[outside].ravel()]))
    relaxed = near[(near >= n) | free[np.minimum(near, n - 1)]]
    old = _minus(_unique(np.concatenate(
        [idx[ptr[v]:ptr[v + 1]] for v in relaxed[relaxed < n]] + [outside])), patch)
    sub = np.concatenate([T[old], made])
    nodes = _unique(sub)  # the added ones (>= n) last
    Xl = np.vstack([X[nodes[nodes < n]], added[nodes[nodes >= n] - n]])
    Tl = np.searchsorted(nodes, sub)
    mov = _member(nodes, relaxed)
    # a neighbour none of whose nodes moves keeps its ratio: a sharp corner's
    # triangle there must not hold the patch to its bound
    held = np.concatenate([~mov[Tl[:len(old)]].any(axis=1), np.zeros(len(made), np.bool_)])
    before = min(float(q[patch].min()), float(q[old[~held[:len(old)]]].min(initial=1.0)))
    lptr, lidx = stars(Tl, len(nodes))
    for _ in range(COMPASS_ROUNDS):
        if not compass_polish(Xl, Tl, lptr, lidx, 0, 1.0, mov, 2.0):
            break
    def short(low):  # the rule a kept variant's smallest ratio must pass
        return low <= before + RISE if floor is None else low < floor

    reached = float(triangle_quality(Xl, Tl)[~held].min())
    if short(reached):  # the mean sweeps keep it as their floor: they will not lift it
        return None
    _mean_sweeps(Xl, Tl, lptr, lidx, mov, reached, halvings, steps, POLISH_SWEEPS)
    ql = triangle_quality(Xl, Tl)
    low = float(ql[~held].min())
    if short(low):
        return None
    if poor_kept and int((ql[~held] < POOR_RATIO).sum()) > int(
            (q[patch] < POOR_RATIO).sum() + (q[old[~held[:len(old)]]] < POOR_RATIO).sum()):
        return None
    bound = np.concatenate([limit[old], np.full(len(made), limit[patch].min())])
    if (_areas(Xl, Tl) > bound).any():
        return None
    gain = float(ql.sum()) - float(q[old].sum()) - float(q[patch].sum())
    return low, gain, nodes[mov], Xl[mov]


def _unique(a):
    """The sorted distinct entries of an int array (np.unique without its
    dispatch, which costs more than the sort for a patch's few nodes)."""
    a = np.sort(np.asarray(a).ravel())
    return a[np.concatenate(([True], a[1:] != a[:-1]))] if len(a) else a


def _member(a, b):
    """Which entries of ``a`` are in the sorted array ``b`` (np.isin for
    the few sorted nodes of a patch, without its set-up cost)."""
    at = np.minimum(np.searchsorted(b, a), max(len(b) - 1, 0))
    return (b[at] == a) if len(b) else np.zeros(len(a), np.bool_)


def _minus(a, b):
    """The entries of the sorted unique ``a`` not in the sorted ``b``."""
    return a[~_member(a, b)]


@njit(cache=True)
def _mean_sweeps(X, T, ptr, idx, movable, floor, halvings, steps, sweeps):
    """Gradient steps on the star means of the ``movable`` nodes, in index
    order (mean_polish's visit without its colouring and threads, which cost
    more than the few nodes of a patch), at most ``sweeps`` sweeps; X in place."""
    buf = np.empty((star_buffer(ptr).shape[0], 5))
    for _ in range(sweeps):
        moved = 0
        for i in range(X.shape[0]):
            if movable[i]:
                moved += _mean_visit(X, T, ptr, idx, i, buf, floor, halvings, 1.0, steps)
        if moved == 0:
            break


def _apply(X, T, limit, free, alive, old, best):
    """The mesh with variant ``best`` in place: new points appended (old
    number -1), the removed node marked dead (dropped at the end), relaxed
    nodes moved, the patch's rows replaced by the new triangles (appended)."""
    patch, made, added, removed, nodes, positions, _ = best
    old = np.concatenate([old, np.full(len(added), -1, np.int64)])
    X = np.vstack([X, added])
    X[nodes] = positions
    free = np.concatenate([free, np.ones(len(added), np.bool_)])
    alive = np.concatenate([alive, np.ones(len(added), np.bool_)])
    if removed >= 0:
        alive[removed] = False
        free[removed] = False
    bound = limit[patch].min()
    rest = np.ones(len(T), np.bool_)
    rest[patch] = False
    T = np.concatenate([T[rest], made])
    limit = np.concatenate([limit[rest], np.full(len(made), bound)])
    return X, T, limit, free, alive, old


def prune_nodes(X, T, segments, movable, limit, least, rounds, halvings, steps, gain,
                floor=0.0):
    """While the element count stays at least ``least`` and the removal
    raises the mesh mean by more than ``gain``, remove a free node: of the
    MEAN_CANDIDATES whose stars have the lowest mean ratio, the one whose
    removal leaves the highest mesh mean, none of the changed triangles
    below the mesh's minimum nor below ``floor`` (a sharp corner's triangle
    can hold the minimum far lower), the area bounds kept.  Unlike
    :func:`balance_count`, which removes where the mesh is most crowded to
    meet a count, this removes only what pays.  The rest and the result as
    :func:`repair_worst`."""
    def pick(X, T, q, ptr, idx, free, limit, walls):
        if len(T) - 2 < least:
            return None
        star_mean = np.bincount(T.ravel(), np.repeat(q, 3), len(X)) / np.maximum(
            np.diff(ptr), 1)
        star_mean[~free] = np.inf
        return _best_of(X, T, q, ptr, idx, _removals(T, ptr, idx, star_mean, MEAN_CANDIDATES),
                        free, limit, walls, halvings, steps, max(float(q.min(initial=1.0)), floor),
                        float(q.mean()) + gain, True)

    return _rounds(X, T, segments, movable, limit, rounds, pick)
