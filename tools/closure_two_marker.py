#!/usr/bin/python3
"""Is the filtered slip the second marker a phi-bar-only drag closure lacks? (issue 28; docs/closure.md
"A second marker: the cell's slip")

Every resolved run is seen on the coarse grid of N cells across through tools/closure_diagnostics.py's operator
(nearest-grid-point deposit of the particles, the fluid's Favre average over the cell). Per particle i in cell c:
  phi_c       the cell's solids fraction;
  D_i         its drag share beta_p (u_i - v_i)_y / (rho_p g): the drag the resolved run gives it, in weights;
  s_c         the cell's slip (u_c - <v>_c)_y / u_t, <v>_c the cell's mean particle velocity;
  s_i         the particle's own slip (u_c - v_i)_y / u_t (what a coarse run's drag law sees of a parcel).
Per phi_c bin of the runs pooled, three closures of the mean drag of the bin's particles given the bin's slips:
  ratio       D = B(phi) s            B = sum D / sum s: the phi-bar-only closure (H(phi) times the micro law)
  cell slip   D = a(phi) + b(phi) s_c least squares over the bin's particles: an affine law in the cell's slip
  own slip    D = a'(phi) + b'(phi) s_i the same in the particle's own slip
and the held-out test: for each run, each closure fitted on the OTHER runs predicts the mean drag of each of the
run's bins (holding at least MIN particles in both) from the run's own mean slip there; printed is the particle-
weighted rms and the worst of (predicted / measured - 1) over the bins. A marker that carries what phi-bar lacks
predicts a run it has not seen; one that does not leaves the ratio closure's error.

usage: /usr/bin/python3 tools/closure_two_marker.py --cells N [--from-tref T] [--every K] [--bin 0.02]
           [--min 3000] [-o PREFIX] RUN RUN [RUN...]
RUN: a resolved run directory (snapshots/*.h5), at least two (the held-out test needs another run to fit on).
--every K uses every K-th snapshot of the window (they are 0.5 t_ref apart and correlated). Writes PREFIX.md and
PREFIX.png (the mean drag against the cell slip in the four most populated phi_c bins, per run, with the pooled
ratio and cell-slip closures) with -o; prints the tables. Exit status 0; 2 for bad arguments or a file that is not a snapshot (the message names it).
"""
import argparse
import collections
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import closure_diagnostics as cd  # noqa: E402


def particles(run, n_cells, from_tref, every):
    """phi_c, D_i, s_c, s_i of every particle of the window's snapshots (every K-th) of one run."""
    phi, drag, cell_slip, own_slip = [], [], [], []
    used = 0
    for path in cd.run_snapshots(run):
        snap = cd.snapshot_cells(path, n_cells, from_tref)
        if snap is None:
            continue
        used += 1
        if (used - 1) % every:
            continue
        u_c, v_c = cd.cell_velocities(snap)
        flat = snap["flat"]
        phi.append(snap["solids"][flat] / snap["cell_volume"])
        drag.append(snap["drag_share"])
        cell_slip.append((u_c - v_c)[flat] / snap["u_t"])
        own_slip.append((u_c[flat] - snap["v_y"]) / snap["u_t"])
    if used == 0:
        cd.fail(f"{run}: no snapshot at or after {from_tref} t_ref")
    return dict(phi=np.concatenate(phi), D=np.concatenate(drag), s_c=np.concatenate(cell_slip),
                s_i=np.concatenate(own_slip))


Fit = collections.namedtuple("Fit", "B a_c b_c a_i b_i n")


