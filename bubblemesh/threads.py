"""The thread pool of the parallel kernels (no paper equation: speed only).

The §3 iterations (paper §3.2-3.4, eq. 7-9) run two parallel loops per
iteration, about 400 per call at the default 200 iterations, so the cost of
starting one matters at 100,000 elements.  Measured on 2 cores: numba's own
``workqueue`` layer starts a loop in ~90 us, GNU OpenMP (``omp``) in ~2 us
spinning, ~50 us sleeping; a 100k-element optimize took 0.45-0.58 s with omp
against 0.53-0.63 s with workqueue.

OpenMP threads spin while they wait by default, and on a busy machine (two
runs side by side, as tox runs its envs) spinning made each run 2x slower:
1.9-2.0 s against 1.04 s for workqueue.  Waiting passively, they were the
fastest there as well (0.94-0.96 s).  So: the omp layer with
``OMP_WAIT_POLICY=passive``, and workqueue where libgomp is missing.  A layer,
priority or wait policy the user set in the environment is kept.  Results do
not depend on any of this: the kernels give the same bits on any number of
threads.
"""

import os

import numba

if not {"NUMBA_THREADING_LAYER", "NUMBA_THREADING_LAYER_PRIORITY"} & set(os.environ):
    numba.config.THREADING_LAYER_PRIORITY = ["omp", "workqueue", "tbb"]  # type: ignore[attr-defined]
# read by libgomp when numba loads it, at the first parallel loop
os.environ.setdefault("OMP_WAIT_POLICY", "passive")
