#!/usr/bin/env bash
# Stability of coarse-grid CFD-DPM (cgd-coarse), the hard cases of docs/coarse.md, each a short run that
# must stay sane (the shared checks: no NaN, bounded energy and slip, void fraction in [floor, 1],
# continuity, overlaps), or be refused up front with the reason:
#  (a) alpha = 8 parcels at <phi> = 0.40 on a 16 d_p grid (4 x 8 x 4 cells, 782 parcels, dense placement);
#  (b) a parcel packing that reaches the void-fraction floor: alpha = 3 at <phi> = 0.60 on cells about as
#      wide as a parcel (3.2 d_p; deposited phi up to 0.68), with the floor raised to 0.35 (numerics key);
#  (c) a filtered law with h near 1: radl2014 at <phi> = 0.40 (h = 0.94) on 64 d_p cells (F = 0.063,
#      H = 0.85: beta_bar = 0.15 beta_micro), alpha = 8: the implicit drag and the step cap stay sane;
#  (d) the coarsest grids: 3 x 3 x 3 cells (the TSC kernel's width) and 2 x 2 x 2 (the kernel wraps);
#  (e) a particle-phase pressure ([particle_stress], P_s = 100 Pa) on (a), and on (b), where cells pass close packing:
#      without the stiffness cap of core/particle_stress.hpp the second blew up at its first step (an overlap of
#      95 % of the diameter: tau' ~ P_s / eps beyond phi_cp), with it it must stay sane. The packing stores pressure
#      energy that the energy bound does not count (it releases 10 x the bound's kinetic energy, a rms speed of
#      0.009 m/s = 0.04 u_t): the speed and slip caps stand in for it there.
source "$(dirname "$0")/lib_stability.sh"
GEN=$BUILD/cgd-coarse
[ -x "$GEN" ] || { echo "FAIL: $GEN not built"; exit 1; }
window=(--set run.sampling_start=0)

run_ok parcels_dense "${window[@]}" --set particles.parcel_size=8 --set particles.solids_fraction=0.40 \
  --set 'domain.size_dp=[64,128,64]' --set 'fluid.cells=[4,8,4]' --set run.end_time=0.004 --set run.dump_interval=0.002
check parcels_dense
run_ok parcels_floor "${window[@]}" --set particles.parcel_size=3 --set particles.solids_fraction=0.60 \
  --set 'domain.size_dp=[32,64,32]' --set 'fluid.cells=[10,20,10]' --set numerics.void_fraction_floor=0.35 \
  --set run.end_time=0.004 --set run.dump_interval=0.002
check parcels_floor --expect-floored
run_ok filtered_h_near_1 "${window[@]}" --set fluid.drag=radl2014 --set particles.parcel_size=8 \
  --set particles.solids_fraction=0.40 --set 'domain.size_dp=[192,192,192]' --set 'fluid.cells=[3,3,3]' \
  --set run.end_time=0.004 --set run.dump_interval=0.002
check filtered_h_near_1
run_ok coarsest "${window[@]}" --set particles.parcel_size=2 --set particles.solids_fraction=0.10 \
  --set 'domain.size_dp=[24,24,24]' --set 'fluid.cells=[3,3,3]' --set run.end_time=0.004 --set run.dump_interval=0.002
check coarsest
# two cells per axis: the TSC kernel wraps onto itself (cells c - 1 and c + 1 coincide), still a partition
# of unity, so volume and momentum stay conserved; the run must stay sane like the others
run_ok two_cells "${window[@]}" --set particles.parcel_size=2 --set particles.solids_fraction=0.10 \
  --set 'domain.size_dp=[24,24,24]' --set 'fluid.cells=[2,2,2]' --set run.end_time=0.004 --set run.dump_interval=0.002
check two_cells
stress=(--set 'particle_stress.model="harris-crighton"' --set particle_stress.p_s=100)
run_ok stress_dense "${window[@]}" "${stress[@]}" --set particles.parcel_size=8 --set particles.solids_fraction=0.40 \
  --set 'domain.size_dp=[64,128,64]' --set 'fluid.cells=[4,8,4]' --set run.end_time=0.004 --set run.dump_interval=0.002
check stress_dense
run_ok stress_packed "${window[@]}" "${stress[@]}" --set particles.parcel_size=3 --set particles.solids_fraction=0.60 \
  --set 'domain.size_dp=[32,64,32]' --set 'fluid.cells=[10,20,10]' --set numerics.void_fraction_floor=0.35 \
  --set run.end_time=0.004 --set run.dump_interval=0.002
check stress_packed --expect-floored --stored-energy
echo "stability: coarse-grid hard cases passed"
