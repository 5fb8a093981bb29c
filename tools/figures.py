#!/usr/bin/python3
"""The paper's Figures 2 and 3 from a study file (tools/study.py, Makefile.pipeline `study`):

  Figure 2: time-averaged slip <u_slip,y>/u_t against the fluid cell size Delta/d_p (alpha = 1): the resolved
            reference, coarse CFD-DEM with the micro law (open), the fitted model, Radl 2014 and the perfect closure;
  Figure 3: the same against the parcel size alpha on the coarsest grid (CFD-DPM), the resolved value as a band.
One panel column per solids fraction. Each point is a configuration's mean over its R realisations; error bars
are the study's slip_se (the larger of sd/sqrt(R) and the batch-means errors; R = 1: batch means only; the
resolved band: the pooled reference's). Prints the tables with R.

usage: /usr/bin/python3 tools/figures.py STUDY.h5 [-o PREFIX]   (writes PREFIX_figure2.png, PREFIX_figure3.png)"""
import argparse
import os
import sys

import h5py
import numpy as np


def load(path):
    f = h5py.File(path, "r")
    if f.attrs.get("cgd_format") != "study":
        sys.exit(f"figures: {path}: cgd_format is {f.attrs.get('cgd_format')!r}, expected 'study'")
    dec = lambda v: v.decode() if isinstance(v, bytes) else str(v)
    if int(f.attrs.get("cgd_format_version", 1)) < 2:
        sys.exit(f"figures: {path}: a version-1 study (one row per run); rerun tools/study.py for version 2")
    rows = []
    for i in range(len(f["phi"])):
        rows.append({k: (dec(f[k][i]) if f[k].dtype.kind in "OS" else float(f[k][i])) for k in
                     ["phi", "cell_over_dp", "alpha", "drag", "R", "slip", "slip_se", "ref_slip", "ref_se", "error",
                      "error_se", "cost", "kind"]})
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("study")
    ap.add_argument("-o", "--prefix", default=None)
    a = ap.parse_args()
    rows = load(a.study)
    prefix = a.prefix or os.path.splitext(a.study)[0]
    phis = sorted({r["phi"] for r in rows})
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    def coarse_curves(ax, candidates, x, x_format):
        """The coarse configurations among `candidates` against `x`: one curve and table rows per law (the micro
        law open; the parcel fit's modelraw runs left out, unless there are no model runs: then they are the
        fitted model, drawn as such with c_corr off)."""
        has_model = any(r["kind"] == "coarse" and r["drag"] == "model" for r in candidates)
        raw = () if has_model else (("modelraw", "b", "fitted model (c_corr off)", dict()),)
        for name, color, label, style in (("micro", "k", "micro law", dict(mfc="white")),
                                          ("model", "b", "fitted model", dict()), *raw,
                                          ("radl2014", "g", "Radl 2014", dict(marker="v")),
                                          ("perfect", "m", "perfect closure", dict(marker="*", ms=9)),
                                          ("drift", "c", "drift closure", dict(marker="D")),
                                          ("wide", "tab:orange", "perfect table of a grid twice as wide", dict(marker="P"))):
            pts = sorted([r for r in candidates if r["kind"] == "coarse" and r["drag"] == name], key=lambda r: r[x])
            for r in pts:
                print(f"{r['phi']:5.2f} {r[x]:{x_format}} {name:>9} {r['R']:2.0f} {r['slip']:7.3f} +- {r['slip_se']:5.3f} "
                      f"{100 * r['error']:6.1f} +- {100 * r['error_se']:4.1f} {r['cost']:9.3g}")
            if pts:
                # a line joins two or more points; a single point is a marker alone (in the legend too)
                ax.errorbar([r[x] for r in pts], [r["slip"] for r in pts], yerr=[r["slip_se"] for r in pts],
                            linestyle="-" if len(pts) > 1 else "none", marker=style.get("marker", "o"), color=color,
                            label=label, **{k: v for k, v in style.items() if k != "marker"})

    # ---- Figure 2 ----
    # a panel per solids fraction with alpha = 1 coarse runs (Makefile.pipeline ALPHA1_PHIS); every one if none has
    phis2 = [p for p in phis if any(r["phi"] == p and r["kind"] == "coarse" and r["alpha"] == 1 for r in rows)] or phis
    fig, axes = plt.subplots(1, len(phis2), figsize=(4 * len(phis2), 3.8), squeeze=False)
    print("Figure 2: <u_slip,y>/u_t against Delta/d_p (alpha = 1)")
    print(f"{'phi':>5} {'Delta/d_p':>9} {'law':>9} {'R':>2} {'slip/u_t':>16} {'error %':>14} {'core-s/s':>9}")
    for ax, phi in zip(axes[0], phis2):
        res = [r for r in rows if r["phi"] == phi and r["kind"] == "resolved"]
        for r in res:
            ax.errorbar(r["cell_over_dp"], r["slip"], yerr=r["slip_se"], fmt="s", color="r", label="resolved")
            print(f"{phi:5.2f} {r['cell_over_dp']:9.2f} {'resolved':>9} {r['R']:2.0f} {r['slip']:7.3f} +- {r['slip_se']:5.3f} {'':>14} {r['cost']:9.3g}")
        coarse_curves(ax, [r for r in rows if r["phi"] == phi and r["alpha"] == 1], "cell_over_dp", "9.2f")
        ax.set_xlabel("Δ_fluid / d_p")
        ax.set_title(f"⟨φ⟩ = {phi:g}", fontsize=10)
        ax.set_ylabel("⟨u_slip,y⟩ / u_t")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(prefix + "_figure2.png", dpi=120)
    # ---- Figure 3 ----
    fig, axes = plt.subplots(1, len(phis), figsize=(4 * len(phis), 3.8), squeeze=False)
    coarsest = max([r["cell_over_dp"] for r in rows if r["kind"] == "coarse"], default=0)
    print(f"\nFigure 3: <u_slip,y>/u_t against alpha (Delta = {coarsest:.3g} d_p)")
    print(f"{'phi':>5} {'alpha':>5} {'law':>9} {'R':>2} {'slip/u_t':>16} {'error %':>14} {'core-s/s':>9}")
    for ax, phi in zip(axes[0], phis):
        for r in [r for r in rows if r["phi"] == phi and r["kind"] == "resolved"]:
            ax.axhspan(r["slip"] - r["slip_se"], r["slip"] + r["slip_se"], color="r", alpha=0.2, label="resolved")
            ax.axhline(r["slip"], color="r", lw=1)
        coarse_curves(ax, [r for r in rows if r["phi"] == phi and abs(r["cell_over_dp"] - coarsest) < 1e-6], "alpha", "5.0f")
        ax.set_xlabel("parcel size α")
        # ticks at the parcel sizes run (alpha is an integer: no 1.5 or 2.5)
        ax.set_xticks(sorted({r["alpha"] for r in rows if r["phi"] == phi and r["kind"] == "coarse"
                              and abs(r["cell_over_dp"] - coarsest) < 1e-6}))
        ax.set_title(f"⟨φ⟩ = {phi:g}, Δ = {coarsest:.3g} d_p", fontsize=10)
        ax.set_ylabel("⟨u_slip,y⟩ / u_t")
    # one legend, outside the panels: inside one it hid points
    handles, labels = max((ax.get_legend_handles_labels() for ax in axes[0]), key=lambda hl: len(hl[1]))
    axes[0][-1].legend(handles, labels, fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    fig.tight_layout()
    fig.savefig(prefix + "_figure3.png", dpi=120)
    print(f"\nwrote {prefix}_figure2.png, {prefix}_figure3.png")


if __name__ == "__main__":
    main()