def fit(data, sel_of):
    """The three closures of the particles selected (sel_of(run) -> mask) in the runs given, pooled."""
    D = np.concatenate([r["D"][sel_of(r)] for r in data])
    s_c = np.concatenate([r["s_c"][sel_of(r)] for r in data])
    s_i = np.concatenate([r["s_i"][sel_of(r)] for r in data])
    b_c, a_c = np.polyfit(s_c, D, 1)
    b_i, a_i = np.polyfit(s_i, D, 1)
    return Fit(B=D.sum() / s_i.sum(), a_c=a_c, b_c=b_c, a_i=a_i, b_i=b_i, n=len(D))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--cells", type=int, required=True)
    ap.add_argument("--from-tref", type=float, default=20.0)
    ap.add_argument("--every", type=int, default=1)
    ap.add_argument("--bin", type=float, default=0.02)
    ap.add_argument("--min", type=int, default=3000)
    ap.add_argument("-o")
    a = ap.parse_args()
    if len(a.runs) < 2:
        cd.fail("give at least two runs: the held-out test fits on the others")
    if a.cells < 1 or a.every < 1 or not a.bin > 0 or a.min < 2:
        cd.fail("--cells and --every must be >= 1, --bin > 0, --min >= 2")
    data = [particles(r, a.cells, a.from_tref, a.every) for r in a.runs]
    names = [os.path.basename(os.path.normpath(r)) for r in a.runs]
    top = max(float(r["phi"].max()) for r in data)
    edges = np.arange(0.0, top + a.bin, a.bin)
    in_bin = lambda lo: (lambda r: (r["phi"] >= lo) & (r["phi"] < lo + a.bin))  # noqa: E731
    out = [f"Coarse grid of {a.cells} cells across; runs {', '.join(names)}; snapshots from {a.from_tref:g} t_ref "
           f"(every {a.every}); drag D in weights, slips in u_t.", "",
           "| φ_c bin | particles | ratio B | cell slip: a | b | own slip: a' | b' |", "|---|---|---|---|---|---|---|"]
    counts = [sum(int(in_bin(lo)(r).sum()) for r in data) for lo in edges[:-1]]
    pooled = {b: fit(data, in_bin(lo)) for b, lo in enumerate(edges[:-1]) if counts[b] >= a.min}
    for b, f in pooled.items():
        lo = edges[b]
        out.append(f"| {lo:.2f}–{lo + a.bin:.2f} | {f.n} | {f.B:.3f} | {f.a_c:+.3f} | {f.b_c:.3f} | "
                   f"{f.a_i:+.3f} | {f.b_i:.3f} |")
    out += ["", "Held out: each run's bin drag predicted by the closures fitted on the other runs "
            "(particle-weighted rms / worst of predicted/measured − 1):", "",
            "| run | bins | ratio (φ̄ only) | cell slip (φ̄, s_c) | own slip (φ̄, s_i) |", "|---|---|---|---|---|"]
    for k, run in enumerate(data):
        others = [r for j, r in enumerate(data) if j != k]
        errs, weights = {"ratio": [], "cell": [], "own": []}, []
        for lo in edges[:-1]:
            sel = in_bin(lo)(run)
            if sel.sum() < a.min or sum(int(in_bin(lo)(r).sum()) for r in others) < a.min:
                continue
            f = fit(others, in_bin(lo))
            measured = run["D"][sel].mean()
            errs["ratio"].append(f.B * run["s_i"][sel].mean() / measured - 1)
            errs["cell"].append((f.a_c + f.b_c * run["s_c"][sel].mean()) / measured - 1)
            errs["own"].append((f.a_i + f.b_i * run["s_i"][sel].mean()) / measured - 1)
            weights.append(sel.sum())
        if not weights:
            out.append(f"| {names[k]} | 0 | – | – | – |")
            continue
        w = np.array(weights, dtype=float) / sum(weights)
        cell = []
        for key in ("ratio", "cell", "own"):
            e = np.array(errs[key])
            cell.append(f"{100 * np.sqrt(np.sum(w * e * e)):.1f} / {100 * e[np.argmax(np.abs(e))]:+.1f} %")
        out.append(f"| {names[k]} | {len(weights)} | " + " | ".join(cell) + " |")
    text = "\n".join(out)
    print(text)
    if a.o:
        with open(a.o + ".md", "w") as fh:
            fh.write(text + "\n")
        plot(data, names, edges, a, in_bin, counts, pooled, a.o + ".png")
    return 0


def plot(data, names, edges, a, in_bin, counts, pooled, path):
    """Mean D per cell-slip bin (0.1 u_t) of each run, in the four phi_c bins holding the most particles (counts:
    the particles of each bin, pooled: the pooled fits of the bins holding at least --min)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    top = sorted(b for b in np.argsort(counts)[::-1][:4] if b in pooled)
    fig, axes = plt.subplots(1, len(top), figsize=(4 * len(top), 3.6), squeeze=False)
    for ax, b in zip(axes[0], top):
        lo = edges[b]
        f = pooled[b]
        for r, name in zip(data, names):
            sel = in_bin(lo)(r)
            s_bins = np.floor(r["s_c"][sel] / 0.1).astype(int)
            xs, ys = [], []
            for k in np.unique(s_bins):
                m = s_bins == k
                if m.sum() >= max(a.min // 10, 2):
                    xs.append(r["s_c"][sel][m].mean())
                    ys.append(r["D"][sel][m].mean())
            ax.plot(xs, ys, "o", ms=3, label=name)
        x = np.linspace(0, max(2.0, ax.get_xlim()[1]), 20)
        ax.plot(x, f.B * x, "k--", lw=1, label="φ̄ only: B s")
        ax.plot(x, f.a_c + f.b_c * x, "k-", lw=1, label="a + b s_c")
        ax.set_title(f"φ_c {lo:.2f}–{lo + a.bin:.2f}")
        ax.set_xlabel("cell slip s_c / u_t")
        ax.set_ylabel("mean drag / weight")
        ax.set_xlim(left=0)
        ax.set_ylim(bottom=0)
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


if __name__ == "__main__":
    sys.exit(main())
