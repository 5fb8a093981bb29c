#!/usr/bin/env bash
# Coupled CFD-DEM restart: a run killed with SIGKILL keeps every completed snapshot readable, and
# `--restart` continues from its last checkpoint to exactly the result of an uninterrupted run -- at 1 rank
# bit for bit: particle positions, velocities, spins, the coupling quantities at the particles (drag
# coefficient, fluid velocity, pressure gradient) and the fluid's velocity, pressure and void fraction.
# What makes it exact (sim/run.cpp): checkpoints are written at fluid-step boundaries and hold, besides
# the DEM state, the fluid's face velocities, pressure (the PCG warm start), eps^n and the Adams-Bashforth
# history (last explicit rate and dt); eps^{n+1}, the drag and the particles' fluid forces are recomputed
# from the particles; FFTW plans use FFTW_ESTIMATE (deterministic).
set -euo pipefail
. "$(dirname "$0")/lib/kill_when_checkpointed.sh"
BIN=${CGD_BINARY_DIR:?}/cgd-generate
PY=/usr/bin/python3
tmp=$(mktemp -d)
trap '[ -n "${KEEP:-}" ] || rm -rf "$tmp"' EXIT  # KEEP=1 keeps the run directories for inspection

# a small suspension (tests/scenes/small_suspension.toml): 16 x 24 x 16 d_p, 5 x 7 x 5 cells, 1,408 particles
# with random initial velocities (collisions and friction exercise the contact history), ~710 fluid steps and
# 46,900 DEM steps (~3 s), a snapshot every 0.015 s; the kill lands about half-way
SCENE=${CGD_SOURCE_DIR:?}/tests/scenes/small_suspension.toml
common=(--quiet)

"$BIN" "$SCENE" "${common[@]}" -o "$tmp/a" > "$tmp/a.log"

"$BIN" "$SCENE" "${common[@]}" --set run.checkpoint_wall_s=0.25 -o "$tmp/b" > "$tmp/b.log" &
pid=$!
kill_when_checkpointed "$pid" "$tmp/b" 4  # once a checkpoint and 4 snapshots are written

"$PY" - "$tmp/b" <<'PYEOF'
import glob, sys, h5py
files = sorted(glob.glob(sys.argv[1] + "/snapshots/snap_*.h5"))
assert files, "no snapshot before the kill"
for f in files:
    with h5py.File(f, "r") as h:
        n = h["particles/position"].shape[0]
        assert h["particles/velocity"].shape == (n, 3), f
        assert h["fluid/void_fraction"].ndim == 3, f
with h5py.File(sys.argv[1] + "/checkpoint.h5", "r") as h:
    step = int(h.attrs["step"])
    fluid_steps = int(h["fluid"].attrs["steps"])
print(f"killed run: {len(files)} readable snapshots, checkpoint at step {step} (fluid step {fluid_steps})")
open(sys.argv[1] + "/../restart_step", "w").write(str(step))
PYEOF

"$BIN" "$SCENE" "${common[@]}" --set run.checkpoint_wall_s=0.25 --restart -o "$tmp/b" > "$tmp/b2.log"
[ -f "$tmp/b/DONE" ] || { echo "FAIL: restarted run did not complete"; exit 1; }

"$PY" - "$tmp/a" "$tmp/b" "$(cat "$tmp/restart_step")" <<'PYEOF'
import glob, os, sys, h5py, numpy as np
a, b, restart_step = sys.argv[1], sys.argv[2], int(sys.argv[3])
fa = sorted(os.path.basename(f) for f in glob.glob(a + "/snapshots/snap_*.h5"))
fb = sorted(os.path.basename(f) for f in glob.glob(b + "/snapshots/snap_*.h5"))
assert fa == fb, (fa, fb)
particle_keys = ("position", "velocity", "angular_velocity", "drag_coefficient", "fluid_velocity", "pressure_gradient")
fluid_keys = ("velocity", "pressure", "void_fraction")
for name in fa:
    with h5py.File(f"{a}/snapshots/{name}") as ha, h5py.File(f"{b}/snapshots/{name}") as hb:
        ia, ib = np.argsort(ha["particles/id"][:]), np.argsort(hb["particles/id"][:])
        for key in particle_keys:
            xa, xb = ha["particles/" + key][:][ia], hb["particles/" + key][:][ib]
            if not np.array_equal(xa, xb):
                print(f"FAIL: {name} particles/{key} differs: max |diff| = {np.abs(xa - xb).max()}")
                sys.exit(1)
        for key in fluid_keys:
            xa, xb = ha["fluid/" + key][:], hb["fluid/" + key][:]
            if not np.array_equal(xa, xb):
                print(f"FAIL: {name} fluid/{key} differs: max |diff| = {np.abs(xa - xb).max()}")
                sys.exit(1)
# Series: every column that follows from the state must agree bit for bit. Known engine limitation
# (reported, sim/run.cpp): the row of the restart step is dropped by Series::truncate_after and written
# again by the restarted run before its first fluid step, and the report of the last fluid step is not
# checkpointed (dt_fluid, pressure_iterations, continuity_residual_rel come out 0 in that row);
# neighbor_rebuilds (DemSystem::rebuilds(), not checkpointed) counts from 0 again. Those differences are
# tolerated at exactly those rows and reported as a NOTE; anything else fails.
restart_row_only = {"dt_fluid", "pressure_iterations", "continuity_residual_rel"}
with h5py.File(a + "/series.h5") as sa, h5py.File(b + "/series.h5") as sb:
    assert np.array_equal(sa["time"][:], sb["time"][:]), "series rows differ in time"
    steps = sa["step"][:]
    rows = steps.shape[0]
    notes = []
    for key in sa.keys():
        if key == "params" or key.startswith("time_") or key == "wall_seconds":
            continue
        xa, xb = sa[key][:], sb[key][:]
        differ = np.where(np.any((xa != xb).reshape(rows, -1), axis=1))[0]
        if differ.size == 0:
            continue
        at = set(steps[differ].astype(np.int64).tolist())
        if key in restart_row_only and at == {restart_step}:
            notes.append(key)
        elif key == "neighbor_rebuilds" and min(at) == restart_step:
            notes.append(key + " (from the restart on)")
        else:
            print(f"FAIL: series column {key} differs at steps {sorted(at)[:5]} (restart at {restart_step})")
            sys.exit(1)
    if notes:
        print(f"NOTE: series diagnostics rewritten at the restart step {restart_step}: {', '.join(notes)}")
print(f"restarted coupled run matches the uninterrupted one bit for bit: {len(fa)} snapshots "
      f"(particles: {', '.join(particle_keys)}; fluid: {', '.join(fluid_keys)}), {rows} series rows")
PYEOF
