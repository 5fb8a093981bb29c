#!/usr/bin/env bash
# The main job of cgd, on a fresh Debian machine: install and build (scripts/setup.sh), then run the
# whole pipeline on the demo profile (Makefile.pipeline PROFILE=demo, 2 jobs at a time): three small
# resolved runs, the filter, the fit, the coarse runs with and without the model, the parcel fit and the
# accuracy-versus-cost study, ending with the summary. About 13 minutes on 2 idle cores (measured).
# Make runs only what is out of date: run it again and it prints the summary at once; an interrupted run
# continues where it stopped (resolved runs from their checkpoints). The output goes to out/pipeline/demo
# (make -f Makefile.pipeline PROFILE=demo print-OUT); an earlier demo's files there are kept where they are
# up to date, and a stage rerun with other parameters replaces its earlier output (each resolved run that
# is removed is named on stderr). To keep an earlier demo, move its folder away first, or give OUT=DIR.
# usage: scripts/run_demo.sh [MAKE VARIABLES...]    e.g. scripts/run_demo.sh PHIS=0.05 (see: make -f Makefile.pipeline help)
# Exit status: 0 done; 1 setup/build or a stage failed (its message is printed); 2 bad variable.
set -uo pipefail

repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$repo" || exit 1
say() { echo "run_demo.sh: $*" >&2; }
start=$(date +%s)

if ! bash scripts/setup.sh; then
  say "FAILED in setup/build (scripts/setup.sh); nothing was run"
  exit 1
fi
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
out=$(make -s -f Makefile.pipeline PROFILE=demo "$@" print-OUT)
summary=$out/summary.txt
before=$(stat -c %Y "$summary" 2>/dev/null || echo none)
if [ -d "$out" ]; then
  say "$out holds an earlier demo: its up-to-date files are reused; stages whose parameters changed are rerun and replace their earlier output (move $out away first to keep it)"
fi
say "running the pipeline: make -f Makefile.pipeline -j2 PROFILE=demo $* (one line per stage; runs only what is out of date)"
make -f Makefile.pipeline -j2 PROFILE=demo "$@" all
status=$?
if [ $status -ne 0 ]; then
  say "the pipeline stopped (make exit status $status): the failing stage's message and log are above"
  exit 1
fi
# the summary is printed when the pipeline writes it; print it here when everything was already done
[ "$(stat -c %Y "$summary" 2>/dev/null || echo none)" = "$before" ] && [ -f "$summary" ] && cat "$summary"
say "done in $(( $(date +%s) - start )) s; look at any file with tools/cgd-show PATH (e.g. tools/cgd-show out/pipeline/demo/fit/model.h5)"
