"""Reproduce the paper's Figs. 3–6 and set bubblemesh against its peers: one study, one report.

    bubblemesh reproduce [--case NAME ...] [--cases-dir DIR] [--scheduler ADDRESS] [--out reports]
    python -m bubblemesh.studies.reproduce ...   (the same, plus --report-only)

The study is the shipped definition ``paper.toml``: for each case, bubblemesh §2
(``bubblemesh.generate``, the paper's "Delaunay mesh") and §2+§3 (``bubblemesh.optimize``
with the paper's defaults, the "optimized mesh"), then every peer of
:mod:`bubblemesh.studies.peers` on the same boundary nodes, tuned to the §2 element count.
Writes, under ``out``: ``results.parquet`` / ``results.csv`` (one row per case × method),
``meshes/<case>__<method>.vtu`` (every mesh, with its ρ per cell), ``figures/*.png`` and the
report (``README.md``, ``index.html``).  Everything but timings and the date is
deterministic; a second run reuses the rows already in ``out``.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path

from .case import bundled_folder
from .engine import run_study
from .report import render
from .results import read_results
from .study import Study, load_study

__all__ = ["command", "main", "paper_study", "rewrite_report"]


def paper_study(cases: Sequence[str] | None = None, cases_dir: str | Path | None = None) -> Study:
    """The paper study (``paper.toml``) on the named cases (default all), from ``cases_dir``
    (default: the paper's four)."""
    return load_study(bundled_folder() / "paper.toml", cases_dir=cases_dir, only_cases=cases)


def command(study: Study, cases: Sequence[str] | None, cases_dir, out) -> str:
    """The command line that regenerates this report."""
    only = "".join(f" --case {n}" for n in cases or ())
    where = f" --cases-dir {cases_dir}" if cases_dir is not None else ""
    return f"bubblemesh reproduce{only}{where} --out {_folder(out)}"


def _folder(out) -> str:
    text = str(out)
    return text if text.endswith("/") else text + "/"


def main(cases: Sequence[str] | None = None, out: str | Path = "reports", *,
         cases_dir: str | Path | None = None, scheduler: str | None = None,
         progress: bool = True, retry_failed: bool = False):
    """Run the paper study into ``out`` and write its report; returns the results table."""
    study = paper_study(cases, cases_dir)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    say = (lambda m: print(m, file=sys.stderr, flush=True)) if progress else (lambda m: None)
    say(f"reproduce: {len(study.cases)} case(s) × {len(study.methods)} methods "
        f"(bubblemesh §2, §2+§3, the default mesher and {len(study.methods) - 3} peers) into {out}")
    run = run_study(study, out, scheduler=scheduler, progress=progress,
                    retry_failed=retry_failed, say=say)
    if cases is None and cases_dir is None:  # the whole paper: the default mesher against Gmsh
        say("reproduce: the default mesher against Gmsh and Triangle (quality_vs_gmsh.csv)")
        _quality_vs_gmsh(out)
    render(study, run.table, out, run, command(study, cases, cases_dir, out))
    bad = run.table[run.table["status"] != "ok"]
    for r in bad.itertuples():
        say(f"{r.case} {r.method}: {r.status}: {r.reason}")
    say(f"report: {out / 'README.md'}, {out / 'index.html'}")
    return run.table


def _quality_vs_gmsh(out: Path) -> None:
    """quality_vs_gmsh.csv into ``out`` (bubblemesh.studies.quality), every
    case with the 100k-element disk, quietly; skipped without Gmsh or Triangle."""
    import contextlib
    import io

    from . import quality

    try:
        import gmsh  # noqa: F401
        import triangle  # noqa: F401
    except ImportError:
        return
    with contextlib.redirect_stdout(io.StringIO()):
        quality.quality_table(None, out, big=True)


def rewrite_report(out: str | Path = "reports") -> bool:
    """Rewrite README.md / index.html from the results, meshes and run record already in
    ``out`` (no meshing), e.g. after a new benchmark run.  False when there is no run."""
    out = Path(out)
    record = out / "paper.run.json"
    table = read_results(out)
    if table is None or not record.exists():
        return False
    meta = json.loads(record.read_text())
    study = load_study(meta.get("definition") or bundled_folder() / "paper.toml",
                       cases_dir=meta.get("cases_dir"), only_cases=meta.get("cases"))
    version = meta.get("versions", {}).get("bubblemesh")  # the code that made the rows
    keys = {c.key for c in study.cells(version)}
    rows = table[table["key"].astype(str).isin(keys)].reset_index(drop=True)
    if rows.empty:
        return False
    render(study, rows, out, meta=meta)
    return True


def _cli(argv=None):
    ap = argparse.ArgumentParser(prog="python -m bubblemesh.studies.reproduce",
                                 description=(__doc__ or "").split("\n\n")[0])
    ap.add_argument("--case", action="append", help="case to run (repeatable; default all)")
    ap.add_argument("--cases-dir", help="folder of case files (default: the paper's)")
    ap.add_argument("--scheduler", help="dask scheduler address (default: a local cluster)")
    ap.add_argument("--out", default="reports", help="output folder (default: reports)")
    ap.add_argument("--no-progress", action="store_true", help="print nothing while running")
    ap.add_argument("--report-only", action="store_true",
                    help="rewrite the report from the files in --out")
    a = ap.parse_args(argv)
    if a.report_only:
        sys.exit(0 if rewrite_report(a.out) else "no results / paper.run.json to report from")
    df = main(a.case, a.out, cases_dir=a.cases_dir, scheduler=a.scheduler,
              progress=not a.no_progress)
    ok = df[df.status == "ok"]
    print(ok[["case", "method", "elements", "rho_mean", "pct_below_0_7", "seconds"]]
          .to_string(index=False))


if __name__ == "__main__":
    _cli()
