#pragma once
// Scene: what to simulate, as plain validated config structs (every key: docs/scene-keys.md).
// core/scene.cpp is the only place that sees the TOML parser; physics code receives these structs.
// SI units everywhere; the unit is in the name or the comment of every field.
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/drag.hpp"  // DragLaw: the drag-law table
#include "core/particle_stress.hpp"  // ParticleStressParams: [particle_stress]

namespace cgd {

using Vec3 = std::array<double, 3>;

struct DomainConfig {
  Vec3 size_m{};                     // box edges (x, y = vertical, z), m; from size or size_dp * d_p
  Vec3 gravity_m_s2{0.0, -9.81, 0.0};
};

struct ParticlesConfig {
  double diameter_m = 75e-6;         // primary diameter d_p
  double density_kg_m3 = 1500.0;     // rho_p
  double solids_fraction = 0.05;     // domain-averaged <phi_p>
  double parcel_size = 1.0;          // alpha = d_parcel / d_prim
  double velocity_rms_m_s = 0.0;     // rms speed of the random initial velocities
  std::uint64_t seed = 1;            // placement and velocities
};

enum class ContactModel { None, SpringDashpot };

struct ContactConfig {
  ContactModel model = ContactModel::SpringDashpot;
  std::optional<double> gamma_star;  // dimensionless stiffness (docs/models.md "Contact law"); or stiffness_n
  std::optional<double> stiffness_n_N_m;
  double t_star = 0.02;              // dt_DEM / t_c
  double restitution = 0.9;
  double friction = 0.1;             // Coulomb mu_pp; 0 switches off tangential history and rotation
  double kn_over_kt = 3.5;
  double gamman_over_gammat = 1.0;
  // Verlet skin of a pair in parcel diameters. Given: fixed. Absent: adaptive (docs/models.md "Contact law"):
  // at each list build each particle's half-skin is set from its own speed so that it would last about
  // numerics.skin_target_steps DEM steps, a pair's within [kAdaptiveSkinMin, kAdaptiveSkinMax] parcel diameters.
  std::optional<double> skin_over_dp;
  static constexpr double kAdaptiveSkinMin = 0.05, kAdaptiveSkinMax = 0.5;
  /// The smallest skin a run uses (what the slab and ghost checks must allow).
  double smallest_skin_over_dp() const { return skin_over_dp ? *skin_over_dp : kAdaptiveSkinMin; }
};

enum class Coupling { Quiescent, OneWay, TwoWay };
struct DragModel;  // a drag model file as read (core/filtered_drag.hpp)

struct FluidConfig {
  double density_kg_m3 = 1.3;
  double viscosity_Pa_s = 1.8e-5;
  std::array<int, 3> cells{0, 0, 0};  // from cells or dx_over_dp (0: not set)
  double courant = 0.3;
  Coupling coupling = Coupling::TwoWay;
  DragLaw drag = DragLaw::Beetstra;
  bool pressure_gradient_force = true;
  bool parcel_correction = true;      // filtered laws: c_corr(alpha) on (false: c_corr = 1, for the parcel fit)
  // the drag law's phi at a particle includes the particle's own deposit (true, the usual CFD-DEM); false: that
  // share, V_p alpha^3 sum_c w_c^2 / V_cell, is taken out of it (issue 28's diagnostic of the parcels' self-bias)
  bool drag_own_deposit = true;
  // filtered laws (radl2014, model): the filter width Delta at which the correction is evaluated, in units of the
  // cube root of the fluid cell volume (docs/closure.md "A filter wider than the cell"): 1, the paper's rule
  // Delta = the cell; r > 1, the correction of the structures a coarse grid cannot build up to r cells
  double filter_to_grid_ratio = 1.0;
  std::string drag_model_path;        // fluid.drag_model: model file of drag = "model" (cgd-fit), as given
  std::string drag_model_checksum;    // its FNV-1a checksum (16 hex digits), recorded in the effective scene
  // drag = "model": the file, read once by load_scene and checked there against the scene's physical
  // system (check_model_matches_scene); the engine uses it as it is (filtered_drag_setup reads nothing)
  std::shared_ptr<const DragModel> drag_model;
  // [particle_stress] (model "none": nothing of it is allocated or computed; core/particle_stress.hpp)
  ParticleStressParams particle_stress;
};

struct RunConfig {
  double end_time_s = 0.0;            // from end_time or end_time_tref * t_ref
  double dump_interval_s = 0.0;       // from dump_interval or dump_interval_tref; 0: final state only
  double series_interval_s = 0.0;     // 0: one series row per (fluid or DEM) output step, see sim
  double checkpoint_wall_s = 600.0;   // wall-clock seconds between checkpoints
  double sampling_start_s = 0.0;      // start of the time-average window (default 15 t_ref; 0 without fluid)
  std::optional<double> dt_s;         // explicit time step (needed when contact.model = "none" and no fluid)
};

/// Numerical constants that change results (issue 10, item 6); the defaults are the values the engine
/// was verified with. Scene section [numerics]; every one is written to the files' /params.
struct NumericsConfig {
  double void_fraction_floor = 0.3;        // eps_min of the coupling's conservative floor (coupler.hpp)
  double overlap_limit = 0.25;             // largest relative overlap (of the diameter) before a run error
  double overlap_warning_fraction = 0.5;   // warn once when the largest overlap passes this x overlap_limit
  double viscous_safety = 0.8;             // fluid step <= this x AB2's explicit-viscosity limit (solver.hpp)
  double drag_safety = 0.5;                // fluid step x beta_max / rho_p <= this (explicit particle drag)
  std::int64_t sort_interval_steps = 1000; // DEM steps between reorderings of the particles by cell
  std::int64_t skin_target_steps = 20;     // adaptive skin (contact.skin_over_dp absent): DEM steps a list lasts
  double particle_stress_courant = 0.5;    // [particle_stress]: longest fluid step x sqrt(tau'/rho_p) / cell, at most
};

/// Numbers derived from the scene, printed at start and stored in every output file (/params).
struct DerivedScales {
  double particle_volume_m3 = 0;      // primary particle volume V_p
  double particle_mass_kg = 0;        // primary particle mass
  double parcel_diameter_m = 0;       // alpha * d_p (collision diameter)
  double parcel_volume_factor = 1;    // alpha^3: primaries per parcel (the one place it is computed)
  double parcel_volume_m3 = 0;        // alpha^3 V_p, the parcel's volume
  double parcel_mass_kg = 0;          // alpha^3 * primary mass
  // fluid-related; 0 when the scene has no fluid
  double u_t_m_s = 0;                 // Schiller-Naumann terminal velocity (docs/models.md convention)
  double re_p = 0;                    // rho_f d u_t / mu_f
  double fr_p = 0;                    // u_t^2 / (g d_p)
  double l_ref_m = 0;                 // u_t^2 / g
  double l_char_m = 0;                // L_ref Fr_p^(-2/3)
  double t_ref_s = 0;                 // u_t / g
  double stokes_relaxation_s = 0;     // rho_p d^2 / (18 mu_f)
  // contact; 0 when contact.model = "none"
  double k_n_N_m = 0, k_t_N_m = 0;    // parcel-scaled stiffness (k_n,parcel = alpha k_n)
  double gamma_n_kg_s = 0, gamma_t_kg_s = 0;
  double t_c_s = 0;                   // contact time of two equal parcels
  double dt_dem_s = 0;
  double dt_fluid_s = 0;              // 0 when no fluid is solved (estimated from Courant and u_t)
  std::array<int, 3> cells{0, 0, 0};
  std::int64_t particle_count = 0;    // parcels when alpha > 1
  double memory_estimate_bytes = 0;
};

struct Scene {
  std::string name;                   // file stem, e.g. "dry_settling"
  std::string source_path;            // the file it was read from
  std::string effective_toml;         // the scene after --set overrides, as TOML text
  DomainConfig domain;
  ParticlesConfig particles;
  ContactConfig contact;
  std::optional<FluidConfig> fluid;   // absent: dry granular run, no grid
  RunConfig run;
  NumericsConfig numerics;
  DerivedScales derived;
  std::vector<std::string> warnings;  // odd but possibly meant: printed with the scene (describe_scene)

