#!/usr/bin/python3
"""The filtered statistics shipped in data/filtered/ (README "Shipped data") carry what a refit needs, and cgd-fit
refits from them what the runs measured.

Files are grouped by box, the name's prefix: half_* (cgd-filter as `PROFILE=half` runs it, grids 12, 8, 6, 5, 4, 3)
and paper_* (`PROFILE=paper`, grids 16, 12, 8, 6, 5, 4); two boxes are never pooled. For every shipped file (one
resolved run each):
  * it is a filtered file of one run whose scene (the `scene` attribute) names the seed and gamma*, and it has the
    box widths and its profile's coarse grids (what `--operator grid` fits);
  * in every width and grid group the stored per-bin H, count and mean phi equal what this script recomputes from
    the per-snapshot sums (H = 1 - sum N / sum beta_micro u_slip), to 1e-12 relative: the sums are what cgd-fit
    pools and bootstraps, so a file whose totals disagree with them would refit to something else;
Then, pooled per box:
  * `cgd-fit --grid-table 4` on the shipped files writes the 4-cell grid's measured H_grid as a table; it must
    equal the pooled H of the per-snapshot sums, recomputed here, in every bin with at least 100 samples (the
    table's --min-count), to 1e-12 (both are the same sums in another order: round-off only);
  * cgd-fit with the profile's FIT_ARGS (`--operator grid --width-exponent fit`, both boxes)
    runs on them and fits every grid.
And per file, as the reference a coarse run is checked against (`cgd-coarse --summarise FILE`): the resolved slip from
the file's whole box agrees with the slip the run's own series gave over the same window (SERIES_SLIP, measured when
each run ended, docs/half_box_runs.md and docs/coarse.md) within 0.005 u_t: the two are the same average at the
snapshots (e2e_coarse), sampled once per snapshot here against once per fluid step there (measured apart: at most
0.002 u_t), while their batch errors are 0.014-0.054 u_t.

Environment (set by CTest): CGD_SOURCE_DIR, CGD_BINARY_DIR.
"""
import glob
import os
import subprocess
import sys
import tempfile

import h5py
import numpy as np

# per box (the file name's prefix): the coarse grids its profile's cgd-filter writes (Makefile.pipeline FILTER_GRIDS)
# and its profile's cgd-fit options (FIT_ARGS); files of one box are pooled, never two boxes together
PROFILES = {"half": dict(grids=(12, 8, 6, 5, 4, 3), fit_args=("--operator", "grid", "--width-exponent", "fit")),
            "paper": dict(grids=(16, 12, 8, 6, 5, 4), fit_args=("--operator", "grid", "--width-exponent", "fit"))}
MIN_COUNT = 100  # cgd-fit's default --min-count, which --grid-table applies
# the resolved runs' slip/u_t over 20-50 t_ref from their series.h5 (cgd-coarse --summarise RUN_DIR --from-tref 20),
# measured when each run ended; a file shipped later adds its run's value here
SERIES_SLIP = {"half_phi0.02.h5": 1.116, "half_phi0.05.h5": 1.116, "half_phi0.10.h5": 1.099, "half_phi0.20.h5": 0.894,
               "half_phi0.30.h5": 0.737, "half_phi0.40.h5": 0.283,
               "paper_phi0.02.h5": 1.357, "paper_phi0.05.h5": 1.515}
SLIP_TOLERANCE = 0.005


def fail(msg):
    print("check_filtered: FAILED:", msg)
    sys.exit(1)


def close(a, b, rel=1e-12):
    a, b = np.asarray(a, float), np.asarray(b, float)
    both_nan = np.isnan(a) & np.isnan(b)
    ok = np.abs(a - b) <= rel * np.maximum(1.0, np.maximum(np.abs(a), np.abs(b)))
    return bool(np.all(both_nan | ok))


def check_group(path, f, name):
    """Checks the group's totals against its per-snapshot sums; returns the summed (count, numerator, micro, phi)."""
    g = f[name]
    ps = g["per_snapshot"]
    count = ps["count"][()].sum(axis=0)
    num, mic, phi = (ps[k][()].sum(axis=0) for k in ("numerator", "micro", "phi"))
    if not np.array_equal(count, g["count"][()]):
        fail(f"{path}:{name}: count is not the sum of per_snapshot/count")
    with np.errstate(invalid="ignore", divide="ignore"):
        H = np.where(count > 0, 1.0 - num / mic, np.nan)
        phi_mean = np.where(count > 0, phi / count, np.nan)
    if not close(H, g["H"][()]):
        fail(f"{path}:{name}: H differs from 1 - sum N / sum beta_micro u_slip of per_snapshot")
    if not close(phi_mean, g["phi_mean"][()]):
        fail(f"{path}:{name}: phi_mean differs from the per-snapshot sums")
    return count, num, mic, phi


