#!/usr/bin/python3
"""The width set a drag model was calibrated on, against the coarse cell sizes it is used at.

A model's n and a(phi) are fitted to the filter sizes of its calibration (cgd-filter --widths / --grids): another
width set gives another n and a(phi) (issue 19: n = 3.99 on the demo's default widths, 2.79 on 8,16,24 d_p), so a
model applied on a grid outside its calibrated range extrapolates. Prints the calibrated range and, for each cell
size given, a warning when it lies outside it (exit status 0 either way; 2 when the file is not a drag model).

usage: /usr/bin/python3 tools/model_widths.py MODEL.h5 [--cells-dp 7.5,15]"""
import argparse
import sys

import h5py
import numpy as np


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("model")
    ap.add_argument("--cells-dp", default="", help="coarse cell sizes (d_p) the model is used at, comma-separated")
    a = ap.parse_args()
    try:
        with h5py.File(a.model, "r") as f:
            fmt = f.attrs.get("cgd_format", b"")
            if (fmt.decode() if isinstance(fmt, bytes) else str(fmt)) != "drag_model" or "data/F" not in f:
                raise OSError("not a fitted drag model (cgd_format drag_model with /data/F)")
            F = f["data/F"][()]
            fitted = f["data/fitted"][()] if "data/fitted" in f else np.ones(len(F), int)
            lc = float(f.attrs["l_char_m"]) / float(f.attrs["diameter_m"])
            n = float(f.attrs.get("width_exponent", 1.0))
    except (OSError, KeyError) as e:
        sys.stderr.write(f"model_widths: {a.model}: {e}\n")
        return 2
    deltas = sorted(lc / x for x, k in zip(F, fitted) if k)
    if not deltas:
        print(f"model {a.model}: no fitted filter size recorded")
        return 0
    lo, hi = deltas[0], deltas[-1]
    print(f"model calibrated on filter sizes {', '.join(f'{d:.3g}' for d in deltas)} d_p (n = {n:.3g}): its n and a(phi) "
          f"belong to this width set (another set fits other values)")
    for c in (float(x) for x in a.cells_dp.split(",") if x.strip()):
        if c < lo * 0.99 or c > hi * 1.01:
            print(f"warning: the model is used on a {c:.3g} d_p grid, outside the {lo:.3g}-{hi:.3g} d_p it was calibrated on: "
                  f"it extrapolates there (filter with widths that reach {c:.3g} d_p, or keep the grids inside)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
