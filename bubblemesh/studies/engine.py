"""Running a study on dask.distributed: a cell is a task, results stream back as they finish.

* No scheduler given (and no ``BUBBLEMESH_SCHEDULER``): a ``LocalCluster`` of worker
  processes on this machine (2 by default, 1 thread each), started and stopped here.
* ``scheduler="tcp://HOST:PORT"``: the same study on an existing cluster.
* ``scheduler="inline"``: every cell in this process, one after another (no dask).

Cells already in ``out``'s results (same key: case, method, parameters, bubblemesh
version) are not computed again; the rest are submitted, collected with ``as_completed``
under a tqdm bar and written to the results table as they come.  A timed cell asks for
the worker resource ``timing`` (1 per worker on the local cluster) when every worker
offers it, and holds a per-process lock in any case: two timed cells never run at once
on one worker.
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .results import frame, read_results, write_results
from .study import Cell, Study, run_cell

__all__ = ["StudyRun", "run_study", "SCHEDULER_ENV", "warm_up"]

SCHEDULER_ENV = "BUBBLEMESH_SCHEDULER"
TIMING = "timing"  # the worker resource a timed cell takes
WRITE_EVERY = 20.0  # seconds between checkpoints of the results table


@dataclass
class StudyRun:
    """What ``run_study`` did: the study's rows (cell order) and how they were made."""

    table: Any
    computed: int
    reused: int
    where: str
    workers: int
    timing: str
    seconds: float
    warm_up_seconds: float | None = None
    files: list[Path] = field(default_factory=list)


def warm_up() -> float:
    """Load (first time: compile) bubblemesh's numba kernels: paper mode twice on a small
    square with a hole (a tiny disk alone left some code paths cold), then ``bubblemesh.mesh``
    with its defaults.  Returns the seconds taken: 0 where numba is off (NUMBA_DISABLE_JIT),
    with nothing to compile and the kernels minutes slower as plain Python."""
    import numba

    import bubblemesh as bm

    if numba.config.DISABLE_JIT:  # type: ignore[attr-defined]
        return 0.0

    from .geometry import circle, clockwise, rectangle

    loops = [rectangle(-1.0, -1.0, 1.0, 1.0, 0.125), clockwise(circle((0.0, 0.0), 0.3, 32))]
    t0 = time.perf_counter()
    domain = bm.Domain.from_loops(loops)
    for _ in range(2):
        bm.optimize(bm.generate(domain))
    bm.mesh(domain)
    return time.perf_counter() - t0


def leave_without_native_destructors() -> None:
    """Make this process, a worker of a local cluster started here, end at its
    exit with its standard streams flushed and ``os._exit(0)``: neither the
    exit handlers registered before this one (a worker being closed has
    nothing left to save) nor native libraries' destructors run.  Gmsh's
    have aborted workers at exit (glibc's "malloc_consolidate(): unaligned
    fastbin chunk detected"), after all their cells were returned."""
    import atexit

    def leave() -> None:
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except (OSError, ValueError):  # a closed or gone stream has nothing to say
                pass
        os._exit(0)

    atexit.register(leave)


def _quiet(message: str) -> None:
    pass


