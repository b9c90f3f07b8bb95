"""The thread pool of the parallel kernels (no paper equation: speed only).

numba's ``tbb`` layer when Intel TBB is installed (the ``fast`` extra), its
own ``workqueue`` layer otherwise; never ``omp``.  A user's own choice
(``NUMBA_THREADING_LAYER`` or ``NUMBA_THREADING_LAYER_PRIORITY``) is left
alone.  Results do not depend on the layer: every kernel gives the same bits
on any number of threads (verification/test_threads.py).

``omp`` is never chosen because it cannot survive ``fork()``: numba then
terminates every forked child that runs a parallel loop, and a
``multiprocessing`` pool (fork is its default on Linux) created after one mesh
in the parent waits forever for its dead workers; tbb and workqueue children
mesh normally.  tbb starts a parallel loop far faster than workqueue, which matters to the
§3 iterations (docs/performance.md has the figures).

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
