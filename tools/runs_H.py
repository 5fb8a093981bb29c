#!/usr/bin/python3
"""Does the filtered drag correction at one phi-bar depend on the run it was measured in? (issue 27: the dense runs)

A closure in phi-bar (and the filter size) alone assumes that a coarse cell at phi-bar = 0.2 has the same
H = 1 - beta_bar/beta_micro whether it sits in a dilute run (a cluster) or a dense one (the emulsion around a void).
This tool sets the runs' measured H_grid side by side on each coarse grid (cgd-filter --grids: the grid's own
operator) and measures each run against the others in the phi-bar bins they share:

  vs others  the particle-weighted mean and rms over the run's bins (>= --min-count samples in the run and in the
             others) of H_run - H_others, with H_others = 1 - sum N / sum beta_micro u_slip pooled over the OTHER
             files' per-snapshot sums (/grids/<N>/per_snapshot: what cgd-fit pools), i.e. what a phi-bar-only table
             of the other runs says of this run's cells;
  vs model   (with --model, a spline model of cgd-fit) the particle-weighted mean over all the run's bins
             (>= --min-count) of H_run - h(phi)/(1 + a(phi) F^n), h and a
             interpolated linearly in the model's /bands grid (held at its ends: the engine's extrapolation
             above phi_max; below phi_crit the engine takes h linearly to 0, this tool holds the first band value).

Every file holds one run (cgd-filter of one run directory, as data/filtered/ ships them); all are filtered with
the same phi-bar bins. A run's offset outside +-2 x its rms is what a phi-bar-only closure cannot give.

usage: /usr/bin/python3 tools/runs_H.py FILTERED.h5 FILTERED.h5 [...] [--grids 8,4] [--min-count 200]
           [--model MODEL.h5] [-o PREFIX]
  -o PREFIX: also PREFIX.md (the tables) and PREFIX.png (H_grid against phi-bar per grid, one curve per run with its
  95 % band, Radl 2014 dashed, the model solid black).
Exit status 0; 2 for a file that is not a one-run filtered file with the grids asked, or files with other bins.
(Debian's h5py/numpy/matplotlib belong to /usr/bin/python3.)"""
import argparse
import os
import sys

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from plot_filtered import radl2014  # noqa: E402


def fail(msg):
    print(f"runs_H.py: {msg}", file=sys.stderr)
    sys.exit(2)


def read_run(path, grids):
    """(<phi> of the run, bin edges, {N: {F, phi_mean, H, H_low, H_high, count, num, micro}}) of a filtered file."""
    try:
        f = h5py.File(path, "r")
    except OSError as e:
        fail(f"{path}: not a readable HDF5 file ({e})")
    with f:
        if f.attrs.get("cgd_format") not in ("filtered", b"filtered"):
            fail(f"{path}: cgd_format is {f.attrs.get('cgd_format')!r}, expected 'filtered'")
        phis = f["runs/mean_solids_fraction"][()] if "runs/mean_solids_fraction" in f else []
        if len(phis) != 1:
            fail(f"{path}: holds {len(phis)} runs (runs/mean_solids_fraction); one run per file is compared")
        edges = f["bins/phi_edges"][()] if "bins/phi_edges" in f else None
        if edges is None:
            fail(f"{path}: /bins/phi_edges missing")
        out = {}
        for n in grids:
            name = f"grids/{n}"
            if name not in f:
                fail(f"{path}: no /{name} (filter it with cgd-filter --grids ...,{n})")
            g = f[name]
            need = ("H", "H_low", "H_high", "count", "phi_mean", "per_snapshot/numerator", "per_snapshot/micro")
            for key in need:
                if key not in g:
                    fail(f"{path}: /{name}/{key} missing")
            out[n] = {"F": float(g.attrs["F"]), **{k: g[k][()] for k in need[:5]},
                      "num": g["per_snapshot/numerator"][()].sum(axis=0),
                      "micro": g["per_snapshot/micro"][()].sum(axis=0)}
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


def offsets(runs, n, min_count, H_model=None):
    """Per run: (bins, phi-bar range, mean and rms of H - H_others, mean of H - model) on grid n (particle-weighted)."""
    rows = []
    for i, (phi_run, g) in enumerate(runs):
        num = sum(r[1][n]["num"] for j, r in enumerate(runs) if j != i)
        micro = sum(r[1][n]["micro"] for j, r in enumerate(runs) if j != i)
        count = sum(r[1][n]["count"] for j, r in enumerate(runs) if j != i)
        m = (g[n]["count"] >= min_count) & (count >= min_count) & (micro != 0)
        w = g[n]["count"][m].astype(float)
        if w.sum() == 0:
            rows.append((phi_run, 0, None, None, None, None))
            continue
        others = 1.0 - num[m] / micro[m]
        d = g[n]["H"][m] - others
        mean, rms = float((w * d).sum() / w.sum()), float(np.sqrt((w * d * d).sum() / w.sum()))
        vs_model = None
        if H_model is not None:
            mm = g[n]["count"] >= min_count
            wm = g[n]["count"][mm].astype(float)
            dm = g[n]["H"][mm] - H_model(g[n]["phi_mean"][mm], g[n]["F"])
            vs_model = float((wm * dm).sum() / wm.sum())
        x = g[n]["phi_mean"][m]
        rows.append((phi_run, int(m.sum()), (float(x.min()), float(x.max())), mean, rms, vs_model))
    return rows


def table(runs, grids, min_count, H_model):
    lines = []
    for n in grids:
        F = runs[0][1][n]["F"]
        lines += [f"grid of {n} cells across (F = {F:.3f}): H_run - H_others in the bins both hold (>= {min_count} "
                  f"samples), particle-weighted", "",
                  "| run <phi> | bins | phi-bar | mean | rms |" + (" mean H_run - model |" if H_model else ""),
                  "|---|---|---|---|---|" + ("---|" if H_model else "")]
        for phi_run, nb, rng, mean, rms, vm in offsets(runs, n, min_count, H_model):
            if nb == 0:
                lines.append(f"| {phi_run:.2f} | 0 | – | – | – |" + (" – |" if H_model else ""))
                continue
            lines.append(f"| {phi_run:.2f} | {nb} | {rng[0]:.3f}–{rng[1]:.3f} | {mean:+.3f} | {rms:.3f} |"
                         + (f" {vm:+.3f} |" if H_model else ""))
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
        for phi_run, g in runs:
            m = g[n]["count"] >= min_count
            line, = ax.plot(g[n]["phi_mean"][m], g[n]["H"][m], "o-", ms=2.5, lw=1, label=f"run <phi> = {phi_run:.2f}")
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
    runs, edges0 = [], None
    for path in a.files:
        phi_run, edges, g = read_run(path, grids)
        if edges0 is None:
            edges0 = edges
        elif len(edges) != len(edges0) or not np.allclose(edges, edges0):
            fail(f"{path}: its phi-bar bins differ from {a.files[0]}'s (filter both with the same --bins)")
        runs.append((phi_run, g))
    runs.sort(key=lambda r: r[0])
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
