"""Figures of the case reports (matplotlib, Agg backend, no screen needed).

``panels``: the paper's six panels (a)–(f) for one case; ``histograms``: the
radius-ratio histograms of every method on the same bins; ``meshes``: every
method's mesh side by side with the elements below 0.7 filled.
"""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import EllipseCollection  # noqa: E402

BIN_WIDTH = 0.025  # half the paper's 0.05: the informative range is narrower than 0..1
LOW = 0.7  # the paper's "low radius ratio" threshold
_SAVE = dict(dpi=110, bbox_inches="tight", metadata={"Software": None})


def _save(fig, path):
    """Save as a palette PNG (Pillow quantization: ~4x smaller; the report is committed)."""
    import io

    buf = io.BytesIO()
    fig.savefig(buf, format="png", **_SAVE)
    plt.close(fig)
    try:
        from PIL import Image

        buf.seek(0)
        img = (
            Image.open(buf)
            .convert("RGB")
            .quantize(colors=128, method=Image.Quantize.MEDIANCUT, dither=0)
        )
        img.save(path, format="PNG", optimize=True)
    except ImportError:
        with open(path, "wb") as fh:
            fh.write(buf.getvalue())


def _mesh(ax, points, triangles, title=None, *, rho=None, lw=0.35):
    ax.triplot(points[:, 0], points[:, 1], triangles, color="k", lw=lw)
    if rho is not None and (rho < LOW).any():
        bad = triangles[rho < LOW]
        ax.tripcolor(
            points[:, 0],
            points[:, 1],
            bad,
            facecolors=np.ones(len(bad)),
            cmap="Reds",
            vmin=0,
            vmax=1.4,
            edgecolors="none",
        )
    ax.set_aspect("equal")
    ax.axis("off")
    if title:
        ax.set_title(title, fontsize=9)


def _bubbles(ax, points, radii, triangles, title):
    ax.triplot(points[:, 0], points[:, 1], triangles, color="0.8", lw=0.3)
    ax.add_collection(
        EllipseCollection(
            2 * radii,
            2 * radii,
            np.zeros_like(radii),
            units="xy",
            offsets=points,
            offset_transform=ax.transData,
            facecolors="none",
            edgecolors="tab:blue",
            linewidths=0.4,
        )
    )
    ax.plot(points[:, 0], points[:, 1], ".", ms=1.0, color="k")
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.axis("off")
    ax.set_title(title, fontsize=9)


def rho_axis(*rhos) -> np.ndarray:
    """Histogram bins over the informative range of ρ: from the lowest 1st percentile of the
    given samples, floored to 0.05 and at most 0.6 (the ρ = 0.7 line stays in view), to 1.
    Values below the first edge are counted in the first bin (the histograms clip them)."""
    lows = [np.percentile(r, 1) for r in rhos if len(r)]
    lo = min(0.6, np.floor(min(lows, default=0.0) / 0.05) * 0.05)
    return np.linspace(lo, 1.0, int(round((1.0 - lo) / BIN_WIDTH)) + 1)


def _hist(ax, rho, title, bins, color="tab:blue", ref=None):
    def draw(r, **kw):
        r = np.clip(r, bins[0], 1.0)  # the first bin also holds everything below it
        ax.hist(r, bins=bins, weights=np.full(len(r), 100.0 / max(len(r), 1)), **kw)

    if ref is not None:
        draw(ref, histtype="step", color="0.55", lw=0.9)
    draw(rho, color=color, alpha=0.85, edgecolor="white", lw=0.3)
    ax.axvline(LOW, color="tab:red", lw=0.8, ls="--")
    ax.set_xlim(bins[0], 1.0)
    ax.tick_params(labelsize=7)
    n_low, n_under = int((rho < LOW).sum()), int((rho < bins[0]).sum())
    if n_under:
        ax.text(0.02, 0.96, f"{n_under} below {bins[0]:.2f} in the first bar", fontsize=7,
                va="top", transform=ax.transAxes)  # fmt: skip
    ax.set_title(f"{title}\nmean {rho.mean():.3f}, min {rho.min():.3f}, {n_low} < {LOW}",
                 fontsize=8)  # fmt: skip