def _say(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def run_study(study: Study, out: str | Path | None = None, *, scheduler: str | None = None,
              workers: int = 2, progress: bool = True, retry_failed: bool = False,
              say: Callable[[str], None] | None = None, timeout: float = 60.0) -> StudyRun:
    """Run the cells of ``study`` not yet in ``out``'s results; returns a :class:`StudyRun`.

    ``out`` gets ``results.parquet`` / ``results.csv`` (every row it holds, this study's
    and others') and, with ``study.keep_meshes``, ``meshes/*.vtu``.  ``retry_failed``
    computes failed and skipped cells again.  ``timeout`` bounds connecting to a scheduler.
    """
    say = say or (_say if progress else _quiet)
    t_start = time.perf_counter()
    cells = study.cells()
    old = read_results(out) if out is not None else None
    done = _done_keys(old, retry_failed)
    todo = [c for c in cells if c.key not in done]
    address = scheduler if scheduler is not None else os.environ.get(SCHEDULER_ENV) or None
    say(f"{study.name}: {len(cells)} cells, {len(cells) - len(todo)} already in the results, "
        f"{len(todo)} to compute")
    rows: dict[str, dict] = {}
    info: dict[str, Any] = dict(where="nothing to compute", workers=0, timing="", warm=None)
    if todo:
        sink = _Sink(out, old, study, rows)
        if address == "inline":
            info = _run_inline(todo, study, sink, progress, say)
        else:
            info = _run_dask(todo, study, sink, address, workers, progress, say, timeout)
        sink.flush()
    table = _table(study, cells, old, rows)
    files = [] if out is None else sorted(Path(out).glob("results.*"))
    return StudyRun(table, len(todo), len(cells) - len(todo), info["where"], info["workers"],
                    info["timing"], time.perf_counter() - t_start, info["warm"], files)


def _done_keys(old, retry_failed: bool) -> set[str]:
    if old is None or old.empty:
        return set()
    keep = old if not retry_failed else old[old["status"] == "ok"]
    return set(keep["key"].astype(str))


def _table(study: Study, cells: list[Cell], old, rows: dict[str, dict]):
    """This study's rows in cell order: new rows, else the stored ones."""
    import pandas as pd

    stored = {}
    if old is not None and not old.empty:
        stored = {str(r["key"]): r for r in old.to_dict("records")}
    picked = [rows.get(c.key) or stored.get(c.key) for c in cells]
    table = frame([r for r in picked if r is not None])
    return table.reset_index(drop=True) if isinstance(table, pd.DataFrame) else table


class _Sink:
    """Collects rows (and meshes) as they arrive; checkpoints the results table."""

    def __init__(self, out, old, study: Study, rows: dict[str, dict]):
        self.out = None if out is None else Path(out)
        self.old, self.study, self.rows = old, study, rows
        self.order = {c.key: i for i, c in enumerate(study.cells())}
        self.last = time.monotonic()

    def add(self, cell: Cell, result: dict[str, Any]) -> None:
        row = result["row"]
        if self.out is not None and result.get("mesh") is not None:
            row["mesh_file"] = _write_mesh(self.out, cell, *result["mesh"])
        self.rows[cell.key] = row
        if time.monotonic() - self.last > WRITE_EVERY:
            self.flush()

    def flush(self) -> None:
        if self.out is None:
            return
        import pandas as pd

        # the study's cell order, not the order the workers finished in: the same file every run
        keys = sorted(self.rows, key=lambda k: self.order.get(k, len(self.order)))
        new = frame([self.rows[k] for k in keys])
        if self.old is not None and not self.old.empty:
            keys = self.old["key"].astype(str)  # other studies' rows, and this one's current cells
            kept = self.old[~keys.isin(self.rows) & ((self.old["study"] != self.study.name)
                                                     | keys.isin(self.order))]
            new = frame(pd.concat([kept, new], ignore_index=True).to_dict("records"))
        write_results(new, self.out)
        self.last = time.monotonic()


def mesh_name(cell: Cell) -> str:
    """``meshes/<case>__<method>[__<param>-<value>...].vtu``."""
    grid = [k for k in cell.method.grid]
    tail = "".join(f"__{k}-{cell.params[k]}" for k in grid)
    return f"meshes/{cell.case.name}__{cell.method.name}{tail}.vtu"


def _write_mesh(out: Path, cell: Cell, points, triangles, radii) -> str:
    import numpy as np

    from bubblemesh.io import write_mesh
    from bubblemesh.quality import radius_ratio

    name = mesh_name(cell)
    (out / "meshes").mkdir(parents=True, exist_ok=True)
    point_data = {}
    if radii is not None:  # a bubblemesh Mesh: node-bubble radii, the boundary nodes first
        boundary = np.zeros(len(points), np.int64)
        boundary[: len(cell.case.boundary)] = 1
        point_data = {"radius": radii, "boundary": boundary}
    write_mesh(out / name, np.asarray(points), np.asarray(triangles), point_data=point_data,
               cell_data={"radius_ratio": radius_ratio(points, triangles)})
    return name


def _failed(cell: Cell, error: BaseException) -> dict[str, Any]:
    """The row of a cell whose task itself failed (a worker died, a result did not arrive)."""
    return {"row": dict(study=cell.study, key=cell.key, case=cell.case.name,
                        method=cell.method.name, adapter=cell.method.reference(),
                        status="failed", reason=f"{type(error).__name__}: {error}",
                        **{f"param_{k}": v for k, v in cell.params.items()}), "mesh": None}


def _bar(total: int, progress: bool, study: Study):
    from tqdm import tqdm

    return tqdm(total=total, desc=study.name, unit="cell", disable=not progress,
                file=sys.stderr, dynamic_ncols=True)


def _run_inline(todo, study, sink, progress, say) -> dict[str, Any]:
    say("loading the numba kernels (the first run compiles them, ~1-2 min) ...")
    warm = warm_up()
    say(f"numba kernels ready ({warm:.1f} s); meshing in this process, one cell at a time")
    with _bar(len(todo), progress, study) as bar:
        for cell in todo:
            sink.add(cell, run_cell(cell, study.verify, study.keep_meshes))
            bar.update()
    return dict(where="this process, one cell at a time", workers=1, warm=warm,
                timing="Timed cells ran one at a time in a single process.")


def _client(address, workers, timeout, say):
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise ImportError("running a study needs dask.distributed: "
                          "pip install 'bubblemesh[studies]'") from None
    if address:
        say(f"connecting to the dask scheduler at {address} ...")
        client = Client(address, timeout=timeout)
        return client, None, f"the dask cluster at {address}"
    import logging

    try:
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                               resources={TIMING: 1}, host="127.0.0.1", dashboard_address=None,
                               # no dashboard; its health endpoints on a free loopback port
                               scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
                               silence_logs=logging.CRITICAL)  # shutdown races are not errors
    except Exception as error:  # most often a script that starts a study unguarded
        raise RuntimeError(
            f"the local dask cluster did not start ({type(error).__name__}: {error}); each "
            "worker process imports the main script, so a script that runs a study must do so "
            "under `if __name__ == '__main__':` (or pass scheduler='inline')") from error
    return Client(cluster), cluster, "a local dask cluster on this machine"


