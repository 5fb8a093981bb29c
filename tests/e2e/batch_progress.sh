#!/usr/bin/env bash
# e2e: progress in a batch log (issue 11 item 1). With stderr not a terminal (here a file), a run prints a
# header naming the columns and then a progress line every --progress-interval seconds of wall time, the
# last one at the final step; each line has a value under every header column (step, time in s and t_ref,
# steps/s, ETA, slip/u_t, kinetic energy, overlap, max phi, fluid step). --quiet prints neither the
# progress nor the banner: stderr stays empty and stdout holds the final summary only. An interval that
# is not > 0 is bad input (exit 2).
# Environment (set by CTest): CGD_SOURCE_DIR, CGD_BINARY_DIR.
set -u
source_dir=${CGD_SOURCE_DIR:-$(cd "$(dirname "$0")/../.." && pwd)}
binary_dir=${CGD_BINARY_DIR:-$source_dir/build}
bin=$binary_dir/cgd-generate
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
failures=0
fail() { echo "FAIL $*"; failures=$((failures + 1)); }
scene=$source_dir/data/scenes/pipeline_demo.toml
# a coupled run of a few seconds (about 40,000 DEM steps)
args=(--set 'domain.size_dp=[30,120,30]' --set fluid.dx_over_dp=5 --set run.end_time_tref=4)

"$bin" "$scene" "${args[@]}" --progress-interval 0.2 -o "$tmp/batch" >"$tmp/batch.out" 2>"$tmp/batch.err" ||
  fail "the batch run failed: $(cat "$tmp/batch.err")"
/usr/bin/python3 - "$tmp/batch.err" "$tmp/batch/series.h5" <<'PY' || failures=$((failures + 1))
import sys, h5py
lines = open(sys.argv[1]).read().splitlines()
header = [l for l in lines if l.startswith("#")]
assert len(header) == 1, f"expected one header line, got {header}"
names = header[0][1:].split()
expected = ["step", "time_s", "time_tref", "steps/s", "ETA", "slip_y/u_t", "kinetic_J", "overlap/d", "max_phi", "dt_fluid_s"]
assert names == expected, names
rows = [l.split() for l in lines[lines.index(header[0]) + 1:]]
assert len(rows) >= 3, f"expected at least 3 progress lines at 0.2 s intervals, got {len(rows)}:\n" + "\n".join(lines)
for r in rows:
    assert len(r) == len(names), f"line {r} does not fill the {len(names)} columns"
with h5py.File(sys.argv[2]) as f:
    end_step = int(f["step"][-1])
    slip_end = f["slip_velocity"][-1, 1]
    u_t = f["params"].attrs["u_t_m_s"]
steps = [int(r[0]) for r in rows]
assert steps == sorted(steps) and steps[-1] == end_step, (steps, end_step)
assert abs(float(rows[-1][names.index("slip_y/u_t")]) - slip_end / u_t) < 1e-3 * abs(slip_end / u_t), "slip differs from the series"
assert any(r[names.index("ETA")] != "--:--" for r in rows), "no line has an ETA"
print(f"ok   batch log: header and {len(rows)} progress lines, the last at the final step {end_step}:")
print("       " + header[0] + "\n       " + "\n       ".join(lines[-2:]))
PY

"$bin" "$scene" "${args[@]}" --set run.end_time_tref=1 --progress-interval 0.2 --quiet -o "$tmp/quiet" \
  >"$tmp/quiet.out" 2>"$tmp/quiet.err" || fail "the quiet run failed: $(cat "$tmp/quiet.err")"
if [ -s "$tmp/quiet.err" ]; then
  fail "--quiet: stderr is not empty: $(head -n 3 "$tmp/quiet.err")"
elif grep -q "^effects\|^MPI ranks" "$tmp/quiet.out"; then
  fail "--quiet: the banner was printed"
elif ! grep -q "^timing" "$tmp/quiet.out"; then
  fail "--quiet: no final summary on stdout"
else
  echo "ok   --quiet: no progress, no banner; the final summary only ($(wc -l <"$tmp/quiet.out") lines)"
fi

# a progress interval that is not a positive number of seconds is bad input: exit 2, nothing written
"$bin" "$scene" "${args[@]}" --progress-interval 0 -o "$tmp/zero" >/dev/null 2>"$tmp/zero.err"
status=$?
if [ "$status" -eq 2 ] && grep -q -- "--progress-interval: 0 is not allowed" "$tmp/zero.err" && [ ! -e "$tmp/zero" ]; then
  echo "ok   --progress-interval 0: exit 2, $(head -n 1 "$tmp/zero.err")"
else
  fail "--progress-interval 0: exit $status, stderr: $(cat "$tmp/zero.err")"
fi

[ "$failures" -eq 0 ] || { echo "$failures failure(s)"; exit 1; }
echo "all batch-progress checks passed"
