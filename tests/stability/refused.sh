#!/usr/bin/env bash
# Stability (g): input that only the run can judge (scene validation passes; the run refuses it before
# writing anything): exit status 2, a message naming what to change, and no output directory.
#   * more MPI ranks than the box has contact-cutoff-high slabs (sim/dem/system.cpp);
#   * a fluid grid with fewer y-rows than ranks need (sim/fluid/grid.cpp);
#   * a quiescent-fluid (Stokes) run whose DEM step exceeds half the particle relaxation time
#     (explicit drag; sim/run.cpp dem_settings_from_scene);
#   * a filtered drag law in a resolved run (generator/main.cpp);
#   * --restart without a checkpoint, and an existing run directory without --restart (left untouched).
# (t_star > 0.2, solids_fraction >= 0.64 and the like are refused by scene validation:
#  tests/e2e/bad_input.sh, tests/unit/test_scene.cpp.)
source "$(dirname "$0")/lib_stability.sh"
failures=0
expect_refused() {  # NAME NP SUBSTRING SCENE ARGS...
  local name=$1 np=$2 want=$3 scene=$4; shift 4
  local status=0
  rm -rf "$tmp/$name"
  if [ "$np" -gt 1 ]; then
    $MPIEXEC --allow-run-as-root --oversubscribe -np "$np" "$GEN" "$scene" "$@" --quiet -o "$tmp/$name" \
      >"$tmp/$name.out" 2>"$tmp/$name.err" || status=$?
  else
    "$GEN" "$scene" "$@" --quiet -o "$tmp/$name" >"$tmp/$name.out" 2>"$tmp/$name.err" || status=$?
  fi
  local ok=1
  [ "$status" -eq 2 ] || { echo "FAIL $name: exit status $status, expected 2"; ok=0; }
  grep -qF -- "$want" "$tmp/$name.err" || { echo "FAIL $name: stderr lacks \"$want\""; ok=0; }
  [ ! -e "$tmp/$name" ] || { echo "FAIL $name: $tmp/$name was created"; ok=0; }
  if [ $ok -eq 1 ]; then echo "ok   $name: $(head -n 1 "$tmp/$name.err" | cut -c1-200)"
  else sed 's/^/     /' "$tmp/$name.err"; failures=$((failures + 1)); fi
}
dry=$SRC/data/scenes/dry_settling.toml
expect_refused too-many-ranks 4 "too many MPI ranks" "$dry" --set 'domain.size_dp=[24,4,24]'
expect_refused grid-rows 4 "fluid.cells" "$BASE" --set 'fluid.cells=[5,2,5]'
expect_refused stokes-step 1 "too large for the Stokes relaxation time" "$dry" --set contact.gamma_star=2.0 --set contact.t_star=0.2
expect_refused filtered-drag 1 "fluid.drag" "$BASE" --set fluid.drag=\"radl2014\"
mkdir -p "$tmp/empty"; rmdir "$tmp/empty"
expect_refused restart-without-checkpoint 1 "no checkpoint to restart from" "$BASE" --restart

# an existing run directory without --restart: refused, its files untouched
mkdir -p "$tmp/existing"; echo keep >"$tmp/existing/marker"
status=0; "$GEN" "$BASE" --quiet -o "$tmp/existing" >"$tmp/existing.out" 2>"$tmp/existing.err" || status=$?
if [ $status -eq 2 ] && grep -q "already holds files" "$tmp/existing.err" && [ "$(ls "$tmp/existing")" = marker ] &&
   [ "$(cat "$tmp/existing/marker")" = keep ]; then
  echo "ok   existing-directory: $(head -n 1 "$tmp/existing.err" | cut -c1-200)"
else
  echo "FAIL existing-directory: status $status, contents: $(ls "$tmp/existing")"; cat "$tmp/existing.err"; failures=$((failures + 1))
fi
[ $failures -eq 0 ] || { echo "$failures refusal check(s) failed"; exit 1; }
echo "stability (g) input only the run can judge is refused with status 2, nothing written: passed"
