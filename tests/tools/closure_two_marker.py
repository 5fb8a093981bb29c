#!/usr/bin/python3
"""tools/closure_two_marker.py against answers computed by hand. Two runs in a 2 x 2 x 2 m periodic box seen on
N = 2 cells (cubes of 1 m), eps = 0.9 everywhere, u_t = 1 m/s, rho_p g = 10^4 N/m^3. Each run has two occupied
cubes with two particles each (V_p = 0.015 m^3: phi_c = 0.03, one bin), particle velocities -/+ 0.1 m/s about 0
(the cell's mean particle velocity 0), so the cell slip s_c is the cube's gas velocity: run A 0.5 and 1.0, run B
1.5 and 2.0. Every particle's drag share is D = 0.3 + 0.7 s_c (beta_p = 10^4, its fluid velocity v + D):
  - the cell-slip closure fitted on both runs is a = 0.3, b = 0.7 exactly, and it predicts each held-out run
    exactly (error 0); pooled over both runs the ratio closure is B = 9.4/10;
  - the ratio closure B = sum D / sum s: fitted on B it is 6.1/7, and it predicts A's mean drag 0.825 as
    0.75 x 6.1/7 (-20.78 %); fitted on A it is 3.3/3 = 1.1, predicting B's 1.525 as 1.925 (+26.23 %).
One run only, or a run without snapshots: exit 2, no traceback.
usage: /usr/bin/python3 tests/tools/closure_two_marker.py SOURCE_DIR"""
import os
import re
import subprocess
import sys
import tempfile

import h5py
import numpy as np

from tool_check import check, failures, source  # noqa: E402  (tests/tools/tool_check.py)
tool = os.path.join(source, "tools", "closure_two_marker.py")

def snapshot(path, slips):
    """Cubes (0,0,0) and (1,0,0) hold two particles each; their gas moves up at slips[0] and slips[1] m/s."""
    eps = np.full((4, 4, 4), 0.9)
    u = np.zeros((4, 4, 4))
    u[:2, :2, :2] = slips[0]   # fine cells (z, y, x) of cube x 0
    u[:2, :2, 2:] = slips[1]   # cube x 1
    eu = np.zeros((4, 4, 4, 3))
    eu[..., 1] = eps * u
    x = np.array([[0.3, 0.5, 0.5], [0.7, 0.5, 0.5], [1.3, 0.5, 0.5], [1.7, 0.5, 0.5]])
    v = np.zeros((4, 3))
    v[:, 1] = [-0.1, 0.1, -0.1, 0.1]
    s_c = np.array([slips[0], slips[0], slips[1], slips[1]])
    drag = 0.3 + 0.7 * s_c
    uf = np.zeros((4, 3))
    uf[:, 1] = v[:, 1] + drag
    with h5py.File(path, "w") as f:
        f.attrs["cgd_format"] = "snapshot"
        f.attrs["time"] = 1.0
        p = f.create_group("params").attrs
        p["box_size_m"] = np.array([2.0, 2.0, 2.0])
        p["particle_volume_m3"], p["parcel_size"], p["u_t_m_s"], p["t_ref_s"] = 0.015, 1.0, 1.0, 0.01
        p["density_kg_m3"], p["fluid_density_kg_m3"], p["gravity_m_s2"] = 1000.0, 1.0, np.array([0.0, -10.0, 0.0])
        parts = f.create_group("particles")
        parts.attrs["pressure_gradient_mean"] = np.array([0.0, 0.0, 0.0])
        for name, a in (("position", x), ("velocity", v), ("pressure_gradient", np.zeros((4, 3))),
                        ("fluid_velocity", uf), ("drag_coefficient", np.full(4, 1e4))):
            parts[name] = a
        fl = f.create_group("fluid")
        fl.attrs["cells"], fl.attrs["spacing"], fl.attrs["origin"] = np.array([4, 4, 4]), np.full(3, 0.5), np.zeros(3)
        fl["void_fraction"] = eps
        fl["eps_velocity"] = eu


def cells(line):
    return [c.strip() for c in line.strip().strip("|").split("|")]


with tempfile.TemporaryDirectory() as tmp:
    runs = []
    for name, slips in (("A", (0.5, 1.0)), ("B", (1.5, 2.0))):
        run = os.path.join(tmp, name)
        os.makedirs(os.path.join(run, "snapshots"))
        snapshot(os.path.join(run, "snapshots", "snap_1.h5"), slips)
        runs.append(run)
    prefix = os.path.join(tmp, "out")
    r = subprocess.run([sys.executable, tool, "--cells", "2", "--from-tref", "0", "--min", "2", "-o", prefix] + runs,
                       capture_output=True, text=True)
    check(r.returncode == 0, f"two runs: exit 0 ({r.returncode}; {r.stderr.strip()[-300:]})")
    lines = r.stdout.splitlines()
    fits = [cells(l) for l in lines if l.startswith("| 0.02–0.04")]
    check(len(fits) == 1, "one phi_c bin (0.02-0.04) holds every particle")
    if fits:
        f = fits[0]
        check(f[1] == "8", f"8 particles pooled ({f[1]})")
        check(abs(float(f[2]) - 9.4 / 10) < 1e-3, f"pooled ratio B = sum D / sum s = 9.4/10 ({f[2]})")
        check(abs(float(f[3]) - 0.3) < 1e-3 and abs(float(f[4]) - 0.7) < 1e-3, f"cell-slip fit a = 0.3, b = 0.7 ({f[3]}, {f[4]})")
    held = {cells(l)[0]: cells(l) for l in lines if re.match(r"\| [AB] \|", l)}
    check(set(held) == {"A", "B"}, f"a held-out row per run ({sorted(held)})")
    if set(held) == {"A", "B"}:
        def rms_worst(cell):
            m = re.match(r"([0-9.]+) / ([-+][0-9.]+) %", cell)
            return float(m[1]), float(m[2])
        check(rms_worst(held["A"][2]) == (20.8, -20.8), f"A from B, ratio closure: -20.8 % ({held['A'][2]})")
        check(rms_worst(held["B"][2]) == (26.2, 26.2), f"B from A, ratio closure: +26.2 % ({held['B'][2]})")
        for k in ("A", "B"):
            rms, worst = rms_worst(held[k][3])
            check(rms == 0.0 and abs(worst) == 0.0, f"{k} held out, cell-slip closure: exact ({held[k][3]})")
    check(os.path.exists(prefix + ".md") and os.path.exists(prefix + ".png"), "-o PREFIX writes PREFIX.md and PREFIX.png")
    r = subprocess.run([sys.executable, tool, "--cells", "2", runs[0]], capture_output=True, text=True)
    check(r.returncode == 2 and "Traceback" not in r.stderr, f"one run: exit 2 without a traceback ({r.returncode})")
    empty = os.path.join(tmp, "empty")
    os.makedirs(empty)
    r = subprocess.run([sys.executable, tool, "--cells", "2", runs[0], empty], capture_output=True, text=True)
    check(r.returncode == 2 and "empty" in r.stderr and "Traceback" not in r.stderr,
          f"a run without snapshots: exit 2 naming it ({r.stderr.strip()[:120]})")

print("closure_two_marker:", "all checks passed" if failures() == 0 else f"{failures()} check(s) FAILED")
sys.exit(1 if failures() else 0)
