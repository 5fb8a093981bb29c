#!/usr/bin/python3
"""How much of a run lies where a drag model has data? A filtered drag model (cgd-fit's file, docs/schema-drag-model.md)
is calibrated on filtered solids fractions phi_crit <= phi_bar <= phi_max and on cells of the calibrated widths; below
phi_crit it takes h linearly to 0 (a held), above phi_max it holds h and a at their end values, and outside the
calibrated cells it extrapolates 1/(1 + a F^n). This tool reads a run's snapshots in its
window and says which share of its particles (parcels) sat where no data stands behind the correction.

phi_bar of a particle is what the engine's drag law sees: the cell solids fraction 1 - eps of the snapshot's fluid
grid interpolated to the particle's position with the coupling's TSC weights (docs/models.md "Coupling kernel": cell
centres at integer + 1/2, three cells per axis, periodic box). Delta is the cube root of the fluid cell's volume
times fluid.filter_to_grid_ratio (--filter-ratio, default 1), against the model's calibrated_delta_m.

usage: /usr/bin/python3 tools/model_coverage.py RUN_DIR... --model MODEL.h5 [--from-tref 40] [--filter-ratio 1] [--markdown]
Prints per run: snapshots used, particles per snapshot, Delta/d_p and whether it lies in the calibrated range, the
shares of particle-snapshots with phi_bar below phi_crit, inside [phi_crit, phi_max] and above phi_max, and the 50,
90, 99 % quantiles and the largest phi_bar. Exit status 0; 2 for a model without phi_max, a directory without
snapshots in the window, or a snapshot that is not one (the checks of tools/closure_diagnostics.py).
(Debian's h5py/numpy belong to /usr/bin/python3.)"""
import argparse
import collections
import sys

import h5py
import numpy as np

import closure_diagnostics as cd

Coverage = collections.namedtuple("Coverage", "snapshots particles delta_dp below inside above q50 q90 q99 largest")


def read_model(path):
    """phi_crit, phi_max, the calibrated cell widths in m, the particle diameter in m."""
    try:
        f = h5py.File(path, "r")
    except OSError as e:
        cd.fail(f"{path}: not a readable HDF5 file ({e})")
    with f:
        if f.attrs.get("cgd_format") not in ("drag_model", b"drag_model"):
            cd.fail(f"{path}: cgd_format is {f.attrs.get('cgd_format')!r}, expected 'drag_model'")
        for key in ("phi_crit", "phi_max", "diameter_m"):
            if key not in f.attrs or not np.isfinite(float(f.attrs[key])):
                cd.fail(f"{path}: attribute {key} missing or not finite (a model of cgd-fit has it)")
        delta = np.asarray(f.attrs.get("calibrated_delta_m", []), dtype=float).reshape(-1)
        return float(f.attrs["phi_crit"]), float(f.attrs["phi_max"]), delta, float(f.attrs["diameter_m"])


def tsc_weights(s):
    """Per axis: the nearest cell centre c (cell units, centres at integer + 1/2) and the weights on c-1, c, c+1."""
    c = np.floor(s).astype(int)
    d = s - (c + 0.5)
    return c, np.stack([0.5 * (0.5 - d) ** 2, 0.75 - d * d, 0.5 * (0.5 + d) ** 2], axis=1)


def phi_at_particles(x, solids, origin, spacing):
    """The cell field `solids` (n_z, n_y, n_x) interpolated to the positions x (N, 3) with the TSC weights, periodic."""
    nz, ny, nx = solids.shape
    n = np.array([nx, ny, nz])
    cs, ws = [], []
    for a in range(3):
        c, w = tsc_weights((x[:, a] - origin[a]) / spacing[a])
        cs.append(c)
        ws.append(w)
    out = np.zeros(x.shape[0])
    for k in range(3):
        iz = np.mod(cs[2] + k - 1, n[2])
        for j in range(3):
            iy = np.mod(cs[1] + j - 1, n[1])
            wzy = ws[2][:, k] * ws[1][:, j]
            for i in range(3):
                ix = np.mod(cs[0] + i - 1, n[0])
                out += wzy * ws[0][:, i] * solids[iz, iy, ix]
    return out


