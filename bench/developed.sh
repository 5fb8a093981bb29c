#!/usr/bin/env bash
# The developed-state benchmark in one command: cgd-bench-developed at 1 and 2 ranks on the Table 1
# phi = 0.05 box (a developed quarter box tiled 4 x 4 x 4; developed once and cached), then a summary
# table. Figures only, never asserted (bench/README.md, "Developed state").
# usage: bench/developed.sh [fluid_steps=10] [ranks=1,2] [tile=4] [extra cgd-bench-developed options...]
#   e.g. bench/developed.sh 4 1 2        (a quick look: 4 fluid steps, 1 rank, a box of half the size)
# Environment: CGD_BENCH_DEVELOPED (default build/bench/cgd-bench-developed), CGD_BENCH_CACHE (the cache of
# developed states, default ~/.cache/cgd-bench). Exit status: 0 all runs done; 1 a run failed; 2 bad arguments.
set -uo pipefail
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bin=${CGD_BENCH_DEVELOPED:-$repo/build/bench/cgd-bench-developed}
steps=${1:-10}
IFS=, read -r -a ranks <<< "${2:-1,2}"
tile=${3:-4}
shift $(( $# < 3 ? $# : 3 ))
[ -x "$bin" ] || { echo "developed.sh: $bin not found: build cgd first (cmake --build build)" >&2; exit 2; }
for n in "$steps" "$tile" "${ranks[@]}"; do
  [[ $n =~ ^[1-9][0-9]*$ ]] || { echo "developed.sh: bad number '$n'" >&2; exit 2; }
done
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
# develop (once) before timing anything, on one rank
"$bin" --tile 1 --fluid-steps 1 --warmup 0 --no-projection "$@" > /dev/null || exit 1
status=0
summaries=()
for r in "${ranks[@]}"; do
  echo "=== $r rank(s) ==="
  if [ "$r" -eq 1 ]; then out=$("$bin" --tile "$tile" --fluid-steps "$steps" "$@")
  else out=$(mpirun --allow-run-as-root --oversubscribe -np "$r" "$bin" --tile "$tile" --fluid-steps "$steps" "$@"); fi
  [ $? -eq 0 ] || status=1
  echo "$out"
  summaries+=("$(grep '^summary:' <<< "$out")")
done
echo
echo "ranks | ns/particle-step (wall x ranks) | ns/particle-step (process CPU) | particle-steps/s/core (wall) | steps/rebuild | dt_fluid"
for s in "${summaries[@]}"; do
  get() { sed -n "s/.* $1=\([^ ]*\).*/\1/p" <<< "$s"; }
  echo "$(get ranks) | $(get ns_per_ps) | $(get ns_cpu_per_ps) | $(get ps_per_s_per_core) | $(get steps_per_rebuild) | $(get dt_fluid)"
done
exit $status
