#!/usr/bin/python3
"""tools/closure_diagnostics.py against answers computed by hand: a 2 x 2 x 2 m periodic box seen on N = 2
cells (8 cubes of 1 m), a 4^3 fluid grid with eps = 0.6, u_y = 1 m/s in the fine cells of cube 0 and eps = 0.9,
u_y = 2 m/s elsewhere, three particles of 0.01 m^3 in cube 0 (v_y = 0.1, 0.2, 0.3) and one in cube 7 given at
x = 3.5 m (wrapped to 1.5: v_y = -0.4); u_t = 1 m/s. Then
  cube 0: phi 0.03, slip 1 - 0.2 = 0.8; cube 7: phi 0.01, slip 2 - (-0.4) = 2.4; local slip (3 x 0.8 + 2.4)/4 = 1.2;
  domain slip (8 x 0.6 + 56 x 1.8)/(8 x 0.6 + 56 x 0.9) - 0.05 = 1.913043... - 0.05; drift = domain - 1.2;
  phi (particle-weighted) mean 0.025, std sqrt(0.0007 - 0.025^2); <phi> = 0.005, tail phi > 0.011: 75 %;
  pressure support: G_y = -59.95 (the mixture weight at rho_p 1000, rho_f 1, g 10) plus the particles' own
  -10, -10, -10, +10 Pa/m: 64.95 / 59.95;
  force balance (beta_p = 1000 kg/(m^3 s), the particles' fluid velocity u_y = 1 m/s, weight rho_p g = 10^4 N/m^3):
  drag shares 0.09, 0.08, 0.07 (cube 0) and 0.14 (cube 7), pressure shares 0.006995 (x3) and 0.004995, so the
  phi = 0.01 bin 0.14 / 0.004995, the phi = 0.03 bin 0.08 / 0.006995, all particles 0.095 / 0.006495.
The particle-phase momentum flux, on a 1 x 4 x 1 m column seen as 4 cells of 1 m along y (x and z have one cell:
no derivative), particles of 0.01 m^3, rho_p g = 10^4 N/m^3: cell 0 holds v_y = 1 and 3, cell 1 v_y = -1, cell 2
nothing, cell 3 v = (1, 0, 0) and (-1, 2, 0). Sub-grid stress R_yy = rho_p (sum V v_y^2 - P_y^2 / M) / V_c =
20, 0, 0, 20 Pa; grid-scale rho_p P_y^2 / (M V_c) = 80, 10, 0, 20 Pa. Minus the central difference in y: sub-grid
force 10, 10, -10, -10 N/m^3, grid-scale 5, 40, -40 (cell 2 empty), -40; over the cells' particles' weight (200,
100, 200 N): sub-grid shares 0.05, 0.1, -0.05, grid-scale 0.025, 0.4, -0.2. In phi bins of 0.015 (cell 1 at
phi 0.01, cells 0 and 3 at 0.02): sub-grid 0.1 and 0, grid-scale 0.4 and -0.0875.
On one cell the drift is 0 (local slip = domain slip). A snapshot before --from-tref (different numbers)
must be left out; the fine-to-coarse overlap of a grid that
does not divide the coarse one (3 fine cells on 2 coarse); the refusals (a missing dataset, cells more than 10 %
from cubes): exit 2, no traceback.
usage: /usr/bin/python3 tests/tools/closure_diagnostics.py SOURCE_DIR"""
import math
import os
import subprocess
import sys
import tempfile

import h5py
import numpy as np

from tool_check import check, failures, source  # noqa: E402  (tests/tools/tool_check.py)
tool = os.path.join(source, "tools", "closure_diagnostics.py")
import closure_diagnostics as cd  # noqa: E402


def snapshot(path, time, vy, box=(2.0, 2.0, 2.0), drop=None):
    eps = np.full((4, 4, 4), 0.9)
    u = np.full((4, 4, 4), 2.0)
    eps[:2, :2, :2] = 0.6
    u[:2, :2, :2] = 1.0
    eu = np.zeros((4, 4, 4, 3))
    eu[..., 1] = eps * u
    x = np.array([[0.5, 0.5, 0.5], [0.25, 0.25, 0.75], [0.75, 0.1, 0.2], [3.5, 1.5, 1.5]])
    v = np.zeros((4, 3))
    v[:, 1] = vy
    gp = np.zeros((4, 3))
    gp[:, 1] = [-10, -10, -10, 10]
    uf = np.zeros((4, 3))
    uf[:, 1] = 1.0
    with h5py.File(path, "w") as f:
        f.attrs["cgd_format"] = "snapshot"
        f.attrs["time"] = time
        p = f.create_group("params").attrs
        p["box_size_m"] = np.array(box)
        p["particle_volume_m3"], p["parcel_size"], p["u_t_m_s"], p["t_ref_s"] = 0.01, 1.0, 1.0, 1.0
        p["density_kg_m3"], p["fluid_density_kg_m3"], p["gravity_m_s2"] = 1000.0, 1.0, np.array([0.0, -10.0, 0.0])
        parts = f.create_group("particles")
        parts.attrs["pressure_gradient_mean"] = np.array([0.0, -59.95, 0.0])
        for name, a in (("position", x), ("velocity", v), ("pressure_gradient", gp), ("fluid_velocity", uf),
                        ("drag_coefficient", np.full(4, 1000.0))):
            if name != drop:
                parts[name] = a
        fl = f.create_group("fluid")
        fl.attrs["cells"], fl.attrs["spacing"], fl.attrs["origin"] = np.array([4, 4, 4]), np.full(3, 0.5), np.zeros(3)
        fl["void_fraction"] = eps
        if drop != "eps_velocity":
            fl["eps_velocity"] = eu


