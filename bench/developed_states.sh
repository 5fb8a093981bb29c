#!/usr/bin/env bash
# The developed states the engine benchmarks time (issue 25), made reproducibly: the PROFILE=half resolved
# run (Makefile.pipeline's GENERATE_SET: 53 x 213 x 53 d_p, gamma* = 2e-3, and its PHI_SET_<phi>: gamma* = 1e-3 at
# 0.20-0.40) at each solids fraction, run from
# rest to T t_ref with cgd-generate (continued from its checkpoint when OUT/phi<phi> already has one), so that
#   build/bench/cgd-bench-developed --from-run OUT/phi<phi>
# times that state. A pipeline run directory (out/generate/phi<phi> of `make -f Makefile.pipeline PROFILE=half
# generate`) serves as well. Figures only, never asserted (bench/README.md, "Developed state").
# usage: bench/developed_states.sh OUT [phis=0.05,0.30] [tref=20] [ranks=2]
# Cost: that of the runs themselves (tools/run_health.py RUN_DIR prints their wall seconds per t_ref).
# Exit status: 0 every state made; 1 a run failed; 2 bad arguments.
set -uo pipefail
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
gen=${CGD_GENERATE:-$repo/build/cgd-generate}
[ $# -ge 1 ] || { echo "usage: bench/developed_states.sh OUT [phis=0.05,0.30] [tref=20] [ranks=2]" >&2; exit 2; }
out=$1
IFS=, read -r -a phis <<< "${2:-0.05,0.30}"
tref=${3:-20}
ranks=${4:-2}
[ -x "$gen" ] || { echo "developed_states.sh: $gen not found: build cgd first (cmake --build build)" >&2; exit 2; }
[[ $tref =~ ^[0-9]+([.][0-9]+)?$ ]] || { echo "developed_states.sh: tref '$tref' is not a number" >&2; exit 2; }
[[ $ranks =~ ^[1-9][0-9]*$ ]] || { echo "developed_states.sh: ranks '$ranks' is not a positive integer" >&2; exit 2; }
for phi in "${phis[@]}"; do
  [[ $phi =~ ^0?[.][0-9]+$ ]] || { echo "developed_states.sh: solids fraction '$phi' is not in (0, 1)" >&2; exit 2; }
done
# the half profile's scene and settings, from Makefile.pipeline itself (its end time is replaced: overrides apply
# in order, the last one given wins)
base=$(make -s -C "$repo" -f Makefile.pipeline PROFILE=half print-BASE_SCENE) &&
  read -r -a profile_set <<< "$(make -s -C "$repo" -f Makefile.pipeline PROFILE=half print-GENERATE_SET)" ||
  { echo "developed_states.sh: could not read PROFILE=half from Makefile.pipeline" >&2; exit 2; }
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
launch=()
[ "$ranks" -gt 1 ] && launch=(mpirun --allow-run-as-root --oversubscribe -np "$ranks")
status=0
for phi in "${phis[@]}"; do
  dir=$out/phi$phi
  args=(--set "run.end_time_tref=$tref" -o "$dir" --quiet)
  if [ -e "$dir/checkpoint.h5" ]; then
    args=(--restart "${args[@]}")
  else
    # the profile's settings for this <phi> too (PHI_SET_<phi>, e.g. the dense runs' gamma*), after GENERATE_SET
    # as the pipeline gives them
    read -r -a phi_set <<< "$(make -s -C "$repo" -f Makefile.pipeline PROFILE=half "print-PHI_SET_$phi")" ||
      { echo "developed_states.sh: could not read PHI_SET_$phi from Makefile.pipeline" >&2; exit 2; }
    sets=()
    for kv in "${profile_set[@]}" "${phi_set[@]}"; do sets+=(--set "$kv"); done
    args=("$repo/$base" --set "particles.solids_fraction=$phi" "${sets[@]}" "${args[@]}")
  fi
  echo "developed_states.sh: phi = $phi to $tref t_ref -> $dir"
  "${launch[@]}" "$gen" "${args[@]}" || { echo "developed_states.sh: the run at phi = $phi failed" >&2; status=1; }
done
[ $status -eq 0 ] && echo "time them with: build/bench/cgd-bench-developed --from-run $out/phi<phi>"
exit $status
