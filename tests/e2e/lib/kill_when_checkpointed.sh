# Sourced by the restart tests (e2e_kill_restart, e2e_coupled_restart); not a test itself (tests/e2e/*.sh are).
#
# kill_when_checkpointed PID DIR SNAPSHOTS: SIGKILL the run PID writing DIR once DIR holds a checkpoint and
# SNAPSHOTS complete snapshots -- on what the run wrote, not after a time (which flakes on a slow or a fast
# machine); the loop's 300 s limit only guards against a hang. Exits 1 when the run finished before the kill
# (lengthen it) or wrote no checkpoint.
kill_when_checkpointed() {
  local pid=$1 dir=$2 want=$3 snaps
  for _ in $(seq 1 30000); do
    snaps=$(ls "$dir/snapshots" 2>/dev/null | grep -c '^snap_.*\.h5$' || true)
    [ -f "$dir/checkpoint.h5" ] && [ "$snaps" -ge "$want" ] && break
    kill -0 "$pid" 2>/dev/null || break
    sleep 0.01
  done
  kill -9 "$pid" 2>/dev/null || true
  wait "$pid" || true
  if [ -f "$dir/DONE" ]; then echo "FAIL: the run finished before it was killed; lengthen it"; exit 1; fi
  [ -f "$dir/checkpoint.h5" ] || { echo "FAIL: no checkpoint written before the kill"; exit 1; }
}
