"""The parallel kernels: same bits on any number of threads, and safe to fork.

- generate (its parallel renumbering) and optimize (the §3 iterations, the
  3-ring blocks) give the same bits with 1 and 2 threads ("results identical
  to the serial run", issue 6);
- after a mesh in the parent, a forked multiprocessing pool still meshes
  (GNU OpenMP, numba's omp layer, kills such children and the pool waits
  forever: the test has a timeout instead).
"""

from __future__ import annotations

import multiprocessing
import sys

import numpy as np
import pytest

import bubblemesh as bm


def _disk(n):
    angle = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return bm.Domain.from_loops([np.column_stack([np.cos(angle), np.sin(angle)])])


def test_thread_count_changes_no_bit():
    """Every node reads the previous iterate, so how the loops are cut
    between threads must not show in any bit."""
    import numba

    if numba.config.DISABLE_JIT or numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("needs the JIT and at least 2 threads")
    dom = _disk(200)
    results = {}
    default = numba.get_num_threads()
    try:
        for threads in (1, 2):
            numba.set_num_threads(threads)
            mesh = bm.generate(dom)
            results[threads] = (mesh, bm.optimize(mesh, max_iterations=40))
    finally:
        numba.set_num_threads(default)
    assert len(results[1][0].points) > 2048, "too small to cut the ring blocks"
    for stage in (0, 1):
        for name in ("points", "triangles", "neighbors", "radii"):
            one, two = (getattr(results[t][stage], name) for t in (1, 2))
            assert np.array_equal(one, two), f"{('generate', 'optimize')[stage]}: {name}"


def _triangle_count(n):
    return len(bm.optimize(bm.generate(_disk(n))).triangles)


@pytest.mark.skipif(sys.platform == "win32", reason="no fork on Windows")
def test_forked_pool_after_a_mesh_in_the_parent():
    expected = [_triangle_count(n) for n in (40, 48)]  # the parent's pool is now running
    with multiprocessing.get_context("fork").Pool(2) as pool:
        result = pool.map_async(_triangle_count, [40, 48])
        try:
            counts = result.get(timeout=120)
        except multiprocessing.TimeoutError:
            pytest.fail("the forked workers never answered (killed by the thread pool?)")
    assert counts == expected
