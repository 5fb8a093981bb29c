#!/usr/bin/env bash
# e2e: Makefile.pipeline on a tiny configuration (two resolved realisations of 2 t_ref at <phi> = 0.05 in a
# 20 x 80 x 20 d_p box, four filter widths, a fit, coarse runs at alpha = 1 and 2 (two realisations of alpha = 2)
# with the micro law, the model, Radl 2014 and, when this build's cgd-filter has --grids, the perfect closure,
# the parcel fit, the study): everything is produced; the study pools both resolved runs and both realisations;
# a model run the parcel fit leaves unchanged is the modelraw run reused; `make -q` right after reports nothing to
# do; changing WIDTHS reruns exactly the filter and what depends on it (the resolved run's files keep their times).
# Environment (set by CTest): CGD_SOURCE_DIR, CGD_BINARY_DIR.
source "$(dirname "$0")/lib/prologue.sh"
vars=(OUT="$tmp/out" BUILD="$binary_dir" PHIS=0.05 BOX_DP=20 FROM_TREF=0.5 BINS=0.005
      "GENERATE_SET=domain.size_dp=[20,80,20] run.end_time_tref=2 run.dump_interval_tref=0.1 run.sampling_start_tref=0.5"
      "COARSE_SET=domain.size_dp=[20,80,20] run.end_time_tref=2 run.sampling_start_tref=0.5"
      "FIT_ARGS=--min-width-over-cell 1.4 --min-count 20 --bootstrap 50 --no-cross-validation --width-exponent fit"
      COARSE_CELLS=4 ALPHAS=1,2 SEEDS=1,2 ALPHA1_SEEDS=1 EXTRA_RESOLVED=0.05_s2)
# the perfect closure needs cgd-filter --grids and cgd-fit --grid-table/--operator grid (docs/filter.md)
if "$binary_dir/cgd-filter" --help 2>&1 | grep -q -- "--grids"; then
  vars+=(COARSE_DRAGS=micro,model,radl2014,perfect FILTER_GRIDS=5,4)
  perfect=yes
else
  vars+=(COARSE_DRAGS=micro,model,radl2014 FILTER_GRIDS=)
  perfect=no
  echo "note: this build's cgd-filter has no --grids: the perfect closure is not run"
fi
make -f Makefile.pipeline -j2 "${vars[@]}" WIDTHS=3.34,5,6.67,10 all >"$tmp/make1.log" 2>&1 || { tail -n 40 "$tmp/make1.log"; fail "first make"; exit 1; }
files="generate/phi0.05/DONE generate/phi0.05_s2/DONE filter/filtered.h5 filter/filtered.png fit/model.h5 fit/model_parcels.h5
  coarse/phi0.05_c4_a1_micro_s1/summary.h5 coarse/phi0.05_c4_a2_model_s1/summary.h5 coarse/phi0.05_c4_a2_modelraw_s2/summary.h5
  coarse/phi0.05_c4_a2_radl2014_s2/summary.h5 study/resolved/phi0.05.h5 study/resolved/phi0.05_s2.h5
  study/study.h5 study/study.csv study/study_runs.csv study/study.png study/study_figure2.png study/study_figure3.png"
[ $perfect = yes ] && files+=" fit/perfect_c4.h5 coarse/phi0.05_c4_a2_perfect_s2/summary.h5"
for f in $files; do
  [ -e "$tmp/out/$f" ] || fail "missing $f"
done
# the study: the reference pooled over both resolved runs, alpha = 2 pooled over both realisations
/usr/bin/python3 -c '
import sys, h5py
f = h5py.File(sys.argv[1], "r")
drag, R, alpha = f["drag"][()].astype(str), f["R"][()], f["alpha"][()]
assert R[list(drag).index("resolved")] == 2, "reference not pooled over 2 runs"
assert all(r == 2 for d, a, r in zip(drag, alpha, R) if d != "resolved" and a == 2), "alpha = 2 not pooled over 2 realisations"
assert all(r == 1 for d, a, r in zip(drag, alpha, R) if d != "resolved" and a == 1)
print("ok   study: reference pooled over 2 resolved runs, alpha = 2 over 2 realisations, alpha = 1 over 1")
' "$tmp/out/study/study.h5" || fail "study pooling"
# the parcel fit's decision, and the model runs it implies
if grep -q "^c_corr not applied" "$tmp/out/fit/model_parcels.report.txt"; then
  if [ -f "$tmp/out/coarse/phi0.05_c4_a2_model_s1/REUSED" ] && [ -f "$tmp/out/coarse/phi0.05_c4_a2_model_s2/REUSED" ] &&
     [ -L "$tmp/out/coarse/phi0.05_c4_a2_model_s1/series.h5" ] &&
     /usr/bin/python3 -c 'import sys, h5py; a = h5py.File(sys.argv[1], "r").attrs; sys.exit(0 if a["label"] == "model" and "modelraw_s1" in a["reused_from"] else 1)' \
       "$tmp/out/coarse/phi0.05_c4_a2_model_s1/summary.h5"; then
    echo "ok   parcel fit applied no c_corr: the alpha = 2 model runs are the modelraw runs (REUSED, label model), not rerun"
  else
    fail "c_corr not applied but the model runs were not reused"
  fi
