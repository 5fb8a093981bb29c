#!/usr/bin/python3
"""The filtered drag correction of two filtered files side by side on coarse grids of the same cell size in d_p
(issue 26: does the model depend on the box?). A grid of file A and one of file B are paired when their cells
(/grids/<N>@dx_over_dp) agree within 1 %: the paper's box (106 d_p) on 16, 8, 6 cells across and the half box
(53 d_p) on 8, 4, 3 have cells of 6.6, 13.3 and 17.7 d_p. Both grids' H is the coarse grid's own operator
(cgd-filter --grids: TSC deposit and interpolation), so at equal cell size the two boxes see the same filter,
and F = L_char/Delta is the same.

Per pair and phi bin holding at least --min-count samples in both files: H of A and of B with their 95 %
block-bootstrap bands, the difference B - A and its z = difference / combined standard error (each file's
bootstrap H_stderr), and the published Radl 2014 H at that phi and F (tools/plot_filtered.py). Then per pair
the samples-weighted mean difference and the chi2/dof of the differences over the common bins.

usage: /usr/bin/python3 tools/compare_boxes.py A.h5 B.h5 [--labels A,B] [--min-count 200] [-o PREFIX]
  -o PREFIX: also PREFIX.md (the tables) and PREFIX.png (H against phi-bar per pair, bands shaded, Radl 2014 dashed).
Exit status 0; 2 for a file that is not a filtered file with grids, or no pair of grids of equal cells.
(Debian's h5py/numpy/matplotlib belong to /usr/bin/python3.)"""
import argparse
import collections
import math
import os
import sys

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from plot_filtered import radl2014  # noqa: E402


def fail(msg):
    """Exit 2 with MSG, named by the tool that runs (tools/runs_H.py reads its files through read_grids)."""
    print(f"{os.path.basename(sys.argv[0])}: {msg}", file=sys.stderr)
    sys.exit(2)


Summary = collections.namedtuple("Summary", "bins mean_diff chi2_dof")  # of the common bins of a pair
GRID_DATASETS = ("H", "H_low", "H_high", "H_stderr", "count", "phi_mean")  # what is read of each /grids/<N>


def read_grids(path):
    """{cells across: {dx_over_dp, F, phi_mean, H, H_low, H_high, H_stderr, count}} of a filtered file (its names)."""
    try:
        f = h5py.File(path, "r")
    except OSError as e:
        fail(f"{path}: not a readable HDF5 file ({e})")
    with f:
        fmt = f.attrs.get("cgd_format")
        if fmt not in ("filtered", b"filtered"):
            fail(f"{path}: cgd_format is {fmt!r}, expected 'filtered'")
        if "grids" not in f or len(f["grids"]) == 0:
            fail(f"{path}: no /grids (filter it with cgd-filter --grids)")
        out = {}
        for name, g in f["grids"].items():
            for key in GRID_DATASETS:
                if key not in g:
                    fail(f"{path}: /grids/{name}/{key} missing")
            out[int(name)] = {"dx_over_dp": float(g.attrs["dx_over_dp"]), "F": float(g.attrs["F"]),
                              **{key: g[key][:] for key in GRID_DATASETS}}
        return out


def pairs_of(a, b):
    """(cells of A, cells of B) whose cell sizes in d_p agree within 1 %, finest first."""
    out = []
    for na, ga in a.items():
        for nb, gb in b.items():
            if abs(ga["dx_over_dp"] / gb["dx_over_dp"] - 1) < 0.01:
                out.append((na, nb))
    return sorted(out, key=lambda p: a[p[0]]["dx_over_dp"])


def compare(ga, gb, min_count):
    """Per common bin: (phi, H_a, lo_a, hi_a, H_b, lo_b, hi_b, diff, z, count_a, count_b); and the summary."""
    n = min(len(ga["H"]), len(gb["H"]))
    rows = []
    for i in range(n):
        if ga["count"][i] < min_count or gb["count"][i] < min_count:
            continue
        if not (np.isfinite(ga["H"][i]) and np.isfinite(gb["H"][i])):
            continue
        diff = gb["H"][i] - ga["H"][i]
        se = math.hypot(ga["H_stderr"][i], gb["H_stderr"][i])
        phi = 0.5 * (ga["phi_mean"][i] + gb["phi_mean"][i])
        rows.append(dict(phi=phi, a=ga["H"][i], a_lo=ga["H_low"][i], a_hi=ga["H_high"][i], b=gb["H"][i], b_lo=gb["H_low"][i],
                         b_hi=gb["H_high"][i], diff=diff, z=diff / se if se > 0 else math.nan,
                         ca=int(ga["count"][i]), cb=int(gb["count"][i]),
                         radl=float(radl2014(phi, ga["F"])[0])))
    if not rows:
        return rows, None
    w = np.array([min(r["ca"], r["cb"]) for r in rows], dtype=float)
    d = np.array([r["diff"] for r in rows])
    z = np.array([r["z"] for r in rows])
    z = z[np.isfinite(z)]
    return rows, Summary(len(rows), float(np.sum(w * d) / np.sum(w)), float(np.mean(z ** 2)) if len(z) else math.nan)


