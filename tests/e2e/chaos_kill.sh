#!/usr/bin/env bash
# Kill it anywhere (issue 10, item 8): a 2-rank coupled run is SIGKILLed (mpirun and both ranks) at 20
# moments and restarted each time from its checkpoint. The moments are events of what the run writes, not
# timings: while a file is being written (a *.tmp beside a snapshot, checkpoint, series or run.xmf), right
# after a new checkpoint appeared, and at a random delay after the series was rewritten. Then:
#   * every snapshot left is readable (particles and fluid fields);
#   * the series has no gap and no duplicate row: its steps are exactly the uninterrupted run's;
#   * the final snapshot equals the uninterrupted 2-rank run's (to round-off: the same rank count restarts
#     bit for bit in practice; the tolerance, 1e-9 d_p and 1e-8 relative, is the coupled MPI test's).
# (The 1-rank bit-for-bit restart is tests/e2e/coupled_restart.sh.)
set -euo pipefail
BIN=${CGD_BINARY_DIR:?}/cgd-generate
MPIEXEC=${CGD_MPIEXEC:-mpirun}
PY=/usr/bin/python3
tmp=$(mktemp -d)
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
pid=
kill_run() {  # SIGKILL mpirun and every process of its session (the ranks have process groups of their own)
  [ -n "$pid" ] || return 0
  local pids
  pids=$(ps -o pid= -s "$pid" 2>/dev/null || true)
  kill -9 $pid $pids 2>/dev/null || true
  wait "$pid" 2>/dev/null || true
  pid=
}
trap 'kill_run; [ -n "${KEEP:-}" ] || rm -rf "$tmp"' EXIT

# the coupled scene of coupled_restart.sh (tests/scenes/small_suspension.toml), 0.2 s: 16 x 24 x 16 d_p,
# 5 x 7 x 5 cells (2 ranks: 4 + 3 rows), 1,408 particles, ~78,000 DEM steps, a snapshot every 0.02 s; every
# invocation, the restarts included, gives the same --set (a restart refuses a scene that differs)
SCENE=${CGD_SOURCE_DIR:?}/tests/scenes/small_suspension.toml
sets=(--set run.end_time=0.2 --set run.dump_interval=0.02)
run=$tmp/chaos

timeout 300 $MPIEXEC --allow-run-as-root --oversubscribe -np 2 "$BIN" "$SCENE" "${sets[@]}" --quiet -o "$tmp/ref" > /dev/null

# a file's identity: checkpoint.h5 and series.h5 are written under a temporary name and renamed into
# place, so each new version has a new inode (mtimes can coincide within the clock's resolution)
mtime() { stat -c '%i %.9Y' "$1" 2>/dev/null || echo none; }
tmp_file_present() { compgen -G "$run/*.tmp" > /dev/null || compgen -G "$run/snapshots/*.tmp" > /dev/null; }
RANDOM=10   # reproducible choice of moments
kills=0 fresh=0 modes=(0 0 0)
for cycle in $(seq 1 20); do
  restart=()
  if [ -f "$run/checkpoint.h5" ]; then restart=(--restart)
  else rm -rf "$run"; fresh=$((fresh + 1)); fi
  ckpt0=$(mtime "$run/checkpoint.h5") series0=$(mtime "$run/series.h5")
  # checkpoints every 0.02 s of wall time while being killed: each cycle advances the run by little, so 20
  # cycles stay well inside the run on a fast machine too (the interval may change on restart)
  setsid $MPIEXEC --allow-run-as-root --oversubscribe -np 2 "$BIN" "$SCENE" "${sets[@]}" --quiet "${restart[@]}" \
    --set run.checkpoint_wall_s=0.02 -o "$run" > "$tmp/cycle$cycle.log" 2>&1 &
  pid=$!
  mode=$((RANDOM % 3))
  deadline=$((SECONDS + 60))
  while [ $SECONDS -lt $deadline ] && kill -0 "$pid" 2>/dev/null; do
    case $mode in
      0) tmp_file_present && break ;;                                         # during a write
      1) [ -f "$run/checkpoint.h5" ] && [ "$(mtime "$run/checkpoint.h5")" != "$ckpt0" ] && break ;;  # after a checkpoint
      2) if [ -f "$run/series.h5" ] && [ "$(mtime "$run/series.h5")" != "$series0" ]; then
           sleep "0.$(printf %03d $((RANDOM % 100)))"; break; fi ;;          # between writes
    esac
    sleep 0.002
  done
  if ! kill -0 "$pid" 2>/dev/null; then
    wait "$pid" || true; pid=
    echo "FAIL: cycle $cycle: the run ended before it was killed (mode $mode): $(tail -n 2 "$tmp/cycle$cycle.log")"; exit 1
  fi
  kill_run
  kills=$((kills + 1)); modes[$mode]=$((modes[mode] + 1))
  [ ! -f "$run/DONE" ] || { echo "FAIL: cycle $cycle: DONE written before the run completed"; exit 1; }
