#!/usr/bin/python3
"""The accuracy-versus-cost study of the pipeline (Makefile.pipeline `study`): for every coarse run
(cgd-coarse, its summary.h5) the error of the time-averaged slip <u_slip,y>/u_t against the resolved
reference of the same solids fraction, with its statistical error, and the cost in core-seconds per
simulated second measured in the same run; the resolved runs themselves for scale. Writes a CSV, an HDF5
table (cgd_format = "study") and a log-log picture of |error| against cost with the Pareto front marked.

usage: /usr/bin/python3 tools/study.py --coarse DIR... --resolved DIR... [--resolved-ranks N] -o STUDY (writes
STUDY.csv, STUDY.h5, STUDY.png)"""
import argparse
import csv
import os
import sys
import tempfile

import h5py
import numpy as np


def batch_mean(t, y, t0, batches=10):
    """Time-weighted mean over t >= t0 with the batch-means standard error (core/time_average.hpp)."""
    m = t >= t0
    t, y = t[m], y[m]
    if len(t) < 2 * batches:
        return np.nan, np.nan
    dt = np.diff(t, append=t[-1] + np.median(np.diff(t)))
    edges = np.linspace(t[0], t[-1] + dt[-1], batches + 1)
    idx = np.clip(np.searchsorted(edges, t + 0.5 * dt, side="right") - 1, 0, batches - 1)
    means = np.array([np.sum(dt[idx == b] * y[idx == b]) / np.sum(dt[idx == b]) for b in range(batches)])
    return np.sum(dt * y) / np.sum(dt), means.std(ddof=1) / np.sqrt(batches)


def run_ranks(run, default):
    """MPI ranks of a run's last session: the checkpoint's `ranks` attribute, else `default`."""
    try:
        with h5py.File(os.path.join(run, "checkpoint.h5"), "r") as c:
            return int(c.attrs["ranks"])
    except (OSError, KeyError):
        return default


def resolved_row(run, ranks, start_tref):
    ranks = run_ranks(run, ranks)
    s = h5py.File(os.path.join(run, "series.h5"), "r")
    p = s["params"].attrs
    ut, tref = p["u_t_m_s"], p["t_ref_s"]
    t = s["time"][:]
    slip, se = batch_mean(t, s["slip_velocity"][:, 1] / ut, start_tref * tref)
    cost = s["wall_seconds"][-1] * ranks / t[-1]
    cell = (np.prod(p["box_size_m"]) / np.prod(p["cells"])) ** (1 / 3) / p["diameter_m"]
    return dict(run=run, kind="resolved", phi=float(p["solids_fraction"]), cell_over_dp=float(cell), alpha=1.0,
                drag=str(p["drag"]), slip=slip, slip_se=se, ref_slip=slip, ref_se=se, error=0.0, error_se=0.0,
                cost=cost)


def coarse_row(run):
    f = h5py.File(os.path.join(run, "summary.h5"), "r")
    a = f.attrs
    p = f["params"].attrs
    return dict(run=run, kind="coarse", phi=float(p["solids_fraction"]), cell_over_dp=float(a["cell_over_dp"]),
                alpha=float(a["parcel_size"]), drag=str(a["drag"]), slip=float(a["slip_over_ut"]),
                slip_se=float(a["slip_stderr"]), ref_slip=float(a.get("reference_slip_over_ut", np.nan)),
                ref_se=float(a.get("reference_slip_stderr", np.nan)), error=float(a.get("relative_error", np.nan)),
                error_se=float(a.get("relative_error_stderr", np.nan)),
                cost=float(a["core_seconds_per_simulated_second"]))


