#!/usr/bin/python3
"""Does a run's suspension stand in horizontal layers (plugs) or in clusters? The solids fraction on a grid of
NX x NY x NZ cells (default the 4 x 16 x 4 of the half box's 4-cell coarse grid), per snapshot of a run's sampling
window: the densest horizontal layer's mean phi, and the lateral spread (the standard deviation of phi within each
layer, averaged over the layers). A one-dimensional voidage wave -- a dense layer spanning the box, which the gas must
cross -- has a dense layer (phi 0.4-0.6) and little lateral spread; clusters have a lateral spread near the layers'
own variation. Particles (or parcels: `particles/diameter` gives each one's volume) are binned to their cell (nearest
grid point), so a resolved run and a coarse run are seen on the same grid the same way.

usage: /usr/bin/python3 tools/layer_profile.py RUN_DIR... [--cells 4,16,4] [--from-tref 40] [--markdown]
Prints per run: snapshots used, the mean over them of the densest layer's phi and of the lateral spread, the
densest cell, and the last snapshot's layer profile. Exit status 0; 2 for a directory without snapshots in the window.
(Debian's h5py/numpy belong to /usr/bin/python3.)"""
import argparse
import collections
import glob
import os
import sys

import h5py
import numpy as np



Profile = collections.namedtuple("Profile", "n dense spread cmax last")


def profile(run, cells, from_tref):
    files = sorted(glob.glob(os.path.join(run, "snapshots", "*.h5")))
    if not files:
        return None
    dens, spread, cmax, last = [], [], 0.0, None
    for fn in files:
        with h5py.File(fn, "r") as f:
            params = f["params"].attrs
            if float(f.attrs["time"]) < from_tref * float(params["t_ref_s"]) * (1 - 1e-9):
                continue
            box = np.asarray(params["box_size_m"], float)
            x = np.mod(f["particles/position"][()], box)
            vol = np.pi / 6.0 * f["particles/diameter"][()] ** 3
        idx = np.minimum((x / box * cells).astype(int), np.asarray(cells) - 1)
        phi = np.zeros(cells)
        np.add.at(phi, (idx[:, 0], idx[:, 1], idx[:, 2]), vol)
        phi /= box.prod() / np.prod(cells)
        layers = phi.mean(axis=(0, 2))
        dens.append(layers.max())
        spread.append(phi.std(axis=(0, 2)).mean())
        cmax = max(cmax, phi.max())
        last = layers
    if not dens:
        return None
    return Profile(len(dens), float(np.mean(dens)), float(np.mean(spread)), float(cmax), last)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--cells", default="4,16,4", help="NX,NY,NZ (y vertical)")
    ap.add_argument("--from-tref", type=float, default=40.0, help="first snapshot time in t_ref (default 40)")
    ap.add_argument("--markdown", action="store_true")
    a = ap.parse_intermixed_args()
    cells = tuple(int(c) for c in a.cells.split(","))
    status = 0
    if a.markdown:
        print("| run | snapshots | densest layer phi | lateral spread | densest cell | last layer profile |")
        print("|---|---|---|---|---|---|")
    for run in a.runs:
        p = profile(run, cells, a.from_tref)
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
    return status


if __name__ == "__main__":
    sys.exit(main())
