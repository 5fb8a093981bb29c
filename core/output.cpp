// cgd::schema — the file schema of ARCHITECTURE.md "Files" and docs/schema-run.md: common root
// attributes and /params, and snapshots. The series is core/series.cpp, the checkpoint core/checkpoint.cpp,
// run.xmf core/xdmf.cpp.
#include "core/output.hpp"

#include <algorithm>
#include <array>
#include <cstring>
#include <ctime>
#include <stdexcept>

#include "core/error.hpp"
#include "core/schema/snapshot_names.hpp"

#ifndef CGD_VERSION
#define CGD_VERSION "unknown"
#endif

namespace cgd::schema {
namespace {

using namespace names;

std::vector<double> as_vector(const Vec3& v) {
  return {v.begin(), v.end()};
}
std::vector<std::int64_t> as_vector(const std::array<int, 3>& v) {
  return {v.begin(), v.end()};
}

/// UTC now as ISO 8601 ("2025-01-31T12:00:00Z"), taken on rank 0 so every rank writes the same text.
std::string utc_now_iso8601(MPI_Comm comm) {
  char text[32] = {};
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  if (rank == 0) {
    const std::time_t now = std::time(nullptr);
    std::tm utc{};
    gmtime_r(&now, &utc);
    std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
  }
  MPI_Bcast(text, sizeof text, MPI_CHAR, 0, comm);
  text[sizeof text - 1] = '\0';
  return text;
}

/// Every field of the scene's config structs and of DerivedScales, SI, the unit in the name.
/// Keep in step with core/scene.hpp: a field added there belongs here too.
void write_params(h5::File& f, const Scene& s) {
  const std::string g = kParams;
  auto flag = [](bool b) { return std::int64_t{b ? 1 : 0}; };
  f.create_group(g);
  f.set_attr(g, kSceneName, s.name);
  f.set_attr(g, "scene_path", s.source_path);
  // effects that are on
  f.set_attr(g, "has_contacts", flag(s.has_contacts()));
  f.set_attr(g, "has_friction", flag(s.has_friction()));
  f.set_attr(g, kHasFluid, flag(s.fluid.has_value()));
  f.set_attr(g, "solves_fluid", flag(s.solves_fluid()));

  // [domain]
  f.set_attr(g, kBoxSize, as_vector(s.domain.size_m));
  f.set_attr(g, kGravity, as_vector(s.domain.gravity_m_s2));

  // [particles]
  const ParticlesConfig& p = s.particles;
  f.set_attr(g, kDiameter, p.diameter_m);
  f.set_attr(g, kDensity, p.density_kg_m3);
  f.set_attr(g, kSolidsFraction, p.solids_fraction);
  f.set_attr(g, kParcelSize, p.parcel_size);
  f.set_attr(g, "velocity_rms_m_s", p.velocity_rms_m_s);
  f.set_attr(g, "seed", static_cast<std::int64_t>(p.seed));

  // [contact]
  const ContactConfig& c = s.contact;
  f.set_attr(g, "contact_model", std::string(to_string(c.model)));
  if (c.gamma_star) f.set_attr(g, "gamma_star", *c.gamma_star);
  if (c.stiffness_n_N_m) f.set_attr(g, "stiffness_n_N_m", *c.stiffness_n_N_m);
  f.set_attr(g, "t_star", c.t_star);
  f.set_attr(g, "restitution", c.restitution);
  f.set_attr(g, "friction", c.friction);
  f.set_attr(g, "kn_over_kt", c.kn_over_kt);
  f.set_attr(g, "gamman_over_gammat", c.gamman_over_gammat);
  if (c.skin_over_dp) f.set_attr(g, "skin_over_dp", *c.skin_over_dp);  // absent: adaptive

  // [fluid] (absent: dry granular run)
  if (s.fluid) {
    const FluidConfig& fl = *s.fluid;
    f.set_attr(g, kFluidDensity, fl.density_kg_m3);
    f.set_attr(g, kFluidViscosity, fl.viscosity_Pa_s);
    f.set_attr(g, "fluid_cells", as_vector(fl.cells));
    f.set_attr(g, "courant", fl.courant);
    f.set_attr(g, kCoupling, std::string(to_string(fl.coupling)));
    f.set_attr(g, kDrag, std::string(to_string(fl.drag)));
    f.set_attr(g, kPressureGradientForce, flag(fl.pressure_gradient_force));
    f.set_attr(g, "parcel_correction", flag(fl.parcel_correction));
    if (!fl.drag_model_path.empty()) {  // drag = "model": the file and its checksum (provenance)
      f.set_attr(g, "drag_model", fl.drag_model_path);
      f.set_attr(g, "drag_model_checksum", fl.drag_model_checksum);
    }
  }

  // [run]
  const RunConfig& r = s.run;
  f.set_attr(g, "end_time_s", r.end_time_s);
  f.set_attr(g, "dump_interval_s", r.dump_interval_s);
  f.set_attr(g, "series_interval_s", r.series_interval_s);
  f.set_attr(g, "checkpoint_wall_s", r.checkpoint_wall_s);
  f.set_attr(g, "sampling_start_s", r.sampling_start_s);
  if (r.dt_s) f.set_attr(g, "dt_s", *r.dt_s);

  // [numerics]
  const NumericsConfig& nm = s.numerics;
  f.set_attr(g, "void_fraction_floor", nm.void_fraction_floor);
  f.set_attr(g, "overlap_limit", nm.overlap_limit);
  f.set_attr(g, "overlap_warning_fraction", nm.overlap_warning_fraction);
  f.set_attr(g, "viscous_safety", nm.viscous_safety);
  f.set_attr(g, "drag_safety", nm.drag_safety);
  f.set_attr(g, "sort_interval_steps", nm.sort_interval_steps);
  f.set_attr(g, "skin_target_steps", nm.skin_target_steps);

  // derived scales
  const DerivedScales& d = s.derived;
  f.set_attr(g, "particle_volume_m3", d.particle_volume_m3);
  f.set_attr(g, "particle_mass_kg", d.particle_mass_kg);
  f.set_attr(g, "parcel_diameter_m", d.parcel_diameter_m);
  f.set_attr(g, "parcel_mass_kg", d.parcel_mass_kg);
  f.set_attr(g, kUt, d.u_t_m_s);
  f.set_attr(g, "re_p", d.re_p);
  f.set_attr(g, "fr_p", d.fr_p);
  f.set_attr(g, "l_ref_m", d.l_ref_m);
  f.set_attr(g, kLChar, d.l_char_m);
  f.set_attr(g, kTref, d.t_ref_s);
  f.set_attr(g, "stokes_relaxation_s", d.stokes_relaxation_s);
  f.set_attr(g, "k_n_N_m", d.k_n_N_m);
  f.set_attr(g, "k_t_N_m", d.k_t_N_m);
  f.set_attr(g, "gamma_n_kg_s", d.gamma_n_kg_s);
  f.set_attr(g, "gamma_t_kg_s", d.gamma_t_kg_s);
  f.set_attr(g, "t_c_s", d.t_c_s);
  f.set_attr(g, "dt_dem_s", d.dt_dem_s);
  f.set_attr(g, "dt_fluid_s", d.dt_fluid_s);
  f.set_attr(g, "cells", as_vector(d.cells));
  f.set_attr(g, "particle_count", d.particle_count);
  f.set_attr(g, "memory_estimate_bytes", d.memory_estimate_bytes);
}

/// One per-particle array of the snapshot: name, data, values per particle, unit.
struct ParticleArray {
  const char* name;  // the dataset's path
  const double* data;
  int width;
  const char* unit;
  bool required;
};

}  // namespace

void write_common(h5::File& file, const Format& format, const Scene& scene) {
  using namespace names;
  file.set_attr(kRoot, kFormat, std::string(format.name));
  file.set_attr(kRoot, kFormatVersion, format.version);
  file.set_attr(kRoot, kCodeVersion, std::string(CGD_VERSION));
  file.set_attr(kRoot, kCreated, utc_now_iso8601(file.comm()));
  file.set_attr(kRoot, kScene, scene.effective_toml);
  write_params(file, scene);
}

void write_snapshot(const std::string& path, MPI_Comm comm, const Scene& scene, double time_s,
                    std::int64_t step, const ParticleFields& particles, const FluidFields* fluid) {
  using namespace names;
  const ParticleArray arrays[] = {
      {kPosition, particles.position, 3, "m", true},
      {kVelocity, particles.velocity, 3, "m/s", true},
      {kAngularVelocity, particles.angular_velocity, 3, "rad/s", false},
      {kParticleDiameter, particles.diameter, 1, "m", true},
      {kDragCoefficient, particles.drag_coefficient, 1, "kg/(m^3 s)", false},
      {kFluidVelocityAtParticles, particles.fluid_velocity, 3, "m/s", false},
      {kPressureGradient, particles.pressure_gradient, 3, "Pa/m", false},
  };
  constexpr int kArrays = std::size(arrays);

  // Which optional arrays are present, agreed over all ranks (a rank without particles may pass
  // nullptr); an array given on some ranks but missing on a rank that has particles is a bug.
  const bool has_rows = particles.count > 0;
  std::array<int, 2 * kArrays + 6> local{}, global{};
  for (int i = 0; i < kArrays; ++i) {
    local[2 * i] = arrays[i].data != nullptr;
    local[2 * i + 1] = arrays[i].data == nullptr && has_rows;
  }
  local[2 * kArrays] = particles.id == nullptr && has_rows;
  local[2 * kArrays + 1] = particles.count < 0;
  local[2 * kArrays + 2] = fluid != nullptr;
  local[2 * kArrays + 3] = fluid == nullptr;
  bool bad_slab = false;
  if (fluid) {
    const auto& n = fluid->cells;
    bad_slab = n[0] <= 0 || n[1] <= 0 || n[2] <= 0 || fluid->y_offset < 0 || fluid->y_count < 0 ||
               fluid->y_offset + fluid->y_count > n[1] ||
               (fluid->y_count > 0 && (!fluid->void_fraction || !fluid->velocity || !fluid->pressure));
  }
  local[2 * kArrays + 4] = bad_slab;
  local[2 * kArrays + 5] = fluid ? fluid->cells[1] : 0;
  MPI_Allreduce(local.data(), global.data(), static_cast<int>(local.size()), MPI_INT, MPI_MAX, comm);

  std::string problem;
  for (int i = 0; i < kArrays; ++i) {
    const bool any_given = global[2 * i], missing_somewhere = global[2 * i + 1];
    if (missing_somewhere && (arrays[i].required || any_given))
      problem =
          std::string("particle array '") + arrays[i].name + "' is missing on a rank that owns particles";
  }
  if (global[2 * kArrays]) problem = std::string("particle array '") + kId + "' is missing on a rank that owns particles";
  if (global[2 * kArrays + 1]) problem = "negative particle count";
  const bool with_fluid = global[2 * kArrays + 2];
  if (with_fluid && global[2 * kArrays + 3]) problem = "fluid fields given on some ranks only";
  if (global[2 * kArrays + 4]) problem = "a rank's fluid slab lies outside the grid or lacks a field";
  if (with_fluid && problem.empty()) {
    int y_cells = fluid->y_count, y_total = 0;
    MPI_Allreduce(&y_cells, &y_total, 1, MPI_INT, MPI_SUM, comm);
    if (y_total != global[2 * kArrays + 5])
      problem = "the ranks' fluid slabs hold " + std::to_string(y_total) + " layers along y, the grid has " +
                std::to_string(global[2 * kArrays + 5]);
  }
  if (!problem.empty()) throw RunError(path + ": cannot write snapshot: " + problem);

  h5::write_atomically(path, comm, [&](h5::File& f) {
    write_common(f, kSnapshot, scene);
    f.set_attr(kRoot, kTime, time_s);
    f.set_attr(kRoot, kStep, step);

    f.create_group(kParticles);
    f.write_rows(kId, particles.id, particles.count, 1);
    f.set_attr(kId, kUnit, std::string("1"));
    for (int i = 0; i < kArrays; ++i) {
      if (!global[2 * i]) continue;  // not simulated
      const std::string name = arrays[i].name;
      f.write_rows(name, arrays[i].data, particles.count, arrays[i].width);
      f.set_attr(name, kUnit, std::string(arrays[i].unit));
    }
    const bool wrote_pressure_gradient =
        std::any_of(std::begin(arrays), std::end(arrays), [&](const ParticleArray& a) {
          return std::strcmp(a.name, kPressureGradient) == 0 && global[2 * (&a - arrays)];
        });
    if (wrote_pressure_gradient) {  // record the mean that was removed from it, and the time levels
      f.set_attr(kParticles, kPressureGradientMean, as_vector(particles.pressure_gradient_mean));
      f.set_attr(kParticles, kTimeLevel,
                 std::string("position x_n at t_n; velocity: the leapfrog v_{n-1/2} the drag used (coupled runs); "
                             "drag_coefficient, fluid_velocity, pressure_gradient: fluid level n interpolated to x_n "
                             "with the TSC kernel (the values of the drag evaluation that starts the fluid step at t_n)"));
    }

    if (with_fluid) {
      const auto n = fluid->cells;  // (n_x, n_y, n_z)
      const auto nx = static_cast<std::uint64_t>(n[0]), ny = static_cast<std::uint64_t>(n[1]),
                 nz = static_cast<std::uint64_t>(n[2]);
      const auto y0 = static_cast<std::uint64_t>(fluid->y_offset),
                 yc = static_cast<std::uint64_t>(fluid->y_count);
      f.create_group(kFluid);
      f.set_attr(kFluid, kCells, as_vector(fluid->cells));
      f.set_attr(kFluid, kSpacing, as_vector(fluid->spacing_m));
      f.set_attr(kFluid, kOrigin, as_vector(fluid->origin_m));
      f.set_attr(kFluid, kLayout,
                 std::string("arrays (n_z, n_y, n_x[, 3]), x fastest; cells, spacing, origin as (x, y, z)"));
      f.write_block(kVoidFraction, fluid->void_fraction, {nz, ny, nx}, {0, y0, 0}, {nz, yc, nx});
      f.set_attr(kVoidFraction, kUnit, std::string("1"));
      f.write_block(kCellVelocity, fluid->velocity, {nz, ny, nx, 3}, {0, y0, 0, 0}, {nz, yc, nx, 3});
      f.set_attr(kCellVelocity, kUnit, std::string("m/s"));
      f.write_block(kPressure, fluid->pressure, {nz, ny, nx}, {0, y0, 0}, {nz, yc, nx});
      f.set_attr(kPressure, kUnit, std::string("Pa"));
      if (fluid->eps_velocity) {
        f.write_block(kEpsVelocity, fluid->eps_velocity, {nz, ny, nx, 3}, {0, y0, 0, 0}, {nz, yc, nx, 3});
        f.set_attr(kEpsVelocity, kUnit, std::string("m/s"));
        f.set_attr(kEpsVelocity, kDefinition,
                   std::string("cell-centred eps*u: mean of the two faces' eps_f u_f, eps_f the mean of the two "
                               "cells; sums to the solver's face sum <eps u> exactly"));
      }
      // The time level of every field (the filter combines them; see docs/schema-filtered.md)
      f.set_attr(kFluid, kTimeLevel,
                 std::string("all fluid fields at the snapshot's time t_n = step * dt_DEM (fluid level n, "
                             "before the fluid step that starts at t_n)"));
      f.set_attr(kPressure, kDefinition,
                 std::string("periodic part of the pressure: the mean gradient rho_mix g (/particles attribute "
                             "pressure_gradient_mean) removed"));
    }
  });
}

}  // namespace cgd::schema