def _run_dask(todo, study, sink, address, workers, progress, say, timeout) -> dict[str, Any]:
    from distributed import as_completed

    say("loading the numba kernels here (the first run compiles them, ~1-2 min) ...")
    warm = warm_up()  # fills the on-disk numba cache the local workers then load
    client, cluster, where = _client(address, workers, timeout, say)
    try:
        info = client.scheduler_info()
        if not info["workers"]:
            client.wait_for_workers(1, timeout=timeout)
            info = client.scheduler_info()
        found = info["workers"].values()
        threads = sum(int(w.get("nthreads", 1)) for w in found)
        say(f"{where}: {len(found)} workers, {threads} threads; loading the numba kernels "
            "on each ...")
        client.run(warm_up)
        if cluster is not None:
            client.run(leave_without_native_destructors)
        with_resource = all(w.get("resources", {}).get(TIMING, 0) >= 1 for w in found)
        timing = _timing_note(len(found), threads, with_resource)
        futures = {}
        for cell in todo:
            resources = {TIMING: 1} if cell.method.timed and with_resource else None
            future = client.submit(run_cell, cell, study.verify, study.keep_meshes,
                                   key=f"cell-{cell.key}", pure=False, resources=resources)
            futures[future] = cell
        with _bar(len(todo), progress, study) as bar:
            for future in as_completed(list(futures)):
                cell = futures[future]
                try:
                    result = future.result()
                except Exception as error:  # the task, not the cell, failed
                    result = _failed(cell, error)
                sink.add(cell, result)
                future.release()
                bar.update()
        return dict(where=where, workers=len(found), timing=timing, warm=warm)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def _timing_note(workers: int, threads: int, with_resource: bool) -> str:
    how = ("each timed cell took the worker resource 'timing', of which each worker has 1"
           if with_resource else "each timed cell held its worker process's timing lock")
    return (f"Cells ran as tasks on {workers} dask worker processes ({threads} threads in "
            f"all); {how}, so no two timed cells ran at once on one worker. Workers share "
            "the machine, so timings are comparable in order of magnitude only.")
