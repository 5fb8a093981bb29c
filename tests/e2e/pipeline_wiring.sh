#!/usr/bin/env bash
# e2e: the wiring of Makefile.pipeline, read with `make -n` (nothing is run): realisations (SEEDS, ALPHA1_SEEDS ->
# ..._s<seed> dirs with particles.seed), the extra resolved realisation (EXTRA_RESOLVED=0.05_s2: its run dir, params
# string and --set particles.seed=2, pooled by the filter), FILTER_GRIDS -> cgd-filter --grids, FIT_ARGS with
# --operator grid, the laws (radl2014: --set fluid.drag=radl2014; perfect: cgd-fit --grid-table, --model
# perfect_c<cells>.h5, c_corr off for alpha > 1; drift: cgd-fit --drift-table, fluid.drag = drift), the model alpha > 1 runs' reuse of their modelraw twins, the
# resolved summaries (cgd-coarse --summarise) feeding the study; and the refusals (make errors) of an unknown drag
# label, an EXTRA_RESOLVED entry outside PHIS, a perfect closure on a grid the filter did not evaluate, a bad seed;
# a profile's own EXTRA_RESOLVED / ALPHA1_PHIS entries outside a smaller PHIS left out (PARCEL_FIT off without alpha = 1).
# Environment (set by CTest): CGD_SOURCE_DIR.
source "$(dirname "$0")/lib/prologue.sh"
mkdir -p "$tmp/bin"
for t in cgd-generate cgd-filter cgd-fit cgd-coarse; do touch "$tmp/bin/$t"; done
mk() { make -f Makefile.pipeline -n BUILD="$tmp/bin" OUT="$tmp/out" "$@" 2>&1; }

# ---- the half profile's defaults ----
n=$(mk PROFILE=half all)
cmd_s2='bash scripts/pipeline_run.sh "generate phi=0.05 seed=2" '"$tmp"'/out/generate/phi0.05_s2 "BASE_SCENE=data/scenes/pipeline_demo.toml GENERATE_SET=domain.size_dp=[53,213,53] contact.gamma_star=2e-3 run.end_time_tref=50 phi=0.05 seed=2" --  '"$tmp"'/bin/cgd-generate data/scenes/pipeline_demo.toml --set particles.solids_fraction=0.05 --set particles.seed=2 --set domain.size_dp=[53,213,53] --set contact.gamma_star=2e-3 --set run.end_time_tref=50'
grep -qxF -- "$cmd_s2" <<<"$n" && ok "half: the second resolved realisation at 0.05 (run dir, params, --set particles.seed=2)" ||
  fail "half: no or another command for generate/phi0.05_s2"
grep -q -- "cgd-filter $tmp/out/generate/phi0.02 $tmp/out/generate/phi0.05 $tmp/out/generate/phi0.10 $tmp/out/generate/phi0.05_s2 --from-tref 20 " <<<"$n" &&
  grep -q -- "--grids 12,8,6,5,4,3 --force" <<<"$n" && ok "half: the filter pools both seeds at 0.05, --from-tref 20, --grids 12,8,6,5,4,3" ||
  fail "half: filter command"
grep -q -- "cgd-fit $tmp/out/filter/filtered.h5 --width-exponent fit --operator grid --force -o $tmp/out/fit/model.h5" <<<"$n" &&
  ok "half: the fit on the grid operator" || fail "half: fit command"
for c in 8 4; do
  grep -q -- "cgd-fit $tmp/out/filter/filtered.h5 --grid-table $c --force -o $tmp/out/fit/perfect_c$c.h5" <<<"$n" || fail "half: no perfect_c$c.h5"
done
ok "half: one perfect-closure table per coarse grid (cgd-fit --grid-table 8, 4)"
# realisations: alpha > 1 at seeds 1, 2, 3; alpha = 1 at seed 1 only
for s in 1 2 3; do grep -q "coarse/phi0.10_c4_a3_micro_s$s .*--set particles.seed=$s " <<<"$n" || fail "half: phi0.10_c4_a3_micro_s$s"; done
grep -q "coarse/phi0.05_c8_a1_model_s1 " <<<"$n" && ! grep -q "coarse/phi0.05_c8_a1_model_s2" <<<"$n" &&
  ok "half: alpha > 1 runs at SEEDS=1,2,3, alpha = 1 at ALPHA1_SEEDS=1" || fail "half: seeds of the alpha = 1 runs"
