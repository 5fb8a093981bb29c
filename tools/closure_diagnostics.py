#!/usr/bin/python3
"""Coarse runs against the resolved runs seen on the same coarse grid (issue 28): why a closure in the
filtered solids fraction alone can miss the slip.

Every run -- resolved (cgd-generate) or coarse (cgd-coarse) -- is seen through one and the same operator: the
box filter of its snapshots onto a grid of N cells across the box width (N x round(N Ly/Lx) x round(N Lz/Lx)
cells, as the engine makes a grid of fluid.dx_over_dp = Lx/N; refused if they are more than 10 % from cubes). For each
snapshot of the window t >= T t_ref, per coarse cell c:

  phi_c   the solids volume of the particles (parcels: alpha^3 particle volumes) whose centre lies in c, over
          the cell volume (nearest-grid-point deposit: the same for a resolved run and a coarse one);
  v_c     the particles' volume-weighted mean velocity in c;
  u_c     the fluid's Favre velocity <eps u>_c / <eps>_c, the sums over the fluid cells that overlap c weighted
          by the overlapping volume (eps u: the snapshot's fluid/eps_velocity; a coarse run's own fluid
          grid is c itself when it has N cells across);
  s_c     the local slip u_c,y - v_c,y.

Per run (means over the window's snapshots; slips over u_t):

  domain slip   <eps u>/<eps> - <v>: the run's own domain slip (docs/models.md; its series' slip_velocity);
  local slip    the particle-weighted mean of s_c: the slip a closure in phi_c sees on average;
  drift         domain slip - local slip: the resolved-scale drift, the part of the slip made by the
                correlation of phi_c and u_c between the cells (the gas bypassing the dense cells at the grid's
                scale: 0 on a one-cell grid, growing as the grid is refined); a coarse run must build it with its
                own grid-scale structures, the closure acting on the local slip only;
  phi spread    the particle-weighted mean and standard deviation of phi_c, its 99th percentile, and the
                fraction of the particles in cells above 2.2 <phi> (the dense tail);
  p support     -<dp/dy> over the particles (particles/pressure_gradient plus the removed mean gradient
                /particles@pressure_gradient_mean: the fluid's whole pressure gradient at each particle) over
                the mixture weight (rho_p <phi> + rho_f (1 - <phi>)) g: 1 when the
                particles sit on average where the mean gradient is, above 1 when the fluid's pressure
                carries them more (dense cells over-compacted by the coarse run).
  (the +- of the domain slip and the drift: their snapshots' standard deviation over sqrt(count); snapshots
  0.5 t_ref apart are correlated, so it is a lower bound -- the study's batch means give the honest error)
  per phi bin   the particle fraction and the mean local slip s_c of the particles in cells of each phi bin
                (the conditional slip: the closure's own target, bin by bin);
  force balance per phi bin: what holds the particles of the bin's cells up, in units of their weight
                alpha^3 V_p rho_p g, from each particle's own forces in the snapshot: drag
                beta_p (u_y - v_y) / (rho_p g) (particles/drag_coefficient, particles/fluid_velocity: the force
                of the run's own drag law, alpha^3 V_p beta_p (u - v)), pressure -dp/dy / (rho_p g) (the whole
                gradient, as above) and the rest 1 - drag - pressure: contacts and the mean acceleration
                (~0 over all particles of a stationary run, whose contacts sum to zero). The hypothesis it
                tests: the coarse run's dense cells are held by another force than the resolved run's.
  momentum flux per phi bin: the particle phase's momentum flux between the cells, as forces in the same units
                (the y row of the divergence, central differences on the periodic coarse grid of cell size h:
                -(D_x T_xy + D_y T_yy + D_z T_zy), D_j T = (T[c + e_j] - T[c - e_j]) / 2h_j, zero along an axis of
                fewer than 3 cells), summed over the bin's cells over the weight rho_p g of their particles:
                  sub-grid    T = R_c = rho_p (sum_i V_i v_i,j v_i,y - P_c,j P_c,y / M_c) / V_c, the stress of the
                              particles' velocity fluctuations about their cell's mean velocity (M_c = sum V_i,
                              P_c = sum V_i v_i): the filtered particle-phase kinetic stress, which a coarse run
                              whose parcels move with their cell cannot carry;
                  grid-scale  T = rho_p phi_c v_c,j v_c,y, the flux of the cell-mean motion (what a coarse run
                              carries if it builds the same cells);
                  residual    rest - sub-grid - grid-scale: contacts minus the cells' momentum change in time
                              (the one term a snapshot cannot give: ~0 for a bin whose cells keep their momentum).
                sub-grid pressure  the isotropic part of R_c in Pa, (R_xx + R_yy + R_zz)/3, averaged over the bin's
                              particles: the filtered particle pressure a coarse closure would supply (its rise
                              with phi is what resists compaction; docs/closure.md "A particle-phase pressure
                              against the plug").
                A particle's Lagrangian acceleration over a cell is the Eulerian change plus the divergence of both
                fluxes, so rest = contacts + sub-grid + grid-scale - unsteady. The hypothesis it tests: the
                resolved run's dense cells are loaded by momentum carried into them at sub-grid scale (a
                particle-phase stress a coarse closure must supply), not by drag.

usage: /usr/bin/python3 tools/closure_diagnostics.py --resolved RUN [--resolved RUN]... [--coarse RUN]...
           --cells N [--from-tref T] [--coarse-from-tref T] [--bin 0.02] [-o PREFIX]
RUN is a run directory (snapshots/*.h5); several --resolved runs (seeds) are pooled as one reference; each
--coarse run is a row of its own (its label: the directory's name). Writes PREFIX.md (the tables) and
PREFIX.png (phi distributions and conditional slip) with -o; prints the tables.
Exit status 0; 2 for bad arguments or a file that is not a snapshot (the message names the file).
(Debian's h5py/numpy/matplotlib belong to /usr/bin/python3.)"""
import argparse
import glob
import math
import os
import signal
import sys

