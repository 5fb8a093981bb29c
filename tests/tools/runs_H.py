#!/usr/bin/python3
"""tools/runs_H.py against answers computed by hand. Three one-run files on the grid of 4 cells across (F = 1), two
phi-bar bins each: A (<phi> = 0.10) H 0.5, 0.6 with 1000 and 300 samples; B's per-snapshot sums N = 2, 3 over
beta_micro u_slip = 4, 10 (two snapshots: 1 + 1, 1.5 + 1.5 over 2 + 2, 5 + 5); C's 1, 1 over 4, 10. The others
pooled for A: 1 - (2 + 1)/(4 + 4) = 0.625 and 1 - (3 + 1)/(10 + 10) = 0.8, so A - others = -0.125, -0.2: weighted
mean (1000 x -0.125 + 300 x -0.2)/1300 = -0.142308, rms sqrt((1000 x 0.015625 + 300 x 0.04)/1300) = 0.145774. A
model h = 0.5, a = 1 (n = 1) gives H = 0.25 at F = 1: A - model = (1000 x 0.25 + 300 x 0.35)/1300 = +0.273077.
A bin with fewer than --min-count samples in the run is left out; files with two runs, other bins or without the
grid asked: exit 2, no traceback.
usage: /usr/bin/python3 tests/tools/runs_H.py SOURCE_DIR"""
import os
import subprocess
import sys
import tempfile

import h5py
import numpy as np

from tool_check import check, failures, source  # noqa: E402  (tests/tools/tool_check.py)
tool = os.path.join(source, "tools", "runs_H.py")
import runs_H  # noqa: E402


def filtered(path, phi_run, num, micro, count, edges=(0.0, 0.1, 0.2, 0.3), runs=1):
    """One grid (4 cells across, F = 1) of three bins; num, micro: per-bin sums, split over two snapshots."""
    num, micro = np.array(num, float), np.array(micro, float)
    with h5py.File(path, "w") as f:
        f.attrs["cgd_format"] = "filtered"
        f["runs/mean_solids_fraction"] = np.full(runs, phi_run)
        f["bins/phi_edges"] = np.array(edges)
        g = f.create_group("grids/4")
        g.attrs["F"] = 1.0
        H = 1 - num / micro
        g["H"], g["H_low"], g["H_high"] = H, H - 0.05, H + 0.05
        g["count"] = np.array(count)
        g["phi_mean"] = np.array([0.05, 0.15, 0.25])
        g["per_snapshot/numerator"] = np.vstack([num / 2, num / 2])
        g["per_snapshot/micro"] = np.vstack([micro / 2, micro / 2])


with tempfile.TemporaryDirectory() as tmp:
    a, b, c = (os.path.join(tmp, x + ".h5") for x in "abc")
    filtered(a, 0.10, [2, 2, 1], [4, 5, 2], [1000, 300, 50])  # H 0.5, 0.6 (0.5 in the third bin: too few samples)
    filtered(b, 0.20, [2, 3, 1], [4, 10, 2], [5000, 5000, 5000])
    filtered(c, 0.05, [1, 1, 1], [4, 10, 2], [5000, 5000, 5000])
    model = os.path.join(tmp, "model.h5")
    with h5py.File(model, "w") as f:
        f.attrs["width_exponent"] = 1.0
        for k, v in {"phi": [0.0, 1.0], "h": [0.5, 0.5], "a": [1.0, 1.0]}.items():
            f[f"bands/{k}"] = np.array(v)
    runs = sorted((runs_H.read_run(p, [4])[::2] for p in (a, b, c)), key=lambda r: r[0])
    rows = runs_H.offsets(runs, 4, 100, runs_H.model_H(model))
    row_a = [r for r in rows if r[0] == 0.10][0]
    check(row_a[1] == 2 and abs(row_a[2][0] - 0.05) < 1e-12 and abs(row_a[2][1] - 0.15) < 1e-12,
          f"A: two bins with >= 100 samples, phi-bar 0.05-0.15 ({row_a})")
    check(abs(row_a[3] + 0.142308) < 1e-6 and abs(row_a[4] - 0.145774) < 1e-6,
          f"A - others: mean -0.142308, rms 0.145774 ({row_a[3]}, {row_a[4]})")
    check(abs(row_a[5] - 0.273077) < 1e-6, f"A - model: +0.273077 ({row_a[5]})")
    out = subprocess.run([sys.executable, tool, c, a, b, "--grids", "4", "--min-count", "100", "--model", model,
                          "-o", os.path.join(tmp, "runs")], capture_output=True, text=True)
    lines = [x for x in out.stdout.splitlines() if x.startswith("| 0.")]
    check(out.returncode == 0 and [x.split(" |")[0] for x in lines] == ["| 0.05", "| 0.10", "| 0.20"] and
          "| 0.10 | 2 | 0.050–0.150 | -0.142 | 0.146 | +0.273 |" in lines and
          os.path.getsize(os.path.join(tmp, "runs.png")) > 0 and os.path.exists(os.path.join(tmp, "runs.md")),
          f"the command line's table, rows by <phi>, and picture ({out.stdout} {out.stderr})")
    two = os.path.join(tmp, "two.h5")
    filtered(two, 0.1, [1, 1, 1], [4, 4, 4], [500, 500, 500], runs=2)
    other_bins = os.path.join(tmp, "bins.h5")
    filtered(other_bins, 0.1, [1, 1, 1], [4, 4, 4], [500, 500, 500], edges=(0.0, 0.2, 0.4, 0.6))
    for bad, what, args in ((two, "2 runs", ["--grids", "4"]), (other_bins, "bins differ", ["--grids", "4"]),
                            (b, "no /grids/8", ["--grids", "8"])):
        out = subprocess.run([sys.executable, tool, a, bad] + args, capture_output=True, text=True)
        check(out.returncode == 2 and what in out.stderr and "Traceback" not in out.stderr,
              f"{what}: exit 2 ({out.returncode}: {out.stderr.strip()})")

print(f"{failures()} failure(s)")
sys.exit(1 if failures() else 0)
