"""Verlet lists over the fixed ring sets (§3.3; not in the paper, the result is
the same): each iteration scans only the ring nodes within (1 + skin)(r_i + r_j),
and a list is rebuilt before any node can have moved or grown past 0.9 skin r_i,
so no overlapping pair is missed and every sum keeps its terms in ring order."""

import numpy as np
from numba import njit, prange

from .memory import unsigned


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
def outgrew(X, R, X0, R0, i, skin):
    """Has node i used up its share of the skin since the lists were built?"""
    dx = X[i, 0] - X0[i, 0]
    dy = X[i, 1] - X0[i, 1]
    # |dx, dy| + growth > share, without the square root
    room = 0.9 * skin * R0[i] - max(0.0, R[i] - R0[i])
    return room < 0.0 or dx * dx + dy * dy > room * room


class VerletLists:
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
