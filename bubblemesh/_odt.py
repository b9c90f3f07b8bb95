"""Size-weighted ODT smoothing for ``bubblemesh.mesh`` (not in the paper).

An optimal Delaunay triangulation (Chen and Xu) moves each interior node to
the average of its incident triangles' circumcentres, weighted by area times
density; with the density 1 / h^2 of the size field the nodes settle at the
spacing the field asks for.  A whole, half or quarter step is taken only if
every incident triangle stays strictly counter-clockwise (exact
:func:`orient2d`) and the star's smallest radius ratio (eq. 10) stays at least
min(its value before, ``floor``): with ``floor`` the mesh's minimum the pass
never lowers that minimum, never inverts a triangle and keeps every node
inside its star (so inside the domain).  Gauss-Seidel colour by colour, the
nodes of a colour in parallel (:mod:`bubblemesh._colouring`): deterministic on
any thread count.
"""

import numpy as np
from numba import njit, prange

from ._colouring import BLOCK, colour_classes
from ._smoothing import gather_star, gathered_stats, shortest_edge, star_buffer
from .simd import quotients

STEPS = (1.0, 0.5, 0.25)
COMPASS = 8
BACKTRACKS = 5  # a gradient step is halved up to 4 times
DX = np.cos(2.0 * np.pi * np.arange(COMPASS) / COMPASS)
DY = np.sin(2.0 * np.pi * np.arange(COMPASS) / COMPASS)


@njit(cache=True, inline="always")
def _circumcentre(ax, ay, bx, by, cx, cy):
    """Circumcentre and twice the signed area of triangle abc."""
    bx, by, cx, cy = bx - ax, by - ay, cx - ax, cy - ay
    d = bx * cy - by * cx
    b2, c2 = bx * bx + by * by, cx * cx + cy * cy
    return ax + (cy * b2 - by * c2) / (2.0 * d), ay + (bx * c2 - cx * b2) / (2.0 * d), d


@njit(cache=True)
def _odt_target(X, triangles, ptr, idx, h, i):
    """Density-weighted average of the circumcentres of node i's triangles."""
    sx = 0.0
    sy = 0.0
    sw = 0.0
    for e in range(ptr[i], ptr[i + 1]):
        t = idx[e]
        a, b, c = triangles[t, 0], triangles[t, 1], triangles[t, 2]
        ox, oy, d = _circumcentre(X[a, 0], X[a, 1], X[b, 0], X[b, 1], X[c, 0], X[c, 1])
        if d <= 0.0:
            return X[i, 0], X[i, 1]
        hm = (h[a] + h[b] + h[c]) / 3.0
        w = d / (hm * hm)
        sx += w * ox
        sy += w * oy
        sw += w
    return sx / sw, sy / sw


@njit(cache=True)
def _odt_visit(X, triangles, ptr, idx, h, i, buf, floor):
    """One ODT step of node i (module docstring): its move over its size, -1
    if none is taken."""
    deg = gather_star(X, triangles, ptr, idx, i, buf)
    tx, ty = _odt_target(X, triangles, ptr, idx, h, i)
    before, mean = gathered_stats(buf, deg, X[i, 0], X[i, 1])
    need = max(min(before, floor), 0.0)
    for step in STEPS:
        px = X[i, 0] + step * (tx - X[i, 0])
        py = X[i, 1] + step * (ty - X[i, 1])
        if px == X[i, 0] and py == X[i, 1]:
            break
        q, m = gathered_stats(buf, deg, px, py)
        if q > 0.0 and q >= need and m > mean:
            moved = np.hypot(px - X[i, 0], py - X[i, 1]) / h[i]
            X[i, 0] = px
            X[i, 1] = py
            return moved
    return -1.0


