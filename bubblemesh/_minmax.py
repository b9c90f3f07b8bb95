"""Joint min-max moves around the worst triangles (not in the paper; after §3).

The smoothing, the compass search and the mean polish
(:mod:`bubblemesh._smoothing`, :mod:`bubblemesh._odt`) move one node at a
time, each only where its own star gains.  The worst triangle's free node is
often held by its neighbours: every move that lifts it lowers a triangle next
to it, which only a move of that neighbour would mend.  Here the free nodes
within RINGS rings of the worst triangle move together, in one solve of
scipy's SLSQP with the exact gradient of the radius ratio (eq. 10, ln rho =
ln 4 + 2 ln 2A - ln(a + b + c) - ln a - ln b - ln c): the largest t + WEIGHT *
(mean ratio of the triangles touching them) with every such ratio at least
t, t at most the *cap*, and the triangles near their area bound kept within
it.  The cap is the smallest ratio elsewhere in the mesh (lifting the patch
past it buys nothing yet), the worst triangle's ties within TIE aside (they
are lifted in turn); where the result is refused, the cap is halved toward
the patch's minimum (CAPS tries): a lower cap costs less of the mean.

A move is kept when every triangle of the patch is strictly counter-clockwise
(exact :func:`~bubblemesh.predicates.orient2d`), within its area bound and
at least min(its ratio before, KEEP), the patch's smallest ratio has risen by
more than RISE and the mesh's mean ratio stays within MEAN_DROP of its value
before the first move.  A triangle none of whose nodes may move, or whose
patch was refused, is *held*: it leads no patch and caps none, and a patch
around it may not lower it (SLSQP bounds it at its ratio, HELD_MARGIN
above, instead of by t).  A patch is lifted if its worst triangle is below
POOR, or below the lowest triangle of fixed nodes (the mesh's minimum
cannot rise past that) and, after the first FIRST_ROUNDS moves or a
refusal, below LIFT_BELOW (a gear's forty teeth are forty such patches;
above it the mean is worth more than the minimum).  FAILED refusals or
``rounds`` moves end the rounds.  Nodes keep their triangles, so the mesh
stays valid and conforming and boundary nodes never move; SLSQP (run on one
BLAS thread: its LAPACK calls give other bits on other thread counts) and
the order of the patches are deterministic.  A solve that fails (a zero-area
or zero-length trial point divides by zero in :func:`ratio_rows`; scipy
raising) refuses its move.
"""

import math
import warnings

import numpy as np
from numba import njit
from scipy.optimize import minimize
from threadpoolctl import threadpool_limits

from ._area_bound import _areas
from ._flips import turned_over
from ._smoothing import stars, triangle_quality

RINGS = 1  # free nodes this many rings around the worst triangle move
TIE = 1e-3  # triangles this close to the minimum do not cap a patch's rise
WEIGHT = 0.1  # of the patch's mean ratio against its minimum in the objective
CAPS = 3  # caps tried per patch, each halfway back to the patch's minimum
FAILED = 16  # patches refused, at most, before the rounds stop
FIRST_ROUNDS = 16  # moves of any patch that can raise the minimum; then only of those
LIFT_BELOW = 0.85  # whose worst triangle is below this
POOR = 0.7  # patches worse than this are lifted whatever the minimum
HELD_MARGIN = 1e-7  # a held triangle's bound above its ratio: SLSQP ends a hair past bounds
RISE = 1e-6  # a smaller rise of a patch's minimum is not worth its solve
MEAN_DROP = 2e-4  # all moves together may lower the mesh's mean ratio by this much
KEEP = 0.8  # nor take a triangle below min(its ratio, this)
NEAR = 0.5  # triangles above this share of their area bound get it as a constraint
ITERATIONS, FTOL = 30, 1e-9  # SLSQP's iterations and tolerance per solve


