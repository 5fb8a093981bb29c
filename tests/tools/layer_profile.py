#!/usr/bin/python3
"""tools/layer_profile.py against known answers: a synthetic run directory (box 4 x 16 x 4 mm, the default 4 x 16 x 4
grid of 1 mm cells, t_ref = 0.01 s) with three snapshots:
  * t = 0.1 s (10 t_ref, before the window of --from-tref 20): particles everywhere, which must be left out;
  * t = 0.2 s: a plug, every one of the 16 cells of layer 5 holding particles of total volume 0.5 mm^3 (phi = 0.5),
    nothing elsewhere: densest layer 0.5, lateral spread 0 (every layer uniform), densest cell 0.5;
  * t = 0.3 s: one column, the 16 cells (1, j, 2) each at phi = 0.4: every layer's mean 0.4/16 = 0.025, its standard
    deviation over the 16 cells 0.4 sqrt(15)/16;
so the window's means are densest layer (0.5 + 0.025)/2 and lateral spread (0 + 0.4 sqrt(15)/16)/2. Particles are
given a diameter whose sphere volume is the cell's share, and positions outside the box (periodic images) must wrap.
Then a directory without snapshots in the window: exit 2.
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


def snapshot(path, time, cells_phi):
    """cells_phi: list of ((i, j, k), phi); one particle per cell at its centre, shifted by a box length in x for
    every other cell (a periodic image the tool must wrap), with the sphere volume phi * CELL_V."""
    pos, dia = [], []
    for n, ((i, j, k), phi) in enumerate(cells_phi):
        x = np.array([i + 0.5, j + 0.5, k + 0.5]) * 1e-3
        if n % 2:
            x[0] += BOX[0]
        pos.append(x)
        dia.append((6.0 * phi * CELL_V / math.pi) ** (1.0 / 3.0))
    with h5py.File(path, "w") as f:
        f.attrs["time"] = time
        p = f.create_group("params")
        p.attrs["t_ref_s"] = 0.01
        p.attrs["box_size_m"] = BOX
        f["particles/position"] = np.array(pos)
        f["particles/diameter"] = np.array(dia)


with tempfile.TemporaryDirectory() as tmp:
    run = os.path.join(tmp, "run")
    os.makedirs(os.path.join(run, "snapshots"))
    snapshot(os.path.join(run, "snapshots", "snap_1.h5"), 0.1,
             [((i, j, k), 0.3) for i in range(4) for j in range(16) for k in range(4)])
    snapshot(os.path.join(run, "snapshots", "snap_2.h5"), 0.2, [((i, 5, k), 0.5) for i in range(4) for k in range(4)])
    snapshot(os.path.join(run, "snapshots", "snap_3.h5"), 0.3, [((1, j, 2), 0.4) for j in range(16)])
    p = lp.profile(run, (4, 16, 4), 20.0)
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
    r = subprocess.run([sys.executable, tool, run, "--from-tref", "40"], capture_output=True, text=True)
    check(r.returncode == 2 and "no snapshot at or after 40" in r.stderr, f"no snapshot in the window: exit {r.returncode}")

print("layer_profile: " + ("OK" if failures() == 0 else f"{failures()} FAILED"))
sys.exit(1 if failures() else 0)