def tables(a, b, labels, pairs, min_count):
    out = [f"H = 1 - beta_bar/beta_micro on coarse grids of equal cells: {labels[0]} against {labels[1]} "
           f"(bins with >= {min_count} samples in both; [95 % band]; z = difference / combined standard error)"]
    summaries = []
    for na, nb in pairs:
        ga, gb = a[na], b[nb]
        rows, s = compare(ga, gb, min_count)
        out += ["", f"### {ga['dx_over_dp']:.2f} d_p cells (F = {ga['F']:.3f}): {labels[0]} {na} cells across, "
                f"{labels[1]} {nb}", "",
                f"| φ̄ | {labels[0]} H | {labels[1]} H | {labels[1]} − {labels[0]} | z | Radl 2014 H | samples |",
                "|---|---|---|---|---|---|---|"]
        for r in rows:
            out.append(f"| {r['phi']:.3f} | {r['a']:.3f} [{r['a_lo']:.3f}, {r['a_hi']:.3f}] | "
                       f"{r['b']:.3f} [{r['b_lo']:.3f}, {r['b_hi']:.3f}] | {r['diff']:+.3f} | {r['z']:+.1f} | "
                       f"{r['radl']:.3f} | {r['ca']} / {r['cb']} |")
        summaries.append((ga, na, nb, s))
    out += ["", f"| cells (d_p) | {labels[0]} / {labels[1]} cells across | common bins | mean difference "
            f"({labels[1]} − {labels[0]}, sample-weighted) | χ²/dof |", "|---|---|---|---|---|"]
    for ga, na, nb, s in summaries:
        if s is None:
            out.append(f"| {ga['dx_over_dp']:.2f} | {na} / {nb} | 0 | – | – |")
        else:
            out.append(f"| {ga['dx_over_dp']:.2f} | {na} / {nb} | {s.bins} | {s.mean_diff:+.3f} | {s.chi2_dof:.2f} |")
    return "\n".join(out)


def plot(a, b, labels, pairs, min_count, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    cols = min(3, len(pairs))
    rows = (len(pairs) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.6 * rows), squeeze=False)
    for ax in axes.flat[len(pairs):]:
        ax.set_visible(False)
    for ax, (na, nb) in zip(axes.flat, pairs):
        shown = [0.0]  # the H values drawn: the axis is set by them, not by a sparse bin's wide band
        for g, label, colour in ((a[na], labels[0], "C0"), (b[nb], labels[1], "C1")):
            keep = (g["count"] >= min_count) & np.isfinite(g["H"])
            ax.fill_between(g["phi_mean"][keep], g["H_low"][keep], g["H_high"][keep], color=colour, alpha=0.25, lw=0)
            ax.plot(g["phi_mean"][keep], g["H"][keep], "o-", ms=2.5, color=colour, label=label)
            shown.extend(g["H"][keep].tolist())
        lo, hi = min(shown), max(max(shown), 1.0)
        ax.set_ylim(lo - 0.1 * (hi - lo), hi + 0.1 * (hi - lo))
        top = max(float(np.nanmax(g["phi_mean"][g["count"] >= min_count], initial=0.0)) for g in (a[na], b[nb]))
        phi = np.linspace(0.005, max(0.05, top), 100)
        ax.plot(phi, radl2014(phi, a[na]["F"]), "k--", lw=1, label="Radl 2014")
        ax.set_title(f"{a[na]['dx_over_dp']:.1f} $d_p$ cells")
        ax.set_xlabel(r"$\bar\phi$")
        ax.set_ylabel("H")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("a")
    ap.add_argument("b")
    ap.add_argument("--labels", default=None, help="two labels, comma-separated (default: the files' names)")
    ap.add_argument("--min-count", type=int, default=200, help="samples a bin needs in both files (default 200)")
    ap.add_argument("-o", dest="prefix", help="write PREFIX.md and PREFIX.png")
    args = ap.parse_args()
    labels = (args.labels.split(",") if args.labels else
              [os.path.splitext(os.path.basename(p))[0] for p in (args.a, args.b)])
    if len(labels) != 2:
        fail(f"--labels {args.labels}: give two labels")
    a, b = read_grids(args.a), read_grids(args.b)
    pairs = pairs_of(a, b)
    if not pairs:
        fail(f"no grid of {args.a} has the cell size of one of {args.b} (cells in d_p: "
             f"{sorted(round(g['dx_over_dp'], 2) for g in a.values())} and "
             f"{sorted(round(g['dx_over_dp'], 2) for g in b.values())})")
    text = tables(a, b, labels, pairs, args.min_count)
    print(text)
    if args.prefix:
        with open(args.prefix + ".md", "w") as f:
            f.write(text + "\n")
        plot(a, b, labels, pairs, args.min_count, args.prefix + ".png")


if __name__ == "__main__":
    main()