import h5py
import numpy as np


def fail(msg):
    """The message on stderr, prefixed with the running tool's name (this module's readers serve other tools too:
    layer_profile.py, model_coverage.py), and exit status 2."""
    print(f"{os.path.basename(sys.argv[0]) or 'closure_diagnostics.py'}: {msg}", file=sys.stderr)
    sys.exit(2)


def need(f, path, name, shape=None):
    if name not in f:
        fail(f"{path}: /{name} missing: not a cgd snapshot")
    d = f[name]
    if shape is not None and (len(d.shape) != len(shape) or any(s is not None and a != s for a, s in zip(d.shape, shape))):
        fail(f"{path}: /{name} has shape {d.shape}, expected {tuple('*' if s is None else s for s in shape)}")
    return d


def overlap_matrix(n_fine, h_fine, origin, n_coarse, h_coarse):
    """W[c, k]: the length of fine cell k inside coarse cell c (one direction of the periodic box)."""
    w = np.zeros((n_coarse, n_fine))
    for k in range(n_fine):
        a = origin + k * h_fine
        b = a + h_fine
        for c in range(n_coarse):
            lo, hi = c * h_coarse, (c + 1) * h_coarse
            w[c, k] = max(0.0, min(b, hi) - max(a, lo))
    return w


def open_window_snapshot(path, from_tref):
    """The snapshot file, open, when its time is at or after from_tref t_ref; None before (nothing else read). Refuses
    (exit 2) a file that is not an HDF5 file or not a cgd snapshot."""
    try:
        f = h5py.File(path, "r")
    except OSError as e:
        fail(f"{path}: not a readable HDF5 file ({e})")
    if "time" not in f.attrs or "params" not in f or "t_ref_s" not in f["params"].attrs:
        f.close()
        fail(f"{path}: no time attribute or /params@t_ref_s: not a cgd snapshot")
    if not float(f.attrs["time"]) >= from_tref * float(f["params"].attrs["t_ref_s"]) * (1 - 1e-9):
        f.close()
        return None
    if f.attrs.get("cgd_format") not in ("snapshot", b"snapshot"):
        f.close()
        fail(f"{path}: cgd_format is {f.attrs.get('cgd_format')!r}, expected 'snapshot'")
    return f