def column_snapshot(path):
    """The 1 x 4 x 1 m column of the momentum-flux check (the doc above)."""
    x = np.array([[0.5, 0.2, 0.5], [0.5, 0.7, 0.5], [0.5, 1.5, 0.5], [0.5, 3.2, 0.5], [0.5, 3.8, 0.5]])
    v = np.array([[0, 1.0, 0], [0, 3.0, 0], [0, -1.0, 0], [1.0, 0, 0], [-1.0, 2.0, 0]])
    eps = np.full((2, 8, 2), 0.9)
    eu = np.zeros((2, 8, 2, 3))
    with h5py.File(path, "w") as f:
        f.attrs["cgd_format"] = "snapshot"
        f.attrs["time"] = 2.0
        p = f.create_group("params").attrs
        p["box_size_m"] = np.array([1.0, 4.0, 1.0])
        p["particle_volume_m3"], p["parcel_size"], p["u_t_m_s"], p["t_ref_s"] = 0.01, 1.0, 1.0, 1.0
        p["density_kg_m3"], p["fluid_density_kg_m3"], p["gravity_m_s2"] = 1000.0, 1.0, np.array([0.0, -10.0, 0.0])
        parts = f.create_group("particles")
        parts.attrs["pressure_gradient_mean"] = np.zeros(3)
        for name, a in (("position", x), ("velocity", v), ("pressure_gradient", np.zeros((5, 3))),
                        ("fluid_velocity", np.zeros((5, 3))), ("drag_coefficient", np.zeros(5))):
            parts[name] = a
        fl = f.create_group("fluid")
        fl.attrs["cells"], fl.attrs["spacing"], fl.attrs["origin"] = np.array([2, 8, 2]), np.full(3, 0.5), np.zeros(3)
        fl["void_fraction"] = eps
        fl["eps_velocity"] = eu


