"""The validation and benchmark suite as a library: cases x methods x parameters.

    from bubblemesh import studies
    cases = studies.paper_cases()                    # the paper's Figs. 3-6, as data
    study = studies.Study("mine", list(cases.values()), [
        studies.Method("bubblemesh", "bubblemesh.paper", grid={"max_iterations": [50, 200]}),
        studies.Method("triangle", "triangle"),
        studies.Method.from_function("mine", my_mesher),   # loops -> (points, triangles)
    ])
    run = studies.run_study(study, "out/")           # dask LocalCluster; or scheduler=...
    run.table                                        # one tidy row per cell (pandas)

A *case* (:class:`Case`) is data: boundary loops, a title, metadata.  A *method*
(:class:`Method`) is an adapter with parameters and a grid.  A *study* (:class:`Study`,
or a TOML definition read by :func:`load_study`) crosses them; :func:`run_study` runs
each cell as a dask task and keeps the results (``results.parquet``, ``results.csv``),
computing only the cells not already there.  :func:`render_report` writes a study's
report from its table.  Nothing here is imported by ``import bubblemesh``; dask,
pyarrow and matplotlib are needed only to run studies and draw reports (the
``studies`` extra).
"""

from .case import Case, load_case, load_cases, paper_cases
from .checks import basic_check
from .engine import StudyRun, run_study
from .methods import ADAPTERS, Method, Output, Skipped
from .results import read_results, write_results
from .study import Cell, Study, load_study, run_cell

__all__ = [
    "ADAPTERS",
    "Case",
    "Cell",
    "Method",
    "Output",
    "Skipped",
    "Study",
    "StudyRun",
    "basic_check",
    "load_case",
    "load_cases",
    "load_study",
    "paper_cases",
    "read_results",
    "render_report",
    "run_cell",
    "run_study",
    "write_results",
]


def render_report(study, table, out, run=None):
    """Write ``out/README.md`` and ``out/index.html`` (and figures) from a results table."""
    from .report import render

    return render(study, table, out, run)
