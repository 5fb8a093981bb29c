#!/usr/bin/python3
"""The contact-stiffness table of scripts/stiffness_study.sh: for every configuration directory
OUT/g<gamma*>[_t<t*>][_s<seed>]_phi<phi>/ (_t: a DEM step t* = dt/t_c other than the scene's; _s: a realisation
other than the scene's seed 1; a Makefile.pipeline OUT holding generate/phi<phi>/, study/resolved/phi<phi>.h5 and
filter/filtered.h5) one row with

  * the slip <u_slip,y>/u_t over the filter window with its batch-means error and drift (the study's
    resolved summary, cgd-coarse --summarise) and its distance from the stiffest run of the same <phi>
    in standard errors (z = (s - s_ref) / sqrt(e^2 + e_ref^2); the stiffest: the smallest gamma*, of those the
    smallest t*, and of those the smallest seed: a second seed of that configuration shows how far two
    realisations lie apart, by chaos alone);
  * H = 1 - beta_bar/beta_micro at two box-filter widths and on one coarse grid's own operator: at the phi-bar
    bin holding most samples (with its block-bootstrap standard error), and chi2/dof of H against the stiffest
    run over every bin both populate (>= --min-count samples in each): chi2/dof ~ 1 means the same H within the
    bootstrap errors;
  * the overlaps: mean and largest overlap / d_p over the touching pairs of the window's snapshots (found
    with a periodic k-d tree, scipy), and the largest of the series' max_overlap_rel over the window (every
    series row, between snapshots too); contacts per particle (the series' mean over the window);
  * the cost: DEM steps to the end, steps per neighbour-list rebuild, wall seconds and wall ns per
    particle-step (the run's own wall time on its one rank; see the note printed under the table: a run that
    shared the machine is slower than an idle one, the step count is not).

usage: /usr/bin/python3 tools/stiffness_table.py OUT [-o PREFIX] [--widths 6.67,12.5] [--grid 4] [--min-count 200]
writes PREFIX.txt (the table as text) and PREFIX.md (the same as a Markdown table); prints the text.
(Debian's h5py/numpy/scipy belong to /usr/bin/python3.)"""
import argparse
import glob
import math
import os
import re
import sys

import h5py
import numpy as np


def fail(msg):
    print(f"stiffness_table.py: {msg}", file=sys.stderr)
    sys.exit(2)


def config_phi(name):
    """The <phi> of a configuration directory's name g<gamma*>[_t<t*>][_s<seed>]_phi<phi>; None for another
    name."""
    m = re.match(r"g[0-9.e+-]+(?:_t[0-9.e+-]+)?(?:_s[0-9]+)?_phi([0-9.]+)$", name)
    return m.group(1) if m else None


def reference_key(row):
    """The stiffest run of a <phi>, the table's reference: the smallest gamma*, of those the smallest t*, and of
    those the smallest seed."""
    return (row["gamma"], row["t_star"], row["seed"])


def overlaps(snapshot_paths):
    """Mean and largest overlap / d over the touching pairs of the snapshots (periodic box)."""
    from scipy.spatial import cKDTree
    total, pairs, largest = 0.0, 0, 0.0
    for path in snapshot_paths:
        with h5py.File(path, "r") as f:
            x = f["particles/position"][:]
            d = float(f["particles/diameter"][0])
            box = np.asarray(f["params"].attrs["box_size_m"], dtype=float)
        tree = cKDTree(np.mod(x, box), boxsize=box)
        ij = tree.query_pairs(d, output_type="ndarray")
        if len(ij) == 0:
            continue
        dx = x[ij[:, 0]] - x[ij[:, 1]]
        dx -= box * np.round(dx / box)
        delta = (d - np.linalg.norm(dx, axis=1)) / d
        total += float(delta.sum())
        pairs += len(delta)
        largest = max(largest, float(delta.max()))
    return (total / pairs if pairs else 0.0), largest


def width_groups(f):
    """{label: group} for the box widths and grids of a filtered file."""
    out = {}
    for name in f:
        g = f[name]
        if not isinstance(g, h5py.Group) or "kind" not in g.attrs:
            continue
        kind = g.attrs["kind"]
        kind = kind.decode() if isinstance(kind, bytes) else str(kind)
        if kind == "box":
            out[("box", round(float(g.attrs["width_over_dp"]), 2))] = g
        elif kind == "grid":
            out[("grid", int(g.attrs["cells_across"]))] = g
    return out


