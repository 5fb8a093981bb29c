#!/usr/bin/python3
"""Write a synthetic filtered file (docs/schema-filtered.md) from a known filtered drag model.

Truth (smooth, Radl-2014-like, used by the fitter's tests and the timing measurement):
    h(phi) = 0.93 (1 - exp(-phi/0.07)) (1 - (phi/0.64)^4),   a(phi) = 1.5 + 4 exp(-phi/0.12),
    H(F, phi) = h / (1 + a F).
Per run r, snapshot s, width w, bin b: count c (fixed), micro sum M = c * beta0, numerator
N = M (1 - H - e), with e = noise * (0.6 xi_{s,b} + 0.8 eta_{s,w,b}) (correlated across widths, as
the same particles feed every width) and AR(1) in time (coefficient 0.5, so neighbouring snapshots are
correlated and blocks of 10 snapshots are close to independent). H, H_low, H_high are formed from the
sums as cgd-filter does: H = 1 - sum N / sum M, interval = H -/+ 1.96 x the standard error of the
block means (the normal approximation of a block bootstrap).

Options make bad files for the refusal tests (--format, --micro-drag, --diameter, --widths, ...).
"""
import argparse
import math
import os

import h5py
import numpy as np


def truth_h(phi):
    return 0.93 * (1 - np.exp(-phi / 0.07)) * (1 - (phi / 0.64) ** 4)


def truth_a(phi):
    return 1.5 + 4 * np.exp(-phi / 0.12)


