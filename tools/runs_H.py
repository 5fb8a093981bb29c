#!/usr/bin/python3
"""Does the filtered drag correction at one phi-bar depend on the run it was measured in? (issue 27: the dense runs)

A closure in phi-bar (and the filter size) alone assumes that a coarse cell at phi-bar = 0.2 has the same
H = 1 - beta_bar/beta_micro whether it sits in a dilute run (a cluster) or a dense one (the emulsion around a void).
This tool sets the runs' measured H_grid side by side on each coarse grid (cgd-filter --grids: the grid's own
operator) and measures each run against the others in the phi-bar bins they share:

  vs others  the particle-weighted mean and rms over the run's bins (>= --min-count samples in the run and in the
             others) of H_run - H_others, with H_others = 1 - sum N / sum beta_micro u_slip pooled over the OTHER
             files' per-snapshot sums (/grids/<N>/per_snapshot), as `cgd-fit --grid-table N` pools them: what the
             perfect phi-bar table of the other runs says of this run's cells; beside it the run's own band, the
             particle-weighted mean half-width (H_high - H_low)/2 of its 95 % bootstrap intervals in those bins
             (an offset well outside it is not the run's sampling noise);
  vs model   (with --model, a spline model of cgd-fit) the particle-weighted mean and rms over ALL the run's bins
             (>= --min-count) of H_run - h(phi)/(1 + a(phi) F^n), h and a interpolated linearly in the model's
             /bands grid (which starts at phi = 0 and ends at phi_max: the engine's ramp below phi_crit, its held
             ends above).

Every file holds one run (cgd-filter of one run directory, as data/filtered/ ships them); all are filtered with
the same phi-bar bins and have the grids asked with the same cells in d_p (files of two boxes are refused: their
grids of N cells across are different filters).

usage: /usr/bin/python3 tools/runs_H.py FILTERED.h5 FILTERED.h5 [...] [--grids 8,4] [--min-count 200]
           [--model MODEL.h5] [-o PREFIX]
  -o PREFIX: also PREFIX.md (the tables) and PREFIX.png (H_grid against phi-bar per grid, one curve per run with its
  95 % band, Radl 2014 dashed, the model solid black).
Exit status 0; 2 for a file that is not a one-run filtered file with the grids asked, or files with other bins.
(Debian's h5py/numpy/matplotlib belong to /usr/bin/python3.)"""
import argparse
import collections
import math
import os
import sys

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from compare_boxes import fail, read_grids  # noqa: E402  (fail: exit 2 named by the running tool)
from plot_filtered import radl2014  # noqa: E402


def read_run(path, grids):
    """(<phi> of the run, phi-bar bin edges, {N: compare_boxes.read_grids' datasets + num, micro: the per-snapshot
    sums totalled}) of a one-run filtered file, for the grids N asked."""
    all_grids = read_grids(path)  # exits 2 naming the file for what is not a filtered file with grids
    with h5py.File(path, "r") as f:
        phis = f["runs/mean_solids_fraction"][()] if "runs/mean_solids_fraction" in f else []
        if len(phis) != 1:
            fail(f"{path}: holds {len(phis)} runs (runs/mean_solids_fraction); one run per file is compared")
        if "bins/phi_edges" not in f:
            fail(f"{path}: /bins/phi_edges missing")
        edges = f["bins/phi_edges"][()]
        out = {}
        for n in grids:
            if n not in all_grids:
                fail(f"{path}: no /grids/{n} (filter it with cgd-filter --grids ...,{n})")
            sums = {}
            for key in ("numerator", "micro"):
                name = f"grids/{n}/per_snapshot/{key}"
                if name not in f:
                    fail(f"{path}: /{name} missing")
                sums[key] = f[name][()].sum(axis=0)
            out[n] = {**all_grids[n], "num": sums["numerator"], "micro": sums["micro"]}
        return float(phis[0]), edges, out


def model_H(path):
    """H(phi, F) of a spline model file from its /bands grid (linear in phi, held at the ends)."""
    try:
        with h5py.File(path, "r") as f:
            phi, h, a = (f["bands"][k][()] for k in ("phi", "h", "a"))
            n = float(f.attrs.get("width_exponent", 1.0))
    except (OSError, KeyError) as e:
        fail(f"{path}: not a spline model file with /bands phi, h, a ({e})")
    return lambda x, F: np.interp(x, phi, h) / (1.0 + np.interp(x, phi, a) * F ** n)


def weighted(d, w):
    """(mean, rms) of d weighted by w."""
    return float((w * d).sum() / w.sum()), float(np.sqrt((w * d * d).sum() / w.sum()))


Row = collections.namedtuple("Row", "label bins phi_range mean rms band model_mean model_rms")


def offsets(runs, n, min_count, H_model=None):
    """Per run (label, grids): a Row on grid n, particle-weighted: H - H_others in the bins both hold (bins, phi-bar
    range, mean, rms, the run's mean band half-width) and H - model over all the run's bins (None without a model)."""
    rows = []
    for i, (label, g) in enumerate(runs):
        others = [r[1][n] for j, r in enumerate(runs) if j != i]
        num, micro = sum(o["num"] for o in others), sum(o["micro"] for o in others)
        count = sum(o["count"] for o in others)
        own = g[n]
        model_mean = model_rms = None
        if H_model is not None:
            mm = own["count"] >= min_count
            if mm.any():
                model_mean, model_rms = weighted(own["H"][mm] - H_model(own["phi_mean"][mm], own["F"]),
                                                 own["count"][mm].astype(float))
        m = (own["count"] >= min_count) & (count >= min_count) & (micro != 0)
        if not m.any():
            rows.append(Row(label, 0, None, None, None, None, model_mean, model_rms))
            continue
        w = own["count"][m].astype(float)
        mean, rms = weighted(own["H"][m] - (1.0 - num[m] / micro[m]), w)
        band = weighted(0.5 * (own["H_high"][m] - own["H_low"][m]), w)[0]
        x = own["phi_mean"][m]
        rows.append(Row(label, int(m.sum()), (float(x.min()), float(x.max())), mean, rms, band, model_mean, model_rms))
    return rows