def fluid_grid(f, path):
    """The snapshot's fluid grid: cells (x, y, z), spacing, origin and the void fraction (n_z, n_y, n_x)."""
    fl = need(f, path, "fluid")
    for key in ("cells", "spacing", "origin"):
        if key not in fl.attrs:
            fail(f"{path}: /fluid attribute {key} missing")
    cells = np.asarray(fl.attrs["cells"], dtype=int)
    eps = np.asarray(need(f, path, "fluid/void_fraction", (cells[2], cells[1], cells[0]))[:], dtype=float)
    return cells, np.asarray(fl.attrs["spacing"], dtype=float), np.asarray(fl.attrs["origin"], dtype=float), eps


def snapshot_cells(path, n_cells, from_tref):
    """Per coarse cell of one snapshot: solids volume, particle volume x velocity (y), fluid <eps> and <eps u_y>
    volumes; the run's constants and the snapshot's time (s). None for a snapshot before from_tref t_ref (its
    arrays are not read)."""
    f = open_window_snapshot(path, from_tref)
    if f is None:
        return None
    with f:
        time = float(f.attrs["time"])
        p = need(f, path, "params").attrs
        for key in ("box_size_m", "particle_volume_m3", "parcel_size", "u_t_m_s", "t_ref_s", "density_kg_m3",
                    "fluid_density_kg_m3", "gravity_m_s2"):
            if key not in p:
                fail(f"{path}: /params attribute {key} missing")
        box = np.asarray(p["box_size_m"], dtype=float)
        x = np.asarray(need(f, path, "particles/position", (None, 3))[:], dtype=float)
        n = x.shape[0]
        v = np.asarray(need(f, path, "particles/velocity", (n, 3))[:], dtype=float)
        # the snapshot's gradient has the mean driving gradient G removed (docs/schema-run.md): add it back
        parts = need(f, path, "particles")
        if "pressure_gradient_mean" not in parts.attrs:
            fail(f"{path}: /particles attribute pressure_gradient_mean missing")
        dpdy = (np.asarray(need(f, path, "particles/pressure_gradient", (n, 3))[:, 1], dtype=float) +
                float(np.asarray(parts.attrs["pressure_gradient_mean"])[1]))
        beta = np.asarray(need(f, path, "particles/drag_coefficient", (n,))[:], dtype=float)
        u_p = np.asarray(need(f, path, "particles/fluid_velocity", (n, 3))[:, 1], dtype=float)
        cells_f, spacing, origin, eps = fluid_grid(f, path)
        shape_f = (cells_f[2], cells_f[1], cells_f[0])
        eu = np.asarray(need(f, path, "fluid/eps_velocity", shape_f + (3,))[:, :, :, 1], dtype=float)
        for name, a in (("particles/position", x), ("particles/velocity", v), ("fluid/void_fraction", eps),
                        ("fluid/eps_velocity", eu), ("particles/pressure_gradient", dpdy),
                        ("particles/drag_coefficient", beta), ("particles/fluid_velocity", u_p)):
            if not np.all(np.isfinite(a)):
                fail(f"{path}: /{name} holds non-finite values")
        alpha = float(p["parcel_size"])
        vol = alpha ** 3 * float(p["particle_volume_m3"])
        consts = dict(box=box, u_t=float(p["u_t_m_s"]), t_ref=float(p["t_ref_s"]), rho_p=float(p["density_kg_m3"]),
                      rho_f=float(p["fluid_density_kg_m3"]), g=abs(float(np.asarray(p["gravity_m_s2"])[1])),
                      vol=vol, time=time)
    # N cells across x, the same size along z (N x Lz/Lx), and the nearest whole number along y: the coarse
    # grid the engine makes of fluid.dx_over_dp = Lx/N (the half box's 53 x 213 x 53 d_p: 4 x 16 x 4 cells of
    # 13.25 x 13.31 x 13.25 d_p)
    grid = (n_cells, max(1, int(round(n_cells * box[1] / box[0]))), max(1, int(round(n_cells * box[2] / box[0]))))
    hs = box / np.array(grid)
    if np.max(hs) > 1.1 * np.min(hs):
        fail(f"{path}: {n_cells} cells across gives cells of {hs.tolist()} m in the box {box.tolist()}: "
             "more than 10 % from cubes")
    # particles: nearest-grid-point deposit (positions wrapped into the periodic box)
    xw = np.mod(x, box)
    idx = np.minimum((xw / hs).astype(int), np.array(grid) - 1)
    flat = (idx[:, 2] * grid[1] + idx[:, 1]) * grid[0] + idx[:, 0]
    ncell = grid[0] * grid[1] * grid[2]
    solids = np.bincount(flat, minlength=ncell) * vol
    momentum = np.bincount(flat, weights=v[:, 1], minlength=ncell) * vol
    flux = particle_flux_shares(flat, v, vol, grid, hs, consts["rho_p"], consts["g"])
    # fluid: overlap-weighted volume sums onto the coarse cells (separable)
    wx = overlap_matrix(cells_f[0], spacing[0], origin[0], grid[0], hs[0])
    wy = overlap_matrix(cells_f[1], spacing[1], origin[1], grid[1], hs[1])
    wz = overlap_matrix(cells_f[2], spacing[2], origin[2], grid[2], hs[2])
    e_c = np.einsum("zk,yj,xi,kji->zyx", wz, wy, wx, eps).reshape(-1)
    eu_c = np.einsum("zk,yj,xi,kji->zyx", wz, wy, wx, eu).reshape(-1)
    cell_volume = float(np.prod(hs))
    fine_volume = float(np.prod(spacing))
    weight = consts["rho_p"] * consts["g"]  # per unit particle volume
    return dict(flat=flat, grid=grid, solids=solids, momentum=momentum, e=e_c, eu=eu_c, cell_volume=cell_volume,
                drag_share=beta * (u_p - v[:, 1]) / weight, pressure_share=-dpdy / weight,
                subgrid_share=flux["subgrid"][flat], grid_share=flux["grid"][flat],
                subgrid_pressure=flux["pressure"][flat],
                n=n, v_y=v[:, 1], v_mean=float(v[:, 1].mean()), dpdy_mean=float(dpdy.mean()),
                u_domain=float(eu.sum() / eps.sum()), phi_mean=n * vol / float(np.prod(box)),
                fine_volume=fine_volume, **consts)


