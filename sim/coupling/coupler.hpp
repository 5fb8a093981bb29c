#pragma once
// Two-way coupling of the DEM and the fluid grid, once per fluid step (models.md, model A):
//
//   1. deposit   phi_c = sum_p V_p w_pc / V_cell (TSC, core/tsc_kernel.hpp); eps = 1 - phi_c, with a floor
//                eps_min applied conservatively (the volume the floor adds is taken back, in
//                proportion, from the cells above the floor, so sum eps is unchanged and the fluid's
//                continuity stays exact);
//   2. drag      per particle: eps_p and u_p = sum_c w_pc u_c (cell-centred u^n), beta_p = law(phi_p,
//                |u_p - v_p|) (core/drag.hpp; filtered laws core/filtered_drag.hpp; with drag_own_deposit off
//                phi_p less the particle's own share V_p w_pc^2 summed over its cells), deposited as the cells' implicit drag
//                B_c = sum_p beta_p V_p w_pc / V_cell and B_c V_c = sum_p beta_p V_p v_p w_pc / V_cell;
//   3. fluid     step with these (sim/fluid/solver.hpp; drag implicit: B dt/rho_f >> 1 is fine);
//   4. forces    per particle, from u^{n+1} and p^{n+1} interpolated with the same weights:
//                a_p = beta_p V_p (u_p^{n+1} - v_p)/m  - V_p grad p_p / m  +  g (1 - rho_mix/rho_p),
//                held constant over the DEM sub-steps of the fluid step.
// Momentum: the fluid's drag impulse dt sum_faces B_f (V_f - u_f^{n+1}) V_cell equals minus the
// particles' dt sum_p beta_p V_p (u_p^{n+1} - v_p) exactly in exact arithmetic, because face values
// are means of the two cells (solver.hpp), cell-centred u is the mean of the two faces, and
// deposition and interpolation use the same weights (transposes). Periodic driving (models.md): the
// mean pressure gradient rho_mix g is removed from p; the fluid gets eps (rho_f - rho_mix) g, each
// particle -V_p rho_mix g besides m g, so the net force on the box is zero.
// Cost (issue 17): each particle's TSC stencil (first cells and offsets, exchange.hpp) is computed once
// per fluid step, at the deposit of step 1, and serves steps 2 and 4 (the particles do not move between
// them); the cell fields a particle reads (u, grad p, phi) are stored together, one cache line per cell,
// and so are the ones it deposits (B, B V), so steps 2 and 4 are one pass each over the particles. The
// sums are the same, in the same order, as with one field at a time: the results are bit for bit those
// of the kernel evaluated per field.
// The drift-velocity law (fluid.drag = "drift", core/drag.hpp above the law table; docs/closure.md "The
// drift-velocity closure"), and only it, adds to step 1 the deposit of the particles' velocities with the same
// weights and in the same order as phi, vbar_c = sum_p V_p w_pc v_p / sum_p V_p w_pc (a cell with no deposit: its
// cell-centred u_c, i.e. zero slip), and to step 2 its interpolation vbar_p = sum_c w_pc vbar_c, the cell slip
// s~_p = u_p - vbar_p and the shift d_p = H(phi_p, |s~_p|/u_t) s~_p (s~_p frozen at the deposit). The particle then
// moves as under the micro law with v_p + d_p in place of v_p: the cells get B_c = sum_p beta_p V_p w_pc / V_cell and
// B_c V_c = sum_p beta_p V_p (v_p + d_p) w_pc / V_cell, the particle a_p = beta_p V_p (u_p^{n+1} - v_p - d_p)/m + ...,
// so the momentum argument below holds unchanged (d_p enters both sides with the same weights). With every other
// law nothing of this is allocated or done, and their results are those of the code without it, bit for bit.
// The particle-phase pressure ([particle_stress], core/particle_stress.hpp), and only it, adds to step 1 the
// potential mu_c = mu(phi_c) of each cell's raw deposit and each particle's a_p = -(V_p/m_p) sum_c mu_c grad w_pc
// (the gradient of the cells' free energy; MP-PIC's -grad tau / (rho_p phi) in the continuum limit, Snider 2001),
// held over the fluid step and added in step 4. The particles' forces need not sum to zero on a fixed grid (the
// energy is not invariant under a shift of all particles against the cells), so the sum over all particles is
// taken off each particle equally: the stress is internal and moves no momentum into or out of the particle phase.
// Parallel runs (issue 25): the coupler's grid is the whole grid on every rank (exchange.hpp), because the DEM
// slabs are chosen to balance the particles (sim/dem/system.hpp), not to match the fluid's FFTW rows. Each rank
// deposits its particles on the whole grid; the deposits are folded (periodic ghost rows) and summed over the
// ranks onto the fluid rows each rank owns, where eps, the floor and B, V are formed as on one rank; the cell
// fields the particles read (u, grad p, phi; the drift law's vbar_c; the stress potential mu_c) are computed on
// the owned rows and gathered to every rank. Across rank counts the sums run in another order (round-off, as the
// fluid's FFTs); at one rank the arithmetic is that of a single slab, and for a given rank count it is fixed.
// One-way coupling: steps 1-2 still give eps and the particle drag, but the fluid is solved as a pure
// fluid (B = 0 and eps = 1 in its equations: a fluid that gets out of the particles' way without being
// pushed develops a growing displacement flow), with hydrostatic driving (G = rho_f g; sim/coupled_step.hpp
// periodic_driving, which also states the driving without the pressure-gradient force).
#include <array>
#include <memory>
#include <vector>

#include "core/drag.hpp"
#include "core/filtered_drag.hpp"
#include "core/particle_stress.hpp"
#include "core/scene.hpp"
#include "sim/coupling/exchange.hpp"
#include "sim/dem/particles.hpp"
#include "sim/fluid/grid.hpp"
#include "sim/fluid/solver.hpp"

