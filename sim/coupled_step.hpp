#pragma once
// The coupled CFD-DEM step (ARCHITECTURE.md "Coupled runs"): one fluid step and its DEM sub-steps with
// the fluid forces held constant over them. One reusable piece: the run driver (sim/run.cpp) calls it
// in its time loop; it knows nothing of output, checkpoints or the run directory.
#include <cstdint>
#include <functional>
#include <memory>

#include "core/schema/checkpoint.hpp"
#include "core/scene.hpp"
#include "core/timers.hpp"
#include "sim/coupling/coupler.hpp"
#include "sim/dem/system.hpp"
#include "sim/fluid/grid.hpp"
#include "sim/fluid/solver.hpp"

namespace cgd {

/// Periodic sedimentation driving of a scene that solves the fluid (docs/models.md "Periodic sedimentation
/// driving"). A mean pressure gradient G is removed from the solved pressure; the fluid gets the body
/// force eps (rho_f g - G) and each particle m g - V_p G when the pressure-gradient force is on (m g
/// alone when it is off), chosen so that the fluid carries what the coupling makes it carry:
///   two-way, pressure-gradient force on:  G = rho_mix g, rho_mix = <phi> rho_p + <eps> rho_f:
///       fluid eps (rho_f - rho_mix) g, particles g (1 - rho_mix/rho_p); net force on the box zero;
///   two-way, pressure-gradient force off: refused by scene validation (core/scene.cpp read_fluid): the
///       fluid's -eps grad p' (p' the periodic part) would have no counterpart on the particles, so the
///       mixture momentum would not be conserved;
///   one-way: the particles do not act on the fluid (no drag on it, and it is solved with eps = 1,
///       coupler.hpp), so it carries no particle weight: G = rho_f g (hydrostatic), the fluid gets no body
///       force and a fluid at rest stays at rest; the particles see the fluid's buoyancy, g (1 - rho_f/rho_p)
///       (force on: the same as a quiescent fluid), or g (force off), and settle at their single-particle
///       drag balance. With rho_mix instead, nothing balanced the fluid's eps (rho_f - rho_mix) g (-565 m/s^2
///       at <phi> = 0.05) and the fluid accelerated without bound.
struct PeriodicDriving {
  Vec3 pressure_gradient_mean_Pa_m{};  // G, removed from the solved pressure
  Vec3 fluid_body_force_N_m3{};        // rho_f g - G, per fluid volume (the fluid gets eps times it)
  Vec3 particle_body_accel_m_s2{};     // g - V_p G / m with the pressure-gradient force on, else g
};
PeriodicDriving periodic_driving(const Scene& scene);

/// The fluid solver, the coupler and the fluid-step rule of a scene that solves the fluid.
///
/// A step of the coupled loop is: begin() (deposit eps, B, B V and interpolate at the particles: the
/// state the series row and snapshot of this step show), then substeps() (how many DEM steps the next
/// fluid step spans), then advance() (the fluid step, the particle forces from its new level, the DEM
/// sub-steps).
class CoupledStep {
 public:
  /// Registers the phase "coupling" (and the fluid solver's phases) on `timers`. Throws InputError,
  /// before anything is written, when the DEM step `dt_dem_s` exceeds the fluid's stability limit.
  CoupledStep(const Scene& scene, fluid::FluidGrid& grid, double dt_dem_s, PhaseTimers& timers);

  /// Coupler step 1 on the current particles (and, at the very first fluid step, eps_old = eps).
  void begin(const dem::Particles& particles);

  /// DEM steps of the next fluid step at DEM step `step`: the `steps_to_target` DEM steps up to the
  /// next snapshot (or the end) divided evenly over the fewest fluid steps the Courant limit (and the
  /// viscous and drag caps) allow. The eps change a fluid step sees is the particles' motion over the
  /// previous fluid step (deposit at the start of each step, coupler.hpp), so consecutive fluid steps
  /// must be of about equal length, instead of cutting the last one short. Throws RunError when the
  /// limit falls below one DEM step.
  std::int64_t substeps(std::int64_t step, std::int64_t steps_to_target) const;

  /// The longest fluid step the current flow allows: min(Co dx / max|u|, viscous limit, drag cap), s.
  /// Collective.
  double max_fluid_dt() const { return fluid_->max_dt(courant_, dt_fluid_cap_); }

  /// One fluid step of n_sub DEM steps, the particle forces from its new level (held constant over the
  /// sub-steps, PerParticleDrive), and the n_sub DEM steps; `after_dem_step` runs after each one.
  void advance(dem::DemSystem& dem, std::int64_t n_sub, const std::function<void()>& after_dem_step);

  fluid::FluidSolver& fluid() { return *fluid_; }
  const fluid::FluidSolver& fluid() const { return *fluid_; }
  const coupling::Coupler& coupler() const { return *coupler_; }
  const fluid::FluidGrid& grid() const { return grid_; }
  /// The removed mean pressure gradient G (snapshots store it beside the periodic part).
  const Vec3& pressure_gradient_mean() const { return pressure_gradient_mean_; }
  /// Fluid steps done (checkpointed: the first one also resets the fluid's history).
  std::int64_t fluid_steps() const { return fluid_steps_; }
  void set_fluid_steps(std::int64_t n) { fluid_steps_ = n; }
  /// This rank's fluid state for checkpoint.h5 (views into the solver's fields).
  checkpoint::FluidRows checkpoint_rows();
  /// Reads the fluid state (and the fluid-step count) back from a checkpoint, any rank count. Collective.
  void restore(const checkpoint::Reader& reader);
  /// The cap on the fluid step from explicit particle drag: dt beta_max / rho_p <= numerics.drag_safety.
  double drag_dt_cap() const { return dt_fluid_cap_; }

 private:
  /// The solver's fields in the order of checkpoint::kFluidFieldNames.
  std::array<std::vector<double>*, checkpoint::kFluidFieldNames.size()> restart_fields();

  fluid::FluidGrid& grid_;
  double dt_dem_s_;
  double courant_;
  PhaseTimers& timers_;
  std::size_t t_coupling_;
  std::unique_ptr<fluid::FluidSolver> fluid_;
  std::unique_ptr<coupling::Coupler> coupler_;
  Vec3 pressure_gradient_mean_{};
  double dt_fluid_cap_ = 0;
  std::int64_t fluid_steps_ = 0;
};

}  // namespace cgd
