"""Write the case-study report (README.md and index.html) from quality.csv's rows.

Every sentence about agreement with the paper is computed from the numbers
(``findings``); nothing about the results is written by hand here.
"""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np

# What the paper says about each figure (§4) is in each case's metadata: ``paper.claim``
# (the sentence) and ``paper.low_elements`` ("few": §4's "still few elements with low
# radius ratio"; "none": the paper singles out no low elements); ``claims`` collects them.
FEW_PCT = 5.0  # "a few" = more than none and at most this % of the elements
MUCH_BETTER_PCT = 0.5  # "much better": elements below 0.7 at most halved ...
MUCH_BETTER_MEAN = 0.03  # ... and mean ρ up by at least this


def _ok(df):
    return df[df["status"] == "ok"]


def _get(df, case, method):
    r = df[(df["case"] == case) & (df["method"] == method) & (df["status"] == "ok")]
    return None if r.empty else r.iloc[0]


def ranking(df):
    """Methods ok in every case they were run on, ranked by the mean over cases of mean ρ (desc)
    and of % below 0.7 (asc); returns a DataFrame sorted by mean-ρ rank."""
    import pandas as pd

    ok = _ok(df).copy()
    if ok.empty:
        return pd.DataFrame()
    ok["rank_mean"] = ok.groupby("case")["rho_mean"].rank(ascending=False, method="min")
    ok["rank_low"] = ok.groupby("case")["pct_below_0_7"].rank(ascending=True, method="min")
    g = ok.groupby("method", sort=False).agg(
        cases=("case", "nunique"),
        rho_mean=("rho_mean", "mean"),
        rho_min=("rho_min", "min"),
        pct_below_0_7=("pct_below_0_7", "mean"),
        avg_rank_by_mean=("rank_mean", "mean"),
        avg_rank_by_below_0_7=("rank_low", "mean"),
        seconds=("seconds", "sum"),
    )
    return g.sort_values(["avg_rank_by_mean", "rho_mean"], ascending=[True, False]).reset_index()


def _n(count, word="element"):
    count = int(count)
    return f"{count} {word}" + ("" if count == 1 else "s")


def claims(cases) -> dict[str, dict]:
    """``paper`` metadata of each case that has it (name -> {claim, low_elements})."""
    return {c.name: dict(c.metadata["paper"]) for c in cases if "paper" in c.metadata}


