#pragma once
// Volume-averaged incompressible Navier–Stokes, "model A" (models.md; set II of Zhou et al. 2010), on a
// fully periodic staggered (MAC) grid:
//
//     d(eps)/dt + div(eps u) = 0
//     rho_f [d(eps u)/dt + div(eps u u)] = -eps grad p + div(eps tau) + B (V - u) + eps f + f_field
//     tau = mu_f (grad u + grad u^T)
//
// The viscous term is the conservative div(eps tau), not models.md's eps div(tau). The two differ by
// tau . grad(eps), O(mu |grad u| |grad eps|): small where eps is smooth on the scale of the velocity,
// but eps div(tau) summed over a periodic box does not vanish where eps varies, and the particles get no
// counterpart of it (models.md eq. 3 gives them -V_p grad p, the drag and gravity only), so the mixture
// momentum would drift. div(eps tau) is what CFDEMcoupling solves (cfdemCloud::divVoidfractionTau:
// -fvm::laplacian(voidfraction nuEff, U) - fvc::div(voidfraction nuEff dev2(T(grad U))), there with the
// -2/3 (div u) I part of dev2) and what MFIX solves with its ISHII option (epmu_g = ep_g mu_g inside the
// divergence; its default drops eps from the stress altogether); with it the fluid's viscous forces sum
// to zero to round-off and the mixture momentum is conserved exactly (with the periodic driving and the
// transposed drag and pressure exchange, sim/coupling/coupler.hpp). The full form of tau is used: where
// eps varies in space or time div u = -(d eps/dt + u.grad eps)/eps is not zero and grad u^T does not
// drop out (no -2/3 mu (div u) I term: tau as models.md has it).
//
// eps(x, t) and the drag are given from outside each step (the coupling computes them): eps at the new
// and the old time level, and the drag in implicit form B (V - u) with B >= 0 (kg m^-3 s^-1) the
// cell's summed drag coefficient and V the cell's drag-weighted particle velocity. f (N/m^3 per unit
// eps) is a constant body force, e.g. rho_f g, or the periodic sedimentation driving (rho_f - rho_mix) g
// (models.md: the mean pressure gradient rho_mix g is removed from the solved p); f_field (N/m^3 on
// the faces) an optional body-force field.
//
// Discretisation (second order in space and time):
//   * MAC grid: p, eps, B, V at cell centres; u_d on the lower d-face of each cell (grid.hpp). Face
//     values of eps and B are the mean of the two cells; of B V the mean of the two cells' B V (so the
//     momentum the fluid receives is the cells' B V).
//   * Advection: conservative flux form div(M u) with the mass flux M = eps_f u, central (second-order,
//     non-dissipative) interpolation of both the transporting flux and the transported velocity on the
//     momentum control volume. A uniform flow in a uniform eps stays uniform.
//   * Viscosity: flux form div(eps tau) with eps at the stress locations: the normal stresses
//     2 mu eps du_d/dx_d at the cell centres (eps of the cell), the shear stresses mu eps_e (du_a/dx_b +
//     du_b/dx_a) on the cell edges (eps_e the mean of the four cells around the edge), each computed
//     once per step. With eps = 1 it is mu [lap u + grad(div u)] of the MAC grid to round-off.
//     Every advective and viscous flux is shared bitwise by its two control volumes, so with B = 0 and
//     f = 0 the total momentum sum(rho_f eps_f u) V_cell changes only by the pressure force
//     -sum eps_f (G p) V_cell (zero for uniform eps), to round-off, for any eps field.
//   * Advection and viscosity explicit, Adams–Bashforth 2 (variable step: F* = (1 + r/2) F^n - (r/2)
//     F^{n-1}, r = dt_n / dt_{n-1}; the first step after reset_history() is forward Euler). AB2's
//     stability interval on the negative real axis is [-1, 0], so the viscous limit is
//     nu dt sum_d 4/h_d^2 <= 1, i.e. dt <= h^2/(12 nu) on cubes: 0.38 ms for air (nu = 1.38e-5 m^2/s)
//     with h = 250 um, comparable with the Courant step 0.3 h/u_t = 0.29 ms at u_t = 0.26 m/s (75 um,
//     1500 kg/m^3 particles), and larger than it as soon as the flow is faster; max_dt() applies both.
//     Von Neumann analysis of AB2 with central advection and diffusion (1-D symbol, Co = u dt/h,
//     d = nu dt/h^2): |G| <= 1 for Co <= 0.5 once d >= 0.03 (Co = 0.3: d >= 0.01) up to the viscous
//     limit; the air case above has d = 0.064 at the Courant step. Inviscid central advection with
//     AB2 is weakly unstable (|G| - 1 = 2.4e-3 per step at Co = 0.3), which viscosity and drag remove.
//     The limit is that of eps = 1 (eps <= 1). With div(eps tau) a face's viscous rate scales with eps
//     at its stress points over its own eps_f, which can exceed 1 locally where eps varies. Measured
//     (B = 0, 16^3 cells, 4000 steps at viscous_safety s): stable up to s = 0.998 for uniform eps and for
//     a smoothed random eps in [0.3, 1], up to s = 0.990 for an independent random eps in [0.3, 1] per
//     cell (rougher than any TSC deposit); the default s = 0.8 covers both.
//   * Drag implicit (B dt / rho_f reaches ~30 in dense regions), body forces and pressure at the new level.
//   * Exact projection for the variable eps: with q = rho_f eps^n_f u^n/dt + F* + eps^{n+1}_f f + f_field
//     + (B V)_f and a = rho_f eps^{n+1}_f/dt + B_f, the new face velocity is
//         u^{n+1} = (q - eps^{n+1}_f G p) / a,
//     and the discrete continuity (eps^{n+1} - eps^n)/dt + D(eps^{n+1}_f u^{n+1}) = 0 gives
//         D(K G p) = D(eps_f q / a) + (eps^{n+1} - eps^n)/dt,   K = eps_f^2 / a,
//     solved by FFT-preconditioned conjugate gradients (pressure.hpp). There is no splitting error: the
//     step satisfies the discrete momentum and continuity equations together, to the PCG tolerance.
//
// Parallel: slabs along y (grid.hpp). Results on 1 and 2 ranks agree to round-off (FFTs and global sums
// add in a different order), not bit for bit.
#include <array>
#include <cstddef>
#include <vector>

