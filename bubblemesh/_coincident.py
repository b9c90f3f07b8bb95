"""Nodes on the same coordinates (not in the paper): the default mesher's
forces can move a node onto another's position far from the origin, where
floats are coarse; such nodes go back to their §2 positions
(``pipeline._separate``).  One pass with a hash table instead of a sort."""

import numpy as np
from numba import njit


@njit(cache=True)
def shared_positions(X):
    """Mask of the rows of X (n, 2) equal to another row (0.0 equals -0.0):
    open addressing on hash((x, y)) (Python's, which maps -0.0 like 0.0), a
    table at most half full, so every probe sequence ends at a free slot."""
    n = X.shape[0]
    size = 2
    while size < 2 * n:
        size *= 2
    table = np.full(size, -1, np.int64)
    shared = np.zeros(n, np.bool_)
    for i in range(n):
        x, y = X[i, 0], X[i, 1]
        slot = hash((x, y)) & (size - 1)
        for _ in range(size):
            j = table[slot]
            if j < 0:
                table[slot] = i
                break
            if X[j, 0] == x and X[j, 1] == y:  # the first row with (x, y) stays in the table
                shared[i] = True
                shared[j] = True
                break
            slot = (slot + 1) & (size - 1)
    return shared
