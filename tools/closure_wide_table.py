#!/usr/bin/python3
"""The closure experiments' table (scripts/closure_wide_filter.sh, scripts/closure_drift.sh; docs/closure.md).

usage: tools/closure_wide_table.py DIR [--plot PNG] [--rms-alphas LIST] [--rms-phis LIST] [--wide] [--cells-in CSV]
                                   [--cells-out CSV]
  --rms-alphas LIST: the per-closure rms and worst over these α only (e.g. 3,4,6,8: the paper's Figure 3 claim
    leaves α = 2 out); the table lists every α
  --rms-phis LIST: the same over these ⟨φ⟩ only (e.g. 0.02,0.05: the dilute end); the table lists every ⟨φ⟩
  --wide: the table with a row per phi and alpha and a column per closure ("mean ± se (seeds)", in %), and after the
    rms and worst per closure the same per closure and phi (where a closure misses, and by how much)
  --plot PNG: also the picture (the paper's Figure 3 as errors): per phi a panel, the error of the slip against alpha
  per closure (mean over the seeds +- its standard error), the resolved run's own +- standard error shaded.
  --cells-out CSV: also the table's cells as CSV (CELL_COLUMNS: one row per phi, closure and alpha; errors in %)
  --cells-in CSV: cells of an earlier table (a --cells-out file, e.g. data/validation/half_box_4cell.csv: runs of a
    machine since replaced) for every phi, closure and alpha DIR has no finished run of; DIR's runs take precedence.
    The table, the rms and the picture are then over both; stderr says how many cells came from the file.

DIR holds resolved_phi<phi>.h5 (cgd-coarse --summarise of each resolved run over its sampling window) and the coarse
runs phi<phi>_a<alpha>_<closure>_s<seed>/summary.h5, <closure> = g<G> (the perfect table of the grid of G cells
across), r<r> (the fitted model at fluid.filter_to_grid_ratio = r), one of the names of LABELS (the drift
experiment's closures and scripts/figure3_box.sh's), or one of those at another filter: <name>r<r> (evaluated at
Delta = r cells, e.g. radlr2) or <table|drift><held|own><G> (the table of the grid of G cells across, e.g.
tableheld4, as CELLS=8 TABLE_CELLS=4 scripts/closure_drift.sh uses it). Prints a markdown table: per phi, closure and
alpha, the relative error of the slip against the resolved run, mean over the seeds +- the standard error of that
mean (the seeds' scatter / sqrt(n); one seed: the run's own batch-means error), and the seeds' count, with how many
of them have a window cgd-coarse found not stationary (the summary's `stationary` = 0: its halves differ by more
than 3 standard errors; "(3, 1 not stationary)"); then per
closure the rms and the worst of the means over every phi and alpha (with --rms-alphas, --rms-phis: over those only).
"""
import argparse
import glob
import math
import os
import re
import sys

import h5py

NAME = re.compile(r"^phi(?P<phi>[0-9.]+)_a(?P<alpha>[0-9]+)_(?P<closure>[gr][0-9.]+|[a-z][a-z0-9]*)_s(?P<seed>[0-9]+)$")
# the named closures of scripts/closure_drift.sh, in the order the table lists them
LABELS = {
    "driftheld": "drift table, held out",
    "driftown": "drift table of the run itself (perfect twin)",
    "tableheld": "phi-bar table, held out",
    "tableown": "phi-bar table of the run itself (perfect)",
    "radl": "radl2014",
    "micro": "micro (no correction)",
    "halfbox": "half-box model (data/models/half_box.h5)",
    "perfect": "perfect (the grid's own phi-bar table)",
    "model": "model fitted in this box",
    "modelraw": "model fitted in this box, c_corr off",
    "modeln1": "model fitted in this box at n = 1, c_corr off",
}


