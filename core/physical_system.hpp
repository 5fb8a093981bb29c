#pragma once
// The physical system a derived file was made for (docs/models.md's u_t and L_char conventions): the
// particle diameter and density, the fluid density and viscosity, |g|, the derived u_t and L_char, and
// the microscopic drag law the file's numbers are relative to. One record and one tolerance-based
// comparison, used by every file that carries it; its attribute names, writer and reader are the schema
// layer's (core/schema/common.hpp: kSystemAttributes, write_physical_system, read_physical_system):
//   filtered files (cgd-filter, docs/schema-filtered.md): root attributes, the law under `micro_drag`;
//   drag model files (cgd-fit, docs/schema-drag-model.md): root attributes, the law under `micro_drag`;
//   snapshots (/params, written by core/schema/common.cpp): RunPhysics::system() (core/schema/common.hpp);
//   scenes: physical_system(scene).
// Adding a field: the member, its row in schema::kSystemAttributes (core/schema/common.hpp), the schema pages.
#include <optional>
#include <string>

#include "core/drag.hpp"

namespace cgd {

struct Scene;

/// "schiller-naumann": the u_t convention of docs/models.md that every cgd file uses (the drag model
/// file's attribute u_t_convention).
inline constexpr const char* kUtConvention = "schiller-naumann";

/// The particle/fluid system (SI units). u_t is docs/models.md's (Schiller-Naumann) terminal velocity,
/// L_char = (u_t^2/g) Fr_p^(-2/3); both derive from the others, and are stored so that a file can be
/// used without recomputing them.
struct PhysicalSystem {
  DragLaw micro_drag = DragLaw::Beetstra;  // a microscopic law (kind Micro in core/drag.hpp's table)
  double u_t_m_s = 0, l_char_m = 0;
  double diameter_m = 0, particle_density_kg_m3 = 0, fluid_density_kg_m3 = 0, fluid_viscosity_Pa_s = 0;
  double gravity_m_s2 = 0;  // |g|

  /// The microscopic law's parameters (rho_f, mu_f, d).
  DragParams drag_params() const { return {fluid_density_kg_m3, fluid_viscosity_Pa_s, diameter_m}; }
};

/// The system of a scene with a [fluid] section; micro_drag is the scene's law when it is microscopic,
/// else `base_law` (a filtered law's base: the model file's, Beetstra for radl2014). InputError naming
/// the scene without a [fluid] section.
PhysicalSystem physical_system(const Scene& scene, DragLaw base_law = DragLaw::Beetstra);

/// |g| of a system from u_t, L_char and d: L_char^3 = u_t^2 d^2 / g (docs/models.md). For files
/// written before gravity_m_s2 was stored (filtered files).
double gravity_from_scales(double u_t_m_s, double l_char_m, double diameter_m);

/// The first field in which two systems differ: its file key (e.g. "diameter_m", schema::kSystemAttributes), its scene key
/// ("particles.diameter") and the two values as text.
struct SystemDifference {
  std::string file_key, scene_key, first, second;
};

/// The comparison every user of the record makes: the numbers to `relative_tolerance` (default 1e-6:
/// the files store them to full precision, and u_t and L_char are computed the same way everywhere),
/// in the order d, rho_p, rho_f, mu_f, |g|, u_t, L_char, then the law (exactly) unless `compare_law` is
/// false. nullopt when they agree.
std::optional<SystemDifference> compare_systems(const PhysicalSystem& first, const PhysicalSystem& second,
                                                bool compare_law = true, double relative_tolerance = 1e-6);

}  // namespace cgd
