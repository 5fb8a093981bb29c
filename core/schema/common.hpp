#pragma once
// What every cgd file of a run carries (docs/schema-run.md "Common root attributes" and "/params"): the
// names of the common root attributes and of the /params attributes a reader takes back, each spelled once;
// write_common, which stamps a file with them; RunPhysics and read_run_physics, which take /params back.
// The format files of core/schema/ (snapshot, series, checkpoint, filtered, drag_model, coarse_summary)
// build on this; nothing outside core/schema/ spells these names.
#include <mpi.h>

#include <array>
#include <string>

#include "core/h5.hpp"
#include "core/physical_system.hpp"
#include "core/schema/check.hpp"  // Format

namespace cgd {
struct Scene;
}

namespace cgd::schema::names {

// common root attributes (schema::write_common)
inline constexpr const char* kRoot = "/";
inline constexpr const char* kFormat = "cgd_format";
inline constexpr const char* kFormatVersion = "cgd_format_version";
inline constexpr const char* kCodeVersion = "code_version";
inline constexpr const char* kCreated = "created";
inline constexpr const char* kScene = "scene";
/// The runs' microscopic drag law (PhysicalSystem::micro_drag: beetstra, wen-yu, stokes), a root attribute
/// of the filtered file and of the drag model file (version 2; version-1 model files: base_drag).
inline constexpr const char* kMicroLawAttribute = "micro_drag";

// /params: the group, and the attributes a reader takes back (the writer spells the others once, in
// write_params)
inline constexpr const char* kParams = "/params";
inline constexpr const char* kSceneName = "scene_name";
inline constexpr const char* kHasFluid = "has_fluid";
inline constexpr const char* kBoxSize = "box_size_m";
inline constexpr const char* kGravity = "gravity_m_s2";  // /params: the vector g; the filtered and model files' root: |g|
inline constexpr const char* kDiameter = "diameter_m";
inline constexpr const char* kDensity = "density_kg_m3";
inline constexpr const char* kSolidsFraction = "solids_fraction";
inline constexpr const char* kParcelSize = "parcel_size";
inline constexpr const char* kFluidDensity = "fluid_density_kg_m3";
inline constexpr const char* kFluidViscosity = "fluid_viscosity_Pa_s";
inline constexpr const char* kCoupling = "coupling";
inline constexpr const char* kDrag = "drag";
inline constexpr const char* kPressureGradientForce = "pressure_gradient_force";
inline constexpr const char* kUt = "u_t_m_s";
inline constexpr const char* kLChar = "l_char_m";
inline constexpr const char* kTref = "t_ref_s";

// attributes of groups and datasets
inline constexpr const char* kUnit = "unit";              // of every dataset
inline constexpr const char* kDefinition = "definition";  // of /fluid/pressure and /fluid/eps_velocity

}  // namespace cgd::schema::names

namespace cgd::schema {

/// Root attributes every cgd file carries: cgd_format, cgd_format_version (format's row in
/// core/schema/check.hpp), code_version, created (ISO 8601 UTC), scene (the effective scene as TOML text);
/// and group /params with every physical and derived parameter of the scene as attributes (SI, names with
/// units). Collective.
void write_common(h5::File& file, const Format& format, const Scene& scene);

/// The physics of the run a file came from, from its /params group (SI).
struct RunPhysics {
  std::string scene_name, scene_toml;
  double diameter_m = 0, particle_density_kg_m3 = 0, parcel_size = 1;
  double solids_fraction = 0;                 // the scene's <phi_p>
  std::array<double, 3> box_size_m{}, gravity_m_s2{};
  bool has_fluid = false;
  double fluid_density_kg_m3 = 0, fluid_viscosity_Pa_s = 0;
  std::string drag, coupling;                  // e.g. "beetstra", "two-way" (empty without fluid)
  bool pressure_gradient_force = false;        // the particles feel -V_p grad p
  double u_t_m_s = 0, l_char_m = 0, t_ref_s = 0;

  /// The run's physical system (core/physical_system.hpp), |g| the norm of gravity_m_s2. InputError
  /// naming the scene when the run has no fluid or its law `drag` is not microscopic (a coarse run's).
  PhysicalSystem system() const;
};

/// The physical system's numeric fields as root attributes of the filtered and drag model files, in the order
/// compare_systems compares them: the attribute name, the scene key (for messages), the member.
struct SystemAttribute {
  const char* file_key;
  const char* scene_key;
  double PhysicalSystem::*member;
};
inline constexpr SystemAttribute kSystemAttributes[] = {
    {"diameter_m", "particles.diameter", &PhysicalSystem::diameter_m},
    {"particle_density_kg_m3", "particles.density", &PhysicalSystem::particle_density_kg_m3},
    {"fluid_density_kg_m3", "fluid.density", &PhysicalSystem::fluid_density_kg_m3},
    {"fluid_viscosity_Pa_s", "fluid.viscosity", &PhysicalSystem::fluid_viscosity_Pa_s},
    {"gravity_m_s2", "|domain.gravity|", &PhysicalSystem::gravity_m_s2},
    {"u_t_m_s", "u_t (derived)", &PhysicalSystem::u_t_m_s},
    {"l_char_m", "L_char (derived)", &PhysicalSystem::l_char_m},
};

/// Writes the system as root attributes of `f`, the law under `law_key` (names::kMicroLawAttribute; version-1 model files: base_drag).
void write_physical_system(h5::File& f, const PhysicalSystem& system, const char* law_key);

/// Reads the system from the root attributes of `f` (the law under `law_key`). `what` names the kind of
/// file in messages ("filtered file", "drag model file"). InputError naming the file and the key for a
/// missing attribute or a law that is not microscopic ("<path>: <law_key> = \"radl2014\": ..."). A file
/// without gravity_m_s2 gets gravity_from_scales (older filtered files).
PhysicalSystem read_physical_system(const h5::File& f, const char* law_key, const std::string& what);

/// /params of `f` (and the root attribute `scene`): every attribute the reader takes, of its type, finite,
/// and positive where a size or a density must be. InputError naming the file and the attribute.
RunPhysics read_run_physics(const h5::File& f);

}  // namespace cgd::schema
