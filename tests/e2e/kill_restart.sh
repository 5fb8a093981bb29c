#!/usr/bin/env bash
# A run killed with SIGKILL at an arbitrary moment keeps every completed snapshot readable, and
# `--restart` continues from its last checkpoint to exactly the result of an uninterrupted run
# (1 rank: bit for bit, positions, velocities, spins and hence the contact history that shaped them).
set -euo pipefail
. "$(dirname "$0")/lib/kill_when_checkpointed.sh"
BIN=${CGD_BINARY_DIR:?}/cgd-generate
SCENE=${CGD_SOURCE_DIR:?}/data/scenes/granular_gas.toml
PY=/usr/bin/python3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# granular gas with friction: 30,000 steps, a snapshot every 3,000
common=(--set run.end_time=0.02154 --set run.dump_interval=0.002154 --quiet)

"$BIN" "$SCENE" "${common[@]}" -o "$tmp/a" > "$tmp/a.log"

"$BIN" "$SCENE" "${common[@]}" --set run.checkpoint_wall_s=0.25 -o "$tmp/b" > "$tmp/b.log" &
pid=$!
kill_when_checkpointed "$pid" "$tmp/b" 2  # once a checkpoint and 2 snapshots are written

# every completed snapshot (renamed into place) is readable; temporary files may be left behind
"$PY" - "$tmp/b" <<'PYEOF'
import glob, sys, h5py
files = sorted(glob.glob(sys.argv[1] + "/snapshots/snap_*.h5"))
assert files, "no snapshot before the kill"
for f in files:
    with h5py.File(f, "r") as h:
        n = h["particles/position"].shape[0]
        assert h["particles/velocity"].shape == (n, 3), f
with h5py.File(sys.argv[1] + "/checkpoint.h5", "r") as h:
    step = int(h.attrs["step"])
print(f"killed run: {len(files)} readable snapshots, checkpoint at step {step}")
PYEOF

"$BIN" "$SCENE" "${common[@]}" --set run.checkpoint_wall_s=0.25 --restart -o "$tmp/b" > "$tmp/b2.log"
[ -f "$tmp/b/DONE" ] || { echo "FAIL: restarted run did not complete"; exit 1; }

"$PY" - "$tmp/a" "$tmp/b" <<'PYEOF'
import glob, os, sys, h5py, numpy as np
a, b = sys.argv[1], sys.argv[2]
fa = sorted(os.path.basename(f) for f in glob.glob(a + "/snapshots/snap_*.h5"))
fb = sorted(os.path.basename(f) for f in glob.glob(b + "/snapshots/snap_*.h5"))
assert fa == fb, (fa, fb)
for name in fa:
    with h5py.File(f"{a}/snapshots/{name}") as ha, h5py.File(f"{b}/snapshots/{name}") as hb:
        ia, ib = np.argsort(ha["particles/id"][:]), np.argsort(hb["particles/id"][:])
        for key in ("position", "velocity", "angular_velocity"):
            xa, xb = ha["particles/" + key][:][ia], hb["particles/" + key][:][ib]
            if not np.array_equal(xa, xb):
                print(f"FAIL: {name} {key} differs: max |diff| = {np.abs(xa - xb).max()}")
                sys.exit(1)
with h5py.File(a + "/series.h5") as sa, h5py.File(b + "/series.h5") as sb:
    assert np.array_equal(sa["time"][:], sb["time"][:]), "series rows differ in time"
    assert np.array_equal(sa["kinetic_energy"][:], sb["kinetic_energy"][:]), "series energies differ"
    rows = sa["time"].shape[0]
print(f"restarted run matches the uninterrupted one bit for bit: {len(fa)} snapshots, {rows} series rows")
PYEOF