def check_box(profile, files, build):
    """The checks of the files of one box; returns a line of what was checked."""
    grids = PROFILES[profile]["grids"]
    pooled = None
    for path in files:
        with h5py.File(path, "r") as f:
            if f.attrs["cgd_format"] != "filtered":
                fail(f"{path}: cgd_format {f.attrs['cgd_format']!r}")
            if len(f["runs"].attrs["paths"]) != 1:
                fail(f"{path}: one run per shipped file (leave-one-run-out pools files)")
            scene = f.attrs["scene"]
            for key in ("seed =", "gamma_star ="):
                if key not in scene:
                    fail(f"{path}: the scene does not name {key.split()[0]}")
            groups = [k for k in f if k.startswith("width_")] + ["whole_box"] + [f"grids/{n}" for n in grids]
            for name in groups:
                if name not in f:
                    fail(f"{path}: no /{name}")
                sums = check_group(path, f, name)
                if name == "grids/4":
                    pooled = sums if pooled is None else [p + s for p, s in zip(pooled, sums)]

    with tempfile.TemporaryDirectory() as tmp:
        table = os.path.join(tmp, "table.h5")
        subprocess.run([os.path.join(build, "cgd-fit"), *files, "--grid-table", "4", "--quiet", "-o", table], check=True)
        with h5py.File(table, "r") as t:
            phi_t, H_t, n_t = t["table/phi"][()], t["table/H"][()], t["table/count"][()]
        count, num, mic, phi = pooled
        keep = count >= MIN_COUNT
        if not (close(n_t, count[keep]) and close(phi_t, phi[keep] / count[keep]) and close(H_t, 1 - num[keep] / mic[keep])):
            fail(f"{profile}: cgd-fit --grid-table 4 does not reproduce the pooled H_grid of the shipped per-snapshot sums")

        model = os.path.join(tmp, "model.h5")
        subprocess.run([os.path.join(build, "cgd-fit"), *files, *PROFILES[profile]["fit_args"], "--bootstrap", "0",
                        "--quiet", "-o", model], check=True)
        with h5py.File(model, "r") as m:
            cells = sorted(int(c) for c in m.attrs["calibrated_cells_across"])
        if cells != sorted(grids):
            fail(f"{profile}: the refit calibrated grids {cells}, not {sorted(grids)}")
    return (f"{profile}: {len(files)} files; --grid-table 4 reproduces the pooled H_grid in {int(keep.sum())} bins; "
            f"the refit fits grids {cells}")


def main():
    src = os.environ.get("CGD_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
    build = os.environ.get("CGD_BINARY_DIR", os.path.join(src, "build"))
    files = sorted(glob.glob(os.path.join(src, "data", "filtered", "*.h5")))
    if not files:
        fail("no data/filtered/*.h5")
    boxes = {}
    for path in files:
        profile = os.path.basename(path).split("_")[0]
        if profile not in PROFILES:
            fail(f"{path}: the name does not start with one of {', '.join(p + '_' for p in PROFILES)} (the box's profile)")
        boxes.setdefault(profile, []).append(path)
    lines = [check_box(profile, box_files, build) for profile, box_files in sorted(boxes.items())]
    with tempfile.TemporaryDirectory() as tmp:
        worst = 0.0
        for path in files:
            name = os.path.basename(path)
            if name not in SERIES_SLIP:
                fail(f"{path}: no series slip in SERIES_SLIP (add the run's cgd-coarse --summarise RUN_DIR --from-tref 20 value)")
            out = os.path.join(tmp, name)
            subprocess.run([os.path.join(build, "cgd-coarse"), "--summarise", path, "-o", out], check=True,
                           stdout=subprocess.DEVNULL)
            slip = h5py.File(out, "r").attrs["slip_over_ut"]
            worst = max(worst, abs(slip - SERIES_SLIP[name]))
            if abs(slip - SERIES_SLIP[name]) > SLIP_TOLERANCE:
                fail(f"{path}: cgd-coarse --summarise gives slip {slip:.4f} u_t, the run's series {SERIES_SLIP[name]}")
    lines.append(f"cgd-coarse --summarise FILE within {worst:.4f} u_t of each run's series slip")
    print(f"check_filtered: {len(files)} shipped files; per-bin H = the per-snapshot sums' in every group; "
          + "; ".join(lines) + ": OK")


if __name__ == "__main__":
    main()
