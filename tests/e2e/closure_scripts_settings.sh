#!/usr/bin/env bash
# e2e: the closure experiments' scripts run each coarse run with its profile's settings, as the pipeline does
# (scripts/coarse_run.sh: profile_coarse_sets, profile_phi_sets): the half profile's COARSE_SET (its 53 x 213 x 53 d_p
# box and gamma* = 2e-3) and, after it, the solids fraction's PHI_SET_<phi> (0.30: gamma* = 1e-3, t* = 0.05), on cells
# of BOX_DP/CELLS d_p; the paper profile's runs (its box in the base scene, no COARSE_SET) as before.
# scripts/figure3_box.sh ran a half-box call in the demo's 30 d_p box without them, and closure_wide_filter.sh ran a
# dense <phi> at the dilute runs' gamma*. Stub binaries record each command line (nothing is simulated); the resolved
# runs are stood in for by filtered files carrying only the params figure3_box.sh checks (the box width in d_p and
# <phi>), or by empty run directories with DONE.
# Environment (set by CTest): CGD_SOURCE_DIR.
source "$(dirname "$0")/lib/prologue.sh"
mkdir -p "$tmp/bin"
# stub NAME BODY: a stub binary $tmp/bin/NAME running BODY with $out its -o argument
stub() {
  printf '#!/usr/bin/env bash\nout=; prev=\nfor a in "$@"; do [ "$prev" = -o ] && out=$a; prev=$a; done\n%s\n' "$2" \
    > "$tmp/bin/$1"
  chmod +x "$tmp/bin/$1"
}
# cgd-coarse: --summarise writes its -o file; a coarse run records its arguments in RUN.args and fails (reported and
# left out of the table by the scripts); --restart records them in RUN.restart.args and writes RUN/summary.h5 (fails
# when RUN/restart_fails exists); cgd-fit and cgd-filter write their -o file
stub cgd-coarse '[ "$1" = --summarise ] && { touch "$out"; exit 0; }
[ "$1" = --restart ] && { echo "$*" > "$out.restart.args"; [ -f "$out/restart_fails" ] && exit 1; touch "$out/summary.h5"; exit 0; }
echo "$*" > "$out.args"
exit 1'
stub cgd-fit 'echo "$*" > "$out.args"; touch "$out"'
stub cgd-filter 'touch "$out"'

# a filtered file as the script reads it: params/box_size_m, diameter_m, solids_fraction
fake_filtered() {  # PATH BOX_DP PHI
  mkdir -p "$(dirname "$1")"
  /usr/bin/python3 - "$@" <<'PY'
import sys, h5py
path, box_dp, phi = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
with h5py.File(path, "w") as f:
    p = f.create_group("params")
    p.attrs["diameter_m"] = 7.5e-05
    p.attrs["box_size_m"] = [box_dp * 7.5e-05, 4 * box_dp * 7.5e-05, box_dp * 7.5e-05]
    p.attrs["solids_fraction"] = phi
PY
}
args_of() { cat "$1.args" 2>/dev/null; }
# the value of the last --set KEY=... on a command line (the one cgd-coarse takes)
last_set() { grep -o -- "--set $2=[^ ]*" <<<"$1" | tail -n 1 | cut -d= -f2-; }
# a command line at the half profile's PHI_SET_0.30 (gamma* = 1e-3, t* = 0.05), given after COARSE_SET's gamma*
at_dense_settings() { [ "$(last_set "$1" contact.gamma_star)" = 1e-3 ] && [ "$(last_set "$1" contact.t_star)" = 0.05 ]; }

# ---- the half profile: dilute 0.05 and dense 0.30 ----
out=$tmp/half
fake_filtered "$out/figure3_c4/filtered_phi0.05.h5" 53 0.05
fake_filtered "$out/figure3_c4/filtered_phi0.30.h5" 53 0.30
PROFILE=half BUILD=$tmp/bin bash scripts/figure3_box.sh "$out" 0.05,0.30 3 1 micro,perfect > "$tmp/half.log" 2>&1
dilute=$(args_of "$out/figure3_c4/phi0.05_a3_micro_s1")
dense=$(args_of "$out/figure3_c4/phi0.30_a3_perfect_s1")
[ -n "$dilute" ] && [ -n "$dense" ] || { fail "half: no coarse command recorded"; cat "$tmp/half.log"; }
before=$failures
for c in "$dilute" "$dense"; do
  [ "$(last_set "$c" domain.size_dp)" = "[53,213,53]" ] || fail "half: the coarse run is not in the half box: $c"
  [ "$(last_set "$c" fluid.dx_over_dp)" = 13.25 ] || fail "half: cells of $(last_set "$c" fluid.dx_over_dp) d_p, not 53/4"
  [ "$(last_set "$c" run.end_time_tref)" = 80 ] && [ "$(last_set "$c" run.sampling_start_tref)" = 40 ] ||
    fail "half: not sampled 40-80 t_ref: $c"
