// The physical system of derived files (core/physical_system.hpp).
#include "core/physical_system.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/error.hpp"
#include "core/h5.hpp"
#include "core/schema/common.hpp"
#include "core/scene.hpp"

namespace cgd {

namespace {

/// The numeric fields in the order they are compared: the attribute name, the scene key, the member.
struct SystemField {
  const char* file_key;
  const char* scene_key;
  double PhysicalSystem::*member;
};
constexpr SystemField kSystemFields[] = {
    {"diameter_m", "particles.diameter", &PhysicalSystem::diameter_m},
    {"particle_density_kg_m3", "particles.density", &PhysicalSystem::particle_density_kg_m3},
    {"fluid_density_kg_m3", "fluid.density", &PhysicalSystem::fluid_density_kg_m3},
    {"fluid_viscosity_Pa_s", "fluid.viscosity", &PhysicalSystem::fluid_viscosity_Pa_s},
    {"gravity_m_s2", "|domain.gravity|", &PhysicalSystem::gravity_m_s2},
    {"u_t_m_s", "u_t (derived)", &PhysicalSystem::u_t_m_s},
    {"l_char_m", "L_char (derived)", &PhysicalSystem::l_char_m},
};

std::string number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", x);
  return buf;
}

}  // namespace

PhysicalSystem physical_system(const Scene& scene, DragLaw base_law) {
  if (!scene.fluid) throw InputError(scene.source_path + ": the scene has no [fluid] section (no fluid, no drag)");
  const FluidConfig& f = *scene.fluid;
  const Vec3& g = scene.domain.gravity_m_s2;
  PhysicalSystem s;
  s.micro_drag = is_microscopic(f.drag) ? f.drag : base_law;
  s.u_t_m_s = scene.derived.u_t_m_s;
  s.l_char_m = scene.derived.l_char_m;
  s.diameter_m = scene.particles.diameter_m;
  s.particle_density_kg_m3 = scene.particles.density_kg_m3;
  s.fluid_density_kg_m3 = f.density_kg_m3;
  s.fluid_viscosity_Pa_s = f.viscosity_Pa_s;
  s.gravity_m_s2 = std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
  return s;
}

double gravity_from_scales(double u_t_m_s, double l_char_m, double diameter_m) {
  return u_t_m_s * u_t_m_s / (diameter_m * std::pow(l_char_m / diameter_m, 3));
}

void write_physical_system(h5::File& f, const PhysicalSystem& system, const char* law_key) {
  f.set_attr("/", law_key, std::string(to_string(system.micro_drag)));
  for (const SystemField& field : kSystemFields) f.set_attr("/", field.file_key, system.*field.member);
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
  for (const SystemField& field : kSystemFields) {
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
  s.gravity_m_s2 = f.has_attr("/", "gravity_m_s2") ? positive_attr("gravity_m_s2")
                                                   : gravity_from_scales(s.u_t_m_s, s.l_char_m, s.diameter_m);
  return s;
}

std::optional<SystemDifference> compare_systems(const PhysicalSystem& first, const PhysicalSystem& second,
                                                bool compare_law, double relative_tolerance) {
  for (const SystemField& field : kSystemFields) {
    const double a = first.*field.member, b = second.*field.member;
    if (!(std::abs(a - b) <= relative_tolerance * std::max(std::abs(a), std::abs(b))))
      return SystemDifference{field.file_key, field.scene_key, number(a), number(b)};
  }
  if (compare_law && first.micro_drag != second.micro_drag)
    return SystemDifference{"micro_drag", "fluid.drag", std::string("\"") + to_string(first.micro_drag) + "\"",
                            std::string("\"") + to_string(second.micro_drag) + "\""};
  return std::nullopt;
}

}  // namespace cgd
