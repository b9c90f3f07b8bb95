"""Reproduce the paper's Figs. 3–6 and set bubblemesh against its peers.

    bubblemesh reproduce [--case NAME ...] [--out reports]
    python -m cases.reproduce ...   (the same, plus --no-progress and --report-only)

For each case: bubblemesh §2 (``bubblemesh.generate``, the paper's "Delaunay
mesh") and §2+§3 (``bubblemesh.optimize``, the "optimized mesh"), then every
peer of ``cases.peers`` on the same boundary nodes, tuned to the §2 element
count.  Writes, under ``out``: ``quality.csv`` (one row per case × method),
``meshes/<case>__<method>.vtu`` (every mesh, with its ρ per cell, so any
number can be recomputed), ``figures/*.png`` and the report (``README.md``,
``index.html``).  Everything but timings and the date is deterministic.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import inspect
import json
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

import bubblemesh as bm
import cases as _cases
from bubblemesh.io import write_mesh
from bubblemesh.quality import radius_ratio, summary
from cases import peers

BUBBLEMESH = ("bubblemesh_delaunay", "bubblemesh_optimized")
METHODS = BUBBLEMESH + peers.PEERS
LABELS = {
    "bubblemesh_delaunay": "bubblemesh §2 (Delaunay)",
    "bubblemesh_optimized": "bubblemesh §2+§3 (optimized)",
    "triangle": "Triangle pq30",
    "gmsh_frontal": "Gmsh Frontal-Delaunay",
    "gmsh_delaunay": "Gmsh Delaunay",
    "pymeshlab_remesh": "pymeshlab isotropic remesh",
    "pymeshlab_remesh_free": "pymeshlab remesh, boundary free",
    "laplacian_pymeshlab": f"Laplacian, pymeshlab ({peers.LAPLACIAN_STEPS} steps)",
    "laplacian_uniform": f"Laplacian, plain uniform ({peers.LAPLACIAN_STEPS} steps)",
}
COLUMNS = [
    "case",
    "method",
    "status",
    "elements",
    "nodes",
    "rho_min",
    "rho_mean",
    "rho_median",
    "n_below_0_5",
    "pct_below_0_5",
    "n_below_0_7",
    "pct_below_0_7",
    "min_angle",
    "max_angle",
    "seconds",
    "boundary_shift",
    "boundary_nodes",
    "inverted",
    "input",
    "mesh_file",
    "options",
    "reason",
]
# paper §3.1; read from bubblemesh.optimize, which runs with its defaults here
AMPLIFICATION = inspect.signature(bm.optimize).parameters["amplification"].default


def _say(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def _quiet(message: str) -> None:
    pass


def _warm_up() -> float:
    """Load/compile bubblemesh's kernels so case timings exclude the JIT: twice on a small
    square with a hole (a tiny disk alone left some code paths uncompiled)."""
    from cases.geometry import circle, clockwise, rectangle

    loops = [rectangle(-1.0, -1.0, 1.0, 1.0, 0.125), clockwise(circle((0.0, 0.0), 0.3, 32))]
    t0 = time.perf_counter()
    for _ in range(2):
        bm.mesh(bm.Domain.from_loops(loops))
    return time.perf_counter() - t0


# --------------------------------------------------------------------------- one case


def _row(case, method, **kw):
    row = dict.fromkeys(COLUMNS, None)
    row.update(case=case, method=method, **kw)
    return row


def _timed(function, *args):
    t0 = time.perf_counter()
    result = function(*args)
    return result, time.perf_counter() - t0


def run_case(case, out: Path, *, methods=METHODS):
    """All methods on one case module; returns (rows, figure paths)."""
    from cases import plots

    loops = [np.asarray(lp, dtype=np.float64) for lp in case.loops()]
    boundary = np.vstack(loops)
    rows, meshes = [], {}

    def record(method, points, triangles, seconds, options, mesh=None, input_="boundary nodes"):
        rho = radius_ratio(points, triangles)
        s = summary(points, triangles)
        shift, nb = peers.boundary_shift(boundary, points, triangles)
        fname = f"{case.NAME}__{method}.vtu"
        if mesh is not None:  # node-bubble radii and the boundary flag too
            mesh.write(out / "meshes" / fname)
        else:
            write_mesh(out / "meshes" / fname, points, triangles, cell_data={"radius_ratio": rho})
        meshes[method] = (np.asarray(points)[:, :2], np.asarray(triangles), rho)
        rows.append(_row(
            case.NAME, method, status="ok", elements=int(s["count"]), nodes=int(len(points)),
            rho_min=s["min"], rho_mean=s["mean"], rho_median=s["median"],
            n_below_0_5=int(s["count_below_0_5"]), pct_below_0_5=100.0 * s["frac_below_0_5"],
            n_below_0_7=int(s["count_below_0_7"]), pct_below_0_7=100.0 * s["frac_below_0_7"],
            min_angle=s["min_angle_deg"], max_angle=s["max_angle_deg"], seconds=float(seconds),
            boundary_shift=shift, boundary_nodes=nb,
            inverted=peers._inverted(np.asarray(points)[:, :2], np.asarray(triangles)),
            input=input_, mesh_file=f"meshes/{fname}", options=options, reason="",
        ))  # fmt: skip

    m2 = m3 = None
    try:
        m2, t2 = _timed(bm.generate, bm.Domain.from_loops(loops))
        record("bubblemesh_delaunay", m2.points, m2.triangles, t2,
               f"bubblemesh.generate: {m2.insertions} insertions, "
               f"ΣA_e = {m2.bubble_area:.6g} ≥ A_geo = {m2.domain_area:.6g}", mesh=m2)
        m3, t3 = _timed(bm.optimize, m2)
        record("bubblemesh_optimized", m3.points, m3.triangles, t2 + t3,
               f"bubblemesh.optimize (paper defaults) after generate: "
               f"{m3.stats.get('iterations', '?')} iterations; seconds = generate + optimize "
               f"({t2:.3f} + {t3:.3f})", mesh=m3)
    except Exception as exc:  # a failing case is reported, the others still run
        reason = f"bubblemesh raised {type(exc).__name__}: {exc}"
        rows += [_row(case.NAME, m, status="failed", reason=reason) for m in BUBBLEMESH[len(rows):]]

    for name in (p for p in peers.PEERS if p in methods):
        if m2 is None:
            rows.append(_row(case.NAME, name, status="skipped",
                             reason="no bubblemesh §2 mesh to match or post-process"))
            continue
        p, t, sec, info = peers.run_peer(name, loops, len(m2.triangles),
                                         base=(m2.points, m2.triangles))
        if info["status"] != "ok":
            rows.append(_row(case.NAME, name, status=info["status"], reason=info["reason"]))
            continue
        runs = f"; tuning runs (parameter, elements): {info['runs']}" if "runs" in info else ""
        record(name, p, t, sec, info["options"] + runs,
               input_="bubblemesh §2 mesh" if name in peers.POSTPROCESSORS else "boundary nodes")

    figs = {}
    fig_dir = out / "figures"
    title = getattr(case, "TITLE", case.NAME)
    if m3 is not None:
        figs["panels"] = fig_dir / f"{case.NAME}_panels.png"
        plots.panels(figs["panels"], title,
                     *(dict(points=m.points, triangles=m.triangles, radii=m.radii,
                            rho=meshes[key][2]) for m, key in zip((m2, m3), BUBBLEMESH)),
                     AMPLIFICATION)  # fmt: skip
    order = [m for m in METHODS if m in meshes]
    figs["histograms"] = fig_dir / f"{case.NAME}_histograms.png"
    plots.histograms(figs["histograms"], title, {m: meshes[m][2] for m in order}, LABELS)
    figs["meshes"] = fig_dir / f"{case.NAME}_meshes.png"
    plots.meshes(figs["meshes"], title, {m: meshes[m] for m in order}, LABELS)
    return rows, figs


# --------------------------------------------------------------------------- whole run


def environment() -> dict:
    from importlib import metadata

    versions = {"python": platform.python_version()}
    for pkg in (
        "bubblemesh",
        "numpy",
        "scipy",
        "numba",
        "matplotlib",
        "pandas",
        "meshio",
        "triangle",
        "gmsh",
        "pymeshlab",
        "shapely",
    ):
        try:
            versions[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            versions[pkg] = (
                "not installed" if pkg != "bubblemesh" else "source tree (not installed)"
            )
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return {
        "date": _dt.datetime.now().astimezone().strftime("%Y-%m-%d %H:%M %Z"),
        "platform": platform.platform(),
        "cpu": cpu,
        "cpu_count": os.cpu_count(),
        "versions": versions,
    }


def main(cases=None, out="reports", *, progress=True, methods=METHODS, write_report=True):
    """Run the named cases (default: all of ``cases.ALL``) into ``out``; returns the DataFrame.
    ``progress`` prints what it is doing to stderr, a line per case."""
    import pandas as pd

    from cases import report

    say = _say if progress else _quiet
    t_start = time.perf_counter()
    names = list(_cases.ALL) if not cases else list(cases)
    mods = [_cases.get(n) for n in names]
    out = Path(out)
    (out / "meshes").mkdir(parents=True, exist_ok=True)
    (out / "figures").mkdir(parents=True, exist_ok=True)

    peer_count = sum(1 for p in peers.PEERS if p in methods)
    say(f"reproduce: {len(mods)} case(s), bubblemesh and {peer_count} peers each, into {out}")
    say("loading the numba kernels (the first run compiles them, ~1-2 min)...")
    warm = None
    try:
        warm = _warm_up()
        say(f"numba kernels ready ({warm:.1f} s)")
    except Exception as exc:  # the cases will report their own failures
        say(f"bubblemesh warm-up failed: {type(exc).__name__}: {exc}")

    rows, figs = [], {}
    for i, mod in enumerate(mods, start=1):
        say(f"[{i}/{len(mods)}] {mod.NAME}: meshing ...")
        t0 = time.perf_counter()
        r, figs[mod.NAME] = run_case(mod, out, methods=methods)
        rows += r
        failed = [f"{x['method']} {x['status']}" for x in r if x["status"] != "ok"]
        say(f"[{i}/{len(mods)}] {mod.NAME}: {sum(x['status'] == 'ok' for x in r)} meshes in "
            f"{time.perf_counter() - t0:.1f} s" + (f" ({', '.join(failed)})" if failed else ""))
    df = pd.DataFrame(rows, columns=COLUMNS)
    df.to_csv(out / "quality.csv", index=False, float_format="%.6g")
    meta = environment()
    meta.update(
        cases=names,
        total_seconds=time.perf_counter() - t_start,
        warm_up_seconds=warm,
        laplacian_steps=peers.LAPLACIAN_STEPS,
        amplification=AMPLIFICATION,
    )
    (out / "reproduce.json").write_text(json.dumps(meta, indent=2, default=str) + "\n")
    if write_report:
        report.write(out, df, figs, meta, {n: _cases.get(n) for n in names}, LABELS)
        say(f"report: {out / 'README.md'}, {out / 'index.html'}")
    return df


def rewrite_report(out="reports") -> bool:
    """Rewrite README.md / index.html from the quality.csv, figures and reproduce.json already in
    ``out`` (no meshing), e.g. after a new benchmark run.  False when there is no run to use."""
    import pandas as pd

    from cases import report

    out = Path(out)
    if not (out / "quality.csv").exists() or not (out / "reproduce.json").exists():
        return False
    df = pd.read_csv(out / "quality.csv")
    meta = json.loads((out / "reproduce.json").read_text())
    names = [n for n in dict.fromkeys(df["case"]) if n in _cases.ALL]
    figs = {
        n: {k: out / "figures" / f"{n}_{k}.png" for k in ("panels", "histograms", "meshes")
            if (out / "figures" / f"{n}_{k}.png").exists()}
        for n in names
    }  # fmt: skip
    report.write(out, df, figs, meta, {n: _cases.get(n) for n in names}, LABELS)
    return True


def _cli(argv=None):
    ap = argparse.ArgumentParser(
        prog="python -m cases.reproduce", description=__doc__.split("\n\n")[0]
    )
    ap.add_argument(
        "--case",
        action="append",
        choices=list(_cases.ALL),
        help="case to run (repeatable; default all)",
    )
    ap.add_argument("--out", default="reports", help="output folder (default: reports)")
    ap.add_argument("--no-progress", action="store_true", help="print nothing while running")
    ap.add_argument(
        "--report-only", action="store_true", help="rewrite the report from the files in --out"
    )
    a = ap.parse_args(argv)
    if a.report_only:
        sys.exit(0 if rewrite_report(a.out) else "no quality.csv / reproduce.json to report from")
    df = main(a.case, a.out, progress=not a.no_progress)
    ok = df[df.status == "ok"]
    print(
        ok[["case", "method", "elements", "rho_mean", "pct_below_0_7", "seconds"]].to_string(
            index=False
        )
    )


if __name__ == "__main__":
    _cli()