def divergence_y(t, grid, hs):
    """y row of the divergence of the cell tensors t[j] (T_jy, j = x, y, z; flat arrays of the grid's cells):
    central differences on the periodic grid, 0 along an axis of fewer than 3 cells (where c + 1 and c - 1 are
    one cell or the cell itself)."""
    shape = (grid[2], grid[1], grid[0])
    out = np.zeros(shape)
    for j, axis in ((0, 2), (1, 1), (2, 0)):
        if grid[j] < 3:
            continue
        a = t[j].reshape(shape)
        out += (np.roll(a, -1, axis=axis) - np.roll(a, 1, axis=axis)) / (2.0 * hs[j])
    return out.reshape(-1)


def particle_flux_shares(flat, v, vol, grid, hs, rho_p, g):
    """Per coarse cell: the y force of the particle phase's sub-grid and grid-scale momentum fluxes (minus the y
    row of their divergence) times the cell volume, over the weight rho_p g M_c of the cell's particles (0 in an
    empty cell), as "subgrid" and "grid"; see "momentum flux" in the module's doc. And "pressure": the isotropic
    part of the sub-grid stress, (R_xx + R_yy + R_zz)/3 with R_jj = rho_p (sum_i V_i v_i,j^2 - P_c,j^2 / M_c) / V_c,
    Pa (0 in an empty cell)."""
    ncell = grid[0] * grid[1] * grid[2]
    cell_volume = float(np.prod(hs))
    m = np.bincount(flat, minlength=ncell) * vol
    occupied = m > 0
    p = [np.bincount(flat, weights=v[:, j], minlength=ncell) * vol for j in range(3)]
    q = [np.bincount(flat, weights=v[:, j] * v[:, 1], minlength=ncell) * vol for j in range(3)]
    safe = np.where(occupied, m, 1.0)
    resolved = [np.where(occupied, p[j] * p[1] / safe, 0.0) for j in range(3)]
    subgrid = [rho_p * (q[j] - resolved[j]) / cell_volume for j in range(3)]
    gridscale = [rho_p * resolved[j] / cell_volume for j in range(3)]
    weight = rho_p * g * safe
    shares = {name: np.where(occupied, -divergence_y(t, grid, hs) * cell_volume / weight, 0.0)
              for name, t in (("subgrid", subgrid), ("grid", gridscale))}
    # R_yy is subgrid[1]; R_xx and R_zz need the squares of v_x and v_z
    r_xx, r_zz = (rho_p * (np.bincount(flat, weights=v[:, j] ** 2, minlength=ncell) * vol -
                           np.where(occupied, p[j] * p[j] / safe, 0.0)) / cell_volume for j in (0, 2))
    shares["pressure"] = (r_xx + subgrid[1] + r_zz) / 3.0
    return shares


