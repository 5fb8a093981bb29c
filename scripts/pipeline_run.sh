#!/usr/bin/env bash
# One simulation stage of Makefile.pipeline: run `COMMAND... -o RUN_DIR` so that make can trust RUN_DIR/DONE.
# usage: scripts/pipeline_run.sh [--fresh] LABEL RUN_DIR PARAMS -- COMMAND...
#   PARAMS: the text that defines the run (scene, --set overrides); kept in RUN_DIR.params.
#   --fresh: always start afresh (coarse runs: a new model must not continue nor keep an old run).
# Without --fresh: a complete run (DONE) of the same PARAMS is kept as it is (its DONE touched, so make takes it
# as up to date): nothing is rerun that would give the same files. An unfinished run of the same PARAMS with a
# checkpoint (a killed or failed make) is continued with --restart: nothing already computed is lost.
# Otherwise (other parameters, no checkpoint, or --fresh) the previous RUN_DIR is set aside (RUN_DIR.previous),
# and removed, saying so and why, only once the new run is under way (it has written series.h5 or a checkpoint,
# or finished); a new run that fails or is interrupted before that gives the previous one back untouched.
# One progress line at the start, one a minute with the simulated time reached and an ETA (from the run's
# series.h5), and one at the end.
set -uo pipefail
fresh=no
[ "${1:-}" = "--fresh" ] && { fresh=yes; shift; }
label=$1 dir=$2 params=$3
shift 3
[ "${1:-}" = "--" ] && shift
say() { echo "[pipeline] $label: $*" >&2; }
start=$(date +%s)
prev="$dir.previous"
under_way() { [ -f "$dir/series.h5" ] || [ -f "$dir/checkpoint.h5" ] || [ -f "$dir/DONE" ]; }
restore_previous() {  # give the set-aside run back (the new one never got under way)
  [ -e "$prev" ] || return 0
  rm -rf "$dir" "$dir.params" "$dir.log"
  mv "$prev" "$dir"
  [ -e "$prev.params" ] && mv "$prev.params" "$dir.params"
  [ -e "$prev.log" ] && mv "$prev.log" "$dir.log"
  say "the new run did not get under way: the previous run in $dir is back, untouched"
}
drop_previous() {
  [ -e "$prev" ] || [ -e "$prev.params" ] || return 0
  say "the new run is under way: removing the previous run ($why)"
  rm -rf "$prev" "$prev.params" "$prev.log"
}
# a run set aside by an earlier call that was interrupted: back if the run after it never got under way
if [ -e "$prev" ]; then
  if under_way; then why="set aside by an earlier call"; drop_previous; else restore_previous; fi
fi
same=no
[ -f "$dir.params" ] && [ "$(cat "$dir.params")" = "$params" ] && same=yes
restart=()
if [ $fresh = no ] && [ -d "$dir" ] && [ $same = yes ] && [ -f "$dir/DONE" ]; then
  touch "$dir/DONE"
  say "up to date: $dir is a complete run of these parameters (kept, not rerun)"
  exit 0
elif [ $fresh = no ] && [ -d "$dir" ] && [ $same = yes ] && [ -f "$dir/checkpoint.h5" ]; then
  restart=(--restart)
  say "continuing the unfinished run in $dir from its checkpoint"
else
  why=
  if [ -e "$dir" ]; then  # set aside; say what will be lost, and why, once the new run is under way
    if [ -f "$dir/DONE" ] && [ $same = yes ]; then why="a complete run of the same parameters: a fresh run was asked"
    elif [ -f "$dir/DONE" ]; then why="a complete run with other parameters"
    elif [ $same = yes ]; then why="an unfinished run without a checkpoint to continue from"
    else why="an unfinished run with other parameters"; fi
    rm -rf "$prev" "$prev.params" "$prev.log"
    mv "$dir" "$prev"
    [ -e "$dir.params" ] && mv "$dir.params" "$prev.params"
    [ -e "$dir.log" ] && mv "$dir.log" "$prev.log"
    say "setting the previous run aside ($why) until the new one is under way"
  else
    rm -f "$dir.params"
  fi
  say "running -> $dir"
fi
mkdir -p "$(dirname "$dir")"
printf '%s\n' "$params" >"$dir.params"
"$@" -o "$dir" "${restart[@]}" --quiet >"$dir.log" 2>&1 &
pid=$!
# interrupted (Ctrl-C, kill): stop the run; the previous one comes back if the new one never got under way
trap 'kill "$pid" 2>/dev/null; wait "$pid" 2>/dev/null; under_way || restore_previous; say "interrupted"; exit 130' INT TERM
# The ETA is the rate of the last fifth of the simulated time (not the average since the start): a coupled
# run slows down as its clusters form (the Table 1 phi = 0.05 run: 47 s per t_ref at the start, 267 s at
# 8 t_ref), so the average promised half the time that was left; the recent rate is still a lower bound
# while the run keeps slowing.
progress() {  # simulated time reached, of the end time, and an ETA from the series (written at each snapshot)
  /usr/bin/python3 - "$dir/series.h5" 2>/dev/null <<'PY'
import sys, h5py, numpy
with h5py.File(sys.argv[1], "r") as f:
    times, walls = f["time"][:], f["wall_seconds"][:]
    t, w = times[-1], walls[-1]
    p = f["params"].attrs
    end, tref = p["end_time_s"], p.get("t_ref_s", 0)
    frac = t / end if end > 0 else 0
    k = min(int(numpy.searchsorted(times, 0.8 * t)), len(times) - 1)
    if times[-1] > times[k] and walls[-1] > walls[k]:
        eta = (walls[-1] - walls[k]) / (times[-1] - times[k]) * (end - t)
    else:
        eta = w * (1 - frac) / frac if frac > 0 else float("nan")
    unit = f"{t / tref:.1f} of {end / tref:.0f} t_ref" if tref > 0 else f"{t:.3g} of {end:.3g} s"
    if eta != eta:
        left = "unknown"
    elif eta < 10:
        left = f"{eta:.1f} s"
    elif eta < 100:
        left = f"{eta:.0f} s"
    elif eta < 5940:
        left = f"{eta / 60:.0f} min"
    else:
        left = f"{eta / 3600:.1f} h"
    print(f"{unit}, ETA {left}")
PY
}
last=$(date +%s)
while kill -0 "$pid" 2>/dev/null; do
  sleep 2
  [ -e "$prev" ] && under_way && drop_previous
  if [ $(( $(date +%s) - last )) -ge 60 ]; then
    last=$(date +%s)
    line=$(progress) && [ -n "$line" ] && say "$line"
  fi
done
wait "$pid"
status=$?
trap - INT TERM
if [ $status -ne 0 ] || [ ! -f "$dir/DONE" ]; then
  say "FAILED (exit status $status); its log: $dir.log"
  tail -n 15 "$dir.log" >&2
  if [ -e "$prev" ] && ! under_way; then
    cp "$dir.log" "$dir.failed.log" 2>/dev/null && say "(the failed attempt's log is kept as $dir.failed.log)"
    restore_previous
  else
    drop_previous
  fi
  exit 1
fi
drop_previous
say "done in $(( $(date +%s) - start )) s"