def snapshot_phi(path, from_tref):
    """phi_bar at each particle of one snapshot and its fluid cell volume; None before from_tref t_ref."""
    f = cd.open_window_snapshot(path, from_tref)
    if f is None:
        return None
    with f:
        x = np.asarray(cd.need(f, path, "particles/position", (None, 3))[:], dtype=float)
        _, spacing, origin, eps = cd.fluid_grid(f, path)
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(eps))):
            cd.fail(f"{path}: /particles/position or /fluid/void_fraction holds non-finite values")
    return phi_at_particles(x, 1.0 - eps, origin, spacing), float(np.prod(spacing))


def coverage(run, model, from_tref, filter_ratio):
    phi_crit, phi_max, _, _ = model
    phis, cell_volume, used = [], None, 0
    for path in cd.run_snapshots(run):
        got = snapshot_phi(path, from_tref)
        if got is None:
            continue
        phis.append(got[0])
        cell_volume = got[1]
        used += 1
    if not phis:
        return None
    phi = np.concatenate(phis)
    delta = filter_ratio * cell_volume ** (1.0 / 3.0)
    q = np.quantile(phi, [0.5, 0.9, 0.99])
    return Coverage(used, phi.size // used, delta / model[3], float(np.mean(phi < phi_crit)),
                    float(np.mean((phi >= phi_crit) & (phi <= phi_max))), float(np.mean(phi > phi_max)),
                    float(q[0]), float(q[1]), float(q[2]), float(phi.max()))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--model", required=True, help="the drag model file (cgd-fit's output)")
    ap.add_argument("--from-tref", type=float, default=40.0, help="first snapshot time in t_ref (default 40)")
    ap.add_argument("--filter-ratio", type=float, default=1.0,
                    help="the runs' fluid.filter_to_grid_ratio: Delta = ratio x the cell (default 1)")
    ap.add_argument("--markdown", action="store_true")
    a = ap.parse_intermixed_args()
    if not a.filter_ratio > 0:
        cd.fail(f"--filter-ratio {a.filter_ratio}: must be positive")
    model = read_model(a.model)
    phi_crit, phi_max, deltas, d = model
    span = (f"{deltas.min() / d:.2f}-{deltas.max() / d:.2f} d_p" if deltas.size else "not recorded")
    print(f"{a.model}: phi_bar calibrated on [{phi_crit:.3f}, {phi_max:.3f}], cells of {span}")
    if a.markdown:
        print("| run | snapshots | particles | Delta/d_p | phi_bar < phi_crit | inside | > phi_max | "
              "phi_bar 50 / 90 / 99 % | largest |")
        print("|---|---|---|---|---|---|---|---|---|")
    status = 0
    for run in a.runs:
        c = coverage(run, model, a.from_tref, a.filter_ratio)
        if c is None:
            print(f"{run}: no snapshot at or after {a.from_tref} t_ref", file=sys.stderr)
            status = 2
            continue
        inside = (not deltas.size or
                  deltas.min() / d * (1 - 1e-6) <= c.delta_dp <= deltas.max() / d * (1 + 1e-6))
        where = "inside" if inside else "OUTSIDE"
        if a.markdown:
            print(f"| {run} | {c.snapshots} | {c.particles} | {c.delta_dp:.2f} ({where}) | {100 * c.below:.1f} % | "
                  f"{100 * c.inside:.1f} % | {100 * c.above:.1f} % | {c.q50:.3f} / {c.q90:.3f} / {c.q99:.3f} | "
                  f"{c.largest:.3f} |")
        else:
            print(f"{run}: {c.snapshots} snapshots, {c.particles} particles; Delta {c.delta_dp:.2f} d_p ({where} the "
                  f"calibrated cells); phi_bar below phi_crit {100 * c.below:.1f} %, inside {100 * c.inside:.1f} %, "
                  f"above phi_max {100 * c.above:.1f} % (held at its end value there); phi_bar 50/90/99 % "
                  f"{c.q50:.3f} / {c.q90:.3f} / {c.q99:.3f}, largest {c.largest:.3f}")
    return status


if __name__ == "__main__":
    sys.exit(main())
