"""Spatial order: keys along a Hilbert curve and a stable radix argsort.

Used for the insertion order of every triangulation (each new point lands next
to the previous one, so point location is O(1) on average) and for the
renumbering of the §2 mesh.
"""

import numpy as np
from numba import njit, prange

SMALL = 4096  # fewer keys are sorted by numpy (the radix sort's 65536 bins cost more)


@njit(cache=True, parallel=True)
def _hilbert_keys(P, bits):
    n = P.shape[0]
    xmin = P[:, 0].min()
    ymin = P[:, 1].min()
    span = max(P[:, 0].max() - xmin, P[:, 1].max() - ymin)
    if span == 0.0:
        span = 1.0
    side = (1 << bits) - 1
    keys = np.empty(n, np.int64)
    for k in prange(n):
        x = int((P[k, 0] - xmin) / span * side)
        y = int((P[k, 1] - ymin) / span * side)
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
        keys[k] = d
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
    keys = _hilbert_keys(np.ascontiguousarray(points, dtype=np.float64), 16)
    if len(keys) < SMALL:  # the same order: a stable sort of the same keys
        return np.argsort(keys, kind="stable")
    return _radix_argsort(keys, 2)  # keys < 4**16
