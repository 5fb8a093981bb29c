#!/usr/bin/env bash
# Only the effects a scene calls for run: one scene (data/scenes/pipeline_demo.toml at <phi> = 0.05,
# 10k particles, 9 x 36 x 9 cells) for a short time with each effect switched off in turn, timed and
# its peak memory measured (GNU time). Printed, never asserted.
# usage: bash bench/effects.sh [END_TIME_TREF (default 2)] [BUILD_DIR (default build)]
set -uo pipefail
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
end=${1:-2}
build=${2:-$repo/build}
scene=$repo/data/scenes/pipeline_demo.toml
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
common=(--set particles.solids_fraction=0.05 --set run.end_time_tref="$end" --set run.dump_interval_tref="$end" --quiet)
variants=(
  "all effects (two-way, friction, pressure force, Beetstra)|generate|"
  "one-way coupling|generate|fluid.coupling=one-way"
  "fluid at rest (quiescent, Stokes drag: no grid)|generate|fluid.coupling=quiescent fluid.drag=stokes fluid.pressure_gradient_force=false"
  "no friction (no history, no rotation)|generate|contact.friction=0"
  "no pressure-gradient force|generate|fluid.pressure_gradient_force=false"
  "no contacts (no neighbour search; same dt)|generate|contact.model=none run.dt=2.149e-6"
  "filtered law radl2014 instead of Beetstra|coarse|fluid.drag=radl2014 run.sampling_start_tref=0"
)
printf '%-52s %10s %8s %10s\n' "scene" "wall s" "ratio" "peak MiB"
base=""
for v in "${variants[@]}"; do
  IFS='|' read -r label tool sets <<<"$v"
  args=()
  for s in $sets; do args+=(--set "$s"); done
  out=$tmp/run_$RANDOM
  exe=$build/cgd-$tool
  /usr/bin/time -f '%M' -o "$tmp/mem" "$exe" "$scene" "${common[@]}" "${args[@]}" -o "$out" >"$tmp/log" 2>&1
  status=$?
  if [ $status -ne 0 ]; then
    printf '%-52s %10s (exit %d: %s)\n' "$label" "-" "$status" "$(grep -m1 -i error "$tmp/log" | head -c 120)"
    continue
  fi
  wall=$(sed -n 's/.*this session: .* in \([0-9.e+]*\) s.*/\1/p' "$tmp/log" | head -n 1)
  mem=$(awk '{printf "%.0f", $1/1024}' "$tmp/mem")
  [ -z "$base" ] && base=$wall
  ratio=$(awk -v a="$wall" -v b="$base" 'BEGIN{printf "%.2f", a/b}')
  printf '%-52s %10.2f %8s %10s\n' "$label" "$wall" "$ratio" "$mem"
  rm -rf "$out"
done