def cell_velocities(snap):
    """u_c (the fluid's Favre velocity) and v_c (the particles' volume-weighted mean velocity, 0 in an empty cell),
    y components, per coarse cell of a snapshot_cells result."""
    occupied = snap["solids"] > 0
    v_c = np.where(occupied, snap["momentum"] / np.where(occupied, snap["solids"], 1.0), 0.0)
    return snap["eu"] / snap["e"], v_c


def run_snapshots(run):
    files = sorted(glob.glob(os.path.join(run, "snapshots", "*.h5")))
    if not files:
        fail(f"{run}: no snapshots/*.h5")
    return files


def analyse(runs, n_cells, from_tref, bin_width):
    """Pooled figures of one or more runs (their window's snapshots)."""
    phi_all, slip_all, drag_all, pressure_all, subgrid_all, grid_all, rows = [], [], [], [], [], [], []
    stress_all = []
    for run in runs:
        used = 0
        for path in run_snapshots(run):
            snap = snapshot_cells(path, n_cells, from_tref)
            if snap is None:
                continue
            used += 1
            phi = snap["solids"] / snap["cell_volume"]
            u_c, v_c = cell_velocities(snap)
            slip_c = (u_c - v_c) / snap["u_t"]
            weight = snap["solids"] / snap["solids"].sum()  # particle (volume) weight of each cell
            phi_p = phi[snap["flat"]]                    # each particle's cell phi
            slip_p = slip_c[snap["flat"]]
            phi_all.append(phi_p)
            slip_all.append(slip_p)
            drag_all.append(snap["drag_share"])
            pressure_all.append(snap["pressure_share"])
            subgrid_all.append(snap["subgrid_share"])
            grid_all.append(snap["grid_share"])
            stress_all.append(snap["subgrid_pressure"])
            domain = (snap["u_domain"] - snap["v_mean"]) / snap["u_t"]
            local = float(np.sum(weight * slip_c))
            weight_mix = (snap["rho_p"] * snap["phi_mean"] + snap["rho_f"] * (1 - snap["phi_mean"])) * snap["g"]
            rows.append(dict(domain=domain, local=local, drift=domain - local,
                             support=-snap["dpdy_mean"] / weight_mix, phi_mean=snap["phi_mean"]))
        if used == 0:
            fail(f"{run}: no snapshot at or after {from_tref} t_ref")
    phi_p = np.concatenate(phi_all)
    slip_p = np.concatenate(slip_all)
    drag_p = np.concatenate(drag_all)
    pressure_p = np.concatenate(pressure_all)
    subgrid_p = np.concatenate(subgrid_all)
    grid_p = np.concatenate(grid_all)
    stress_p = np.concatenate(stress_all)
    phi_mean = rows[0]["phi_mean"]
    mean = lambda k: float(np.mean([r[k] for r in rows]))  # noqa: E731
    stderr = lambda k: float(np.std([r[k] for r in rows], ddof=1) / math.sqrt(len(rows))) if len(rows) > 1 else math.nan  # noqa: E731
    edges = np.arange(0.0, max(phi_p.max(), 0.0) + bin_width, bin_width)
    which = np.minimum(np.digitize(phi_p, edges) - 1, len(edges) - 2)
    bins = []
    for b in range(len(edges) - 1):
        sel = which == b
        bins.append(dict(lo=edges[b], hi=edges[b + 1], fraction=float(sel.mean()),
                         slip=float(slip_p[sel].mean()) if sel.any() else math.nan,
                         drag=float(drag_p[sel].mean()) if sel.any() else math.nan,
                         pressure=float(pressure_p[sel].mean()) if sel.any() else math.nan,
                         subgrid=float(subgrid_p[sel].mean()) if sel.any() else math.nan,
                         grid=float(grid_p[sel].mean()) if sel.any() else math.nan,
                         stress=float(stress_p[sel].mean()) if sel.any() else math.nan))
    return dict(snapshots=len(rows), phi=phi_mean, domain=mean("domain"), domain_err=stderr("domain"),
                local=mean("local"), drift=mean("drift"), drift_err=stderr("drift"), support=mean("support"),
                phi_pw=float(phi_p.mean()), phi_std=float(phi_p.std()), phi_p99=float(np.percentile(phi_p, 99)),
                tail=float(np.mean(phi_p > 2.2 * phi_mean)), bins=bins, phi_p=phi_p,
                drag=float(drag_p.mean()), pressure=float(pressure_p.mean()),
                subgrid=float(subgrid_p.mean()), grid=float(grid_p.mean()))