def panels(path, title, delaunay, optimized, amplification):
    """Paper-style figure.  ``delaunay`` / ``optimized``: dicts with points,
    triangles, radii, rho (the §2 and §2+§3 meshes)."""
    fig, ax = plt.subplots(3, 2, figsize=(9, 12))
    _mesh(ax[0, 0], delaunay["points"], delaunay["triangles"], "(a) Delaunay mesh (§2)")
    _mesh(ax[0, 1], optimized["points"], optimized["triangles"], "(b) Optimized mesh (§2 + §3)")
    _bubbles(
        ax[1, 0],
        delaunay["points"],
        amplification * delaunay["radii"],
        delaunay["triangles"],
        f"(c) Initial node bubbles ({amplification:g} × §2 radii, §3.1)",
    )
    _bubbles(
        ax[1, 1],
        optimized["points"],
        optimized["radii"],
        optimized["triangles"],
        "(d) Optimized node bubbles",
    )
    bins = rho_axis(delaunay["rho"], optimized["rho"])
    for a, mesh, name, color in ((ax[2, 0], delaunay, "(e) Mesh quality (Delaunay mesh)",
                                  "tab:orange"),
                                 (ax[2, 1], optimized, "(f) Mesh quality (Optimized mesh)",
                                  "tab:green")):  # fmt: skip
        _hist(a, mesh["rho"], name, bins, color=color)
        a.set_xlabel("radius ratio ρ", fontsize=8)
        a.set_ylabel("% of elements", fontsize=8)
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    _save(fig, path)


def _grid(n):
    cols = min(4, n)
    return (n + cols - 1) // cols, cols


def histograms(path, title, results, labels, ref_key="bubblemesh_delaunay"):
    """Small multiples: one ρ histogram per method, same bins and axes, the §2
    histogram outlined in each for reference.  ``results``: method -> rho."""
    keys = list(results)
    rows, cols = _grid(len(keys))
    fig, axes = plt.subplots(
        rows, cols, figsize=(3.2 * cols, 2.9 * rows), sharex=True, sharey=True, squeeze=False
    )
    bins = rho_axis(*results.values())
    ref = results.get(ref_key)
    for i, (ax, k) in enumerate(zip(axes.flat, keys, strict=False)):
        _hist(ax, results[k], labels.get(k, k), bins,
              color="tab:green" if k.startswith("bubblemesh") else "tab:blue",
              ref=None if k == ref_key else ref)  # fmt: skip
        if i + cols >= len(keys):  # the lowest panel of its column: its x axis is labelled
            ax.xaxis.set_tick_params(labelbottom=True)
            ax.set_xlabel("radius ratio ρ", fontsize=8)
        if i % cols == 0:
            ax.set_ylabel("% of elements", fontsize=8)
    for ax in list(axes.flat)[len(keys) :]:
        ax.axis("off")
    fig.suptitle(
        f"{title}\nradius-ratio histograms on the same bins (grey outline: bubblemesh §2; "
        f"dashed: ρ = {LOW})",
        fontsize=10,
    )
    fig.tight_layout()
    _save(fig, path)


def meshes(path, title, results, labels):
    """Small multiples of every method's mesh, elements with ρ < 0.7 filled red.
    ``results``: method -> (points, triangles, rho)."""
    keys = list(results)
    rows, cols = _grid(len(keys))
    fig, axes = plt.subplots(rows, cols, figsize=(3.6 * cols, 3.4 * rows), squeeze=False)
    for ax, k in zip(axes.flat, keys, strict=False):
        p, t, rho = results[k]
        _mesh(
            ax,
            p,
            t,
            f"{labels.get(k, k)}\n{len(t)} elements, {int((rho < LOW).sum())} with ρ < {LOW}",
            rho=rho,
            lw=0.25,
        )
    for ax in list(axes.flat)[len(keys) :]:
        ax.axis("off")
    fig.suptitle(f"{title}: all methods on the same boundary nodes (red: ρ < {LOW})", fontsize=10)
    fig.tight_layout()
    _save(fig, path)


