#!/usr/bin/env bash
# The paper's Figure 3 in any box (issue 26; docs/coarse.md): coarse parcel runs on one grid with every closure a
# user can take from this repository beside each other, against the resolved runs of that box.
#
# usage: scripts/figure3_box.sh OUT [PHIS=0.02] [ALPHAS=2,3,4,6,8] [SEEDS=1,2,3] [CLOSURES=micro,radl,halfbox,perfect,model]
#   (CLOSURES may also name modelraw)
#   OUT: a `Makefile.pipeline PROFILE=$PROFILE` output directory with OUT/generate/phi<phi>/DONE for every phi, or
#        with the run's filtered file as OUT/figure3_c<CELLS>/filtered_phi<phi>.h5 (a copy of the shipped
#        data/filtered/<box>_phi<phi>.h5, of this profile's box: checked): the resolved slip is then the filtered
#        file's (cgd-coarse --summarise FILE, over the filter's window); or, without perfect, with the
#        resolved_phi<phi>.h5 an earlier call left there.
# Closures (the run directory's label):
#   micro    the scene's micro law (Beetstra), no correction;
#   radl     radl2014 with the paper's c_corr(alpha), as the pipeline runs it;
#   halfbox  the shipped half-box model (data/models/half_box.h5, with its c_corr(alpha)): a model fitted in
#            another box (53 x 213 x 53 d_p), used here at the same F = L_char/Delta rule;
#   perfect  the grid's own a-priori correction as a table in phi-bar (cgd-fit --grid-table CELLS of the run's own
#            filtered file), c_corr off, as the pipeline's perfect runs;
#   model    OUT/fit/model.h5 when it exists (the model fitted in this box, with the c_corr(alpha) in its file: the
#            parcel fit's, or the paper's k = 0.05 when none was made);
#   modelraw the same model with c_corr off (fluid.parcel_correction = false), as the half-box model is used (its
#            c_corr is 1): the fair comparison of the two boxes' models when this box has no parcel fit;
#   heldout  the phi-bar table of the grid of TABLE_CELLS across fitted on the OTHER runs' filtered files in
#            OUT/figure3_c<CELLS> (cgd-fit --grid-table of every filtered_phi*.h5 there but the run's own), c_corr off:
#            the perfect closure's held-out twin, a closure the run has not seen;
#   driftheld the drift-velocity closure held out: the drift table H(phi-bar, cell slip) of the grid of TABLE_CELLS
#            across fitted on the same other files (cgd-fit --drift-table), fluid.drag = "drift", c_corr off
#            (docs/closure.md "The drift-velocity closure");
#   radl, halfbox, model, modelraw followed by r<R> (e.g. radlr2, modelrawr2): the law's correction at
#            Delta = R cells (fluid.filter_to_grid_ratio = R; docs/closure.md "A filter wider than the cell").
# With TABLE_CELLS (default CELLS) other than CELLS, perfect and heldout take the table of that grid (e.g. CELLS=8
# TABLE_CELLS=4: the correction of the structures up to twice the cell, the recipe of docs/coarse.md on the 8-cell
# grid); their runs are then labelled tableown<T>, tableheld<T> and driftheld<T> (tools/closure_wide_table.py).
# Each on the grid of CELLS cells across (default 4: the paper's Figure 3 grid, 26.5 d_p in its box), sampled
# over WINDOW (default 40-80 t_ref: a coarse parcel grid seeds its clustering from little noise, as the half profile's
# COARSE_SET; alpha = 1 runs, as noisy as the resolved ones, may take the resolved runs' 20-50) with the
# profile's COARSE_SET and PHI_SET_<phi> (the box, gamma* and t* of the resolved runs), then the
# table of the slip error against each resolved run (tools/closure_wide_table.py) -> OUT/figure3_c<CELLS>/table.md.
# A coarse run whose summary.h5 exists is not run again, one killed before its end is continued from its checkpoint
# (scripts/coarse_run.sh); a filtered file or table that exists is kept.
# Environment: PROFILE (default paper), CELLS (default 4), TABLE_CELLS (default CELLS), WINDOW (default 40-80), BUILD
# (default build), NICE (default 0), NP (default 1: ranks of each coarse run).
# Exit status: 0 done (a coarse run that fails is reported and left out of the table); 2 bad arguments.
set -euo pipefail
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
out=${1:?usage: figure3_box.sh OUT [PHIS] [ALPHAS] [SEEDS] [CLOSURES]}
IFS=, read -r -a phis <<< "${2:-0.02}"
IFS=, read -r -a alphas <<< "${3:-2,3,4,6,8}"
IFS=, read -r -a seeds <<< "${4:-1,2,3}"
IFS=, read -r -a closures <<< "${5:-micro,radl,halfbox,perfect,model}"
profile=${PROFILE:-paper}
cells=${CELLS:-4}
table_cells=${TABLE_CELLS:-$cells}
window=${WINDOW:-40-80}
build=${BUILD:-$repo/build}
nice_level=${NICE:-0}
np=${NP:-1}
[[ $cells =~ ^[1-9][0-9]*$ ]] || { echo "figure3_box.sh: CELLS=$cells is not a positive integer" >&2; exit 2; }
[[ $window =~ ^([0-9]+)-([0-9]+)$ ]] && [ "${BASH_REMATCH[1]}" -lt "${BASH_REMATCH[2]}" ] ||
  { echo "figure3_box.sh: WINDOW=$window: expected START-END in t_ref, whole numbers, START < END (e.g. 40-80)" >&2; exit 2; }
