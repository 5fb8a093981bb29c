#!/usr/bin/python3
"""The spline of a drag model file, evaluated with h5py + numpy alone (docs/schema-drag-model.md,
"Evaluating h and a"), agrees with the C++ evaluator to round-off.

cgd-fit writes /bands/h and /bands/a on the grid /bands/phi with core/filtered_drag.hpp's SplineCurves
(the evaluator the engine uses); this script recomputes them from /h and /log_a (knots, coefficients,
order) and the root attributes phi_crit, h_max, with its own de Boor. Tolerance 1e-12 (absolute for h,
relative for a): both are a few dozen flops on O(1) numbers, so they differ by round-off only.

Environment (set by CTest): CGD_SOURCE_DIR, CGD_BINARY_DIR.
"""
import os
import subprocess
import sys
import tempfile

import h5py
import numpy as np


def de_boor(t, c, k, x):
    """Value at x of the B-spline of order k (degree k - 1), full knot vector t, coefficients c."""
    n = len(c)
    x = min(max(x, t[k - 1]), t[n])
    i = int(np.searchsorted(t[:n], x, side="right")) - 1
    i = min(max(i, k - 1), n - 1)
    p = k - 1
    d = [c[j + i - p] for j in range(p + 1)]
    for r in range(1, p + 1):
        for j in range(p, r - 1, -1):
            left, right = t[j + i - p], t[j + 1 + i - r]
            alpha = (x - left) / (right - left) if right > left else 0.0
            d[j] = (1 - alpha) * d[j - 1] + alpha * d[j]
    return d[p]


def curves(path):
    with h5py.File(path, "r") as f:
        assert f.attrs["cgd_format"] == "drag_model"
        th, ch, kh = f["h/knots"][()], f["h/coefficients"][()], int(f["h"].attrs["order"])
        ta, ca, ka = f["log_a/knots"][()], f["log_a/coefficients"][()], int(f["log_a"].attrs["order"])
        phi_crit, h_max = float(f.attrs["phi_crit"]), float(f.attrs["h_max"])
        phi_max = th[len(ch)]
        la_min, la_max = float(f.attrs.get("log_a_min", -np.inf)), float(f.attrs.get("log_a_max", np.inf))

    def h(phi):
        if phi < phi_crit:
            return min(max(de_boor(th, ch, kh, phi_crit), 0.0), h_max) * max(phi, 0.0) / phi_crit
        return min(max(de_boor(th, ch, kh, min(phi, phi_max)), 0.0), h_max)

    def a(phi):
        return np.exp(min(max(de_boor(ta, ca, ka, min(max(phi, phi_crit), ta[len(ca)])), la_min), la_max))

    return h, a


def main():
    src = os.environ.get("CGD_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
    build = os.environ.get("CGD_BINARY_DIR", os.path.join(src, "build"))
    fit = os.path.join(build, "cgd-fit")
    if not os.access(fit, os.X_OK):
        print(f"SKIP: {fit} not built")
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        filtered, model = os.path.join(tmp, "f.h5"), os.path.join(tmp, "m.h5")
        subprocess.run([sys.executable, os.path.join(src, "tests", "fit", "make_synthetic_filtered.py"), "-o",
                        filtered, "--runs", "2", "--snapshots", "40"], check=True)
        subprocess.run([fit, filtered, "-o", model, "--bootstrap", "20", "--quiet"], check=True)
        h, a = curves(model)
        with h5py.File(model, "r") as f:
            phi, h_cpp, a_cpp = f["bands/phi"][()], f["bands/h"][()], f["bands/a"][()]
        dh = max(abs(h(p) - v) for p, v in zip(phi, h_cpp))
        da = max(abs(a(p) / v - 1) for p, v in zip(phi, a_cpp))
        print(f"{len(phi)} points on [0, {phi[-1]:.3f}]: max |h_numpy - h_cpp| = {dh:.2e}, "
              f"max |a_numpy/a_cpp - 1| = {da:.2e}")
        if not (dh < 1e-12 and da < 1e-12) or not np.all(h_cpp[phi > 0.05] > 0):
            print("FAIL: the model file's spline does not reproduce the C++ evaluator")
            return 1
    print("ok")
    return 0


if __name__ == "__main__":
    sys.exit(main())