#include "core/timers.hpp"
#include "sim/fluid/grid.hpp"
#include "sim/fluid/pressure.hpp"

namespace cgd::fluid {

struct FluidSettings {
  double density_kg_m3 = 1.3;
  double viscosity_Pa_s = 1.8e-5;
  /// f: the fluid momentum equation gets eps f (N/m^3 per unit eps); rho_f g, or (rho_f - rho_mix) g.
  std::array<double, 3> body_force_per_fluid_volume_N_m3{0.0, 0.0, 0.0};
  /// Also add FluidState::body_force (N/m^3 on the faces) each step.
  bool body_force_field = false;
  /// Fraction of AB2's explicit-viscosity stability limit used by max_dt().
  double viscous_safety = 0.8;
  /// Start PCG from the previous pressure (fewer iterations); off: from zero.
  bool warm_start = true;
  /// The pressure equation's right-hand side must have zero mean (sum of eps conserved by the coupling):
  /// RunError when |mean| > this times the size of its terms (max over cells of |d eps/dt| + sum_d
  /// (|eps u|_lo + |eps u|_hi)/h_d).
  double rhs_mean_tolerance = 1e-9;
  /// PCG stops at max|r| <= max(tolerance max|b|, roundoff_floor * that same term size): below that
  /// the right-hand side itself is round-off.
  double roundoff_floor = 1e-14;
  PressureSettings pressure;
};

/// All fields of the fluid, in grid storage (grid.hpp: (j, k, i) with y-ghosts). Inputs the caller sets
/// each step: void_fraction, drag_coefficient, drag_velocity (owned cells; ghosts are filled by step()).
struct FluidState {
  std::vector<double> void_fraction;                 // eps^{n+1}, cell centres (set before each step)
  std::vector<double> void_fraction_old;             // eps^n (step() sets it to eps^{n+1} when done)
  std::array<std::vector<double>, 3> velocity;       // u_d on the lower d-face, m/s
  std::vector<double> pressure;                      // Pa, cell centres, zero mean (mean gradient removed)
  std::vector<double> drag_coefficient;              // B, kg m^-3 s^-1, cell centres
  std::array<std::vector<double>, 3> drag_velocity;  // V, m/s, cell centres
  std::array<std::vector<double>, 3> body_force;     // N/m^3 on the d-faces (read if body_force_field)
  // Adams–Bashforth history: the explicit rate of the last step (N/m^3 on the faces) and that step's dt
  // (0: the next step is forward Euler). A bit-exact restart needs these, velocity, void_fraction_old
  // and pressure (PCG starts from it when warm_start is on).
  std::array<std::vector<double>, 3> explicit_rate_old;
  double dt_previous_s = 0.0;
};

struct StepReport {
  double dt_s = 0.0;
  PressureStats pressure;
  double rhs_term_scale_1_s = 0.0;  // max over cells of |d eps/dt| + sum_d (|eps u*|_lo + |eps u*|_hi)/h_d
  double continuity_residual_1_s = 0.0;  // max |(eps^{n+1} - eps^n)/dt + D(eps_f u^{n+1})|
  double continuity_relative =
      0.0;  // the same over max_cells(|d eps/dt| + sum_d (|eps u|_lo + |eps u|_hi)/h_d)
};

/// Domain averages (all ranks get the same values). Face quantities use eps at the faces.
struct FlowAverages {
  double void_fraction = 0.0;               // <eps>
  std::array<double, 3> eps_velocity{};     // <eps u>, m/s
  std::array<double, 3> fluid_velocity{};   // <eps u>/<eps> (phase average), m/s
  std::array<double, 3> momentum_kg_m_s{};  // sum rho_f eps_f u V_cell
  double kinetic_energy_J = 0.0;            // sum 1/2 rho_f eps_f u_d^2 V_cell over all faces
};

/// This rank's slab in the file order of the snapshot schema (docs/schema-run.md "Snapshot"): (n_z, ny_local, n_x),
/// x fastest; velocity at cell centres (mean of the two faces) with a trailing 3.
/// eps_velocity: cell-centred eps u, the mean of the two faces' eps_f u_f (eps_f = mean of the two
/// cells), so sum over cells = the solver's face sum (FlowAverages::eps_velocity) exactly.
struct FileOrderFields {
  std::vector<double> void_fraction, velocity, pressure, eps_velocity;
};

class FluidSolver {
 public:
  /// Initial state: eps = 1, u = 0, p = 0, B = 0. If `timers` is given, the phases "fluid predictor",
  /// "fluid pressure" and "fluid correction" are registered in it and timed. Collective.
  FluidSolver(const FluidGrid& grid, const FluidSettings& settings, PhaseTimers* timers = nullptr);
  FluidSolver(const FluidSolver&) = delete;
  FluidSolver& operator=(const FluidSolver&) = delete;

