#!/usr/bin/env bash
# Stability (b): a packed bed, <phi_p> = 0.55 (RSA to 0.25, then grown: sim/dem/placement.cpp), two-way
# coupled with the paper's parameters in a 16 x 32 x 16 d_p box, 5 x 10 x 5 cells (3.2 d_p). Beetstra's
# beta at phi = 0.55 is ~25x its dilute value: the stiffest drag a resolved run meets short of the floor.
# 6,980 DEM steps (0.005 s).
source "$(dirname "$0")/lib_stability.sh"
run_ok bed055 --set particles.solids_fraction=0.55 --set run.end_time=0.005
check bed055
echo "stability (b) packed bed phi = 0.55 two-way: passed"