done
[ $failures -eq $before ] && ok "half: the coarse runs in the 53 x 213 x 53 d_p box on 13.25 d_p cells, sampled 40-80 t_ref (COARSE_SET)"
[ "$(last_set "$dilute" contact.gamma_star)" = 2e-3 ] && [ -z "$(last_set "$dilute" contact.t_star)" ] &&
  ok "half: 0.05 at the dilute runs' gamma* = 2e-3 and the scene's t*" || fail "half: 0.05's contact settings: $dilute"
at_dense_settings "$dense" &&
  ok "half: 0.30 at its PHI_SET (gamma* = 1e-3, t* = 0.05), after COARSE_SET" || fail "half: 0.30's contact settings: $dense"
grep -q -- "--set particles.solids_fraction=0.30 " <<<"$dense" && grep -q -- "--model $out/figure3_c4/perfect_phi0.30.h5" <<<"$dense" &&
  ok "half: the perfect run at 0.30 with its own grid table" || fail "half: the perfect run's model: $dense"

# ---- the 8-cell grid with the 4-cell grid's tables (TABLE_CELLS), held out, and laws at Delta = 2 cells ----
out=$tmp/wide8
for phi in 0.05 0.10 0.30; do fake_filtered "$out/figure3_c8/filtered_phi$phi.h5" 53 "$phi"; done
mkdir -p "$out/fit" && touch "$out/fit/model.h5"
PROFILE=half CELLS=8 TABLE_CELLS=4 BUILD=$tmp/bin bash scripts/figure3_box.sh "$out" 0.30 3 1 heldout,driftheld,perfect,radlr2,modelrawr2 \
  > "$tmp/wide8.log" 2>&1
d=$out/figure3_c8
held=$(args_of "$d/phi0.30_a3_tableheld4_s1") own=$(args_of "$d/phi0.30_a3_tableown4_s1")
radl2=$(args_of "$d/phi0.30_a3_radlr2_s1") model2=$(args_of "$d/phi0.30_a3_modelrawr2_s1")
drift=$(args_of "$d/phi0.30_a3_driftheld4_s1")
fit_held=$(cat "$d/heldout_phi0.30_t4.h5.args" 2>/dev/null) fit_drift=$(cat "$d/driftheld_phi0.30_t4.h5.args" 2>/dev/null)
[ -n "$fit_held" ] && grep -q -- "--grid-table 4" <<<"$fit_held" && grep -q "filtered_phi0.05.h5" <<<"$fit_held" &&
  grep -q "filtered_phi0.10.h5" <<<"$fit_held" && ! grep -q "filtered_phi0.30.h5" <<<"$fit_held" &&
  ok "heldout at 0.30: the 4-cell grid's table of the other runs' files (0.05, 0.10), not its own" ||
  { fail "heldout table: ${fit_held:-not made}"; cat "$tmp/wide8.log"; }
[ "${fit_drift%% --*}" = "${fit_held%% --*}" ] && grep -q -- "--drift-table 4" <<<"$fit_drift" &&
  [ "$(last_set "$drift" fluid.drag)" = drift ] && [ "$(last_set "$drift" fluid.drag_model)" = "$d/driftheld_phi0.30_t4.h5" ] &&
  [ "$(last_set "$drift" fluid.parcel_correction)" = false ] && at_dense_settings "$drift" &&
  ok "driftheld at 0.30: the 4-cell drift table of the same other files, fluid.drag = drift (driftheld4)" ||
  fail "driftheld: ${fit_drift:-no table} / ${drift:-no run}"
