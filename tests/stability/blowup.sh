#!/usr/bin/env bash
# Stability (f): a configuration the integrator cannot handle must end cleanly: exit status 1, a message
# naming the step and the particles, a diagnostic snapshot in snapshots/, the last good checkpoint kept
# (and usable: --restart from it meets the same blow-up at the same step), no completion marker.
# Contacts far too soft for the impact speeds: gamma* = 0.1 (k_n = 1.3e-4 N/m, 10^4 x softer than the
# paper's; t_c = 3.6 ms, dt_DEM = 72 us) with random initial velocities of 0.03 m/s rms: two particles
# closing at v overlap by v sqrt(m_eff/k_n) = 15 v/(m/s) diameters, so the 25 % blow-up limit
# (sim/dem/system.cpp) is crossed at ~0.017 m/s. A checkpoint at every fluid step
# (checkpoint_wall_s = 1e-6) makes the last good one the start of the failing fluid step (with this seed
# the blow-up is at DEM step 10, inside the fluid step that starts at step 9).
source "$(dirname "$0")/lib_stability.sh"
args=(--set contact.gamma_star=0.1 --set particles.velocity_rms=0.03 --set run.end_time=0.05
      --set run.dump_interval=0.01 --set run.checkpoint_wall_s=1e-6)

expect_blowup() {  # NAME: exit 1, the message, the diagnostic snapshot, the checkpoint; prints the step
  local name=$1 status=$2
  if [ "$status" -ne 1 ]; then echo "FAIL $name: exit status $status, expected 1"; cat "$tmp/$name.err"; exit 1; fi
  grep -q "numerical blow-up at step [0-9]* " "$tmp/$name.err" ||
    { echo "FAIL $name: stderr does not name the step"; cat "$tmp/$name.err"; exit 1; }
  grep -q "between particles [0-9]* and [0-9]*" "$tmp/$name.err" ||
    { echo "FAIL $name: stderr does not name the particles"; cat "$tmp/$name.err"; exit 1; }
  [ ! -e "$tmp/$name/DONE" ] || { echo "FAIL $name: a failed run wrote DONE"; exit 1; }
}

status=0; run fail "${args[@]}" || status=$?
expect_blowup fail $status
"$PY" - "$tmp/fail" "$tmp/fail.err" <<'PYEOF'
import glob, re, sys, h5py, numpy as np
run, err = sys.argv[1], open(sys.argv[2]).read()
step = int(re.search(r"numerical blow-up at step (\d+)", err).group(1))
a, b = map(int, re.search(r"between particles (\d+) and (\d+)", err).group(1, 2))
diag = glob.glob(run + "/snapshots/diagnostic_*.h5")
assert len(diag) == 1, f"expected one diagnostic snapshot, found {diag}"
with h5py.File(diag[0], "r") as h:
    ids = h["particles/id"][:]
    n = int(h["params"].attrs["particle_count"])
    assert len(ids) == n, f"diagnostic snapshot holds {len(ids)} particles, the run {n}"
    assert a in ids and b in ids, f"particles {a}, {b} not in the diagnostic snapshot"
    dstep = int(h.attrs["step"])
with h5py.File(run + "/checkpoint.h5", "r") as h:
    assert h.attrs["cgd_format"] in ("checkpoint", b"checkpoint")
    cstep = int(h.attrs["step"])
    assert len(h["particles/id"][:]) == n
    assert np.all(np.isfinite(h["particles/velocity"][:])), "the checkpoint kept holds non-finite velocities"
assert 0 < cstep <= step, f"checkpoint at step {cstep}, the blow-up at step {step}: not the last good state"
with h5py.File(run + "/series.h5", "r") as s:
    last = int(s["step"][-1])
    assert last <= step
print(f"  blow-up at step {step} (particles {a} and {b}); diagnostic snapshot {diag[0].split('/')[-1]} "
      f"(step attribute {dstep}); checkpoint kept at step {cstep}; series up to step {last}")
open(run + ".step", "w").write(str(step))
PYEOF
step=$(cat "$tmp/fail.step")

# the checkpoint kept is usable: --restart meets the same blow-up at the same step
status=0; run fail "${args[@]}" --restart || status=$?
expect_blowup fail $status
grep -q "numerical blow-up at step $step " "$tmp/fail.err" ||
  { echo "FAIL: --restart from the kept checkpoint did not fail at step $step:"; cat "$tmp/fail.err"; exit 1; }
echo "  --restart from the kept checkpoint: the same blow-up at step $step"

# 2 ranks: every rank agrees, exit status 1 (not an MPI abort), the same files
status=0; run fail2 --np 2 "${args[@]}" || status=$?
expect_blowup fail2 $status
ls "$tmp/fail2/snapshots/"diagnostic_*.h5 >/dev/null && [ -f "$tmp/fail2/checkpoint.h5" ] ||
  { echo "FAIL: 2 ranks: no diagnostic snapshot or checkpoint"; exit 1; }
echo "  2 ranks: $(grep -o 'numerical blow-up at step [0-9]*' "$tmp/fail2.err")"
echo "stability (f) blow-up ends with status 1, message, diagnostic snapshot, checkpoint kept: passed"
