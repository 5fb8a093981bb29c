#!/usr/bin/env bash
# tools/cgd-show on every kind it knows (issue 19): a tiny resolved run (20 x 80 x 20 d_p, 1 t_ref) gives the run
# directory, a snapshot, the checkpoint and the series; cgd-filter, cgd-fit (and --grid-table) and cgd-coarse
# --summarise give a filtered file, a drag model, a table model (the perfect closure) and a coarse summary; tools/study.py a study. For each kind: a text summary (exit 0)
# that writes no file (not beside its input, not in the working directory, not in TMPDIR, no cgd-show file in /tmp), and --plot FILE.png that draws a
# PNG there (exit 0). A picture that cannot be drawn (no directory for it, a version-1 study) and a file that is
# not a cgd file are refused with exit 2 and a message; --help lists the kinds and what PATH may be.
# usage: bash tests/tools/cgd_show.sh   (environment, set by CTest: CGD_SOURCE_DIR, CGD_BINARY_DIR)
set -u
source_dir=${CGD_SOURCE_DIR:-$(cd "$(dirname "$0")/../.." && pwd)}
binary_dir=${CGD_BINARY_DIR:-$source_dir/build}
show=$source_dir/tools/cgd-show
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
failures=0
fail() { echo "FAIL $*"; failures=$((failures + 1)); }
ok() { echo "ok   $*"; }
cd "$tmp" || exit 1
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
"$binary_dir/cgd-generate" "$source_dir/data/scenes/pipeline_demo.toml" --set 'domain.size_dp=[20,80,20]' \
  --set run.end_time_tref=1 --set run.dump_interval_tref=0.1 --set run.sampling_start_tref=0.5 \
  --set particles.solids_fraction=0.05 --quiet -o run >gen.log 2>&1 || { cat gen.log; echo "FAIL tiny run"; exit 1; }
"$binary_dir/cgd-filter" run --from-tref 0.5 --widths 5,6.67,10 --grids 4 --bins 0.005 --quiet -o filtered.h5 >filter.log 2>&1 ||
  { cat filter.log; echo "FAIL filter"; exit 1; }
"$binary_dir/cgd-fit" filtered.h5 --min-width-over-cell 1.4 --min-count 20 --bootstrap 20 --no-cross-validation \
  -o model.h5 >fit.log 2>&1 || { cat fit.log; echo "FAIL fit"; exit 1; }
"$binary_dir/cgd-fit" filtered.h5 --grid-table 4 --min-count 20 -o perfect.h5 >perfect.log 2>&1 ||
  { cat perfect.log; echo "FAIL fit --grid-table"; exit 1; }
"$binary_dir/cgd-coarse" --summarise run --from-tref 0.5 -o summary.h5 >summarise.log 2>&1 ||
  { cat summarise.log; echo "FAIL summarise"; exit 1; }
mkdir -p coarse/phi0.05_c6_a1_micro_s1 && cp summary.h5 coarse/phi0.05_c6_a1_micro_s1/
/usr/bin/python3 "$source_dir/tools/study.py" --coarse coarse/phi0.05_c6_a1_micro_s1 --resolved summary.h5 --bootstrap 200 \
  -o study >study.txt 2>study.log || { cat study.log; echo "FAIL study"; exit 1; }
snap=$(ls run/snapshots/snap_*.h5 | tail -n 1)
mkdir pictures work tmpdir

# kind, PATH, a word its summary prints
checks=("run directory|run|run: complete (DONE)"
        "snapshot|$snap|format        snapshot"
        "checkpoint|run/checkpoint.h5|format        checkpoint"
        "series|run/series.h5|format        series"
        "filtered|filtered.h5|H = 1 - beta_bar/beta_micro"
        "drag_model|model.h5|micro law beetstra, H(F, phi)"
        "drag_model (table)|perfect.h5|a table model (the perfect closure"
        "coarse_summary|summary.h5|coarse run summary"
        "study|study.h5|over the solids fractions")