def table(runs, grids, min_count, H_model):
    lines = []
    for n in grids:
        F, dx = runs[0][1][n]["F"], runs[0][1][n]["dx_over_dp"]
        lines += [f"grid of {n} cells across ({dx:.2f} d_p, F = {F:.3f}): H_run - H_others in the bins both hold "
                  f"(>= {min_count} samples), particle-weighted; the run's band: its mean 95 % half-width there"
                  + ("; H_run - model over all the run's bins" if H_model else ""), "",
                  "| run | bins | phi-bar | mean | rms | band |" + (" model: mean | rms |" if H_model else ""),
                  "|---|---|---|---|---|---|" + ("---|---|" if H_model else "")]
        for r in offsets(runs, n, min_count, H_model):
            tail = (f" {r.model_mean:+.3f} | {r.model_rms:.3f} |" if r.model_mean is not None else " – | – |") \
                if H_model else ""
            if r.bins == 0:
                lines.append(f"| {r.label} | 0 | – | – | – | – |" + tail)
            else:
                lines.append(f"| {r.label} | {r.bins} | {r.phi_range[0]:.3f}–{r.phi_range[1]:.3f} | {r.mean:+.3f} | "
                             f"{r.rms:.3f} | {r.band:.3f} |" + tail)
        lines.append("")
    return "\n".join(lines)


def plot(runs, grids, min_count, H_model, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axs = plt.subplots(1, len(grids), figsize=(5.5 * len(grids), 4.3), squeeze=False)
    xs = np.linspace(0.005, 0.6, 200)
    for ax, n in zip(axs[0], grids):
        F = runs[0][1][n]["F"]
        for label, g in runs:
            m = g[n]["count"] >= min_count
            line, = ax.plot(g[n]["phi_mean"][m], g[n]["H"][m], "o-", ms=2.5, lw=1, label=f"run {label}")
            ax.fill_between(g[n]["phi_mean"][m], g[n]["H_low"][m], g[n]["H_high"][m], color=line.get_color(), alpha=0.2)
        ax.plot(xs, radl2014(xs, F), "k--", lw=1, label="Radl 2014")
        if H_model is not None:
            ax.plot(xs, H_model(xs, F), "k-", lw=1.5, label="model")
        ax.axhline(0, color="grey", lw=0.5)
        ax.set(xlabel=r"$\bar\phi_p$", ylabel=r"$H = 1 - \bar\beta/\beta_{micro}$", ylim=(-0.6, 1.0),
               title=f"{n} cells across (F = {F:.3f})")
    axs[0][0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=100)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("files", nargs="+")
    ap.add_argument("--grids", default="8,4", help="coarse grids (cells across) to compare (default 8,4)")
    ap.add_argument("--min-count", type=int, default=200, help="samples a bin needs (default 200)")
    ap.add_argument("--model", default=None, help="a spline model file (cgd-fit) drawn and measured against")
    ap.add_argument("-o", "--output", default=None, help="PREFIX of PREFIX.md and PREFIX.png")
    a = ap.parse_args()
    if len(a.files) < 2:
        fail("give at least two filtered files (each run is compared with the others)")
    try:
        grids = [int(x) for x in a.grids.split(",")]
    except ValueError:
        fail(f"--grids {a.grids}: expected cells across, e.g. 8,4")
    read = [(path, *read_run(path, grids)) for path in a.files]
    path0, _, edges0, grids0 = read[0]
    for path, _, edges, g in read[1:]:
        if len(edges) != len(edges0) or not np.allclose(edges, edges0):
            fail(f"{path}: its phi-bar bins differ from {path0}'s (filter both with the same --bins)")
        for n in grids:
            if not math.isclose(g[n]["dx_over_dp"], grids0[n]["dx_over_dp"], rel_tol=0.01):
                fail(f"{path}: /grids/{n} has cells of {g[n]['dx_over_dp']:.2f} d_p, {path0}'s "
                     f"{grids0[n]['dx_over_dp']:.2f} d_p: runs of two boxes (tools/compare_boxes.py sets boxes side by side)")
    read.sort(key=lambda r: r[1])
    phis = [r[1] for r in read]
    # a run is labelled by its <phi>, and by its file too when another run has the same <phi>
    runs = [(f"<phi> = {phi:.2f}" + (f" ({os.path.basename(path)})" if phis.count(phi) > 1 else ""), g)
            for path, phi, _, g in read]
    H_model = model_H(a.model) if a.model else None
    text = table(runs, grids, a.min_count, H_model)
    print(text)
    if a.output:
        with open(a.output + ".md", "w") as f:
            f.write(text + "\n")
        plot(runs, grids, a.min_count, H_model, a.output + ".png")
        print(f"wrote {a.output}.md, {a.output}.png")


if __name__ == "__main__":
    main()
