"""Quality-guarded smoothing for ``bubblemesh.mesh`` (not in the paper).

An interior node moves toward the mean of its neighbours (the Laplacian
position), a whole, half or quarter step, only if every incident triangle stays
strictly counter-clockwise by the exact :func:`orient2d` and the smallest
radius ratio (eq. 10) of its incident triangles grows.  So a sweep never
lowers the mesh's minimum radius ratio, never inverts a triangle and never
lets a node cross its star (which keeps it inside the domain).  Nodes are
visited in index order and read the latest positions (Gauss-Seidel): the
result is deterministic.

Nodes of triangles below a radius ratio ``poor`` then get a compass search
(:func:`compass_polish`): steps in 8 directions from a tenth of the shortest
incident edge, halved on failure, taken under the same guard; it raises the
worst stars toward a local optimum of their smallest ratio.
"""

import math

import numpy as np
from numba import njit, prange

from .predicates import orient2d

STEPS = (1.0, 0.5, 0.25)
COMPASS = 8  # directions of the compass search
COMPASS_HALVINGS = 6
MARGIN = 1e-9  # far above the rounding of eq. 10 from another corner of the triangle
SMALL_QUALITY = 4096  # fewer triangles are rated without threads


@njit(cache=True, inline="always")
def rho(ax, ay, bx, by, cx, cy):
    """Eq. 10 radius ratio 2 r_in / r_circ = 4 (2A)^2 / ((a + b + c) a b c);
    0 for a triangle that is not counter-clockwise in floating point."""
    return rho_opposite(ax, ay, bx, by, cx, cy, math.sqrt((bx - cx) ** 2 + (by - cy) ** 2))


@njit(cache=True, inline="always")
def rho_opposite(ax, ay, bx, by, cx, cy, a):
    """:func:`rho` given a = |bc| (a star's fixed edge, computed once)."""
    b = math.sqrt((ax - cx) ** 2 + (ay - cy) ** 2)
    c = math.sqrt((ax - bx) ** 2 + (ay - by) ** 2)
    area2 = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
    if area2 <= 0.0 or a * b * c == 0.0:
        return 0.0
    return min(1.0, 4.0 * area2 * area2 / ((a + b + c) * a * b * c))


@njit(cache=True)
def stars(triangles, n):
    """CSR node -> incident triangles (ptr (n + 1,), idx)."""
    count = np.zeros(n + 1, np.int64)
    for t in range(triangles.shape[0]):
        for k in range(3):
            count[triangles[t, k] + 1] += 1
    ptr = np.cumsum(count)
    fill = ptr[:-1].copy()
    idx = np.empty(ptr[-1], np.int64)
    for t in range(triangles.shape[0]):
        for k in range(3):
            v = triangles[t, k]
            idx[fill[v]] = t
            fill[v] += 1
    return ptr, idx


@njit(cache=True)
def star_stats(X, triangles, ptr, idx, i, px, py):
    """(smallest, mean) radius ratio of node i's triangles with i at (px, py);
    (-1, -1) if one of them is not strictly counter-clockwise (exact)."""
    worst = 1.0
    total = 0.0
    for e in range(ptr[i], ptr[i + 1]):
        t = idx[e]
        k = 0 if triangles[t, 0] == i else (1 if triangles[t, 1] == i else 2)
        u = triangles[t, (k + 1) % 3]
        v = triangles[t, (k + 2) % 3]
        if orient2d(px, py, X[u, 0], X[u, 1], X[v, 0], X[v, 1]) <= 0.0:
            return -1.0, -1.0
        q = rho(px, py, X[u, 0], X[u, 1], X[v, 0], X[v, 1])
        worst = min(worst, q)
        total += q
    return worst, total / (ptr[i + 1] - ptr[i])


@njit(cache=True)
def star_buffer(ptr):
    """Room for the largest star (see :func:`gather_star`)."""
    most = 1
    for i in range(ptr.shape[0] - 1):
        most = max(most, ptr[i + 1] - ptr[i])
    return np.empty((most, 5))


@njit(cache=True, inline="always")
def _star_row(X, triangles, t, i, buf, e):
    """Row e of node i's gathered star from its triangle t: (u, v, |uv|), u and
    v the far corners counter-clockwise.  Returns (i's corner in t, u, v)."""
    k = 0 if triangles[t, 0] == i else (1 if triangles[t, 1] == i else 2)
    u = triangles[t, (k + 1) % 3]
    v = triangles[t, (k + 2) % 3]
    buf[e, 0] = X[u, 0]
    buf[e, 1] = X[u, 1]
    buf[e, 2] = X[v, 0]
    buf[e, 3] = X[v, 1]
    buf[e, 4] = math.sqrt((X[u, 0] - X[v, 0]) ** 2 + (X[u, 1] - X[v, 1]) ** 2)
    return k, u, v


