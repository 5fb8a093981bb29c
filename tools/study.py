#!/usr/bin/python3
"""The accuracy-versus-cost study of the pipeline (Makefile.pipeline `study`): for every coarse configuration
(solids fraction, grid, parcel size, drag law) the mean time-averaged slip <u_slip,y>/u_t over its realisations
(coarse runs that differ only in particles.seed), its error against the resolved reference of the same solids
fraction (the mean over the resolved runs of that fraction), with an error bar that holds the scatter between
realisations and the reference's own error, and the cost in core-seconds per simulated second measured in the
same runs; per (grid, parcel size, law) the rms error over the solids fractions with a bootstrap interval, and the
Pareto front of cost against that error's upper 68 % bound. Writes a CSV per configuration, a CSV per run, an HDF5
table (cgd_format = "study", version 2; docs/schema-study.md) and a log-log picture.

usage: /usr/bin/python3 tools/study.py --coarse DIR... [--resolved SUMMARY.h5...] -o STEM
  --coarse     coarse run directories (cgd-coarse, each with summary.h5); a directory named
               ..._<label>_s<seed> (Makefile.pipeline) gives the law's label, else the summary's `label` or `drag`
  --resolved   slip summaries of the resolved runs over the study's window (cgd-coarse --summarise RUN_DIR
               --from-tref T -o FILE); a solids fraction without one uses the reference stored in its coarse runs'
               summaries (cgd-coarse --reference)
  writes STEM.csv, STEM_runs.csv, STEM.h5, STEM.png"""
import argparse
import csv
import os
import re
import sys

import h5py
import numpy as np

LABEL_RE = re.compile(r"_(micro|model|modelraw|radl2014|perfect|drift|wide)_s(\d+)$")
PARCEL_FIT_LABELS = ("modelraw", "model-raw")  # the parcel fit's own runs: listed, never compared
BOOTSTRAP_QUANTILES = (0.16, 0.84)  # a 68 % interval: the 1-sigma band of a normal distribution


def fail(message):
    """Bad input: the message on stderr, exit status 2, nothing written."""
    sys.stderr.write(f"study: {message}\n")
    sys.exit(2)


def text(v):
    return v.decode() if isinstance(v, bytes) else str(v)


def read_summary(path, kind, run, label_by="auto"):
    """One run's row from a coarse_summary file (cgd-coarse, or cgd-coarse --summarise for a resolved run).
    label_by "dir": the run directory's name is the label (every run its own configuration)."""
    try:
        f = h5py.File(path, "r")
    except OSError as e:
        fail(f"{path}: no readable summary ({e})")
    with f:
        a = f.attrs
        if text(a.get("cgd_format", "")) != "coarse_summary":
            fail(f"{path}: cgd_format is {text(a.get('cgd_format', ''))!r}, expected 'coarse_summary' "
                     f"(a cgd-coarse summary.h5, or cgd-coarse --summarise RUN_DIR -o FILE for a resolved run)")
        p = f["params"].attrs if "params" in f else {}
        drag = text(a["drag"])
        m = LABEL_RE.search(os.path.basename(os.path.normpath(run)))
        label = text(a["label"]) if "label" in a else (m.group(1) if m else ("modelraw" if drag == "model-raw" else drag))
        if label_by == "dir":
            label = os.path.basename(os.path.normpath(run))
        seed = int(p["seed"]) if "seed" in p else (int(m.group(2)) if m else 1)
        get = lambda k, d=np.nan: float(a[k]) if k in a else d
        return dict(run=run, kind=kind, phi=float(p["solids_fraction"]), cell_over_dp=float(a["cell_over_dp"]),
                    alpha=float(a["parcel_size"]), drag=label, law=drag, seed=seed, slip=float(a["slip_over_ut"]),
                    slip_se=float(a["slip_stderr"]), drift=get("drift_over_ut"), drift_se=get("drift_stderr"),
                    stationary=int(a["stationary"]) if "stationary" in a else -1,
                    window_start_s=get("window_start_s"), window_end_s=get("window_end_s"),
                    t_ref_s=float(p["t_ref_s"]) if "t_ref_s" in p else np.nan,
                    cost=float(a["core_seconds_per_simulated_second"]), reused=int("reused_from" in a),
                    ref_slip=get("reference_slip_over_ut"), ref_se=get("reference_slip_stderr"))


