"""Nodes on the same coordinates (not in the paper): the default mesher's
forces can move a node onto another's position far from the origin, where
floats are coarse; such nodes go back to their §2 positions
(``pipeline._separate``).  One pass with a hash table instead of a sort."""

import numba
import numpy as np
from numba import njit

_MASK = (1 << 64) - 1

if numba.config.DISABLE_JIT:  # type: ignore[attr-defined]

    def _mixed(x, y):
        """A 64-bit hash of two 64-bit patterns (splitmix64's finaliser on x
        xor the finalised y), in Python integers: without the JIT numpy's
        would warn on the wrap-around that the compiled kernel relies on."""
        z = int(x) & _MASK
        w = int(y) & _MASK
        for _ in range(2):
            w = ((w ^ (w >> 30)) * 0xBF58476D1CE4E5B9) & _MASK
            w = ((w ^ (w >> 27)) * 0x94D049BB133111EB) & _MASK
            w ^= w >> 31
            z, w = w, z ^ w
        return w

else:

    @njit(cache=True, inline="always")
    def _mixed(x, y):
        """A 64-bit hash of two 64-bit patterns (splitmix64's finaliser on x
        xor the finalised y); unsigned products wrap around."""
        z = np.uint64(x)
        w = np.uint64(y)
        for _ in range(2):
            w = (w ^ (w >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
            w = (w ^ (w >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
            w ^= w >> np.uint64(31)
            z, w = w, z ^ w
        return w


def shared_positions(X):
    """Mask of the rows of X (n, 2) equal to another row (0.0 equals -0.0)."""
    bits = np.ascontiguousarray(np.asarray(X, dtype=np.float64) + 0.0).view(np.int64)
    return _shared_bits(bits.reshape(-1, 2))


@njit(cache=True)
def _shared_bits(bits):
    """Mask of the rows of ``bits`` (the coordinates' bit patterns, -0.0 made
    0.0) equal to another row: open addressing on a mixed hash, a table at
    most half full, so every probe sequence ends at a free slot."""
    n = bits.shape[0]
    size = 2
    while size < 2 * n:
        size *= 2
    table = np.full(size, -1, np.int64)
    shared = np.zeros(n, np.bool_)
    for i in range(n):
        x, y = bits[i, 0], bits[i, 1]
        slot = np.int64(_mixed(x, y) & np.uint64(size - 1))
        for _ in range(size):
            j = table[slot]
            if j < 0:
                table[slot] = i
                break
            if bits[j, 0] == x and bits[j, 1] == y:  # the first row with (x, y) stays
                shared[i] = True
                shared[j] = True
                break
            slot = (slot + 1) & (size - 1)
    return shared
