#!/usr/bin/python3
"""tools/compare_boxes.py against answers computed by hand: file A (a 106 d_p box) with grids of 8 and 4 cells
across (13.25 and 26.5 d_p), file B (53 d_p) with grids of 4 and 3 (13.25 and 17.67 d_p): only A's 8 and B's 4 pair.
In the pair, bin 0 has H 0.10 (A, stderr 0.03) and 0.14 (B, stderr 0.04): difference +0.04, z = 0.04/0.05 = 0.8;
bin 1 H 0.20 and 0.17 with stderr 0.01 and 0.02 (z = -0.03/sqrt(5e-4) = -1.3416); bin 2 has 50 samples in B
(below --min-count 100): left out. Sample-weighted mean difference (the smaller count of each bin, 1000 and
300): (1000 x 0.04 - 300 x 0.03)/1300 = 0.023846; chi2/dof = (0.64 + 1.8)/2 = 1.22. Two files without a grid of
equal cells: exit 2, no traceback.
usage: /usr/bin/python3 tests/tools/compare_boxes.py SOURCE_DIR"""
import os
import subprocess
import sys
import tempfile

import h5py
import numpy as np

from tool_check import check, failures, source  # noqa: E402  (tests/tools/tool_check.py)
tool = os.path.join(source, "tools", "compare_boxes.py")
import compare_boxes as cb  # noqa: E402


def filtered(path, grids):
    """grids: {cells across: (dx_over_dp, H, stderr, count)}"""
    with h5py.File(path, "w") as f:
        f.attrs["cgd_format"] = "filtered"
        for n, (dx, h, se, count) in grids.items():
            g = f.create_group(f"grids/{n}")
            g.attrs["dx_over_dp"], g.attrs["F"] = dx, 0.3
            g["H"], g["H_stderr"], g["count"] = np.array(h), np.array(se), np.array(count)
            g["H_low"], g["H_high"] = np.array(h) - 0.05, np.array(h) + 0.05
            g["phi_mean"] = np.array([0.015, 0.025, 0.035])


with tempfile.TemporaryDirectory() as tmp:
    a, b = os.path.join(tmp, "a.h5"), os.path.join(tmp, "b.h5")
    filtered(a, {8: (13.25, [0.10, 0.20, 0.3], [0.03, 0.01, 0.01], [1000, 400, 400]),
                 4: (26.5, [0.3, 0.4, 0.5], [0.01, 0.01, 0.01], [1000, 1000, 1000])})
    filtered(b, {4: (13.25, [0.14, 0.17, 0.9], [0.04, 0.02, 0.01], [5000, 300, 50]),
                 3: (17.67, [0.3, 0.4, 0.5], [0.01, 0.01, 0.01], [1000, 1000, 1000])})
    ga, gb = cb.read_grids(a), cb.read_grids(b)
    pairs = cb.pairs_of(ga, gb)
    check(pairs == [(8, 4)], f"only 8 (A) and 4 (B) pair ({pairs})")
    rows, s = cb.compare(ga[8], gb[4], 100)
    check(len(rows) == 2, f"two common bins with >= 100 samples ({len(rows)})")
    check(abs(rows[0]["diff"] - 0.04) < 1e-12 and abs(rows[0]["z"] - 0.8) < 1e-12 and
          abs(rows[1]["z"] + 0.03 / np.sqrt(5e-4)) < 1e-12, f"differences and z ({rows})")
    check(abs(s.mean_diff - (1000 * 0.04 - 300 * 0.03) / 1300) < 1e-12 and
          abs(s.chi2_dof - (0.8 ** 2 + 0.03 ** 2 / 5e-4) / 2) < 1e-12,
          f"mean difference 0.023846, chi2/dof 1.22 ({s})")
    out = subprocess.run([sys.executable, tool, a, b, "--min-count", "100", "-o", os.path.join(tmp, "cmp")],
                         capture_output=True, text=True)
    check(out.returncode == 0 and "| 13.25 | 8 / 4 | 2 | +0.024 | 1.22 |" in out.stdout and
          os.path.getsize(os.path.join(tmp, "cmp.png")) > 0, f"the command line's table and picture ({out.stderr})")
    c = os.path.join(tmp, "c.h5")
    filtered(c, {5: (10.6, [0.1, 0.2, 0.3], [0.01, 0.01, 0.01], [1000, 1000, 1000])})
    out = subprocess.run([sys.executable, tool, a, c], capture_output=True, text=True)
    check(out.returncode == 2 and "no grid" in out.stderr and "Traceback" not in out.stderr,
          f"no pair: exit 2 ({out.returncode}: {out.stderr.strip()})")

print(f"{failures()} failure(s)")
sys.exit(1 if failures() else 0)
