#!/usr/bin/python3
"""tools/pipeline_reuse.py: --identity tells a model whose c_corr is 1 at every alpha (k = 0 or a = 1) from one
whose c_corr is not; --link makes the model run's directory from its modelraw twin: the summary relabelled, links
to the other files, a REUSED note and DONE, all at once (no DIR.tmp left).
usage: /usr/bin/python3 tests/tools/pipeline_reuse.py SOURCE_DIR"""
import os
import subprocess
import sys
import tempfile

import h5py

from tool_check import check, failures, source  # noqa: E402  (tests/tools/tool_check.py)
tool = os.path.join(source, "tools", "pipeline_reuse.py")

def model(path, a, k):
    with h5py.File(path, "w") as f:
        g = f.create_group("c_corr")
        g.attrs["a"], g.attrs["k"] = a, k


def run(*args):
    return subprocess.run(["/usr/bin/python3", tool, *args], capture_output=True, text=True).returncode


with tempfile.TemporaryDirectory() as tmp:
    for name, a, k, expected in (("identity_k0", 0.0, 0.0, 0), ("identity_a1", 1.0, 0.3, 0), ("paper", 0.0, 0.05, 1),
                                 ("negative_k", 0.0, -0.05, 1)):
        model(os.path.join(tmp, name + ".h5"), a, k)
        check(run("--identity", os.path.join(tmp, name + ".h5")) == expected,
              f"--identity a = {a}, k = {k}: exit {expected} ({'c_corr = 1' if expected == 0 else 'c_corr != 1'})")
    check(run("--identity", os.path.join(tmp, "missing.h5")) == 2, "--identity of a missing file: exit 2")
    coarse = os.path.join(tmp, "coarse")
    raw = os.path.join(coarse, "phi0.05_c4_a2_modelraw_s2")
    os.makedirs(raw)
    with h5py.File(os.path.join(raw, "summary.h5"), "w") as f:
        f.attrs["cgd_format"], f.attrs["drag"], f.attrs["slip_over_ut"] = "coarse_summary", "model-raw", 0.9
    for name in ("DONE", "series.h5", "scene.toml"):
        open(os.path.join(raw, name), "w").write(name)
    out = os.path.join(coarse, "phi0.05_c4_a2_model_s2")
    os.makedirs(out)  # a stale directory is replaced
    check(run("--link", raw, out, "--label", "model", "--model", "fit/model_parcels.h5") == 0, "--link exits 0")
    with h5py.File(os.path.join(out, "summary.h5"), "r") as f:
        a = f.attrs
        check(a["label"] == "model" and a["reused_from"] == raw and a["slip_over_ut"] == 0.9 and a["drag"] == "model-raw",
              "summary: the twin's values, label = model, reused_from the twin")
    with h5py.File(os.path.join(raw, "summary.h5"), "r") as f:
        check("label" not in f.attrs, "the twin's own summary is untouched")
    check(os.path.islink(os.path.join(out, "series.h5")) and open(os.path.join(out, "series.h5")).read() == "series.h5",
          "series.h5 links to the twin's")
    check(os.path.isfile(os.path.join(out, "REUSED")) and os.path.isfile(os.path.join(out, "DONE"))
          and not os.path.islink(os.path.join(out, "DONE")), "REUSED note and an own DONE")
    check(not os.path.exists(out + ".tmp"), "no temporary directory left")
    check(run("--link", os.path.join(coarse, "nothing"), os.path.join(coarse, "x")) == 2 and
          not os.path.exists(os.path.join(coarse, "x")), "--link from an incomplete run: exit 2, nothing made")
sys.exit(1 if failures() else 0)
