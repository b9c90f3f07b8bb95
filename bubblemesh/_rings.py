"""The fixed sets of nearby bubbles of §3.3: every node's 1st-3rd ring
neighbours in the §2 mesh, as a CSR list built once for all iterations."""

import numba
import numpy as np
from numba import njit, prange

from .memory import unsigned

_ONE = np.uint64(1)


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
    frontier = np.empty(n + 1, np.int64)  # + 1: the slot past the end takes stray writes
    m = base
    for i in range(lo, hi):
        mark[unsigned(i)] = i
        frontier[0] = i
        first = 0
        last = 1
        for _ in range(rings):
            end = last
            for f in range(first, last):
                u = unsigned(frontier[unsigned(f)])
                for e in range(unsigned(ptr[u]), unsigned(ptr[u + _ONE])):
                    if m >= base + room:
                        return -1
                    # every neighbour is written and only a new one kept (the
                    # ends move past it): whether it is new is a coin toss
                    # that a branch mispredicts
                    v = idx[e]
                    new = mark[unsigned(v)] != i
                    mark[unsigned(v)] = i
                    frontier[unsigned(end)] = v
                    out[unsigned(m)] = v
                    end += 1 if new else 0
                    m += 1 if new else 0
            first = last
            last = end
        counts[unsigned(i)] = last - 1
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


def ring_neighbors(ptr: np.ndarray, idx: np.ndarray, n: int, rings: int, per_node: int = 48
                   ) -> tuple[np.ndarray, np.ndarray]:
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


def vertex_triangles(triangles: np.ndarray, n: int) -> np.ndarray:
    """One triangle incident to each node (the last one listed)."""
    home = np.full(n, -1, np.int64)
    home[triangles.ravel()] = np.repeat(np.arange(len(triangles)), 3)
    return home