grep -q -- "--model $d/heldout_phi0.30_t4.h5 --set fluid.parcel_correction=false" <<<"$held" &&
  grep -q -- "--model $d/perfect_phi0.30_t4.h5 --set fluid.parcel_correction=false" <<<"$own" &&
  grep -q -- "--grid-table 4" "$d/perfect_phi0.30_t4.h5.args" &&
  ok "the tables' runs labelled tableheld4 and tableown4, c_corr off" || fail "table runs: $held / $own"
[ "$(last_set "$radl2" fluid.drag)" = radl2014 ] && [ "$(last_set "$radl2" fluid.filter_to_grid_ratio)" = 2 ] &&
  grep -q -- "--model $out/fit/model.h5 --set fluid.parcel_correction=false" <<<"$model2" &&
  [ "$(last_set "$model2" fluid.filter_to_grid_ratio)" = 2 ] &&
  ok "radlr2 and modelrawr2: the laws at fluid.filter_to_grid_ratio = 2" || fail "r2 runs: $radl2 / $model2"
before=$failures
for c in "$held" "$own" "$radl2" "$model2"; do
  [ "$(last_set "$c" fluid.dx_over_dp)" = 6.625 ] && at_dense_settings "$c" || fail "8-cell run: $c"
done
[ $failures -eq $before ] && ok "every 8-cell run on 6.625 d_p cells at 0.30's PHI_SET"
PROFILE=half CELLS=8 BUILD=$tmp/bin bash scripts/figure3_box.sh "$out" 0.30 3 1 radlrx > "$tmp/bad.log" 2>&1
status=$?
[ $status -eq 2 ] && grep -q "closure radlrx" "$tmp/bad.log" && ok "closure radlrx: exit 2" || fail "radlrx: exit $status"
# WINDOW: the sampling window of alpha = 1 runs (the resolved runs' 20-50 t_ref); a window backwards is refused
PROFILE=half CELLS=8 WINDOW=20-50 BUILD=$tmp/bin bash scripts/figure3_box.sh "$out" 0.30 1 1 micro > "$tmp/w.log" 2>&1
c=$(args_of "$d/phi0.30_a1_micro_s1")
[ "$(last_set "$c" run.end_time_tref)" = 50 ] && [ "$(last_set "$c" run.sampling_start_tref)" = 20 ] &&
  ok "WINDOW=20-50: sampled 20-50 t_ref" || fail "WINDOW=20-50: $c"
PROFILE=half CELLS=8 WINDOW=50-20 BUILD=$tmp/bin bash scripts/figure3_box.sh "$out" 0.30 1 1 micro > "$tmp/w.log" 2>&1
status=$?
[ $status -eq 2 ] && grep -q "WINDOW=50-20" "$tmp/w.log" && ok "WINDOW=50-20: exit 2" || fail "WINDOW=50-20: exit $status"

# ---- the paper profile: its box is its base scene's; no COARSE_SET or PHI_SET ----
out=$tmp/paper
fake_filtered "$out/figure3_c4/filtered_phi0.05.h5" 106 0.05
PROFILE=paper BUILD=$tmp/bin bash scripts/figure3_box.sh "$out" 0.05 6 2 radl > "$tmp/paper.log" 2>&1
paper=$(args_of "$out/figure3_c4/phi0.05_a6_radl_s2")
[ -n "$paper" ] && [ -z "$(last_set "$paper" domain.size_dp)" ] && [ -z "$(last_set "$paper" contact.gamma_star)" ] &&
  [ "$(last_set "$paper" fluid.dx_over_dp)" = 26.5 ] && [ "$(last_set "$paper" run.sampling_start_tref)" = 40 ] &&
  [ "$(last_set "$paper" fluid.drag)" = radl2014 ] && grep -q "data/scenes/table1_phi005.toml" <<<"$paper" &&
  ok "paper: the base scene's box, 26.5 d_p cells, 40-80 t_ref, radl2014" || { fail "paper: $paper"; cat "$tmp/paper.log"; }