def findings(df, labels=None, case_labels=None, paper=None):
    """Plain-language findings, (kind, sentence) with kind agree/disagree/info, from the data.
    ``labels`` / ``case_labels`` name the methods / cases (default: their keys); ``paper``
    maps a case to its claims (see ``claims``)."""
    paper = paper or {}
    labels = labels or {}
    lab = lambda m: labels.get(m, m)  # noqa: E731
    cl = lambda c: (case_labels or {}).get(c, c)  # noqa: E731
    out = []
    for key in dict.fromkeys(df["case"]):
        d, o = _get(df, key, "bubblemesh_delaunay"), _get(df, key, "bubblemesh_optimized")
        case = cl(key)
        if d is None or o is None:
            msg = (
                f"{case}: bubblemesh did not produce both meshes; the paper's result is unchecked."
            )
            out.append(("disagree", msg))
            continue
        up = o.rho_mean - d.rho_mean
        base = (
            f"{case}: optimization took mean ρ from {d.rho_mean:.3f} to {o.rho_mean:.3f}, the "
            f"elements below 0.7 from {d.n_below_0_7} ({d.pct_below_0_7:.1f}%) to {o.n_below_0_7} "
            f"({o.pct_below_0_7:.1f}%) and the minimum ρ from {d.rho_min:.3f} to {o.rho_min:.3f}"
        )
        if up >= MUCH_BETTER_MEAN and o.n_below_0_7 <= MUCH_BETTER_PCT * d.n_below_0_7:
            out.append(("agree", base + ": much better, as the paper reports."))
        elif up > 0 and o.n_below_0_7 < d.n_below_0_7:
            out.append(
                (
                    "disagree",
                    base + ": better, but less than the paper's 'much better' "
                    f"(our bar: mean ρ +{MUCH_BETTER_MEAN} and the low elements halved).",
                )
            )
        else:
            out.append(("disagree", base + ": no improvement, unlike the paper."))
        verb = "stays" if int(o.n_below_0_7) == 1 else "stay"
        low = f"{_n(o.n_below_0_7)} of the optimized mesh {verb} below 0.7 ({o.pct_below_0_7:.1f}%)"
        expected = paper.get(key, {}).get("low_elements")
        if expected == "few":
            if o.n_below_0_7 == 0:
                out.append(
                    (
                        "disagree",
                        f"{case}: the paper keeps a few elements below 0.7 here; "
                        "ours keeps none (better than reported).",
                    )
                )
            elif o.pct_below_0_7 <= FEW_PCT:
                out.append(("agree", f"{case}: {low}, the few the paper reports for this figure."))
            else:
                out.append(("disagree", f"{case}: {low}, more than the paper's few."))
        elif expected is not None:
            kind = "agree" if o.pct_below_0_7 <= FEW_PCT else "disagree"
            out.append(
                (
                    kind,
                    f"{case}: {low}; the paper singles out only Figs. 4–5 for low "
                    "elements, so it implies at most a few here.",
                )
            )
        g = _get(df, key, "gmsh_frontal")
        if g is not None:
            cmp_ = "higher" if o.rho_mean > g.rho_mean else "lower"
            out.append(
                (
                    "info",
                    f"{case}: bubblemesh's optimized mean ρ {o.rho_mean:.3f} "
                    f"({o.elements} elements, {o.n_below_0_7} below 0.7) is {cmp_} than "
                    f"Gmsh Frontal-Delaunay's {g.rho_mean:.3f} ({g.elements} elements, "
                    f"{g.n_below_0_7} below 0.7).",
                )
            )
    ok = _ok(df)
    moved = ok[ok["boundary_shift"] > 1e-12]
    for _, r in moved.iterrows():
        out.append(
            (
                "info",
                f"{cl(r.case)}: {lab(r.method)} moved boundary nodes by up to "
                f"{r.boundary_shift:.3g} ({r.boundary_nodes} boundary nodes in its mesh).",
            )
        )
    if moved.empty and not ok.empty:
        out.append(("info", "Every method kept every boundary node exactly."))
    elif not ok.empty:
        kept = sorted({lab(m) for m in ok.method} - {lab(m) for m in moved.method})
        out.append(
            (
                "info",
                "Every other method kept every boundary node exactly: " + ", ".join(kept) + ".",
            )
        )
    for _, r in ok[ok["inverted"] > 0].iterrows():
        out.append(
            ("info", f"{cl(r.case)}: {lab(r.method)} has "
                     f"{_n(r.inverted, 'inverted or flat element')}.")
        )
    ref = ok[ok.method == "bubblemesh_delaunay"].set_index("case")["elements"]
    if not ref.empty:
        dev = (ok.elements / ok.case.map(ref) - 1).abs()
        dev = dev[ok.method != "bubblemesh_delaunay"].dropna()
        if len(dev):
            out.append(
                (
                    "info",
                    f"Element counts are matched to the §2 mesh within "
                    f"{100 * dev.max():.1f}% (median {100 * dev.median():.1f}%).",
                )
            )
    lp = ok[ok.method == "laplacian_pymeshlab"].set_index("case")["rho_mean"]
    lu = ok[ok.method == "laplacian_uniform"].set_index("case")["rho_mean"]
    both = lp.index.intersection(lu.index)
    if len(both):
        gap = float((lp[both] - lu[both]).abs().max())
        out.append(
            (
                "info",
                f"pymeshlab's Laplacian and the plain uniform one differ by at most "
                f"{gap:.4f} in mean ρ over the cases (their updates differ by a self "
                "weight; both converge to the same fixed point).",
            )
        )
    rk = ranking(df)
    if not rk.empty:
        by_mean = ", ".join(
            f"{lab(m)} ({v:.3f})" for m, v in zip(rk.method, rk.rho_mean, strict=True)
        )
        low = rk.sort_values(["avg_rank_by_below_0_7", "pct_below_0_7"])
        by_low = ", ".join(
            f"{lab(m)} ({v:.1f}%)" for m, v in zip(low.method, low.pct_below_0_7, strict=True)
        )
        out.append(("info", f"Ranking by mean ρ (average rank over the cases): {by_mean}."))
        out.append(("info", f"Ranking by share of elements below 0.7 (average rank): {by_low}."))
    for _, r in df[df["status"] != "ok"].iterrows():
        out.append(("info", f"{cl(r.case)}: {lab(r.method)} {r.status}: {r.reason}"))
    return out


# --------------------------------------------------------------------------- tables

TABLE_COLS = [
    ("method", "method"),
    ("elements", "elements"),
    ("nodes", "nodes"),
    ("rho_min", "ρ min"),
    ("rho_mean", "ρ mean"),
    ("rho_median", "ρ median"),
    ("n_below_0_5", "< 0.5"),
    ("pct_below_0_5", "% < 0.5"),
    ("n_below_0_7", "< 0.7"),
    ("pct_below_0_7", "% < 0.7"),
    ("min_angle", "min angle°"),
    ("max_angle", "max angle°"),
    ("seconds", "seconds"),
    ("boundary_shift", "boundary shift"),
]


def _fmt(key, v):
    if v is None or (isinstance(v, float) and np.isnan(v)):
        return "–"
    if key in ("elements", "nodes", "n_below_0_5", "n_below_0_7", "cases"):
        return str(int(v))
    if key.startswith("rho") or key.startswith("avg_rank"):
        return f"{v:.3f}" if key.startswith("rho") else f"{v:.2f}"
    if key.startswith("pct") or key.endswith("angle"):
        return f"{v:.1f}"
    if key == "seconds":
        return f"{v:.3f}"
    if key == "boundary_shift":
        return "0" if v == 0 else f"{v:.2g}"
    return str(v)


