#!/usr/bin/env bash
# Stability (c): contacts 100x stiffer than the paper's (gamma* = 1e-4 instead of 1e-3: k_n ~ 1/gamma*^2,
# so k_n = 127.6 N/m and t_c, dt_DEM 10x smaller: dt = 7.16e-8 s, ~3,900 DEM sub-steps per fluid step)
# at <phi_p> = 0.20 with random initial velocities of 0.5 m/s rms (frequent, energetic collisions),
# two-way coupled, 16 x 32 x 16 d_p box. 27,920 DEM steps (2 ms).
source "$(dirname "$0")/lib_stability.sh"
run_ok stiff --set particles.solids_fraction=0.2 --set contact.gamma_star=1e-4 --set particles.velocity_rms=0.5 \
  --set run.end_time=0.002 --set run.dump_interval=0.001
check stiff
echo "stability (c) gamma* = 1e-4 (t_c, dt 10x smaller): passed"