namespace cgd::coupling {

struct CouplerSettings {
  DragLaw drag = DragLaw::Beetstra;
  DragParams drag_params;              // rho_f, mu_f, primary diameter
  FilteredDragSetup filtered;          // model, Delta, L_char, alpha: for drag = radl2014 / model
  double particle_volume_m3 = 0;       // V_p of the primary
  double parcel_volume_factor = 1;     // alpha^3: primaries per parcel (drag scales with it)
  double particle_mass_kg = 0;         // mass of one (parcel) particle
  bool two_way = true;                 // false: no momentum returned to the fluid (B = 0)
  bool pressure_gradient_force = true;
  // false: the drag's phi_p leaves out the particle's own deposit, V alpha^3 sum_c w_pc^2 / V_cell (at least 0);
  // eps of the fluid and every other use of phi keep it (scene key fluid.drag_own_deposit)
  bool drag_own_deposit = true;
  double void_fraction_floor = 0.3;    // eps_min
  std::array<double, 3> particle_body_accel{};  // g less the mean pressure gradient's V_p G/m (coupled_step.hpp periodic_driving)
  ParticleStressParams particle_stress;         // [particle_stress]; model None: nothing below is allocated or done
};

/// Per-particle coupling quantities of the last `compute_drag` (owned particles, current order).
struct ParticleCoupling {
  std::vector<double> beta;              // beta_p,i, kg m^-3 s^-1
  std::vector<double> fluid_velocity;    // u at the particle, 3 per particle
  std::vector<double> pressure_gradient; // grad p at the particle (mean removed), 3 per particle
  // drift law only (empty otherwise): d_p = H(phi_p, |s~_p|/u_t) s~_p, 3 per particle, m/s; the force is
  // beta_p V_p (u_p - v_p - d_p), so beta is the micro law's coefficient
  std::vector<double> drift_shift;
  std::vector<double> cell_slip;         // drift law only: s~_p = u_p - vbar_p, 3 per particle, m/s
  // particle-phase pressure only (empty otherwise): a_p = -(V_p/m_p) sum_c mu_c grad w_pc less its mean
  // over all particles, 3 per particle, m/s^2 (from the deposit of compute_drag; added by compute_particle_forces)
  std::vector<double> stress_accel;
};

class Coupler {
 public:
  Coupler(const CouplerSettings& settings, const fluid::FluidGrid& grid);

  /// Steps 1 and 2: eps into state.void_fraction; B, V into the state's drag fields; the particles'
  /// beta, u_p and grad p_p (at the fluid's current level) into `particles()`. Collective.
  void compute_drag(const dem::Particles& p, fluid::FluidState& state);
  /// Step 4: the particles' external accelerations (p.a_ext) from the fluid's new level, with the stencils
  /// of the last compute_drag (the particles must not have moved since). Collective.
  void compute_particle_forces(dem::Particles& p, fluid::FluidState& state);

  const ParticleCoupling& particles() const { return pc_; }
  /// Cells at the void-fraction floor at the last deposit (global count) and the largest phi found.
  long long floored_cells() const { return floored_; }
  double max_solids_fraction() const { return max_phi_; }
  const CouplerSettings& settings() const { return s_; }

 private:
  /// Cell-centred u and grad p of the fluid's current level (and, with `with_phi`, phi_) into the
  /// interleaved cells_ (kRead values per cell): computed on the owned rows, then every row and the ghost rows
  /// gathered to every rank. Collective.
  void cell_fields(const fluid::FluidState& state, bool with_phi);
  static constexpr int kRead = 8;  // u (3), grad p (3), phi, unused: one 64-byte line per cell
  static constexpr int kDeposit = 4;  // B, B V (3)
  /// Drift law: the owned cells' mean particle velocity (or u_c where nothing is deposited) into drift_cells_
  /// (3 per cell, interleaved), then gathered to every rank. After cell_fields(state, true). Collective.
  void drift_cell_velocity();
  /// Particle-phase pressure: mu(phi_c) of the raw deposit on the owned cells (gathered to every rank), and at
  /// each of the `n` owned particles a_p = -(V_p/m_p) sum_c mu_c grad w_pc with its stencil, into pc_.stress_accel,
  /// less the mean over all particles. Before the void-fraction floor alters phi_. Collective.
  void particle_stress_accelerations(std::size_t n);
  CouplerSettings s_;
  bool stress_ = false;            // particle_stress.model != None: the two members below are used
  std::vector<double> stress_mu_;  // stress only: mu(phi_c), on the whole view
  std::unique_ptr<StressPotential> stress_potential_;  // stress only
  bool drift_ = false;             // fluid.drag = "drift": the cell-mean velocity deposit below is used
  std::vector<double> drift_mass_, drift_mv_[3];  // drift only: sum V w / V_cell (raw) and sum V w v / V_cell
  std::vector<double> drift_cells_;               // drift only: vbar_c, 3 per cell
  const fluid::FluidGrid& grid_;
  RowOwners rows_;                 // every rank's fluid rows
  GridView view_;                  // the whole grid, j0 = 0, ny_local = n_y, kGhost periodic ghost rows
  std::size_t owned_offset_ = 0;   // j0 * plane: a fluid-grid index plus this is the view's index
  // every field below is on the whole view (storage layout view_.storage_size(), cell-major when interleaved)
  std::vector<double> phi_;
  std::vector<double> cells_;      // kRead per cell
  std::vector<double> deposit_;    // kDeposit per cell
  std::vector<Stencil> stencil_;   // per owned particle, from the last compute_drag
  ParticleCoupling pc_;
  long long floored_ = 0;
  double max_phi_ = 0;
};

}  // namespace cgd::coupling
