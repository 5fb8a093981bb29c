#!/usr/bin/env bash
# Stability (e): cells where the void fraction reaches its floor (eps_min = 0.3, coupler.hpp). A random
# packing cannot exceed phi ~ 0.64 on the paper's grid (TSC deposition over 3 cells of 3.33 d_p smooths
# it), so the floor is reached with a dense packing, <phi_p> = 0.60 (grown: sim/dem/placement.cpp), on
# cells smaller than a particle (0.8 d_p: 15 x 30 x 15 cells in 12 x 24 x 12 d_p), where the deposited
# phi fluctuates up to ~0.73. Two-way coupled, paper's contacts, 4,188 DEM steps (3 ms). The series must
# show floored_cells > 0, the snapshots cells at eps = 0.3 and a conserved mean eps, and the run stay sane.
source "$(dirname "$0")/lib_stability.sh"
run_ok floor --set particles.solids_fraction=0.60 --set 'domain.size_dp=[12,24,12]' --set 'fluid.cells=[15,30,15]' \
  --set run.end_time=0.003 --set run.dump_interval=0.001
check floor --expect-floored
echo "stability (e) void fraction at its floor: passed"