  bool has_contacts() const { return contact.model != ContactModel::None; }
  bool has_friction() const { return has_contacts() && contact.friction > 0.0; }
  bool solves_fluid() const { return fluid && fluid->coupling != Coupling::Quiescent; }
};

/// What the tool loading a scene accepts beyond the schema: a scene means the same to every tool, but
/// not every tool runs every scene, and a refusal is made (and the allowed values are offered) while
/// the scene is read.
struct ToolAccepts {
  bool filtered_drag = true;  // fluid.drag = "radl2014" / "model": coarse-grid runs (cgd-coarse)
};
/// A resolved run (cgd-generate) uses a microscopic drag law.
inline constexpr ToolAccepts kResolvedRunAccepts{.filtered_drag = false};

/// Load, apply overrides ("section.key=value"), validate and derive. Throws InputError whose
/// message names the file, the key, the value given and what is allowed; a scene's structural
/// problems (unknown, misplaced and mistyped keys, both keys of an alternative) are listed all at once.
/// An override of a key that has an alternative (run.end_time / run.end_time_tref, fluid.cells /
/// fluid.dx_over_dp, ...) replaces the alternative the file gives. Writes nothing.
Scene load_scene(const std::string& path, const std::vector<std::string>& overrides = {},
                 const ToolAccepts& accepts = {});

/// Same, from TOML text (tests); `origin` stands in for the file name in messages.
Scene load_scene_from_string(const std::string& toml_text, const std::string& origin,
                             const std::vector<std::string>& overrides = {}, const ToolAccepts& accepts = {});

/// The keys a restart may change (the run's end, its snapshot, series and checkpoint intervals): every
/// other key is physics, and a restart that changes it would continue a different simulation.
bool restart_may_change(const std::string& section_dot_key);

/// Every key other than those a restart may change whose value differs between two scenes given as
/// effective TOML text (Scene::effective_toml), one line each: "section.key = OLD in the checkpoint, NEW
/// now" (a key given in only one of them counts as a difference). Numbers compare by value.
std::vector<std::string> restart_differences(const std::string& checkpoint_toml, const std::string& given_toml);

/// Human-readable table of the effects that are on and the derived numbers (printed at start).
std::string describe_scene(const Scene& scene);

/// Names used in files and messages (to_string(DragLaw) is in core/drag.hpp, from the drag-law table).
const char* to_string(ContactModel m);
const char* to_string(Coupling c);

}  // namespace cgd
