// The coupled CFD-DEM step (sim/coupled_step.hpp).
#include "sim/coupled_step.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.hpp"
#include "core/filtered_drag.hpp"

namespace cgd {

PeriodicDriving periodic_driving(const Scene& scene) {
  const FluidConfig& f = *scene.fluid;
  const double volume = scene.domain.size_m[0] * scene.domain.size_m[1] * scene.domain.size_m[2];
  const double phi = static_cast<double>(scene.derived.particle_count) * scene.derived.parcel_volume_factor *
                     scene.derived.particle_volume_m3 / volume;
  const double rho_p = scene.particles.density_kg_m3, rho_f = f.density_kg_m3;
  const double rho_mix = phi * rho_p + (1.0 - phi) * rho_f;
  // density whose weight the mean pressure gradient carries (see coupled_step.hpp)
  double carried = rho_f;
  if (f.coupling == Coupling::TwoWay) carried = rho_mix;  // with the force on (scene validation)
  const Vec3& g = scene.domain.gravity_m_s2;
  PeriodicDriving d;
  for (int c = 0; c < 3; ++c) {
    d.pressure_gradient_mean_Pa_m[c] = carried * g[c];
    d.fluid_body_force_N_m3[c] = (rho_f - carried) * g[c];
    d.particle_body_accel_m_s2[c] = f.pressure_gradient_force ? g[c] * (1.0 - carried / rho_p) : g[c];
  }
  return d;
}

CoupledStep::CoupledStep(const Scene& scene, fluid::FluidGrid& grid, double dt_dem_s, PhaseTimers& timers)
    : grid_(grid), dt_dem_s_(dt_dem_s), courant_(scene.fluid->courant), timers_(timers) {
  const FluidConfig& f = *scene.fluid;
  const PeriodicDriving driving = periodic_driving(scene);
  fluid::FluidSettings fs;
  fs.density_kg_m3 = f.density_kg_m3;
  fs.viscosity_Pa_s = f.viscosity_Pa_s;
  fs.body_force_per_fluid_volume_N_m3 = driving.fluid_body_force_N_m3;
  fs.viscous_safety = scene.numerics.viscous_safety;
  t_coupling_ = timers_.add("coupling");  // before the solver's phases: the series and checkpoint order
  fluid_ = std::make_unique<fluid::FluidSolver>(grid_, fs, &timers_);
  coupling::CouplerSettings cs;
  cs.drag = f.drag;
  cs.drag_params = {f.density_kg_m3, f.viscosity_Pa_s, scene.particles.diameter_m};
  cs.filtered = filtered_drag_setup(scene, grid_.spacing());
  cs.particle_volume_m3 = scene.derived.particle_volume_m3;
  cs.parcel_volume_factor = scene.derived.parcel_volume_factor;
  cs.particle_mass_kg = scene.derived.parcel_mass_kg;
  cs.two_way = f.coupling == Coupling::TwoWay;
  cs.pressure_gradient_force = f.pressure_gradient_force;
  cs.drag_own_deposit = f.drag_own_deposit;
  cs.void_fraction_floor = scene.numerics.void_fraction_floor;
  cs.particle_body_accel = driving.particle_body_accel_m_s2;
  pressure_gradient_mean_ = driving.pressure_gradient_mean_Pa_m;
  // Particle drag is explicit over a fluid step (momentum exchange exact, coupler.hpp): keep
  // dt_fluid beta_max / rho_p <= numerics.drag_safety (0.5), beta_max at the densest admissible state
  // (eps at its floor).
  const double beta_max = beta_p(f.drag, cs.drag_params, cs.filtered, 1.0 - cs.void_fraction_floor, 0.0);
  dt_fluid_cap_ = scene.numerics.drag_safety * scene.particles.density_kg_m3 / beta_max;
  // A fluid step is a whole number of DEM steps: a DEM step longer than the fluid's stability
  // limits (explicit viscosity, explicit particle drag) cannot be run; refuse it before writing.
  const double limit = std::min(fluid_->viscous_dt_limit(), dt_fluid_cap_);
  // The particle-phase pressure's force is explicit over a fluid step too: its waves, of speed sqrt(tau'/rho_p),
  // may cross at most numerics.particle_stress_courant of a cell in the longest fluid step (`limit`), so tau' is
  // capped at rho_p (C h_min / limit)^2 (core/particle_stress.hpp; it binds only near close packing)
  cs.particle_stress = f.particle_stress;
  if (cs.particle_stress.model != ParticleStressModel::None) {
    const auto& h = grid_.spacing();
    const double c = scene.numerics.particle_stress_courant * std::min({h[0], h[1], h[2]}) / limit;
    cs.particle_stress.max_stiffness_Pa = scene.particles.density_kg_m3 * c * c;
  }
  coupler_ = std::make_unique<coupling::Coupler>(cs, grid_);
  if (dt_dem_s_ > limit)
    throw InputError(scene.source_path + ": the DEM time step " + std::to_string(dt_dem_s_) +
                     " s exceeds the fluid's stability limit " + std::to_string(limit) +
                     " s (explicit viscosity on cells of " + std::to_string(grid_.spacing()[0]) +
                     " m, explicit particle drag): lower contact.t_star (or run.dt), or use larger cells");
}

void CoupledStep::begin(const dem::Particles& particles) {
  {
    ScopedPhase t(timers_, t_coupling_);
    coupler_->compute_drag(particles, fluid_->state());
  }
  if (fluid_steps_ == 0) fluid_->reset_history();  // eps_old = eps at the very first step
}

std::int64_t CoupledStep::substeps(std::int64_t step, std::int64_t steps_to_target) const {
  const double dt_fluid_max = max_fluid_dt();
  if (dt_fluid_max < dt_dem_s_)
    throw RunError(
        "at step " + std::to_string(step) + " (t = " + std::to_string(static_cast<double>(step) * dt_dem_s_) +
        " s) the fluid's Courant limit " + std::to_string(dt_fluid_max) + " s fell below one DEM step (" +
        std::to_string(dt_dem_s_) + " s): the flow is too fast for this grid");
  const std::int64_t n_max = static_cast<std::int64_t>(dt_fluid_max / dt_dem_s_);
  const std::int64_t fluid_steps_to_target = (steps_to_target + n_max - 1) / n_max;
  return (steps_to_target + fluid_steps_to_target - 1) / fluid_steps_to_target;
}

void CoupledStep::advance(dem::DemSystem& dem, std::int64_t n_sub,
                          const std::function<void()>& after_dem_step) {
  fluid_->step(static_cast<double>(n_sub) * dt_dem_s_);
  ++fluid_steps_;
  {
    ScopedPhase t(timers_, t_coupling_);
    coupler_->compute_particle_forces(dem.particles(), fluid_->state());
  }
  for (std::int64_t k = 0; k < n_sub; ++k) {
    dem.step();
    after_dem_step();
  }
}

std::array<std::vector<double>*, checkpoint::kFluidFieldNames.size()> CoupledStep::restart_fields() {
  fluid::FluidState& st = fluid_->state();
  return {
      &st.velocity[0],       &st.velocity[1],          &st.velocity[2],          &st.pressure,
      &st.void_fraction_old, &st.explicit_rate_old[0], &st.explicit_rate_old[1], &st.explicit_rate_old[2]};
}

checkpoint::FluidRows CoupledStep::checkpoint_rows() {
  checkpoint::FluidRows rows;
  rows.dt_previous_s = fluid_->state().dt_previous_s;
  rows.steps = fluid_steps_;
  rows.cells = static_cast<std::int64_t>(grid_.owned_size());
  const auto fields = restart_fields();
  for (std::size_t k = 0; k < fields.size(); ++k) rows.fields[k] = fields[k]->data() + grid_.first_owned();
  return rows;
}

void CoupledStep::restore(const checkpoint::Reader& reader) {
  fluid::FluidState& st = fluid_->state();
  const auto& n = grid_.cells();
  const std::int64_t cells = static_cast<std::int64_t>(n[0]) * n[1] * n[2];
  if (!reader.has_fluid() || reader.fluid_cells() != cells)  // the same verdict on every rank: metadata
    throw InputError(reader.path() + ": " +
                     (reader.has_fluid() ? "the fluid fields hold " + std::to_string(reader.fluid_cells()) + " cells"
                                         : std::string("no group '/fluid'")) +
                     ", expected the scene's grid of " + std::to_string(n[0]) + " x " + std::to_string(n[1]) + " x " +
                     std::to_string(n[2]) + " = " + std::to_string(cells) + " cells");
  // this rank's planes start at row j0 of the global (y, z, x) order
  const std::int64_t first = static_cast<std::int64_t>(grid_.j0()) * static_cast<std::int64_t>(grid_.plane());
  const auto fields = restart_fields();
  for (std::size_t k = 0; k < fields.size(); ++k)
    reader.read_fluid_field(k, first, static_cast<std::int64_t>(grid_.owned_size()),
                            fields[k]->data() + grid_.first_owned());
  st.dt_previous_s = reader.fluid_dt_previous_s();
  fluid_steps_ = reader.fluid_steps();
  grid_.exchange_ghosts({st.velocity[0].data(), st.velocity[1].data(), st.velocity[2].data(),
                         st.pressure.data(), st.void_fraction_old.data()});
}

}  // namespace cgd
