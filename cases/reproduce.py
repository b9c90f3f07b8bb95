"""Reproduce the paper's Figs. 3–6 and set bubblemesh against its peers.

    python -m cases.reproduce [--case NAME ...] [--out reports]

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
import json
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

import cases as _cases
from cases import metrics, peers

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
AMPLIFICATION = 1.7  # paper §3.1, bubblemesh.optimize's default


# --------------------------------------------------------------------------- bubblemesh access


def _bubblemesh():
    """(module, None) when bubblemesh's Domain/generate/optimize exist, else (None, reason)."""
    try:
        import bubblemesh as bm
    except Exception as exc:
        return None, f"bubblemesh not importable: {exc}"
    missing = [n for n in ("Domain", "generate", "optimize") if not hasattr(bm, n)]
    if missing:
        return None, f"bubblemesh has no {', '.join(missing)} yet"
    return bm, None


def _quality_summary():
    """bubblemesh.quality.summary when it exists (the product's own measure), else cases.metrics."""
    try:
        from bubblemesh.quality import summary

        return summary, "bubblemesh.quality.summary"
    except Exception:
        return metrics.summary, "cases.metrics.summary (bubblemesh.quality not available)"


def _radius_ratio():
    try:
        from bubblemesh import radius_ratio

        return radius_ratio
    except Exception:
        return metrics.radius_ratio


def _warm_up(bm) -> float:
    """Load/compile bubblemesh's kernels so case timings exclude the JIT: twice on a small
    square with a hole (a tiny disk alone left some code paths uncompiled)."""
    from cases.geometry import circle, clockwise, rectangle

    loops = [rectangle(-1.0, -1.0, 1.0, 1.0, 0.125), clockwise(circle((0.0, 0.0), 0.3, 32))]
    t0 = time.perf_counter()
    for _ in range(2):
        bm.optimize(bm.generate(bm.Domain.from_loops(loops)))
    return time.perf_counter() - t0


def _standin_base(loops):
    """Before bubblemesh exists: Triangle without quality bound ('p' + area), sized like §2."""
    import triangle as tr

    pts, segs = peers._segments(loops)
    sizes = np.concatenate([peers._node_sizes(lp) for lp in loops])
    target = int(round(peers._domain_area(loops) / np.mean(np.sqrt(3.0) / 4.0 * sizes**2)))
    data = {"vertices": pts, "segments": segs}
    if len(loops) > 1:
        data["holes"] = peers.hole_points(loops)
    area = peers.triangle_number(peers._domain_area(loops) / target)
    out = tr.triangulate(data, f"pa{area}YQ")
    return np.asarray(out["vertices"], np.float64), np.asarray(out["triangles"], np.int64)


# --------------------------------------------------------------------------- one case


def _row(case, method, **kw):
    row = dict.fromkeys(COLUMNS, None)
    row.update(case=case, method=method, **kw)
    return row


def _write_vtu(path, points, triangles, rho, radii=None):
    import meshio

    p3 = np.zeros((len(points), 3))
    p3[:, :2] = points[:, :2]
    point_data = {} if radii is None else {"radius": np.asarray(radii, dtype=np.float64)}
    meshio.Mesh(
        p3,
        [("triangle", np.asarray(triangles, dtype=np.int64))],
        point_data=point_data,
        cell_data={"radius_ratio": [np.asarray(rho, dtype=np.float64)]},
    ).write(path)


