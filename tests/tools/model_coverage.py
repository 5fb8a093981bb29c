#!/usr/bin/python3
"""tools/model_coverage.py against known answers: a synthetic run (box 4 x 6 x 5 mm, a fluid grid of 4 x 6 x 5 cells of
1 mm -- not a cube, so that the axes cannot be mixed up unseen --, t_ref = 0.01 s, d_p = 0.1 mm) whose cells are at
phi = 1 - eps = 0.1, but cell (x, y, z) = (0, 1, 1) at 0.5 and the rows y = 3, 4, 5 at 0.01, and five particles; four
with y and z at the centre of row 1:
  * at the dense cell's centre: TSC weight 0.75^3 on it, phi_bar = 0.1 + 0.4 * 0.421875 = 0.26875;
  * at x = 2.5 mm (cell 2's centre: no weight on cell 0): 0.1;
  * at x = 1 mm (the face of cells 0 and 1: 0.5 along x): 0.1 + 0.4 * 0.5 * 0.5625 = 0.2125;
  * at x = 3.75 mm (cell 3, offset +1/4: weight (1/2 + 1/4)^2 / 2 = 0.28125 on cell 4, i.e. cell 0 of the periodic
    box): 0.1 + 0.4 * 0.28125 * 0.5625 = 0.1632813;
and one at y = 4.5 mm (rows 3-5 only): 0.01, below phi_crit;
and a model calibrated on phi_bar [0.016, 0.2] and cells of 0.5-2 mm: two particles of five above phi_max, two inside,
one below,
Delta 10 d_p inside the calibrated cells, 30 d_p (--filter-ratio 3) outside. A snapshot at 5 t_ref, before the
window of --from-tref 8, holds particles at other places and must be left out. Then the refusals, exit 2: a model
without phi_max, a directory without snapshots in the window.
usage: /usr/bin/python3 tests/tools/model_coverage.py SOURCE_DIR"""
import os
import subprocess
import sys
import tempfile

import h5py
import numpy as np

from tool_check import check, failures, source  # noqa: E402  (tests/tools/tool_check.py)
tool = os.path.join(source, "tools", "model_coverage.py")
import model_coverage as mc  # noqa: E402

H = 1e-3
NX, NY, NZ = 4, 6, 5


def snapshot(path, time, xs):
    solids = np.full((NZ, NY, NX), 0.1)
    solids[1, 1, 0] = 0.5  # (z, y, x)
    solids[:, 3:, :] = 0.01
    with h5py.File(path, "w") as f:
        f.attrs["cgd_format"] = "snapshot"
        f.attrs["time"] = time
        f.create_group("params").attrs["t_ref_s"] = 0.01
        pos = np.array([[x, 1.5 * H, 1.5 * H] for x in xs] + [[1.5 * H, 4.5 * H, 2.5 * H]])
        f.create_dataset("particles/position", data=pos)
        fl = f["/"].create_group("fluid")
        fl.attrs["cells"] = np.array([NX, NY, NZ])
        fl.attrs["spacing"] = np.array([H, H, H])
        fl.attrs["origin"] = np.zeros(3)
        fl.create_dataset("void_fraction", data=1.0 - solids)


def model(path, with_phi_max=True):
    with h5py.File(path, "w") as f:
        f.attrs["cgd_format"] = "drag_model"
        f.attrs["phi_crit"] = 0.016
        if with_phi_max:
            f.attrs["phi_max"] = 0.2
        f.attrs["diameter_m"] = 1e-4
        f.attrs["calibrated_delta_m"] = np.array([0.5e-3, 1e-3, 2e-3])


def run(*args):
    r = subprocess.run([sys.executable, tool, *args], capture_output=True, text=True)
    return r.returncode, r.stdout + r.stderr


with tempfile.TemporaryDirectory() as tmp:
    rd = os.path.join(tmp, "run")
    os.makedirs(os.path.join(rd, "snapshots"))
    snapshot(os.path.join(rd, "snapshots", "snapshot_000000.h5"), 0.05, [0.5 * H] * 7)
    xs = [0.5 * H, 2.5 * H, 1.0 * H, 3.75 * H]
    snapshot(os.path.join(rd, "snapshots", "snapshot_000001.h5"), 0.10, xs)
    mfile = os.path.join(tmp, "model.h5")
    model(mfile)

    # the interpolation itself
    with h5py.File(os.path.join(rd, "snapshots", "snapshot_000001.h5")) as f:
        phi = mc.phi_at_particles(f["particles/position"][:], 1.0 - f["fluid/void_fraction"][:], np.zeros(3),
                                  np.array([H, H, H]))
    want = [0.1 + 0.4 * 0.421875, 0.1, 0.1 + 0.4 * 0.5 * 0.5625, 0.1 + 0.4 * 0.28125 * 0.5625, 0.01]
    check(np.allclose(phi, want, rtol=0, atol=1e-12), f"TSC phi_bar at the five particles {phi.tolist()} = {want}")
    c, w = mc.tsc_weights(np.array([0.1, 3.99, 2.5]))
    check(np.allclose(w.sum(axis=1), 1.0, atol=1e-15), "the TSC weights sum to one")

    # the run's shares
    cov = mc.coverage(rd, mc.read_model(mfile), 8.0, 1.0)
    check(cov.snapshots == 1 and cov.particles == 5, f"only the window's snapshot is used ({cov.snapshots}, "
          f"{cov.particles} particles)")
    check(abs(cov.above - 0.4) < 1e-12 and abs(cov.inside - 0.4) < 1e-12 and abs(cov.below - 0.2) < 1e-12,
          f"shares below / inside / above = {cov.below}, {cov.inside}, {cov.above} (0.2, 0.4, 0.4)")
    check(abs(cov.largest - want[0]) < 1e-12, f"largest phi_bar {cov.largest}")
    check(abs(cov.delta_dp - 10.0) < 1e-9, f"Delta {cov.delta_dp} d_p (10)")
    code, out = run(rd, "--model", mfile, "--from-tref", "8", "--markdown")
    check(code == 0 and "| 10.00 (inside) | 20.0 % | 40.0 % | 40.0 % |" in out, f"markdown row (exit {code}):\n{out}")
    code, out = run(rd, "--model", mfile, "--from-tref", "8", "--filter-ratio", "3")
    check(code == 0 and "Delta 30.00 d_p (OUTSIDE the calibrated cells)" in out, f"Delta outside (exit {code}):\n{out}")

    # refusals
    bad = os.path.join(tmp, "bad.h5")
    model(bad, with_phi_max=False)
    code, out = run(rd, "--model", bad)
    check(code == 2 and "phi_max" in out, f"a model without phi_max: exit {code}, {out.strip()}")
    code, out = run(rd, "--model", mfile, "--from-tref", "50")
    check(code == 2 and "no snapshot at or after 50" in out, f"no snapshot in the window: exit {code}, {out.strip()}")

print("model_coverage: " + ("OK" if failures() == 0 else f"{failures()} FAILED"))
sys.exit(1 if failures() else 0)
