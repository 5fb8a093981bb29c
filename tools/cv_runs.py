#!/usr/bin/python3
"""The leave-one-run-out cross-validation lines of a cgd-fit report, each run named by its <phi> and directory.

cgd-fit's report lists the runs left out as "FILE run K: ..." (K the run's index in the filtered file); this reads
each FILE's /runs (mean_solids_fraction, the paths attribute) and prints the same lines as
"<phi> = 0.05 (generate/phi0.05, run K of FILE): ...". The pipeline's summary.txt uses it.

usage: /usr/bin/python3 tools/cv_runs.py MODEL.report.txt"""
import os
import re
import sys

import h5py

LINE = re.compile(r"^  (?P<file>\S+) run (?P<run>\d+): (?P<rest>.*)$")


def runs_of(path, cache={}):
    if path not in cache:
        try:
            with h5py.File(path, "r") as f:
                phi = f["runs/mean_solids_fraction"][()]
                paths = [p.decode() if isinstance(p, bytes) else str(p) for p in f["runs"].attrs.get("paths", [])]
        except (OSError, KeyError):
            phi, paths = [], []
        cache[path] = (phi, paths)
    return cache[path]


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__.split("usage: ")[1])
    inside = False
    with open(sys.argv[1]) as fh:
        for line in fh:
            line = line.rstrip("\n")
            if line.startswith("leave-one-run-out cross-validation"):
                inside = True
                print(line)
                continue
            if not inside:
                continue
            m = LINE.match(line)
            if not m:
                break
            phi, paths = runs_of(m["file"])
            k = int(m["run"])
            where = (os.path.join(os.path.basename(os.path.dirname(paths[k].rstrip("/"))), os.path.basename(paths[k].rstrip("/")))
                     if k < len(paths) else "")
            name = f"<phi> = {phi[k]:.3f}" if k < len(phi) else f"run {k}"
            print(f"  {name} ({where + ', ' if where else ''}run {k} of {m['file']}): {m['rest']}")


if __name__ == "__main__":
    main()
