"""The §3 iteration kernels: position adjustment by the repulsive overlap
forces (§3.2, eq. 7-8) and size adjustment (§3.4, eq. 9), Jacobi updates
(every node reads the previous iterate), so the parallel kernels give the
same bits as a serial run."""

import numpy as np
from numba import njit, prange

from ._inside import walk_inside
from ._verlet import outgrew
from .memory import unsigned
from .simd import roots_and_reciprocals

MAX_HALVINGS = 4
_ONE, _TWO = np.uint64(1), np.uint64(2)  # steps of unsigned list positions


@njit(cache=True, inline="always")
def _difference(X, i, j):
    """(dx, dy): the vector from node j to node i."""
    return X[i, 0] - X[j, 0], X[i, 1] - X[j, 1]


@njit(cache=True, inline="always")
def _separation(X, i, j):
    """(dx, dy, l_ij): the vector from node j to node i and its length."""
    dx, dy = _difference(X, i, j)
    return dx, dy, np.sqrt(dx * dx + dy * dy)


@njit(cache=True, inline="always")
def _inverse_separation(X, i, j):
    """(dx, dy, 1 / l_ij) from node j to node i; 0 for coincident nodes."""
    dx, dy, length = _separation(X, i, j)
    return dx, dy, 1.0 / length if length > 0.0 else 0.0


@njit(cache=True, inline="always")
def _push(X, R, i, j, w, fx, fy):
    """Adds eq. 8's term of node j, ((r_i + r_j) / l - 1)(x_i - x_j) when
    the bubbles overlap (w = 1 / l, 0 for coincident nodes), to (fx, fy)."""
    dx, dy = _difference(X, i, j)
    scale = (R[i] + R[j]) * w - 1.0  # 0 for coincident nodes (w = 0)
    # a select, not a branch: many listed pairs do not overlap, and a branch
    # on it is mispredicted
    scale = scale if scale > 0.0 else 0.0
    return fx + scale * dx, fy + scale * dy


@njit(cache=True, inline="always")
def _stored_force(X, R, i, e, end, nearby, inverse):
    """Eq. 8's sum over list entries e..end-1 with the stored 1 / l."""
    fx = 0.0
    fy = 0.0
    while e < end:
        fx, fy = _push(X, R, i, unsigned(nearby[e]), inverse[e], fx, fy)
        e += _ONE
    return fx, fy


@njit(cache=True, inline="always")
def _fresh_force(X, R, i, e, end, nearby):
    """Eq. 8's sum over list entries e..end-1, in list order, computing 1 / l:
    two entries at a time with one packed square root and one packed
    division (``simd.py``; the same bits as one at a time)."""
    fx = 0.0
    fy = 0.0
    while e + _ONE < end:
        j = unsigned(nearby[e])
        k = unsigned(nearby[e + _ONE])
        dx, dy = _difference(X, i, j)
        ex, ey = _difference(X, i, k)
        l_j, l_k, w_j, w_k = roots_and_reciprocals(dx * dx + dy * dy, ex * ex + ey * ey)
        fx, fy = _push(X, R, i, j, w_j if l_j > 0.0 else 0.0, fx, fy)
        fx, fy = _push(X, R, i, k, w_k if l_k > 0.0 else 0.0, fx, fy)
        e += _TWO
    if e < end:
        _, _, w = _inverse_separation(X, i, unsigned(nearby[e]))
        fx, fy = _push(X, R, i, unsigned(nearby[e]), w, fx, fy)
    return fx, fy


