"""Physically-based mesh optimisation: paper §3, steps (a)-(e) of §3.6.

(a) §3.1 initial node bubbles: every radius of the §2 mesh times
    ``amplification`` (1.7), so that neighbouring bubbles overlap; §3.3 nearby
    bubbles: the nodes within ``rings`` (3) topological rings of the §2 mesh,
    fixed for all iterations (a CSR list built once).
(b) §3.2 position adjustment of interior nodes, eq. 7-8:
    x_i <- x_i + alpha * sum_j (r_i + r_j - l_ij) n_ji  over nearby j with
    r_i + r_j > l_ij, where n_ji is the unit vector from j to i: the overlap
    pushes i away from j (the paper's repulsive force).
(c) §3.4 size adjustment of interior nodes, eq. 9: r_p is the
    reciprocal-distance mean of the radii of the nearby bubbles that overlap it
    (r_i + r_p > l_pi); unchanged if none overlaps.
(d) repeat until the largest move relative to its node's radius is below
    ``tol``, or ``max_iterations``.
(e) §3.5 constrained Delaunay re-triangulation of the moved nodes.

Speed without changing the result: overlaps are looked for only among the
3-ring nodes within (1 + skin)(r_i + r_j) of each node (a Verlet list, as in
molecular dynamics), rebuilt as soon as some node's displacement plus radius
growth since the last build exceeds 0.9 skin r_i.  No pair outside the list can
overlap before that, and the list keeps the ring order, so every sum has the
same terms in the same order: ``skin=inf`` (no pruning) gives the same bits.

Boundary nodes and their radii never change.  Interior nodes never leave the
domain: a move is accepted only if an exact visibility walk in the (fixed) §2
mesh reaches the target without touching the boundary; otherwise the step is
halved, up to 4 times, and the node stays if none fits.  A target closer to
the node's §2 position than half a lower bound on that position's distance to
the boundary is inside without a walk (the disc of that radius is).  Updates are Jacobi
(every node reads the previous iterate), so the parallel kernel gives the same
bits as a serial run.
"""


import numba
import numpy as np
from numba import njit, prange

from ._mesh import Mesh, OptimizationStats
from .errors import GeometryError, MeshingError
from .memory import unsigned
from .predicates import orient2d
from .simd import roots_and_reciprocals
from .timing import PhaseClock
from .triangulation import constrained_delaunay

MAX_HALVINGS = 4
_ONE, _TWO = np.uint64(1), np.uint64(2)  # steps of unsigned list positions


# --- (a) neighbour sets --------------------------------------------------------------


@njit(cache=True)
def node_adjacency(triangles, neighbors, n):
    """CSR (ptr, idx) of the mesh's edge graph: each edge once per direction."""
    deg = np.zeros(n + 1, np.int64)
    for t in range(triangles.shape[0]):
        for j in range(3):
            u = triangles[t, (j + 1) % 3]
            v = triangles[t, (j + 2) % 3]
            deg[u + 1] += 1
            if neighbors[t, j] < 0:
                deg[v + 1] += 1
    ptr = np.cumsum(deg)
    fill = ptr[:-1].copy()
    idx = np.empty(ptr[-1], np.int64)
    for t in range(triangles.shape[0]):
        for j in range(3):
            u = triangles[t, (j + 1) % 3]
            v = triangles[t, (j + 2) % 3]
            idx[fill[u]] = v
            fill[u] += 1
            if neighbors[t, j] < 0:
                idx[fill[v]] = u
                fill[v] += 1
    return ptr, idx


@njit(cache=True)
def _rings_into(ptr, idx, lo, hi, rings, out, base, room, counts):
    """Breadth-first 1..rings of nodes lo..hi-1 into out[base:base + room],
    counts[i] entries for node i.  Returns the entries written, -1 if no room."""
    n = ptr.shape[0] - 1
    mark = np.full(n, -1, np.int64)
    frontier = np.empty(n, np.int64)
    m = base
    for i in range(lo, hi):
        mark[i] = i
        frontier[0] = i
        first = 0
        last = 1
        for _ in range(rings):
            end = last
            for f in range(first, last):
                u = frontier[f]
                for e in range(ptr[u], ptr[u + 1]):
                    v = idx[e]
                    if mark[v] != i:
                        if m >= base + room:
                            return -1
                        mark[v] = i
                        frontier[end] = v
                        end += 1
                        out[m] = v
                        m += 1
            first = last
            last = end
        counts[i] = last - 1
    return m - base


