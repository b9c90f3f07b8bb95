"""The thread pool of the parallel kernels (no paper equation: speed only).

numba's own ``workqueue`` layer, unless the user chose a layer
(``NUMBA_THREADING_LAYER`` or ``NUMBA_THREADING_LAYER_PRIORITY``).  Results
do not depend on the choice: every kernel gives the same bits on any number
of threads.

Measured on 2 cores, for the record.  The §3 iterations (paper §3.2-3.4,
eq. 7-9) start about 400 parallel loops per call at the default 200
iterations.  workqueue starts one in ~90 us; GNU OpenMP (``omp``) in ~2 us
spinning or ~50 us with ``OMP_WAIT_POLICY=passive``.  A 100k-element optimize
took 0.45-0.58 s with omp/passive against 0.53-0.64 s with workqueue.  Two
runs side by side, as tox runs its envs: omp spinning 1.9-2.0 s, workqueue
1.04 s, omp passive 0.94-0.96 s.  omp is not the default all the same: GNU
OpenMP cannot survive ``fork()``, and numba then terminates every forked
child that runs a parallel loop.  A ``multiprocessing`` pool (fork is its
default on Linux) created after one mesh in the parent then waits forever
for its dead workers (verification/test_threads.py).  Users who never fork
can set ``NUMBA_THREADING_LAYER=omp`` and ``OMP_WAIT_POLICY=passive``.
"""

import os

import numba

if not {"NUMBA_THREADING_LAYER", "NUMBA_THREADING_LAYER_PRIORITY"} & set(os.environ):
    numba.config.THREADING_LAYER = "workqueue"  # type: ignore[attr-defined]