def pick(groups, key):
    kind, value = key
    cands = [k for k in groups if k[0] == kind]
    if not cands:
        return None, None
    best = min(cands, key=lambda k: abs(k[1] - value))
    return best, groups[best]


def h_bins(g, min_count):
    c = g["count"][:]
    return {"count": c, "H": g["H"][:], "err": g["H_stderr"][:], "phi": g["phi_mean"][:], "ok": c >= min_count}


def one_config(d, phi_name, widths, grid, min_count):
    run = os.path.join(d, "generate", f"phi{phi_name}")
    summ = os.path.join(d, "study", "resolved", f"phi{phi_name}.h5")
    filt = os.path.join(d, "filter", "filtered.h5")
    for p in (run, summ, filt):
        if not os.path.exists(p):
            return None
    row = {}
    with h5py.File(summ, "r") as s:
        a = s.attrs
        row["slip"] = float(a["slip_over_ut"])
        row["slip_err"] = float(a["slip_stderr"])
        row["drift"] = float(a["drift_over_ut"])
        row["drift_err"] = float(a["drift_stderr"])
        w0, w1 = float(a["window_start_s"]), float(a["window_end_s"])
        row["wall_s"] = float(a["wall_s"])
        row["ranks"] = int(a["ranks"])
    with h5py.File(os.path.join(run, "series.h5"), "r") as s:
        p = s["params"].attrs
        t = s["time"][:]
        win = (t >= w0 - 1e-12) & (t <= w1 + 1e-12)
        steps = s["step"][:]
        rebuilds = s["neighbor_rebuilds"][:]
        row["gamma"] = float(p["gamma_star"]) if "gamma_star" in p else float("nan")
        row["t_star"] = float(p["t_star"]) if "t_star" in p else float("nan")
        row["seed"] = int(p["seed"]) if "seed" in p else 1
        row["n"] = int(p["particle_count"])
        row["dt"] = float(p["dt_dem_s"])
        row["t_ref"] = float(p["t_ref_s"])
        row["steps"] = int(steps[-1])
        row["steps_per_rebuild"] = float(steps[-1] / max(rebuilds[-1], 1))
        row["contacts"] = float(np.mean(s["contacts_per_particle"][:][win]))
        row["max_overlap_series"] = float(np.max(s["max_overlap_rel"][:][win]))
        row["pcg"] = float(np.mean(s["pressure_iterations"][:][win]))
    snaps = []
    for path in sorted(glob.glob(os.path.join(run, "snapshots", "*.h5"))):
        with h5py.File(path, "r") as f:
            if w0 - 1e-12 <= float(f.attrs["time"]) <= w1 + 1e-12:
                snaps.append(path)
    row["mean_overlap"], row["max_overlap_snap"] = overlaps(snaps)
    row["snapshots"] = len(snaps)
    row["ns_per_ps"] = row["wall_s"] * row["ranks"] / (row["steps"] * row["n"]) * 1e9
    with h5py.File(filt, "r") as f:
        groups = width_groups(f)
        row["H"] = {}
        for key in [("box", w) for w in widths] + [("grid", grid)]:
            got, g = pick(groups, key)
            if g is not None:
                row["H"][got] = h_bins(g, min_count)
    return row


def modal(b):
    if not b["ok"].any():
        return float("nan"), float("nan"), float("nan")
    i = int(np.argmax(np.where(b["ok"], b["count"], -1)))
    return b["phi"][i], b["H"][i], b["err"][i]


def chi2(b, r):
    n = min(len(b["H"]), len(r["H"]))
    m = b["ok"][:n] & r["ok"][:n] & np.isfinite(b["err"][:n]) & np.isfinite(r["err"][:n])
    if not m.any():
        return float("nan"), 0
    z = (b["H"][:n][m] - r["H"][:n][m]) / np.sqrt(b["err"][:n][m] ** 2 + r["err"][:n][m] ** 2)
    return float(np.mean(z * z)), int(m.sum())