@njit(cache=True, parallel=True)
def _rings_in_blocks(ptr, idx, rings, blocks, out, counts, written):
    """Block b (nodes b n / blocks .. (b + 1) n / blocks) fills its own share
    of ``out``; the blocks run in parallel."""
    n = ptr.shape[0] - 1
    share = out.shape[0] // blocks
    for b in prange(blocks):
        written[b] = _rings_into(ptr, idx, b * n // blocks, (b + 1) * n // blocks, rings,
                                 out, b * share, share, counts)


def ring_neighbors(ptr, idx, n, rings, per_node=48):
    """CSR of the nodes within 1..rings topological rings of each node (§3.3),
    in breadth-first order.

    The nodes are cut into one block per thread, each written to its own
    share of a buffer of ``per_node`` entries per node (a 3-ring of a
    Delaunay mesh has about 38); the shares are then closed up in place, so
    the result does not depend on the number of blocks.  A share that
    overflows (a very irregular mesh) makes all blocks start again with twice
    the room; no node has more than n neighbours, so this ends."""
    blocks = max(1, min(numba.get_num_threads(), n // 1024))
    while True:
        out = np.empty(max(blocks, per_node * n + 64 * blocks), np.int32)
        counts = np.zeros(n, np.int64)
        written = np.zeros(blocks, np.int64)
        _rings_in_blocks(ptr, idx, rings, blocks, out, counts, written)
        if (written >= 0).all():
            break
        per_node *= 2
    share = len(out) // blocks
    end = int(written[0])
    for b in range(1, blocks):  # close up the shares, left to right
        out[end:end + written[b]] = out[b * share:b * share + written[b]]
        end += int(written[b])
    ring_ptr = np.zeros(n + 1, np.int64)
    np.cumsum(counts, out=ring_ptr[1:])
    return ring_ptr, out[:end]  # a view: copying would raise the peak memory


def boundary_clearance(points, segments, n_boundary, reach):
    """Half a lower bound on each node's distance to the boundary: the distance
    to the nearest segment midpoint minus half the longest segment (a point of
    segment s is within L_s / 2 of its midpoint).  0 for boundary nodes.

    Bounds above ``reach`` are not needed (a move farther than that from the
    §2 position is checked by the walk instead), so the search stops there:
    nodes with no midpoint within L / 2 + 2 reach get the bound ``reach``.
    Unbounded, the deep nodes of a disk, about equally far from every
    midpoint, made this 1.5 s at 500,000 nodes; bounded, 0.1 s."""
    from scipy.spatial import cKDTree

    ends = points[segments]
    midpoints = ends.mean(axis=1)
    longest = float(np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1).max())
    clearance = np.zeros(len(points))
    if len(points) > n_boundary:
        horizon = 0.5 * longest + 2.0 * reach
        nearest, _ = cKDTree(midpoints).query(points[n_boundary:], workers=-1,
                                              distance_upper_bound=horizon)
        nearest = np.minimum(nearest, horizon)  # inf: no midpoint within the horizon
        clearance[n_boundary:] = 0.5 * np.maximum(nearest - 0.5 * longest, 0.0)
    return clearance


def vertex_triangles(triangles, n):
    """One triangle incident to each node (the last one listed)."""
    home = np.full(n, -1, np.int64)
    home[triangles.ravel()] = np.repeat(np.arange(len(triangles)), 3)
    return home


@njit(cache=True, inline="always")
def _closer_than(X, i, j, distance):
    dx = X[i, 0] - X[j, 0]
    dy = X[i, 1] - X[j, 1]
    return dx * dx + dy * dy < distance * distance


@njit(cache=True, parallel=True)
def _fill_close(X, R, ring_ptr, ring_idx, n_boundary, skin, start, room, count, out):
    """Node i's list, its ring neighbours within (1 + skin)(r_i + r_j) in ring
    order, goes to out[start[i]:] if it fits in room[i] slots; count[i] is its
    length either way.  Returns how many lists did not fit."""
    overflow = 0
    for node in prange(n_boundary, X.shape[0]):
        i = unsigned(node)
        c = 0
        for e in range(unsigned(ring_ptr[i]), unsigned(ring_ptr[node + 1])):
            j = unsigned(ring_idx[e])
            if _closer_than(X, i, j, (1.0 + skin) * (R[i] + R[j])):
                if c < room[i]:
                    out[unsigned(start[i] + c)] = j
                c += 1
        count[i] = c
        if c > room[i]:
            overflow += 1
    return overflow


def _layout(count, spare):
    """Slots for lists of ``count`` entries plus ``spare`` each: (start, room)."""
    room = count + spare
    room[count == 0] = 0
    start = np.zeros(len(count), np.int64)
    np.cumsum(room[:-1], out=start[1:])
    return start, room


@njit(cache=True, inline="always")
def _outgrew(X, R, X0, R0, i, skin):
    """Has node i used up its share of the skin since the lists were built?"""
    dx = X[i, 0] - X0[i, 0]
    dy = X[i, 1] - X0[i, 1]
    # |dx, dy| + growth > share, without the square root
    room = 0.9 * skin * R0[i] - max(0.0, R[i] - R0[i])
    return room < 0.0 or dx * dx + dy * dy > room * room


# --- keeping nodes inside: a walk in the §2 mesh ----------------------------------------


@njit(cache=True)
def walk_inside(P0, tri0, nbr0, start, px, py, max_steps):
    """Triangle of the §2 mesh whose closure holds (px, py) without lying on the
    domain boundary, reached by a visibility walk from ``start``; -1 if the walk
    would cross or touch the boundary (or exceeds its bound)."""
    t = start
    for _ in range(max_steps):
        moved = False
        for j in range(3):
            u = tri0[t, (j + 1) % 3]
            v = tri0[t, (j + 2) % 3]
            if orient2d(P0[u, 0], P0[u, 1], P0[v, 0], P0[v, 1], px, py) < 0.0:
                t = nbr0[t, j]
                moved = True
                break
        if t < 0:
            return -1
        if not moved:
            for j in range(3):
                if nbr0[t, j] < 0:
                    u = tri0[t, (j + 1) % 3]
                    v = tri0[t, (j + 2) % 3]
                    if orient2d(P0[u, 0], P0[u, 1], P0[v, 0], P0[v, 1], px, py) == 0.0:
                        return -1
            return t
    return -1


# --- (b)-(d) the iterations ------------------------------------------------------------


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


@njit(cache=True, parallel=True)
def _move(X, R, Xn, home, start, count, nearby, inverse, reuse, n_boundary, alpha, P0, tri0,
          nbr0, clearance, X0, R0, skin):
    """(b) eq. 7-8 for every interior node, moves kept inside the domain.

    The overlap term of eq. 8 is (r_i + r_j - l) / l = (r_i + r_j) / l - 1.
    The previous eq. 9 pass already evaluated 1 / l at these very positions
    and stored it per list entry (``inverse``); when ``reuse`` (the lists
    have not been rebuilt since), the square root and division are skipped,
    with the same bits as computing them again.

    ``home[i]`` (a §2 triangle holding node i) is node i's own, so it is
    updated in place.  Returns how many nodes outgrew the lists built at
    (X0, R0), how many pushed nodes found no step inside the domain, and the
    largest move relative to the node's radius."""
    expired = 0
    blocked = 0
    largest = 0.0
    for node in prange(n_boundary, X.shape[0]):
        i = unsigned(node)
        fx = 0.0
        fy = 0.0
        first = unsigned(start[i])
        for e in range(first, first + unsigned(count[i])):
            j = unsigned(nearby[e])
            if reuse:
                dx, dy = _difference(X, i, j)
                w = inverse[e]
            else:
                dx, dy, w = _inverse_separation(X, i, j)
            scale = (R[i] + R[j]) * w - 1.0  # 0 for coincident nodes (w = 0)
            # a select, not a branch: about 40% of listed pairs do not overlap, and
            # mispredicting them cost half the kernel's time (measured)
            scale = scale if scale > 0.0 else 0.0
            fx += scale * dx
            fy += scale * dy
        Xn[i, 0] = X[i, 0]
        Xn[i, 1] = X[i, 1]
        step = alpha
        for attempt in range(MAX_HALVINGS + 1 if fx != 0.0 or fy != 0.0 else 0):
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
        largest = max(largest, (dx * dx + dy * dy) / (R[i] * R[i]))
        if _outgrew(Xn, R, X0, R0, i, skin):
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
def _resize(X, R, Rn, start, count, nearby, inverse, n_boundary, X0, R0, skin):
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
        if _outgrew(X, Rn, X0, R0, i, skin):
            expired += 1
    return expired


def optimize(mesh, *, amplification=1.7, rings=3, alpha=0.1, max_iterations=200, tol=1e-3,
             skin=0.3, progress=False):
    """Paper §3: move interior nodes by bubble overlap forces, adjust their
    bubbles, then re-triangulate (constrained Delaunay).

    Parameters are the paper's: ``amplification`` 1.7 (§3.1), ``rings`` 3
    (§3.3), ``alpha`` 0.1 (eq. 7).  The iterations stop when every node moved
    less than ``tol`` times its radius, or after ``max_iterations``.  Returns a
    new :class:`Mesh`; ``stats`` gains ``iterations``, ``max_displacement``
    (relative to the radius, last iteration), ``blocked_moves`` (node moves,
    summed over iterations, that found no step inside the domain),
    ``list_builds``, ``list_layouts``, ``optimize_seconds`` and
    ``optimize_phases`` (seconds in rings, setup, lists, move, resize,
    retriangulation).  ``skin`` only trades Verlet-list rebuilds against list
    length; the result does not depend on it (module
    docstring).  The returned ``radii`` are the §3 bubbles: every radius
    amplified (§3.1), the boundary ones then fixed, the interior ones from
    eq. 9 (the paper's panel (d), "optimised node bubbles")."""
    _check_parameters(amplification=amplification, alpha=alpha, skin=skin, rings=rings,
                      max_iterations=max_iterations, tol=tol)
    clock = PhaseClock()
    n_b = mesh.n_boundary
    P0 = np.ascontiguousarray(mesh.points)
    tri0 = np.ascontiguousarray(mesh.triangles)
    nbr0 = np.ascontiguousarray(mesh.neighbors)
    n = len(P0)
    ring_ptr, ring_idx = ring_neighbors(*node_adjacency(tri0, nbr0, n), n, int(rings))
    clock.lap("rings")
    X = P0.copy()
    R = np.asarray(mesh.radii, dtype=np.float64) * amplification
    home = vertex_triangles(tri0, n)
    clearance = boundary_clearance(P0, np.asarray(mesh.segments), n_b,
                                   reach=4.0 * float(R.max(initial=0.0)))
    Xn, Rn = X.copy(), R.copy()
    iterations, largest, blocked = 0, 0.0, 0
    bar = _progress_bar(progress, max_iterations)
    lists = _Lists(ring_ptr, ring_idx, n_b, skin)
    expired = True  # no lists yet
    reuse = False  # 1 / l stored for these lists and positions?
    clock.lap("setup")
    while iterations < max_iterations:
        iterations += 1
        if expired:
            lists.build(X, R)
            reuse = False
            clock.lap("lists")
        expired, stuck, largest = _move(X, R, Xn, home, *lists.arrays, reuse, n_b, alpha, P0,
                                        tri0, nbr0, clearance, lists.X0, lists.R0, lists.skin)
        blocked += stuck
        clock.lap("move")
        if expired:
            lists.build(Xn, R)
            clock.lap("lists")
        expired = _resize(Xn, R, Rn, *lists.arrays, n_b, lists.X0, lists.R0, lists.skin) > 0
        reuse = True
        clock.lap("resize")
        X, Xn, R, Rn = Xn, X, Rn, R
        if bar is not None:
            bar.update(1)
            bar.set_postfix(max_move=f"{largest:.2e}")
        if largest < tol:
            break
    if bar is not None:
        bar.close()
    builds, layouts = lists.builds, lists.layouts
    # not needed by the re-triangulation: freed to lower the peak memory
    del lists, ring_ptr, ring_idx, Xn, Rn, home, clearance
    triangles, neighbors = _retriangulate(X, mesh.segments)
    clock.lap("retriangulation")
    stats = OptimizationStats(
        iterations=iterations, max_displacement=float(largest), blocked_moves=int(blocked),
        list_builds=builds, list_layouts=layouts, amplification=amplification, rings=rings,
        alpha=alpha, seconds=clock.total(), phases=dict(clock.seconds))
    return Mesh(points=X, triangles=triangles, neighbors=neighbors, radii=R,
                segments=mesh.segments, n_boundary=n_b, domain=mesh.domain,
                generation=mesh.generation, optimization=stats)


def _check_parameters(*, amplification, alpha, skin, rings, max_iterations, tol):
    """ValueError naming the first parameter outside its meaningful range."""
    rules = [
        ("amplification", amplification, amplification > 0, "> 0"),
        ("alpha", alpha, alpha > 0, "> 0"),
        ("skin", skin, skin > 0, "> 0 (inf disables the lists)"),
        ("rings", rings, int(rings) == rings and rings >= 1, "an integer >= 1"),
        ("max_iterations", max_iterations, int(max_iterations) == max_iterations
         and max_iterations >= 0, "an integer >= 0"),
        ("tol", tol, tol >= 0, ">= 0"),
    ]
    for name, value, ok, expected in rules:
        if not ok:
            raise ValueError(f"optimize: {name} must be {expected}, got {value!r}")


class _Lists:
    """Verlet lists over the fixed ring sets, and the state (X0, R0) they were
    built at; the kernels report when a node outgrows them.

    Each node's list sits in its own slots, with ``SPARE`` free ones, so a
    rebuild is one pass over the rings; only when some list outgrows its slots
    are they laid out afresh from the new lengths and filled again (the
    counting pass a packed CSR would need every time)."""

    SPARE = 6  # at 1M elements: 1 layout in 16 builds (4 spare: 3, 2 spare: 16)

    def __init__(self, ring_ptr, ring_idx, n_boundary, skin):
        self.ring_ptr, self.ring_idx = ring_ptr, ring_idx
        self.n_boundary, self.skin = n_boundary, float(skin)
        n = len(ring_ptr) - 1
        if np.isinf(self.skin):  # no pruning: the rings themselves
            self.arrays = (ring_ptr[:-1], np.diff(ring_ptr), ring_idx, np.zeros(len(ring_idx)))
        else:
            self.arrays = (np.zeros(n, np.int64), np.zeros(n, np.int64), np.empty(0, np.int32),
                           np.empty(0))
        self.room = np.zeros(n, np.int64)
        self.builds = self.layouts = 0

    def build(self, X, R):
        if not np.isinf(self.skin):
            start, count, out, inverse = self.arrays
            args = (X, R, self.ring_ptr, self.ring_idx, self.n_boundary, self.skin)
            if _fill_close(*args, start, self.room, count, out) > 0:
                self.arrays = None  # the old slots go before the new ones come
                del out, inverse
                start, self.room = _layout(count, self.SPARE)
                out = np.empty(int(start[-1] + self.room[-1]), np.int32)
                inverse = np.zeros(len(out))
                _fill_close(*args, start, self.room, count, out)
                self.layouts += 1
            self.arrays = (start, count, out, inverse)
        self.X0, self.R0 = X.copy(), R.copy()
        self.builds += 1


def _retriangulate(points, segments):
    """(e) §3.5; a failure here means two nodes met, which is reported."""
    try:
        return constrained_delaunay(points, segments)
    except GeometryError as error:
        raise MeshingError(f"re-triangulation after optimisation failed: {error}") from error


def _progress_bar(progress, total):
    if not progress:
        return None
    from tqdm.auto import tqdm

    return tqdm(total=total, desc="optimize (§3)", unit="it")
