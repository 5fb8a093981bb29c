#!/usr/bin/env bash
# e2e (issue 11, items 3, 6 and 7): a short coupled run, a short quiescent run and a short dry run as a
# user makes them, then
#   - the --set of an alternative: sedimentation_demo gives run.end_time_tref and dump_interval_tref,
#     --set run.end_time / run.dump_interval (s) replace them and the run ends at the time given;
#   - run.xmf names every dataset of every snapshot's /particles and /fluid groups (h5py's listing);
#   - tools/render_snapshot.py draws both runs to PNG (two panels with fluid, one without) and
#     refuses bad input with exit status 2 and a message naming the file or option;
#   - tools/plot_series.py plots a dry run's energies, divides a quiescent run's slip by its own law's
#     terminal velocity (dry_settling: Stokes without buoyancy, 0.2555 m/s) and refuses to mix the two.
#
# Environment (set by CTest): CGD_SOURCE_DIR, CGD_BINARY_DIR.
set -u

source_dir=${CGD_SOURCE_DIR:-$(cd "$(dirname "$0")/../.." && pwd)}
binary_dir=${CGD_BINARY_DIR:-$source_dir/build}
generate=$binary_dir/cgd-generate
python=/usr/bin/python3
if [ ! -x "$generate" ]; then echo "SKIP: $generate not built"; exit 0; fi
if ! "$python" -c 'import h5py, matplotlib' 2>/dev/null; then echo "SKIP: $python lacks h5py or matplotlib"; exit 0; fi

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
failures=0
fail() { echo "FAIL $1"; failures=$((failures + 1)); }

# a coupled run of 2 ms in a small box, its times given in s on a scene that gives them in t_ref
"$generate" "$source_dir/data/scenes/sedimentation_demo.toml" --set 'domain.size_dp=[20,80,20]' \
  --set run.end_time=0.002 --set run.dump_interval=0.001 --quiet -o "$tmp/coupled" >"$tmp/coupled.log" 2>&1 ||
  { cat "$tmp/coupled.log"; fail "coupled run with --set run.end_time on a scene with run.end_time_tref"; }
"$generate" "$source_dir/data/scenes/dry_settling.toml" --set run.end_time=2e-5 --set run.dump_interval=1e-5 \
  --quiet -o "$tmp/dry" >"$tmp/dry.log" 2>&1 || { cat "$tmp/dry.log"; fail "dry run"; }

"$generate" "$source_dir/data/scenes/granular_gas.toml" --set run.end_time=1e-4 --quiet -o "$tmp/gas" \
  >"$tmp/gas.log" 2>&1 || { cat "$tmp/gas.log"; fail "granular gas run"; }

"$python" - "$tmp/coupled" "$tmp/dry" <<'PY' || fail "run.xmf against the snapshots"
import os, sys, h5py, xml.etree.ElementTree as ET
coupled, dry = sys.argv[1:]
with open(os.path.join(coupled, "scene.toml")) as f:
    scene = f.read()
assert "end_time = 0.002" in scene and "end_time_tref" not in scene, "the --set did not replace end_time_tref"
for run in (coupled, dry):
    frames = ET.parse(os.path.join(run, "run.xmf")).getroot().findall("./Domain/Grid/Grid")
    assert len(frames) == 3, (run, len(frames))
    for frame in frames:
        items = [i.text for i in frame.iter("DataItem") if i.get("Format") == "HDF"]
        file = items[0].split(":")[0]
        with h5py.File(os.path.join(run, file), "r") as f:
            everything = {"%s:/%s/%s" % (file, g, n) for g in ("particles", "fluid") if g in f for n in f[g]}
        missing = everything - set(items)
        assert not missing, (run, "not in run.xmf", sorted(missing))
        if run == coupled:
            for name in ("drag_coefficient", "fluid_velocity", "pressure_gradient"):
                assert "%s:/particles/%s" % (file, name) in items, name
print("ok   run.xmf names every dataset of every snapshot (coupled and dry)")
PY

render=$source_dir/tools/render_snapshot.py
"$python" "$render" "$tmp/coupled" -o "$tmp/coupled.png" --backend matplotlib >/dev/null && [ -s "$tmp/coupled.png" ] || fail "render coupled"
"$python" "$render" "$tmp/coupled/snapshots/snap_000000000.h5" -o "$tmp/phi.png" --color phi --backend matplotlib >/dev/null &&
  [ -s "$tmp/phi.png" ] || fail "render a snapshot file by local phi"