@njit(cache=True)
def gather_star(X, triangles, ptr, idx, i, buf):
    """Node i's star as rows (u, v, |uv|), u and v the far corners of each
    triangle in counter-clockwise order: the part of :func:`star_stats` that
    does not depend on where i is.  Returns the star's size."""
    deg = ptr[i + 1] - ptr[i]
    for e in range(deg):
        _star_row(X, triangles, idx[ptr[i] + e], i, buf, e)
    return deg


@njit(cache=True)
def gathered_stats(buf, deg, px, py):
    """:func:`star_stats` on a star from :func:`gather_star` (the same bits)."""
    worst = 1.0
    total = 0.0
    for e in range(deg):
        ux, uy, vx, vy = buf[e, 0], buf[e, 1], buf[e, 2], buf[e, 3]
        if orient2d(px, py, ux, uy, vx, vy) <= 0.0:
            return -1.0, -1.0
        q = rho_opposite(px, py, ux, uy, vx, vy, buf[e, 4])
        worst = min(worst, q)
        total += q
    return worst, total / deg


@njit(cache=True)
def gathered_beats(buf, deg, px, py, bar):
    """``gathered_stats(buf, deg, px, py)[0] > bar``, stopping at the first
    triangle that decides it: one not counter-clockwise or with a radius
    ratio not above ``bar`` (most guarded moves fail, often early)."""
    if bar >= 1.0:
        return False  # the smallest ratio starts at 1
    for e in range(deg):
        ux, uy, vx, vy = buf[e, 0], buf[e, 1], buf[e, 2], buf[e, 3]
        if orient2d(px, py, ux, uy, vx, vy) <= 0.0:
            return False
        if rho_opposite(px, py, ux, uy, vx, vy, buf[e, 4]) <= bar:
            return False
    return True


@njit(cache=True)
def gather_for_smoothing(X, triangles, ptr, idx, i, buf, moved_at, seen):
    """One pass over node i's star for :func:`guarded_smooth`: its rows into
    ``buf`` as :func:`gather_star`, the sums of its neighbours' coordinates
    (each neighbour twice in a closed star, in the star's triangle and corner
    order), and whether neither node i nor a node of its star has moved since
    i was last looked at (visit ``seen``, -1 for never; ``moved_at``: the visit
    of each node's last move, -1 for never): then looking again would find
    what the last look did, no move (the active set of a Gauss-Seidel sweep).
    Returns (the star's size, sum x, sum y, unchanged)."""
    unchanged = seen >= 0 and moved_at[i] < seen
    sx = 0.0
    sy = 0.0
    deg = ptr[i + 1] - ptr[i]
    for e in range(deg):
        k, u, v = _star_row(X, triangles, idx[ptr[i] + e], i, buf, e)
        unchanged = unchanged and moved_at[u] <= seen and moved_at[v] <= seen
        first, second = (v, u) if k == 1 else (u, v)  # the triangle's corner order
        sx += X[first, 0]
        sy += X[first, 1]
        sx += X[second, 0]
        sy += X[second, 1]
    return deg, sx, sy, unchanged


@njit(cache=True)
def triangle_quality(X, triangles):
    """Eq. 10 per triangle (0 for one that is not counter-clockwise); the
    triangles in parallel from SMALL_QUALITY on (below, starting the threads
    costs more than the loop)."""
    if triangles.shape[0] < SMALL_QUALITY:
        q = np.empty(triangles.shape[0])
        for t in range(triangles.shape[0]):
            q[t] = _rho_of(X, triangles, t)
        return q
    return _quality_parallel(X, triangles)


@njit(cache=True, parallel=True)
def _quality_parallel(X, triangles):
    q = np.empty(triangles.shape[0])
    for t in prange(triangles.shape[0]):
        q[t] = _rho_of(X, triangles, t)
    return q


@njit(cache=True, inline="always")
def _rho_of(X, triangles, t):
    a, b, c = triangles[t, 0], triangles[t, 1], triangles[t, 2]
    return rho(X[a, 0], X[a, 1], X[b, 0], X[b, 1], X[c, 0], X[c, 1])


