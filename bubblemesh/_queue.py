"""The §2 priority queue (paper §2.4 (c)): a 4-ary heap of (D_e, triangle id)
pairs, ordered by key then id, so ties go to the smaller id and runs are
deterministic.

Keys and ids are two arrays: a sift compares keys only, so each level reads
the 4 children's keys from one cache line (``heap_arrays`` aligns them).
Entries are invalidated lazily by the caller (an entry is live while its key
equals its triangle's current density).
"""

import numpy as np
from numba import njit

from .memory import prefetch, unsigned

HEAP_ARITY = 4  # half the depth of a binary heap


@njit(cache=True, inline="always")
def _before(key, ident, other_key, other_ident):
    return key < other_key or (key == other_key and ident < other_ident)


@njit(cache=True)
def heap_push(keys, ids, size, key, ident):
    """Add (key, ident): a hole rises from the end to its place."""
    i = size
    while i > 0:
        parent = (i - 1) // HEAP_ARITY
        p = unsigned(parent)
        if not _before(key, ident, keys[p], ids[p]):
            break
        keys[unsigned(i)] = keys[p]
        ids[unsigned(i)] = ids[p]
        i = parent
    keys[i] = key
    ids[i] = ident
    return size + 1


@njit(cache=True, inline="always")
def _entry_before(keys, ids, a, b):
    """Does heap entry a come before entry b?"""
    ua = unsigned(a)
    ub = unsigned(b)
    return _before(keys[ua], ids[ua], keys[ub], ids[ub])


@njit(cache=True)
def heap_pop(keys, ids, size):
    """Move the smallest pair to ``size - 1`` and restore the heap: the last
    pair sinks from the root through a hole to its place."""
    size -= 1
    top_key = keys[0]
    top_id = ids[0]
    key = keys[size]
    ident = ids[size]
    i = 0
    while True:
        first = HEAP_ARITY * i + 1
        if first >= size:
            break
        # the next level's keys (all 16 grandchildren, at most 3 cache lines)
        # start loading while this level's comparisons wait for theirs
        grand = HEAP_ARITY * first + 1
        if grand < size:
            last = min(grand + HEAP_ARITY * HEAP_ARITY, size) - 1
            prefetch(keys, grand)
            prefetch(keys, (grand + last) // 2)
            prefetch(keys, last)
        prefetch(ids, first)  # read on ties and by the move below
        child = first
        for c in range(first + 1, min(first + HEAP_ARITY, size)):
            if _entry_before(keys, ids, c, child):
                child = c
        u = unsigned(child)
        if not _before(keys[u], ids[u], key, ident):
            break
        keys[unsigned(i)] = keys[u]
        ids[unsigned(i)] = ids[u]
        i = child
    keys[i] = key
    ids[i] = ident
    keys[size] = top_key
    ids[size] = top_id
    return size


def heap_arrays(rows: int, index: type) -> tuple[np.ndarray, np.ndarray]:
    """Zeroed heap keys and ids; keys[1] starts a cache line, so the keys of
    every group of children (4p+1 .. 4p+4) share one."""
    buf = np.zeros(rows + 8)
    skip = (-(buf.ctypes.data + 8) % 64) // 8 if buf.ctypes.data % 8 == 0 else 0
    return buf[skip:skip + rows], np.zeros(rows, index)
