#!/usr/bin/env bash
# e2e: the banner and the final report describe what the run does (issue 11 item 2):
#  * the scene line is printed once;
#  * "series.h5: a row every fluid step" (coupled) / "every N DEM steps" (dry) matches the rows written;
#  * the memory estimate is within 20 % of the measured peak printed beside it;
#  * after a restart, the timing table has this session's and the whole run's seconds.
# Environment (set by CTest): CGD_SOURCE_DIR, CGD_BINARY_DIR.
set -u
source_dir=${CGD_SOURCE_DIR:-$(cd "$(dirname "$0")/../.." && pwd)}
binary_dir=${CGD_BINARY_DIR:-$source_dir/build}
bin=$binary_dir/cgd-generate
py=/usr/bin/python3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
failures=0
fail() { echo "FAIL $*"; failures=$((failures + 1)); }

coupled=(--set 'domain.size_dp=[30,120,30]' --set fluid.dx_over_dp=5 --set run.dump_interval_tref=0.25)
"$bin" "$source_dir/data/scenes/pipeline_demo.toml" "${coupled[@]}" --set run.end_time_tref=0.5 -o "$tmp/c" \
  >"$tmp/c.out" 2>/dev/null || fail "coupled run"
"$bin" "$source_dir/data/scenes/granular_gas.toml" --set run.end_time=7.18e-4 -o "$tmp/d" >"$tmp/d.out" 2>/dev/null ||
  fail "dry run"
"$bin" "$source_dir/data/scenes/pipeline_demo.toml" "${coupled[@]}" --set run.end_time_tref=1 --restart -o "$tmp/c" \
  >"$tmp/r.out" 2>/dev/null || fail "restarted run"

"$py" - "$tmp" <<'PY' || failures=$((failures + 1))
import re, sys, h5py
tmp = sys.argv[1]
ok = True
def check(cond, text):
    global ok
    print(("ok   " if cond else "FAIL ") + text)
    ok &= bool(cond)
for name, scene in (("c", "pipeline_demo"), ("d", "granular_gas"), ("r", "pipeline_demo")):
    out = open(f"{tmp}/{name}.out").read()
    check(len(re.findall(rf"^scene {scene} ", out, re.M)) == 1, f"{name}: the scene line is printed once")
    est, peak = map(float, re.search(r"estimated ([\d.]+) MiB, measured peak ([\d.]+) MiB", out).groups())
    check(abs(est - peak) <= 0.2 * peak, f"{name}: memory estimated {est} MiB, measured peak {peak} MiB (within 20 %)")
c = open(f"{tmp}/c.out").read()
with h5py.File(f"{tmp}/c/series.h5") as s, h5py.File(f"{tmp}/c/checkpoint.h5") as k:
    rows, fluid_steps = s["time"].shape[0], int(k["fluid"].attrs["steps"])
check("a row every fluid step" in c and "CFL-limited" in c and rows == fluid_steps + 1,
      f"coupled: 'a row every fluid step', {rows} rows for {fluid_steps} fluid steps (+ the initial row)")
d = open(f"{tmp}/d.out").read()
every = int(re.search(r"series.h5 +a row every (\d+) DEM steps", d).group(1))
with h5py.File(f"{tmp}/d/series.h5") as s:
    steps = s["step"][:].astype(int)
check(all(x % every == 0 for x in steps[:-1]) and len(steps) == steps[-1] // every + 1 + (steps[-1] % every != 0),
      f"dry: 'a row every {every} DEM steps' and the series has rows at steps {list(steps[:3])}..{steps[-1]}")
r = open(f"{tmp}/r.out").read()
check(re.search(r"^  phase +this session +whole run", r, re.M) and "restarted from the checkpoint" in r,
      "restart: the timing table has this session's and the whole run's columns")
sys.exit(0 if ok else 1)
PY

[ "$failures" -eq 0 ] || { echo "$failures failure(s)"; exit 1; }
echo "all banner checks passed"