@njit(cache=True, parallel=True)
def odt_smooth(X, triangles, ptr, idx, h, n_boundary, sweeps, movable, floor, tol):
    """``sweeps`` ODT sweeps (module docstring) over the nodes >= n_boundary
    with ``movable`` set, h the size at every node; X in place.  Stops early
    when no node moves by more than ``tol`` times its size.  Returns (moves
    taken, sweeps run)."""
    order, colour_ptr = colour_classes(triangles, ptr, idx, n_boundary, movable)
    most = star_buffer(ptr).shape[0]
    taken = 0
    run = 0
    for _ in range(sweeps):
        run += 1
        largest = 0.0
        for c in range(colour_ptr.shape[0] - 1):
            lo, hi = colour_ptr[c], colour_ptr[c + 1]
            blocks = (hi - lo + BLOCK - 1) // BLOCK
            moves = np.zeros(blocks, np.int64)
            far = np.zeros(blocks)
            for b in prange(blocks):
                buf = np.empty((most, 5))
                for j in range(lo + b * BLOCK, min(hi, lo + (b + 1) * BLOCK)):
                    moved = _odt_visit(X, triangles, ptr, idx, h, order[j], buf, floor)
                    if moved >= 0.0:
                        moves[b] += 1
                        far[b] = max(far[b], moved)
            taken += moves.sum()
            if blocks:
                largest = max(largest, far.max())
        if largest < tol:
            break
    return taken, run


@njit(cache=True)
def _mean_gradient(buf, deg, px, py):
    """Gradient of the sum of the star's radius ratios at (px, py) (a star from
    :func:`gather_star`): grad rho = rho (2 grad A / A - (grad b + grad c) / (a + b + c)
    - grad b / b - grad c / c), with b = |pv|, c = |pu| and A twice the area."""
    gx = 0.0
    gy = 0.0
    for e in range(deg):
        ux, uy, vx, vy, a = buf[e, 0], buf[e, 1], buf[e, 2], buf[e, 3], buf[e, 4]
        bx, by = px - vx, py - vy
        cx, cy = px - ux, py - uy
        b = np.sqrt(bx * bx + by * by)
        c = np.sqrt(cx * cx + cy * cy)
        area2 = (ux - px) * (vy - py) - (uy - py) * (vx - px)
        if area2 <= 0.0 or b == 0.0 or c == 0.0:
            continue
        s = a + b + c
        r = 4.0 * area2 * area2 / (s * a * b * c)
        # both coordinates' divisions by the same length as one packed
        # division each (simd.py): the divider bounds this loop
        ax, ay = quotients(2.0 * (uy - vy), 2.0 * (vx - ux), area2, area2)
        bx_b, by_b = quotients(bx, by, b, b)
        cx_c, cy_c = quotients(cx, cy, c, c)
        sx, sy = quotients(bx_b + cx_c, by_b + cy_c, s, s)
        b2x, b2y = quotients(bx, by, b * b, b * b)
        c2x, c2y = quotients(cx, cy, c * c, c * c)
        gx += r * (ax - sx - b2x - c2x)
        gy += r * (ay - sy - b2y - c2y)
    return gx, gy


@njit(cache=True)
def _gradient_steps(X, i, buf, deg, step, steps, need, mean):
    """Up to ``steps`` moves of node i along the gradient of its star's mean,
    each from ``step``, halved until taken (the guard of :func:`mean_polish`).
    Returns (the star's mean, moves taken, blocked: no slope, or a trial
    rejected by the smallest ratio or the orientation, not by the mean)."""
    moves = 0
    blocked = False
    for _ in range(steps):
        gx, gy = _mean_gradient(buf, deg, X[i, 0], X[i, 1])
        norm = np.hypot(gx, gy)
        if norm == 0.0:
            blocked = True
            break
        s = step / norm
        for _ in range(BACKTRACKS):
            taken, mean = _try_move(X, i, buf, deg, X[i, 0] + s * gx, X[i, 1] + s * gy,
                                    need, mean)
            if taken > 0:
                moves += 1
                break
            blocked = blocked or taken < 0
            s *= 0.5
        else:
            break
    return mean, moves, blocked


@njit(cache=True, inline="always")
def _try_move(X, i, buf, deg, px, py, need, mean):
    """Move node i to (px, py) if its star stays counter-clockwise, its worst
    ratio at least ``need`` and its mean above ``mean``: (1 taken, 0 not
    for the mean, -1 not for the worst ratio or the orientation; the mean)."""
    q, m = gathered_stats(buf, deg, px, py)
    if not (q > 0.0 and q >= need):
        return -1, mean
    if m > mean + 1e-12:
        X[i, 0] = px
        X[i, 1] = py
        return 1, m
    return 0, mean