def _case_table(df, case, labels):
    rows = []
    for _, r in df[df["case"] == case].iterrows():
        if r.status == "ok":
            rows.append(
                [labels.get(r.method, r.method)] + [_fmt(k, r[k]) for k, _ in TABLE_COLS[1:]]
            )
        else:
            rows.append(
                [labels.get(r.method, r.method), f"{r.status}: {r.reason}"]
                + [""] * (len(TABLE_COLS) - 2)
            )
    return [h for _, h in TABLE_COLS], rows


def _rank_table(df, labels):
    rk = ranking(df)
    header = [
        "method",
        "cases",
        "mean ρ",
        "min ρ",
        "% < 0.7",
        "avg rank (mean ρ)",
        "avg rank (% < 0.7)",
    ]
    rows = [
        [
            labels.get(r.method, r.method),
            _fmt("cases", r.cases),
            _fmt("rho_mean", r.rho_mean),
            _fmt("rho_min", r.rho_min),
            _fmt("pct_below_0_7", r.pct_below_0_7),
            _fmt("avg_rank_by_mean", r.avg_rank_by_mean),
            _fmt("avg_rank_by_below_0_7", r.avg_rank_by_below_0_7),
        ]
        for _, r in rk.iterrows()
    ]
    return header, rows


# --------------------------------------------------------------------------- benchmark

BENCH_COLS = [  # benchmark.csv column, header; its "note" column is listed below the table
    ("method", "method"),
    ("elements", "elements"),
    ("seconds", "seconds"),
    ("elements_per_s", "elements/s"),
    ("peak_mb", "peak memory, MB"),
    ("peak_delta_mb", "MB above warm-up"),
    ("ratio_to_triangle", "time per element ÷ Triangle's"),
    ("boundary_nodes", "boundary nodes"),
    ("repeats", "repeats"),
    ("status", "status"),
]


def _bench_cell(key, v, labels):
    import pandas as pd

    if v is None or (not isinstance(v, str) and pd.isna(v)):
        return ""
    if key == "method":
        return labels.get(v, v)
    if key in ("elements", "boundary_nodes", "repeats"):
        return f"{int(v)}"
    if key == "elements_per_s":
        return f"{v:,.0f}"
    if key in ("peak_mb", "peak_delta_mb"):
        return f"{v:.1f}"
    if key == "ratio_to_triangle":
        return f"{v:.2f}"
    if key == "seconds":
        return f"{v:.4g}"
    return str(v)


def _quality_vs_gmsh(out: Path):
    """The default mesher against Gmsh and Triangle at matched counts, from
    quality_vs_gmsh.csv ([] when absent), with the project's targets met."""
    import pandas as pd

    from .quality import COUNT_MATCH, GMSH_SMOOTHING, target_summary

    csv = out / "quality_vs_gmsh.csv"
    if not csv.exists():
        return []
    q = pd.read_csv(csv)
    rows = [[r["case"], r["mesher"], str(r["N"]), f"{r['N/predicted']:.3f}", f"{r['min']:.3f}",
             f"{r['mean']:.4f}", str(r["below_0.7"]), str(r["below_0.7_off_sharp"]),
             "yes" if r["valid"] else "NO", r["wins_mean"], r["wins_min"],
             r["wins_below_0.7"]] for r in q.to_dict("records")]
    return [("h2", "The default mesher against Gmsh Frontal-Delaunay"),
            ("p", "`bm.mesh` (defaults; corner-only inputs with max_area = area / 200) against "
                  f"Gmsh's Frontal-Delaunay (algorithm 6 with {GMSH_SMOOTHING} smoothing steps, "
                  "on bm's refined boundary nodes and its "
                  f"size field, scaled until the counts match within {COUNT_MATCH:.0%} or "
                  "the closest of 12 "
                  "runs; on the uniform disk Gmsh's own constant size) and Triangle -pq30 "
                  "(area bound tuned to the count), from "
                  f"`python -m bubblemesh.studies.quality --big --out {out}`, which the "
                  "reproduce command runs (Triangle's A.poly and double_hex3.poly from the "
                  "triangle package, `--big` the benchmark's 100k disk; "
                  "[quality_vs_gmsh.csv](quality_vs_gmsh.csv)). N/pred is the count "
                  "over the count the size field asks for: the integral of its element "
                  "density 4 / (√3 h²) over the domain, computed apart from every mesh (to "
                  "0.01%). Off sharp: elements below 0.7 not touching an input corner too "
                  "sharp for 0.7. Valid: bubblemesh.verify's exact check (validity, "
                  f"conformity). {target_summary(q)}.{_unmatched(q)}"),
            ("table", ["case", "mesher", "N", "N/pred", "min ρ", "mean ρ", "< 0.7",
                       "off sharp", "valid", "best mean", "best min", "fewest < 0.7"], rows)]


