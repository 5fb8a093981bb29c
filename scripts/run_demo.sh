#!/usr/bin/env bash
# The main job of cgd, on a fresh Debian machine: install and build (scripts/setup.sh), run the demo
# scene, then summarise its result (last snapshot and the tail of the time series).
# usage: scripts/run_demo.sh [EXTRA ARGS...]   extra arguments go to the main job
#        (e.g. --set run.end_time=0.01 for cgd-generate)
# Exit status: the main job's (0 done, 1 run failed, 2 bad input); 1 if setup/build failed.
set -uo pipefail

repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$repo" || exit 1

run_dir=out/generate/sedimentation_demo
# The main job. Switching to the pipeline is this one line: main_job=(make -f Makefile.pipeline)
main_job=(build/cgd-generate data/scenes/sedimentation_demo.toml -o "$run_dir")

say() { echo "run_demo.sh: $*" >&2; }
start=$(date +%s)

if ! bash scripts/setup.sh; then
  say "FAILED in setup/build (scripts/setup.sh); nothing was run"
  exit 1
fi

export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
# the demo always starts afresh (a run directory is never overwritten by cgd-generate itself)
rm -rf "$run_dir"
say "running: ${main_job[*]} $*"
"${main_job[@]}" "$@"
status=$?
say "main job finished with exit status $status after $(( $(date +%s) - start )) s"
if [ $status -ne 0 ]; then
  case $status in
    2) say "bad input (scene, file or option): see the message above; nothing was written" ;;
    1) say "the run failed: see the message above; $run_dir keeps a diagnostic snapshot and the last checkpoint" ;;
  esac
  exit $status
fi

# ---- summary ----------------------------------------------------------------------------------
echo
echo "== run directory: $run_dir"
if [ -e "$run_dir/DONE" ]; then echo "completion marker: $run_dir/DONE present"
else echo "WARNING: no completion marker $run_dir/DONE"; fi
ls -l "$run_dir"

last=$(ls "$run_dir"/snapshots/snap_*.h5 2>/dev/null | sort -V | tail -n 1)
echo
if [ -z "$last" ]; then
  echo "== no snapshots in $run_dir/snapshots"
else
  echo "== last snapshot: $last ($(ls "$run_dir"/snapshots/snap_*.h5 | wc -l) in all)"
  if [ -f tools/inspect_snapshot.py ]; then
    /usr/bin/python3 tools/inspect_snapshot.py "$last" || say "tools/inspect_snapshot.py failed on $last"
  else
    echo "(tools/inspect_snapshot.py is not there yet; listing the file instead)"
    h5ls -r "$last"
  fi
fi

echo
if [ -f "$run_dir/series.h5" ]; then
  echo "== tail of $run_dir/series.h5"
  /usr/bin/python3 - "$run_dir/series.h5" <<'PY' || say "could not read $run_dir/series.h5"
import sys
import h5py
import numpy as np

# Every dataset whose first dimension is the row count is a column (vectors have a trailing 3).
with h5py.File(sys.argv[1], "r") as f:
    columns = {}
    f.visititems(lambda name, obj: columns.__setitem__(name, obj[()])
                 if isinstance(obj, h5py.Dataset) and obj.ndim >= 1 else None)
    rows = len(columns["time"]) if "time" in columns else max((len(v) for v in columns.values()), default=0)
    names, values = [], []
    for name, v in sorted(columns.items(), key=lambda item: item[0] != "time"):
        if len(v) != rows or not np.issubdtype(v.dtype, np.number):
            continue
        v = v.reshape(rows, -1)
        for j in range(v.shape[1]):
            names.append(name if v.shape[1] == 1 else f"{name}[{'xyz'[j] if v.shape[1] == 3 else j}]")
            values.append(v[:, j])
    print(f"{rows} rows; last {min(rows, 5)}:")
    for name, col in zip(names, values):
        print(f"  {name:32s}" + "".join(f" {x:12.5g}" for x in col[-5:]))
PY
else
  echo "== no $run_dir/series.h5"
fi
echo
if /usr/bin/python3 tools/plot_series.py "$run_dir" --homogeneous 0.644 -o "$run_dir/slip.png"; then
  echo "slip velocity plot: $run_dir/slip.png (dashed: the homogeneous Beetstra balance of models.md)"
fi
echo "Open $run_dir/run.xmf in ParaView to look at the run."