for c in "${checks[@]}"; do
  IFS='|' read -r kind path word <<<"$c"
  touch marker
  listing=$(cd "$tmp" && find . -newer gen.log -type f ! -name marker | sort | md5sum)
  out=$(cd work && TMPDIR="$tmp/tmpdir" "$show" "$tmp/$path" 2>&1); s=$?
  [ $s -eq 0 ] && grep -qF -- "$word" <<<"$out" && ok "$kind: text summary" || fail "$kind: summary status $s: $(head -n 3 <<<"$out")"
  [ -z "$(find work tmpdir -mindepth 1)" ] && [ -z "$(find /tmp -maxdepth 1 -newer marker -iname '*cgd*show*' 2>/dev/null)" ] &&
    [ "$(cd "$tmp" && find . -newer gen.log -type f ! -name marker | sort | md5sum)" = "$listing" ] &&
    ok "$kind: no file written without --plot" || fail "$kind: files written without --plot: $(find work tmpdir -mindepth 1) $(find /tmp -maxdepth 1 -newer marker -iname '*cgd*show*')"
  png="pictures/$(tr -c 'A-Za-z0-9_\n' _ <<<"$kind").png"
  out=$("$show" "$tmp/$path" --plot "$png" 2>&1); s=$?
  [ $s -eq 0 ] && [ "$(head -c 4 "$png" 2>/dev/null | tail -c 3)" = "PNG" ] && ok "$kind: --plot draws $png" ||
    fail "$kind: --plot status $s, $(ls -l "$png" 2>&1): $(tail -n 2 <<<"$out")"
done

# refusals: exit 2 with a message
out=$("$show" model.h5 --plot nodir/m.png 2>&1); s=$?
[ $s -eq 2 ] && grep -q "no directory" <<<"$out" && ok "--plot into a missing directory: exit 2, says so" || fail "--plot nodir: $s $out"
/usr/bin/python3 -c 'import h5py, shutil, sys; shutil.copy("study.h5", "study_v1.h5"); f = h5py.File("study_v1.h5", "r+"); del f["summary"]' &&
  out=$("$show" study_v1.h5 --plot pictures/v1.png 2>&1); s=$?
[ $s -eq 2 ] && grep -q "version-1 study" <<<"$out" && [ ! -e pictures/v1.png ] && ok "a study it cannot draw: exit 2, says why" ||
  fail "version-1 study --plot: $s $out"
echo "not hdf5" >plain.txt
out=$("$show" plain.txt 2>&1); s=$?
[ $s -eq 2 ] && grep -q "cannot open as HDF5" <<<"$out" && ok "not an HDF5 file: exit 2" || fail "plain file: $s $out"
/usr/bin/python3 -c 'import h5py; h5py.File("other.h5", "w").attrs["x"] = 1'
out=$("$show" other.h5 2>&1); s=$?
[ $s -eq 2 ] && grep -q "not a cgd file" <<<"$out" && ok "an HDF5 file without cgd_format: exit 2" || fail "other.h5: $s $out"
out=$("$show" run/snapshots 2>&1); s=$?
[ $s -eq 2 ] && grep -q "not a cgd run directory" <<<"$out" && ok "a directory that is not a run: exit 2" || fail "snapshots dir: $s $out"
# a run directory given to cgd-fit: it says the run is filtered first (not "not a regular file")
out=$("$binary_dir/cgd-fit" run -o fit_of_run.h5 2>&1); s=$?
[ $s -eq 2 ] && grep -q "run directory, not a filtered file: filter it first (cgd-filter" <<<"$out" && [ ! -e fit_of_run.h5 ] &&
  ok "cgd-fit RUN_DIR: exit 2, filter it first" || fail "cgd-fit RUN_DIR: $s $out"
h=$("$show" --help 2>&1); s=$?
missing=""
for k in "run directory" snapshot checkpoint series filtered drag_model coarse_summary study "PATH is" "--plot FILE.png" "Exit status"; do
  grep -qF -- "$k" <<<"$h" || missing+=" '$k'"
done
[ $s -eq 0 ] && [ -z "$missing" ] && ok "--help lists the kinds, what PATH may be, --plot and the exit status" || fail "--help lacks$missing"
[ $failures -eq 0 ] && echo "all cgd-show checks passed" || echo "$failures cgd-show check(s) failed"
exit $((failures > 0))
