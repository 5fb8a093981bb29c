#!/usr/bin/env bash
# Regression test of an engine bug found with issue 10: a coupled run whose end time is a whole number k of
# snapshot intervals, rounded to DEM steps separately from the interval, ended a few DEM steps after its
# last snapshot step (here 6,003 steps against 6 x 1,000), so its final fluid step was 3 DEM steps long
# after steps of ~390: that step's continuity source -- the eps change of the whole previous step over its
# own short dt (sim/run.cpp time_loop_coupled) -- spoiled the final snapshot's fluid fields. Fixed in
# sim/run.cpp (coupled_end_step): such runs end on the k-th snapshot step.
# Check: the run ends at step 6 x round(dump_interval / dt_DEM), its last fluid step is at least half the
# median one, and the usual stability checks hold.
source "$(dirname "$0")/lib_stability.sh"
run_ok final --set run.end_time=0.0043 --set run.dump_interval=7.166666666666667e-4
check final
"$PY" - "$tmp/final" <<'PYEOF'
import sys, h5py, numpy as np
s = h5py.File(sys.argv[1] + "/series.h5", "r")
p = s["params"].attrs
dt = float(p["dt_dem_s"])
every = round(float(p["dump_interval_s"]) / dt)
steps = s["step"][:]
lengths = np.diff(steps)
print(f"  last step {int(steps[-1])} (6 x {every} = {6 * every}; round(end/dt) = {round(float(p['end_time_s']) / dt)}); "
      f"fluid steps of {int(lengths.min())}..{int(lengths.max())} DEM steps, the last {int(lengths[-1])}")
ok = int(steps[-1]) == 6 * every and lengths[-1] >= 0.5 * np.median(lengths)
sys.exit(0 if ok else 1)
PYEOF
echo "final fluid step: passed"