def read_summary(path):
    """A summary's (slip_over_ut, slip_stderr, stationary), read in one opening; stationary is False only when the
    summary says its window is not (attribute `stationary` = 0: cgd-coarse's), True when it says it is or does not say."""
    with h5py.File(path, "r") as f:
        return float(f.attrs["slip_over_ut"]), float(f.attrs["slip_stderr"]), bool(f.attrs.get("stationary", 1))


# a named closure of LABELS at another filter: <name>r<r> (a law evaluated at Delta = r cells, e.g. radlr2) and
# <table or drift><held or own><G> (the table of the grid of G cells across used on the run's grid, e.g. tableheld4)
AT_RATIO = re.compile(r"^(?P<base>[a-z]+?)r(?P<n>[0-9.]+)$")
OF_GRID = re.compile(r"^(?P<base>(?:table|drift)(?:held|own))(?P<n>[0-9]+)$")


# the columns of --cells-out and --cells-in: the resolved run's slip and its standard error (u_t), the closure's name
# (the runs' label: radl, micro, perfect, modelraw, g4, ...), the mean error of the slip over the realisations and
# its standard error (%), the realisations and how many of them cgd-coarse found not stationary (blank: not counted,
# a table made before the tool counted them)
CELL_COLUMNS = ["phi", "resolved_slip_over_ut", "resolved_stderr", "closure", "alpha", "error_pct", "stderr_pct",
                "realisations", "not_stationary"]


# how far (u_t) an earlier table's resolved slip may differ from DIR's and still be the same resolved run: the
# rounding of a slip written to three decimals
REF_TOLERANCE = 0.0015


def read_cells(path):
    """A --cells-out file -> ({phi: (slip, stderr)}, {(phi, closure, alpha): (mean, se, n, not stationary)}), the
    errors as fractions; phi as the file spells it. A missing column, a value that is not a finite number (or, for
    the counts, not an integer), a cell listed twice or two resolved slips for one phi: ValueError naming the file,
    the line and the column."""
    import csv
    refs, cells = {}, {}

    def number(r, column, kind=float, blank=False):
        text = r[column]
        if blank and not text:
            return None
        try:
            value = kind(text)
        except (TypeError, ValueError):
            value = None
        if value is None or not math.isfinite(value):
            raise ValueError(f"{path}, line {rows.line_num}, column {column}: {text!r} is not a finite "
                             f"{'integer' if kind is int else 'number'}")
        return value

    with open(path, newline="") as f:
        rows = csv.DictReader(f)
        missing = [c for c in CELL_COLUMNS if c not in (rows.fieldnames or [])]
        if missing:
            raise ValueError(f"{path}: no column {', '.join(missing)} (the columns are {','.join(CELL_COLUMNS)})")
        for r in rows:
            phi = r["phi"]
            number(r, "phi")
            ref = (number(r, "resolved_slip_over_ut"), number(r, "resolved_stderr"))
            if refs.setdefault(phi, ref) != ref:
                raise ValueError(f"{path}, line {rows.line_num}, column resolved_slip_over_ut: phi = {phi} has two "
                                 f"resolved runs ({refs[phi][0]} and {ref[0]} u_t)")
            key = (phi, r["closure"], number(r, "alpha", int))
            if key in cells:
                raise ValueError(f"{path}, line {rows.line_num}: phi = {phi}, {key[1]}, alpha = {key[2]} is listed twice")
            cells[key] = (number(r, "error_pct") / 100, number(r, "stderr_pct") / 100, number(r, "realisations", int),
                          number(r, "not_stationary", int, blank=True))
    return refs, cells


def write_cells(path, refs, ref_err, table):
    """The table's cells -> CSV at path (CELL_COLUMNS; errors in %, to 1e-4 so that the table read back rounds as this one)."""
    import csv
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(CELL_COLUMNS)
        for (phi, c, alpha), (mean, se, n, moving) in table.items():
            w.writerow([phi, f"{refs[phi]:.4f}", f"{ref_err[phi]:.4f}", c, alpha, f"{100 * mean:.4f}", f"{100 * se:.4f}",
                        n, "" if moving is None else moving])