def balance(r):
    """drag / pressure / rest of a bin (or of a run's particles): each a share of the weight."""
    return f"{r['drag']:.2f} / {r['pressure']:.2f} / {1 - r['drag'] - r['pressure']:+.2f}"


def fluxes(r):
    """sub-grid / grid-scale / residual of a bin (or of a run's particles): each a share of the weight."""
    rest = 1 - r["drag"] - r["pressure"]
    return f"{r['subgrid']:+.2f} / {r['grid']:+.2f} / {rest - r['subgrid'] - r['grid']:+.2f}"


def bin_table(results, cell, first=None):
    """A Markdown table of one row per phi bin that holds particles in some run, a column per run: cell(bin) where
    the run's bin holds particles, empty otherwise; `first` = (label, results): a row of cell(run) above them."""
    width = results[0][1]["bins"][0]["hi"] - results[0][1]["bins"][0]["lo"]
    rows = ["| phi bin | " + " | ".join(label for label, _ in results) + " |", "|---|" + "---|" * len(results)]
    if first is not None:
        rows.append(f"| {first[0]} | " + " | ".join(cell(r) for _, r in first[1]) + " |")
    for b in range(max(len(r["bins"]) for _, r in results)):
        cells = [cell(r["bins"][b]) if b < len(r["bins"]) and r["bins"][b]["fraction"] > 0 else "" for _, r in results]
        if any(cells):
            rows.append(f"| {b * width:.2f}-{b * width + width:.2f} | " + " | ".join(cells) + " |")
    return rows


def tables(results, n_cells, from_tref, coarse_from_tref=None):
    window = f"{from_tref:g} t_ref" + ("" if coarse_from_tref is None else f" (coarse runs: {coarse_from_tref:g})")
    out = [f"Runs seen on the grid of {n_cells} cells across (box filter, nearest-grid-point particles), "
           f"snapshots from {window}; slips over u_t; ± snapshot scatter / sqrt(count), a lower bound "
           "(correlated snapshots).", "",
           "| run | snapshots | <phi> | domain slip | local slip | drift | phi (pw) mean / std / p99 | "
           "particles at phi > 2.2 <phi> | p support |", "|---|---|---|---|---|---|---|---|---|"]
    for label, r in results:
        err = f" ± {r['domain_err']:.3f}" if math.isfinite(r["domain_err"]) else ""
        derr = f" ± {r['drift_err']:.3f}" if math.isfinite(r["drift_err"]) else ""
        out.append(f"| {label} | {r['snapshots']} | {r['phi']:.3f} | {r['domain']:.3f}{err} | {r['local']:.3f} | "
                   f"{r['drift']:.3f}{derr} | {r['phi_pw']:.3f} / {r['phi_std']:.3f} / {r['phi_p99']:.3f} | "
                   f"{100 * r['tail']:.1f} % | {r['support']:.2f} |")
    out += ["", "Conditional slip: particle fraction and mean local slip per phi bin", ""]
    out += bin_table(results, lambda bn: f"{100 * bn['fraction']:.1f} % : {bn['slip']:.3f}")
    out += ["", "Vertical force balance per phi bin, in units of the particles' weight: drag / pressure / rest "
            "(contacts and mean acceleration); the first row over all particles", ""]
    out += bin_table(results, balance, first=("all", results))
    out += ["", "Particle-phase momentum flux between the cells per phi bin, in the same units: sub-grid (the "
            "particles' velocity fluctuations in their cell) / grid-scale (the cells' mean motion) / residual (rest - "
            "both: contacts minus the cells' momentum change)", ""]
    out += bin_table(results, fluxes, first=("all", results))
    out += ["", "Sub-grid particle pressure per phi bin, Pa: the isotropic part of the particles' velocity-fluctuation "
            "stress in their cell, averaged over the bin's particles", ""]
    out += bin_table(results, lambda bn: f"{bn['stress']:.3f}")
    return "\n".join(out)


