#!/usr/bin/env bash
# Regression test of a fixed engine bug: a fluid step cut short to land on a snapshot time or the end (sim/run.cpp time_loop_coupled: n_sub =
# min(n_sub, end_step - step), min(n_sub, dump_every - step % dump_every)) gets the void-fraction change
# of the whole previous fluid step as its d(eps)/dt: compute_drag deposits eps at the particles'
# positions at the start of the step, eps_old is the deposit at the start of the previous step, and the
# solver divides their difference by the new, short dt. A step of 1 DEM step after steps of ~2,000
# multiplies the continuity source by ~2,000: the fluid velocity and pressure in the snapshot written
# right after it (exactly the fields cgd-filter uses) are wrong by orders of magnitude.
# Fixed in sim/run.cpp: the DEM steps up to the next snapshot or the end are divided evenly over the
# fluid steps, so consecutive fluid steps differ by at most one DEM step.
# Check: a run whose end is one DEM step past a whole number of full fluid steps has fluid steps that
# differ by at most one DEM step, and ends with a fluid state comparable to a run of whole full steps
# (max |u| within 2x, pressure span within 3x).
source "$(dirname "$0")/lib_stability.sh"
common=(--set particles.solids_fraction=0.3 --set 'fluid.cells=[4,8,4]' --set fluid.courant=0.5
        --set contact.gamma_star=3e-4 --set particles.velocity_rms=1.0 --set run.dump_interval=0)
dt=2.1489886990891763e-07      # dt_DEM of gamma* = 3e-4; the fluid step from rest is 2,016 DEM steps
run_ok short "${common[@]}" --set run.end_time=$("$PY" -c "print((2016 * 5 + 1) * $dt)")
run_ok full "${common[@]}" --set run.end_time=$("$PY" -c "print(2016 * 6 * $dt)")
"$PY" - "$tmp/short" "$tmp/full" <<'PYEOF'
import glob, sys, h5py, numpy as np
def last(run):
    s = h5py.File(run + "/series.h5", "r")
    steps = np.diff(s["step"][:])
    f = h5py.File(sorted(glob.glob(run + "/snapshots/snap_*.h5"))[-1], "r")
    u, p = f["fluid/velocity"][:], f["fluid/pressure"][:]
    return steps, float(np.abs(u).max()), float(p.max() - p.min())
(ss, us, ps), (sf, uf, pf) = last(sys.argv[1]), last(sys.argv[2])
print(f"  fluid steps of the odd-length run (DEM steps): {sorted(set(ss.astype(int)))}, of the full run: {sorted(set(sf.astype(int)))}")
even = ss.max() - ss.min() <= 1
print(f"  odd-length run: max |u| {us:.3g} m/s, pressure span {ps:.3g} Pa")
print(f"  full run:       max |u| {uf:.3g} m/s, pressure span {pf:.3g} Pa")
ok = even and us < 2 * uf and ps < 3 * pf
print("passed" if ok else "FAIL: fluid steps of unequal length, or a corrupted fluid state in the last snapshot")
sys.exit(0 if ok else 1)
PYEOF