done
# one more restart runs to the end
timeout 300 $MPIEXEC --allow-run-as-root --oversubscribe -np 2 "$BIN" "$SCENE" "${sets[@]}" --quiet --restart -o "$run" > "$tmp/final.log" 2>&1 ||
  { echo "FAIL: the final restart failed"; cat "$tmp/final.log"; exit 1; }
echo "killed $kills times (during a write: ${modes[0]}, after a checkpoint: ${modes[1]}, at a random delay: ${modes[2]}; fresh starts without a checkpoint: $fresh)"

"$PY" - "$tmp/ref" "$run" <<'PYEOF'
import glob, os, sys, h5py, numpy as np
ref, run = sys.argv[1], sys.argv[2]
snaps = sorted(glob.glob(run + "/snapshots/snap_*.h5"))
for f in snaps:
    with h5py.File(f, "r") as h:
        n = h["particles/id"].shape[0]
        for key in ("position", "velocity", "fluid_velocity"):
            assert h["particles/" + key].shape == (n, 3), f
        assert h["fluid/void_fraction"].ndim == 3 and np.all(np.isfinite(h["fluid/pressure"][:])), f
names = lambda d: sorted(os.path.basename(f) for f in glob.glob(d + "/snapshots/snap_*.h5"))
assert names(ref) == names(run), (names(ref), names(run))
with h5py.File(ref + "/series.h5") as a, h5py.File(run + "/series.h5") as b:
    sa, sb = a["step"][:], b["step"][:]
    dup = len(sb) - len(np.unique(sb))
    missing = sorted(set(sa.tolist()) - set(sb.tolist()))[:5]
    extra = sorted(set(sb.tolist()) - set(sa.tolist()))[:5]
    assert dup == 0 and not missing and not extra and np.all(np.diff(sb) > 0), \
        f"series: {dup} duplicate rows, missing steps {missing}, extra steps {extra}"
last = names(ref)[-1]
with h5py.File(f"{ref}/snapshots/{last}") as a, h5py.File(f"{run}/snapshots/{last}") as b:
    ia, ib = np.argsort(a["particles/id"][:]), np.argsort(b["particles/id"][:])
    L = a["params"].attrs["box_size_m"]
    d = float(a["params"].attrs["diameter_m"])
    dx = a["particles/position"][:][ia] - b["particles/position"][:][ib]
    dx = np.abs(dx - L * np.round(dx / L)).max() / d
    rel = lambda x, y: np.abs(x - y).max() / max(np.abs(x).max(), 1e-300)
    dv = rel(a["particles/velocity"][:][ia], b["particles/velocity"][:][ib])
    du = rel(a["fluid/velocity"][:], b["fluid/velocity"][:])
    dp = rel(a["fluid/pressure"][:], b["fluid/pressure"][:])
print(f"{len(snaps)} snapshots readable; series {len(sb)} rows, no gap or duplicate; final snapshot {last}: "
      f"max |dx|/d_p {dx:.2e}, |dv| {dv:.2e}, fluid |du| {du:.2e}, |dp| {dp:.2e} (relative)")
assert dx <= 1e-9 and dv <= 1e-8 and du <= 1e-8 and dp <= 1e-8, "final snapshot differs beyond round-off"
PYEOF
echo "chaos kill test: passed"
