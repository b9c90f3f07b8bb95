"""Spatial order: keys along a Hilbert curve and a stable radix argsort.

Used for the insertion order of every triangulation (each new point lands next
to the previous one, so point location is O(1) on average) and for the
renumbering of the §2 mesh.
"""

import numpy as np
from numba import njit, prange

_BLOCK = 1024  # keys a thread computes in turn
SMALL = 4096  # fewer keys are sorted by numpy (the radix sort's 65536 bins cost more)


@njit(cache=True, inline="always")
def _frame(P):
    xmin = P[:, 0].min()
    ymin = P[:, 1].min()
    span = max(P[:, 0].max() - xmin, P[:, 1].max() - ymin)
    return xmin, ymin, span if span > 0.0 else 1.0


@njit(cache=True, inline="always")
def _hilbert_key(px, py, xmin, ymin, span, bits):
    side = (1 << bits) - 1
    x = int((px - xmin) / span * side)
    y = int((py - ymin) / span * side)
    d = 0
    s = 1 << (bits - 1)
    while s > 0:
        rx = 1 if (x & s) > 0 else 0
        ry = 1 if (y & s) > 0 else 0
        d += s * s * ((3 * rx) ^ ry)
        if ry == 0:
            if rx == 1:
                x = side - x
                y = side - y
            x, y = y, x
        s >>= 1
    return d


@njit(cache=True, inline="always")
def _fill(P, bits, frame, keys, lo, hi):
    for k in range(lo, hi):
        keys[k] = _hilbert_key(P[k, 0], P[k, 1], frame[0], frame[1], frame[2], bits)


@njit(cache=True, parallel=True)
def _hilbert_keys(P, bits):
    keys = np.empty(P.shape[0], np.int64)
    frame = _frame(P)
    for block in prange((P.shape[0] + _BLOCK - 1) // _BLOCK):
        _fill(P, bits, frame, keys, block * _BLOCK, min(P.shape[0], (block + 1) * _BLOCK))
    return keys


@njit(cache=True)
def _hilbert_keys_serial(P, bits):
    """:func:`_hilbert_keys` in one thread (starting the pool costs more for a
    patch's few points)."""
    keys = np.empty(P.shape[0], np.int64)
    _fill(P, bits, _frame(P), keys, 0, P.shape[0])
    return keys


@njit(cache=True)
def _radix_argsort(keys, digits):
    """Stable argsort of non-negative keys below 2**(16 digits): least
    significant 16 bits first (what np.argsort(kind="stable") gives, in O(n))."""
    n = keys.shape[0]
    order = np.arange(n)
    spare = np.empty(n, np.int64)
    count = np.empty(65537, np.int64)
    for d in range(digits):
        shift = 16 * d
        count[:] = 0
        for k in range(n):
            count[((keys[order[k]] >> shift) & 0xFFFF) + 1] += 1
        for b in range(65536):
            count[b + 1] += count[b]
        for k in range(n):
            digit = (keys[order[k]] >> shift) & 0xFFFF
            spare[count[digit]] = order[k]
            count[digit] += 1
        order, spare = spare, order
    return order


def hilbert_order(points: np.ndarray) -> np.ndarray:
    """Insertion order along a Hilbert curve: each new point lands next to the
    previous one, so the walking point location takes O(1) steps on average."""
    if len(points) == 0:
        return np.zeros(0, np.int64)
    P = np.ascontiguousarray(points, dtype=np.float64)
    if len(P) < SMALL:  # the same order: a stable sort of the same keys
        return np.argsort(_hilbert_keys_serial(P, 16), kind="stable")
    keys = _hilbert_keys(P, 16)
    return _radix_argsort(keys, 2)  # keys < 4**16
