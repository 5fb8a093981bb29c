#!/usr/bin/env bash
# Stability (a): the densest of the paper's suspensions, <phi_p> = 0.40, two-way coupled, on 2 ranks.
# Paper parameters (gamma* = 1e-3, t* = 1/50, Co = 0.3, Beetstra, pressure-gradient force) in a
# 20 x 40 x 20 d_p box, 6 x 12 x 6 cells (3.33 d_p, as the paper); placement grows RSA packings above
# 0.30 (sim/dem/placement.cpp). 13,960 DEM steps (0.01 s); beta dt/rho_f is ~30 in these cells, so the
# implicit drag and the dt_fluid cap (dt beta_max/rho_p <= 0.5) are what is exercised.
source "$(dirname "$0")/lib_stability.sh"
run_ok dense040 --np 2 --set particles.solids_fraction=0.40 --set 'domain.size_dp=[20,40,20]' \
  --set 'fluid.cells=[6,12,6]' --set run.end_time=0.01 --set run.dump_interval=0.0025
check dense040
echo "stability (a) phi = 0.40 two-way on 2 ranks: passed"