window_start=${BASH_REMATCH[1]} window_end=${BASH_REMATCH[2]}
[[ $table_cells =~ ^[1-9][0-9]*$ ]] ||
  { echo "figure3_box.sh: TABLE_CELLS=$table_cells is not a positive integer" >&2; exit 2; }
[[ $np =~ ^[1-9][0-9]*$ ]] || { echo "figure3_box.sh: NP=$np is not a positive integer" >&2; exit 2; }
launcher=()
[ "$np" -gt 1 ] && launcher=(mpirun --allow-run-as-root --oversubscribe -np "$np")
mk() { make -s -f "$repo/Makefile.pipeline" PROFILE="$profile" "$@"; }
base_scene=$(cd "$repo" && mk print-BASE_SCENE)
box_dp=$(cd "$repo" && mk print-BOX_DP)
from_tref=$(cd "$repo" && mk print-FROM_TREF)
source "$repo/scripts/coarse_run.sh"
profile_words FILTER_ARGS_LINE filter_args
dx=$(python3 -c "print($box_dp/$cells)")
dir=$out/figure3_c$cells
mkdir -p "$dir"
say() { echo "[figure3] $*" >&2; }
# a law at Delta = R cells: its name, r, R (radlr2)
at_ratio='^([a-z]+)r([0-9]+(\.[0-9]+)?)$'
# the tables' closures need the runs' filtered files (their own for perfect, the others' for heldout)
needs_filtered=0
for c in "${closures[@]}"; do
  case $c in
    perfect | heldout | driftheld) needs_filtered=1 ;;
    micro | radl | halfbox | model | modelraw) ;;
    radlr* | halfboxr* | modelr* | modelrawr*) [[ $c =~ $at_ratio ]] ||
      { echo "figure3_box.sh: closure $c: a law's name and r<R>, R a number (e.g. radlr2)" >&2; exit 2; } ;;
    *) echo "figure3_box.sh: closure $c is not one of micro, radl, halfbox, perfect, heldout, driftheld, model, modelraw" \
      "(or radl, halfbox, model, modelraw followed by r<R>)" >&2; exit 2 ;;
  esac
done
# the resolved run is read only to make its summary (resolved_phi<phi>.h5) and, for perfect, its filtered file
# (filtered_phi<phi>.h5) in OUT/figure3_c<CELLS>: its filtered file alone (the shipped data/filtered/<box>_phi<phi>.h5,
# copied there) stands in for a run directory that is gone
for phi in "${phis[@]}"; do
  [ -f "$out/generate/phi$phi/DONE" ] && continue
  if [ -f "$dir/filtered_phi$phi.h5" ]; then
    # a copied file must be of this profile's box (its width in d_p) and solids fraction
    /usr/bin/python3 - "$dir/filtered_phi$phi.h5" "$box_dp" "$phi" <<'PY' || exit 2
import sys, h5py
path, box_dp, phi = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
p = h5py.File(path, "r")["params"].attrs
width = p["box_size_m"][0] / p["diameter_m"]
if abs(width / box_dp - 1) > 0.01 or abs(p["solids_fraction"] - phi) > 1e-9:
    sys.exit(f"figure3_box.sh: {path} is a run of a {width:.0f} d_p box at <phi> = {p['solids_fraction']:g}, "
             f"not this profile's {box_dp:.0f} d_p at {phi:g}")
PY
    continue
  fi
  [ -f "$dir/resolved_phi$phi.h5" ] && [ $needs_filtered = 0 ] && continue
  echo "figure3_box.sh: $out/generate/phi$phi is not a finished run (and $dir has not its filtered_phi$phi.h5," \
    "from an earlier call or copied from data/filtered/)" >&2
  exit 2
done

