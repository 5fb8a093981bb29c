#!/usr/bin/env bash
# e2e: Makefile.pipeline's queries change nothing, and a stage made with other parameters is not destroyed before
# its successor is under way (issue 19). On a tiny resolved run (20 x 80 x 20 d_p, 1 t_ref at <phi> = 0.05) and its
# filter: `make -q` is 0 with the variables it was made with and 1 with others, and neither writes a stamp (the
# query after another one still answers for its own variables); `make -n` with another GENERATE_SET plans the run
# but leaves every file as it was, and the plain make after it reruns nothing; help, summary, figures and
# `make -n summary` write nothing and plan no run; PHIS=.05 is the run phi0.05 (solids fractions normalised);
# FIT_EXTRA adds to the profile's FIT_ARGS (replacing an option given in both); a new resolved run that fails at
# start (an unknown scene key) gives the complete run it was to replace back, and make then keeps that run (its
# own parameters are the ones asked) instead of running it again.
# Environment (set by CTest): CGD_SOURCE_DIR, CGD_BINARY_DIR.
source "$(dirname "$0")/lib/prologue.sh"
gen_set="domain.size_dp=[20,80,20] run.end_time_tref=1 run.dump_interval_tref=0.1 run.sampling_start_tref=0.5"
vars=(OUT="$tmp/out" BUILD="$binary_dir" PROFILE=demo PHIS=0.05 BOX_DP=20 FROM_TREF=0.5 BINS=0.005 WIDTHS=3.34,5,6.67
      "GENERATE_SET=$gen_set" FILTER_GRIDS= COARSE_CELLS=4 ALPHAS=1,2 SEEDS=1 COARSE_DRAGS=micro,model)
mk() { make -f Makefile.pipeline "${vars[@]}" "$@"; }
state() { (cd "$tmp/out" && find . -printf '%p %s %T@ %l\n' | sort) | md5sum; }

mk generate filter >"$tmp/make1.log" 2>&1 || { tail -n 30 "$tmp/make1.log"; fail "first make (generate filter)"; exit 1; }
[ -f "$tmp/out/generate/phi0.05/DONE" ] && [ -f "$tmp/out/filter/filtered.h5" ] && ok "tiny resolved run and its filter made" ||
  fail "no DONE or filtered.h5"
s0=$(state)
done0=$(stat -c %Y.%y "$tmp/out/generate/phi0.05/DONE")

# ---- -q answers for its own variables and writes nothing ----
mk -q generate filter; q=$?
[ $q -eq 0 ] && ok "make -q with the variables it was made with: 0" || fail "make -q after make: $q"
mk -q filter WIDTHS=3.34,5 2>/dev/null; q=$?
[ $q -eq 1 ] && ok "make -q with other WIDTHS: 1 (out of date)" || fail "make -q with other WIDTHS: $q"
[ "$(state)" = "$s0" ] && ok "make -q with other WIDTHS wrote nothing (the filter stamp is as it was)" ||
  fail "make -q with other WIDTHS changed files under OUT: $(cat "$tmp/out/stamps/filter.stamp")"
mk -q generate filter; q=$?
[ $q -eq 0 ] && ok "make -q with the first variables again: still 0" || fail "make -q after a query with other WIDTHS: $q"

# ---- -n with another resolved run's parameters plans it, changes nothing; the plain make then reruns nothing ----
n=$(mk -n generate "GENERATE_SET=$gen_set contact.gamma_star=2e-3" 2>&1); s=$?
[ $s -eq 0 ] && grep -q "pipeline_run.sh \"generate phi=0.05\"" <<<"$n" && ok "make -n with another GENERATE_SET plans the resolved run" ||
  fail "make -n with another GENERATE_SET: status $s, no run planned"
[ "$(state)" = "$s0" ] && ok "make -n with another GENERATE_SET wrote nothing" || fail "make -n with another GENERATE_SET changed files under OUT"
mk generate filter >"$tmp/make2.log" 2>&1 || fail "make after make -n: $(tail -n 5 "$tmp/make2.log")"
[ "$(stat -c %Y.%y "$tmp/out/generate/phi0.05/DONE")" = "$done0" ] && ! grep -q "removing\|setting the previous run aside" "$tmp/make2.log" &&
  [ "$(state)" = "$s0" ] && ok "the make after make -n reran nothing (the resolved run untouched)" ||
  fail "the make after make -n touched the resolved run: $(grep pipeline "$tmp/make2.log" | head -n 3)"