@njit(cache=True)
def _compass(X, i, buf, deg, step, halvings, need, mean):
    """Compass search of node i: 8 directions from ``step``, halved
    ``halvings`` times, every improving step taken (the guard of
    :func:`mean_polish`).  Returns (the star's mean, moves taken)."""
    moves = 0
    for _ in range(halvings):
        for d in range(COMPASS):
            taken, mean = _try_move(X, i, buf, deg, X[i, 0] + step * DX[d],
                                    X[i, 1] + step * DY[d], need, mean)
            moves += taken > 0
        step *= 0.5
    return mean, moves


@njit(cache=True)
def _mean_visit(X, triangles, ptr, idx, i, buf, floor, halvings, below, steps):
    """One :func:`mean_polish` visit of node i: the moves taken."""
    deg = gather_star(X, triangles, ptr, idx, i, buf)
    return polish_gathered(X, i, buf, deg, floor, halvings, below, steps)


@njit(cache=True)
def polish_gathered(X, i, buf, deg, floor, halvings, below, steps):
    """:func:`_mean_visit` on node i's star gathered into buf (deg rows, as
    :func:`gather_star` lays them out): the moves taken."""
    worst, mean = gathered_stats(buf, deg, X[i, 0], X[i, 1])
    if mean >= below:
        return 0
    need = max(min(worst, floor), 0.0)
    step = 0.1 * shortest_edge(buf, deg, X[i, 0], X[i, 1])
    mean, moves, blocked = _gradient_steps(X, i, buf, deg, step, steps, need, mean)
    if moves == 0 and (blocked or steps == 0):  # not at a smooth optimum of the mean
        mean, moves = _compass(X, i, buf, deg, step, halvings, need, mean)
    return moves


@njit(cache=True, parallel=True)
def mean_polish(X, triangles, ptr, idx, n_boundary, sweeps, movable, floor, halvings, below,
                steps=0):
    """Raise each star's mean radius ratio: up to ``steps`` steps along its
    gradient, and where none is taken because the smallest ratio binds (or
    there is no slope, or ``steps`` is 0) a compass search, 8 directions
    halved ``halvings`` times.  Where every gradient step fails for the mean
    alone, the star sits at a smooth optimum of it, where the compass search
    finds nothing either: it is not run.
    Both start from a tenth of the shortest incident edge; a step is taken
    if the star's mean grows and its minimum stays at least min(its value
    before, ``floor``) (exact orientation as in :func:`odt_smooth`).  Only
    stars whose mean is below ``below`` are searched.  ``sweeps`` sweeps,
    colour by colour (:mod:`bubblemesh._colouring`); X in place.  A node
    whose last visit moved nothing, and none of whose star has moved since,
    is not visited again: the visit would find what the last one did (an
    exact active set).  Returns the steps taken."""
    order, colour_ptr = colour_classes(triangles, ptr, idx, n_boundary, movable)
    most = star_buffer(ptr).shape[0]
    moved_at = np.full(X.shape[0], -1, np.int64)  # the colour class of each node's last move
    seen_at = np.full(X.shape[0], -1, np.int64)  # and of its last visit
    stamp = 0
    taken = 0
    for _ in range(sweeps):
        moved = 0
        for c in range(colour_ptr.shape[0] - 1):
            stamp += 1
            lo, hi = colour_ptr[c], colour_ptr[c + 1]
            blocks = (hi - lo + BLOCK - 1) // BLOCK
            moves = np.zeros(blocks, np.int64)
            for b in prange(blocks):
                buf = np.empty((most, 5))
                for j in range(lo + b * BLOCK, min(hi, lo + (b + 1) * BLOCK)):
                    i = order[j]
                    if _settled(triangles, ptr, idx, i, moved_at, seen_at[i]):
                        continue
                    seen_at[i] = stamp
                    taken_here = _mean_visit(X, triangles, ptr, idx, i, buf, floor, halvings,
                                             below, steps)
                    if taken_here:
                        moved_at[i] = stamp
                    moves[b] += taken_here
            moved += moves.sum()
        taken += moved
        if moved == 0:
            break
    return taken


@njit(cache=True)
def _settled(triangles, ptr, idx, i, moved_at, seen):
    """Has node i been visited (at class ``seen``) and has nothing of its
    star, i included, moved at or since that visit?  Nodes of one colour share
    no edge, so the neighbours' stamps do not change while i's class runs."""
    if seen < 0:
        return False
    for e in range(ptr[i], ptr[i + 1]):
        t = idx[e]
        for k in range(3):
            if moved_at[triangles[t, k]] >= seen:
                return False
    return True
