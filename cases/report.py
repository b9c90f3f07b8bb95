"""Write the case-study report (README.md and index.html) from quality.csv's rows.

Every sentence about agreement with the paper is computed from the numbers
(``findings``); nothing about the results is written by hand here.
"""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np

# What the paper says about each figure (§4), the claims the findings test.
PAPER = {
    "fig3_circle": "Fig. 3: the optimized mesh is of high quality (no low-quality elements are "
    "singled out).",
    "fig4_square_hole": "Fig. 4: the optimized mesh is much better, but a few elements below ρ = "
    "0.7 remain.",
    "fig5_rect_two_holes": "Fig. 5: the optimized mesh is much better, but a few elements below ρ "
    "= 0.7 remain.",
    "fig6_arbitrary_two_holes": "Fig. 6: the optimization is also feasible for a complicated "
    "geometry.",
}
FEW_LOW = {
    "fig4_square_hole",
    "fig5_rect_two_holes",
}  # §4: "still few elements with low radius ratio"
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


def findings(df, labels=None):
    """Plain-language findings, (kind, sentence) with kind agree/disagree/info, from the data."""
    labels = labels or {}
    lab = lambda m: labels.get(m, m)  # noqa: E731
    out = []
    for case in dict.fromkeys(df["case"]):
        d, o = _get(df, case, "bubblemesh_delaunay"), _get(df, case, "bubblemesh_optimized")
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
        if case in FEW_LOW:
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
        elif case in PAPER:
            kind = "agree" if o.pct_below_0_7 <= FEW_PCT else "disagree"
            out.append(
                (
                    kind,
                    f"{case}: {low}; the paper singles out only Figs. 4–5 for low "
                    "elements, so it implies at most a few here.",
                )
            )
        g = _get(df, case, "gmsh_frontal")
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
                f"{r.case}: {lab(r.method)} moved boundary nodes by up to "
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
            ("info", f"{r.case}: {lab(r.method)} has {_n(r.inverted, 'inverted or flat element')}.")
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
        out.append(("info", f"{r.case}: {lab(r.method)} {r.status}: {r.reason}"))
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