def label(key):
    return f"box {key[1]:g} d_p" if key[0] == "box" else f"grid {key[1]} across"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("-o", dest="prefix")
    ap.add_argument("--widths", default="6.67,12.5")
    ap.add_argument("--grid", type=int, default=4)
    ap.add_argument("--min-count", type=int, default=200)
    args = ap.parse_args()
    widths = [float(w) for w in args.widths.split(",")]
    rows = []
    for d in sorted(glob.glob(os.path.join(args.out, "g*_phi*"))):
        phi_name = config_phi(os.path.basename(d))
        if phi_name is None or not os.path.isdir(d):
            continue
        r = one_config(d, phi_name, widths, args.grid, args.min_count)
        if r is None:
            print(f"stiffness_table.py: {d}: not complete yet (skipped)", file=sys.stderr)
            continue
        r["phi_name"] = phi_name
        rows.append(r)
    if not rows:
        fail(f"{args.out}: no complete configuration g<gamma>_phi<phi>/")
    rows.sort(key=lambda r: (float(r["phi_name"]),) + reference_key(r))
    keys = sorted({k for r in rows for k in r["H"]}, key=lambda k: (k[0] != "box", k[1]))
    head = ["<phi>", "gamma*", "t*", "seed", "slip/u_t", "z vs stiffest", "drift/u_t"]
    for k in keys:
        head += [f"H {label(k)} (modal phi-bar)", f"chi2/dof vs stiffest, {label(k)}"]
    head += ["mean overlap/d", "max overlap/d", "contacts/particle", "steps", "steps/rebuild",
             "PCG iterations", "wall s", "wall ns/particle-step"]
    table = []
    for r in rows:
        ref = min((q for q in rows if q["phi_name"] == r["phi_name"]), key=reference_key)
        z = (r["slip"] - ref["slip"]) / math.hypot(r["slip_err"], ref["slip_err"]) if r is not ref else 0.0
        line = [r["phi_name"], f"{r['gamma']:.0e}", f"{r['t_star']:g}", str(r["seed"]), f"{r['slip']:.3f} ± {r['slip_err']:.3f}",
                "(ref)" if r is ref else f"{z:+.1f}", f"{r['drift']:+.3f} ± {r['drift_err']:.3f}"]
        for k in keys:
            b = r["H"].get(k)
            if b is None:
                line += ["-", "-"]
                continue
            phi, h, e = modal(b)
            line.append(f"{h:.3f} ± {e:.3f} (φ̄ {phi:.3f})")
            if r is ref:
                line.append("(ref)")
            else:
                c, n = chi2(b, ref["H"][k]) if k in ref["H"] else (float("nan"), 0)
                line.append(f"{c:.2f} ({n} bins)")
        line += [f"{r['mean_overlap']:.2e}", f"{max(r['max_overlap_snap'], r['max_overlap_series']):.2e}",
                 f"{r['contacts']:.3f}", f"{r['steps']:,}", f"{r['steps_per_rebuild']:.1f}", f"{r['pcg']:.1f}",
                 f"{r['wall_s']:.0f}", f"{r['ns_per_ps']:.1f}"]
        table.append(line)
    note = ("slip: mean over the filter window (15-35 t_ref), batch-means standard error; z: distance from the "
            "stiffest run of the same <phi> (its first seed) in combined standard errors; a second seed of the "
            "stiffest run gives the spread between realisations. H: 1 - beta_bar/beta_micro at the phi-bar "
            "bin with most samples, +- its block-bootstrap standard error; chi2/dof over the bins both runs populate "
            f"(>= {args.min_count} samples each; ~1: the same H within errors). Overlaps over the touching pairs of "
            "the window's snapshots (max also over every series row). wall: the run's own wall time on one rank; "
            "the runs shared the 2-core machine with other work, so wall times are upper bounds; the DEM step count "
            "scales as 1/(gamma* t*) (k_n ~ 1/gamma*^2, dt = t* t_c, t_c ~ gamma*) and is exact.")
    txt = ["  |  ".join(head)] + ["  |  ".join(l) for l in table] + ["", note]
    md = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)] + ["| " + " | ".join(l) + " |" for l in table]
    md += ["", note]
    if args.prefix:
        for ext, lines in ((".txt", txt), (".md", md)):
            tmp = args.prefix + ext + ".tmp"
            with open(tmp, "w") as f:
                f.write("\n".join(lines) + "\n")
            os.replace(tmp, args.prefix + ext)
    print("\n".join(txt))


if __name__ == "__main__":
    main()
