#!/usr/bin/python3
"""A synthetic coarse summary (cgd_format "coarse_summary", docs/schema-coarse-summary.md) with every attribute
the reader requires, as cgd-coarse --reference writes it: for the parcel-fit tests (tests/e2e/parcel_fit.sh,
tests/schema/damage.py).

    synthetic_summary.py DIR PHI ALPHA SEED SLIP     writes DIR/summary.h5 (slip in u_t, error 0.005)
"""
import os
import sys

import h5py


def write(run_dir, phi, alpha, seed, slip, slip_stderr=0.005, reference=1.0, reference_stderr=0.01):
    os.makedirs(run_dir, exist_ok=True)
    with h5py.File(os.path.join(run_dir, "summary.h5"), "w") as f:
        p = f.create_group("params").attrs
        p["solids_fraction"], p["seed"], p["parcel_correction"] = float(phi), int(seed), int(alpha == 1)
        a = f.attrs
        a["cgd_format"], a["cgd_format_version"] = "coarse_summary", 1
        a["drag"] = "model" if alpha == 1 else "model-raw"
        a["parcel_size"], a["cell_over_dp"] = float(alpha), 13.3
        a["slip_over_ut"], a["slip_stderr"] = float(slip), float(slip_stderr)
        a["window_start_s"], a["window_end_s"], a["batches"] = 1.0, 2.0, 10
        a["drift_over_ut"], a["drift_stderr"], a["stationary"] = 0.0, 0.01, 1
        a["simulated_s"], a["wall_s"], a["ranks"], a["core_seconds_per_simulated_second"] = 2.0, 10.0, 1, 5.0
        a["reference"] = "synthetic/resolved"
        a["reference_slip_over_ut"], a["reference_slip_stderr"] = float(reference), float(reference_stderr)
        a["reference_window_start_s"], a["reference_window_end_s"] = 1.0, 2.0
        a["relative_error"] = (slip - reference) / reference
        a["relative_error_stderr"] = abs(slip / reference) * ((slip_stderr / slip) ** 2 +
                                                              (reference_stderr / reference) ** 2) ** 0.5


if __name__ == "__main__":
    d, phi, alpha, seed, slip = sys.argv[1:6]
    write(d, float(phi), float(alpha), int(seed), float(slip))