# ---- a copied filtered file of another box is refused (exit 2) ----
out=$tmp/wrongbox
fake_filtered "$out/figure3_c4/filtered_phi0.05.h5" 106 0.05
PROFILE=half BUILD=$tmp/bin bash scripts/figure3_box.sh "$out" 0.05 3 1 micro > "$tmp/wrong.log" 2>&1
status=$?
[ $status -eq 2 ] && grep -q "106 d_p box" "$tmp/wrong.log" && [ ! -e "$out/figure3_c4/phi0.05_a3_micro_s1.args" ] &&
  ok "a paper-box filtered file in a half-box call: exit 2, nothing run" || fail "wrong box: exit $status, $(cat "$tmp/wrong.log")"

# ---- a killed run: continued from its checkpoint; a partial run without one, or whose restart fails, started again ----
out=$tmp/killed
fake_filtered "$out/figure3_c4/filtered_phi0.05.h5" 53 0.05
d=$out/figure3_c4
mkdir -p "$d/phi0.05_a3_micro_s1" "$d/phi0.05_a3_micro_s2" "$d/phi0.05_a3_micro_s3"
touch "$d/phi0.05_a3_micro_s1/checkpoint.h5" "$d/phi0.05_a3_micro_s2/partial" "$d/phi0.05_a3_micro_s3/checkpoint.h5" \
  "$d/phi0.05_a3_micro_s3/restart_fails"
PROFILE=half BUILD=$tmp/bin bash scripts/figure3_box.sh "$out" 0.05 3 1,2,3 micro > "$tmp/killed.log" 2>&1
r1=$(cat "$d/phi0.05_a3_micro_s1.restart.args" 2>/dev/null)
[ "$r1" = "--restart --quiet -o $d/phi0.05_a3_micro_s1" ] && [ -f "$d/phi0.05_a3_micro_s1/summary.h5" ] &&
  [ ! -e "$d/phi0.05_a3_micro_s1.args" ] &&
  ok "a run with a checkpoint and no summary: continued (cgd-coarse --restart -o RUN), not started again" ||
  fail "killed run with a checkpoint: restart args '${r1}', $(cat "$tmp/killed.log")"
[ ! -e "$d/phi0.05_a3_micro_s2.restart.args" ] && [ -n "$(args_of "$d/phi0.05_a3_micro_s2")" ] &&
  [ ! -e "$d/phi0.05_a3_micro_s2/partial" ] &&
  ok "a partial run without a checkpoint: removed and started again" || fail "partial run without a checkpoint"
[ -e "$d/phi0.05_a3_micro_s3.restart.args" ] && [ -n "$(args_of "$d/phi0.05_a3_micro_s3")" ] &&
  grep -q "phi0.05_a3_micro_s3: the restart failed" "$tmp/killed.log" && [ -f "$d/phi0.05_a3_micro_s3.restart.log" ] &&
  ok "a run whose restart fails: reported and started again, the restart's log kept" || fail "failed restart: $(cat "$tmp/killed.log")"

# ---- closure_wide_filter.sh and closure_drift.sh at a dense <phi>: PHI_SET_0.30 after COARSE_SET ----
out=$tmp/wide
mkdir -p "$out/generate/phi0.05" "$out/generate/phi0.30"
mkdir -p "$out/fit"
touch "$out/generate/phi0.05/DONE" "$out/generate/phi0.30/DONE" "$out/fit/model.h5"
BUILD=$tmp/bin bash scripts/closure_wide_filter.sh "$out" 0.30 3 1 4 1 > "$tmp/wide.log" 2>&1
BUILD=$tmp/bin bash scripts/closure_drift.sh "$out" 0.30 3 1 radl > "$tmp/drift.log" 2>&1
# the perfect table's and the model's runs of closure_wide_filter.sh, the published law's of closure_drift.sh
for run in closure_wide/phi0.30_a3_g4_s1 closure_wide/phi0.30_a3_r1_s1 closure_drift/phi0.30_a3_radl_s1; do
  c=$(args_of "$out/$run")
  [ "$(last_set "$c" domain.size_dp)" = "[53,213,53]" ] && [ "$(last_set "$c" fluid.dx_over_dp)" = 13.25 ] &&
    at_dense_settings "$c" &&
    ok "$run: the half box on 13.25 d_p cells at 0.30's PHI_SET (gamma* = 1e-3, t* = 0.05)" ||
    { fail "$run: ${c:-no coarse command recorded}"; cat "$tmp/wide.log" "$tmp/drift.log"; }
done
exit $((failures > 0))