with tempfile.TemporaryDirectory() as tmp:
    run = os.path.join(tmp, "run")
    os.makedirs(os.path.join(run, "snapshots"))
    snapshot(os.path.join(run, "snapshots", "snap_0.h5"), 0.5, [5.0, 5.0, 5.0, 5.0])  # before the window
    snapshot(os.path.join(run, "snapshots", "snap_1.h5"), 2.0, [0.1, 0.2, 0.3, -0.4])
    r = cd.analyse([run], 2, 1.0, 0.02)
    domain = (8 * 0.6 + 56 * 1.8) / (8 * 0.6 + 56 * 0.9) - 0.05
    check(r["snapshots"] == 1, f"only the snapshot in the window ({r['snapshots']})")
    check(abs(r["local"] - 1.2) < 1e-12, f"local slip 1.2 ({r['local']})")
    check(abs(r["domain"] - domain) < 1e-12, f"domain slip {domain:.6f} ({r['domain']})")
    check(abs(r["drift"] - (domain - 1.2)) < 1e-12, f"drift {domain - 1.2:.6f} ({r['drift']})")
    check(abs(r["phi_pw"] - 0.025) < 1e-12 and abs(r["phi_std"] - math.sqrt(0.0007 - 0.025 ** 2)) < 1e-12,
          f"phi mean 0.025, std 0.00866 ({r['phi_pw']}, {r['phi_std']})")
    check(abs(r["phi"] - 0.005) < 1e-15 and abs(r["tail"] - 0.75) < 1e-12, f"<phi> 0.005, tail 75 % ({r['tail']})")
    check(abs(r["support"] - 64.95 / 59.95) < 1e-12, f"pressure support 1.0834 ({r['support']})")
    b0, b1 = r["bins"][0], r["bins"][1]
    check(abs(b0["fraction"] - 0.25) < 1e-12 and abs(b0["slip"] - 2.4) < 1e-12 and
          abs(b1["fraction"] - 0.75) < 1e-12 and abs(b1["slip"] - 0.8) < 1e-12,
          f"per bin: 25 % at slip 2.4, 75 % at 0.8 ({b0}, {b1})")
    check(abs(b0["drag"] - 0.14) < 1e-12 and abs(b0["pressure"] - 0.004995) < 1e-12 and
          abs(b1["drag"] - 0.08) < 1e-12 and abs(b1["pressure"] - 0.006995) < 1e-12 and
          abs(r["drag"] - 0.095) < 1e-12 and abs(r["pressure"] - 0.006495) < 1e-12,
          f"force balance: drag/pressure 0.14/0.004995 and 0.08/0.006995 per bin, 0.095/0.006495 in all "
          f"({b0['drag']}, {b0['pressure']}, {b1['drag']}, {b1['pressure']}, {r['drag']}, {r['pressure']})")
    r1 = cd.analyse([run], 1, 1.0, 0.02)  # one cell: the local slip is the domain slip, no drift
    check(abs(r1["drift"]) < 1e-12 and abs(r1["local"] - domain) < 1e-12, f"one cell: drift 0 ({r1['drift']})")
    column = os.path.join(tmp, "column")
    os.makedirs(os.path.join(column, "snapshots"))
    column_snapshot(os.path.join(column, "snapshots", "snap_1.h5"))
    snap = cd.snapshot_cells(os.path.join(column, "snapshots", "snap_1.h5"), 1, 1.0)
    want_sub, want_grid = [0.05, 0.05, 0.1, -0.05, -0.05], [0.025, 0.025, 0.4, -0.2, -0.2]
    check(np.allclose(snap["subgrid_share"], want_sub, rtol=0, atol=1e-12) and
          np.allclose(snap["grid_share"], want_grid, rtol=0, atol=1e-12),
          f"momentum flux per particle: sub-grid {want_sub}, grid-scale {want_grid} "
          f"({snap['subgrid_share'].tolist()}, {snap['grid_share'].tolist()})")
    rc = cd.analyse([column], 1, 1.0, 0.015)
    c0, c1 = rc["bins"][0], rc["bins"][1]
    check(abs(c0["subgrid"] - 0.1) < 1e-12 and abs(c0["grid"] - 0.4) < 1e-12 and abs(c1["subgrid"]) < 1e-12 and
          abs(c1["grid"] + 0.0875) < 1e-12,
          f"momentum flux per bin: 0.1 / 0.4 at phi 0.01, 0 / -0.0875 at 0.02 ({c0['subgrid']}, {c0['grid']}, "
          f"{c1['subgrid']}, {c1['grid']})")
    # sub-grid pressure: cell 0 (v_y 1 and 3) R_yy = 1000 (0.1 - 0.04^2/0.02) = 20 Pa, cell 3 (v = (1, 0), (-1, 2))
    # R_xx = R_yy = 20 Pa, a lone particle 0: isotropic parts 20/3, 0 and 40/3; per bin (particle-weighted) 0 at
    # phi 0.01 and (2 x 20/3 + 2 x 40/3)/4 = 10 at 0.02
    check(np.allclose(snap["subgrid_pressure"], [20 / 3, 20 / 3, 0.0, 40 / 3, 40 / 3], rtol=0, atol=1e-9) and
          abs(c0["stress"]) < 1e-12 and abs(c1["stress"] - 10.0) < 1e-9,
          f"sub-grid pressure 6.67, 0, 13.3 Pa per cell, 0 and 10 Pa per bin ({snap['subgrid_pressure'].tolist()}, "
          f"{c0['stress']}, {c1['stress']})")
    check(abs(r["subgrid"]) < 1e-12 and abs(r["grid"]) < 1e-12,
          f"two cells across: no flux derivative ({r['subgrid']}, {r['grid']})")
    w = cd.overlap_matrix(3, 2.0 / 3.0, 0.0, 2, 1.0)
    check(np.allclose(w, [[2 / 3, 1 / 3, 0], [0, 1 / 3, 2 / 3]]), f"overlap of 3 fine cells on 2 coarse ({w.tolist()})")
    out = subprocess.run([sys.executable, tool, "--resolved", run, "--cells", "2", "--from-tref", "1"],
                         capture_output=True, text=True)
    check(out.returncode == 0 and "| resolved | 1 | 0.005 |" in out.stdout, "the table of the command line")
    for label, kw, cells in (("a missing dataset", {"drop": "eps_velocity"}, "2"),
                             ("cells far from cubes", {"box": (2.0, 2.5, 2.0)}, "2"),
                             ("no drag coefficient", {"drop": "drag_coefficient"}, "2")):
        bad = os.path.join(tmp, "bad")
        os.makedirs(os.path.join(bad, "snapshots"), exist_ok=True)
        snapshot(os.path.join(bad, "snapshots", "snap_1.h5"), 2.0, [0.1, 0.2, 0.3, -0.4], **kw)
        out = subprocess.run([sys.executable, tool, "--resolved", bad, "--cells", cells, "--from-tref", "1"],
                             capture_output=True, text=True)
        check(out.returncode == 2 and "snap_1.h5" in out.stderr and "Traceback" not in out.stderr,
              f"{label}: exit 2 naming the file ({out.returncode}: {out.stderr.strip()})")

print(f"{failures()} failure(s)")
sys.exit(1 if failures() else 0)