def pareto(rows):
    """Rows not dominated in (cost, |error|): sorted by cost, each strictly more accurate than all cheaper."""
    front, best = [], np.inf
    for r in sorted(rows, key=lambda r: r["cost"]):
        if abs(r["error"]) < best:
            front.append(r)
            best = abs(r["error"])
    return front


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--coarse", nargs="+", default=[])
    ap.add_argument("--resolved", nargs="+", default=[])
    ap.add_argument("--resolved-ranks", type=int, default=1,
                    help="ranks of the resolved runs when their checkpoint does not say (default 1)")
    ap.add_argument("--start-tref", type=float, default=15.0, help="start of the sampling window (t_ref)")
    ap.add_argument("-o", "--output", required=True, help="output stem: STEM.csv, STEM.h5, STEM.png")
    a = ap.parse_args()
    rows = [resolved_row(r, a.resolved_ranks, a.start_tref) for r in a.resolved]
    for r in a.coarse:
        try:
            rows.append(coarse_row(r))
        except OSError as e:
            sys.exit(f"study: {r}: no readable summary.h5 ({e})")
    keys = ["phi", "cell_over_dp", "alpha", "drag", "slip", "slip_se", "ref_slip", "ref_se", "error", "error_se", "cost", "kind", "run"]
    coarse = [r for r in rows if r["kind"] == "coarse"]
    # a configuration (grid, alpha, drag law) is judged over every solids fraction: its rms error and mean
    # cost; the Pareto front is over configurations (the parcel fit's own runs, model-raw, are left out).
    # A configuration run at only some of the solids fractions (Makefile.pipeline ALPHA1_PHIS) is listed
    # but not compared: its errors and cost are over another set of phi
    configs = {}
    for r in coarse:
        if r["drag"] != "model-raw":
            configs.setdefault((r["cell_over_dp"], r["alpha"], r["drag"]), []).append(r)
    agg = []
    for (cell, alpha, drag), rs in sorted(configs.items()):
        agg.append(dict(cell_over_dp=cell, alpha=alpha, drag=drag, n=len({r["phi"] for r in rs}),
                        error=float(np.sqrt(np.mean([r["error"] ** 2 for r in rs]))),
                        worst=float(max(abs(r["error"]) for r in rs)),
                        error_se=float(np.sqrt(np.mean([r["error_se"] ** 2 for r in rs]))),
                        cost=float(np.mean([r["cost"] for r in rs]))))
    n_phi = len({r["phi"] for r in coarse})
    complete = [c for c in agg if c["n"] == n_phi]
    front_cfg = {id(c) for c in pareto(complete)}
    for c in agg:
        c["pareto"] = int(id(c) in front_cfg)
    for r in rows:
        key = (r["cell_over_dp"], r["alpha"], r["drag"])
        r["pareto"] = int(r["kind"] == "coarse" and any(c["pareto"] and (c["cell_over_dp"], c["alpha"], c["drag"]) == key for c in agg))
    # CSV and HDF5, each written to a temporary name and renamed
    tmp = a.output + ".csv.tmp"
    with open(tmp, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(keys + ["pareto"])
        for r in rows:
            w.writerow([r[k] for k in keys] + [r["pareto"]])
    os.replace(tmp, a.output + ".csv")
    tmp = a.output + ".h5.tmp"
    with h5py.File(tmp, "w") as f:
        f.attrs["cgd_format"] = "study"
        f.attrs["cgd_format_version"] = 1
        f.attrs["definition"] = ("error = (slip - ref_slip)/ref_slip of <u_slip,y>/u_t averaged over the sampling window; "
                                 "*_se batch-means standard errors; cost = wall seconds x ranks / simulated seconds")
        for k in keys:
            v = [r[k] for r in rows]
            f[k] = np.array(v, dtype=h5py.string_dtype() if isinstance(v[0], str) else float) if v else np.array([])
        f["pareto"] = np.array([r["pareto"] for r in rows], dtype=np.int64)
    os.replace(tmp, a.output + ".h5")
    # table
    print(f"{'phi':>5} {'cell/d_p':>8} {'alpha':>5} {'drag':>9} {'slip/u_t':>15} {'ref':>15} {'error %':>14} {'core-s/s':>10}  pareto  run")
    for r in sorted(rows, key=lambda r: (r["phi"], r["kind"] != "resolved", r["drag"], r["cell_over_dp"], r["alpha"])):
        print(f"{r['phi']:5.2f} {r['cell_over_dp']:8.2f} {r['alpha']:5.0f} {r['drag']:>9} {r['slip']:7.3f} +- {r['slip_se']:5.3f} "
              f"{r['ref_slip']:7.3f} +- {r['ref_se']:5.3f} {100 * r['error']:6.1f} +- {100 * r['error_se']:4.1f} {r['cost']:10.3g}  "
              f"{'*' if r['pareto'] else ' '}       {os.path.basename(os.path.normpath(r['run']))}")
    print(f"\nconfigurations over {len({r['phi'] for r in coarse})} solids fraction(s): rms and worst error, mean cost")
    print(f"{'cell/d_p':>8} {'alpha':>5} {'drag':>9} {'rms error %':>12} {'worst %':>8} {'core-s/s':>9}  pareto")
    for c in sorted(agg, key=lambda c: c["cost"]):
        partial = "" if c["n"] == n_phi else f"  (run at {c['n']} of {n_phi} solids fractions: not compared)"
        print(f"{c['cell_over_dp']:8.2f} {c['alpha']:5.0f} {c['drag']:>9} {100 * c['error']:12.1f} {100 * c['worst']:8.1f} "
              f"{c['cost']:9.3g}  {'*' if c['pareto'] else ''}{partial}")
    for target in (0.05, 0.15):
        ok = [c for c in complete if c["worst"] <= target]
        pick = min(ok, key=lambda c: c["cost"]) if ok else None
        print(f"cheapest configuration within {100 * target:.0f} % at every solids fraction: " +
              (f"cell {pick['cell_over_dp']:.3g} d_p, alpha {pick['alpha']:.0f}, {pick['drag']} ({pick['cost']:.3g} core-s/s)"
               if pick else "none of the coarse runs (use the resolved run)"))
    # picture
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7.5, 5))
    markers = {"beetstra": "o", "wen-yu": "s", "model": "^", "model-raw": "x", "radl2014": "v"}
    for r in coarse:  # every run, faint
        ax.plot(r["cost"], 100 * max(abs(r["error"]), 1e-2), markers.get(r["drag"], "o"),
                color="C%d" % (int(round(r["alpha"])) % 10), ms=4, alpha=0.3)
    for c in agg:  # every configuration: rms error over the solids fractions
        ax.errorbar(c["cost"], 100 * max(c["error"], 1e-2), yerr=100 * c["error_se"], fmt=markers.get(c["drag"], "o"),
                    color="C%d" % (int(round(c["alpha"])) % 10), ms=8)
    for r in rows:
        if r["kind"] == "resolved":
            ax.axvline(r["cost"], color="gray", lw=0.8, ls=":")
    f_rows = pareto(agg)
    if f_rows:
        ax.plot([r["cost"] for r in f_rows], [100 * max(abs(r["error"]), 1e-2) for r in f_rows], "k--", lw=1, label="Pareto front")
    for d, m in markers.items():
        if any(r["drag"] == d for r in coarse):
            ax.plot([], [], m, color="k", label=f"drag: {d}")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.axhline(5, color="r", lw=0.5)
    ax.axhline(15, color="orange", lw=0.5)
    ax.set_xlabel("cost (core-seconds per simulated second)")
    ax.set_ylabel("|error of <u_slip,y>| (%)")
    ax.set_title("rms error over the solids fractions against cost (faint: single runs;\ncolour: parcel size α; dotted: resolved runs)", fontsize=9)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(a.output + ".png", dpi=120)
    print(f"wrote {a.output}.csv, {a.output}.h5, {a.output}.png")


if __name__ == "__main__":
    main()
