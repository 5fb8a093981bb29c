#!/usr/bin/env bash
# One simulation stage of Makefile.pipeline: run `COMMAND... -o RUN_DIR` so that make can trust RUN_DIR/DONE.
# usage: scripts/pipeline_run.sh LABEL RUN_DIR PARAMS -- COMMAND...
#   PARAMS: the text that defines the run (scene, --set overrides); kept in RUN_DIR.params.
# If RUN_DIR holds an unfinished run of the same PARAMS with a checkpoint (a killed or failed make), it is
# continued with --restart: nothing already computed is lost. Otherwise (new parameters, or no checkpoint)
# RUN_DIR is removed, saying so and why, and the run starts afresh. One progress line at the start, one a minute with the
# simulated time reached and an ETA (from the run's series.h5), and one at the end.
set -uo pipefail
label=$1 dir=$2 params=$3
shift 3
[ "${1:-}" = "--" ] && shift
say() { echo "[pipeline] $label: $*" >&2; }
start=$(date +%s)
restart=()
if [ -d "$dir" ] && [ -f "$dir.params" ] && [ "$(cat "$dir.params")" = "$params" ] && [ -f "$dir/checkpoint.h5" ] &&
   [ ! -f "$dir/DONE" ]; then
  restart=(--restart)
  say "continuing the unfinished run in $dir from its checkpoint"
else
  if [ -e "$dir" ]; then  # say what is lost, and why
    same=no
    [ -f "$dir.params" ] && [ "$(cat "$dir.params")" = "$params" ] && same=yes
    if [ -f "$dir/DONE" ] && [ $same = yes ]; then why="a complete run that make found out of date"
    elif [ -f "$dir/DONE" ]; then why="a complete run with other parameters"
    elif [ $same = yes ]; then why="an unfinished run without a checkpoint to continue from"
    else why="an unfinished run with other parameters"; fi
    say "removing the previous run in $dir ($why)"
  fi
  rm -rf "$dir" "$dir.params"
  say "running -> $dir"
fi
mkdir -p "$(dirname "$dir")"
printf '%s\n' "$params" >"$dir.params"
"$@" -o "$dir" "${restart[@]}" --quiet >"$dir.log" 2>&1 &
pid=$!
progress() {  # simulated time reached, of the end time, and an ETA from the series (written at each snapshot)
  /usr/bin/python3 - "$dir/series.h5" 2>/dev/null <<'PY'
import sys, h5py
with h5py.File(sys.argv[1], "r") as f:
    t, w = f["time"][-1], f["wall_seconds"][-1]
    p = f["params"].attrs
    end, tref = p["end_time_s"], p.get("t_ref_s", 0)
    frac = t / end if end > 0 else 0
    eta = w * (1 - frac) / frac if frac > 0 else float("nan")
    unit = f"{t / tref:.1f} of {end / tref:.0f} t_ref" if tref > 0 else f"{t:.3g} of {end:.3g} s"
    print(f"{unit}, ETA {eta:.0f} s")
PY
}
last=$(date +%s)
while kill -0 "$pid" 2>/dev/null; do
  sleep 2
  if [ $(( $(date +%s) - last )) -ge 60 ]; then
    last=$(date +%s)
    line=$(progress) && [ -n "$line" ] && say "$line"
  fi
done
wait "$pid"
status=$?
if [ $status -ne 0 ] || [ ! -f "$dir/DONE" ]; then
  say "FAILED (exit status $status); its log: $dir.log"
  tail -n 15 "$dir.log" >&2
  exit 1
fi
say "done in $(( $(date +%s) - start )) s"