# ---- help, summary, figures: print, write nothing, plan no run ----
mk help >/dev/null 2>&1 || fail "make help failed"
out=$(timeout 120 make -f Makefile.pipeline "${vars[@]}" summary 2>&1); s=$?
[ $s -ne 0 ] && grep -q "no complete run yet" <<<"$out" && ok "make summary without a complete run: says so, runs nothing" ||
  fail "make summary without a complete run: status $s: $(tail -n 3 <<<"$out")"
out=$(timeout 120 make -f Makefile.pipeline "${vars[@]}" figures 2>&1); s=$?
[ $s -ne 0 ] && grep -q "no study yet" <<<"$out" && ok "make figures without a study: says so, runs nothing" ||
  fail "make figures without a study: status $s: $(tail -n 3 <<<"$out")"
n=$(mk -n summary 2>&1)
! grep -q "cgd-fit\|cgd-coarse\|pipeline_run" <<<"$n" && ok "make -n summary plans no fit and no run" ||
  fail "make -n summary plans: $(grep -c "cgd-fit\|cgd-coarse\|pipeline_run" <<<"$n") commands"
mk -q all >/dev/null 2>&1; q=$?
[ $q -eq 1 ] && ok "make -q all (nothing fitted yet): 1" || fail "make -q all: $q"
[ "$(state)" = "$s0" ] && ok "help, summary, figures, make -n summary, make -q all wrote nothing" ||
  fail "help, summary, figures or a query changed files under OUT"

# ---- solids fractions normalised; FIT_EXTRA adds to FIT_ARGS ----
mk -q generate filter PHIS=.050 2>/dev/null; q=$?
[ $q -eq 0 ] && ok "PHIS=.050 is the run phi0.05: nothing to do" || fail "PHIS=.050: make -q $q"
n=$(mk -n all PHIS=0.05,0.1 2>&1)
grep -q "generate/phi0.10 " <<<"$n" && ! grep -q "generate/phi0.1 " <<<"$n" && ok "PHIS=0.05,0.1 plans phi0.10 (not phi0.1)" ||
  fail "PHIS=0.05,0.1: $(grep -o 'generate/phi0.1[0-9]* ' <<<"$n" | sort -u)"
e=$(mk -n all PHIS=0.05,x1 2>&1); s=$?
[ $s -ne 0 ] && grep -q "'x1' is not a solids fraction" <<<"$e" && ok "PHIS=0.05,x1 refused with a message" || fail "PHIS=0.05,x1: $s $e"
n=$(mk -n fit FIT_ARGS="--width-exponent fit --min-count 20" FIT_EXTRA="--phi-crit 0.02 --min-count 30" 2>&1)
grep -q "cgd-fit $tmp/out/filter/filtered.h5 --width-exponent fit --phi-crit 0.02 --min-count 30 --force" <<<"$n" &&
  ok "FIT_EXTRA adds to FIT_ARGS (--min-count given in both: FIT_EXTRA's)" || fail "FIT_EXTRA: $(grep 'cgd-fit ' <<<"$n")"
[ "$(state)" = "$s0" ] && ok "those queries wrote nothing" || fail "the PHIS/FIT_EXTRA queries changed files under OUT"

# ---- a new resolved run that fails at start gives the old one back; make then keeps it ----
mk generate "GENERATE_SET=$gen_set particles.no_such_key=1" >"$tmp/make3.log" 2>&1; s=$?
[ $s -ne 0 ] && ok "a resolved run with an unknown key fails" || fail "the resolved run with an unknown key did not fail"
[ -f "$tmp/out/generate/phi0.05/DONE" ] && [ "$(stat -c %Y.%y "$tmp/out/generate/phi0.05/DONE")" = "$done0" ] &&
  [ -f "$tmp/out/generate/phi0.05/series.h5" ] && [ ! -e "$tmp/out/generate/phi0.05.previous" ] &&
  ok "the complete run it was to replace is back, untouched" || fail "the complete resolved run was lost: $(ls "$tmp/out/generate" | tr '\n' ' ')"
mk generate >"$tmp/make4.log" 2>&1 || fail "make after the failed run: $(tail -n 5 "$tmp/make4.log")"
grep -q "up to date: .*complete run of these parameters (kept" "$tmp/make4.log" && [ -f "$tmp/out/generate/phi0.05/DONE" ] &&
  ! grep -q "running ->" "$tmp/make4.log" && ok "make with the first parameters keeps the complete run (not run again)" ||
  fail "make with the first parameters: $(grep pipeline "$tmp/make4.log" | head -n 3)"
mk -q generate; q=$?
[ $q -eq 0 ] && ok "make -q generate: 0 again" || fail "make -q generate after keeping the run: $q"

[ $failures -eq 0 ] && echo "all pipeline query checks passed" || echo "$failures pipeline query check(s) failed"
exit $((failures > 0))