def _md_table(header, rows):
    esc = lambda s: str(s).replace("|", "\\|")  # noqa: E731
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(esc(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def _html_table(header, rows):
    h = "".join(f"<th>{html.escape(c)}</th>" for c in header)
    body = "".join(
        "<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in row) + "</tr>" for row in rows
    )
    return f"<table><thead><tr>{h}</tr></thead><tbody>{body}</tbody></table>"


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


def _benchmark(out: Path):
    """(header, rows, png name, notes) of benchmark.csv / benchmark.json when present."""
    import pandas as pd

    csv = out / "benchmark.csv"
    if not csv.exists():
        return None
    b = pd.read_csv(csv)
    header = list(b.columns)
    rows = [
        [("" if pd.isna(v) else (f"{v:.4g}" if isinstance(v, float) else str(v))) for v in r]
        for r in b.values
    ]
    png = "figures/benchmark.png" if (out / "figures" / "benchmark.png").exists() else None
    return header, rows, png, _benchmark_notes(out)


def _benchmark_notes(out: Path) -> list[str]:
    """Sentences from benchmark.json: when and where it ran, slopes, compile times, caps."""
    import json

    path = out / "benchmark.json"
    if not path.exists():
        return []
    m = json.loads(path.read_text())
    notes = [
        f"Run {m.get('date')} on {m.get('platform')}, {m.get('cpu')}, {m.get('cpu_count')} CPUs"
        + (" (quick mode)" if m.get("quick") else "")
        + f"; minimum of {m.get('repeats')} repeats after a warm-up; "
        f"{m.get('total_seconds', float('nan')):.0f} s in all; 1-minute load average "
        f"{m.get('load_average_start_end')} at start/end (other jobs share the machine).",
        f"Memory: {m.get('memory')}.",
        f"Gmsh Frontal-Delaunay is run only up to {m.get('gmsh_cap')} elements (far slower); "
        "the rows above that say skipped.",
    ]
    slopes = m.get("loglog_slopes", {})
    if slopes:
        s = ", ".join(f"{k} {v:.3f}" for k, v in slopes.items() if v == v)
        if s:
            notes.append(
                f"Fitted log-log slope of seconds vs elements (sizes >= "
                f"{m.get('slope_from_elements')} elements): {s}."
            )
    if m.get("threads"):
        notes.append(f"numba threading in the children: {m['threads']}.")
    trade = [r for r in m.get("iterations_tradeoff", []) if "seconds" in r]
    if trade:
        parts = "; ".join(
            f"{r['iterations']}: {r['seconds']:.3g} s"
            + (f" ({r['speedup_vs_gmsh']:.2f}x Gmsh's speed)" if "speedup_vs_gmsh" in r else "")
            + f", mean ρ {r['rho_mean']:.4f}, min {r['rho_min']:.3f}, "
            f"{r['pct_below_0_7']:.2f}% < 0.7"
            for r in trade)
        notes.append(f"§3 iterations vs time and quality, generate + optimize at "
                     f"{trade[0]['elements']} elements (the default is 200): {parts}.")
    for method, p in m.get("profile", {}).items():
        total = sum(p["phases"].values())
        parts = ", ".join(f"{k} {v:.3g} s ({100 * v / total:.0f}%)"
                          for k, v in p["phases"].items())
        notes.append(f"Where the time goes, {method} at {p['elements']} elements: {parts}.")
    for t in m.get("targets", []):
        notes.append(
            f"Issue-6 target {'met' if t['met'] else 'MISSED'}: {t['target']} "
            f"(measured {t['measured']} {t['unit']}).".replace(" )", ")")
        )
    c = m.get("compile", {})
    if "cold_first_call_s" in c:
        notes.append(
            f"numba: first generate+optimize in a fresh process takes "
            f"{c['cold_first_call_s']:.1f} s with an empty cache (compile) and "
            f"{c.get('warm_first_call_s', float('nan')):.2f} s with the cache filled "
            f"(import {c.get('warm_import_s', float('nan')):.2f} s)."
        )
    elif c:
        notes.append(f"numba compile time: {c}.")
    return notes


# --------------------------------------------------------------------------- writers

METHOD_NOTES = [
    "**bubblemesh §2** is `bubblemesh.generate` (the paper's Delaunay mesh); **§2+§3** is "
    "`bubblemesh.optimize` on it with the paper's defaults (amplification 1.7, 3 rings, α = 0.1); "
    "its time is "
    "generate + optimize.",
    "**Triangle** is `triangulate(..., 'pq30a<A>YQ')`: `Y` forbids new boundary nodes; the area "
    "bound A starts "
    "at domain area / §2 element count and is corrected (A *= count/target, 3 runs, the closest "
    "kept).",
    "**Gmsh** meshes a geometry whose points are the boundary nodes and whose lines are "
    "transfinite with 2 nodes (no node added on the boundary). Gmsh's size factor does not reach "
    "the interior then, so the interior size is a factor times the reciprocal-distance mean, over "
    "the loops, of the size at each loop's nearest node (node size: mean of its two segments; a "
    "Python size callback, counted in the time); the factor is tuned to the §2 element count.",
    "**pymeshlab isotropic remesh** runs `meshing_isotropic_explicit_remeshing` on the §2 mesh "
    "with an absolute "
    "target edge length tuned to the §2 element count. The filter has no boundary lock (on the "
    "whole mesh it "
    "splits and collapses boundary edges), so it runs with `selectedonly` on the faces that own "
    "no boundary edge: "
    "the boundary nodes and the §2 mesh's boundary strip of faces are kept as they were. "
    "**boundary free** is the "
    "same filter on the whole mesh, for reference; its boundary shift and boundary-node count "
    "show what it changed.",
    "**Laplacian** smoothing moves the §2 mesh's interior nodes, boundary fixed, same "
    "connectivity: pymeshlab's "
    "`apply_coord_laplacian_smoothing` (uniform weights, only interior vertices selected) and a "
    "plain numpy/scipy "
    "mean-of-neighbours variant. pymeshlab's update keeps a self weight: x ← (x + 2Σ "
    "neighbours)/(2·deg + 1).",
    "Post-processor times exclude building their §2 input; every generator's time is its last "
    "tuning run. "
    "Times are wall-clock on a shared machine: compare orders of magnitude only. The issue-6 "
    "benchmark "
    "measures speed properly.",
]


def _inline_html(text):
    """The two markdown marks METHOD_NOTES use (**bold**, `code`) as HTML."""
    import re

    t = html.escape(text)
    t = re.sub(r"[*][*]([^*]*)[*][*]", r"<b>\1</b>", t)
    return re.sub(r"`([^`]*)`", r"<code>\1</code>", t)


def write(out: Path, df, figs, meta, case_mods, labels):
    out = Path(out)
    f = findings(df, labels)
    v = meta["versions"]
    versions = ", ".join(f"{k} {val}" for k, val in v.items())
    machine = f"{meta['platform']}; {meta['cpu']}; {meta['cpu_count']} CPUs"
    bench = _benchmark(out)
    warm = meta.get("warm_up_seconds")
    run_line = (
        f"Generated {meta['date']} in {meta['total_seconds']:.1f} s"
        + (
            f" (of which {warm:.1f} s bubblemesh warm-up incl. JIT compile)"
            if warm is not None
            else ""
        )
        + f". Quality numbers: {meta['quality_source']}."
    )

    # ---------------- markdown
    md = [
        "# bubblemesh: reproduction of the paper's Figs. 3–6",
        "",
        "Regenerate with `python -m cases.reproduce --out reports` (or `bubblemesh reproduce`). "
        "Numbers: [quality.csv](quality.csv); meshes: `meshes/*.vtu` (cell data `radius_ratio`).",
        "",
        run_line,
        "",
    ]
    if meta.get("bubblemesh_status") != "ok":
        md += [
            f"> **bubblemesh was not available** ({meta['bubblemesh_status']}): its rows are "
            "skipped and the "
            f"post-processors ran on a stand-in mesh. This report only proves the pipeline.",
            "",
        ]
    md += ["## Findings (computed from the numbers below)", ""]
    md += [
        f"- **{'agrees' if k == 'agree' else 'differs' if k == 'disagree' else 'note'}**: {s}"
        for k, s in f
    ]
    md += ["", "## Ranking over all cases", ""]
    md += [_md_table(*_rank_table(df, labels)), ""]
    for name, mod in case_mods.items():
        md += [f"## {getattr(mod, 'TITLE', name)}", "", f"*{PAPER.get(name, '')}*", ""]
        for key in ("panels", "histograms", "meshes"):
            if key in figs.get(name, {}):
                md += [f"![{name} {key}](figures/{figs[name][key].name})", ""]
        md += [_md_table(*_case_table(df, name, labels)), ""]
    if bench:
        md += ["## Speed benchmark (issue 6)", ""]
        if bench[2]:
            md += [f"![benchmark]({bench[2]})", ""]
        md += [_md_table(bench[0], bench[1]), ""] + [f"- {n}" for n in bench[3]] + [""]
    md += ["## How each method was run", ""] + [f"- {n}" for n in METHOD_NOTES]
    md += [f"- Laplacian steps: {meta['laplacian_steps']}.", ""]
    md += ["## Environment", "", f"- Machine: {machine}", f"- Software: {versions}", ""]
    for n in meta.get("notes", []):
        md += [f"- {n}"]
    (out / "README.md").write_text("\n".join(md) + "\n", encoding="utf-8")

    # ---------------- html
    e = html.escape
    css = (
        "body{font-family:system-ui,sans-serif;max-width:1200px;margin:auto;padding:1em;color:#222}"
        "table{border-collapse:collapse;font-size:13px;margin:0.5em 0 1.5em}"
        "td,th{border:1px solid #ccc;padding:3px 6px;text-align:right}td:first-child,th:first-child"
        "{text-align:left}img{max-width:100%}li.agree{color:#135}li.disagree{color:#a40}"
        ".warn{background:#fee;padding:0.5em;border:1px solid #c66}"
    )
    h = [
        f"<!doctype html><html><head><meta charset='utf-8'><title>bubblemesh reproduction</title>"
        f"<style>{css}</style></head><body>",
        "<h1>bubblemesh: reproduction of the paper's Figs. 3–6</h1>",
        f"<p>Regenerate with <code>python -m cases.reproduce --out reports</code>. Numbers: "
        "<a href='quality.csv'>quality.csv</a>; meshes: "
        f"<code>meshes/*.vtu</code>.</p><p>{e(run_line)}</p>",
    ]
    if meta.get("bubblemesh_status") != "ok":
        h.append(
            f"<p class='warn'>bubblemesh was not available ({e(meta['bubblemesh_status'])}): its "
            "rows are "
            f"skipped and the post-processors ran on a stand-in mesh.</p>"
        )
    h.append("<h2>Findings (computed from the numbers)</h2><ul>")
    word = {"agree": "agrees", "disagree": "differs"}
    h += [f"<li class='{k}'><b>{word.get(k, 'note')}</b>: {e(s)}</li>" for k, s in f]
    h.append("</ul><h2>Ranking over all cases</h2>" + _html_table(*_rank_table(df, labels)))
    for name, mod in case_mods.items():
        h.append(f"<h2>{e(getattr(mod, 'TITLE', name))}</h2><p><i>{e(PAPER.get(name, ''))}</i></p>")
        for key in ("panels", "histograms", "meshes"):
            if key in figs.get(name, {}):
                h.append(f"<p><img src='figures/{figs[name][key].name}' alt='{name} {key}'></p>")
        h.append(_html_table(*_case_table(df, name, labels)))
    if bench:
        h.append("<h2>Speed benchmark (issue 6)</h2>")
        if bench[2]:
            h.append(f"<p><img src='{bench[2]}' alt='benchmark'></p>")
        h.append(_html_table(bench[0], bench[1]))
        h.append("<ul>" + "".join(f"<li>{e(n)}</li>" for n in bench[3]) + "</ul>")
    h.append("<h2>How each method was run</h2><ul>")
    h += [f"<li>{_inline_html(n)}</li>" for n in METHOD_NOTES]
    h.append(f"<li>Laplacian steps: {meta['laplacian_steps']}.</li></ul>")
    h.append(
        f"<h2>Environment</h2><ul><li>Machine: {e(machine)}</li><li>Software: {e(versions)}</li>"
    )
    h += [f"<li>{e(n)}</li>" for n in meta.get("notes", [])]
    h.append("</ul></body></html>")
    (out / "index.html").write_text("\n".join(h) + "\n", encoding="utf-8")
