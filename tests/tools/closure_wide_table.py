#!/usr/bin/python3
"""tools/closure_wide_table.py against a table computed by hand (scripts/closure_wide_filter.sh's summary).

Synthetic summaries: resolved <phi> = 0.05 slip 1.00; perfect table of grid 4 (g4) at alpha 3, seeds 1-3 with slips
0.90, 0.92, 0.94 (errors -10, -8, -6 %: mean -8.0 %, scatter sd 2 %, standard error 2/sqrt(3) = 1.15 %); the model
at r = 2 at alpha 3, one seed, slip 1.05 +- 0.02 (error +5.0 +- 2.0 %, the run's own error); a directory with
another name pattern and one at a phi with no reference are ignored; a named closure (driftheld, alpha 3, one seed,
slip 0.97 +- 0.01: -3.0 +- 1.0 %) is listed under its label before the numbered ones. rms per closure: g4 8.0 %,
r2 5.0 %, driftheld 3.0 %. A run whose summary says stationary = 0 (g4 at alpha 6, slips 0.90 and 0.70: -20 +- 10 %)
is counted beside the seeds. --cells-out writes the cells as CSV and --cells-in reads them back (the same table), DIR's
runs taking precedence.
usage: /usr/bin/python3 tests/tools/closure_wide_table.py SOURCE_DIR"""
import os
import subprocess
import sys
import tempfile

import h5py

from tool_check import check, failures, source  # noqa: E402  (tests/tools/tool_check.py)
tool = os.path.join(source, "tools", "closure_wide_table.py")

def summary(path, slip, se):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with h5py.File(path, "w") as f:
        f.attrs["slip_over_ut"], f.attrs["slip_stderr"] = slip, se


