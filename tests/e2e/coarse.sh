#!/usr/bin/env bash
# e2e: cgd-coarse
#  * alpha = 1 with a micro law reproduces cgd-generate bit for bit (the same engine and scene);
#  * a run stopped half-way and continued with --restart (end time extended) equals an uninterrupted
#    run bit for bit at 1 rank;
#  * --reference writes summary.h5 with the slip, its error and the cost; --model sets the model;
#  * refusals (exit 2, nothing written): a parcel wider than a cell, too few parcels, an empty window;
#  * --summarise RUN_DIR over the reference's own window gives the reference values a coarse run stored, and the
#    drift of its halves; over a later window (--from-tref) another window; refuses an existing -o, a non-run.
# Environment (set by CTest): CGD_SOURCE_DIR, CGD_BINARY_DIR.
set -u
source_dir=${CGD_SOURCE_DIR:-$(cd "$(dirname "$0")/../.." && pwd)}
binary_dir=${CGD_BINARY_DIR:-$source_dir/build}
generate=$binary_dir/cgd-generate
coarse=$binary_dir/cgd-coarse
py=/usr/bin/python3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
failures=0
fail() { echo "FAIL $*"; failures=$((failures + 1)); }
scene=$source_dir/data/scenes/pipeline_demo.toml
small=(--set 'domain.size_dp=[20,80,20]' --set fluid.dx_over_dp=5 --set run.dump_interval_tref=0.25 --set run.sampling_start_tref=0.25 --quiet)

same_snapshot() {  # A B: every dataset of the two last snapshots identical
  "$py" - "$1" "$2" <<'PY'
import sys, os, h5py, numpy as np
def last(d):
    s = sorted(f for f in os.listdir(os.path.join(d, "snapshots")) if f.startswith("snap_"))
    return os.path.join(d, "snapshots", s[-1])
a, b = h5py.File(last(sys.argv[1])), h5py.File(last(sys.argv[2]))
names = []
a.visit(names.append)
n = 0
for k in names:
    if isinstance(a[k], h5py.Dataset):
        assert np.array_equal(a[k][()], b[k][()]), k
        n += 1
assert a.attrs["step"] == b.attrs["step"]
print(n)
PY
}

"$generate" "$scene" "${small[@]}" --set run.end_time_tref=1 -o "$tmp/gen" >/dev/null 2>&1 || fail "cgd-generate"
"$coarse" "$scene" "${small[@]}" --set run.end_time_tref=1 --reference "$tmp/gen" -o "$tmp/coarse" >"$tmp/c.out" 2>&1 || { cat "$tmp/c.out"; fail "cgd-coarse"; }
n=$(same_snapshot "$tmp/gen" "$tmp/coarse") && echo "ok   alpha = 1: cgd-coarse equals cgd-generate bit for bit ($n datasets)" || fail "coarse != generate"
grep -q "relative error" "$tmp/c.out" && "$py" -c "
import h5py; a = h5py.File('$tmp/coarse/summary.h5').attrs
assert a['cgd_format'] == 'coarse_summary' and abs(a['relative_error']) < 1e-12 and a['core_seconds_per_simulated_second'] > 0
" && echo "ok   summary.h5 with the slip, the error against the reference (0 for the same run) and the cost" || fail "summary"