def _unmatched(q):
    """Sentences giving the counts where Gmsh's missed bm's by more than
    MATCHED (no scale of its size reached it), '' when none."""
    from .quality import MATCHED, bracketed_cases, unmatched_cases

    n = q.set_index(["case", "mesher"])["N"]
    text = ""
    off = unmatched_cases(q)
    if off:
        text += (f" Gmsh's count could not be brought within {MATCHED:.0%} of bm's on " +
                 ", ".join(f"{c} ({n[c, 'gmsh']} against {n[c, 'bm']})" for c in off) +
                 ": its count jumps past that range as its size scale changes.")
    jumped = bracketed_cases(q)
    if jumped:
        text += (" Gmsh's count jumped across bm's as its size scale changed on " +
                 ", ".join(f"{c} (from {min(n[c, 'gmsh'], n[c, 'gmsh_beyond'])} to "
                           f"{max(n[c, 'gmsh'], n[c, 'gmsh_beyond'])}, bm {n[c, 'bm']})"
                           for c in jumped) +
                 ": there both of its meshes are rows (gmsh_beyond the farther), and bm is "
                 "judged against their mean and minimum interpolated linearly in the count "
                 "to bm's.")
    return text


def _benchmark(out: Path):
    """The benchmark section's blocks from benchmark.csv / benchmark.json, [] when absent."""
    import json

    import pandas as pd

    from .benchmark import LABELS

    csv = out / "benchmark.csv"
    if not csv.exists():
        return []
    b = pd.read_csv(csv)
    path = out / "benchmark.json"
    m = json.loads(path.read_text()) if path.exists() else {}
    blocks: list = [("h2", "Speed benchmark"), ("p", _bench_command(m))]
    if (out / "figures" / "benchmark.png").exists():
        blocks.append(("img", "figures/benchmark.png", "benchmark: seconds and elements/s"))
    cols = [(k, h) for k, h in BENCH_COLS if k in b.columns]
    blocks.append(("table", [h for _, h in cols],
                   [[_bench_cell(k, r[k], LABELS) for k, _ in cols] for _, r in b.iterrows()]))
    targets = m.get("targets", [])
    if targets:
        blocks += [("h3", "Speed targets"), ("table", ["target", "measured", "met"], [
            [t["target"], f"{t['measured']} {t['unit']}".strip(), "yes" if t["met"] else "NO"]
            for t in targets])]  # fmt: skip
    trade = [r for r in m.get("iterations_tradeoff", []) if "seconds" in r]
    if trade:
        blocks += [
            ("h3", f"§3 iterations against time and quality ({trade[0]['elements']} elements, "
                   "generate + optimize; the default is 200)"),
            ("table", ["iterations", "seconds", "× Gmsh's speed", "mean ρ", "min ρ", "% < 0.7"], [
                [str(r["iterations"]), f"{r['seconds']:.3g}",
                 f"{r['speedup_vs_gmsh']:.2f}" if "speedup_vs_gmsh" in r else "",
                 f"{r['rho_mean']:.4f}", f"{r['rho_min']:.3f}", f"{r['pct_below_0_7']:.2f}"]
                for r in trade]),
        ]  # fmt: skip
    blocks += [("h3", "How the benchmark ran"), ("ul", _benchmark_notes(m, LABELS))]
    noted = b[b["note"].notna() & (b["note"] != "")] if "note" in b else b.iloc[:0]
    if len(noted):
        blocks += [("h3", "Notes on the rows"), ("table", ["method", "elements", "note"], [
            [LABELS.get(r.method, r.method), _bench_cell("elements", r.elements, LABELS), r.note]
            for r in noted.itertuples()])]  # fmt: skip
    return blocks


def _bench_command(m: dict) -> str:
    """The command that regenerates the benchmark as it was run."""
    if m.get("quick"):
        args = " --quick"
    else:
        size, repeats = max(m.get("sizes") or [0]), m.get("repeats")
        args = (f" --max-elements {size}" if size else "") + (
            f" --repeats {repeats}" if repeats else "")
    return (f"Regenerate with `bubblemesh bench{args} --out reports/` (a fresh process per "
            "method and size; it rewrites this report too).")


