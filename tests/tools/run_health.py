#!/usr/bin/python3
"""tools/run_health.py against known answers: a synthetic series (t_ref = 0.01 s, u_t = 0.2 m/s, 1000 particles,
one row per 1e-3 s over 10 t_ref) whose columns are chosen so that each window's figures are known by hand:
100 DEM steps per row and one rebuild every 4 rows, 0.5 wall s per row (5 wall s per t_ref, 5000 ns per
particle-step on one rank, 10000 on two), slip 0.1 m/s then 0.3 m/s (0.5 and 1.5 u_t), the largest overlap and
PCG count placed in one window; and the refusals (a missing dataset, a row-count mismatch: exit 2).
usage: /usr/bin/python3 tests/tools/run_health.py SOURCE_DIR"""
import math
import os
import subprocess
import sys
import tempfile

import h5py
import numpy as np

from tool_check import check, failures, source  # noqa: E402  (tests/tools/tool_check.py)
tool = os.path.join(source, "tools", "run_health.py")
import run_health as rh  # noqa: E402


def write_series(path, n=101, drop=None, short=None):
    t = np.arange(n) * 1e-3
    cols = {
        "time": t, "step": np.arange(n) * 100.0, "wall_seconds": 3.0 + 0.5 * np.arange(n),
        "neighbor_rebuilds": 1.0 + np.arange(n) // 4, "contacts_per_particle": np.full(n, 0.25),
        "max_overlap_rel": np.where(np.arange(n) == 70, 0.08, 0.01), "dt_fluid": np.full(n, 1e-3),
        "pressure_iterations": np.where(np.arange(n) == 12, 30.0, 10.0),
        "slip_velocity": np.stack([np.zeros(n), np.where(t <= 0.05 + 1e-12, 0.1, 0.3), np.zeros(n)], axis=1),
        "max_solids_fraction": np.full(n, 0.5), "floored_cells": np.zeros(n),
    }
    with h5py.File(path, "w") as f:
        for k, v in cols.items():
            if k == drop:
                continue
            f[k] = v[:short] if k == short_col and short else v
        p = f.create_group("params").attrs
        p["t_ref_s"], p["u_t_m_s"], p["particle_count"] = 0.01, 0.2, 1000


short_col = "dt_fluid"
with tempfile.TemporaryDirectory() as tmp:
    good = os.path.join(tmp, "series.h5")
    write_series(good)
    data, t_ref, u_t, n = rh.read_series(good)
    rows = rh.windows(data, t_ref, u_t, n, 5.0, 2)
    check(len(rows) == 2, f"two windows of 5 t_ref over 10 t_ref ({len(rows)})")
    r0, r1 = rows
    check(abs(r0["slip"] - 0.5) < 1e-12 and abs(r1["slip"] - 1.5) < 1e-12,
          f"slip 0.5 then 1.5 u_t ({r0['slip']}, {r1['slip']})")
    # window 0 = (0, 5] t_ref: means over rows 1..50, counters from row 0 to row 50: 5000 steps, 12 rebuilds
    check(abs(r0["steps_per_rebuild"] - 5000 / 12) < 1e-9, f"steps per rebuild 5000/12 ({r0['steps_per_rebuild']})")
    check(abs(r0["wall_per_tref"] - 5.0) < 1e-9, f"5 wall s per t_ref ({r0['wall_per_tref']})")
    check(abs(r0["ns_per_ps"] - 1e9 * 25.0 * 2 / (1000 * 5000)) < 1e-6,
          f"wall ns per particle-step x 2 ranks = 10000 ({r0['ns_per_ps']})")
    check(r1["overlap"] == 0.08 and r0["overlap"] == 0.01, "largest overlap in its window only")
    check(r0["pcg_max"] == 30 and r1["pcg_max"] == 10, "largest PCG count in its window only")
    check(abs(r0["contacts"] - 0.25) < 1e-12, "mean contacts per particle")
    out = subprocess.run([sys.executable, tool, tmp, "--markdown"], capture_output=True, text=True)
    check(out.returncode == 0 and "| 0-5.0 | 0.500 |" in out.stdout, "the Markdown table of a run directory")
    for label, kw in (("a missing dataset", {"drop": "pressure_iterations"}), ("a short column", {"short": 50})):
        bad = os.path.join(tmp, "bad.h5")
        write_series(bad, **kw)
        out = subprocess.run([sys.executable, tool, bad], capture_output=True, text=True)
        check(out.returncode == 2 and "bad.h5" in out.stderr and "Traceback" not in out.stderr,
              f"{label}: exit 2 naming the file ({out.returncode}: {out.stderr.strip()})")
    out = subprocess.run([sys.executable, tool, good, "--window", "0"], capture_output=True, text=True)
    check(out.returncode == 2, "--window 0 refused")

print(f"{failures()} failure(s)")
sys.exit(1 if failures() else 0)