# --summarise: the same code path as --reference: over the reference scene's window (0.25 t_ref, the default)
# the values equal those the coarse run stored; --from-tref 0.5 starts the window there
"$coarse" --summarise "$tmp/gen" -o "$tmp/gen_summary.h5" >"$tmp/s.out" 2>&1 || { cat "$tmp/s.out"; fail "--summarise"; }
"$coarse" --summarise "$tmp/gen" --from-tref 0.5 -o "$tmp/gen_late.h5" >/dev/null 2>&1 || fail "--summarise --from-tref"
"$py" -c "
import h5py
c = h5py.File('$tmp/coarse/summary.h5').attrs; s = h5py.File('$tmp/gen_summary.h5').attrs; l = h5py.File('$tmp/gen_late.h5').attrs
assert s['cgd_format'] == 'coarse_summary' and s['slip_over_ut'] == c['reference_slip_over_ut'], (s['slip_over_ut'], c['reference_slip_over_ut'])
assert s['slip_stderr'] == c['reference_slip_stderr'] and s['window_start_s'] == c['reference_window_start_s']
assert 'drift_over_ut' in s and 'stationary' in s and s['core_seconds_per_simulated_second'] > 0
assert abs(l['window_start_s'] / s['window_start_s'] - 2) < 1e-9, (l['window_start_s'], s['window_start_s'])
" && echo "ok   --summarise: the reference values of --reference, bit for bit, with the drift; --from-tref moves the window" ||
  fail "--summarise values"
"$coarse" --summarise "$tmp/gen" -o "$tmp/gen_summary.h5" >/dev/null 2>"$tmp/err"; st=$?
[ $st -eq 2 ] && grep -q "exists" "$tmp/err" && echo "ok   --summarise: an existing -o is refused (exit 2)" || fail "--summarise over an existing file: $st"
"$coarse" --summarise "$tmp" -o "$tmp/nothing.h5" >/dev/null 2>"$tmp/err"; st=$?
[ $st -eq 2 ] && [ ! -e "$tmp/nothing.h5" ] && echo "ok   --summarise: a directory that is no run is refused (exit 2)" || fail "--summarise of a non-run: $st"

# restart: half, then continue to the end, against the uninterrupted run
"$coarse" "$scene" "${small[@]}" --set particles.parcel_size=2 --set run.end_time_tref=0.5 -o "$tmp/half" >/dev/null 2>&1 || fail "half run"
"$coarse" "$scene" "${small[@]}" --set particles.parcel_size=2 --set run.end_time_tref=1 -o "$tmp/half" --restart >/dev/null 2>"$tmp/r.err" || { cat "$tmp/r.err"; fail "restart"; }
"$coarse" "$scene" "${small[@]}" --set particles.parcel_size=2 --set run.end_time_tref=1 -o "$tmp/whole" >/dev/null 2>&1 || fail "whole run"
n=$(same_snapshot "$tmp/whole" "$tmp/half") && echo "ok   restart of a parcel run equals the uninterrupted run bit for bit ($n datasets)" || fail "restart differs"

expect_bad() {  # NAME SUBSTRING -- ARGS
  local name=$1 expected=$2; shift 3
  rm -rf "$tmp/bad"
  "$coarse" "$@" -o "$tmp/bad" >/dev/null 2>"$tmp/err"
  local status=$?
  [ $status -eq 2 ] || { fail "$name: exit $status ($(head -c 300 "$tmp/err"))"; return; }
  grep -qF -- "$expected" "$tmp/err" || { fail "$name: stderr lacks '$expected': $(cat "$tmp/err")"; return; }
  [ -e "$tmp/bad" ] && { fail "$name: output written"; return; }
  echo "ok   $name: $(head -n 1 "$tmp/err" | head -c 200)"
}
expect_bad parcel_wider_than_cell "wider than a fluid cell" -- "$scene" "${small[@]}" --set 'domain.size_dp=[30,120,30]' --set particles.parcel_size=6
expect_bad too_few_parcels "at least 100" -- "$scene" "${small[@]}" --set particles.parcel_size=4 --set particles.solids_fraction=0.02
expect_bad empty_window "must be before run.end_time" -- "$scene" "${small[@]}" --set run.end_time_tref=0.2
expect_bad missing_model "drag_model" -- "$scene" "${small[@]}" --model "$tmp/nope.h5"
expect_bad missing_reference "--reference" -- "$scene" "${small[@]}" --reference "$tmp/nope"
[ $failures -eq 0 ] && echo "all cgd-coarse checks passed" || echo "$failures cgd-coarse check(s) failed"
exit $((failures > 0))
