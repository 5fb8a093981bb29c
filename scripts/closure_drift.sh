#!/usr/bin/env bash
# The drift-velocity closure's held-out validation (issue 28; docs/closure.md "The drift-velocity closure",
# docs/coarse.md): on the half box's 4-cell grid (13.25 d_p), coarse parcel runs with
#   driftheld  the drift table H(phi-bar, s-hat) fitted WITHOUT the run it predicts (cgd-fit --drift-table on the
#              other runs' filtered files): the closure under test;
#   driftown   the drift table of the run itself: its perfect twin (what the form can do at best);
#   tableheld  the phi-bar-only table of the grid fitted without the run (the phi-bar closure held out);
#   tableown   the phi-bar-only table of the run itself: the perfect closure of docs/coarse.md;
#   radl       radl2014, the published model;
# each at alpha = ALPHAS and realisations SEEDS, c_corr off for the tables (the grid's own correction; radl2014 keeps
# the paper's c_corr(alpha)), the
# pipeline's coarse settings (the half profile's COARSE_SET: sampled 40-80 t_ref, and its PHI_SET_<phi>); then the table of the slip
# error against each resolved run (tools/closure_wide_table.py) -> DIR/table.md.
#
# usage: scripts/closure_drift.sh OUT [PHIS=0.02,0.05,0.10] [ALPHAS=3,4,6] [SEEDS=1,2,3] [CLOSURES=...]
#   OUT: a `Makefile.pipeline PROFILE=half` output directory whose OUT/generate/<run>/DONE exist for every phi of
#        PHIS. Every finished resolved run of OUT/generate (phi<phi> and phi<phi>_s<seed>) is filtered and pooled:
#        a held-out table for phi leaves out every run at that phi (all its seeds).
# Results go to OUT/closure_drift (DIR). A coarse run whose summary.h5 exists is not run again (one killed before its
# end is continued from its checkpoint, scripts/coarse_run.sh); a filtered file or
# table that exists is kept (delete it to make it again).
# Environment: BUILD (default build), NICE (default 0), CELLS (default 4), DRIFT_FILTER_ARGS (more cgd-filter
# options, e.g. the slip bins), OWN_DEPOSIT (default true; false: every coarse run's drag leaves the parcel's own
# deposit out of its phi, fluid.drag_own_deposit = false, docs/closure.md; the runs go to DIR/noself, the tables
# and filtered files are shared), TABLE_CELLS (default CELLS: the grid the four tables are fitted on; a coarser one,
# e.g. 3 with CELLS=4, asks the closure for the structures up to that grid's cell too, the wider filter of
# docs/closure.md; its tables and runs go to DIR/t<TABLE_CELLS>, the filtered files hold both grids).
set -euo pipefail
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
out=${1:?usage: closure_drift.sh OUT [PHIS] [ALPHAS] [SEEDS] [CLOSURES]}
IFS=, read -r -a phis <<< "${2:-0.02,0.05,0.10}"
IFS=, read -r -a alphas <<< "${3:-3,4,6}"
IFS=, read -r -a seeds <<< "${4:-1,2,3}"
IFS=, read -r -a closures <<< "${5:-driftheld,driftown,tableheld,tableown,radl}"
build=${BUILD:-$repo/build}
nice_level=${NICE:-0}
cells=${CELLS:-4}
table_cells=${TABLE_CELLS:-$cells}
[[ $table_cells =~ ^[1-9][0-9]*$ ]] || { echo "closure_drift.sh: TABLE_CELLS=$table_cells is not a positive integer" >&2; exit 2; }
read -r -a drift_filter_args <<< "${DRIFT_FILTER_ARGS:-}"
from_tref=20
mk() { make -s -f "$repo/Makefile.pipeline" PROFILE=half "$@"; }
base_scene=$(cd "$repo" && mk print-BASE_SCENE)
box_dp=$(cd "$repo" && mk print-BOX_DP)
dx=$(python3 -c "print($box_dp/$cells)")
dir=$out/closure_drift
own_deposit=${OWN_DEPOSIT:-true}
case $own_deposit in true | false) ;; *) echo "closure_drift.sh: OWN_DEPOSIT=$own_deposit: allowed true, false" >&2; exit 2 ;; esac
# the tables (and the runs that use them) of a table grid other than the run's: DIR/t<TABLE_CELLS>
tables_dir=$dir
[ "$table_cells" = "$cells" ] || tables_dir=$dir/t$table_cells
runs_dir=$tables_dir
[ "$own_deposit" = false ] && runs_dir=$tables_dir/noself
filter_grids=$cells
[ "$table_cells" = "$cells" ] || filter_grids=$cells,$table_cells
mkdir -p "$dir" "$tables_dir" "$runs_dir"
say() { echo "[closure_drift] $*" >&2; }