! grep -q "phi0.10_c[0-9]*_a1_" <<<"$n" && ok "half: no alpha = 1 run at 0.10 (ALPHA1_PHIS)" || fail "half: an alpha = 1 run at 0.10"
grep -q "phi0.05_c4_a2_radl2014_s1 .*--set particles.parcel_size=2  --set fluid.drag=radl2014 " <<<"$n" &&
  ok "half: radl2014 runs with --set fluid.drag=radl2014" || fail "half: radl2014 command"
grep -q "phi0.05_c4_a2_perfect_s2 .*--model $tmp/out/fit/perfect_c4.h5  --set fluid.parcel_correction=false" <<<"$n" &&
  grep -q "phi0.05_c8_a1_perfect_s1 .*--model $tmp/out/fit/perfect_c8.h5 " <<<"$n" &&
  ok "half: perfect runs with their grid's table (c_corr off for alpha > 1)" || fail "half: perfect command"
nd=$(mk PROFILE=half COARSE_DRAGS=drift PARCEL_FIT=0 coarse)
grep -q -- "cgd-fit $tmp/out/filter/filtered.h5 --drift-table 4 --force -o $tmp/out/fit/drift_c4.h5" <<<"$nd" &&
  grep -q "phi0.05_c4_a2_drift_s2 .*--set fluid.drag=drift --set fluid.drag_model=$tmp/out/fit/drift_c4.h5 " <<<"$nd" &&
  ! grep -q -- "--model $tmp/out/fit/drift_c4.h5" <<<"$nd" &&
  ok "half: drift runs with their grid's drift table as fluid.drag_model (cgd-fit --drift-table)" || fail "half: drift command"
nw=$(mk PROFILE=half COARSE_DRAGS=wide COARSE_CELLS=8 PARCEL_FIT=0 ALPHA1_PHIS= coarse)
grep -q -- "cgd-fit $tmp/out/filter/filtered.h5 --grid-table 4 --force -o $tmp/out/fit/perfect_c4.h5" <<<"$nw" &&
  grep -q "phi0.05_c8_a3_wide_s2 .*--set fluid.dx_over_dp=6.625 .*--model $tmp/out/fit/perfect_c4.h5  --set fluid.parcel_correction=false" <<<"$nw" &&
  ! grep -q "perfect_c8.h5" <<<"$nw" &&
  ok "half: wide runs on the 8-cell grid with the 4-cell grid's table, c_corr off" || fail "half: wide command"
nw=$(mk PROFILE=half COARSE_DRAGS=wide COARSE_CELLS=8,4 PARCEL_FIT=0 coarse)
grep -q "COARSE_DRAGS has wide: .*FILTER_GRIDS=12,8,6,5,4,3 lacks 2 (for 4)" <<<"$nw" &&
  ok "half: wide on the 4-cell grid refused: the filter has no 2-cell grid" || fail "half: wide without its grid: $nw"
nw=$(mk PROFILE=half COARSE_DRAGS=wide COARSE_CELLS=5 PARCEL_FIT=0 coarse)
grep -q "COARSE_DRAGS has wide: .*has the odd 5" <<<"$nw" && ok "half: wide on an odd grid refused" || fail "half: wide on an odd grid: $nw"
grep -q "pipeline_reuse.py --identity $tmp/out/fit/model_parcels.h5; then .*--link $tmp/out/coarse/phi0.05_c4_a3_modelraw_s3 $tmp/out/coarse/phi0.05_c4_a3_model_s3 " <<<"$n" &&
  ok "half: model alpha > 1 runs reuse their modelraw twins when c_corr = 1" || fail "half: no reuse of the modelraw twin"
grep -q "coarse/phi0.10_c4_a3_model_s1 .*--model $tmp/out/fit/model_parcels.h5" <<<"$n" &&
  ! grep -q "phi0.10_c4_a3_modelraw" <<<"$n" && ok "half: model runs at 0.10 (no modelraw twin) are run" || fail "half: model at 0.10"