else
  [ ! -e "$tmp/out/coarse/phi0.05_c4_a2_model_s1/REUSED" ] && echo "ok   parcel fit applied c_corr: the model runs ran" ||
    fail "c_corr applied but a model run was reused"
fi
# the fitted width exponent reached the model file and the parcel fit's copy of it
/usr/bin/python3 -c '
import sys, h5py
for p in sys.argv[1:]:
    a = h5py.File(p, "r").attrs
    assert a["width_exponent_fitted"] == 1 and a["width_exponent_low"] <= a["width_exponent"] <= a["width_exponent_high"], p
    print("ok   %s: width_exponent %.3f [%.3f, %.3f]" % (p.split("/")[-1], a["width_exponent"], a["width_exponent_low"], a["width_exponent_high"]))
' "$tmp/out/fit/model.h5" "$tmp/out/fit/model_parcels.h5" || fail "width exponent not in the model files"
# the fit report names each cross-validation run by its resolved run's directory (phi and seed), not only "run 1"
# (the pipeline's fit above runs without cross-validation: one more fit of the same filtered file, with it)
"$binary_dir/cgd-fit" "$tmp/out/filter/filtered.h5" --min-width-over-cell 1.4 --min-count 20 --bootstrap 0 \
  -o "$tmp/cv.h5" >"$tmp/cv.report.txt" 2>&1
grep -q "run [0-9] (.*generate/phi0.05_s2)" "$tmp/cv.report.txt" && echo "ok   CV runs named by their run" \
  || { grep -A3 "cross-validation" "$tmp/cv.report.txt"; fail "the fit report's cross-validation runs are not named by their run directory"; }
grep -q "==== cgd pipeline" "$tmp/make1.log" && echo "ok   pipeline complete, summary printed" || fail "no summary"
make -f Makefile.pipeline -q "${vars[@]}" WIDTHS=3.34,5,6.67,10 all; q=$?
[ $q -eq 0 ] && echo "ok   make -q after a complete make: nothing to do" || fail "make -q exit status $q after a complete make"

stamp() { stat -c %Y.%y "$tmp/out/$1"; }
sleep 1.1
gen_before=$(stamp generate/phi0.05/DONE); snap_before=$(ls -l --time-style=full-iso "$tmp/out/generate/phi0.05/snapshots" | md5sum)
filt_before=$(stamp filter/filtered.h5); fit_before=$(stamp fit/model.h5); study_before=$(stamp study/study.h5)
coarse_before=$(stamp coarse/phi0.05_c4_a1_micro_s1/DONE)
make -f Makefile.pipeline -j2 "${vars[@]}" WIDTHS=3.34,5,6.67,8.33 all >"$tmp/make2.log" 2>&1 || { tail -n 30 "$tmp/make2.log"; fail "second make"; }
[ "$(stamp generate/phi0.05/DONE)" = "$gen_before" ] && [ "$(ls -l --time-style=full-iso "$tmp/out/generate/phi0.05/snapshots" | md5sum)" = "$snap_before" ] &&
  echo "ok   WIDTHS changed: the resolved run was not rerun" || fail "the resolved run was rerun"
[ "$(stamp filter/filtered.h5)" != "$filt_before" ] && [ "$(stamp fit/model.h5)" != "$fit_before" ] &&
  [ "$(stamp study/study.h5)" != "$study_before" ] && echo "ok   WIDTHS changed: filter, fit and study reran" || fail "filter/fit/study not rerun"
[ "$(stamp coarse/phi0.05_c4_a1_micro_s1/DONE)" = "$coarse_before" ] && echo "ok   micro-law coarse runs (no model) were not rerun" ||
  fail "a micro-law coarse run was rerun"
[ $failures -eq 0 ] && echo "all pipeline checks passed" || echo "$failures pipeline check(s) failed"
exit $((failures > 0))
