#!/usr/bin/python3
"""data/validation/half_box_4cell.csv, the validation table of docs/coarse.md ("Validation at all six <phi>") as data:
every <phi> of the shipped filtered files and every alpha of the paper's Figure 3 claim (3, 4, 6) has the four closures
(radl, micro, perfect, modelraw), each <phi>'s resolved slip is the one docs/coarse.md lists (the shipped filtered
file's window, to its 3 decimals), and the rms of each closure over alpha = 3, 4, 6 that tools/closure_wide_table.py
computes from the file is the one docs/coarse.md prints (so the page and the data cannot drift apart).
usage: /usr/bin/python3 tests/data/check_validation.py SOURCE_DIR"""
import os
import re
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tools"))
from tool_check import check, failures, source  # noqa: E402  (tests/tools/tool_check.py)
from closure_wide_table import read_cells  # noqa: E402  (tools/ is on the path: tool_check puts it there)

table = os.path.join(source, "data", "validation", "half_box_4cell.csv")
refs, cells = read_cells(table)
phis = sorted(refs, key=float)
check(phis == ["0.02", "0.05", "0.10", "0.20", "0.30", "0.40"], f"the six <phi> of the half box ({phis})")
# the resolved slips of the shipped filtered files' windows (docs/coarse.md: 1.116, 1.117, 1.100, 0.895, 0.739, 0.283)
for phi, slip in zip(phis, (1.116, 1.117, 1.100, 0.895, 0.739, 0.283)):
    check(abs(refs[phi][0] - slip) < 6e-4, f"<phi> = {phi}: resolved slip {refs[phi][0]} u_t (the docs' {slip})")
missing = [(p, c, a) for p in phis for a in (3, 4, 6) for c in ("radl", "micro", "perfect", "modelraw") if (p, c, a) not in cells]
check(not missing, f"every <phi>, alpha = 3, 4, 6 and closure has its cell (missing: {missing})")
check(all(n >= 1 and 0 <= se for (_, se, n, _) in cells.values()), "every cell has a realisation and a standard error >= 0")
with tempfile.TemporaryDirectory() as empty:
    p = subprocess.run([sys.executable, os.path.join(source, "tools", "closure_wide_table.py"), empty, "--rms-alphas",
                        "3,4,6", "--cells-in", table], capture_output=True, text=True)
check(p.returncode == 0, f"closure_wide_table.py reads the file ({p.stderr.strip()})")
rms = dict(re.findall(r"^\| (radl2014|micro \(no correction\)|perfect \(the grid's own phi-bar table\)|model fitted in "
                      r"this box, c_corr off) \| ([0-9.]+) % \|", p.stdout, re.M))
with open(os.path.join(source, "docs", "coarse.md")) as f:
    page = f.read()
for label, name in (("radl2014", "Radl 2014"), ("micro (no correction)", "micro"),
                    ("perfect (the grid's own phi-bar table)", "perfect"), ("model fitted in this box, c_corr off", "six-run model")):
    check(label in rms and f"| {name} | {rms[label]} % |" in page,
          f"{name}: the rms over alpha = 3, 4, 6 from the file ({rms.get(label)} %) is docs/coarse.md's")
print(f"{failures()} failed" if failures() else "all passed")
sys.exit(1 if failures() else 0)
