#!/usr/bin/python3
"""Does a run's suspension stand in horizontal layers (plugs) or in clusters? The solids fraction on the coarse grid
of N cells across (default 4: the half box's 4 x 16 x 4 grid), per snapshot of a run's sampling window: the densest
horizontal layer's mean phi, and the lateral spread (the standard deviation of phi within each layer, averaged over
the layers). A one-dimensional voidage wave -- a dense layer spanning the box, which the gas must cross -- has a dense
layer (phi 0.4-0.6) and little lateral spread; clusters have a lateral spread near the layers' own variation. The
snapshots are read, checked and deposited by tools/closure_diagnostics.py (`run_snapshots`, `snapshot_cells`: the
grid of N cells across, particles or parcels -- alpha^3 particle volumes -- to the cell of their centre), so a resolved
run and a coarse run are seen on the same grid the same way, and a damaged snapshot is refused the same way.

usage: /usr/bin/python3 tools/layer_profile.py RUN_DIR... [--cells N] [--from-tref 40] [--markdown] [--history]
Prints per run: snapshots used, the mean over them of the densest layer's phi and of the lateral spread, the
densest cell, and the last snapshot's layer profile. --history: also one row per snapshot (its time in t_ref, densest
layer, lateral spread, layer profile), to see whether layers form and whether they last (a run that is still
running: whether its window will be a plug's). Exit status 0; 2 for a directory without snapshots in the
window or a damaged snapshot. (Debian's h5py/numpy belong to /usr/bin/python3.)"""
import argparse
import collections
import os
import sys

import numpy as np

import closure_diagnostics as cd

Profile = collections.namedtuple("Profile", "n dense spread cmax last history")


def profile(run, n_cells, from_tref):
    """The run's Profile over its snapshots at or after from_tref t_ref; None when there are none."""
    dens, spread, cmax, last, history = [], [], 0.0, None, []
    for path in cd.run_snapshots(run):
        snap = cd.snapshot_cells(path, n_cells, from_tref)
        if snap is None:
            continue
        nx, ny, nz = snap["grid"]
        phi = (snap["solids"] / snap["cell_volume"]).reshape(nz, ny, nx)  # cd's cell order: x fastest
        layers = phi.mean(axis=(0, 2))
        dens.append(layers.max())
        spread.append(phi.std(axis=(0, 2)).mean())
        cmax = max(cmax, phi.max())
        last = layers
        history.append((snap["time"] / snap["t_ref"], float(dens[-1]), float(spread[-1]), layers))
    if not dens:
        return None
    return Profile(len(dens), float(np.mean(dens)), float(np.mean(spread)), float(cmax), last, history)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--cells", type=int, default=4, help="cells across the box width (default 4)")
    ap.add_argument("--from-tref", type=float, default=40.0, help="first snapshot time in t_ref (default 40)")
    ap.add_argument("--markdown", action="store_true")
    ap.add_argument("--history", action="store_true", help="also a row per snapshot")
    a = ap.parse_intermixed_args()
    status = 0
    if a.markdown:
        print("| run | snapshots | densest layer phi | lateral spread | densest cell | last layer profile |")
        print("|---|---|---|---|---|---|")
    for run in a.runs:
        p = profile(run, a.cells, a.from_tref)
        if p is None:
            print(f"layer_profile: {run}: no snapshot at or after {a.from_tref} t_ref", file=sys.stderr)
            status = 2
            continue
        prof = " ".join(f"{v:.2f}" for v in p.last)
        if a.markdown:
            print(f"| {os.path.basename(os.path.normpath(run))} | {p.n} | {p.dense:.3f} | {p.spread:.3f} | "
                  f"{p.cmax:.2f} | {prof} |")
        else:
            print(f"{run}: {p.n} snapshots, densest layer {p.dense:.3f}, lateral spread {p.spread:.3f}, "
                  f"densest cell {p.cmax:.2f}\n  last: {prof}")
        if a.history:
            print(f"  {'t/t_ref':>7}  densest  spread  layers (bottom to top)")
            for t, dense, spr, layers in p.history:
                print(f"  {t:7.2f}  {dense:7.3f}  {spr:6.3f}  " + " ".join(f"{v:.2f}" for v in layers))
    return status


if __name__ == "__main__":
    sys.exit(main())