def pool(values, errors):
    """Mean of R realisations and its standard error: the larger of the between-realisation one (sd/sqrt(R),
    R >= 2) and the batch-means errors combined (sqrt(sum se^2)/R). With R = 1 only the batch-means error exists,
    and it is known to run low (a single run's slip wanders between windows by more than it says)."""
    v, e = np.asarray(values, float), np.asarray(errors, float)
    r = len(v)
    within = np.sqrt(np.sum(e ** 2)) / r
    sd = float(v.std(ddof=1)) if r >= 2 else np.nan
    se = max(sd / np.sqrt(r), within) if r >= 2 else within
    return float(v.mean()), float(se), sd


def relative_error(m, m_se, ref, ref_se):
    return m / ref - 1, abs(m / ref) * np.hypot(m_se / m, ref_se / ref)


def pareto(items, key):
    """Items not dominated in (cost, key): sorted by cost, each strictly better than every cheaper one."""
    front, best = [], np.inf
    for c in sorted(items, key=lambda c: c["cost"]):
        if c[key] < best:
            front.append(c)
            best = c[key]
    return front


MARKERS = {"micro": "o", "model": "^", "modelraw": "x", "radl2014": "v", "perfect": "*", "drift": "D", "wide": "P"}


def draw(configs, agg, ref_costs, plt):
    """The study's picture (study.png; tools/cgd-show STUDY.h5 --plot): every configuration at every phi (faint) and
    the rms error over the solids fractions with its 68 % interval against cost; marker = law, colour = parcel size
    alpha (both keyed), the Pareto front, the 5 % and 15 % error levels labelled, the resolved runs' costs dotted.
    configs: dicts with cost, error, drag, alpha; agg: with cost, error, rms_low, rms_high, drag, alpha, pareto."""
    fig, ax = plt.subplots(figsize=(8.5, 5))
    colour = lambda alpha: "C%d" % (int(round(alpha)) % 10)
    for c in configs:  # every configuration at every phi, faint
        ax.plot(c["cost"], 100 * max(abs(c["error"]), 1e-2), MARKERS.get(c["drag"], "s"), color=colour(c["alpha"]),
                ms=4, alpha=0.3)
    for c in agg:  # rms error over the solids fractions with its 68 % interval
        y = 100 * max(c["error"], 1e-2)
        ax.errorbar(c["cost"], y, yerr=[[max(y - 100 * c["rms_low"], 0)], [max(100 * c["rms_high"] - y, 0)]],
                    fmt=MARKERS.get(c["drag"], "s"), color=colour(c["alpha"]), ms=8)
    for cost in ref_costs:
        ax.axvline(cost, color="gray", lw=0.8, ls=":")
    if ref_costs:
        ax.plot([], [], color="gray", lw=0.8, ls=":", label="resolved runs' cost")
    front = sorted([c for c in agg if c["pareto"]], key=lambda c: c["cost"])
    if front:
        ax.plot([c["cost"] for c in front], [100 * max(c["rms_high"], 1e-2) for c in front], "k--", lw=1,
                label="Pareto front (upper 68 % bound)")
    for d, m in MARKERS.items():
        if any(c["drag"] == d for c in configs):
            ax.plot([], [], m, color="k", label=f"law: {d}")
    for alpha in sorted({c["alpha"] for c in configs}):  # the colour key
        ax.plot([], [], "s", color=colour(alpha), ms=8, label=f"α = {alpha:g}")
    ax.set_xscale("log")
    ax.set_yscale("log")
    for level, col in ((5, "r"), (15, "orange")):
        ax.axhline(level, color=col, lw=0.6)
        ax.annotate(f"{level} % error", xy=(1.0, level), xycoords=("axes fraction", "data"), xytext=(-4, 2),
                    textcoords="offset points", ha="right", va="bottom", fontsize=8, color=col)
    ax.set_xlabel("cost (core-seconds per simulated second)")
    ax.set_ylabel("|error of <u_slip,y>| (%)")
    ax.set_title("rms error over the solids fractions (68 % interval) against cost\n(faint: single configurations; "
                 "marker: law; colour: parcel size α)", fontsize=9)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    fig.tight_layout()
    return fig


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--coarse", nargs="+", default=[])
    ap.add_argument("--resolved", nargs="+", default=[], help="slip summaries of the resolved runs (cgd-coarse --summarise)")
    ap.add_argument("--bootstrap", type=int, default=4000, help="replicates of the rms error's interval (default 4000)")
    ap.add_argument("--seed", type=int, default=1, help="seed of the bootstrap (default 1)")
    ap.add_argument("--label-by", choices=["auto", "dir"], default="auto",
                    help="auto (default): the summary's label, the pipeline's ..._<label>_s<seed> name, or the law; "
                         "dir: each coarse run directory's name (every run its own configuration: study-resolved)")
    ap.add_argument("-o", "--output", required=True, help="output stem: STEM.csv, STEM_runs.csv, STEM.h5, STEM.png")
    a = ap.parse_args()
    if a.bootstrap < 100:
        fail(f"--bootstrap {a.bootstrap}: at least 100 replicates (the 16/84 % quantiles need them)")
    for r in a.resolved:
        if os.path.isdir(r):
            fail(f"--resolved {r} is a run directory; give its slip summary (cgd-coarse --summarise {r} "
                     f"--from-tref T -o FILE.h5), as Makefile.pipeline does")
    resolved = [read_summary(r, "resolved", r) for r in a.resolved]
    coarse = [read_summary(os.path.join(r, "summary.h5"), "coarse", r, a.label_by) for r in a.coarse]
    for r in resolved:  # a resolved run is its own drag law on its own grid
        r["drag"], r["alpha"] = "resolved", 1.0

    # ---- references: every resolved run of a solids fraction pooled ----
    refs = {}
    for phi in sorted({r["phi"] for r in resolved}):
        rs = [r for r in resolved if r["phi"] == phi]
        m, se, sd = pool([r["slip"] for r in rs], [r["slip_se"] for r in rs])
        refs[phi] = dict(phi=phi, R=len(rs), slip=m, slip_se=se, slip_sd=sd, cost=float(np.mean([r["cost"] for r in rs])),
                         cell_over_dp=rs[0]["cell_over_dp"], runs=rs, source="resolved")
    for phi in sorted({r["phi"] for r in coarse} - set(refs)):
        rs = [r for r in coarse if r["phi"] == phi and np.isfinite(r["ref_slip"])]
        if not rs:
            fail(f"<phi> = {phi:g}: no resolved summary (--resolved) and no reference in its coarse runs' "
                     f"summaries (cgd-coarse --reference): its error cannot be computed")
        refs[phi] = dict(phi=phi, R=0, slip=rs[0]["ref_slip"], slip_se=rs[0]["ref_se"], slip_sd=np.nan, cost=np.nan,
                         cell_over_dp=np.nan, runs=[], source="coarse summaries")

    # ---- configurations: the realisations of one (phi, grid, alpha, law) pooled ----
    groups = {}
    for r in coarse:
        groups.setdefault((r["phi"], round(r["cell_over_dp"], 6), r["alpha"], r["drag"]), []).append(r)
    configs = []
    for (phi, cell, alpha, label), rs in sorted(groups.items()):
        seeds = [r["seed"] for r in rs]
        if len(set(seeds)) != len(seeds):
            fail(f"<phi> = {phi:g}, cell {cell:.3g} d_p, alpha {alpha:g}, {label}: two runs with the same "
                     f"seed {sorted(s for s in seeds if seeds.count(s) > 1)[0]} ({', '.join(r['run'] for r in rs)}): "
                     f"realisations must differ in particles.seed")
        m, se, sd = pool([r["slip"] for r in rs], [r["slip_se"] for r in rs])
        ref = refs[phi]
        err, err_se = relative_error(m, se, ref["slip"], ref["slip_se"])
        configs.append(dict(kind="coarse", phi=phi, cell_over_dp=rs[0]["cell_over_dp"], alpha=alpha, drag=label,
                            law=rs[0]["law"], R=len(rs), slip=m, slip_se=se, slip_sd=sd,
                            slip_se_batch=float(np.sqrt(np.sum([r["slip_se"] ** 2 for r in rs])) / len(rs)),
                            ref_slip=ref["slip"], ref_se=ref["slip_se"], ref_R=ref["R"], error=err, error_se=err_se,
                            drift=float(np.mean([r["drift"] for r in rs])),
                            nonstationary=sum(r["stationary"] == 0 for r in rs),
                            cost=float(np.mean([r["cost"] for r in rs])), reused=sum(r["reused"] for r in rs),
                            seeds=" ".join(str(s) for s in sorted(seeds)), runs=rs))

    # ---- summary over the solids fractions: rms error with a parametric bootstrap ----
    # Each replicate draws every configuration's mean slip from N(slip, slip_se) and every reference from
    # N(ref, ref_se) (one draw per phi, shared by the configurations of that phi) and recomputes the errors, the rms
    # and the worst |error|. Reported: the rms of the measured errors, the bootstrap's standard deviation of it
    # (rms_sd) and its 16-84 % interval (rms_low, rms_high); the same for the worst |error|.
    rng = np.random.default_rng(a.seed)
    phis = sorted(refs)
    ref_draws = {phi: rng.normal(refs[phi]["slip"], refs[phi]["slip_se"], a.bootstrap) for phi in phis}
    for c in configs:
        c["draws"] = rng.normal(c["slip"], c["slip_se"], a.bootstrap) / ref_draws[c["phi"]] - 1
    by_cfg = {}
    for c in configs:
        if c["drag"] not in PARCEL_FIT_LABELS:
            by_cfg.setdefault((round(c["cell_over_dp"], 6), c["alpha"], c["drag"]), []).append(c)
    agg = []
    for (cell, alpha, label), cs in sorted(by_cfg.items()):
        e = np.array([c["error"] for c in cs])
        d = np.array([c["draws"] for c in cs])
        rms_b = np.sqrt(np.mean(d ** 2, axis=0))
        worst_b = np.max(np.abs(d), axis=0)
        lo, hi = np.quantile(rms_b, BOOTSTRAP_QUANTILES)
        wlo, whi = np.quantile(worst_b, BOOTSTRAP_QUANTILES)
        agg.append(dict(cell_over_dp=cs[0]["cell_over_dp"], alpha=alpha, drag=label, n=len(cs),
                        R=" ".join(str(c["R"]) for c in sorted(cs, key=lambda c: c["phi"])),
                        error=float(np.sqrt(np.mean(e ** 2))), rms_sd=float(rms_b.std(ddof=1)), rms_low=float(lo),
                        rms_high=float(hi), worst=float(np.max(np.abs(e))), worst_low=float(wlo), worst_high=float(whi),
                        cost=float(np.mean([c["cost"] for c in cs]))))
    n_phi = len({c["phi"] for c in configs})
    complete = [c for c in agg if c["n"] == n_phi]
    front = {id(c) for c in pareto(complete, "rms_high")}
    for c in agg:
        c["pareto"] = int(id(c) in front)
    on_front = {(round(c["cell_over_dp"], 6), c["alpha"], c["drag"]) for c in agg if c["pareto"]}
    for c in configs:
        c["pareto"] = int((round(c["cell_over_dp"], 6), c["alpha"], c["drag"]) in on_front)

    # rows of the main table: one per pooled reference (kind resolved), then one per coarse configuration
    rows = [dict(kind="resolved", phi=phi, cell_over_dp=ref["cell_over_dp"], alpha=1.0, drag="resolved",
                 law=(ref["runs"][0]["law"] if ref["runs"] else "resolved"), R=ref["R"], slip=ref["slip"],
                 slip_se=ref["slip_se"], slip_sd=ref["slip_sd"],
                 slip_se_batch=(float(np.sqrt(np.sum([r["slip_se"] ** 2 for r in ref["runs"]])) / len(ref["runs"]))
                                if ref["runs"] else ref["slip_se"]),
                 ref_slip=ref["slip"], ref_se=ref["slip_se"], ref_R=ref["R"], error=0.0, error_se=0.0,
                 drift=float(np.mean([r["drift"] for r in ref["runs"]])) if ref["runs"] else np.nan,
                 nonstationary=sum(r["stationary"] == 0 for r in ref["runs"]), cost=ref["cost"], reused=0,
                 seeds=" ".join(str(r["seed"]) for r in ref["runs"]), pareto=0, runs=ref["runs"])
            for phi, ref in sorted(refs.items()) if ref["R"] > 0] + configs
    keys = ["phi", "cell_over_dp", "alpha", "drag", "law", "R", "slip", "slip_se", "slip_sd", "slip_se_batch",
            "ref_slip", "ref_se", "ref_R", "error", "error_se", "drift", "nonstationary", "cost", "reused", "seeds",
            "kind", "pareto"]
    run_rows = resolved + coarse
    run_keys = ["phi", "cell_over_dp", "alpha", "drag", "law", "seed", "slip", "slip_se", "drift", "drift_se",
                "stationary", "window_start_s", "window_end_s", "cost", "reused", "kind", "run"]
    sum_keys = ["cell_over_dp", "alpha", "drag", "n", "R", "error", "rms_sd", "rms_low", "rms_high", "worst",
                "worst_low", "worst_high", "cost", "pareto"]

    # ---- files, each written to a temporary name and renamed ----
    def write_csv(path, ks, rs):
        with open(path + ".tmp", "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(ks)
            for r in rs:
                w.writerow([r[k] for k in ks])
        os.replace(path + ".tmp", path)

    write_csv(a.output + ".csv", keys, rows)
    write_csv(a.output + "_runs.csv", run_keys, run_rows)
    tmp = a.output + ".h5.tmp"

    def put(group, ks, rs):
        for k in ks:
            v = [r[k] for r in rs]
            if v and isinstance(v[0], str):
                group[k] = np.array(v, dtype=h5py.string_dtype())
            elif v and isinstance(v[0], (int, np.integer)) and not isinstance(v[0], bool):
                group[k] = np.array(v, dtype=np.int64)
            else:
                group[k] = np.array(v, dtype=float)

    with h5py.File(tmp, "w") as f:
        f.attrs["cgd_format"] = "study"
        f.attrs["cgd_format_version"] = 2
        f.attrs["definition"] = (
            "one row per pooled resolved reference and per coarse configuration (phi, grid, alpha, law); slip = mean over "
            "the R realisations of <u_slip,y>/u_t over the window, slip_se = max(sd/sqrt(R), batch-means errors combined) "
            "(R = 1: the batch-means error only); ref_slip, ref_se the same over the resolved runs of phi; error = "
            "slip/ref_slip - 1, error_se = |slip/ref_slip| hypot(slip_se/slip, ref_se/ref_slip); /summary: rms error over "
            "phi per (grid, alpha, law) with a parametric-bootstrap sd and 16-84 % interval; Pareto front on (mean cost, "
            "rms_high); cost = wall seconds x ranks / simulated seconds")
        f.attrs["bootstrap"] = a.bootstrap
        put(f, keys, rows)
        put(f.create_group("runs"), run_keys, run_rows)
        put(f.create_group("summary"), sum_keys, agg)
    os.replace(tmp, a.output + ".h5")

    # ---- tables ----
    print("resolved references (each run over the study's window; drift = second half minus first, as cgd-coarse computes it)")
    print(f"{'phi':>5} {'seed':>4} {'slip/u_t':>15} {'drift/u_t':>16} {'window t_ref':>13} {'core-s/s':>9}  run")
    for r in sorted(resolved, key=lambda r: (r["phi"], r["seed"])):
        flag = "" if r["stationary"] != 0 else "  NOT STATIONARY"
        win = f"{r['window_start_s'] / r['t_ref_s']:.0f}-{r['window_end_s'] / r['t_ref_s']:.0f}" if np.isfinite(r["t_ref_s"]) else ""
        print(f"{r['phi']:5.2f} {r['seed']:4d} {r['slip']:7.3f} +- {r['slip_se']:5.3f} {r['drift']:+7.3f} +- {r['drift_se']:5.3f} "
              f"{win:>13} {r['cost']:9.3g}  {r['run']}{flag}")
    for phi, ref in sorted(refs.items()):
        if ref["R"] > 1:
            print(f"{phi:5.2f} pooled over {ref['R']} runs: {ref['slip']:.3f} +- {ref['slip_se']:.3f} (sd between runs {ref['slip_sd']:.3f})")
        elif ref["R"] == 0:
            print(f"{phi:5.2f} reference from the coarse runs' summaries: {ref['slip']:.3f} +- {ref['slip_se']:.3f}")
    print("\nconfigurations: mean over R realisations; +- = max(sd/sqrt(R), batch means) of the mean, and of the error with "
          "the reference's")
    print(f"{'phi':>5} {'cell/d_p':>8} {'alpha':>5} {'law':>9} {'R':>2} {'slip/u_t':>15} {'sd':>6} {'ref':>15} "
          f"{'error %':>14} {'drift':>7} {'core-s/s':>9}  pareto")
    for r in sorted(rows, key=lambda r: (r["phi"], r["kind"] != "resolved", r["drag"], r["cell_over_dp"], r["alpha"])):
        sd = f"{r['slip_sd']:6.3f}" if np.isfinite(r["slip_sd"]) else f"{'':>6}"
        notes = []
        if r["kind"] == "coarse" and r["R"] == 1:
            notes.append("R=1: batch-means error only")
        if r["nonstationary"]:
            notes.append(f"{r['nonstationary']} of {r['R']} windows not stationary")
        if r["reused"]:
            notes.append("the modelraw runs (c_corr = 1)")
        print(f"{r['phi']:5.2f} {r['cell_over_dp']:8.2f} {r['alpha']:5.0f} {r['drag']:>9} {r['R']:2d} {r['slip']:7.3f} +- {r['slip_se']:5.3f} "
              f"{sd} {r['ref_slip']:7.3f} +- {r['ref_se']:5.3f} {100 * r['error']:6.1f} +- {100 * r['error_se']:4.1f} "
              f"{r['drift']:+7.3f} {r['cost']:9.3g}  {'*' if r['pareto'] else ' '}" + (f"  ({'; '.join(notes)})" if notes else ""))
    print(f"\nconfigurations over {n_phi} solids fraction(s): rms and worst |error| with 68 % bootstrap intervals, mean cost; "
          f"Pareto front on the rms error's upper 68 % bound")
    print(f"{'cell/d_p':>8} {'alpha':>5} {'law':>9} {'R per phi':>10} {'rms error %':>24} {'worst %':>20} {'core-s/s':>9}  pareto")
    for c in sorted(agg, key=lambda c: c["cost"]):
        partial = "" if c["n"] == n_phi else f"  (run at {c['n']} of {n_phi} solids fractions: not compared)"
        print(f"{c['cell_over_dp']:8.2f} {c['alpha']:5.0f} {c['drag']:>9} {c['R']:>10} "
              f"{100 * c['error']:6.1f} [{100 * c['rms_low']:5.1f}, {100 * c['rms_high']:5.1f}] +- {100 * c['rms_sd']:4.1f} "
              f"{100 * c['worst']:6.1f} [{100 * c['worst_low']:5.1f}, {100 * c['worst_high']:5.1f}] {c['cost']:9.3g}  "
              f"{'*' if c['pareto'] else ''}{partial}")
    for target in (0.05, 0.15):
        ok = [c for c in complete if c["worst_high"] <= target]
        pick = min(ok, key=lambda c: c["cost"]) if ok else None
        print(f"cheapest configuration within {100 * target:.0f} % at every solids fraction (upper 68 % bound of the worst |error|): " +
              (f"cell {pick['cell_over_dp']:.3g} d_p, alpha {pick['alpha']:.0f}, {pick['drag']} ({pick['cost']:.3g} core-s/s)"
               if pick else "none of the coarse runs (use the resolved run)"))

    # ---- picture ----
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig = draw(configs, agg, [ref["cost"] for ref in refs.values() if np.isfinite(ref["cost"])], plt)
    fig.savefig(a.output + ".png.tmp.png", dpi=120)
    os.replace(a.output + ".png.tmp.png", a.output + ".png")
    print(f"wrote {a.output}.csv, {a.output}_runs.csv, {a.output}.h5, {a.output}.png", file=sys.stderr)


if __name__ == "__main__":
    main()