def named_variant(c):
    """(base name, kind 'r' or 'g', number) of a LABELS closure at another filter, or None."""
    for kind, pattern in (("g", OF_GRID), ("r", AT_RATIO)):
        m = pattern.match(c)
        if m and m["base"] in LABELS:
            return m["base"], kind, float(m["n"])
    return None


def closure_label(c):
    """LABELS's label, g<G> and r<r> spelled out, a LABELS closure at another filter (radlr2, tableheld4) as its
    label with the filter; any other name (a closure of some other script: model4, perfectc8, ...) as it is."""
    if c in LABELS:
        return LABELS[c]
    v = named_variant(c)
    if v:
        base, kind, n = v
        return f"{LABELS[base]}, the {n:g}-cell grid's table" if kind == "g" else f"{LABELS[base]} at Δ = {n:g} cells"
    if re.fullmatch(r"g[0-9.]+", c):
        return f"perfect table of the {c[1:]}-cell grid"
    if re.fullmatch(r"r[0-9.]+", c):
        return f"model, r = {c[1:]}"
    return c


def closure_order(c):
    """The named closures first in LABELS's order, then g<G> and r<r> by kind and number, then any other name; ties
    by the name, so that every listing (and the picture's colours) is the same from run to run."""
    if c in LABELS:
        return (0, list(LABELS).index(c), 0.0, c)
    v = named_variant(c)
    if v:
        return (0, list(LABELS).index(v[0]), v[2], c)
    if re.fullmatch(r"[gr][0-9.]+", c):
        return (1 if c[0] == "g" else 2, 0, float(c[1:]), c)
    return (3, 0, 0.0, c)