@njit(cache=True)
def guarded_smooth(X, triangles, ptr, idx, n_boundary, sweeps, movable):
    """``sweeps`` Gauss-Seidel sweeps over the interior nodes with
    ``movable[i]`` set (module docstring); X is updated in place.  Returns the
    number of moves taken."""
    taken = 0
    buf = star_buffer(ptr)
    moved_at = np.full(X.shape[0], -1, np.int64)
    seen_at = np.full(X.shape[0], -1, np.int64)
    visit = 0
    for _ in range(sweeps):
        moved = 0
        for i in range(n_boundary, X.shape[0]):
            if not movable[i] or ptr[i + 1] == ptr[i]:
                continue
            visit += 1
            deg, sx, sy, unchanged = gather_for_smoothing(X, triangles, ptr, idx, i, buf,
                                                          moved_at, seen_at[i])
            if unchanged:
                continue  # the same look as last time: no move
            seen_at[i] = visit
            m = 2.0 * deg
            tx, ty = sx / m, sy / m
            before = gathered_stats(buf, deg, X[i, 0], X[i, 1])[0]
            for step in STEPS:
                px = X[i, 0] + step * (tx - X[i, 0])
                py = X[i, 1] + step * (ty - X[i, 1])
                if gathered_beats(buf, deg, px, py, before):
                    X[i, 0] = px
                    X[i, 1] = py
                    moved += 1
                    moved_at[i] = visit
                    break
        taken += moved
        if moved == 0:
            break
    return taken


@njit(cache=True)
def shortest_edge(buf, deg, px, py):
    """The shortest edge at node i, at (px, py), of its star gathered by
    :func:`gather_star` (the far corners are its neighbours): the step scale
    of a search, by ``math.hypot``.  hypot is slow, so only the edges whose
    squared length is within a relative 1e-9 of the smallest get it: hypot
    is within an ulp or two of the true length, so no other edge is shorter."""
    least = np.inf
    for e in range(deg):
        for c in (0, 2):
            least = min(least, (buf[e, c] - px) ** 2 + (buf[e, c + 1] - py) ** 2)
    shortest = np.inf
    for e in range(deg):
        for c in (0, 2):
            dx, dy = buf[e, c] - px, buf[e, c + 1] - py
            if dx ** 2 + dy ** 2 <= least * (1.0 + 1e-9):
                shortest = min(shortest, math.hypot(dx, dy))
    return shortest


@njit(cache=True)
def _clearly_fine(triangles, ptr, idx, i, q, touched, poor):
    """Is node i's star at least ``poor`` by its triangles' ratios ``q`` with
    room to spare (:data:`MARGIN`: a triangle's ratio computed from another
    corner rounds differently), and has none of its nodes moved since ``q``
    was computed?  Then the compass search would pass the star over."""
    for e in range(ptr[i], ptr[i + 1]):
        t = idx[e]
        if q[t] < poor + MARGIN:
            return False
        for k in range(3):
            if touched[triangles[t, k]]:
                return False
    return True


@njit(cache=True)
def compass_polish(X, triangles, ptr, idx, n_boundary, poor, movable, cap=2.0):
    """Compass search on the interior nodes with ``movable`` set whose star's
    smallest ratio is below ``poor`` (module docstring), each star's search
    ended once that ratio reaches ``cap``; X in place.  Most
    stars are well above it: their triangles' ratios, computed once for the
    pass, pass them over while none of their nodes has moved in it.  Returns
    the number of steps taken."""
    taken = 0
    buf = star_buffer(ptr)
    q = triangle_quality(X, triangles)
    touched = np.zeros(X.shape[0], np.bool_)
    for i in range(n_boundary, X.shape[0]):
        if not movable[i] or ptr[i + 1] == ptr[i]:
            continue
        if _clearly_fine(triangles, ptr, idx, i, q, touched, poor):
            continue
        deg = gather_star(X, triangles, ptr, idx, i, buf)
        best = gathered_stats(buf, deg, X[i, 0], X[i, 1])[0]
        if best >= poor:
            continue
        step = 0.1 * shortest_edge(buf, deg, X[i, 0], X[i, 1])
        for _ in range(COMPASS_HALVINGS):
            improved = True
            while improved:
                improved = False
                for d in range(COMPASS):
                    a = 2.0 * math.pi * d / COMPASS
                    px = X[i, 0] + step * math.cos(a)
                    py = X[i, 1] + step * math.sin(a)
                    if gathered_beats(buf, deg, px, py, best):
                        X[i, 0] = px
                        X[i, 1] = py
                        best = gathered_stats(buf, deg, px, py)[0]
                        improved = True
                        taken += 1
                        touched[i] = True
                        break
                if best >= cap:
                    break
                if taken > 64 * (X.shape[0] - n_boundary):  # bounded whatever happens
                    return taken
            if best >= cap:
                break
            step *= 0.5
    return taken