@njit(cache=True)
def ratio_rows(Y, corners, slot, rho, area2, d_rho, d_area2):
    """Eq. 10 ratio and twice the signed area of each triangle ``corners``
    (k, 3) of the points Y, into rho and area2 (k,), and their gradients
    with respect to the variables, into the rows of d_rho and d_area2
    (k, v): corner j of triangle t is variables 2 slot[t, j] (x) and
    2 slot[t, j] + 1 (y), none where slot is -1.  ln rho = ln 4 + 2 ln 2A -
    ln(a + b + c) - ln a - ln b - ln c, differentiated term by term."""
    d_rho[:] = 0.0
    d_area2[:] = 0.0
    g = np.empty((3, 2))
    for t in range(corners.shape[0]):
        x0, y0 = Y[corners[t, 0], 0], Y[corners[t, 0], 1]
        x1, y1 = Y[corners[t, 1], 0], Y[corners[t, 1], 1]
        x2, y2 = Y[corners[t, 2], 0], Y[corners[t, 2], 1]
        a2 = (x1 - x0) * (y2 - y0) - (y1 - y0) * (x2 - x0)
        # side j is opposite corner j and runs from corner j+1 to j+2
        sx = (x2 - x1, x0 - x2, x1 - x0)
        sy = (y2 - y1, y0 - y2, y1 - y0)
        ln = (math.hypot(sx[0], sy[0]), math.hypot(sx[1], sy[1]), math.hypot(sx[2], sy[2]))
        perimeter = ln[0] + ln[1] + ln[2]
        r = 4.0 * a2 * a2 / (perimeter * ln[0] * ln[1] * ln[2])
        rho[t], area2[t] = r, a2
        for j in range(3):  # d(2A)/d corner j: the opposite side turned by -90 degrees
            g[j, 0] = -2.0 * sy[j] / a2
            g[j, 1] = 2.0 * sx[j] / a2
        for j in range(3):
            w = (1.0 / perimeter + 1.0 / ln[j]) / ln[j]
            g[(j + 2) % 3, 0] -= w * sx[j]
            g[(j + 2) % 3, 1] -= w * sy[j]
            g[(j + 1) % 3, 0] += w * sx[j]
            g[(j + 1) % 3, 1] += w * sy[j]
        for j in range(3):
            v = slot[t, j]
            if v >= 0:
                d_rho[t, 2 * v] += r * g[j, 0]
                d_rho[t, 2 * v + 1] += r * g[j, 1]
                d_area2[t, 2 * v] -= sy[j]
                d_area2[t, 2 * v + 1] += sx[j]


class _Patch:
    """The triangles ``tris`` around the free nodes ``free``, in coordinates
    centred on them and scaled by their mean edge (SLSQP's tolerances are
    absolute): the variables z are the free nodes' local x, y, then t.
    :meth:`at` evaluates :func:`ratio_rows` once per z."""

    def __init__(self, X, T, free, tris, limit, held, least):
        self.held, self.least = held, least  # per triangle: bounded by least, not by t
        nodes = np.unique(T[tris])
        self.corners = np.searchsorted(nodes, T[tris])
        self.free = np.searchsorted(nodes, free)
        self.centre = X[free].mean(axis=0)
        P = X[T[tris]]
        self.scale = float(np.mean(np.hypot(*(P[:, 1] - P[:, 0]).T)))
        self.local = (X[nodes] - self.centre) / self.scale
        slot = np.full(len(nodes), -1, np.int64)
        slot[self.free] = np.arange(len(free))
        self.slot = slot[self.corners]  # (k, 3): the corner's variable, or -1
        k, v = len(tris), 2 * len(free) + 1
        self.rho, self.area2 = np.empty(k), np.empty(k)
        self.d_rho, self.d_area2 = np.empty((k, v)), np.empty((k, v))
        self.z = None
        self.limit2 = 2.0 * limit[tris] / self.scale ** 2
        self.near = self.at(self.start(0.0))[1] > NEAR * self.limit2

    def start(self, t):
        return np.r_[self.local[self.free].ravel(), t]

    def at(self, z):
        """(rho, area2, d_rho, d_area2) at z; d_rho's last column is zero (no t)."""
        if self.z is None or not np.array_equal(z, self.z):
            Y = self.local.copy()
            Y[self.free] = z[:-1].reshape(-1, 2)
            ratio_rows(Y, self.corners, self.slot, self.rho, self.area2, self.d_rho,
                       self.d_area2)
            self.z = z.copy()
        return self.rho, self.area2, self.d_rho, self.d_area2

    def coordinates(self, z):
        return z[:-1].reshape(-1, 2) * self.scale + self.centre


def _solve(patch, start, cap):
    """The free nodes' positions maximising t + WEIGHT * mean rho with rho >=
    t on the patch (a held triangle's rho >= its ``least``), t <= cap, the
    areas near their bound within it."""
    k = len(patch.rho)
    z0 = patch.start(start)

    def objective(z):
        return -z[-1] - WEIGHT * patch.at(z)[0].sum() / k

    def gradient(z):
        g = -WEIGHT / k * patch.at(z)[2].sum(axis=0)
        g[-1] = -1.0
        return g

    def constraint(z):
        rho, area2, _, _ = patch.at(z)
        return np.r_[rho - np.where(patch.held, patch.least, z[-1]),
                     (patch.limit2 - area2)[patch.near]]

    def constraint_jacobian(z):
        _, _, d_rho, d_area2 = patch.at(z)
        J = d_rho.copy()
        J[:, -1] = np.where(patch.held, 0.0, -1.0)
        return np.vstack([J, -d_area2[patch.near]])

    bounds = [(None, None)] * (len(z0) - 1) + [(None, cap)]
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore", RuntimeWarning)
        try:
            z = minimize(objective, z0, jac=gradient, method="SLSQP", bounds=bounds,
                         constraints=[dict(type="ineq", fun=constraint,
                                           jac=constraint_jacobian)],
                         options=dict(maxiter=ITERATIONS, ftol=FTOL)).x
        except (ArithmeticError, ValueError, np.linalg.LinAlgError):  # refuse the move only
            z = np.full_like(z0, np.nan)
    return patch.coordinates(z)


