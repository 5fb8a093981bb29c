#!/usr/bin/env bash
# e2e (issue 19): the example scene cgd-coarse --help names is one cgd-coarse runs (it named a dry scene it refuses):
# the scene of "e.g. data/scenes/<name>.toml" run for a fraction of a t_ref in a small box exits 0 with a summary.
# Environment (set by CTest): CGD_SOURCE_DIR, CGD_BINARY_DIR.
source "$(dirname "$0")/lib/prologue.sh"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
scene=$("$binary_dir/cgd-coarse" --help 2>&1 | grep -o 'e\.g\. data/scenes/[A-Za-z0-9_]*\.toml' | head -n 1 | cut -c6-)
[ -n "$scene" ] && [ -f "$scene" ] || { echo "FAIL cgd-coarse --help names no existing example scene ('$scene')"; exit 1; }
"$binary_dir/cgd-coarse" "$scene" --set 'domain.size_dp=[20,80,20]' --set fluid.dx_over_dp=5 --set run.end_time_tref=1 \
  --set run.sampling_start_tref=0.3 --quiet -o "$tmp/run" >"$tmp/log" 2>&1; s=$?
if [ $s -eq 0 ] && [ -f "$tmp/run/summary.h5" ]; then
  echo "ok   cgd-coarse --help's example $scene runs (exit 0, summary.h5)"
else
  echo "FAIL cgd-coarse --help's example $scene: exit $s: $(tail -n 3 "$tmp/log")"
  exit 1
fi