"$python" "$render" "$tmp/dry" -o "$tmp/dry.png" --color speed --backend matplotlib >/dev/null && [ -s "$tmp/dry.png" ] || fail "render dry"
"$python" - "$tmp/coupled.png" "$tmp/dry.png" <<'PY' || fail "picture sizes"
import sys, matplotlib.image as im
coupled, dry = (im.imread(p).shape for p in sys.argv[1:])
assert coupled[1] > 1.5 * dry[1], ("two panels with fluid, one without", coupled, dry)
PY

# ParaView's backend, where Debian's python3-paraview and Xvfb are installed (a virtual display is made)
if "$python" -c 'import paraview.simple' 2>/dev/null && command -v Xvfb >/dev/null; then
  env -u DISPLAY "$python" "$render" "$tmp/coupled" -o "$tmp/pv.png" --backend paraview >"$tmp/pv.out" 2>&1 &&
    [ -s "$tmp/pv.png" ] && grep -q "(ParaView)" "$tmp/pv.out" || { cat "$tmp/pv.out"; fail "render with ParaView"; }
  [ "$failures" -eq 0 ] && echo "ok   render_snapshot.py --backend paraview"
else
  echo "skip render_snapshot.py --backend paraview (no python3-paraview or no Xvfb)"
fi

# expect_bad NAME EXPECTED -- ARGS: render_snapshot.py ARGS exits 2 with EXPECTED on stderr
expect_bad() {
  local name=$1 expected=$2; shift 3
  "$python" "$render" "$@" >/dev/null 2>"$tmp/err"
  local status=$?
  if [ "$status" -ne 2 ] || ! grep -qF -- "$expected" "$tmp/err"; then
    fail "$name: status $status (expected 2), stderr: $(cat "$tmp/err")"
  else
    echo "ok   $name: $(head -n 1 "$tmp/err")"
  fi
}
expect_bad missing       "no such file or directory"         -- "$tmp/none" -o "$tmp/x.png"
expect_bad not-snapshot  "cgd_format = 'series'"             -- "$tmp/coupled/series.h5" -o "$tmp/x.png"
expect_bad phi-when-dry  "--color phi: the snapshot has no fluid grid" -- "$tmp/dry" -o "$tmp/x.png" --color phi
expect_bad slab-outside  "--slab-center 500: outside the box" -- "$tmp/dry" -o "$tmp/x.png" --slab-center 500
expect_bad unknown-color "invalid choice"                    -- "$tmp/dry" -o "$tmp/x.png" --color red
expect_bad unwritable    "-o $tmp/none/x.png: cannot write"  -- "$tmp/dry" -o "$tmp/none/x.png"
expect_bad not-a-backend "invalid choice"                    -- "$tmp/dry" -o "$tmp/x.png" --backend vtk

series=$source_dir/tools/plot_series.py
"$python" "$series" "$tmp/gas" -o "$tmp/gas.png" >"$tmp/gas.out" 2>&1 && [ -s "$tmp/gas.png" ] &&
  grep -q "dry run" "$tmp/gas.out" || { cat "$tmp/gas.out"; fail "plot_series.py on a dry run"; }
"$python" "$series" "$tmp/dry" -o "$tmp/quiescent.png" >"$tmp/q.out" 2>&1 &&
  grep -q "u_ref = u_t of stokes drag = 0.2555 m/s" "$tmp/q.out" || { cat "$tmp/q.out"; fail "quiescent slip scale"; }
"$python" "$series" "$tmp/coupled" -o "$tmp/coupled_slip.png" >"$tmp/c.out" 2>&1 &&
  grep -q "u_ref = u_t (Schiller-Naumann) = 0.2185 m/s" "$tmp/c.out" || { cat "$tmp/c.out"; fail "coupled slip scale"; }
"$python" "$series" "$tmp/gas" "$tmp/coupled" -o "$tmp/mixed.png" >/dev/null 2>"$tmp/mixed.err"
[ $? -eq 2 ] && grep -q "cannot share one plot" "$tmp/mixed.err" || fail "plot_series.py mixing dry and fluid runs"
[ "$failures" -eq 0 ] && echo "ok   plot_series.py: dry energies, quiescent and coupled slip scales, no mixing"

if [ "$failures" -ne 0 ]; then echo "$failures check(s) failed"; exit 1; fi
echo "all tool checks passed"
