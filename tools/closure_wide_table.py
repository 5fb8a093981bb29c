#!/usr/bin/python3
"""The closure experiments' table (scripts/closure_wide_filter.sh, scripts/closure_drift.sh; docs/closure.md).

usage: tools/closure_wide_table.py DIR

DIR holds resolved_phi<phi>.h5 (cgd-coarse --summarise of each resolved run over its sampling window) and the coarse
runs phi<phi>_a<alpha>_<closure>_s<seed>/summary.h5, <closure> = g<G> (the perfect table of the grid of G cells
across), r<r> (the fitted model at fluid.filter_to_grid_ratio = r) or one of the names of LABELS (the drift
experiment's closures and scripts/figure3_box.sh's). Prints a markdown table: per phi, closure and
alpha, the relative error of the slip against the resolved run, mean over the seeds +- the standard error of that
mean (the seeds' scatter / sqrt(n); one seed: the run's own batch-means error), and the seeds' count; then per
closure the rms and the worst of the means over every phi and alpha.
"""
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
}


def attr(path, key):
    with h5py.File(path, "r") as f:
        return float(f.attrs[key])


def closure_label(c):
    if c in LABELS:
        return LABELS[c]
    return f"perfect table of the {c[1:]}-cell grid" if c[0] == "g" else f"model, r = {c[1:]}"


def closure_order(c):
    """The named closures first in LABELS's order, then g<G> and r<r> by kind and number."""
    if c in LABELS:
        return (0, list(LABELS).index(c), 0.0)
    if re.fullmatch(r"[gr][0-9.]+", c):
        return (1 if c[0] == "g" else 2, 0, float(c[1:]))
    return (3, 0, 0.0)


def main(argv):
    if len(argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    d = argv[1]
    refs = {}
    for p in glob.glob(os.path.join(d, "resolved_phi*.h5")):
        phi = os.path.basename(p)[len("resolved_phi"):-3]
        refs[phi] = attr(p, "slip_over_ut")
    runs = {}
    for s in glob.glob(os.path.join(d, "*", "summary.h5")):
        m = NAME.match(os.path.basename(os.path.dirname(s)))
        if not m or m["phi"] not in refs:
            continue
        err = attr(s, "slip_over_ut") / refs[m["phi"]] - 1
        own = attr(s, "slip_stderr") / refs[m["phi"]]
        runs.setdefault((m["phi"], m["closure"], int(m["alpha"])), []).append((err, own))
    if not runs:
        print(f"closure_wide_table.py: no finished runs in {d}", file=sys.stderr)
        return 1
    print("| ⟨φ⟩ | resolved slip/u_t | closure | α | error of the slip | seeds |")
    print("|---|---|---|---|---|---|")
    per_closure = {}
    for (phi, c, alpha) in sorted(runs, key=lambda k: (float(k[0]), closure_order(k[1]), k[2])):
        e = [x[0] for x in runs[(phi, c, alpha)]]
        n = len(e)
        mean = sum(e) / n
        se = (math.sqrt(sum((x - mean) ** 2 for x in e) / (n - 1)) / math.sqrt(n)) if n > 1 else runs[(phi, c, alpha)][0][1]
        per_closure.setdefault(c, []).append(mean)
        print(f"| {phi} | {refs[phi]:.3f} | {closure_label(c)} | {alpha} | {100 * mean:+.1f} ± {100 * se:.1f} % | {n} |")
    print()
    print("| closure | rms of the means | worst | configurations |")
    print("|---|---|---|---|")
    for c in sorted(per_closure, key=closure_order):
        m = per_closure[c]
        rms = math.sqrt(sum(x * x for x in m) / len(m))
        worst = max(m, key=abs)
        print(f"| {closure_label(c)} | {100 * rms:.1f} % | {100 * worst:+.1f} % | {len(m)} |")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