# per phi: the resolved reference, the run's filtered file (the profile's filter settings) and the perfect table
# from it; then the held-out tables from the other runs' files
# a table of another grid than the runs' is named for it: files KIND_phi<phi>_t<T>.h5, runs tableown<T>, tableheld<T>,
# driftheld<T>
other_grid=
[ "$table_cells" = "$cells" ] || other_grid=$table_cells
table_of() {  # KIND PHI -> the table file of perfect (own), heldout or driftheld
  echo "$dir/$1_phi$2${other_grid:+_t$other_grid}.h5"
}
grid_table() {  # OUT OPTION FILTERED... : cgd-fit OPTION (--grid-table or --drift-table) TABLE_CELLS, kept when it exists
  local table=$1 option=$2
  shift 2
  [ -f "$table" ] || "$build/cgd-fit" "$@" "$option" "$table_cells" --force -o "$table" > "${table%.h5}.report.txt" 2>&1 ||
    { cat "${table%.h5}.report.txt" >&2; exit 1; }
}
for phi in "${phis[@]}"; do
  ref=$dir/resolved_phi$phi.h5
  if [ ! -f "$ref" ]; then
    if [ -f "$out/generate/phi$phi/DONE" ]; then
      "$build/cgd-coarse" --summarise "$out/generate/phi$phi" --from-tref "$from_tref" --force -o "$ref" > /dev/null
    else  # the filtered file's window is the filter's: from_tref to the end, as above
      "$build/cgd-coarse" --summarise "$dir/filtered_phi$phi.h5" --force -o "$ref" > /dev/null
    fi
  fi
  [ $needs_filtered = 1 ] || continue
  filtered=$dir/filtered_phi$phi.h5
  if [ ! -f "$filtered" ]; then
    say "filter phi = $phi"
    nice -n "$nice_level" "${launcher[@]}" "$build/cgd-filter" "$out/generate/phi$phi" "${filter_args[@]}" --force --quiet \
      -o "$filtered"
  fi
  if [[ " ${closures[*]} " == *" perfect "* ]]; then grid_table "$(table_of perfect "$phi")" --grid-table "$filtered"; fi
done
for kind in heldout driftheld; do
  [[ " ${closures[*]} " == *" $kind "* ]] || continue
  option=--grid-table
  [ $kind = driftheld ] && option=--drift-table
  for phi in "${phis[@]}"; do
    others=()
    for f in "$dir"/filtered_phi*.h5; do [ "$f" = "$dir/filtered_phi$phi.h5" ] || others+=("$f"); done
    [ ${#others[@]} -gt 0 ] || { echo "figure3_box.sh: $kind at $phi: no other run's filtered file in $dir" >&2; exit 2; }
    grid_table "$(table_of $kind "$phi")" $option "${others[@]}"
  done
done

profile_coarse_sets
coarse_sets+=(--set run.end_time_tref="$window_end" --set run.sampling_start_tref="$window_start")
for phi in "${phis[@]}"; do
  profile_phi_sets "$phi"
  for alpha in "${alphas[@]}"; do
    for seed in "${seeds[@]}"; do
      for c in "${closures[@]}"; do
        law=$c label=$c ratio=()
        if [[ $c =~ $at_ratio ]]; then
          law=${BASH_REMATCH[1]} ratio=(--set fluid.filter_to_grid_ratio="${BASH_REMATCH[2]}")
        fi
        case $law in
          micro) args=() ;;
          radl) args=(--set fluid.drag=radl2014) ;;
          halfbox) args=(--model "$repo/data/models/half_box.h5") ;;
          perfect)
            args=(--model "$(table_of perfect "$phi")" --set fluid.parcel_correction=false)
            [ -z "$other_grid" ] || label=tableown$other_grid ;;
          heldout)
            args=(--model "$(table_of heldout "$phi")" --set fluid.parcel_correction=false)
            label=tableheld$other_grid ;;
          driftheld)
            args=(--set fluid.drag=drift --set fluid.drag_model="$(table_of driftheld "$phi")" --set fluid.parcel_correction=false)
            label=driftheld$other_grid ;;
          model | modelraw)
            [ -f "$out/fit/model.h5" ] || { say "no $out/fit/model.h5: the $c runs are left out"; continue; }
            args=(--model "$out/fit/model.h5")
            if [ "$law" = modelraw ]; then args+=(--set fluid.parcel_correction=false); fi ;;
        esac
        coarse_run "$dir/phi${phi}_a${alpha}_${label}_s$seed" "$phi" "$alpha" "$seed" "${args[@]}" "${ratio[@]}" \
          "${phi_sets[@]}"
      done
    done
  done
done
/usr/bin/python3 "$repo/tools/closure_wide_table.py" "$dir" | tee "$dir/table.md"