def terminal_velocity(d, rho_p, rho_f, mu, g):
    u = (rho_p - rho_f) * g * d * d / (18 * mu)
    for _ in range(200):
        re = rho_f * d * u / mu
        u = (rho_p - rho_f) * g * d * d / (18 * mu * (1 + 0.15 * re ** 0.687))
    return u


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("-o", "--output", required=True)
    p.add_argument("--runs", type=int, default=2)
    p.add_argument("--snapshots", type=int, default=60, help="per run")
    p.add_argument("--block", type=int, default=10, help="snapshots per bootstrap block")
    p.add_argument("--bins", type=int, default=25)
    p.add_argument("--phi-max", type=float, default=0.5)
    p.add_argument("--widths", type=int, default=6)
    p.add_argument("--count", type=int, default=400, help="samples per snapshot and bin")
    p.add_argument("--noise", type=float, default=0.1, help="sd of one snapshot's H")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--format", default="filtered")
    p.add_argument("--micro-drag", default="beetstra")
    p.add_argument("--diameter", type=float, default=75e-6)
    p.add_argument("--viscosity", type=float, default=1.8e-5)
    p.add_argument("--no-per-snapshot", action="store_true")
    args = p.parse_args()

    rng = np.random.default_rng(args.seed)
    d, rho_p, rho_f, mu, g = args.diameter, 1500.0, 1.3, args.viscosity, 9.81
    u_t = terminal_velocity(d, rho_p, rho_f, mu, g)
    fr = u_t * u_t / (g * d)
    l_char = d * fr ** (1.0 / 3.0)
    nb, nw, ns_run = args.bins, args.widths, args.snapshots
    ns = args.runs * ns_run
    edges = np.linspace(0.0, args.phi_max, nb + 1)
    centers = 0.5 * (edges[:-1] + edges[1:])
    width_over_dp = np.array([6.67, 10.0, 13.3, 20.0, 26.7, 40.0, 53.3, 80.0][:nw]) if nw <= 8 else \
        np.geomspace(6.67, 80, nw)
    F = l_char / (width_over_dp * d)
    box = np.array([40, 160, 40]) * d
    F_box = l_char / np.cbrt(box.prod())

    # noise: AR(1) in time per run, correlated across widths
    def noise(shape_extra):
        e = np.empty((ns,) + shape_extra)
        for r in range(args.runs):
            prev = rng.standard_normal(shape_extra)
            for s in range(ns_run):
                prev = 0.5 * prev + math.sqrt(0.75) * rng.standard_normal(shape_extra)
                e[r * ns_run + s] = prev
        return e

    common = noise((nb,))
    all_F = list(F) + [F_box]
    beta0 = 1.0e4
    count = np.full((ns, nb), args.count, dtype=np.int64)
    micro = count * beta0
    run_index = np.repeat(np.arange(args.runs), ns_run)
    block = np.concatenate([r * ((ns_run + args.block - 1) // args.block) + np.arange(ns_run) // args.block
                            for r in range(args.runs)])
    scene = open(os.path.join(os.path.dirname(__file__), "..", "..", "data", "scenes",
                              "sedimentation_demo.toml")).read()

    with h5py.File(args.output, "w") as f:
        f.attrs["cgd_format"] = args.format
        f.attrs["cgd_format_version"] = np.int64(1)
        f.attrs["code_version"] = "synthetic"
        f.attrs["created"] = "2026-01-01T00:00:00Z"
        f.attrs["scene"] = scene
        f.attrs["micro_drag"] = args.micro_drag
        f.attrs["u_t_m_s"] = u_t
        f.attrs["l_char_m"] = l_char
        f.attrs["diameter_m"] = d
        f.attrs["particle_density_kg_m3"] = rho_p
        f.attrs["fluid_density_kg_m3"] = rho_f
        f.attrs["fluid_viscosity_Pa_s"] = mu
        f.attrs["cell_size_m"] = np.array([3.33 * d] * 3)
        f.attrs["H_definition"] = "synthetic: H = h/(1 + a F) + noise"
        f.attrs["bootstrap_replicates"] = np.int64(0)
        f.attrs["bootstrap_seed"] = np.int64(args.seed)
        f.attrs["confidence"] = 0.95
        f.attrs["synthetic_truth"] = "h = 0.93 (1 - exp(-phi/0.07)) (1 - (phi/0.64)^4), a = 1.5 + 4 exp(-phi/0.12)"
        f.attrs["synthetic_noise"] = args.noise
        runs = f.create_group("runs")
        runs.attrs["paths"] = [f"synthetic/run_{r}" for r in range(args.runs)]
        runs["mean_solids_fraction"] = np.full(args.runs, 0.1)
        runs["snapshot_count"] = np.full(args.runs, ns_run, dtype=np.int64)
        runs["block_length"] = np.full(args.runs, args.block, dtype=np.int64)
        runs["tau_int"] = np.full(args.runs, 1.5)
        runs["n_eff"] = np.full(args.runs, ns_run / 3.0)
        sn = f.create_group("snapshots")
        sn["run_index"] = run_index.astype(np.int64)
        sn["time_s"] = np.arange(ns) * 0.02
        sn["step"] = np.arange(ns, dtype=np.int64)
        sn["block"] = block.astype(np.int64)
        f.create_group("bins")["phi_edges"] = edges
        f["bins"].attrs["width"] = edges[1] - edges[0]
        for k, FF in enumerate(all_F):
            whole = k == len(F)
            name = "whole_box" if whole else f"width_{k}"
            own = noise((nb,))
            e = args.noise * (0.6 * common + 0.8 * own)
            H_true = truth_h(centers) / (1 + truth_a(centers) * FF)
            numerator = micro * (1 - H_true[None, :] - e)
            H = 1 - numerator.sum(0) / micro.sum(0)
            # standard error from the block means (normal approximation of the block bootstrap)
            blocks = np.unique(block)
            bm = np.array([1 - numerator[block == b].sum(0) / micro[block == b].sum(0) for b in blocks])
            se = bm.std(0, ddof=1) / math.sqrt(len(blocks))
            grp = f.create_group(name)
            grp.attrs["width_m"] = l_char / FF
            grp.attrs["width_over_dp"] = l_char / FF / d
            grp.attrs["width_over_cell"] = l_char / FF / (3.33 * d)
            grp.attrs["F"] = FF
            grp.attrs["kind"] = "whole_box" if whole else "box"
            grp["phi_center"] = centers
            grp["count"] = count.sum(0)
            grp["phi_mean"] = centers
            grp["slip"] = np.full(nb, 0.1)
            grp["slip_over_ut"] = np.full(nb, 0.1 / u_t)
            grp["drag"] = numerator.sum(0) / count.sum(0)
            grp["beta_bar"] = beta0 * (1 - H)
            grp["beta_micro"] = np.full(nb, beta0)
            grp["H"] = H
            grp["H_low"] = H - 1.959963984540054 * se
            grp["H_high"] = H + 1.959963984540054 * se
            grp["H_stderr"] = se
            grp["n_eff"] = np.full(nb, ns / 3.0)
            if not args.no_per_snapshot:
                ps = grp.create_group("per_snapshot")
                ps["count"] = count
                ps["numerator"] = numerator
                ps["micro"] = micro
                ps["slip"] = count * 0.1
                ps["phi"] = count * centers[None, :]


if __name__ == "__main__":
    main()
