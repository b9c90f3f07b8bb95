"""The thread pool of the parallel kernels (no paper equation: speed only).

numba's ``tbb`` layer when Intel TBB is installed (the ``fast`` extra), its
own ``workqueue`` layer otherwise; never ``omp``.  A user's own choice
(``NUMBA_THREADING_LAYER`` or ``NUMBA_THREADING_LAYER_PRIORITY``) is left
alone.  Results do not depend on the layer: every kernel gives the same bits
on any number of threads (verification/test_threads.py).

Measured on 2 cores, for the record.  The §3 iterations (paper §3.2-3.4,
eq. 7-9) start about 400 parallel loops per call at the default 200
iterations.

- Starting one loop: workqueue ~95 us, tbb ~3 us, GNU OpenMP (``omp``) ~2 us
  spinning or ~50 us with ``OMP_WAIT_POLICY=passive``.
- 100k-element optimize, three alternating processes each: tbb 0.46-0.51 s,
  workqueue 0.58-0.90 s (min of 6 calls).  1M: tbb 5.5-6.0 s, workqueue
  6.9-8.1 s (TBB's work stealing also evens out the uneven per-node work).
- Two 100k runs side by side, as tox runs its envs: tbb 0.95-0.98 s,
  workqueue 1.05-1.10 s; omp spinning 1.9-2.0 s, omp passive 0.94-0.96 s.
- Fork: GNU OpenMP cannot survive ``fork()``; numba then terminates every
  forked child that runs a parallel loop, and a ``multiprocessing`` pool
  (fork is its default on Linux) created after one mesh in the parent waits
  forever for its dead workers.  tbb and workqueue children mesh normally.

pip's ``tbb`` wheel puts ``libtbb.so.12`` in ``<prefix>/lib``, which the
dynamic loader does not search in a virtual environment: numba's tbb layer
then fails to import and numba quietly falls back.  Loading the library by
its path first lets numba find it.
"""

import ctypes
import os
import site
import sys

import numba


def _load_pip_tbb():
    """Load the libtbb of a pip-installed ``tbb`` (Linux), if there is one."""
    if not sys.platform.startswith("linux"):
        return
    for prefix in (sys.prefix, site.getuserbase()):
        path = os.path.join(prefix, "lib", "libtbb.so.12")
        if os.path.exists(path):
            try:
                ctypes.CDLL(path, mode=ctypes.RTLD_GLOBAL)
                return
            except OSError:
                continue


if not {"NUMBA_THREADING_LAYER", "NUMBA_THREADING_LAYER_PRIORITY"} & set(os.environ):
    _load_pip_tbb()
    # numba tries these in order at the first parallel loop (the list must name
    # all three); workqueue always loads, so omp is never reached
    numba.config.THREADING_LAYER_PRIORITY = ["tbb", "workqueue", "omp"]  # type: ignore[attr-defined]
    numba.config.THREADING_LAYER = "default"  # type: ignore[attr-defined]