with tempfile.TemporaryDirectory() as d:
    p = subprocess.run([sys.executable, tool, d], capture_output=True, text=True)
    check(p.returncode == 1 and "no finished runs" in p.stderr, "an empty directory: exit 1 with a message")
    summary(os.path.join(d, "resolved_phi0.05.h5"), 1.00, 0.01)
    for seed, slip in ((1, 0.90), (2, 0.92), (3, 0.94)):
        summary(os.path.join(d, f"phi0.05_a3_g4_s{seed}", "summary.h5"), slip, 0.005)
    summary(os.path.join(d, "phi0.05_a3_r2_s1", "summary.h5"), 1.05, 0.02)
    summary(os.path.join(d, "phi0.05_a3_driftheld_s1", "summary.h5"), 0.97, 0.01)
    summary(os.path.join(d, "phi0.05_a3_model4_s1", "summary.h5"), 0.95, 0.01)  # another script's closure name
    summary(os.path.join(d, "phi0.05_a3_radlr2_s1", "summary.h5"), 1.02, 0.01)  # radl2014 at Delta = 2 cells
    summary(os.path.join(d, "phi0.05_a3_tableheld4_s1", "summary.h5"), 0.99, 0.01)  # the 4-cell grid's table
    summary(os.path.join(d, "phi0.10_a3_g4_s1", "summary.h5"), 0.5, 0.01)  # no reference: ignored
    summary(os.path.join(d, "other_run", "summary.h5"), 0.5, 0.01)  # not the pattern: ignored
    p = subprocess.run([sys.executable, tool, d], capture_output=True, text=True)
    out = p.stdout
    check(p.returncode == 0, f"exit 0 (got {p.returncode}: {p.stderr.strip()})")
    check("| 0.05 | 1.000 | perfect table of the 4-cell grid | 3 | -8.0 ± 1.2 % | 3 |" in out,
          "g4: mean -8.0 %, standard error of the mean 1.2 %, 3 seeds")
    check("| 0.05 | 1.000 | model, r = 2 | 3 | +5.0 ± 2.0 % | 1 |" in out, "r2: one seed, its own error")
    check("| perfect table of the 4-cell grid | 8.0 % | -8.0 % | 1 |" in out, "rms and worst of g4")
    check("| model, r = 2 | 5.0 % | +5.0 % | 1 |" in out, "rms and worst of r2")
    check("| 0.05 | 1.000 | drift table, held out | 3 | -3.0 ± 1.0 % | 1 |" in out, "a named closure: its label")
    check("| drift table, held out | 3.0 % | -3.0 % | 1 |" in out, "rms and worst of the named closure")
    check(out.index("drift table, held out") < out.index("perfect table of the 4-cell grid"),
          "named closures are listed first")
    check("| 0.05 | 1.000 | model4 | 3 | -5.0 ± 1.0 % | 1 |" in out, "a name the tool does not know: itself")
    check("| 0.05 | 1.000 | radl2014 at Δ = 2 cells | 3 | +2.0 ± 1.0 % | 1 |" in out, "radlr2: radl2014 at Delta = 2 cells")
    check("| 0.05 | 1.000 | phi-bar table, held out, the 4-cell grid's table | 3 | -1.0 ± 1.0 % | 1 |" in out,
          "tableheld4: the held-out table of the 4-cell grid")
    check(out.index("phi-bar table, held out, the 4-cell") < out.index("radl2014 at") < out.index("perfect table of the 4-cell"),
          "a named closure at another filter is listed beside its base")
    check("0.10" not in out, "a phi without a reference is left out")
    # --rms-alphas: the rms over the listed alphas only (an alpha = 2 run of g4 at -20 % is listed, not in the rms)
    summary(os.path.join(d, "phi0.05_a2_g4_s1", "summary.h5"), 0.80, 0.01)
    p = subprocess.run([sys.executable, tool, d, "--rms-alphas", "3,4,6,8"], capture_output=True, text=True)
    check(p.returncode == 0 and "| 0.05 | 1.000 | perfect table of the 4-cell grid | 2 | -20.0 ± 1.0 % | 1 |" in p.stdout,
          "--rms-alphas: every alpha is still listed")
    check("| perfect table of the 4-cell grid | 8.0 % | -8.0 % | 1 |" in p.stdout and "α = 3,4,6,8" in p.stdout,
          "--rms-alphas 3,4,6,8: g4's rms over alpha = 3 alone (8.0 %), the alpha = 2 run left out")
    p = subprocess.run([sys.executable, tool, d], capture_output=True, text=True)
    check("| perfect table of the 4-cell grid | 15.2 % | -20.0 % | 2 |" in p.stdout,
          "without --rms-alphas: g4's rms over alpha = 2 and 3 (sqrt((20^2 + 8^2)/2) = 15.2 %)")
    p = subprocess.run([sys.executable, tool, d, "--rms-alphas", "3;4"], capture_output=True, text=True)
    check(p.returncode == 2 and "not a comma-separated list" in p.stderr, "--rms-alphas with a bad list: exit 2 with its message")
    # --wide: a row per phi and alpha, a column per closure; then the rms and worst per closure and phi
    p = subprocess.run([sys.executable, tool, d, "--wide", "--rms-alphas", "3"], capture_output=True, text=True)
    out = p.stdout
    header = next((l for l in out.splitlines() if l.startswith("| ⟨φ⟩ | resolved slip/u_t | α |")), "")
    cols = [c.strip() for c in header.strip("|").split("|")]
    check(p.returncode == 0 and "perfect table of the 4-cell grid" in cols and "drift table, held out" in cols,
          f"--wide: a column per closure ({p.stderr.strip()})")
    row3 = next((l for l in out.splitlines() if l.startswith("| 0.05 | 1.000 | 3 |")), "")
    row2 = next((l for l in out.splitlines() if l.startswith("| 0.05 | 1.000 | 2 |")), "")
    cell = lambda row, c: [x.strip() for x in row.strip("|").split("|")][cols.index(c)] if c in cols and row else None
    check(cell(row3, "perfect table of the 4-cell grid") == "-8.0 ± 1.2 (3)", "--wide: g4 at alpha 3, mean ± se (seeds)")
    check(cell(row3, "model, r = 2") == "+5.0 ± 2.0 (1)", "--wide: r2 at alpha 3, one seed, its own error")
    check(cell(row2, "perfect table of the 4-cell grid") == "-20.0 ± 1.0 (1)" and cell(row2, "model, r = 2") == "",
          "--wide: the alpha = 2 row has g4 and an empty cell for r2, which has no alpha = 2 run")
    check("| perfect table of the 4-cell grid | 8.0 / -8.0 % |" in out,
          "--wide --rms-alphas 3: g4's rms / worst at 0.05 over alpha = 3 (the alpha = 2 run left out)")
    # --rms-phis: the rms over the listed phis only (a run at 0.02, error +30 %, listed but not in the rms)
    summary(os.path.join(d, "resolved_phi0.02.h5"), 1.00, 0.01)
    summary(os.path.join(d, "phi0.02_a3_g4_s1", "summary.h5"), 1.30, 0.01)
    p = subprocess.run([sys.executable, tool, d, "--rms-alphas", "3", "--rms-phis", "0.050"], capture_output=True, text=True)
    check(p.returncode == 0 and "| 0.02 | 1.000 | perfect table of the 4-cell grid | 3 | +30.0 ± 1.0 % | 1 |" in p.stdout,
          "--rms-phis: every phi is still listed")
    check("| perfect table of the 4-cell grid | 8.0 % | -8.0 % | 1 |" in p.stdout and "⟨φ⟩ = 0.05" in p.stdout,
          "--rms-phis 0.050: g4's rms over phi = 0.05 alone (8.0 %; 0.050 and 0.05 are one phi)")
    p = subprocess.run([sys.executable, tool, d, "--rms-alphas", "3"], capture_output=True, text=True)
    check("| perfect table of the 4-cell grid | 22.0 % | +30.0 % | 2 |" in p.stdout,
          "without --rms-phis: g4's rms over both phis (sqrt((30^2 + 8^2)/2) = 22.0 %)")
    p = subprocess.run([sys.executable, tool, d, "--rms-phis", "0.05,0.7"], capture_output=True, text=True)
    check(p.returncode == 2 and "0.7: no finished runs" in p.stderr, "--rms-phis naming a phi with no runs: exit 2 with its message")
    p = subprocess.run([sys.executable, tool, d, "--rms-phis", "nan"], capture_output=True, text=True)
    check(p.returncode == 2 and "must lie in (0, 1)" in p.stderr, "--rms-phis nan: exit 2")
    # a run spelled phi0.020 belongs to the resolved run spelled 0.02 (one phi, one row)
    summary(os.path.join(d, "phi0.020_a4_g4_s1", "summary.h5"), 1.10, 0.01)
    p = subprocess.run([sys.executable, tool, d], capture_output=True, text=True)
    check("| 0.02 | 1.000 | perfect table of the 4-cell grid | 4 | +10.0 ± 1.0 % | 1 |" in p.stdout and "0.020" not in p.stdout,
          "a run spelled phi0.020 is listed under the resolved run's 0.02")
    p = subprocess.run([sys.executable, tool, d, "--rms-phis", "0.05;0.1"], capture_output=True, text=True)
    check(p.returncode == 2 and "not a comma-separated list" in p.stderr, "--rms-phis with a bad list: exit 2 with its message")
    # a run whose window cgd-coarse found not stationary (summary attribute stationary = 0) is counted in its cell
    summary(os.path.join(d, "phi0.05_a6_g4_s1", "summary.h5"), 0.90, 0.01)
    summary(os.path.join(d, "phi0.05_a6_g4_s2", "summary.h5"), 0.70, 0.01)
    with h5py.File(os.path.join(d, "phi0.05_a6_g4_s2", "summary.h5"), "a") as f:
        f.attrs["stationary"] = 0
    p = subprocess.run([sys.executable, tool, d], capture_output=True, text=True)
    check("| 0.05 | 1.000 | perfect table of the 4-cell grid | 6 | -20.0 ± 10.0 % | 2, 1 not stationary |" in p.stdout
          and "not stationary: cgd-coarse found" in p.stdout,
          "a run with stationary = 0: counted beside the seeds, and the note under the table")
    check("| 0.05 | 1.000 | perfect table of the 4-cell grid | 3 | -8.0 ± 1.2 % | 3 |" in p.stdout,
          "runs without the attribute are not flagged")
    p = subprocess.run([sys.executable, tool, d, "--wide"], capture_output=True, text=True)
    check("-20.0 ± 10.0 (2, 1 not stationary)" in p.stdout, "--wide: the same count in the cell")
    # --cells-out, then --cells-in: the same table from the CSV alone (a machine replaced, its runs gone), DIR's runs
    # taking precedence over the file's cells, and a file measured against another resolved run refused
    cells = os.path.join(d, "cells.csv")
    p = subprocess.run([sys.executable, tool, d, "--wide", "--cells-out", cells], capture_output=True, text=True)
    with open(cells) as f:
        head, *rows = f.read().splitlines()
    check(p.returncode == 0 and head.split(",")[:5] == ["phi", "resolved_slip_over_ut", "resolved_stderr", "closure", "alpha"]
          and "0.05,1.0000,0.0100,g4,6,-20.0000,10.0000,2,1" in rows,
          f"--cells-out: a row per cell, g4 at alpha 6: -20 +- 10 %, 2 realisations, 1 not stationary ({p.stderr.strip()})")
    with tempfile.TemporaryDirectory() as e:
        q = subprocess.run([sys.executable, tool, e, "--wide", "--cells-in", cells], capture_output=True, text=True)
        check(q.returncode == 0 and q.stdout == p.stdout and f"{len(rows)} cells from" in q.stderr,
              f"--cells-in alone: the same table as the runs gave ({q.stderr.strip()})")
        summary(os.path.join(e, "resolved_phi0.05.h5"), 1.00, 0.01)
        summary(os.path.join(e, "phi0.05_a6_g4_s1", "summary.h5"), 0.95, 0.01)
        q = subprocess.run([sys.executable, tool, e, "--cells-in", cells], capture_output=True, text=True)
        check("| 0.05 | 1.000 | perfect table of the 4-cell grid | 6 | -5.0 ± 1.0 % | 1 |" in q.stdout
              and f"{len(rows) - 1} cells from" in q.stderr, "a run in DIR takes precedence over the file's cell")
        check("| 0.05 | 1.000 | perfect table of the 4-cell grid | 3 | -8.0 ± 1.2 % | 3 |" in q.stdout,
              "the cells DIR has not run come from the file")
        summary(os.path.join(e, "resolved_phi0.05.h5"), 1.01, 0.01)
        q = subprocess.run([sys.executable, tool, e, "--cells-in", cells], capture_output=True, text=True)
        check(q.returncode == 2 and "measured against another resolved run" in q.stderr,
              "a file whose resolved slip is not DIR's (1.00 against 1.01): exit 2 with its message")
        bad = os.path.join(e, "bad.csv")
        with open(bad, "w") as f:
            f.write("phi,closure,alpha\n0.05,g4,3\n")
        q = subprocess.run([sys.executable, tool, e, "--cells-in", bad], capture_output=True, text=True)
        check(q.returncode == 2 and "no column resolved_slip_over_ut" in q.stderr, "a file without a column: exit 2 naming it")
        with open(bad, "w") as f:
            f.write(head + "\n" + rows[0] + "\n" + rows[0].replace(",3,", ",three,", 1) + "\n")
        q = subprocess.run([sys.executable, tool, e, "--cells-in", bad], capture_output=True, text=True)
        check(q.returncode == 2 and "line 3, column alpha" in q.stderr,
              f"a value that is not a number: exit 2 naming the line and the column ({q.stderr.strip()})")
        nan_error = ",".join(v if i != head.split(",").index("error_pct") else "nan" for i, v in enumerate(rows[0].split(",")))
        for damage, what in ((nan_error, "column error_pct"),
                             (rows[0] + "\n" + rows[0], "listed twice")):
            with open(bad, "w") as f:
                f.write(head + "\n" + damage + "\n")
            q = subprocess.run([sys.executable, tool, e, "--cells-in", bad], capture_output=True, text=True)
            check(q.returncode == 2 and what in q.stderr, f"a damaged file ({what}): exit 2 naming it ({q.stderr.strip()})")
        with open(bad, "w") as f:
            f.write(head + "\n" + rows[0].rsplit(",", 1)[0] + ",\n")
        q = subprocess.run([sys.executable, tool, e, "--cells-in", bad], capture_output=True, text=True)
        check(q.returncode == 0 and "not stationary" not in q.stdout, "a blank not_stationary (not counted): no mark")
    png = os.path.join(d, "figure.png")
    p = subprocess.run([sys.executable, tool, d, "--plot", png], capture_output=True, text=True)
    check(p.returncode == 0 and os.path.getsize(png) > 0, f"--plot writes the picture ({p.stderr.strip()})")
    # four phi: two rows of at most three panels (4.0 inches a row at 120 dpi: 960 pixels high, 3 x 5.2 inches wide)
    for phi in ("0.10", "0.20"):
        summary(os.path.join(d, f"resolved_phi{phi}.h5"), 1.00, 0.01)
        summary(os.path.join(d, f"phi{phi}_a3_g4_s1", "summary.h5"), 0.9, 0.01)
    p = subprocess.run([sys.executable, tool, d, "--plot", png], capture_output=True, text=True)
    import matplotlib.image
    height, width = matplotlib.image.imread(png).shape[:2]
    check(p.returncode == 0 and (height, width) == (960, 1872), f"--plot with four phi: two rows of three panels ({width} x {height})")
print(f"{failures()} failed" if failures() else "all passed")
sys.exit(1 if failures() else 0)
