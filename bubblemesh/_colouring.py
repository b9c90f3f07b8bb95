"""Node colouring for the parallel smoothing sweeps of ``bubblemesh.mesh`` (not
in the paper).

A sweep that moves each node by looking at its star only (the guarded
smoothing, the ODT pass, the mean polish) reads the positions of the node's
neighbours and writes its own.  Two nodes that share no edge can therefore be
visited at the same time, and all nodes of one colour of a proper colouring
of the edge graph may be visited in parallel: each reads only nodes of other
colours, which do not move meanwhile.  Colour by colour, the result depends
on the colouring alone, not on the threads (deterministic on any thread
count).  The colouring is greedy in index order (the smallest colour no
coloured neighbour has), so it is deterministic too; nodes of one colour stay
in index order, which keeps the spatial order of the Hilbert-sorted nodes.
"""

import numpy as np
from numba import njit

BLOCK = 64  # nodes per parallel task


@njit(cache=True)
def colour_classes(triangles, ptr, idx, first, visit):
    """Nodes i >= first with ``visit[i]`` set and a non-empty star, grouped by
    a greedy colouring of the edge graph (stars from
    :func:`bubblemesh._smoothing.stars`): (order, colour_ptr), colour c being
    order[colour_ptr[c]:colour_ptr[c + 1]], each in index order."""
    n = ptr.shape[0] - 1
    colour = np.full(n, -1, np.int64)
    used = np.full(64, -1, np.int64)  # used[c] == i: a neighbour of i has colour c
    ncol = 0
    for i in range(first, n):
        if not visit[i] or ptr[i + 1] == ptr[i]:
            continue
        for e in range(ptr[i], ptr[i + 1]):
            t = idx[e]
            for k in range(3):
                c = colour[triangles[t, k]]
                if c >= 0:
                    if c >= used.shape[0]:
                        used = np.concatenate((used, np.full(used.shape[0], -1, np.int64)))
                    used[c] = i
        c = 0
        while c < used.shape[0] and used[c] == i:
            c += 1
        if c >= used.shape[0]:
            used = np.concatenate((used, np.full(used.shape[0], -1, np.int64)))
        colour[i] = c
        ncol = max(ncol, c + 1)
    count = np.zeros(ncol + 1, np.int64)
    for i in range(n):
        if colour[i] >= 0:
            count[colour[i] + 1] += 1
    colour_ptr = np.cumsum(count)
    fill = colour_ptr[:-1].copy()
    order = np.empty(colour_ptr[-1], np.int64)
    for i in range(n):
        c = colour[i]
        if c >= 0:
            order[fill[c]] = i
            fill[c] += 1
    return order, colour_ptr
