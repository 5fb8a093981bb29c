#!/usr/bin/env bash
# The wide-filter experiment of issue 28 (docs/closure.md "A filter wider than the cell"): does a drag
# correction measured on a coarser grid than the coarse run's own close the phi-bar-only closure's gap?
#
# usage: scripts/closure_wide_filter.sh OUT [PHIS=0.05,0.10] [ALPHAS=3,4,6] [SEEDS=1,2,3] [TABLE_GRIDS=4,3,2]
#                                           [RATIOS=1,1.5,2]
#   OUT: a finished `Makefile.pipeline PROFILE=half` output directory (OUT/generate/phi<phi>/DONE for every phi
#        of PHIS; OUT/fit/model.h5 for the model runs, which are skipped when it is absent).
# What it runs, on the coarse grid of COARSE_CELLS = 4 cells across (13.25 d_p, the half box's validation grid):
#   1. cgd-filter of the PHIS runs (from FROM_TREF = 20 t_ref) with --grids TABLE_GRIDS -> OUT/closure_wide/filtered.h5
#   2. cgd-fit --grid-table G for each G of TABLE_GRIDS -> OUT/closure_wide/perfect_g<G>.h5: the perfect closure of
#      the grid of G cells across (G = 4: the run's own grid, the usual perfect closure; G = 3, 2: the correction of
#      a grid 4/3 and 2 times coarser, i.e. Delta = r x the cell with r = 4/G)
#   3. coarse runs phi<phi>_a<alpha>_g<G>_s<seed> (the table of grid G, c_corr off, as the pipeline's perfect runs)
#      and phi<phi>_a<alpha>_r<r>_s<seed> (the fitted model at fluid.filter_to_grid_ratio = r), each with the
#      pipeline's coarse settings (COARSE_SET of the half profile: sampled 40-80 t_ref; then PHI_SET_<phi>, the dense
#      runs' gamma* = 1e-3 and t*)
#   4. the table (tools/closure_wide_table.py): slip error against the resolved run (its 20-50 t_ref slip) per
#      configuration, mean over the seeds +- their standard error -> OUT/closure_wide/table.md
# A configuration whose summary.h5 exists is not run again (delete its directory to rerun it); one killed before its
# end is continued from its checkpoint (scripts/coarse_run.sh).
# Environment: BUILD (default build), NICE (default 0: a niceness for the coarse runs).
#   HELDOUT=PHI,PHI,... (e.g. 0.02,0.05,0.10; default empty): the held-out test instead. Everything goes to
#   OUT/closure_heldout; the model runs of each phi of PHIS use a model fitted WITHOUT that phi's run: cgd-filter
#   of the other HELDOUT runs with the pipeline's filter settings (FILTER_GRIDS, WIDTHS, BINS, FROM_TREF of the
#   half profile) and cgd-fit with its FIT_ARGS -> OUT/closure_heldout/without_phi<phi>/model.h5. The perfect
#   tables (steps 1-2) stay each run's own: they are the reference, not a closure under test.
set -euo pipefail
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
out=${1:?usage: closure_wide_filter.sh OUT [PHIS] [ALPHAS] [SEEDS] [TABLE_GRIDS] [RATIOS]}
IFS=, read -r -a phis <<< "${2:-0.05,0.10}"
IFS=, read -r -a alphas <<< "${3:-3,4,6}"
IFS=, read -r -a seeds <<< "${4:-1,2,3}"
table_grids=${5-4,3,2}
IFS=, read -r -a grids <<< "$table_grids"
IFS=, read -r -a ratios <<< "${6:-1,1.5,2}"
build=${BUILD:-$repo/build}
nice_level=${NICE:-0}
cells=4
from_tref=20
mk() { make -s -f "$repo/Makefile.pipeline" PROFILE=half "$@"; }
source "$repo/scripts/coarse_run.sh"
base_scene=$(cd "$repo" && mk print-BASE_SCENE)
box_dp=$(cd "$repo" && mk print-BOX_DP)
dx=$(python3 -c "print($box_dp/$cells)")
IFS=, read -r -a heldout <<< "${HELDOUT:-}"
dir=$out/closure_wide
[ ${#heldout[@]} -gt 0 ] && dir=$out/closure_heldout
mkdir -p "$dir"
run_dirs=()
for phi in "${phis[@]}"; do
  [ -f "$out/generate/phi$phi/DONE" ] || { echo "closure_wide_filter.sh: $out/generate/phi$phi is not a finished run" >&2; exit 2; }
  run_dirs+=("$out/generate/phi$phi")
done

# TABLE_GRIDS may be empty ("" : the model runs only)
if [ ${#grids[@]} -gt 0 ] && [ ! -f "$dir/filtered.h5" ]; then
  echo "[closure_wide] filter ${phis[*]} on grids $table_grids" >&2
  "$build/cgd-filter" "${run_dirs[@]}" --from-tref $from_tref --grids "$table_grids" --force --quiet -o "$dir/filtered.h5"
fi
for g in "${grids[@]}"; do
  [ -f "$dir/perfect_g$g.h5" ] || "$build/cgd-fit" "$dir/filtered.h5" --grid-table "$g" --force -o "$dir/perfect_g$g.h5" \
    > "$dir/perfect_g$g.report.txt"
done
# the held-out models: for each phi, the pipeline's filter and fit on the other HELDOUT runs
model_for() {  # phi -> the model file its runs use
  if [ ${#heldout[@]} -eq 0 ]; then echo "$out/fit/model.h5"; else echo "$dir/without_phi$1/model.h5"; fi
}
if [ ${#heldout[@]} -gt 0 ]; then
  profile_words FILTER_ARGS_LINE filter_args
  profile_words FIT_ARGS fit_args
  for phi in "${phis[@]}"; do
    others=()
    for h in "${heldout[@]}"; do
      [ "$h" = "$phi" ] && continue
      [ -f "$out/generate/phi$h/DONE" ] || { echo "closure_wide_filter.sh: HELDOUT run $out/generate/phi$h is not finished" >&2; exit 2; }
      others+=("$out/generate/phi$h")
    done
    sub=$dir/without_phi$phi
    mkdir -p "$sub"
    if [ ! -f "$sub/filtered.h5" ]; then
      echo "[closure_heldout] filter ${others[*]} (without $phi)" >&2
      "$build/cgd-filter" "${others[@]}" "${filter_args[@]}" --force --quiet -o "$sub/filtered.h5"
    fi
    [ -f "$sub/model.h5" ] || "$build/cgd-fit" "$sub/filtered.h5" "${fit_args[@]}" --force -o "$sub/model.h5" > "$sub/model.report.txt"
  done
fi
for phi in "${phis[@]}"; do
  ref=$dir/resolved_phi$phi.h5
  [ -f "$ref" ] || "$build/cgd-coarse" --summarise "$out/generate/phi$phi" --from-tref $from_tref --force -o "$ref" > /dev/null
done

say() { echo "[closure_wide] $*" >&2; }
launcher=()
profile_coarse_sets
for phi in "${phis[@]}"; do
  profile_phi_sets "$phi"
  for alpha in "${alphas[@]}"; do
    for seed in "${seeds[@]}"; do
      for g in "${grids[@]}"; do
        coarse_run "$dir/phi${phi}_a${alpha}_g${g}_s$seed" "$phi" "$alpha" "$seed" --model "$dir/perfect_g$g.h5" \
          --set fluid.parcel_correction=false "${phi_sets[@]}"
      done
      model=$(model_for "$phi")
      if [ -f "$model" ]; then
        for r in "${ratios[@]}"; do
          coarse_run "$dir/phi${phi}_a${alpha}_r${r}_s$seed" "$phi" "$alpha" "$seed" --model "$model" \
            --set fluid.parcel_correction=false --set fluid.filter_to_grid_ratio="$r" "${phi_sets[@]}"
        done
      fi
    done
  done
done
/usr/bin/python3 "$repo/tools/closure_wide_table.py" "$dir" | tee "$dir/table.md"
