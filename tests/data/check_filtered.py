#!/usr/bin/python3
"""The filtered statistics shipped in data/filtered/ (README "Shipped data") carry what a refit needs, and cgd-fit
refits from them what the runs measured.

For every shipped file (one resolved run each, cgd-filter as `PROFILE=half` runs it):
  * it is a filtered file of one run whose scene (the `scene` attribute) names the seed and gamma*, and it has the
    box widths and the coarse grids 12, 8, 6, 5, 4, 3 (what `--operator grid` fits);
  * in every width and grid group the stored per-bin H, count and mean phi equal what this script recomputes from
    the per-snapshot sums (H = 1 - sum N / sum beta_micro u_slip), to 1e-12 relative: the sums are what cgd-fit
    pools and bootstraps, so a file whose totals disagree with them would refit to something else;
Then, pooled:
  * `cgd-fit --grid-table 4` on the shipped files writes the 4-cell grid's measured H_grid as a table; it must
    equal the pooled H of the per-snapshot sums, recomputed here, in every bin with at least 100 samples (the
    table's --min-count), to 1e-12 (both are the same sums in another order: round-off only);
  * `cgd-fit --operator grid --width-exponent fit` (the half profile's fit) runs on them and fits every grid.

Environment (set by CTest): CGD_SOURCE_DIR, CGD_BINARY_DIR.
"""
import glob
import os
import subprocess
import sys
import tempfile

import h5py
import numpy as np

GRIDS = (12, 8, 6, 5, 4, 3)
MIN_COUNT = 100  # cgd-fit's default --min-count, which --grid-table applies


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


def main():
    src = os.environ.get("CGD_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
    build = os.environ.get("CGD_BINARY_DIR", os.path.join(src, "build"))
    files = sorted(glob.glob(os.path.join(src, "data", "filtered", "*.h5")))
    if not files:
        fail("no data/filtered/*.h5")
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
            groups = [k for k in f if k.startswith("width_")] + ["whole_box"] + [f"grids/{n}" for n in GRIDS]
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
            fail("cgd-fit --grid-table 4 does not reproduce the pooled H_grid of the shipped per-snapshot sums")

        model = os.path.join(tmp, "model.h5")
        subprocess.run([os.path.join(build, "cgd-fit"), *files, "--operator", "grid", "--width-exponent", "fit",
                        "--bootstrap", "0", "--quiet", "-o", model], check=True)
        with h5py.File(model, "r") as m:
            cells = sorted(int(c) for c in m.attrs["calibrated_cells_across"])
        if cells != sorted(GRIDS):
            fail(f"the refit calibrated grids {cells}, not {sorted(GRIDS)}")
    print(f"check_filtered: {len(files)} shipped files; per-bin H = the per-snapshot sums' in every group; "
          f"--grid-table 4 reproduces the pooled H_grid in {int(keep.sum())} bins; the refit fits grids {cells}: OK")


if __name__ == "__main__":
    main()
