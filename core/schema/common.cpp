// What every cgd file of a run carries (docs/schema-run.md "Common root attributes", "/params"): the writer
// write_common (with write_params, every field of the scene) and the reader of /params, read_run_physics.
#include "core/schema/common.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <array>
#include <cstring>
#include <ctime>
#include <stdexcept>

#include "core/error.hpp"
#include "core/scene.hpp"
#include "core/version.hpp"

namespace cgd::schema {
namespace {

using namespace names;

std::string number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", x);
  return buf;
}

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

}  // namespace

void write_common(h5::File& file, const Format& format, const Scene& scene) {
  using namespace names;
  file.set_attr(kRoot, kFormat, std::string(format.name));
  file.set_attr(kRoot, kFormatVersion, format.version);
  file.set_attr(kRoot, kCodeVersion, std::string(code_version()));
  file.set_attr(kRoot, kCreated, utc_now_iso8601(file.comm()));
  file.set_attr(kRoot, kScene, scene.effective_toml);
  write_params(file, scene);
}

using namespace names;

void write_physical_system(h5::File& f, const PhysicalSystem& system, const char* law_key) {
  f.set_attr("/", law_key, std::string(to_string(system.micro_drag)));
  for (const SystemAttribute& field : kSystemAttributes) f.set_attr("/", field.file_key, system.*field.member);
}

PhysicalSystem read_physical_system(const h5::File& f, const char* law_key, const std::string& what) {
  const std::string& path = f.path();
  auto need = [&](const char* key) {
    if (!f.has_attr("/", key)) throw InputError(path + ": " + what + " lacks the root attribute " + key);
  };
  need(law_key);
  // every field of a physical system is a size, a density, a speed or a viscosity: finite and positive
  auto positive_attr = [&](const char* key) {
    const double v = schema::finite_attr(f, "/", key);
    if (!(v > 0))
      throw InputError(path + ": attribute '" + key + "' of '/' is " + number(v) + ", expected a positive number");
    return v;
  };
  PhysicalSystem s;
  for (const SystemAttribute& field : kSystemAttributes) {
    if (field.member == &PhysicalSystem::gravity_m_s2) continue;  // optional in older files: below
    need(field.file_key);
    s.*field.member = positive_attr(field.file_key);
  }
  const std::string law = f.attr_string("/", law_key);
  if (const auto micro = microscopic_drag_law(law))
    s.micro_drag = *micro;
  else
    throw InputError(path + ": " + law_key + " = \"" + law + "\": the " + what +
                     "'s law must be a microscopic law (" + drag_law_names(DragKind::Micro) + ")");
  s.gravity_m_s2 = f.has_attr(kRoot, kGravity) ? positive_attr(kGravity)
                                                   : gravity_from_scales(s.u_t_m_s, s.l_char_m, s.diameter_m);
  return s;
}

RunPhysics read_run_physics(const h5::File& f) {
  RunPhysics p;
  const std::string g = kParams;
  if (!f.exists(g)) throw InputError(f.path() + ": no group " + g + ", expected the scene's parameters there");
  auto positive = [&](const char* name) {
    const double v = finite_attr(f, g, name);
    if (!(v > 0))
      throw InputError(f.path() + ": attribute '" + name + "' of '" + g + "' is " + std::to_string(v) +
                       ", expected a positive number");
    return v;
  };
  auto vec3 = [&](const char* name) {
    const std::vector<double> v = finite_attrs(f, g, name, 3);
    return std::array<double, 3>{v[0], v[1], v[2]};
  };
  p.scene_name = f.attr_string(g, kSceneName);
  p.scene_toml = f.has_attr(kRoot, kScene) ? f.attr_string(kRoot, kScene) : "";
  p.diameter_m = positive(kDiameter);
  p.particle_density_kg_m3 = positive(kDensity);
  p.parcel_size = positive(kParcelSize);
  p.solids_fraction = finite_attr(f, g, kSolidsFraction);
  p.box_size_m = vec3(kBoxSize);
  for (double edge : p.box_size_m)
    if (!(edge > 0))
      throw InputError(f.path() + ": attribute '" + std::string(kBoxSize) + "' of '" + g + "' holds " + std::to_string(edge) +
                       ", expected positive edges");
  p.gravity_m_s2 = vec3(kGravity);
  p.has_fluid = f.attr_int(g, kHasFluid) != 0;
  if (p.has_fluid) {
    p.fluid_density_kg_m3 = positive(kFluidDensity);
    p.fluid_viscosity_Pa_s = positive(kFluidViscosity);
    p.drag = f.attr_string(g, kDrag);
    p.coupling = f.attr_string(g, kCoupling);
    p.pressure_gradient_force = f.attr_int(g, kPressureGradientForce) != 0;
    p.u_t_m_s = positive(kUt);
    p.l_char_m = positive(kLChar);
    p.t_ref_s = positive(kTref);
  }
  return p;
}


PhysicalSystem RunPhysics::system() const {
  const auto law = microscopic_drag_law(drag);
  if (!has_fluid || !law)
    throw InputError(scene_name + ": the run's drag law is '" + drag + "': its physical system needs a fluid and a "
                     "microscopic law (" + drag_law_names(DragKind::Micro) + ")");
  const auto& g = gravity_m_s2;
  return PhysicalSystem{*law,          u_t_m_s,
                        l_char_m,      diameter_m,
                        particle_density_kg_m3, fluid_density_kg_m3,
                        fluid_viscosity_Pa_s,   std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2])};
}

}  // namespace cgd::schema