def plot(results, prefix):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
    for label, r in results:
        lo = np.array([bn["lo"] for bn in r["bins"]])
        w = r["bins"][0]["hi"] - r["bins"][0]["lo"]
        frac = np.array([bn["fraction"] for bn in r["bins"]])
        slip = np.array([bn["slip"] for bn in r["bins"]])
        ax[0].step(lo + w, frac / w, where="pre", label=label)
        keep = frac > 1e-3
        ax[1].plot(lo[keep] + w / 2, slip[keep], "o-", ms=3, label=label)
    ax[0].set_xlabel("cell $\\bar\\phi$ (box filter)")
    ax[0].set_ylabel("particle-weighted density")
    ax[1].set_xlabel("cell $\\bar\\phi$")
    ax[1].set_ylabel("local slip / $u_t$")
    ax[1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(prefix + ".png", dpi=120)


def main():
    signal.signal(signal.SIGPIPE, signal.SIG_DFL)  # `| head` closes the pipe: no traceback
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--resolved", action="append", default=[], help="a resolved run directory (repeat: pooled)")
    ap.add_argument("--coarse", action="append", default=[], help="a coarse run directory (repeat: one row each)")
    ap.add_argument("--cells", type=int, required=True, help="cells across the box width of the common grid")
    ap.add_argument("--from-tref", type=float, default=20.0, help="first snapshot time, t_ref (default 20)")
    ap.add_argument("--coarse-from-tref", type=float, default=None,
                    help="first snapshot time of the coarse runs, t_ref (default: --from-tref; a coarse run's "
                         "homogeneous transient lasts longer: the pipeline samples PROFILE=half's from 40)")
    ap.add_argument("--bin", type=float, default=0.02, help="phi bin width (default 0.02)")
    ap.add_argument("-o", dest="prefix", help="write PREFIX.md and PREFIX.png")
    a = ap.parse_args()
    if not a.resolved:
        fail("give at least one --resolved run")
    if a.cells < 1:
        fail(f"--cells {a.cells}: must be >= 1")
    if not a.bin > 0:
        fail(f"--bin {a.bin}: must be > 0")
    for run in a.resolved + a.coarse:
        if not os.path.isdir(run):
            fail(f"{run}: not a run directory")
    results = [("resolved" + (f" ({len(a.resolved)} runs)" if len(a.resolved) > 1 else ""),
                analyse(a.resolved, a.cells, a.from_tref, a.bin))]
    for run in a.coarse:
        results.append((os.path.basename(os.path.normpath(run)),
                        analyse([run], a.cells, a.from_tref if a.coarse_from_tref is None else a.coarse_from_tref,
                                a.bin)))
    text = tables(results, a.cells, a.from_tref, a.coarse_from_tref)
    print(text)
    if a.prefix:
        with open(a.prefix + ".md", "w") as f:
            f.write(text + "\n")
        plot(results, a.prefix)


if __name__ == "__main__":
    main()