def _around(T, ptr, idx, worst, movable):
    """The free nodes within RINGS rings of triangle ``worst`` and the
    triangles touching them."""
    nodes = np.unique(T[worst])
    for _ in range(RINGS):
        nodes = np.unique(T[np.concatenate([idx[ptr[v]:ptr[v + 1]] for v in nodes])])
    free = nodes[movable[nodes]]
    if not len(free):
        return free, free
    return free, np.unique(np.concatenate([idx[ptr[v]:ptr[v + 1]] for v in free]))


def minmax_patches(X, T, movable, limit, rounds):
    """Lift the worst triangles' ratios by joint moves of the free nodes
    around them (module docstring).  X (n, 2) is updated in place; T (m, 3)
    CCW, ``movable`` (n,) the free nodes, ``limit`` (m,) each triangle's area
    bound.  Returns the number of moves kept."""
    if not len(T) or not movable.any():
        return 0
    ptr, idx = stars(T, len(X))
    q = triangle_quality(X, T)
    lowest = (float(q.mean()) - MEAN_DROP) * len(T)  # the least sum of ratios
    held = ~movable[T].any(axis=1)  # and, in turn, those whose patch was refused
    bar = float(q[held].min(initial=np.inf))  # the mesh's minimum cannot rise past it
    kept = failed = 0
    with threadpool_limits(limits=1, user_api="blas"):
        while kept < rounds and failed < FAILED and not held.all():
            worst = int(np.argmin(np.where(held, np.inf, q)))
            if not _worth(float(q[worst]), bar, kept, failed):
                break
            free, tris = _around(T, ptr, idx, worst, movable)
            if len(free) and _moved(X, T, q, free, tris, limit, lowest, held):
                kept += 1
                continue
            held[worst] = True  # a later patch around it may still lift it
            failed += 1
    return kept


def _worth(worst, bar, kept, failed):
    """Is a patch whose worst ratio is ``worst`` worth its solve and its share
    of the mean: below POOR, or able to raise the mesh's minimum (below the
    ``bar`` of the triangles of fixed nodes), after the first FIRST_ROUNDS
    moves or a refusal only below LIFT_BELOW?"""
    first = kept < FIRST_ROUNDS and not failed
    return worst < POOR or (worst < bar and (first or worst < LIFT_BELOW))


def _moved(X, T, q, free, tris, limit, lowest, held):
    """Move the ``free`` nodes of X by :func:`_solve`, its cap halved toward
    the patch's minimum while the move is refused; True if one was kept (q,
    the triangles' ratios, updated), else False (X unchanged)."""
    before = q[tris]
    lead = ~held[tris]  # the held triangles may rise but not fall, and neither lead nor cap
    if not lead.any():
        return False
    floor = float(before[lead].min())
    if not floor > 0.0:  # a flat triangle: its ratio's gradient divides by its area
        return False
    patch = _Patch(X, T, free, tris, limit, ~lead, before + HELD_MARGIN)
    elsewhere = np.where(q <= floor + TIE, np.inf, q)  # the worst's ties are lifted in turn
    elsewhere[tris] = np.inf
    elsewhere[held] = np.inf
    cap = min(float(elsewhere.min()), 1.0)
    old = X[free].copy()
    others = float(q.sum()) - float(before.sum())
    for _ in range(CAPS):
        if not cap > floor + RISE:
            return False
        X[free] = _solve(patch, floor, cap)
        if np.all(np.isfinite(X[free])) and not turned_over(X, T[tris]).any():
            after = triangle_quality(X, T[tris])
            if (after[lead].min() > floor + RISE and others + float(after.sum()) >= lowest
                    and np.all(after >= np.minimum(before, KEEP))
                    and np.all(_areas(X, T[tris]) <= limit[tris])):
                q[tris] = after
                return True
        X[free] = old
        cap = 0.5 * (cap + floor)
    return False