def _benchmark_notes(m: dict, labels) -> list[str]:
    """Sentences from benchmark.json: when and where it ran, slopes, compile times, caps."""
    from .benchmark import phase_name

    if not m:
        return []
    notes = [
        f"Run {m.get('date')} on {m.get('platform')}, {m.get('cpu')}, {m.get('cpu_count')} CPUs"
        + (" (quick mode)" if m.get("quick") else "")
        + f"; minimum of {m.get('repeats')} repeats after a warm-up; "
        f"{m.get('total_seconds', float('nan')):.0f} s in all; 1-minute load average "
        f"{m.get('load_average_start_end')} at start/end (other jobs share the machine).",
        "Memory is the peak resident set size of a fresh process per method and size, "
        "interpreter and libraries included; the column beside it is the part above that "
        "process's size after its warm-up.",
        f"The disk's boundary has n uniformly spaced nodes, n = √(elements / "
        f"{m.get('c_disk', float('nan'))}) (bubblemesh's §2 element count on it); Triangle and "
        "Gmsh are tuned, untimed, to bubblemesh's element count.",
        f"Gmsh Frontal-Delaunay is run only up to {m.get('gmsh_cap')} elements (far slower); "
        "the rows above that say skipped.",
    ]
    slopes = ", ".join(f"{labels.get(k, k)} {v:.3f}"
                       for k, v in m.get("loglog_slopes", {}).items() if v == v)
    if slopes:
        notes.append(f"Fitted log-log slope of seconds against elements (sizes ≥ "
                     f"{m.get('slope_from_elements')} elements; 1 is linear): {slopes}.")
    t = m.get("threads", {})
    if "layer" in t:
        notes.append(f"numba ran with its {t['layer']} threading layer and {t['numba_threads']} "
                     "threads (the 1-thread rows with one).")
    for method, p in m.get("profile", {}).items():
        total = sum(p["phases"].values())
        parts = ", ".join(f"{phase_name(k)} {v:.3g} s ({100 * v / total:.0f}%)"
                          for k, v in p["phases"].items())
        notes.append(f"Where the time goes, {labels.get(method, method)} at {p['elements']} "
                     f"elements: {parts}.")
    c = m.get("compile", {})
    if "cold_first_call_s" in c:
        notes.append(
            f"numba: the first generate + optimize in a fresh process takes "
            f"{c['cold_first_call_s']:.1f} s with an empty cache (compiling the kernels) and "
            f"{c.get('warm_first_call_s', float('nan')):.2f} s with the cache filled "
            f"(import {c.get('warm_import_s', float('nan')):.2f} s)."
        )
    return notes


# --------------------------------------------------------------------------- writers

METHOD_NOTES = [
    "**bubblemesh §2** is `bubblemesh.generate` (the paper's Delaunay mesh); **§2+§3** is "
    "`bubblemesh.optimize` on it with the paper's defaults (amplification 1.7, 3 rings, "
    "α = 0.1); its time is generate + optimize.",
    "**Triangle** is `triangulate(..., 'pq30a<A>YQ')`: `Y` forbids new boundary nodes; the area "
    "bound A starts at domain area / §2 element count and is corrected (A ← A·count/target, "
    "3 runs, the closest kept).",
    "**Gmsh** meshes a geometry whose points are the boundary nodes and whose lines are "
    "transfinite with 2 nodes (no node added on the boundary). Gmsh's size factor does not reach "
    "the interior then, so the interior size is a factor times the reciprocal-distance mean, over "
    "the loops, of the size at each loop's nearest node (node size: mean of its two segments; a "
    "Python size callback, counted in the time); the factor is tuned to the §2 element count.",
    "**pymeshlab isotropic remesh** runs `meshing_isotropic_explicit_remeshing` on the §2 mesh "
    "with an absolute target edge length tuned to the §2 element count. The filter has no "
    "boundary lock (on the whole mesh it splits and collapses boundary edges), so it runs with "
    "`selectedonly` on the faces that own no boundary edge: the boundary nodes and the §2 mesh's "
    "boundary strip of faces are kept as they were. **boundary free** is the same filter on the "
    "whole mesh, for reference; its boundary shift and boundary-node count show what it changed.",
    "**Laplacian** smoothing moves the §2 mesh's interior nodes, boundary fixed, same "
    "connectivity: pymeshlab's `apply_coord_laplacian_smoothing` (uniform weights, only interior "
    "vertices selected) and a plain numpy/scipy mean-of-neighbours variant. pymeshlab's update "
    "keeps a self weight: x ← (x + 2Σ neighbours)/(2·deg + 1).",
    "Post-processor times exclude building their §2 input; every generator's time is its last "
    "tuning run. Times are wall-clock on a shared machine: compare orders of magnitude only; "
    "the speed benchmark measures speed properly.",
]


def _inline_html(text):
    """The markdown marks the report uses (**bold**, `code`, [text](link)) as HTML."""
    import re

    t = html.escape(text, quote=False)
    t = re.sub(r"[*][*]([^*]*)[*][*]", r"<b>\1</b>", t)
    t = re.sub(r"`([^`]*)`", r"<code>\1</code>", t)
    return re.sub(r"\[([^\]]*)\]\(([^)]*)\)", r"<a href='\2'>\1</a>", t)


def _markdown(blocks) -> str:
    out = []
    for kind, *a in blocks:
        if kind in ("h1", "h2", "h3"):
            out.append("#" * int(kind[1]) + " " + a[0])
        elif kind == "p":
            out.append(a[0])
        elif kind == "em":
            out.append(f"*{a[0]}*")
        elif kind == "img":
            out.append(f"![{a[1]}]({a[0]})")
        elif kind == "ul":
            out.append("\n".join(f"- {item if isinstance(item, str) else item[1]}"
                                 for item in a[0]))
        elif kind == "table":
            esc = lambda c: str(c).replace("|", "\\|")  # noqa: E731
            lines = ["| " + " | ".join(map(esc, a[0])) + " |", "|" + "---|" * len(a[0])]
            out.append("\n".join(lines + ["| " + " | ".join(map(esc, r)) + " |" for r in a[1]]))
    return "\n\n".join(out) + "\n"


