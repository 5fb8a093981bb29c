#!/usr/bin/python3
"""Draw a filtered file of cgd-filter (cgd_format = "filtered"): the filtered drag correction
H = 1 - beta_bar/beta_micro against the filtered solids fraction, one curve per filter width with its
95 % block-bootstrap band (the shape of Radl & Sundaresan's Figure 1), beside the published Radl 2014
correction h(phi)/(1 + a(phi) F) at the same F (dashed). Also prints the table behind the picture.

usage: /usr/bin/python3 tools/plot_filtered.py FILTERED.h5 [-o H.png] [--min-count N] [--table-phi 0.02,0.05,...]
(Debian's h5py/matplotlib belong to /usr/bin/python3.)"""
import argparse
import os
import sys

import h5py
import numpy as np

import cgd_schema  # tools/cgd_schema.py: the spellings shared with core/schema/

HERE = os.path.dirname(os.path.abspath(__file__))


def radl2014(phi, F):
    """Published Radl & Sundaresan (2014) correction H = h(phi) / (1 + a(phi) F), with h and a from
    tools/plot_model.py (the piecewise cubics of data/reference/radl2014-filtered-drag.csv)."""
    h, a = _radl_curves()
    phi = np.atleast_1d(phi)
    return h(phi) / (1.0 + a(phi) * F)


def _radl_curves():
    if not hasattr(_radl_curves, "cached"):
        sys.path.insert(0, HERE)
        from plot_model import radl2014 as curves
        _radl_curves.cached = curves()
    return _radl_curves.cached


class _NoAxes:
    """Stands in for matplotlib's axes when only the table is wanted."""

    def __getattr__(self, name):
        return lambda *args, **kwargs: None


