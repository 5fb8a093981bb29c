#!/usr/bin/env bash
# --restart checks the scene (issue 10, item 3): a restart continues the same simulation, so it refuses --
# exit 2, naming each differing key, nothing written -- a scene whose physics differs from the checkpoint's
# (before: a changed grid read the wrong rows and failed later about particle volume; a changed restitution
# was accepted and the clock jumped, time = step x the new dt; a refused restart still rewrote scene.toml).
# Only the run's end time and its snapshot, series and checkpoint intervals may change. A restart of a
# completed run with nothing left to do writes nothing (before: scene.toml, the series' scene and DONE were
# rewritten for steps that never ran). `--restart -o DIR` alone takes the scene from the run and keeps its
# name (before: restarting from the run's own scene.toml renamed the scene "scene"). A different rank count
# stays allowed.
#
# Environment (set by CTest): CGD_SOURCE_DIR, CGD_BINARY_DIR, CGD_MPIEXEC (optional).
set -euo pipefail
BIN=${CGD_BINARY_DIR:?}/cgd-generate
PY=/usr/bin/python3
MPIEXEC=${CGD_MPIEXEC:-mpirun}
tmp=$(mktemp -d)
trap '[ -n "${KEEP:-}" ] || rm -rf "$tmp"' EXIT
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1

# a small coupled suspension, tests/scenes/small_suspension.toml with 16 x 32 x 16 d_p, 5 x 10 x 5 cells,
# <phi> = 0.05, soft contacts (dt_DEM 2.5 us), 4,000 steps; every invocation gives these --set first (a
# restart refuses a scene that differs), and the checks' own --set after them
scene=("${CGD_SOURCE_DIR:?}/tests/scenes/small_suspension.toml" --set 'domain.size_dp=[16,32,16]'
       --set particles.solids_fraction=0.05 --set particles.velocity_rms=0.02 --set 'fluid.cells=[5,10,5]'
       --set run.end_time=0.01 --set run.dump_interval=0.005)
run=$tmp/run
failures=0
fail() { echo "FAIL $*"; failures=$((failures + 1)); }
state() { (cd "$run" && find . -type f | sort | xargs sha256sum); }

timeout 120 "$BIN" "${scene[@]}" --quiet -o "$run" > "$tmp/first.log"
[ -f "$run/DONE" ] || { echo "FAIL: the first run did not complete"; exit 1; }
state > "$tmp/state0"

# expect_refused NAME SUBSTRING... -- ARGS: exit 2, each SUBSTRING on stderr, the run directory untouched
expect_refused() {
  local name=$1; shift
  local want=()
  while [ "$1" != "--" ]; do want+=("$1"); shift; done
  shift
  local status=0
  timeout 120 "$BIN" "$@" --quiet >"$tmp/$name.out" 2>"$tmp/$name.err" || status=$?
  local ok=1
  [ $status -eq 2 ] || { fail "$name: exit status $status, expected 2"; ok=0; }
  for w in "${want[@]}"; do grep -qF -- "$w" "$tmp/$name.err" || { fail "$name: stderr lacks \"$w\""; ok=0; }; done
  state | cmp -s - "$tmp/state0" || { fail "$name: the run directory changed"; ok=0; }
  [ $ok -eq 1 ] && echo "ok   $name: $(tr '\n' ' ' < "$tmp/$name.err" | cut -c1-300)"
  [ $ok -eq 1 ] || sed 's/^/     /' "$tmp/$name.err"
}

expect_refused restitution "contact.restitution = 0.9 in the checkpoint, 0.5 now" -- \
  "${scene[@]}" --restart -o "$run" --set contact.restitution=0.5 --set run.end_time=0.02
expect_refused grid "fluid.cells = [5, 10, 5] in the checkpoint, [5, 12, 5] now" -- \
  "${scene[@]}" --restart -o "$run" --set 'fluid.cells=[5,12,5]' --set run.end_time=0.02
expect_refused two-keys "2 key(s)" "contact.friction" "particles.seed" -- \
  "${scene[@]}" --restart -o "$run" --set contact.friction=0.2 --set particles.seed=4
expect_refused completed-with-set "contact.friction" -- "${scene[@]}" --restart -o "$run" --set contact.friction=0.2
expect_refused end-before-checkpoint "before the checkpoint's time" -- "${scene[@]}" --restart -o "$run" --set run.end_time=0.005

# a completed run restarted with only an output interval changed: nothing to do, nothing written
status=0
timeout 120 "$BIN" "${scene[@]}" --restart -o "$run" --set run.dump_interval=0.0025 --quiet > "$tmp/noop.out" 2>&1 || status=$?
if [ $status -eq 0 ] && grep -q "already complete" "$tmp/noop.out" && state | cmp -s - "$tmp/state0"; then
  echo "ok   completed-run: $(head -n 1 "$tmp/noop.out")"
else
  fail "completed-run: status $status, directory unchanged: $(state | cmp -s - "$tmp/state0" && echo yes || echo no)"
  cat "$tmp/noop.out"
fi

# --restart -o DIR alone: the scene from the run (its scene.toml), extended with --set; the name is kept
status=0
timeout 120 "$BIN" --restart -o "$run" --set run.end_time=0.015 --quiet > "$tmp/alone.out" 2> "$tmp/alone.err" || status=$?
[ $status -eq 0 ] || { fail "restart -o DIR alone: status $status"; cat "$tmp/alone.err"; }
# and on 2 ranks (a different rank count than the checkpoint's): allowed
status=0
timeout 120 $MPIEXEC --allow-run-as-root --oversubscribe -np 2 "$BIN" "${scene[@]}" --restart -o "$run" \
  --set run.end_time=0.02 --quiet > "$tmp/np2.out" 2> "$tmp/np2.err" || status=$?
[ $status -eq 0 ] || { fail "restart on 2 ranks: status $status"; cat "$tmp/np2.err"; }
"$PY" - "$run" <<'PYEOF' || failures=$((failures + 1))
import glob, sys, h5py, numpy as np
run = sys.argv[1]
with h5py.File(run + "/series.h5") as s:
    t, step = s["time"][:], s["step"][:]
    name = s["params"].attrs["scene_name"]
    name = name.decode() if isinstance(name, bytes) else name
    dt = float(s["params"].attrs["dt_dem_s"])
assert np.all(np.diff(step) > 0), "series steps not increasing"
assert abs(t[-1] - 0.02) <= 2.5 * dt, f"series ends at {t[-1]}, expected 0.02"  # 4 x round(0.005/dt) steps
assert np.allclose(t, step * dt, rtol=0, atol=1e-15), "time != step x dt"
assert name == "small_suspension", f"scene renamed to {name!r}"
snaps = sorted(glob.glob(run + "/snapshots/snap_*.h5"))
for f in snaps:
    with h5py.File(f) as h:
        n = h["params"].attrs["scene_name"]
        n = n.decode() if isinstance(n, bytes) else n
        assert n == "small_suspension", f"{f}: scene renamed to {n!r}"
print(f"ok   continued runs (-o DIR alone to 0.015 s, 2 ranks to 0.02 s): {len(t)} series rows, {len(snaps)} snapshots, scene name kept")
PYEOF
grep -q "^end_time = 0.02" "$run/scene.toml" || fail "scene.toml does not hold the extended end time"

[ $failures -eq 0 ] || { echo "$failures restart check(s) failed"; exit 1; }
echo "restart scene checks passed"
