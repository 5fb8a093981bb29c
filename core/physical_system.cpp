// The physical system of derived files (core/physical_system.hpp).
#include "core/physical_system.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/error.hpp"
#include "core/schema/common.hpp"
#include "core/scene.hpp"

namespace cgd {

namespace {

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

std::optional<SystemDifference> compare_systems(const PhysicalSystem& first, const PhysicalSystem& second,
                                                bool compare_law, double relative_tolerance) {
  for (const schema::SystemAttribute& field : schema::kSystemAttributes) {
    const double a = first.*field.member, b = second.*field.member;
    if (!(std::abs(a - b) <= relative_tolerance * std::max(std::abs(a), std::abs(b))))
      return SystemDifference{field.file_key, field.scene_key, number(a), number(b)};
  }
  if (compare_law && first.micro_drag != second.micro_drag)
    return SystemDifference{schema::names::kMicroLawAttribute, "fluid.drag", std::string("\"") + to_string(first.micro_drag) + "\"",
                            std::string("\"") + to_string(second.micro_drag) + "\""};
  return std::nullopt;
}

}  // namespace cgd
