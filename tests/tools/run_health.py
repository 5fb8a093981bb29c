#!/usr/bin/python3
"""tools/run_health.py against known answers: a synthetic series (t_ref = 0.01 s, u_t = 0.2 m/s, 1000 particles,
one row per 1e-3 s over 10 t_ref) whose columns are chosen so that each window's figures are known by hand:
100 DEM steps per row and one rebuild every 4 rows, 0.5 wall s per row (5 wall s per t_ref, 5000 ns per
particle-step on one rank, 10000 on two), slip 0.1 m/s then 0.3 m/s (0.5 and 1.5 u_t), the largest overlap and
PCG count placed in one window; with --timers the phases' shares of the wall time (per row 0.1 s of neighbour lists,
0.25 forces, 0.05 coupling, 0.01 + 0.02 + 0.01 fluid, 0.03 communication, 0.005 + 0.005 + 0 output of the 0.5 s:
20, 50, 10, 8, 6, 2 % and 4 % other); and the refusals (a missing dataset, a row-count mismatch, --timers on a series
without the timers: exit 2).
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


TIMER_ROWS = {"time_neighbor_s": 0.1, "time_force_integrate_s": 0.25, "time_coupling_s": 0.05,
              "time_fluid_predictor_s": 0.01, "time_fluid_pressure_s": 0.02, "time_fluid_correction_s": 0.01,
              "time_comm_s": 0.03, "time_output_s": 0.005, "time_checkpoint_s": 0.005, "time_diagnostics_s": 0.0}


def write_series(path, n=101, drop=None, short=None, timers=True):
    t = np.arange(n) * 1e-3
    cols = {
        "time": t, "step": np.arange(n) * 100.0, "wall_seconds": 3.0 + 0.5 * np.arange(n),
        "neighbor_rebuilds": 1.0 + np.arange(n) // 4, "contacts_per_particle": np.full(n, 0.25),
        "max_overlap_rel": np.where(np.arange(n) == 70, 0.08, 0.01), "dt_fluid": np.full(n, 1e-3),
        "pressure_iterations": np.where(np.arange(n) == 12, 30.0, 10.0),
        "slip_velocity": np.stack([np.zeros(n), np.where(t <= 0.05 + 1e-12, 0.1, 0.3), np.zeros(n)], axis=1),
        "max_solids_fraction": np.full(n, 0.5), "floored_cells": np.zeros(n),
    }
    if timers:  # cumulative seconds, as the series holds them
        cols.update({k: 7.0 + v * np.arange(n) for k, v in TIMER_ROWS.items()})
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
    data, t_ref, u_t, n = rh.read_series(good, timers=True)
    shares = rh.windows(data, t_ref, u_t, n, 5.0, 1)[1]["timers"]
    want = {"neighbour": 20, "forces+integrate": 50, "coupling": 10, "fluid": 8, "comm": 6, "output": 2, "other": 4}
    check(all(abs(shares[k] - v) < 1e-9 for k, v in want.items()), f"the phases' shares of the wall time ({shares})")
    out = subprocess.run([sys.executable, tool, good, "--markdown", "--timers"], capture_output=True, text=True)
    check(out.returncode == 0 and "| 5-10.0 | 20.0 | 50.0 | 10.0 | 8.0 | 6.0 | 2.0 | 4.0 |" in out.stdout,
          f"the timers' Markdown table ({out.stdout[-200:]} {out.stderr})")
    old = os.path.join(tmp, "old.h5")
    write_series(old, timers=False)
    out = subprocess.run([sys.executable, tool, old], capture_output=True, text=True)
    check(out.returncode == 0, "a series without the timers reads without --timers")
    out = subprocess.run([sys.executable, tool, old, "--timers"], capture_output=True, text=True)
    check(out.returncode == 2 and "old.h5" in out.stderr and "time_neighbor_s" in out.stderr and
          "Traceback" not in out.stderr, f"--timers on it: exit 2 naming the dataset ({out.stderr.strip()})")
    out = subprocess.run([sys.executable, tool, good, "--window", "0"], capture_output=True, text=True)
    check(out.returncode == 2, "--window 0 refused")

print(f"{failures()} failure(s)")
sys.exit(1 if failures() else 0)