def run_case(case, out: Path, bar=None, *, methods=METHODS, summary=None):
    """All methods on one case module; returns (rows, figure paths, notes)."""
    from cases import plots

    summary = summary or _quality_summary()[0]
    rr = _radius_ratio()
    loops = [np.asarray(lp, dtype=np.float64) for lp in case.loops()]
    boundary = np.vstack(loops)
    rows, meshes, notes = [], {}, []

    def step(label):
        if bar is not None:
            bar.set_postfix_str(f"{case.NAME}: {label}")

    def record(method, points, triangles, seconds, info, radii=None, input_=None):
        rho = np.asarray(rr(points, triangles), dtype=np.float64)
        s = summary(points, triangles)
        shift, nb = metrics.boundary_shift(boundary, points, triangles)
        fname = f"{case.NAME}__{method}.vtu"
        _write_vtu(out / "meshes" / fname, points, triangles, rho, radii)
        meshes[method] = (np.asarray(points)[:, :2], np.asarray(triangles), rho)
        rows.append(
            _row(
                case.NAME,
                method,
                status="ok",
                elements=int(s["count"]),
                nodes=int(len(points)),
                rho_min=s["min"],
                rho_mean=s["mean"],
                rho_median=s["median"],
                n_below_0_5=int(s["count_below_0_5"]),
                pct_below_0_5=100.0 * s["frac_below_0_5"],
                n_below_0_7=int(s["count_below_0_7"]),
                pct_below_0_7=100.0 * s["frac_below_0_7"],
                min_angle=s["min_angle_deg"],
                max_angle=s["max_angle_deg"],
                seconds=float(seconds),
                boundary_shift=shift,
                boundary_nodes=nb,
                inverted=int(peers._inverted(np.asarray(points)[:, :2], np.asarray(triangles))),
                input=input_ or "boundary nodes",
                mesh_file=f"meshes/{fname}",
                options=info.get("options", ""),
                reason="",
            )
        )

    bm, why = _bubblemesh()
    base, panels, m2, m3 = None, {}, None, None
    if bm is not None:
        step("§2 generate")
        try:
            t0 = time.perf_counter()
            m2 = bm.generate(bm.Domain.from_loops(loops))
            t2 = time.perf_counter() - t0
        except Exception as exc:  # a failing case is reported, the others still run
            why = f"bubblemesh.generate raised {type(exc).__name__}: {exc}"
            rows.append(_row(case.NAME, "bubblemesh_delaunay", status="failed", reason=why))
        else:
            s2 = m2.stats
            record(
                "bubblemesh_delaunay",
                m2.points,
                m2.triangles,
                t2,
                {
                    "options": f"bubblemesh.generate: {s2.get('insertions', '?')} insertions, "
                    f"ΣA_e = {s2.get('bubble_area', float('nan')):.6g} ≥ "
                    f"A_geo = {s2.get('domain_area', float('nan')):.6g}"
                },
                radii=m2.radii,
            )
        if bar is not None:
            bar.update(1)
        step("§3 optimize")
        if m2 is None:
            rows.append(_row(case.NAME, "bubblemesh_optimized", status="failed", reason=why))
        else:
            try:
                t0 = time.perf_counter()
                m3 = bm.optimize(m2, amplification=AMPLIFICATION)
                t3 = time.perf_counter() - t0
            except Exception as exc:
                reason = f"bubblemesh.optimize raised {type(exc).__name__}: {exc}"
                rows.append(_row(case.NAME, "bubblemesh_optimized", status="failed", reason=reason))
            else:
                record(
                    "bubblemesh_optimized",
                    m3.points,
                    m3.triangles,
                    t2 + t3,
                    {
                        "options": f"bubblemesh.optimize(amplification={AMPLIFICATION}) after "
                        f"generate: {m3.stats.get('iterations', '?')} iterations; seconds = "
                        f"generate + optimize ({t2:.3f} + {t3:.3f})"
                    },
                    radii=m3.radii,
                )
        if bar is not None:
            bar.update(1)
        if m2 is not None:
            base = (np.asarray(m2.points), np.asarray(m2.triangles))
            base_label = "bubblemesh §2 mesh"
        if m2 is not None and m3 is not None:
            for key, m in (("delaunay", m2), ("optimized", m3)):
                panels[key] = dict(
                    points=np.asarray(m.points),
                    triangles=np.asarray(m.triangles),
                    radii=np.asarray(m.radii),
                    rho=meshes[f"bubblemesh_{key}"][2],
                )
    else:
        for method in BUBBLEMESH:
            rows.append(_row(case.NAME, method, status="skipped", reason=why))
            if bar is not None:
                bar.update(1)
    if base is None:
        step("stand-in base")
        base = _standin_base(loops)
        base_label = "STAND-IN Triangle 'pa' mesh (bubblemesh §2 mesh not available)"
        notes.append(
            f"{case.NAME}: no bubblemesh §2 mesh ({why}); the post-processors ran on a stand-in "
            f"Triangle mesh without quality bound, {len(base[1])} elements."
        )
    target = len(base[1])

    for name in peers.PEERS:
        if name not in methods:
            continue
        step(name)
        p, t, sec, info = peers.run_peer(name, loops, target, base=base)
        if info["status"] == "ok":
            record(
                name, p, t, sec, info, input_=base_label if name in peers.POSTPROCESSORS else None
            )
            rows[-1]["options"] = info["options"] + (
                f"; tuning runs (parameter, elements): {info['runs']}" if "runs" in info else ""
            )
        else:
            rows.append(_row(case.NAME, name, status=info["status"], reason=info["reason"]))
        if bar is not None:
            bar.update(1)

    step("figures")
    figs = {}
    fig_dir = out / "figures"
    title = getattr(case, "TITLE", case.NAME)
    if panels:
        figs["panels"] = fig_dir / f"{case.NAME}_panels.png"
        plots.panels(figs["panels"], title, panels["delaunay"], panels["optimized"], AMPLIFICATION)
    order = [m for m in METHODS if m in meshes]
    figs["histograms"] = fig_dir / f"{case.NAME}_histograms.png"
    plots.histograms(figs["histograms"], title, {m: meshes[m][2] for m in order}, LABELS)
    figs["meshes"] = fig_dir / f"{case.NAME}_meshes.png"
    plots.meshes(figs["meshes"], title, {m: meshes[m] for m in order}, LABELS)
    return rows, figs, notes


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
    """Run the named cases (default: all of ``cases.ALL``) into ``out``; returns the DataFrame."""
    import pandas as pd
    from tqdm import tqdm

    from cases import report

    t_start = time.perf_counter()
    names = list(_cases.ALL) if not cases else list(cases)
    mods = [_cases.get(n) for n in names]
    out = Path(out)
    (out / "meshes").mkdir(parents=True, exist_ok=True)
    (out / "figures").mkdir(parents=True, exist_ok=True)

    summary, summary_src = _quality_summary()
    bm, why = _bubblemesh()
    warm = None
    if bm is not None:
        try:
            warm = _warm_up(bm)
        except Exception as exc:  # the cases will report their own failures
            print(f"bubblemesh warm-up failed: {type(exc).__name__}: {exc}", file=sys.stderr)

    per_case = len(BUBBLEMESH) + sum(1 for p in peers.PEERS if p in methods)
    rows, figs, notes = [], {}, []
    with tqdm(
        total=len(mods) * per_case,
        desc="reproduce",
        unit="mesh",
        disable=not progress,
        file=sys.stderr,
    ) as bar:
        for mod in mods:
            r, f, n = run_case(mod, out, bar, methods=methods, summary=summary)
            rows += r
            figs[mod.NAME] = f
            notes += n
    df = pd.DataFrame(rows, columns=COLUMNS)
    df.to_csv(out / "quality.csv", index=False, float_format="%.6g")
    meta = environment()
    meta.update(
        total_seconds=time.perf_counter() - t_start,
        warm_up_seconds=warm,
        quality_source=summary_src,
        bubblemesh_status="ok" if bm is not None else why,
        notes=notes,
        laplacian_steps=peers.LAPLACIAN_STEPS,
        amplification=AMPLIFICATION,
    )
    (out / "reproduce.json").write_text(json.dumps(meta, indent=2, default=str) + "\n")
    if write_report:
        report.write(out, df, figs, meta, {n: _cases.get(n) for n in names}, LABELS)
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
    ap.add_argument("--no-progress", action="store_true")
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
    print(f"report: {Path(a.out) / 'index.html'}")


if __name__ == "__main__":
    _cli()