  const FluidGrid& grid() const { return grid_; }
  const FluidSettings& settings() const { return settings_; }
  FluidState& state() { return state_; }
  const FluidState& state() const { return state_; }
  void set_body_force_per_fluid_volume(const std::array<double, 3>& f_N_m3) {
    settings_.body_force_per_fluid_volume_N_m3 = f_N_m3;
  }
  void set_pressure_settings(const PressureSettings& s);

  /// After setting an initial eps (and u): eps^n = eps, Adams–Bashforth history cleared.
  void reset_history();

  /// One step of length dt_s: explicit predictor (AB2) -> pressure (PCG) -> correction. Reads eps
  /// (new level), eps_old, B, V; afterwards u and p hold the new level with valid y-ghosts and
  /// eps_old = eps. Collective. Throws RunError on a non-finite state, an unconverged pressure solve
  /// or a right-hand side whose mean is not zero (sum of eps not conserved).
  StepReport step(double dt_s);
  const StepReport& last_report() const { return report_; }

  /// Largest stable step: min(dt_cap_s, courant / max_cells sum_d |u_d|/h_d, viscous limit). The
  /// Courant number is OpenFOAM's (0.5 sum_faces |phi| dt / V_cell), as the paper's Co. Collective.
  double max_dt(double courant, double dt_cap_s) const;
  /// AB2's explicit-viscosity limit times settings.viscous_safety: 1/(4 nu sum_d 1/h_d^2).
  double viscous_dt_limit() const;

  /// Domain averages of the current state. Collective.
  FlowAverages averages();
  /// This rank's eps, cell-centred u and p in file order. Collective (refreshes the ghosts of u).
  void fill_file_order(FileOrderFields& out);

 private:
  void explicit_rate();
  void predictor(double dt);
  void correction(double dt);

  FluidGrid grid_;
  FluidSettings settings_;
  PressureSolver pressure_;
  FluidState state_;
  StepReport report_;
  PhaseTimers* timers_ = nullptr;
  std::size_t phase_predictor_ = 0, phase_pressure_ = 0, phase_correction_ = 0;
  // Work fields (grid storage): mass flux eps^n_f u^n, then the provisional eps u; the explicit rate;
  // q (N/m^3), which explicit_rate() uses first for eps times the normal stresses; K, first the eps times
  // shear stresses on the edges; the pressure right-hand side.
  std::array<std::vector<double>, 3> flux_, rate_, q_, K_;
  std::vector<double> rhs_;
};

}  // namespace cgd::fluid
