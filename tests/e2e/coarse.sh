#!/usr/bin/env bash
# e2e: cgd-coarse
#  * alpha = 1 with a micro law reproduces cgd-generate bit for bit (the same engine and scene);
#  * a run stopped half-way and continued with --restart (end time extended) equals an uninterrupted
#    run bit for bit at 1 rank;
#  * --reference writes summary.h5 with the slip, its error and the cost; --model sets the model;
#  * refusals (exit 2, nothing written): a parcel wider than a cell, too few parcels, an empty window;
#  * --summarise RUN_DIR over the reference's own window gives the reference values a coarse run stored, and the
#    drift of its halves; over a later window (--from-tref) another window; refuses an existing -o, a non-run.
#  * --summarise FILTERED.h5 (a resolved run's filtered file, as shipped in data/filtered/): the whole box's slip at
#    each snapshot equals the series' slip_velocity at that time (to round-off: the same average, <eps u>/<eps> minus
#    the particles' mean velocity), and the summary is the time-weighted mean of those, recomputed here;
#    --reference FILTERED.h5 compares a coarse run with it; refusals (exit 2, nothing written): --from-tref with a
#    file, a file that is not a filtered file, a filtered file of two runs, too few snapshots for the batches, the
#    input as its own -o, a wrong --reference file (before the run).
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

# --summarise / --reference with a resolved run's filtered file: a run with a snapshot every 0.05 t_ref (16 in the
# filter's window from 0.25 t_ref: enough rows for 2 batches in each half)
filter=$binary_dir/cgd-filter
"$generate" "$scene" "${small[@]}" --set run.dump_interval_tref=0.05 --set run.end_time_tref=1 -o "$tmp/genf" >/dev/null 2>&1 || fail "cgd-generate (filtered)"
"$filter" "$tmp/genf" --from-tref 0.25 --quiet -o "$tmp/genf.h5" >/dev/null 2>&1 || fail "cgd-filter"
"$coarse" --summarise "$tmp/genf.h5" --batches 2 -o "$tmp/fsum.h5" >"$tmp/f.out" 2>&1 || { cat "$tmp/f.out"; fail "--summarise FILTERED.h5"; }
"$py" - "$tmp" <<'PY' && echo "ok   --summarise FILTERED.h5: the whole box's slip of every snapshot is the series' (round-off), the summary their time-weighted mean" || fail "--summarise FILTERED.h5 values"
import sys, h5py, numpy as np
d = sys.argv[1]
f = h5py.File(d + "/genf.h5", "r")
ps = f["whole_box/per_snapshot"]
t = f["snapshots/time_s"][()]
slip = ps["slip"][()].sum(axis=1) / ps["count"][()].sum(axis=1)
series = h5py.File(d + "/genf/series.h5", "r")
ts, ss = series["time"][()], series["slip_velocity"][()][:, 1]
for tk, sk in zip(t, slip):
    i = int(np.argmin(abs(ts - tk)))
    assert ts[i] == tk, (ts[i], tk)  # a series row at every snapshot
    assert abs(sk / ss[i] - 1) < 1e-12, (tk, sk, ss[i])
a = h5py.File(d + "/fsum.h5", "r").attrs
u_t = h5py.File(d + "/genf/series.h5", "r")["params"].attrs["u_t_m_s"]
w = np.append(np.diff(t), np.median(np.diff(t)))  # core/time_average.hpp: each row to the next, the last the median
mean = (w * slip).sum() / w.sum() / u_t
assert a["cgd_format"] == "coarse_summary" and abs(a["slip_over_ut"] / mean - 1) < 1e-12, (a["slip_over_ut"], mean)
assert a["window_start_s"] == t[0] and a["wall_s"] == 0 and a["batches"] == 2 and a["slip_stderr"] > 0
PY
"$coarse" "$scene" "${small[@]}" --set particles.parcel_size=2 --set run.end_time_tref=1 --reference "$tmp/genf.h5" --batches 2 -o "$tmp/cref" >/dev/null 2>&1 || fail "--reference FILTERED.h5"
"$py" -c "
import h5py
c = h5py.File('$tmp/cref/summary.h5').attrs; f = h5py.File('$tmp/fsum.h5').attrs
assert c['reference'] == '$tmp/genf.h5' and c['reference_slip_over_ut'] == f['slip_over_ut'], (c['reference_slip_over_ut'], f['slip_over_ut'])
assert abs(c['relative_error'] - (c['slip_over_ut'] / f['slip_over_ut'] - 1)) < 1e-12
" && echo "ok   --reference FILTERED.h5: the coarse run's error against the filtered file's slip" || fail "--reference FILTERED.h5 values"
"$coarse" --summarise "$tmp/genf.h5" --from-tref 0.5 -o "$tmp/nothing.h5" >/dev/null 2>"$tmp/err"; st=$?
[ $st -eq 2 ] && [ ! -e "$tmp/nothing.h5" ] && grep -q "from-tref" "$tmp/err" && echo "ok   --summarise FILTERED.h5 --from-tref is refused (exit 2): the window is the filter's" || fail "--from-tref with a file: $st"
"$coarse" --summarise "$tmp/genf/series.h5" -o "$tmp/nothing.h5" >/dev/null 2>"$tmp/err"; st=$?
[ $st -eq 2 ] && [ ! -e "$tmp/nothing.h5" ] && grep -q "not a filtered file" "$tmp/err" && echo "ok   --summarise of a file that is not a filtered file is refused (exit 2): $(head -n 1 "$tmp/err" | head -c 160)" || fail "--summarise series.h5: $st"
"$filter" "$tmp/genf" "$tmp/gen" --from-tref 0.25 --quiet -o "$tmp/pooled.h5" >/dev/null 2>&1 || fail "cgd-filter of two runs"
"$coarse" --summarise "$tmp/pooled.h5" -o "$tmp/nothing.h5" >/dev/null 2>"$tmp/err"; st=$?
[ $st -eq 2 ] && [ ! -e "$tmp/nothing.h5" ] && grep -q "2 runs" "$tmp/err" && echo "ok   --summarise of a filtered file of two runs is refused (exit 2): $(head -n 1 "$tmp/err" | head -c 160)" || fail "--summarise of a pooled file: $st"
"$coarse" --summarise "$tmp/genf.h5" --batches 9 -o "$tmp/nothing.h5" >/dev/null 2>"$tmp/err"; st=$?
[ $st -eq 2 ] && [ ! -e "$tmp/nothing.h5" ] && grep -q "fewer --batches" "$tmp/err" && echo "ok   --summarise FILTERED.h5 with too few snapshots for the batches is refused (exit 2)" || fail "--summarise, too few snapshots: $st"
cp "$tmp/genf.h5" "$tmp/genf_copy.h5"
"$coarse" --summarise "$tmp/genf_copy.h5" -o "$tmp/genf_copy.h5" --force >/dev/null 2>"$tmp/err"; st=$?
[ $st -eq 2 ] && cmp -s "$tmp/genf.h5" "$tmp/genf_copy.h5" && echo "ok   --summarise FILTERED.h5 -o FILTERED.h5 --force is refused (exit 2), the file untouched" || fail "--summarise over its own input: $st"

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
expect_bad reference_not_filtered "not a filtered file" -- "$scene" "${small[@]}" --reference "$tmp/genf/series.h5"
[ $failures -eq 0 ] && echo "all cgd-coarse checks passed" || echo "$failures cgd-coarse check(s) failed"
exit $((failures > 0))