grep -q -- "cgd-coarse --summarise $tmp/out/generate/phi0.05_s2 --from-tref 20 --force -o $tmp/out/study/resolved/phi0.05_s2.h5" <<<"$n" &&
  grep -q -- "--resolved $tmp/out/study/resolved/phi0.02.h5 $tmp/out/study/resolved/phi0.05.h5 $tmp/out/study/resolved/phi0.10.h5 $tmp/out/study/resolved/phi0.05_s2.h5 " <<<"$n" &&
  ok "half: every resolved run summarised over 20 t_ref to its end; the study gets all four" || fail "half: resolved summaries"
# the coarse runs at 0.05 are compared with the seed-1 run by cgd-coarse; the study pools both
grep -q "phi0.05_c4_a2_micro_s1 .*--reference $tmp/out/generate/phi0.05 " <<<"$n" && ok "half: cgd-coarse --reference the seed-1 run" ||
  fail "half: coarse --reference"

# ---- PHI_SET_<phi>: the half profile's dense runs at gamma* = 1e-3, its dilute runs' parameters untouched ----
n=$(mk PROFILE=half PHIS=0.05,0.20 EXTRA_RESOLVED= ALPHA1_PHIS=0.05 all)
base='BASE_SCENE=data/scenes/pipeline_demo.toml GENERATE_SET=domain.size_dp=[53,213,53] contact.gamma_star=2e-3 run.end_time_tref=50'
grep -qF -- "\"$base phi=0.05\" --" <<<"$n" && grep -qF -- "\"$base phi=0.20 PHI_SET=contact.gamma_star=1e-3\" --" <<<"$n" &&
  grep -q -- "--set particles.solids_fraction=0.20 .*--set contact.gamma_star=2e-3 --set run.end_time_tref=50 --set contact.gamma_star=1e-3$" <<<"$n" &&
  ! grep -q -- "--set particles.solids_fraction=0.05 .*gamma_star=1e-3" <<<"$n" &&
  ok "half: PHI_SET_0.20 sets gamma* = 1e-3 last, in the 0.20 run's params only (the 0.05 run's are as before)" ||
  fail "half: PHI_SET_0.20 of the resolved runs"
grep -q "coarse/phi0.20_c4_a3_micro_s1 .*--set contact.gamma_star=1e-3$" <<<"$n" && ! grep -q "coarse/phi0.05_c4_a3_micro_s1 .*gamma_star=1e-3" <<<"$n" &&
  ok "half: PHI_SET_0.20 reaches the coarse runs at 0.20 only" || fail "half: PHI_SET_0.20 of the coarse runs"
n=$(mk PROFILE=half PHIS=0.05,0.20 EXTRA_RESOLVED= ALPHA1_PHIS=0.05 PHI_SET_0.20= generate)
! grep -q "gamma_star=1e-3" <<<"$n" && ok "half: PHI_SET_0.20= (empty) drops it" || fail "half: an empty PHI_SET_0.20 still sets"

# ---- a profile's defaults follow PHIS: one dense half-box run needs no other override ----
n=$(mk PROFILE=half PHIS=0.30 all); s=$?
[ $s -eq 0 ] && grep -q "the profile's EXTRA_RESOLVED=0.05_s2: 0.05_s2 left out" <<<"$n" &&
  grep -q "the profile's ALPHA1_PHIS=0.02,0.05: 0.02 0.05 left out" <<<"$n" && grep -q "PARCEL_FIT=0" <<<"$n" &&
  grep -q -- "cgd-filter $tmp/out/generate/phi0.30  --from-tref 20 " <<<"$n" && ! grep -q "_a1_\|modelraw\|phi0.05" <<<"$n" &&
  ok "half PHIS=0.30: the profile's 0.05_s2 and alpha = 1 solids fractions left out with a note, no parcel fit" ||
  fail "half PHIS=0.30: status $s"
e=$(mk PROFILE=half PHIS=0.30 ALPHA1_PHIS=0.05 all); s=$?
[ $s -ne 0 ] && grep -q "ALPHA1_PHIS=0.05: every entry must be one of PHIS=0.30" <<<"$e" &&
  ok "half PHIS=0.30: an ALPHA1_PHIS given outside PHIS is still refused" || fail "half PHIS=0.30 ALPHA1_PHIS=0.05: $s"