# every finished resolved run, filtered on its own (so that any pool can be formed from the files)
runs=()
for done_file in "$out"/generate/phi*/DONE; do
  [ -f "$done_file" ] || continue
  runs+=("$(basename "$(dirname "$done_file")")")
done
[ ${#runs[@]} -gt 0 ] || { echo "closure_drift.sh: no finished resolved run in $out/generate" >&2; exit 2; }
for phi in "${phis[@]}"; do
  [ -f "$out/generate/phi$phi/DONE" ] || { echo "closure_drift.sh: $out/generate/phi$phi is not a finished run" >&2; exit 2; }
done
phi_of() { local r=${1#phi}; echo "${r%%_s*}"; }
for r in "${runs[@]}"; do
  filtered=$dir/filtered_$r.h5
  [ "$table_cells" = "$cells" ] || filtered=$tables_dir/filtered_$r.h5
  [ -f "$filtered" ] && continue
  say "filter $r on the grids $filter_grids"
  nice -n "$nice_level" "$build/cgd-filter" "$out/generate/$r" --from-tref $from_tref --grids "$filter_grids" \
    --samples 0 "${drift_filter_args[@]}" --force --quiet -o "$filtered"
done
filtered_of() { if [ "$table_cells" = "$cells" ]; then echo "$dir/filtered_$1.h5"; else echo "$tables_dir/filtered_$1.h5"; fi; }
# the tables: own = the runs at phi; held = every other run
for phi in "${phis[@]}"; do
  own=() held=()
  for r in "${runs[@]}"; do
    if [ "$(phi_of "$r")" = "$phi" ]; then own+=("$(filtered_of "$r")"); else held+=("$(filtered_of "$r")"); fi
  done
  [ ${#held[@]} -gt 0 ] || { echo "closure_drift.sh: no run besides phi = $phi to fit a held-out table on" >&2; exit 2; }
  fit() {  # output, option, files...
    local o=$1 opt=$2
    shift 2
    [ -f "$o" ] && return 0
    "$build/cgd-fit" "$@" "$opt" "$table_cells" --force -o "$o" > "${o%.h5}.report.txt" 2>&1 ||
      { cat "${o%.h5}.report.txt" >&2; exit 1; }
  }
  fit "$tables_dir/driftown_phi$phi.h5" --drift-table "${own[@]}"
  fit "$tables_dir/driftheld_phi$phi.h5" --drift-table "${held[@]}"
  fit "$tables_dir/tableown_phi$phi.h5" --grid-table "${own[@]}"
  fit "$tables_dir/tableheld_phi$phi.h5" --grid-table "${held[@]}"
  ref=$dir/resolved_phi$phi.h5
  [ -f "$ref" ] || "$build/cgd-coarse" --summarise "$out/generate/phi$phi" --from-tref $from_tref --force -o "$ref" > /dev/null
done

source "$repo/scripts/coarse_run.sh"
launcher=()
profile_coarse_sets
for phi in "${phis[@]}"; do
  profile_phi_sets "$phi"
  for alpha in "${alphas[@]}"; do
    for seed in "${seeds[@]}"; do
      for c in "${closures[@]}"; do
        case $c in
          driftheld | driftown)
            args=(--set fluid.drag=drift --set fluid.drag_model="$tables_dir/${c}_phi$phi.h5" --set fluid.parcel_correction=false) ;;
          tableheld | tableown) args=(--model "$tables_dir/${c}_phi$phi.h5" --set fluid.parcel_correction=false) ;;
          radl) args=(--set fluid.drag=radl2014) ;;  # with the paper's c_corr(alpha), as the pipeline runs it
          *) echo "closure_drift.sh: closure $c is not one of driftheld, driftown, tableheld, tableown, radl" >&2; exit 2 ;;
        esac
        coarse_run "$runs_dir/phi${phi}_a${alpha}_${c}_s$seed" "$phi" "$alpha" "$seed" \
          --set fluid.drag_own_deposit="$own_deposit" "${args[@]}" "${phi_sets[@]}"
      done
    done
  done
done
[ "$runs_dir" = "$dir" ] || for f in "$dir"/resolved_phi*.h5; do ln -sf "$f" "$runs_dir/"; done
/usr/bin/python3 "$repo/tools/closure_wide_table.py" "$runs_dir" | tee "$runs_dir/table.md"