def plot(path, refs, ref_err, table):
    """table: {(phi, closure, alpha): (mean, se, n, not stationary)} -> PNG at path."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    phis = sorted({k[0] for k in table}, key=float)
    # one colour per closure in every panel (the closures differ between panels when some were not run at a phi)
    colour = {c: f"C{i % 10}" for i, c in enumerate(sorted({k[1] for k in table}, key=closure_order))}
    # at most three panels a row (six <phi> in two rows)
    cols = min(3, len(phis))
    rows = (len(phis) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(5.2 * cols, 4.0 * rows), squeeze=False)
    for ax in axes.flat[len(phis):]:
        ax.set_visible(False)
    for ax, phi in zip(axes.flat, phis):
        band = 100 * ref_err[phi] / refs[phi]
        ax.axhspan(-band, band, color="0.85", lw=0, label="resolved ± its standard error")
        ax.axhline(0, color="0.4", lw=0.8)
        for c in sorted({k[1] for k in table if k[0] == phi}, key=closure_order):
            alphas = sorted(a for (p, cc, a) in table if p == phi and cc == c)
            m = [100 * table[(phi, c, a)][0] for a in alphas]
            e = [100 * table[(phi, c, a)][1] for a in alphas]
            ax.errorbar(alphas, m, yerr=e, marker="o", ms=4, capsize=3, color=colour[c], label=closure_label(c))
        ax.set_xlabel("parcel size α")
        ax.set_ylabel("error of the slip, %")
        ax.set_title(f"⟨φ⟩ = {phi}, resolved slip {refs[phi]:.3f} u_t")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def alpha_list(text):
    """--rms-alphas: a comma-separated list of integers -> their set."""
    try:
        return {int(a) for a in text.split(",")}
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a comma-separated list of integers")


def phi_list(text):
    """--rms-phis: a comma-separated list of numbers -> their set (as floats: 0.1 and 0.10 are one phi)."""
    try:
        phis = {float(p) for p in text.split(",")}
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a comma-separated list of numbers")
    if not all(0 < p < 1 for p in phis):
        raise argparse.ArgumentTypeError(f"{text!r}: every solids fraction must lie in (0, 1)")
    return phis


def main(argv):
    ap = argparse.ArgumentParser(prog="closure_wide_table.py", description=__doc__.split("\n")[0])
    ap.add_argument("dir", help="the directory of resolved_phi<phi>.h5 and the coarse runs")
    ap.add_argument("--plot", metavar="PNG", help="also the picture")
    ap.add_argument("--rms-alphas", type=alpha_list, metavar="LIST", help="the rms and worst over these alphas only")
    ap.add_argument("--rms-phis", type=phi_list, metavar="LIST", help="the rms and worst over these phis only")
    ap.add_argument("--wide", action="store_true", help="a row per phi and alpha, a column per closure")
    ap.add_argument("--cells-in", metavar="CSV", help="cells of an earlier table for what DIR has not run")
    ap.add_argument("--cells-out", metavar="CSV", help="also the table's cells as CSV")
    args = ap.parse_args(argv[1:])  # exit 2 with argparse's message on bad arguments
    plot_path, rms_alphas, d = args.plot, args.rms_alphas, args.dir
    ref_err = {}
    refs = {}
    spelled = {}  # float(phi) -> the resolved file's spelling of it (runs spelled 0.1 or 0.10 are one phi)
    for p in glob.glob(os.path.join(d, "resolved_phi*.h5")):
        phi = os.path.basename(p)[len("resolved_phi"):-3]
        try:
            value = float(phi)
        except ValueError:
            continue
        if value in spelled:
            print(f"closure_wide_table.py: {d} has two resolved files of phi = {value:g} (resolved_phi{spelled[value]}.h5 "
                  f"and resolved_phi{phi}.h5): keep one", file=sys.stderr)
            return 2
        spelled[value] = phi
        refs[phi], ref_err[phi], _ = read_summary(p)
    old_cells = {}
    if args.cells_in:
        try:
            old_refs, old_cells = read_cells(args.cells_in)
        except (OSError, ValueError) as e:
            print(f"closure_wide_table.py: --cells-in: {e}", file=sys.stderr)
            return 2
        for phi, (slip, err) in old_refs.items():  # the file's phi spelled as DIR spells it, where DIR has it
            mine = spelled.setdefault(float(phi), phi)
            if mine in refs and abs(refs[mine] - slip) > REF_TOLERANCE:
                print(f"closure_wide_table.py: --cells-in {args.cells_in}: its resolved slip at phi = {phi} is {slip} u_t, "
                      f"{d}'s resolved_phi{mine}.h5 says {refs[mine]:.4f}: the cells were measured against another "
                      f"resolved run", file=sys.stderr)
                return 2
            refs.setdefault(mine, slip)
            ref_err.setdefault(mine, err)
    runs = {}
    for s in glob.glob(os.path.join(d, "*", "summary.h5")):
        m = NAME.match(os.path.basename(os.path.dirname(s)))
        phi = spelled.get(float(m["phi"])) if m else None
        if phi is None:
            continue
        slip, slip_se, still = read_summary(s)
        runs.setdefault((phi, m["closure"], int(m["alpha"])), []).append((slip / refs[phi] - 1, slip_se / refs[phi], still))
    table = {}  # (phi, closure, alpha) -> (mean, se, n, not stationary): DIR's runs, then the file's other cells
    for key, found in runs.items():
        e = [x[0] for x in found]
        n = len(e)
        mean = sum(e) / n
        se = (math.sqrt(sum((x - mean) ** 2 for x in e) / (n - 1)) / math.sqrt(n)) if n > 1 else found[0][1]
        table[key] = (mean, se, n, sum(1 for x in found if not x[2]))
    earlier = {(spelled[float(phi)], c, alpha): cell for (phi, c, alpha), cell in old_cells.items()}
    earlier = {key: cell for key, cell in earlier.items() if key not in table}
    if args.cells_in:
        print(f"closure_wide_table.py: {len(earlier)} cells from {args.cells_in} (DIR has no run of them)", file=sys.stderr)
    table = dict(sorted({**table, **earlier}.items(), key=lambda kv: (float(kv[0][0]), closure_order(kv[0][1]), kv[0][2])))
    if not table:
        print(f"closure_wide_table.py: no finished runs in {d}", file=sys.stderr)
        return 1
    absent = sorted((args.rms_phis or set()) - {float(k[0]) for k in table})
    if absent:
        print(f"closure_wide_table.py: --rms-phis {','.join(f'{p:g}' for p in absent)}: no finished runs at that phi in {d}",
              file=sys.stderr)
        return 2
    per_closure = {}  # closure -> [(phi, mean)] over the rms alphas
    for (phi, c, alpha), (mean, *_) in table.items():
        if (rms_alphas is None or alpha in rms_alphas) and (args.rms_phis is None or float(phi) in args.rms_phis):
            per_closure.setdefault(c, []).append((phi, mean))
    closures = sorted({k[1] for k in table}, key=closure_order)

    def pm(mean, se):  # a mean error and its standard error, in %
        return f"{100 * mean:+.1f} ± {100 * se:.1f}"

    def seeds(n, moving):  # the realisations' count, and how many of them are not stationary
        return f"{n}, {moving} not stationary" if moving else f"{n}"

    if args.wide:
        print("| ⟨φ⟩ | resolved slip/u_t | α | " + " | ".join(closure_label(c) for c in closures) + " |")
        print("|---|---|---|" + "---|" * len(closures))
        for phi, alpha in sorted({(k[0], k[2]) for k in table}, key=lambda k: (float(k[0]), k[1])):
            cells = [f"{pm(*table[(phi, c, alpha)][:2])} ({seeds(*table[(phi, c, alpha)][2:])})" if (phi, c, alpha) in table else ""
                     for c in closures]
            print(f"| {phi} | {refs[phi]:.3f} | {alpha} | " + " | ".join(cells) + " |")
    else:
        print("| ⟨φ⟩ | resolved slip/u_t | closure | α | error of the slip | seeds |")
        print("|---|---|---|---|---|---|")
        for (phi, c, alpha), (mean, se, n, moving) in table.items():
            print(f"| {phi} | {refs[phi]:.3f} | {closure_label(c)} | {alpha} | {pm(mean, se)} % | {seeds(n, moving)} |")
    if any(v[3] for v in table.values()):
        print()
        print("not stationary: cgd-coarse found the run's window not stationary (its halves differ by more than 3 standard "
              "errors: a plug or a cluster forming inside it); its mean depends on the window")
    print()
    over = "" if rms_alphas is None else f", α = {','.join(str(a) for a in sorted(rms_alphas))}"
    if args.rms_phis is not None:
        over += f", ⟨φ⟩ = {','.join(spelled[p] for p in sorted(args.rms_phis))}"

    def rms_worst(m):
        return 100 * math.sqrt(sum(x * x for x in m) / len(m)), 100 * max(m, key=abs)

    print(f"| closure | rms of the means{over} | worst | configurations |")
    print("|---|---|---|---|")
    for c in sorted(per_closure, key=closure_order):
        rms, worst = rms_worst([x for _, x in per_closure[c]])
        print(f"| {closure_label(c)} | {rms:.1f} % | {worst:+.1f} % | {len(per_closure[c])} |")
    if args.wide:
        phis = sorted({p for c in per_closure for p, _ in per_closure[c]}, key=float)
        print()
        print(f"| closure: rms / worst of the means{over}, per ⟨φ⟩ | " + " | ".join(phis) + " |")
        print("|---|" + "---|" * len(phis))
        for c in sorted(per_closure, key=closure_order):
            cells = []
            for phi in phis:
                m = [x for p, x in per_closure[c] if p == phi]
                cells.append("%.1f / %+.1f %%" % rms_worst(m) if m else "")
            print(f"| {closure_label(c)} | " + " | ".join(cells) + " |")
    if plot_path:
        plot(plot_path, refs, ref_err, table)
    if args.cells_out:
        write_cells(args.cells_out, refs, ref_err, table)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