def benchmark(path, df, labels):
    """Log-log seconds and elements per second vs elements, a line per method (benchmark.csv
    rows with status ok); a method's 1-thread run is dashed in its colour."""
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.6))
    colors = {}
    for method, g in df.groupby("method", sort=False):
        g = g.sort_values("elements")
        base = method.removesuffix("_1thread")
        style = dict(marker="o", ms=3, label=labels.get(method, method),
                     ls="--" if base != method else "-")
        if base in colors:
            style["color"] = colors[base]
        (line,) = ax[0].loglog(g["elements"], g["seconds"], **style)
        colors.setdefault(base, line.get_color())
        ax[1].loglog(g["elements"], g["elements_per_s"], **{**style, "color": colors[base]})
    for a, ylabel in zip(ax, ("seconds (minimum of the repeats)", "elements per second"),
                         strict=True):  # fmt: skip
        a.set_xlabel("elements")
        a.set_ylabel(ylabel)
        a.grid(True, which="both", alpha=0.3)
    handles, names = ax[0].get_legend_handles_labels()
    fig.legend(handles, names, loc="lower center", ncol=4, fontsize=8, frameon=False)
    fig.suptitle("Unit disk, uniformly spaced boundary nodes: time (left) and throughput (right)",
                 fontsize=10)
    fig.tight_layout(rect=(0, 0.1, 1, 1))
    _save(fig, path)


QUALITY = (("rho_mean", "mean ρ"), ("rho_min", "min ρ"),
           ("pct_below_0_7", f"% of elements < {LOW}"))


def quality_against(path, df, labels, case_labels, axis, title):
    """Quality (rows: mean ρ, min ρ, % below 0.7) against ``df['x']``, one column per case,
    a line per method (rows with status ok and an x value)."""
    ok = df[(df["status"] == "ok") & df["x"].notna()]
    cases = list(dict.fromkeys(ok["case"]))
    fig, axes = plt.subplots(len(QUALITY), max(1, len(cases)), figsize=(3.4 * max(1, len(cases)),
                             2.6 * len(QUALITY)), sharex=True, squeeze=False)  # fmt: skip
    colors: dict[str, str] = {}
    for j, case in enumerate(cases):
        for method, g in ok[ok["case"] == case].groupby("method", sort=False):
            g = g.sort_values("x")
            for i, (column, _) in enumerate(QUALITY):
                (line,) = axes[i, j].plot(g["x"], g[column], marker="o", ms=2.5, lw=1,
                                          label=labels.get(method, method),
                                          color=colors.get(method))
                colors.setdefault(method, line.get_color())
        axes[0, j].set_title(case_labels.get(case, case), fontsize=9)
        axes[-1, j].set_xlabel(axis, fontsize=8)
    x = ok["x"].astype(float)
    for a in axes.flat:
        if len(x) and x.min() > 0 and x.max() / x.min() >= 20:
            a.set_xscale("log")
        a.tick_params(labelsize=7)
        a.grid(True, alpha=0.3)
    for i, (_, name) in enumerate(QUALITY):
        axes[i, 0].set_ylabel(name, fontsize=8)
    handles, names = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, names, loc="lower center", ncol=min(4, len(names)), fontsize=8,
               frameon=False)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout(rect=(0, 0.06, 1, 1))
    _save(fig, path)


def quality_per_second(path, df, labels, case_labels):
    """Mean ρ against seconds (log), one panel per case, a point per method:
    quality per unit of time (rows with status ok and a time)."""
    ok = df[(df["status"] == "ok") & df["seconds"].notna() & (df["seconds"] > 0)]
    cases = list(dict.fromkeys(ok["case"]))
    fig, axes = plt.subplots(1, max(1, len(cases)), figsize=(3.4 * max(1, len(cases)), 3.2),
                             squeeze=False)
    colors: dict[str, str] = {}
    for j, case in enumerate(cases):
        a = axes[0, j]
        for r in ok[ok["case"] == case].itertuples():
            (line,) = a.plot([r.seconds], [r.rho_mean], "o", ms=5, color=colors.get(r.method),
                             label=labels.get(r.method, r.method))
            colors.setdefault(r.method, line.get_color())
        a.set_xscale("log")
        a.set_title(case_labels.get(case, case), fontsize=9)
        a.set_xlabel("seconds", fontsize=8)
        a.tick_params(labelsize=7)
        a.grid(True, alpha=0.3)
    axes[0, 0].set_ylabel("mean ρ", fontsize=8)
    handles, names = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, names, loc="lower center", ncol=min(5, len(names)), fontsize=8,
               frameon=False)
    fig.tight_layout(rect=(0, 0.16, 1, 1))
    _save(fig, path)
