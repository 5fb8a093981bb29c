#!/usr/bin/python3
"""tools/stiffness_table.py against known answers: the overlaps of a hand-placed periodic configuration (a pair
touching across the box's periodic face at 0.9 d, one at 0.99 d, a free particle: mean overlap 0.055 d, largest
0.1 d), chi2/dof of H against itself (0) and against a copy shifted by one standard error (0.5: each bin's
combined error is sqrt(2) sigma), the modal bin, the configuration names (with and without t* and seed) and the
reference row (the smallest gamma*, then t*, then seed).
usage: /usr/bin/python3 tests/tools/stiffness_table.py SOURCE_DIR"""
import os
import sys
import tempfile

import h5py
import numpy as np

from tool_check import check, failures, source  # noqa: E402  (tests/tools/tool_check.py)
import stiffness_table as st  # noqa: E402


d, box = 1e-4, np.array([1e-3, 2e-3, 1e-3])
x = np.array([[0.2 * d, 1e-3, 5e-4],          # pair A: across the x face, centres 0.9 d apart
              [1e-3 - 0.7 * d, 1e-3, 5e-4],
              [5e-4, 1.5e-3, 5e-4],             # pair B: 0.99 d apart (unwrapped position: 1 box above)
              [5e-4, 1.5e-3 + 0.99 * d + 2e-3, 5e-4],
              [5e-4, 5e-4, 2.5e-4]])            # free
with tempfile.TemporaryDirectory() as tmp:
    path = os.path.join(tmp, "snap.h5")
    with h5py.File(path, "w") as f:
        f["particles/position"] = x
        f["particles/diameter"] = np.full(len(x), d)
        f.create_group("params").attrs["box_size_m"] = box
    mean, largest = st.overlaps([path])
# round-off: positions of order 1e-3 m, overlaps of order 1e-5 m: 1e-9 relative to d is ample
check(abs(mean - 0.055) < 1e-9 and abs(largest - 0.1) < 1e-9, f"overlaps: mean {mean:.6f} (0.055), largest {largest:.6f} (0.1)")

b = {"count": np.array([100, 500, 300]), "H": np.array([0.5, 0.4, 0.3]), "err": np.array([0.01, 0.02, 0.01]),
     "phi": np.array([0.01, 0.02, 0.03])}
b["ok"] = b["count"] >= 200
c0, n0 = st.chi2(b, b)
shifted = dict(b, H=b["H"] + b["err"])
c1, n1 = st.chi2(shifted, b)
check(c0 == 0.0 and n0 == 2, f"chi2 against itself: {c0} over {n0} bins (0 over 2)")
check(abs(c1 - 0.5) < 1e-12 and n1 == 2, f"chi2 shifted by one sigma: {c1} (0.5)")
phi, h, e = st.modal(b)
check(phi == 0.02 and h == 0.4 and e == 0.02, f"modal bin: phi {phi} H {h} +- {e} (0.02, 0.4, 0.02)")
names = {"g1e-3_phi0.30": "0.30", "g2e-3_t0.05_phi0.05": "0.05", "g1e-3_s2_phi0.30": "0.30",
         "g1e-3_t0.05_s12_phi0.05": "0.05", "g1e-3_s2_t0.05_phi0.05": None, "g1e-3_t0.05": None,
         "g1e-3_phi0.30.make.log": None}
got = {n: st.config_phi(n) for n in names}
check(got == names, f"configuration names: {got}")
rows = [{"gamma": 2e-3, "t_star": 0.02, "seed": 1}, {"gamma": 1e-3, "t_star": 0.05, "seed": 1},
        {"gamma": 1e-3, "t_star": 0.02, "seed": 2}, {"gamma": 1e-3, "t_star": 0.02, "seed": 1}]
check(min(rows, key=st.reference_key) is rows[3], "the reference: the smallest gamma*, then t*, then seed")
sys.exit(1 if failures() else 0)