def _html(blocks, title) -> str:
    css = (
        "body{font-family:system-ui,sans-serif;max-width:1200px;margin:auto;padding:1em;color:#222}"
        "table{border-collapse:collapse;font-size:13px;margin:0.5em 0 1.5em}"
        "td,th{border:1px solid #ccc;padding:3px 6px;text-align:right}td:first-child,th:first-child"
        "{text-align:left}img{max-width:100%}li.agree{color:#135}li.disagree{color:#a40}"
    )
    out = [f"<!doctype html><html><head><meta charset='utf-8'><title>{html.escape(title)}"
           f"</title><style>{css}</style></head><body>"]
    for kind, *a in blocks:
        if kind in ("h1", "h2", "h3"):
            out.append(f"<{kind}>{_inline_html(a[0])}</{kind}>")
        elif kind == "p":
            out.append(f"<p>{_inline_html(a[0])}</p>")
        elif kind == "em":
            out.append(f"<p><i>{html.escape(a[0])}</i></p>")
        elif kind == "img":
            out.append(f"<p><img src='{a[0]}' alt='{html.escape(a[1])}'></p>")
        elif kind == "ul":
            items = [(None, i) if isinstance(i, str) else i for i in a[0]]
            out.append("<ul>" + "".join(
                (f"<li class='{c}'>" if c else "<li>") + _inline_html(t) + "</li>"
                for c, t in items) + "</ul>")  # fmt: skip
        elif kind == "table":
            head = "".join(f"<th>{html.escape(c)}</th>" for c in a[0])
            body = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in r)
                           + "</tr>" for r in a[1])  # fmt: skip
            out.append(f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>")
    return "\n".join(out + ["</body></html>"]) + "\n"


def environment() -> dict:
    """When and where this ran: date, platform, CPU, and the packages' versions."""
    import datetime as dt
    import os
    import platform

    from .study import versions

    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as fh:
            cpu = next((line.split(":", 1)[1].strip() for line in fh
                        if line.startswith("model name")), cpu)
    except OSError:
        pass
    found = versions()
    for package in ("matplotlib", "shapely", "pyarrow"):
        from importlib import metadata

        try:
            found[package] = metadata.version(package)
        except metadata.PackageNotFoundError:
            found[package] = "not installed"
    return {"date": dt.datetime.now().astimezone().strftime("%Y-%m-%d %H:%M %Z"),
            "platform": platform.platform(), "cpu": cpu, "cpu_count": os.cpu_count(),
            "versions": found}


def run_meta(study, run, command: str) -> dict:
    """The run record written beside the results (``<study>.run.json``) and read by reports."""
    meta = environment()
    source = study.cases[0].source
    meta.update(study=study.name, definition=study.source, command=command,
                cases=[c.name for c in study.cases],
                cases_dir=str(Path(source).resolve().parent) if source else None)
    if run is not None:
        meta.update(computed=run.computed, reused=run.reused, where=run.where,
                    workers=run.workers, timing=run.timing, total_seconds=run.seconds,
                    warm_up_seconds=run.warm_up_seconds)
    return meta


def _how_it_ran(meta: dict) -> str:
    """One paragraph: when, how long, on what, which cells were reused, how timing was kept."""
    warm = meta.get("warm_up_seconds")
    text = (f"Generated {meta['date']} in {meta.get('total_seconds', float('nan')):.1f} s"
            + (f", {warm:.1f} s of it loading or compiling the numba kernels" if warm else "")
            + ".")
    if meta.get("computed") is not None:
        reused = meta.get("reused", 0)
        text += (f" {meta['computed']} cells were computed on {meta.get('where')}"
                 + (f" and {reused} taken from earlier runs of the same cells (same case, "
                    "method, parameters and bubblemesh version)" if reused else "") + ".")
    if meta.get("timing"):
        text += " " + meta["timing"]
    return text


def _read_vtu(out: Path, name: str):
    import meshio

    m = meshio.read(out / name)
    radius = m.point_data.get("radius")
    return (np.asarray(m.points)[:, :2], np.asarray(m.cells_dict["triangle"], dtype=np.int64),
            None if radius is None else np.asarray(radius),
            np.asarray(m.cell_data["radius_ratio"][0]))


def _paper_figures(out: Path, study, df, labels) -> dict[str, dict[str, Path]]:
    """Per case: the paper's panels, the histograms and the meshes, from the written VTUs."""
    from . import plots

    figs: dict[str, dict[str, Path]] = {}
    amplification = _default("amplification")
    for case in study.cases:
        rows = df[(df["case"] == case.name) & (df["status"] == "ok") & df["mesh_file"].notna()]
        meshes = {r.method: _read_vtu(out, r.mesh_file) for r in rows.itertuples()
                  if (out / r.mesh_file).exists()}
        if not meshes:
            continue
        fig_dir, title, f = out / "figures", case.title, figs.setdefault(case.name, {})
        fig_dir.mkdir(parents=True, exist_ok=True)
        pair = [meshes.get(k) for k in ("bubblemesh_delaunay", "bubblemesh_optimized")]
        if all(m is not None and m[2] is not None for m in pair):
            f["panels"] = fig_dir / f"{case.name}_panels.png"
            delaunay, optimized = (dict(points=m[0], triangles=m[1], radii=m[2], rho=m[3])
                                   for m in pair if m is not None)
            plots.panels(f["panels"], title, delaunay, optimized, amplification)
        f["histograms"] = fig_dir / f"{case.name}_histograms.png"
        plots.histograms(f["histograms"], title, {k: m[3] for k, m in meshes.items()}, labels)
        f["meshes"] = fig_dir / f"{case.name}_meshes.png"
        plots.meshes(f["meshes"], title, {k: (m[0], m[1], m[3]) for k, m in meshes.items()},
                     labels)
    return figs


def _default(name: str):
    import inspect

    from bubblemesh import optimize

    return inspect.signature(optimize).parameters[name].default


def _laplacian_steps(study) -> str:
    steps = sorted({str(m.params["steps"]) for m in study.methods
                    if m.adapter.startswith("laplacian") and "steps" in m.params})
    return f"Laplacian steps: {', '.join(steps)}." if steps else ""


def render_paper(study, df, out: Path, meta: dict) -> list[Path]:
    """The paper reproduction's README.md and index.html (figures redrawn from the meshes)."""
    out = Path(out)
    labels = study.labels
    case_labels = {c.name: c.label for c in study.cases}
    figs = _paper_figures(out, study, df, labels)
    word = {"agree": "agrees", "disagree": "differs"}
    paper = claims(study.cases)
    blocks = [
        ("h1", study.title),
        ("p", "The paper “Automatic Delaunay mesh generation method and physically-based mesh "
              "optimization method on two-dimensional regions” meshes four regions (its Figs. "
              "3–6) in two stages: a Delaunay mesh whose node spacing is set by node and element "
              "bubbles (§2), then an optimisation that moves the interior nodes by forces "
              "between their bubbles and re-triangulates (§3). bubblemesh implements both. "
              "Here it meshes the same four regions, and other meshers and smoothers mesh them "
              "on the same boundary nodes with about the same element count."),
        ("p", "Quality is the radius ratio ρ = 2r/R of the paper's eq. 10 (r the inradius, R "
              "the circumradius): 1 for an equilateral triangle, towards 0 as a triangle "
              "flattens. The paper counts elements below ρ = 0.7 as low quality. For each "
              "region: the paper's six panels, the ρ histogram of every method, every mesh "
              "with its elements below 0.7 in red, and the numbers."),
        ("p", f"Regenerate with `{meta['command']}`. Numbers: [results.csv](results.csv) "
              "(also as `results.parquet`, one row per case and method); every mesh: "
              "`meshes/*.vtu` (cell data `radius_ratio`)."),
        ("p", _how_it_ran(meta)),
        ("h2", "Findings (computed from the numbers below)"),
        ("ul", [(k, f"**{word.get(k, 'note')}**: {s}")
                for k, s in findings(df, labels, case_labels, paper)]),
        ("h2", "Ranking over all cases"),
        ("table", *_rank_table(df, labels)),
    ]
    for case in study.cases:
        blocks += [("h2", case.title), ("em", paper.get(case.name, {}).get("claim", ""))]
        blocks += [("img", f"figures/{figs[case.name][key].name}", f"{case.label} {key}")
                   for key in ("panels", "histograms", "meshes") if key in figs.get(case.name, {})]
        blocks.append(("table", *_case_table(df, case.name, labels)))
    from . import plots

    figure = out / "figures" / "quality_per_second.png"
    figure.parent.mkdir(parents=True, exist_ok=True)
    plots.quality_per_second(figure, df, labels, case_labels)
    blocks += [("h2", "Quality per unit of time"),
               ("p", "Mean ρ of every method against its seconds (generation and, where "
                     "there is one, optimisation; one run each, so small times are noisy)."),
               ("img", "figures/quality_per_second.png", "mean ρ against seconds")]
    blocks += _quality_vs_gmsh(out)
    blocks += _benchmark(out)
    steps = _laplacian_steps(study)
    blocks += [("h2", "How each method was run"), ("ul", METHOD_NOTES + ([steps] if steps else []))]
    blocks += _environment_blocks(meta)
    return _write(out, blocks, "bubblemesh reproduction")


def _environment_blocks(meta: dict) -> list:
    v = meta["versions"]
    return [("h2", "Environment"), ("ul", [
        f"Machine: {meta['platform']}; {meta['cpu']}; {meta['cpu_count']} CPUs",
        "Software: " + ", ".join(f"{k} {val}" for k, val in v.items()),
    ])]  # fmt: skip


def _write(out: Path, blocks, title: str) -> list[Path]:
    paths = [out / "README.md", out / "index.html"]
    paths[0].write_text(_markdown(blocks), encoding="utf-8")
    paths[1].write_text(_html(blocks, title), encoding="utf-8")
    return paths


# --------------------------------------------------------------------------- any study

SUMMARY_COLS = [("rho_mean", "mean ρ"), ("rho_min", "min ρ"), ("pct_below_0_7", "% < 0.7"),
                ("elements", "elements"), ("seconds", "seconds")]


def x_values(df, x):
    """The first of the ``x`` parameter columns a row has (NaN when none)."""
    import pandas as pd

    value = pd.Series(np.nan, index=df.index, dtype=float)
    for name in x:
        column = f"param_{name}"
        if column in df:
            value = value.fillna(pd.to_numeric(df[column], errors="coerce"))
    return value


def _summary_table(df, study):
    """Per method and grid point: the mean over the cases of each quality column."""
    ok = df[df["status"] == "ok"]
    header = ["method", "parameters", "cases"] + [h for _, h in SUMMARY_COLS]
    rows = []
    for (method, params), g in ok.groupby(["method", "params"], sort=False):
        rows.append([study.labels.get(method, method), _params_text(params), str(len(g))]
                    + [_fmt(k, float(g[k].mean())) for k, _ in SUMMARY_COLS])
    return header, rows


def _params_text(params: str) -> str:
    import json

    values = json.loads(params) if params else {}
    return ", ".join(f"{k} = {v}" for k, v in values.items()) or "defaults"


def render_study(study, df, out: Path, meta: dict) -> list[Path]:
    """README.md / index.html of any study: how it ran, quality against the ``x``
    parameters (a figure), a summary per method and grid point, verify outcomes, failures."""
    from . import plots

    out = Path(out)
    blocks: list = [("h1", study.title)]
    if study.description:
        blocks.append(("p", study.description))
    blocks += [
        ("p", f"{len(df)} cells: {len(study.cases)} cases × {len(study.methods)} methods and "
              f"their parameter grids. Quality is the radius ratio ρ = 2r/R (eq. 10 of the "
              "paper; 1 for an equilateral triangle); % < 0.7 counts the paper's low-quality "
              "elements."),
        ("p", f"Regenerate with `{meta['command']}`. Numbers: [results.csv](results.csv) "
              "(also `results.parquet`), one row per cell."),
        ("p", _how_it_ran(meta)),
    ]
    if study.x:
        x = x_values(df, study.x)
        figure = out / "figures" / f"{study.name}_quality.png"
        figure.parent.mkdir(parents=True, exist_ok=True)
        axis = " / ".join(study.x)
        plots.quality_against(figure, df.assign(x=x), study.labels,
                              {c.name: c.label for c in study.cases}, axis, study.title)
        blocks += [("h2", f"Quality against {axis}"),
                   ("img", f"figures/{figure.name}", f"quality against {axis}")]
    blocks += [("h2", "Mean over the cases, per method and parameters"),
               ("table", *_summary_table(df, study))]
    if "verify" in df and df["verify"].notna().any():
        counts = df.groupby("method", sort=False)["verify"].apply(
            lambda v: f"{int((v == 'ok').sum())} ok of {int(v.notna().sum())}")
        blocks += [("h2", "Validity checks"), ("ul", [
            f"{study.labels.get(m, m)}: {c}" for m, c in counts.items()])]
        bad = df[df["verify"].notna() & (df["verify"] != "ok")]
        blocks += [("ul", [f"{r.case}, {study.labels.get(r.method, r.method)} "
                           f"({_params_text(r.params)}): {r.verify}" for r in bad.itertuples()])]
    failed = df[df["status"] != "ok"]
    if len(failed):
        blocks += [("h2", "Cells that did not run"), ("ul", [
            f"{r.case}, {study.labels.get(r.method, r.method)} ({_params_text(r.params)}): "
            f"{r.status}: {r.reason}" for r in failed.itertuples()])]
    blocks += _environment_blocks(meta)
    return _write(out, blocks, study.title)


def render(study, df, out, run=None, command: str | None = None, meta: dict | None = None):
    """The report of ``study`` from its results table ``df`` into ``out``."""
    import json

    out = Path(out)
    record = out / f"{study.name}.run.json"
    if meta is None and run is not None and run.computed == 0 and record.exists():
        meta = json.loads(record.read_text())  # nothing new: the run that made the rows
    if meta is None:
        meta = run_meta(study, run, command or f"bubblemesh study {study.name} --out {out}")
        record.write_text(json.dumps(meta, indent=2, default=str) + "\n")
    if study.report == "paper":
        return render_paper(study, df, out, meta)
    return render_study(study, df, out, meta)