@njit(cache=True, parallel=True)
def move(X, R, Xn, home, start, count, nearby, inverse, reuse, n_boundary, alpha, P0, tri0,
          nbr0, clearance, X0, R0, skin, V, beta):
    """(b) eq. 7-8 for every interior node, moves kept inside the domain.

    ``beta`` > 0 (``bubblemesh.mesh``, not the paper) adds beta times each
    node's last move ``V[i]`` to its step (heavy-ball momentum: the slow,
    long-wavelength settling of the bubble lattice converges in fewer
    iterations), halved with it, and stores the move taken in ``V``;
    ``beta`` = 0 is the paper's step, bit for bit, and leaves ``V`` alone.

    The overlap term of eq. 8 is (r_i + r_j - l) / l = (r_i + r_j) / l - 1.
    The previous eq. 9 pass already evaluated 1 / l at these very positions
    and stored it per list entry (``inverse``); when ``reuse`` (the lists
    have not been rebuilt since), the square root and division are skipped,
    with the same bits as computing them again; otherwise they go two list
    entries at a time, packed (``simd.py``), the sums still in list order.

    ``home[i]`` (a §2 triangle holding node i) is node i's own, so it is
    updated in place.  Returns how many nodes outgrew the lists built at
    (X0, R0), how many pushed nodes found no step inside the domain, and the
    largest move relative to the node's radius."""
    expired = 0
    blocked = 0
    largest = 0.0
    for node in prange(n_boundary, X.shape[0]):
        i = unsigned(node)
        first = unsigned(start[i])
        end = first + unsigned(count[i])
        if reuse:
            fx, fy = _stored_force(X, R, i, first, end, nearby, inverse)
        else:
            fx, fy = _fresh_force(X, R, i, first, end, nearby)
        Xn[i, 0] = X[i, 0]
        Xn[i, 1] = X[i, 1]
        step = alpha
        vx = beta * V[i, 0] if beta > 0.0 else 0.0
        vy = beta * V[i, 1] if beta > 0.0 else 0.0
        pushed = fx != 0.0 or fy != 0.0 or vx != 0.0 or vy != 0.0
        for attempt in range(MAX_HALVINGS + 1 if pushed else 0):
            if beta > 0.0:
                tx = X[i, 0] + step * fx + (step / alpha) * vx
                ty = X[i, 1] + step * fy + (step / alpha) * vy
            else:
                tx = X[i, 0] + step * fx
                ty = X[i, 1] + step * fy
            if (tx - P0[i, 0]) ** 2 + (ty - P0[i, 1]) ** 2 < clearance[i] ** 2:
                t = home[i]  # deep inside: no walk needed, the old start stays valid
            else:
                t = walk_inside(P0, tri0, nbr0, home[i], tx, ty, 4 * tri0.shape[0] + 8)
            if t >= 0:
                Xn[i, 0] = tx
                Xn[i, 1] = ty
                home[i] = t
                break
            if attempt == MAX_HALVINGS:
                blocked += 1
            step *= 0.5
        dx = Xn[i, 0] - X[i, 0]
        dy = Xn[i, 1] - X[i, 1]
        if beta > 0.0:
            V[i, 0] = dx
            V[i, 1] = dy
        largest = max(largest, (dx * dx + dy * dy) / (R[i] * R[i]))
        if outgrew(Xn, R, X0, R0, i, skin):
            expired += 1
    return expired, blocked, np.sqrt(largest)


@njit(cache=True, inline="always")
def _weigh(R, i, j, length, w, inverse, e, num, den):
    """One term of eq. 9 for list entry e (node j): stores 1 / l (``w``; 0 for
    coincident nodes) for the next eq. 8 pass, and adds r_j / l and 1 / l to
    the sums if the bubbles overlap.  Returns the sums."""
    w = w if length > 0.0 else 0.0
    inverse[e] = w
    weight = w if R[j] + R[i] > length else 0.0
    return num + R[j] * weight, den + weight


@njit(cache=True, parallel=True)
def resize(X, R, Rn, start, count, nearby, inverse, n_boundary, X0, R0, skin):
    """(c) eq. 9 for every interior node, from the nearby bubbles overlapping it;
    stores 1 / l of every listed pair in ``inverse`` for the next eq. 8 pass.
    The lengths and their reciprocals go two list entries at a time (packed,
    the same bits; ``simd.py``), the sums stay in list order.
    Returns how many resized nodes outgrew the lists built at (X0, R0)."""
    n = X.shape[0]
    expired = 0
    for node in prange(n_boundary, n):
        i = unsigned(node)
        num = 0.0
        den = 0.0
        e = unsigned(start[i])
        end = e + unsigned(count[i])
        while e + _ONE < end:
            j = unsigned(nearby[e])
            k = unsigned(nearby[e + _ONE])
            dx, dy = _difference(X, i, j)
            ex, ey = _difference(X, i, k)
            l_j, l_k, w_j, w_k = roots_and_reciprocals(dx * dx + dy * dy, ex * ex + ey * ey)
            num, den = _weigh(R, i, j, l_j, w_j, inverse, e, num, den)
            num, den = _weigh(R, i, k, l_k, w_k, inverse, e + _ONE, num, den)
            e += _TWO
        if e < end:
            j = unsigned(nearby[e])
            _, _, length = _separation(X, i, j)
            w = 1.0 / length if length > 0.0 else 0.0
            num, den = _weigh(R, i, j, length, w, inverse, e, num, den)
        Rn[i] = num / den if den > 0.0 else R[i]
        if outgrew(X, Rn, X0, R0, i, skin):
            expired += 1
    return expired
