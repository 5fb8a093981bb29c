#!/usr/bin/python3
"""Makefile.pipeline's reuse of a modelraw coarse run as its model twin, when the parcel fit applied no c_corr.

  pipeline_reuse.py --identity MODEL.h5
      exit 0 if the model's c_corr(alpha) = a + (1 - a) exp(-k (alpha - 1)) is 1 at every alpha (k = 0 or a = 1),
      1 if not, 2 if the file cannot be read. An alpha > 1 run with that model is then the same run, bit for bit, as
      the one with c_corr switched off (the modelraw run of the same configuration and seed).
  pipeline_reuse.py --link RAW_DIR DIR --label model --model MODEL.h5
      makes DIR (atomically: built as DIR.tmp, renamed) holding RAW_DIR's summary.h5 with the root attributes
      label = LABEL, reused_from = RAW_DIR and reused_model = MODEL.h5 added, symbolic links to RAW_DIR's other
      files, a REUSED note, and DONE. tools/study.py reads the label; the cost is the raw run's.
"""
import argparse
import os
import shutil
import sys

import h5py


def identity(model):
    try:
        with h5py.File(model, "r") as f:
            a = f["c_corr"].attrs
            return float(a["k"]) == 0.0 or float(a["a"]) == 1.0
    except (OSError, KeyError) as e:
        sys.stderr.write(f"pipeline_reuse: {model}: cannot read /c_corr a and k ({e})\n")
        sys.exit(2)


def link(raw, out, label, model):
    if not os.path.isfile(os.path.join(raw, "DONE")) or not os.path.isfile(os.path.join(raw, "summary.h5")):
        sys.stderr.write(f"pipeline_reuse: {raw}: not a complete coarse run with a summary.h5\n")
        sys.exit(2)
    tmp = out.rstrip("/") + ".tmp"
    shutil.rmtree(tmp, ignore_errors=True)
    os.makedirs(tmp)
    shutil.copyfile(os.path.join(raw, "summary.h5"), os.path.join(tmp, "summary.h5"))
    with h5py.File(os.path.join(tmp, "summary.h5"), "r+") as f:
        f.attrs["label"] = label
        f.attrs["reused_from"] = raw
        f.attrs["reused_model"] = model
    rel = os.path.relpath(os.path.abspath(raw), os.path.abspath(out))  # the links live in DIR (DIR.tmp is renamed)
    for name in sorted(os.listdir(raw)):
        if name not in ("summary.h5", "DONE"):
            os.symlink(os.path.join(rel, name), os.path.join(tmp, name))
    with open(os.path.join(tmp, "REUSED"), "w") as fh:
        fh.write(f"Not run: the parcel fit ({model}) applied no c_corr (c_corr = 1 at every alpha), so this run would\n"
                 f"repeat {raw} bit for bit. summary.h5 is that run's, with label = {label}; the other files link to it.\n")
    open(os.path.join(tmp, "DONE"), "w").close()
    shutil.rmtree(out, ignore_errors=True)
    os.replace(tmp, out)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--identity", metavar="MODEL.h5")
    ap.add_argument("--link", nargs=2, metavar=("RAW_DIR", "DIR"))
    ap.add_argument("--label", default="model")
    ap.add_argument("--model", default="")
    a = ap.parse_args()
    if a.identity:
        sys.exit(0 if identity(a.identity) else 1)
    if a.link:
        link(a.link[0], a.link[1], a.label, a.model)
        return
    ap.error("give --identity MODEL.h5 or --link RAW_DIR DIR")


if __name__ == "__main__":
    main()