e=$(mk PROFILE=half PHIS=0.30 EXTRA_RESOLVED=0.05_s2 all); s=$?
[ $s -ne 0 ] && grep -q "EXTRA_RESOLVED entry '0.05_s2'" <<<"$e" &&
  ok "half PHIS=0.30: an EXTRA_RESOLVED given outside PHIS is still refused" || fail "half PHIS=0.30 EXTRA_RESOLVED=0.05_s2: $s"

# ---- demo defaults and help ----
n=$(mk PROFILE=demo all)
grep -q -- "--grids 6,5,4,3" <<<"$n" && ! grep -q "_s2/DONE\|phi0.05_s2 " <<<"$(grep generate <<<"$n")" &&
  ok "demo: --grids 6,5,4,3, no extra resolved run" || fail "demo: filter grids / extra resolved"
grep -q "phi0.10_c4_a3_perfect_s3" <<<"$n" && ok "demo: perfect closure at every alpha with SEEDS=1,2,3" || fail "demo: perfect runs"
n=$(mk PROFILE=demo PHIS=0.05 all); s=$?
[ $s -eq 0 ] && grep -q "coarse/phi0.05_c4_a1_model_s1 " <<<"$n" && ok "demo PHIS=0.05: its alpha = 1 runs follow (ALPHA1_PHIS defaults to PHIS without 0.10)" ||
  fail "demo PHIS=0.05: status $s"
n=$(mk PROFILE=demo all)
! grep -q "coarse/phi0.10_c4_a1_" <<<"$n" && ok "demo: no alpha = 1 run at 0.10" || fail "demo: an alpha = 1 run at 0.10"
h=$(make -f Makefile.pipeline help OUT="$tmp/out" PROFILE=half 2>&1)
for v in SEEDS=1,2,3 ALPHA1_SEEDS=1 EXTRA_RESOLVED=0.05_s2 FILTER_GRIDS=12,8,6,5,4,3 PARCEL_FIT=1 COARSE_DRAGS=micro,model,radl2014,perfect; do
  grep -qF -- "$v" <<<"$h" || fail "make help lacks $v"
done
ok "make help lists SEEDS, ALPHA1_SEEDS, EXTRA_RESOLVED, FILTER_GRIDS, PARCEL_FIT, COARSE_DRAGS with their values"

# ---- refusals: make errors naming what is allowed ----
e=$(mk PROFILE=demo COARSE_DRAGS=micro,wen-yu all); s=$?
[ $s -ne 0 ] && grep -q "'wen-yu' is not a drag label (allowed: micro model modelraw radl2014 perfect drift wide)" <<<"$e" &&
  ok "an unknown drag label is a make error listing the allowed ones" || fail "unknown drag label: status $s, $e"
e=$(mk PROFILE=half EXTRA_RESOLVED=0.07_s2 all); s=$?
[ $s -ne 0 ] && grep -q "EXTRA_RESOLVED entry '0.07_s2'" <<<"$e" && ok "EXTRA_RESOLVED outside PHIS refused" || fail "EXTRA_RESOLVED=0.07_s2: $s"
e=$(mk PROFILE=half EXTRA_RESOLVED=0.05_sx all); s=$?
[ $s -ne 0 ] && grep -q "EXTRA_RESOLVED entry '0.05_sx'" <<<"$e" && ok "EXTRA_RESOLVED with a bad seed refused" || fail "EXTRA_RESOLVED=0.05_sx: $s"
e=$(mk PROFILE=demo COARSE_CELLS=4,2 all); s=$?
[ $s -ne 0 ] && grep -q "FILTER_GRIDS=6,5,4,3 lacks 2" <<<"$e" && ok "perfect on a grid the filter did not evaluate refused" || fail "perfect grid: $s"
e=$(mk PROFILE=demo SEEDS=1,x all); s=$?
[ $s -ne 0 ] && grep -q "integer >= 0" <<<"$e" && ok "a non-integer seed refused" || fail "SEEDS=1,x: $s"
e=$(mk PROFILE=demo "ALPHA1_PHIS=" all); s=$?
[ $s -ne 0 ] && grep -q "PARCEL_FIT=1 needs alpha = 1 runs" <<<"$e" && ok "a parcel fit without alpha = 1 runs refused" || fail "ALPHA1_PHIS empty: $s"
[ $failures -eq 0 ] && echo "all pipeline wiring checks passed" || echo "$failures pipeline wiring check(s) failed"
exit $((failures > 0))
