#!/usr/bin/python3
"""tools/plot_model.py: the stretch past the model's data (from phi_max to --phi-to, none when --phi-to is below it),
the shipped model drawn to a PNG (Debian's matplotlib; the file starts with the PNG signature), and a --phi-to beyond
random close packing refused with exit status 2 and no file written.
usage: /usr/bin/python3 tests/tools/plot_model.py SOURCE_DIR"""
import os
import subprocess
import sys
import tempfile

import numpy as np

from tool_check import check, failures, source  # noqa: E402  (tests/tools/tool_check.py)
import plot_model as pm  # noqa: E402

g = pm.beyond_grid(0.485, 0.6)
check(len(g) == 30 and g[0] == 0.485 and g[-1] == 0.6 and np.all(np.diff(g) > 0),
      f"beyond phi_max 0.485 to 0.6: {len(g)} points from {g[0]} to {g[-1]}")
check(len(pm.beyond_grid(0.485, 0.4)) == 0 and len(pm.beyond_grid(0.485, 0.485)) == 0,
      "no stretch when --phi-to is at or below phi_max")
tool = os.path.join(source, "tools", "plot_model.py")
model = os.path.join(source, "data", "models", "half_box.h5")
with tempfile.TemporaryDirectory() as tmp:
    png = os.path.join(tmp, "m.png")
    r = subprocess.run([sys.executable, tool, model, "-o", png], capture_output=True, text=True)
    head = open(png, "rb").read(8) if os.path.exists(png) else b""
    check(r.returncode == 0 and head == b"\x89PNG\r\n\x1a\n", f"the shipped model drawn: exit {r.returncode}, {head!r}")
    bad = os.path.join(tmp, "bad.png")
    r = subprocess.run([sys.executable, tool, model, "-o", bad, "--phi-to", "0.9"], capture_output=True, text=True)
    check(r.returncode == 2 and "--phi-to 0.9" in r.stderr and not os.path.exists(bad),
          f"--phi-to 0.9 refused: exit {r.returncode}, nothing written: {not os.path.exists(bad)}")
sys.exit(1 if failures() else 0)
