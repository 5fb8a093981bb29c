#!/usr/bin/python3
"""tools/layer_profile.py against known answers: a synthetic run directory (box 4 x 16 x 4 mm, seen on 4 cells across:
the 4 x 16 x 4 grid of 1 mm cells, t_ref = 0.01 s) with three snapshots:
  * t = 0.1 s (10 t_ref, before the window of --from-tref 20): particles everywhere, which must be left out;
  * t = 0.2 s: a plug, every one of the 16 cells of layer 5 holding one particle of 0.5 mm^3 (phi = 0.5), nothing
    elsewhere: densest layer 0.5, lateral spread 0 (every layer uniform), densest cell 0.5;
  * t = 0.3 s: one column, the 16 cells (1, j, 2) each at phi = 0.4 (two particles of 0.2 mm^3): every layer's mean
    0.4/16 = 0.025, its standard deviation over the 16 cells 0.4 sqrt(15)/16;
so the window's means are densest layer (0.5 + 0.025)/2 and lateral spread (0 + 0.4 sqrt(15)/16)/2. Every other
particle is given a box length further in x (a periodic image the reader must wrap). Then the refusals, exit 2: a
directory without snapshots in the window, and a snapshot without particles/velocity (the reader shared with
tools/closure_diagnostics.py).
usage: /usr/bin/python3 tests/tools/layer_profile.py SOURCE_DIR"""
import math
import os
import subprocess
import sys
import tempfile

import h5py
import numpy as np

from tool_check import check, failures, source  # noqa: E402  (tests/tools/tool_check.py)
tool = os.path.join(source, "tools", "layer_profile.py")
import layer_profile as lp  # noqa: E402


BOX = np.array([4e-3, 16e-3, 4e-3])
CELL_V = 1e-9  # m^3


def snapshot(path, time, cells_phi, per_cell=1, drop=None):
    """cells_phi: list of ((i, j, k), phi); per_cell particles of phi CELL_V / per_cell each at the cell's centre,
    every other one shifted by a box length in x; a complete cgd snapshot (the fluid at rest on the same grid)."""
    vol = {phi / per_cell * CELL_V for _, phi in cells_phi}
    assert len(vol) == 1, "one particle volume per snapshot (params/particle_volume_m3)"
    pos = []
    for (i, j, k), _ in cells_phi:
        for _ in range(per_cell):
            x = np.array([i + 0.5, j + 0.5, k + 0.5]) * 1e-3
            if len(pos) % 2:
                x[0] += BOX[0]
            pos.append(x)
    n = len(pos)
    with h5py.File(path, "w") as f:
        f.attrs["cgd_format"] = "snapshot"
        f.attrs["time"] = time
        p = f.create_group("params").attrs
        p["box_size_m"] = BOX
        p["particle_volume_m3"], p["parcel_size"], p["u_t_m_s"], p["t_ref_s"] = vol.pop(), 1.0, 0.2, 0.01
        p["density_kg_m3"], p["fluid_density_kg_m3"], p["gravity_m_s2"] = 1500.0, 1.3, np.array([0.0, -9.81, 0.0])
        parts = f.create_group("particles")
        parts.attrs["pressure_gradient_mean"] = np.zeros(3)
        for name, a in (("position", np.array(pos)), ("velocity", np.zeros((n, 3))), ("pressure_gradient", np.zeros((n, 3))),
                        ("fluid_velocity", np.zeros((n, 3))), ("drag_coefficient", np.ones(n))):
            if name != drop:
                parts[name] = a
        fl = f.create_group("fluid")
        fl.attrs["cells"], fl.attrs["spacing"], fl.attrs["origin"] = np.array([4, 16, 4]), np.full(3, 1e-3), np.zeros(3)
        fl["void_fraction"] = np.ones((4, 16, 4))
        fl["eps_velocity"] = np.zeros((4, 16, 4, 3))


with tempfile.TemporaryDirectory() as tmp:
    run = os.path.join(tmp, "run")
    os.makedirs(os.path.join(run, "snapshots"))
    snapshot(os.path.join(run, "snapshots", "snap_1.h5"), 0.1,
             [((i, j, k), 0.3) for i in range(4) for j in range(16) for k in range(4)])
    snapshot(os.path.join(run, "snapshots", "snap_2.h5"), 0.2, [((i, 5, k), 0.5) for i in range(4) for k in range(4)])
    snapshot(os.path.join(run, "snapshots", "snap_3.h5"), 0.3, [((1, j, 2), 0.4) for j in range(16)], per_cell=2)
    p = lp.profile(run, 4, 20.0)
    check(p is not None and p.n == 2, f"the snapshot before 20 t_ref is left out: {p.n if p else None} used, want 2")
    want_dense = (0.5 + 0.4 / 16) / 2
    want_spread = (0.0 + 0.4 * math.sqrt(15) / 16) / 2
    check(abs(p.dense - want_dense) < 1e-12, f"densest layer {p.dense:.15f}, want {want_dense:.15f}")
    check(abs(p.spread - want_spread) < 1e-12, f"lateral spread {p.spread:.15f}, want {want_spread:.15f}")
    check(abs(p.cmax - 0.5) < 1e-12, f"densest cell {p.cmax:.15f}, want 0.5")
    check(np.allclose(p.last, 0.4 / 16, rtol=0, atol=1e-15), "the last snapshot's layers: 0.025 each")
    r = subprocess.run([sys.executable, tool, run, "--from-tref", "20", "--markdown"], capture_output=True, text=True)
    check(r.returncode == 0 and f"| run | 2 | {want_dense:.3f} | {want_spread:.3f} | 0.50 |" in r.stdout,
          f"the markdown row (exit {r.returncode}): {r.stdout.strip().splitlines()[-1] if r.stdout.strip() else r.stderr}")
    check([round(h[0], 9) for h in p.history] == [20.0, 30.0] and abs(p.history[0][1] - 0.5) < 1e-12 and
          abs(p.history[1][2] - 0.4 * math.sqrt(15) / 16) < 1e-12, f"the history: {[h[:3] for h in p.history]}")
    r = subprocess.run([sys.executable, tool, run, "--from-tref", "20", "--history"], capture_output=True, text=True)
    rows = [l.split() for l in r.stdout.splitlines() if l.startswith("    20.00") or l.startswith("    30.00")]
    check(r.returncode == 0 and len(rows) == 2 and rows[0][1:3] == ["0.500", "0.000"] and len(rows[1]) == 3 + 16,
          f"--history: a row per snapshot, t/t_ref, densest, spread and the 16 layers ({r.stdout.strip()})")
    r = subprocess.run([sys.executable, tool, run, "--from-tref", "40"], capture_output=True, text=True)
    check(r.returncode == 2 and "no snapshot at or after 40" in r.stderr, f"no snapshot in the window: exit {r.returncode}")
    damaged = os.path.join(tmp, "damaged")
    os.makedirs(os.path.join(damaged, "snapshots"))
    snapshot(os.path.join(damaged, "snapshots", "snap_1.h5"), 0.3, [((0, 0, 0), 0.5)], drop="velocity")
    r = subprocess.run([sys.executable, tool, damaged, "--from-tref", "20"], capture_output=True, text=True)
    check(r.returncode == 2 and "particles/velocity missing" in r.stderr and "Traceback" not in r.stderr,
          f"a snapshot without particles/velocity: exit {r.returncode}, {r.stderr.strip()}")

print("layer_profile: " + ("OK" if failures() == 0 else f"{failures()} FAILED"))
sys.exit(1 if failures() else 0)