def widths(f):
    names = sorted([k for k in f if k.startswith("width_")], key=lambda k: f[k].attrs["width_m"])
    return names + (["whole_box"] if "whole_box" in f else [])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("file")
    ap.add_argument("-o", "--output", default=None, help="PNG to write (default: FILE with .png)")
    ap.add_argument("--min-count", type=int, default=200, help="bins with fewer samples are not drawn (default 200)")
    ap.add_argument("--no-plot", action="store_true", help="print the table only")
    ap.add_argument("--table-phi", default="0.02,0.05,0.08,0.1,0.15,0.2", help="phi_bar values of the printed table")
    a = ap.parse_args()
    try:
        f = h5py.File(a.file, "r")
    except OSError as e:
        sys.exit(f"plot_filtered: {a.file}: cannot open ({e})")
    if f.attrs.get("cgd_format") != "filtered":
        sys.exit(f"plot_filtered: {a.file}: cgd_format is {f.attrs.get('cgd_format')!r}, expected 'filtered'")
    if a.no_plot:
        plt = None
        ax = _NoAxes()
        colors = ["k"]
    else:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(7.5, 5))
        colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    table_phi = [float(x) for x in a.table_phi.split(",")]
    print(f"{a.file}: H = 1 - beta_bar/beta_micro ({cgd_schema.micro_law(f.attrs)}), 95 % block-bootstrap intervals; "
          f"Radl 2014 = h/(1 + a F) at the same F")
    print(f"{'width/d_p':>9} {'F':>6} " + " ".join(f"{'phi=' + str(p):>26}" for p in table_phi))
    for n, g in enumerate(widths(f)):
        G = f[g]
        c = G["count"][:]
        m = c >= a.min_count
        phi = G["phi_mean"][:]
        H, lo, hi = G["H"][:], G["H_low"][:], G["H_high"][:]
        F = G.attrs["F"]
        label = ("whole box" if g == "whole_box" else f"Δ = {G.attrs['width_over_dp']:.1f} d_p") + f" (F = {F:.2f})"
        col = colors[n % len(colors)]
        if g == "whole_box":
            ax.errorbar(phi[m], H[m], yerr=[H[m] - lo[m], hi[m] - H[m]], fmt="s", color=col, label=label)
        else:
            ax.plot(phi[m], H[m], "o-", ms=3, color=col, label=label)
            ax.fill_between(phi[m], lo[m], hi[m], color=col, alpha=0.25, lw=0)
            grid = np.linspace(0.0, max(0.3, phi[m].max() if m.any() else 0.3), 200)
            ax.plot(grid, radl2014(grid, F), "--", color=col, lw=1)
        if g == "whole_box":
            for b in np.nonzero(c > 0)[0]:
                print(f"{'whole box':>9} {F:6.3f}  phi_bar = {phi[b]:.4f}: H = {H[b]:.3f} [{lo[b]:.3f},{hi[b]:.3f}], "
                      f"slip {G['slip_over_ut'][b]:.3f} u_t; Radl 2014 {radl2014(phi[b], F)[0]:.2f}")
            continue
        cells = []
        centers = G["phi_center"][:]
        for p in table_phi:
            b = min(int(np.floor(p / f["bins"].attrs["width"])), len(centers) - 1)
            if c[b] >= a.min_count:
                cells.append(f"{H[b]:6.3f} [{lo[b]:6.3f},{hi[b]:6.3f}] R{radl2014(p, F)[0]:5.2f}")
            else:
                cells.append(f"{'-':>26}")
        print(f"{G.attrs['width_over_dp']:9.2f} {F:6.3f} " + " ".join(cells))
    # the coarse grids' operator (cgd-filter --grids): H_grid per grid, its equivalent box width; drawn dotted
    if "grids" in f:
        print(f"coarse grids (TSC deposit + interpolation; docs/filter.md): H_grid, equivalent box width")
        print(f"{'grid':>9} {'cell/d_p':>8} {'F':>6} {'equiv/d_p':>9} {'/cell':>6} " +
              " ".join(f"{'phi=' + str(p):>17}" for p in table_phi))
        for k, n in enumerate(f["grids"].attrs["cells_across"]):
            G = f[f"grids/{n}"]
            c, phi, H, lo, hi = G["count"][:], G["phi_mean"][:], G["H"][:], G["H_low"][:], G["H_high"][:]
            m = c >= a.min_count
            ax.plot(phi[m], H[m], "x:", ms=4, color=colors[(k + 3) % len(colors)],
                    label=f"grid {n} across (cell {G.attrs['cell_size_over_dp']:.2f} d_p)")
            cells = []
            for p in table_phi:
                b = min(int(np.floor(p / f["bins"].attrs["width"])), len(c) - 1)
                cells.append(f"{H[b]:6.3f} [{lo[b]:5.2f},{hi[b]:5.2f}]" if c[b] >= a.min_count else f"{'-':>17}")
            eq = G.attrs["equivalent_width_over_dp"]
            eqc = G.attrs["equivalent_width_over_grid_cell"]
            flag = "*" if G.attrs["equivalent_width_at_bound"] else " "
            print(f"{n:>9} {G.attrs['cell_size_over_dp']:8.2f} {G.attrs['F']:6.3f} {eq:8.2f}{flag} {eqc:6.2f} " + " ".join(cells))
        print("  (* the equivalent width is the end of the box widths filtered: a bound)")
    if plt is None:
        return
    ax.axhline(0, color="k", lw=0.5)
    ax.set_xlabel(r"filtered solids fraction $\bar{\phi}$")
    ax.set_ylabel(r"H = 1 $-$ $\bar{\beta}$ / $\beta_{micro}$")
    ax.set_title(f"{os.path.basename(a.file)}: filtered drag correction (dashed: Radl 2014 at the same F)", fontsize=9)
    # the legend beside the axes: inside it hid the whole-box point (at <phi>, the upper left)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    out = a.output or os.path.splitext(a.file)[0] + ".png"
    fig.set_size_inches(10, 5)
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
