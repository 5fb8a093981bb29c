#!/usr/bin/python3
"""tools/runs_H.py against answers computed by hand. Three one-run files on the grid of 4 cells across (13.25 d_p,
F = 1), three phi-bar bins each, the H of B and C made of unequal snapshots (so that a plain or count-weighted mean
of the runs' H, or of the snapshots', differs from the pooled ratio of the sums that `cgd-fit --grid-table` takes):
  A <phi> 0.10: sums N 2, 2, 1 over beta_micro u_slip 4, 5, 2 (H 0.5, 0.6, 0.5), samples 1000, 300, 50;
  B <phi> 0.20: three snapshots, N totals 3, 3, 1 over 4, 12, 2 (H 0.25, 0.75, 0.5), samples 5000, 2000, 5000;
  C <phi> 0.05: two snapshots, N totals 1, 1, 1 over 6, 6, 4 (H 0.8333, 0.8333, 0.75), samples 3000, 100, 40.
A against B + C pooled: 1 - 4/10 = 0.6, 1 - 4/18 = 0.77778 (bin 3: A has 50 < 100 samples, left out); A - others
= -0.1, -0.17778, weighted by 1000, 300: mean -0.117949, rms sqrt((10 + 9.48148)/1300) = 0.122417.
B against A + C: 1 - 3/10 = 0.7, 1 - 3/11 = 0.72727 (bin 3: the others hold 50 + 40 < 100, left out); B - others
= -0.45, +0.022727 by 5000, 2000: mean -0.314935, rms 0.380513. Bands 0.05 (the files' H -+ 0.05).
A model h = 0.5, a = 1 (n = 1) gives H = 0.25 at F = 1: A - model over A's bins 1, 2 = 0.25, 0.35: mean +0.273077,
rms 0.276308. Refused with exit 2 and no traceback: a file of two runs, other bins, without the grid asked, a grid of
other cells (another box). Two runs at one <phi> are told apart by their files.
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


def filtered(path, phi_run, num, micro, count, edges=(0.0, 0.1, 0.2, 0.3), runs=1, dx=13.25):
    """Grid 4 (dx d_p, F = 1) of three bins; num, micro: per-snapshot sums (rows: snapshots)."""
    num, micro = np.atleast_2d(np.array(num, float)), np.atleast_2d(np.array(micro, float))
    with h5py.File(path, "w") as f:
        f.attrs["cgd_format"] = "filtered"
        f["runs/mean_solids_fraction"] = np.full(runs, phi_run)
        f["bins/phi_edges"] = np.array(edges)
        g = f.create_group("grids/4")
        g.attrs["F"], g.attrs["dx_over_dp"] = 1.0, dx
        H = 1 - num.sum(axis=0) / micro.sum(axis=0)
        g["H"], g["H_low"], g["H_high"], g["H_stderr"] = H, H - 0.05, H + 0.05, np.full(3, 0.025)
        g["count"] = np.array(count)
        g["phi_mean"] = np.array([0.05, 0.15, 0.25])
        g["per_snapshot/numerator"], g["per_snapshot/micro"] = num, micro


def near(x, y):
    return x is not None and abs(x - y) < 1e-6


with tempfile.TemporaryDirectory() as tmp:
    a, b, c, d = (os.path.join(tmp, x + ".h5") for x in "abcd")
    filtered(a, 0.10, [2, 2, 1], [4, 5, 2], [1000, 300, 50])
    filtered(b, 0.20, [[2, 1, 0.5], [0.5, 1, 0.25], [0.5, 1, 0.25]], [[2, 4, 1], [1, 4, 0.5], [1, 4, 0.5]],
             [5000, 2000, 5000])
    filtered(c, 0.05, [[1, 0.5, 1], [0, 0.5, 0]], [[3, 2, 2], [3, 4, 2]], [3000, 100, 40])
    model = os.path.join(tmp, "model.h5")
    with h5py.File(model, "w") as f:
        f.attrs["width_exponent"] = 1.0
        for k, v in {"phi": [0.0, 1.0], "h": [0.5, 0.5], "a": [1.0, 1.0]}.items():
            f[f"bands/{k}"] = np.array(v)
    runs = [(label, runs_H.read_run(p, [4])[2]) for label, p in (("C", c), ("A", a), ("B", b))]
    rows = {r.label: r for r in runs_H.offsets(runs, 4, 100, runs_H.model_H(model))}
    ra, rb = rows["A"], rows["B"]
    check(ra.bins == 2 and ra.phi_range == (0.05, 0.15) and near(ra.mean, -0.117949) and near(ra.rms, 0.122417),
          f"A - (B + C pooled): 2 bins, mean -0.117949, rms 0.122417 ({ra})")
    check(rb.bins == 2 and near(rb.mean, -0.314935) and near(rb.rms, 0.380513),
          f"B - (A + C pooled), the bin the others hold too few samples of left out: mean -0.314935, rms 0.380513 ({rb})")
    check(near(ra.band, 0.05) and near(ra.model_mean, 0.273077) and near(ra.model_rms, 0.276308),
          f"A: band 0.05, A - model mean +0.273077, rms 0.276308 ({ra})")
    out = subprocess.run([sys.executable, tool, c, a, b, "--grids", "4", "--min-count", "100", "--model", model,
                          "-o", os.path.join(tmp, "runs")], capture_output=True, text=True)
    lines = [x for x in out.stdout.splitlines() if x.startswith("| <phi>")]
    check(out.returncode == 0 and [x.split(" |")[0] for x in lines] == ["| <phi> = 0.05", "| <phi> = 0.10",
                                                                         "| <phi> = 0.20"] and
          "| <phi> = 0.10 | 2 | 0.050–0.150 | -0.118 | 0.122 | 0.050 | +0.273 | 0.276 |" in lines and
          os.path.getsize(os.path.join(tmp, "runs.png")) > 0 and os.path.exists(os.path.join(tmp, "runs.md")),
          f"the command line's table, rows by <phi>, and picture ({out.stdout} {out.stderr})")
    filtered(d, 0.10, [1, 1, 1], [4, 4, 4], [500, 500, 500])
    out = subprocess.run([sys.executable, tool, a, d, "--grids", "4"], capture_output=True, text=True)
    check(out.returncode == 0 and "| <phi> = 0.10 (a.h5) |" in out.stdout and "| <phi> = 0.10 (d.h5) |" in out.stdout,
          f"two runs at one <phi> labelled by their files ({out.stdout})")
    two, other_bins, other_box = (os.path.join(tmp, x + ".h5") for x in ("two", "bins", "box"))
    filtered(two, 0.1, [1, 1, 1], [4, 4, 4], [500, 500, 500], runs=2)
    filtered(other_bins, 0.1, [1, 1, 1], [4, 4, 4], [500, 500, 500], edges=(0.0, 0.2, 0.4, 0.6))
    filtered(other_box, 0.1, [1, 1, 1], [4, 4, 4], [500, 500, 500], dx=26.5)
    for bad, what, args in ((two, "2 runs", ["--grids", "4"]), (other_bins, "bins differ", ["--grids", "4"]),
                            (b, "no /grids/8", ["--grids", "8"]), (other_box, "two boxes", ["--grids", "4"])):
        out = subprocess.run([sys.executable, tool, a, bad] + args, capture_output=True, text=True)
        check(out.returncode == 2 and what in out.stderr and "Traceback" not in out.stderr and
              out.stderr.startswith("runs_H.py: "), f"{what}: exit 2 ({out.returncode}: {out.stderr.strip()})")

print(f"{failures()} failure(s)")
sys.exit(1 if failures() else 0)
