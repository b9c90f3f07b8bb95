"""The parallel kernels: same bits on any number of threads and in any
threading layer, and safe to fork.

- generate (its parallel renumbering), optimize (the §3 iterations, the
  3-ring blocks) and bm.mesh, with frontal and with centroid insertion (its
  colour-by-colour smoothing sweeps) give the
  same bits with 1 and 2 threads (results identical to the serial run), and
  with tbb (the ``fast`` extra) as with numba's workqueue;
- BLAS's thread count (SLSQP's in the joint moves) changes no bit either;
- after a mesh in the parent, a forked multiprocessing pool still meshes
  (GNU OpenMP, numba's omp layer, kills such children and the pool waits
  forever: the test has a timeout instead).
"""

from __future__ import annotations

import multiprocessing
import os
import subprocess
import sys

import numpy as np
import pytest

import bubblemesh as bm


def _disk(n):
    angle = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return bm.Domain.from_loops([np.column_stack([np.cos(angle), np.sin(angle)])])


def _meshes():
    """The generated and the optimised mesh of a disk big enough (> 2048
    nodes) to cut the 3-ring blocks, as named arrays."""
    mesh = bm.generate(_disk(200))
    assert len(mesh.points) > 2048, "too small to cut the ring blocks"
    optimized = bm.optimize(mesh, max_iterations=40)
    default = bm.mesh(_disk(200), size=0.02, max_iterations=40)  # the parallel sweeps too
    assert default.generation.insertion == "frontal"
    centroid = bm.mesh(_disk(200), size=0.02, max_iterations=40, insertion="centroid")
    return {f"{stage}_{name}": getattr(m, name)
            for stage, m in (("generate", mesh), ("optimize", optimized), ("mesh", default),
                             ("mesh_centroid", centroid))
            for name in ("points", "triangles", "neighbors", "radii")}


def _assert_same_bits(one, two):
    for key in one:
        assert np.array_equal(one[key], two[key]), key


def test_thread_count_changes_no_bit():
    """Every node reads the previous iterate, so how the loops are cut
    between threads must not show in any bit; nor may BLAS's thread count
    (SLSQP's LAPACK calls in the joint moves give other bits on other
    counts)."""
    import numba
    from threadpoolctl import threadpool_limits

    if numba.config.DISABLE_JIT or numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("needs the JIT and at least 2 threads")
    results = {}
    default = numba.get_num_threads()
    try:
        for threads in (1, 2):
            numba.set_num_threads(threads)
            with threadpool_limits(limits=threads, user_api="blas"):
                results[threads] = _meshes()
    finally:
        numba.set_num_threads(default)
    _assert_same_bits(results[1], results[2])


def test_threading_layer_changes_no_bit(tmp_path):
    """The layer bubblemesh picked here (tbb, with the fast extra) against
    numba's workqueue in a child process: the same bits."""
    import numba

    if numba.config.DISABLE_JIT:
        pytest.skip("needs the JIT")
    here = _meshes()
    if numba.threading_layer() == "workqueue":
        pytest.skip("this environment runs workqueue itself (no tbb): nothing to compare")
    out = tmp_path / "workqueue.npz"
    code = (f"import sys; sys.path.insert(0, {os.path.dirname(__file__)!r}); "
            "import numba, numpy as np, test_threads as t; m = t._meshes(); "
            f"assert numba.threading_layer() == 'workqueue'; np.savez({str(out)!r}, **m)")
    subprocess.run([sys.executable, "-c", code], check=True, timeout=600,
                   env=dict(os.environ, NUMBA_THREADING_LAYER="workqueue"))
    with np.load(out) as child:
        _assert_same_bits(here, child)


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
