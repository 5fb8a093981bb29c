// Scene loading, --set overrides, validation and derived numbers (the formulas: docs/models.md).
// The only file that sees the TOML parser: everything after load_scene works on plain structs.
//
// Steps of load_scene_from_string:
//   1. parse the text (a syntax error names the line and column);
//   2. apply the --set overrides in order (each is section.key=value, the value read as TOML; a key
//      with an alternative, e.g. run.end_time / run.end_time_tref, replaces the other: alternatives());
//   3. check the structure against the schema below: known sections and keys (did-you-mean on a
//      typo, the right section for a misplaced key), value types, array lengths, alternatives given
//      twice; every problem found is listed in one error;
//   4. read every key into the config structs with its range check (one rule per key);
//   5. cross-key rules (keys that need a [fluid] section, ...), the tool's refusals (ToolAccepts) and
//      the derived numbers of docs/models.md;
//   6. print the effective scene (after overrides) as TOML text.
// Every error is an InputError: "<file>: <section.key> = <value given>: <what is allowed>".
#include "core/scene.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "core/checksum.hpp"
#include "core/error.hpp"
#include "core/filtered_drag.hpp"
#include "core/scales.hpp"
#include "core/scene_toml.hpp"

namespace cgd {

const char* to_string(ContactModel m) { return m == ContactModel::None ? "none" : "spring-dashpot"; }

const char* to_string(Coupling c) {
  constexpr const char* kNames[] = {"quiescent", "one-way", "two-way"};  // the enum's order
  return kNames[static_cast<int>(c)];
}

namespace {

using namespace scene_toml;

// ---- the scene -----------------------------------------------------------------------------------

double norm(const Vec3& v) {
  return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

/// fluid.drag: the laws the tool accepts (the drag-law table of core/drag.hpp). The microscopic laws serve
/// every run; the filtered laws belong to coarse-grid runs, and a tool that refuses them (cgd-generate)
/// neither offers them nor accepts them.
DragLaw drag_law(const SceneReader& in, const ToolAccepts& accepts) {
  const auto given = in.string("fluid", "drag");
  if (!given) return FluidConfig{}.drag;
  const std::string micro = drag_law_names(DragKind::Micro);
  if (const auto law = drag_law_from_name(*given)) {
    if (is_microscopic(*law) || accepts.filtered_drag) return *law;
    in.fail_value("fluid", "drag",
                  "a filtered drag model belongs to coarse-grid runs (cgd-coarse); this tool runs resolved "
                  "simulations, which take a microscopic law: " +
                      micro);
  }
  std::vector<std::string> names;
  for (const DragLawInfo& row : kDragLaws)
    if (row.kind == DragKind::Micro || accepts.filtered_drag) names.emplace_back(row.name);
  std::string rule = "must be one of " + (accepts.filtered_drag ? drag_law_names() : micro);
  rule += accepts.filtered_drag
              ? " (" + micro + ": microscopic laws; " + drag_law_names(DragKind::Filtered) +
                    ": filtered laws of coarse-grid runs, \"model\" with fluid.drag_model = PATH)"
              : " (microscopic drag law; the filtered laws belong to coarse-grid runs, cgd-coarse)";
  if (auto near = closest(*given, names)) rule += "; did you mean " + quote(*near) + "?";
  in.fail_value("fluid", "drag", rule);
}

/// [particles]: diameter, density, solids fraction (required), parcel size, initial rms speed, seed.
ParticlesConfig read_particles(const SceneReader& in) {
  ParticlesConfig p;
  p.diameter_m = in.positive("particles", "diameter", in.required("particles", "diameter"));
  p.density_kg_m3 = in.positive("particles", "density", in.required("particles", "density"));
  p.solids_fraction =
      in.in_range("particles", "solids_fraction", in.required("particles", "solids_fraction"), 0.0, 0.64,
                  false, "; 0.64 is random close packing: more particles would not fit");
  if (auto v = in.number("particles", "parcel_size")) {
    if (!(*v >= 1.0))
      in.fail_value("particles", "parcel_size",
                    "must be >= 1 (alpha = d_parcel / d_prim; 1: every particle resolved)");
    p.parcel_size = *v;
  }
  if (auto v = in.number("particles", "velocity_rms"))
    p.velocity_rms_m_s = in.non_negative("particles", "velocity_rms", *v);
  if (auto v = in.integer("particles", "seed")) {
    if (*v < 0) in.fail_value("particles", "seed", "must be an integer >= 0");
    p.seed = static_cast<std::uint64_t>(*v);
  }

  return p;
}

/// [domain]: the box (size_dp or size, every edge >= 4 parcel diameters) and gravity.
DomainConfig read_domain(const SceneReader& in, const ParticlesConfig& p) {
  DomainConfig domain;
  const double d = p.diameter_m;
  const double parcel_d = p.parcel_size * d;
  const bool has_size_dp = in.has("domain", "size_dp"), has_size = in.has("domain", "size");
  if (!has_size_dp && !has_size)
    in.fail(
        "domain.size_dp is missing: required, the box edges [x, y, z] in primary diameters (or domain.size "
        "in m)");
  const char* size_key = has_size_dp ? "size_dp" : "size";
  const Vec3 size_given = *in.vec3("domain", size_key);
  for (int i = 0; i < 3; ++i) {
    const double edge_m = has_size_dp ? size_given[i] * d : size_given[i];
    domain.size_m[i] = edge_m;
    if (!(edge_m >= 4.0 * parcel_d)) {
      const std::string minimum = has_size_dp
                                      ? SceneReader::format_short(4.0 * p.parcel_size) + " primary diameters"
                                      : SceneReader::format_short(4.0 * parcel_d) + " m";
      in.fail_value("domain", size_key,
                    "every edge must be >= 4 parcel diameters (4 alpha d_p = " + minimum + "); edge " +
                        "xyz"[i] + " is too small");
    }
  }
  if (auto g = in.vec3("domain", "gravity")) domain.gravity_m_s2 = *g;

  return domain;
}

/// [contact]: the contact law and its parameters; a spring-dashpot needs stiffness or gamma_star.
ContactConfig read_contact(const SceneReader& in) {
  ContactConfig c;
  c.model = in.choice<ContactModel>(
      "contact", "model", {{"spring-dashpot", ContactModel::SpringDashpot}, {"none", ContactModel::None}},
      c.model);
  if (auto v = in.number("contact", "gamma_star")) c.gamma_star = in.positive("contact", "gamma_star", *v);
  if (auto v = in.number("contact", "stiffness")) c.stiffness_n_N_m = in.positive("contact", "stiffness", *v);
  if (auto v = in.number("contact", "t_star"))
    c.t_star = in.in_range("contact", "t_star", *v, 0.0, 0.2, true);
  if (auto v = in.number("contact", "restitution"))
    c.restitution = in.in_range("contact", "restitution", *v, 0.0, 1.0, true);
  if (auto v = in.number("contact", "friction")) c.friction = in.non_negative("contact", "friction", *v);
  if (auto v = in.number("contact", "kn_over_kt")) c.kn_over_kt = in.positive("contact", "kn_over_kt", *v);
  if (auto v = in.number("contact", "gamman_over_gammat"))
    c.gamman_over_gammat = in.positive("contact", "gamman_over_gammat", *v);
  if (auto v = in.number("contact", "skin_over_dp"))
    c.skin_over_dp = in.non_negative("contact", "skin_over_dp", *v);  // absent: adaptive (scene.hpp)
  if (c.model != ContactModel::None && !c.gamma_star && !c.stiffness_n_N_m)
    in.fail(std::string("contact.stiffness is missing: with contact.model = \"") + to_string(c.model) +
            "\" give contact.stiffness (N/m) or contact.gamma_star (dimensionless, needs a [fluid] section)");

  return c;
}

/// [particle_stress]: the particle-phase pressure of core/particle_stress.hpp, on the fluid grid's cells (so only
/// when the fluid is solved); every key but `model` is refused while the model is "none".
ParticleStressParams read_particle_stress(const SceneReader& in, const ToolAccepts& accepts, const FluidConfig& f) {
  ParticleStressParams p;
  if (!in.has_section("particle_stress")) return p;
  p.model = in.choice<ParticleStressModel>(
      "particle_stress", "model",
      {{"none", ParticleStressModel::None}, {"harris-crighton", ParticleStressModel::HarrisCrighton}}, p.model);
  if (p.model == ParticleStressModel::None) {
    for (const char* key : {"p_s", "beta", "phi_packed", "epsilon"})
      if (in.has("particle_stress", key))
        in.fail_value("particle_stress", key,
                      "is only used with particle_stress.model = \"harris-crighton\" (the model is \"none\"); remove "
                      "it or set the model");
    return p;
  }
  if (!accepts.filtered_drag)
    in.fail_value("particle_stress", "model",
                  "is a closure of the coarse grid (cgd-coarse): a resolved run (cgd-generate) resolves the particle "
                  "phase's stresses through its contacts; remove [particle_stress]");
  if (f.coupling == Coupling::Quiescent)
    in.fail_value("particle_stress", "model",
                  "needs a solved fluid (fluid.coupling = \"two-way\" or \"one-way\"): the pressure's gradient is "
                  "taken on the fluid grid's cells, and a quiescent fluid has no grid");
  if (auto v = in.number("particle_stress", "p_s")) p.p_s_Pa = in.positive("particle_stress", "p_s", *v);
  if (auto v = in.number("particle_stress", "beta")) {
    if (!(*v >= 2.0 && *v <= 10.0))
      in.fail_value("particle_stress", "beta",
                    "must be in [2, 10] (Snider 2001 uses 2 to 5; below 2 the potential of the discrete force, "
                    "integral_0^phi tau(s)/s^2 ds, diverges at phi = 0: core/particle_stress.hpp)");
    p.beta = *v;
  }
  if (auto v = in.number("particle_stress", "phi_packed"))
    p.phi_packed = in.in_range("particle_stress", "phi_packed", *v, 0.0, 1.0, false);
  if (auto v = in.number("particle_stress", "epsilon"))
    p.epsilon = in.in_range("particle_stress", "epsilon", *v, 0.0, 1.0, true);
  return p;
}

/// [fluid] (absent: a dry run, and gamma_star is refused): density below the particles', viscosity,
/// Courant number, coupling, drag law (the tool's ToolAccepts), the model file and its checksum, the grid
/// (cells or dx_over_dp; required when the fluid is solved).
std::optional<FluidConfig> read_fluid(const SceneReader& in, const ToolAccepts& accepts, const Scene& s) {
  const ParticlesConfig& p = s.particles;
  const ContactConfig& c = s.contact;
  const double d = p.diameter_m;
  if (in.has_section("fluid")) {
    FluidConfig f;
    if (auto v = in.number("fluid", "density")) f.density_kg_m3 = *v;
    if (!(f.density_kg_m3 > 0.0 && f.density_kg_m3 < p.density_kg_m3))
      in.fail_value("fluid", "density",
                    "must be in (0, particles.density = " + SceneReader::format_short(p.density_kg_m3) +
                        ") kg/m^3 (fluid density; the particles must sink)");
    if (auto v = in.number("fluid", "viscosity")) f.viscosity_Pa_s = in.positive("fluid", "viscosity", *v);
    // AB2 with central advection (sim/fluid/solver.hpp, von Neumann): |G| <= 1 for Co <= 0.5 only
    if (auto v = in.number("fluid", "courant"))
      f.courant = in.in_range("fluid", "courant", *v, 0.0, 0.5, true,
                              "; above 0.5 the fluid scheme -- Adams-Bashforth 2 with central advection -- is "
                              "unstable: its amplification factor exceeds 1 for Co = sum_d |u_d| dt/h_d > 0.5");
    f.coupling = in.choice<Coupling>(
        "fluid", "coupling",
        {{"two-way", Coupling::TwoWay}, {"one-way", Coupling::OneWay}, {"quiescent", Coupling::Quiescent}},
        f.coupling);
    f.drag = drag_law(in, accepts);
    if (auto v = in.boolean("fluid", "pressure_gradient_force")) f.pressure_gradient_force = *v;
    if (auto v = in.boolean("fluid", "parcel_correction")) f.parcel_correction = *v;
    if (auto v = in.boolean("fluid", "drag_own_deposit")) f.drag_own_deposit = *v;
    if (auto v = in.number("fluid", "filter_to_grid_ratio")) {
      if (!(*v >= 1.0 && *v <= 16.0))
        in.fail_value("fluid", "filter_to_grid_ratio",
                      "must be in [1, 16] (the filter width Delta of a filtered law in fluid cells; 1 = the cell, "
                      "the paper's rule: docs/closure.md)");
      f.filter_to_grid_ratio = *v;
      if (f.drag != DragLaw::Radl2014 && f.drag != DragLaw::Model && f.filter_to_grid_ratio != 1.0)
        in.fail_value("fluid", "filter_to_grid_ratio",
                      std::string("is only used by the filtered laws \"radl2014\" and \"model\" (the scene has \"") +
                          to_string(f.drag) + "\"); remove it");
    }
    if (auto v = in.string("fluid", "drag_model")) f.drag_model_path = *v;
    if (auto v = in.string("fluid", "drag_model_checksum")) f.drag_model_checksum = *v;
    const bool takes_model = f.drag == DragLaw::Model || f.drag == DragLaw::Drift;
    if (takes_model && f.drag_model_path.empty())
      in.fail_missing("fluid", "drag_model", std::string(" with fluid.drag = \"") + to_string(f.drag) + "\"");
    if (!takes_model && !f.drag_model_path.empty())
      in.fail_value("fluid", "drag_model",
                    std::string("is only used with fluid.drag = \"model\" or \"drift\" (the scene has \"") +
                        to_string(f.drag) + "\"); remove it or set fluid.drag = \"model\" (or \"drift\" for a drift table)");
    if (!f.drag_model_path.empty()) {
      std::error_code ec;
      if (!std::filesystem::is_regular_file(f.drag_model_path, ec))
        in.fail_value("fluid", "drag_model", "no such file");
      // The model is read here, once (its checksum with it); load_scene checks it against the scene's
      // physical system once the derived numbers are known. The checksum identifies the model in every
      // output file (the effective scene records it); a scene that pins one refuses a model file that has
      // changed since.
      auto model = std::make_shared<const DragModel>(load_drag_model(f.drag_model_path));
      const std::string sum = model->checksum;
      if (!f.drag_model_checksum.empty() && f.drag_model_checksum != sum)
        in.fail_value("fluid", "drag_model_checksum",
                      "differs from the checksum of " + f.drag_model_path + " (" + sum +
                          "): the model file has changed since this scene recorded it");
      // the file's kind must be the law's: a drift table (curves = "drift_table") only with "drift", any other
      // model only with "model"
      if (f.drag == DragLaw::Model && model->drift)
        in.fail_value("fluid", "drag_model",
                      "is a drift table (curves = \"drift_table\", cgd-fit --drift-table N), the drift-velocity closure's "
                      "H(phi, cell slip): allowed with fluid.drag = \"drift\"; fluid.drag = \"model\" takes a model of "
                      "h(phi), a(phi) (cgd-fit) or a --grid-table table");
      if (f.drag == DragLaw::Drift && !model->drift)
        in.fail_value("fluid", "drag_model",
                      std::string("is a model of curves = \"") + (model->table ? "table" : "splines") +
                          "\" (a phi-only correction): fluid.drag = \"drift\" takes a drift table (curves = \"drift_table\", "
                          "cgd-fit --drift-table N); use this file with fluid.drag = \"model\"");
      f.drag_model_checksum = sum;
      f.drag_model = std::move(model);
    }
    const bool has_cells = in.has("fluid", "cells"), has_dx = in.has("fluid", "dx_over_dp");
    if (auto cells = in.ivec3("fluid", "cells")) {
      for (int i = 0; i < 3; ++i) {
        if ((*cells)[i] < 1 || (*cells)[i] > 1'000'000)
          in.fail_value("fluid", "cells",
                        "every entry must be an integer in [1, 1000000] (fluid cells along x, y, z)");
        f.cells[i] = static_cast<int>((*cells)[i]);
      }
    }
    if (auto v = in.number("fluid", "dx_over_dp")) {
      // one rule: a cell size that gives 1 to 1000000 cells along every box edge
      const std::string rule = "must be > 0 and give between 1 and 1000000 cells along every box edge (" +
                               std::string(key_spec("fluid", "dx_over_dp").meaning) + "; the box is " +
                               SceneReader::format_short(s.domain.size_m[0] / d) + " x " +
                               SceneReader::format_short(s.domain.size_m[1] / d) + " x " +
                               SceneReader::format_short(s.domain.size_m[2] / d) + " d_p)";
      if (!(*v > 0.0)) in.fail_value("fluid", "dx_over_dp", rule);
      for (int i = 0; i < 3; ++i) {
        const double n = std::round(s.domain.size_m[i] / (*v * d));
        if (!(n >= 1.0) || n > 1e6)
          in.fail_value("fluid", "dx_over_dp",
                        rule + "; it gives " + SceneReader::format_short(n) + " cells along " + "xyz"[i]);
        f.cells[i] = static_cast<int>(n);
      }
    }
    if (f.coupling != Coupling::Quiescent && !has_cells && !has_dx)
      in.fail(std::string("fluid.cells is missing: required when the fluid is solved (fluid.coupling = \"") +
              to_string(f.coupling) +
              "\"); give fluid.cells = [nx, ny, nz] or fluid.dx_over_dp (a quiescent fluid needs no grid)");
    // Model A needs -V_p grad p on the particles when they act on the fluid: without it the fluid's
    // -eps grad p' (the periodic part) has no counterpart, and the mixture momentum drifts (0.6 m/s^2 at
    // phi = 0.1). One-way and quiescent runs may switch it off (no momentum goes back to the fluid).
    if (f.coupling == Coupling::TwoWay && !f.pressure_gradient_force)
      in.fail_value("fluid", "pressure_gradient_force",
                    "must be true with fluid.coupling = \"two-way\": without the pressure-gradient force on the "
                    "particles the fluid's periodic pressure gradient has no counterpart and the mixture momentum "
                    "is not conserved (docs/models.md \"Periodic driving\"); switch it off only with "
                    "fluid.coupling = \"one-way\" or \"quiescent\"");
    f.particle_stress = read_particle_stress(in, accepts, f);
    return f;
  } else {
    if (in.has_section("particle_stress"))
      in.fail("[particle_stress] needs a [fluid] section with a solved fluid: the particle-phase pressure acts "
              "through the fluid grid's cells (docs/scene-keys.md); remove the section");
    if (c.gamma_star)
      in.fail_value(
          "contact", "gamma_star",
          "needs a [fluid] section: gamma* is defined with the terminal velocity u_t, which is undefined "
          "without a fluid; give contact.stiffness (N/m) instead");
  }

  return std::nullopt;
}

/// [run], the keys read before the derived numbers: the t_ref keys need a fluid, the checkpoint
/// interval, the explicit DEM step (its times are read by read_run_times, with t_ref known).
RunConfig read_run(const SceneReader& in, const Scene& s) {
  RunConfig r;
  for (const char* key : {"end_time_tref", "dump_interval_tref", "series_interval_tref", "sampling_start_tref"})
    if (in.has("run", key) && !s.fluid)
      in.fail_value("run", key,
                    "needs a [fluid] section: t_ref = u_t/g is undefined without a fluid; give run." +
                        std::string(key).substr(0, std::string(key).size() - 5) + " in s instead");
  if (auto v = in.number("run", "checkpoint_wall_s"))
    r.checkpoint_wall_s = in.positive("run", "checkpoint_wall_s", *v);
  if (auto v = in.number("run", "dt")) r.dt_s = in.positive("run", "dt", *v);

  return r;
}

/// [numerics]: the numerical limits, each in its range.
NumericsConfig read_numerics(const SceneReader& in) {
  NumericsConfig nm;
  if (auto v = in.number("numerics", "void_fraction_floor"))
    nm.void_fraction_floor = in.in_range("numerics", "void_fraction_floor", *v, 0.0, 1.0, false);
  if (auto v = in.number("numerics", "overlap_limit"))
    nm.overlap_limit = in.in_range("numerics", "overlap_limit", *v, 0.0, 1.0, true);
  if (auto v = in.number("numerics", "overlap_warning_fraction"))
    nm.overlap_warning_fraction = in.in_range("numerics", "overlap_warning_fraction", *v, 0.0, 1.0, true);
  if (auto v = in.number("numerics", "viscous_safety"))
    nm.viscous_safety = in.in_range("numerics", "viscous_safety", *v, 0.0, 0.99, true,
                                    "; measured stable up to 0.99 for the roughest eps fields, solver.hpp");
  if (auto v = in.number("numerics", "drag_safety"))
    nm.drag_safety = in.in_range("numerics", "drag_safety", *v, 0.0, 1.0, true,
                                 "; explicit particle drag over a fluid step overshoots above 1");
  if (auto v = in.integer("numerics", "sort_interval_steps")) {
    if (*v < 1) in.fail_value("numerics", "sort_interval_steps", "must be an integer >= 1");
    nm.sort_interval_steps = *v;
  }
  if (auto v = in.number("numerics", "particle_stress_courant"))
    nm.particle_stress_courant = in.in_range("numerics", "particle_stress_courant", *v, 0.0, 1.0, true,
                                             "; an explicit pressure force held over a fluid step");
  if (auto v = in.integer("numerics", "skin_target_steps")) {
    if (*v < 1) in.fail_value("numerics", "skin_target_steps", "must be an integer >= 1");
    nm.skin_target_steps = *v;
  }

  return nm;
}

/// The derived numbers of docs/models.md that the rest of the scene needs: volumes and masses of the
/// particle and the parcel; with a fluid the Stokes relaxation time and, with gravity, u_t, Re_p, Fr_p,
/// L_ref, L_char and t_ref (without gravity the keys that need them are refused).
void derive_scales(const SceneReader& in, Scene& s) {
  const ParticlesConfig& p = s.particles;
  const ContactConfig& c = s.contact;
  const double d = p.diameter_m;
  const double g = norm(s.domain.gravity_m_s2);
  // ---- derived numbers (docs/models.md) ----
  DerivedScales& x = s.derived;
  x.particle_volume_m3 = sphere_volume(d);
  x.particle_mass_kg = p.density_kg_m3 * x.particle_volume_m3;
  x.parcel_diameter_m = p.parcel_size * d;
  x.parcel_volume_factor = std::pow(p.parcel_size, 3);
  x.parcel_volume_m3 = x.parcel_volume_factor * x.particle_volume_m3;
  x.parcel_mass_kg = x.parcel_volume_factor * x.particle_mass_kg;

  if (s.fluid) {
    const FluidConfig& f = *s.fluid;
    x.stokes_relaxation_s = p.density_kg_m3 * d * d / (18.0 * f.viscosity_Pa_s);
    if (g > 0.0) {
      x.u_t_m_s =
          schiller_naumann_terminal_velocity(d, p.density_kg_m3, f.density_kg_m3, f.viscosity_Pa_s, g);
      x.re_p = f.density_kg_m3 * d * x.u_t_m_s / f.viscosity_Pa_s;
      x.fr_p = x.u_t_m_s * x.u_t_m_s / (g * d);
      x.l_ref_m = x.u_t_m_s * x.u_t_m_s / g;
      x.l_char_m = x.l_ref_m * std::pow(x.fr_p, -2.0 / 3.0);
      x.t_ref_s = x.u_t_m_s / g;
    } else {
      for (const char* key : {"end_time_tref", "dump_interval_tref", "series_interval_tref", "sampling_start_tref"})
        if (in.has("run", key))
          in.fail_value("run", key,
                        "needs gravity: t_ref = u_t/g is undefined when domain.gravity = [0, 0, 0]");
      if (c.gamma_star)
        in.fail_value("contact", "gamma_star",
                      "needs gravity: gamma* = (g/u_t) sqrt(rho_p d^3/k_n) is undefined when domain.gravity "
                      "= [0, 0, 0]; "
                      "give contact.stiffness (N/m) instead");
    }
  }

}

/// [run]'s times, in s or in units of t_ref: the end time > 0, the intervals and the start of the
/// sampling window >= 0 (by default the first 15 t_ref are transient).
void read_run_times(const SceneReader& in, Scene& s) {
  RunConfig& r = s.run;
  const DerivedScales& x = s.derived;
  const auto time_key = [&](const char* seconds_key, const char* tref_key,
                            bool positive) -> std::optional<double> {
    const bool has_t = in.has("run", tref_key);
    const char* key = has_t ? tref_key : seconds_key;
    const auto given = in.number("run", key);
    if (!given) return std::nullopt;
    const double value = positive ? in.positive("run", key, *given) : in.non_negative("run", key, *given);
    return has_t ? value * x.t_ref_s : value;
  };
  const auto end_time = time_key("end_time", "end_time_tref", true);
  if (!end_time) in.fail_missing("run", "end_time", " (or run.end_time_tref with a [fluid] section)");
  r.end_time_s = *end_time;
  r.dump_interval_s = time_key("dump_interval", "dump_interval_tref", false).value_or(0.0);
  r.series_interval_s = time_key("series_interval", "series_interval_tref", false).value_or(0.0);
  // the window of time averages (cgd-coarse's slip): by default the first 15 t_ref are transient
  r.sampling_start_s = time_key("sampling_start", "sampling_start_tref", false).value_or(15.0 * x.t_ref_s);

}

/// The contact parameters of the parcels and the DEM step (contact.t_star x t_c, run.dt without
/// contacts, or t_star x the Stokes relaxation time), the fluid grid and its Courant step at u_t, the
/// particle count and the memory estimate.
void derive_steps(const SceneReader& in, Scene& s) {
  const ParticlesConfig& p = s.particles;
  const ContactConfig& c = s.contact;
  const RunConfig& r = s.run;
  DerivedScales& x = s.derived;
  const double d = p.diameter_m;
  const double g = norm(s.domain.gravity_m_s2);
  if (s.has_contacts()) {
    const double k_n_primary =
        c.stiffness_n_N_m ? *c.stiffness_n_N_m
                          : stiffness_from_gamma_star(*c.gamma_star, p.density_kg_m3, d, g, x.u_t_m_s);
    // docs/models.md "Parcels": k_n,parcel = alpha k_n keeps restitution, relative overlap and t_c/(d/v).
    const SpringDashpot sd = spring_dashpot(p.parcel_size * k_n_primary, c.restitution,
                                            x.parcel_mass_kg / 2.0, c.kn_over_kt, c.gamman_over_gammat);
    x.k_n_N_m = sd.k_n;
    x.k_t_N_m = sd.k_t;
    x.gamma_n_kg_s = sd.gamma_n;
    x.gamma_t_kg_s = sd.gamma_t;
    x.t_c_s = sd.t_c;
    if (r.dt_s)
      in.fail_value("run", "dt",
                    std::string("only used when contact.model = \"none\"; with contacts the DEM step is "
                                "contact.t_star x t_c (t_c = ") +
                        SceneReader::format_short(sd.t_c) + " s): set contact.t_star instead");
    x.dt_dem_s = c.t_star * sd.t_c;
  } else if (r.dt_s) {
    x.dt_dem_s = *r.dt_s;
  } else if (s.fluid) {
    x.dt_dem_s = c.t_star * x.stokes_relaxation_s;  // no contacts: resolve the drag relaxation
  } else {
    in.fail(
        "run.dt is missing: required when contact.model = \"none\" and there is no [fluid] section "
        "(nothing else sets the time step; s, explicit DEM time step)");
  }

  if (s.solves_fluid()) {
    x.cells = s.fluid->cells;
    double smallest_cell = s.domain.size_m[0] / x.cells[0];
    for (int i = 1; i < 3; ++i) smallest_cell = std::min(smallest_cell, s.domain.size_m[i] / x.cells[i]);
    x.dt_fluid_s = s.fluid->courant * smallest_cell / std::max(x.u_t_m_s, 1e-30);
  }

  const double box_volume = s.domain.size_m[0] * s.domain.size_m[1] * s.domain.size_m[2];
  const double count =
      std::round(p.solids_fraction * box_volume / x.parcel_volume_m3);
  if (count < 1.0)
    in.fail_value("particles", "solids_fraction",
                  "gives no particle in a box of " + SceneReader::format_short(box_volume) +
                      " m^3; raise it or enlarge the box");
  if (count > 9e15) in.fail_value("particles", "solids_fraction", "gives more particles than can be counted");
  x.particle_count = static_cast<std::int64_t>(count);

  // Measured peak per particle (bench/README.md): ~300 B of DEM arrays (state, neighbour list with
  // history, ghosts; measured before the in-place integration of issue 17 dropped the second state buffer, so now
  // a little high) plus placement and I/O buffers: 450 B is the peak seen at 200k-600k particles.
  x.memory_estimate_bytes = count * 450.0;
  if (s.solves_fluid())
    x.memory_estimate_bytes +=
        16.0 * sizeof(double) * double(x.cells[0]) * double(x.cells[1]) * double(x.cells[2]);
}

/// Scenes that validate key by key but cannot be run, refused before anything is written (and the
/// odd ones that may be meant, kept as warnings).
void check_runnable(const SceneReader& in, Scene& s) {
  const RunConfig& r = s.run;
  const DerivedScales& x = s.derived;
  // The drag laws' range (core/drag.hpp): Beetstra was fitted to lattice-Boltzmann data for Re < 1000, Wen-Yu's
  // C_d switches to Newton's 0.44 above 1000, Stokes drag holds for Re << 1. A terminal Reynolds number far
  // outside is almost always a unit mistake (a diameter in um or mm given as m).
  if (s.fluid && x.re_p > 1000.0)
    in.fail_value("particles", "diameter",
                  "gives a terminal Reynolds number Re_p = " + SceneReader::format_short(x.re_p) +
                      " (u_t = " + SceneReader::format_short(x.u_t_m_s) +
                      " m/s), outside the range the drag laws were fitted for (Re_p <= 1000); the diameter is "
                      "in metres (75 um is 75e-6)");
  // A run that would do no step: the run does round(end_time / dt_DEM) steps.
  if (std::llround(r.end_time_s / x.dt_dem_s) < 1)
    in.fail_value("run", in.has("run", "end_time") ? "end_time" : "end_time_tref",
                  "is shorter than one DEM step (dt_DEM = " + SceneReader::format_short(x.dt_dem_s) +
                      " s): the run would do no step; lengthen it or shorten the step (contact.t_star)");
  // A fluid step is a whole number of DEM steps: a DEM step above the fluid's Courant step at u_t
  // would advance the fluid by more than the Courant number allows from the first step on.
  if (s.solves_fluid() && x.dt_dem_s > x.dt_fluid_s)
    in.fail(std::string("the DEM step dt_DEM = ") + SceneReader::format_short(x.dt_dem_s) +
            " s (contact.t_star x t_c) is longer than the fluid step " + SceneReader::format_short(x.dt_fluid_s) +
            " s (fluid.courant x cell / u_t): a fluid step is a whole number of DEM steps; lower contact.t_star, "
            "stiffen the contacts (contact.gamma_star / contact.stiffness) or use larger cells");
  if (s.fluid && s.fluid->drag == DragLaw::Stokes && x.re_p > 10.0)
    s.warnings.push_back("fluid.drag = \"stokes\" at Re_p = " + SceneReader::format_short(x.re_p) +
                         ": Stokes drag holds for Re_p << 1 and underestimates the drag here by 1 + 0.15 Re^0.687 = " +
                         SceneReader::format_short(1.0 + 0.15 * std::pow(x.re_p, 0.687)));
}

/// The scene from a checked table: one reader per section, then the derived numbers and the refusals, in
/// the order in which the keys depend on each other (the t_ref-based times need u_t and g, the DEM step
/// needs the contacts and run.dt).
Scene build_scene(const SceneReader& in, const ToolAccepts& accepts) {
  Scene s;
  s.particles = read_particles(in);
  s.domain = read_domain(in, s.particles);
  s.contact = read_contact(in);
  s.fluid = read_fluid(in, accepts, s);
  s.run = read_run(in, s);
  s.numerics = read_numerics(in);
  derive_scales(in, s);
  read_run_times(in, s);
  derive_steps(in, s);
  check_runnable(in, s);
  return s;
}

std::string read_file(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path + ": cannot read the scene file: no such file");
  if (fs::is_directory(path, ec)) throw InputError(path + ": cannot read the scene file: it is a directory");
  std::ifstream file(path, std::ios::binary);
  if (!file) throw InputError(path + ": cannot read the scene file: " + std::strerror(errno));
  std::ostringstream text;
  text << file.rdbuf();
  if (file.bad()) throw InputError(path + ": cannot read the scene file: " + std::strerror(errno));
  return text.str();
}

}  // namespace

Scene load_scene_from_string(const std::string& toml_text, const std::string& origin,
                             const std::vector<std::string>& overrides, const ToolAccepts& accepts) {
  toml::table root;
  try {
    root = toml::parse(toml_text, std::string_view(origin));
  } catch (const toml::parse_error& e) {
    const auto& where = e.source().begin;
    throw InputError(origin + ": TOML syntax error at line " + std::to_string(where.line) + ", column " +
                     std::to_string(where.column) + ": " + std::string(e.description()));
  }
  std::set<std::string> overridden;
  for (const auto& o : overrides) overridden.insert(apply_override(root, o, origin));

  const SceneReader reader(origin, root, overridden);
  reader.check_structure();
  Scene scene = build_scene(reader, accepts);
  scene.name = std::filesystem::path(origin).stem().string();
  scene.source_path = origin;
  if (scene.fluid && scene.fluid->drag_model) check_model_matches_scene(*scene.fluid->drag_model, scene);
  if (scene.fluid && !scene.fluid->drag_model_checksum.empty())  // record the model file's checksum
    root["fluid"].as_table()->insert_or_assign("drag_model_checksum", scene.fluid->drag_model_checksum);
  scene.effective_toml = emit_scene(root);
  return scene;
}

Scene load_scene(const std::string& path, const std::vector<std::string>& overrides,
                 const ToolAccepts& accepts) {
  return load_scene_from_string(read_file(path), path, overrides, accepts);
}

// ---- describe_scene ------------------------------------------------------------------------------

namespace {

std::string num(double v) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.4g", v);
  return buffer;
}

std::string with_unit(double v, const char* unit) {
  return num(v) + " " + unit;
}

std::string vec(const Vec3& v) {
  return "[" + num(v[0]) + ", " + num(v[1]) + ", " + num(v[2]) + "]";
}

std::string bytes(double b) {
  const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  int i = 0;
  while (b >= 1024.0 && i < 4) {
    b /= 1024.0;
    ++i;
  }
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.3g %s", b, units[i]);
  return buffer;
}

}  // namespace

bool restart_may_change(const std::string& key) {
  static const std::set<std::string> allowed = {
      "run.end_time",        "run.end_time_tref",        "run.dump_interval", "run.dump_interval_tref",
      "run.series_interval", "run.series_interval_tref", "run.checkpoint_wall_s"};
  return allowed.count(key) != 0;
}

namespace {
bool same_value(const toml::node& a, const toml::node& b) {
  if ((a.is_integer() || a.is_floating_point()) && (b.is_integer() || b.is_floating_point()))
    return a.value<double>() == b.value<double>();
  const toml::array* x = a.as_array();
  const toml::array* y = b.as_array();
  if (x && y) {
    if (x->size() != y->size()) return false;
    for (std::size_t i = 0; i < x->size(); ++i)
      if (!same_value(*x->get(i), *y->get(i))) return false;
    return true;
  }
  return format_node(a) == format_node(b);
}
}  // namespace

std::vector<std::string> restart_differences(const std::string& checkpoint_toml, const std::string& given_toml) {
  toml::table then, now;
  try {
    then = toml::parse(checkpoint_toml, std::string_view("checkpoint scene"));
    now = toml::parse(given_toml, std::string_view("scene"));
  } catch (const toml::parse_error& e) {
    throw InputError(std::string("the checkpoint's stored scene cannot be read: ") + std::string(e.description()));
  }
  std::vector<std::string> out;
  for (const auto& section : schema()) {
    const toml::table* a = then[section.name].as_table();
    const toml::table* b = now[section.name].as_table();
    for (const auto& key : section.keys) {
      const std::string name = std::string(section.name) + "." + key.name;
      if (restart_may_change(name)) continue;
      const toml::node* x = a ? a->get(key.name) : nullptr;
      const toml::node* y = b ? b->get(key.name) : nullptr;
      if (!x && !y) continue;
      if (x && y && same_value(*x, *y)) continue;
      out.push_back(name + " = " + (x ? format_node(*x) : std::string("(not given)")) + " in the checkpoint, " +
                    (y ? format_node(*y) : std::string("(not given)")) + " now");
    }
  }
  return out;
}

std::string describe_scene(const Scene& s) {
  std::ostringstream out;
  const auto row = [&](const std::string& label, const std::string& value) {
    out << "  " << label << std::string(label.size() < 26 ? 26 - label.size() : 1, ' ') << value << "\n";
  };
  const DerivedScales& x = s.derived;
  const double d = s.particles.diameter_m;

  out << "scene " << s.name << (s.source_path.empty() ? "" : " (" + s.source_path + ")") << "\n";
  out << "effects\n";
  if (s.has_contacts())
    row("contacts", std::string(to_string(s.contact.model)) + " (e = " + num(s.contact.restitution) +
                        ", t* = " + num(s.contact.t_star) + ", neighbour skin " +
                        (s.contact.skin_over_dp ? num(*s.contact.skin_over_dp) + " d_p)"
                                                : "adaptive per particle, " + num(ContactConfig::kAdaptiveSkinMin) + "-" +
                                                      num(ContactConfig::kAdaptiveSkinMax) + " d_p, used up in ~" +
                                                      std::to_string(s.numerics.skin_target_steps) + " steps)"));
  else
    row("contacts", "none (no neighbour search)");
  if (s.has_friction())
    row("friction and rotation", "on (mu = " + num(s.contact.friction) +
                                     ", tangential history, k_n/k_t = " + num(s.contact.kn_over_kt) + ")");
  else
    row("friction and rotation", "off");
  if (!s.fluid) {
    row("fluid", "none (dry granular run, no grid)");
    row("pressure-gradient force", "off (no fluid)");
  } else {
    const FluidConfig& f = *s.fluid;
    const std::string drag = std::string("drag \"") + to_string(f.drag) + "\"";
    switch (f.coupling) {
      case Coupling::Quiescent:
        row("fluid", "quiescent: " + drag + " toward a fluid at rest, no grid");
        break;
      case Coupling::OneWay:
        row("fluid", "one-way: " + drag + ", fluid solved, no momentum returned to it");
        break;
      case Coupling::TwoWay:
        row("fluid", "two-way: " + drag + ", fluid solved, momentum exchanged");
        break;
    }
    if (f.coupling == Coupling::Quiescent && f.pressure_gradient_force)
      row("pressure-gradient force", "on (buoyancy of the fluid at rest)");
    else
      row("pressure-gradient force", f.pressure_gradient_force ? "on" : "off");
    const ParticleStressParams& ps = f.particle_stress;
    if (ps.model == ParticleStressModel::HarrisCrighton)
      row("particle-phase pressure", "Harris-Crighton, P_s = " + with_unit(ps.p_s_Pa, "Pa") + ", beta = " + num(ps.beta) +
                                         ", phi_cp = " + num(ps.phi_packed) + ", eps = " + num(ps.epsilon));
    else
      row("particle-phase pressure", "off");
  }
  const double g = norm(s.domain.gravity_m_s2);
  row("gravity", g > 0 ? "on " + vec(s.domain.gravity_m_s2) + " m/s^2" : "off");

  out << "scene\n";
  row("box", num(s.domain.size_m[0]) + " x " + num(s.domain.size_m[1]) + " x " + num(s.domain.size_m[2]) +
                 " m (" + num(s.domain.size_m[0] / d) + " x " + num(s.domain.size_m[1] / d) + " x " +
                 num(s.domain.size_m[2] / d) + " d_p)");
  row("particles", "d_p = " + with_unit(d, "m") +
                       ", rho_p = " + with_unit(s.particles.density_kg_m3, "kg/m^3") +
                       ", <phi_p> = " + num(s.particles.solids_fraction));
  if (s.fluid)
    row("fluid", "rho_f = " + with_unit(s.fluid->density_kg_m3, "kg/m^3") +
                     ", mu_f = " + with_unit(s.fluid->viscosity_Pa_s, "Pa s") +
                     (s.solves_fluid() ? ", Co = " + num(s.fluid->courant) : std::string()));
  row("run", "end time " + with_unit(s.run.end_time_s, "s") + ", snapshots " +
                 (s.run.dump_interval_s > 0 ? "every " + with_unit(s.run.dump_interval_s, "s")
                                            : std::string("of the final state only")) +
                 ", checkpoints every " + with_unit(s.run.checkpoint_wall_s, "s of wall time"));

  out << "derived\n";
  row("particle volume V_p", with_unit(x.particle_volume_m3, "m^3"));
  row("particle mass", with_unit(x.particle_mass_kg, "kg"));
  if (s.particles.parcel_size != 1.0) {
    row("parcel size alpha", num(s.particles.parcel_size));
    row("parcel diameter", with_unit(x.parcel_diameter_m, "m"));
    row("parcel mass", with_unit(x.parcel_mass_kg, "kg"));
  }
  row(s.particles.parcel_size != 1.0 ? "parcel count" : "particle count", std::to_string(x.particle_count));
  if (s.fluid) {
    row("u_t (Schiller-Naumann)", with_unit(x.u_t_m_s, "m/s"));
    row("Re_p", num(x.re_p));
    row("Fr_p", num(x.fr_p));
    row("L_ref = u_t^2/g", with_unit(x.l_ref_m, "m"));
    row("L_char", with_unit(x.l_char_m, "m") + " (" + num(x.l_char_m / d) + " d_p)");
    row("t_ref = u_t/g", with_unit(x.t_ref_s, "s"));
    row("Stokes relaxation", with_unit(x.stokes_relaxation_s, "s"));
  }
  if (s.has_contacts()) {
    const std::string suffix = s.particles.parcel_size != 1.0 ? " (parcel-scaled)" : "";
    row("k_n", with_unit(x.k_n_N_m, "N/m") + suffix);
    row("k_t", with_unit(x.k_t_N_m, "N/m"));
    row("gamma_n", with_unit(x.gamma_n_kg_s, "kg/s"));
    row("gamma_t", with_unit(x.gamma_t_kg_s, "kg/s"));
    row("t_c", with_unit(x.t_c_s, "s"));
  }
  row("dt_DEM", with_unit(x.dt_dem_s, "s") + " (" + num(s.run.end_time_s / x.dt_dem_s) + " steps)");
  if (s.solves_fluid()) {
    row("dt_fluid (initial)", with_unit(x.dt_fluid_s, "s") + " (Courant step at u_t; adapts, see \"fluid step\")");
    row("cells", std::to_string(x.cells[0]) + " x " + std::to_string(x.cells[1]) + " x " +
                     std::to_string(x.cells[2]) + " (cell " + num(s.domain.size_m[0] / x.cells[0] / d) +
                     " d_p along x)");
  } else {
    row("cells", "none (no grid)");
  }
  row("memory estimate", bytes(x.memory_estimate_bytes));
  const NumericsConfig& nm = s.numerics;
  row("numerics", "overlap limit " + num(nm.overlap_limit) + " d (warning at " + num(nm.overlap_warning_fraction) +
                      " of it), sort every " + std::to_string(nm.sort_interval_steps) + " steps" +
                      (s.solves_fluid() ? ", void-fraction floor " + num(nm.void_fraction_floor) +
                                              ", viscous safety " + num(nm.viscous_safety) + ", drag safety " +
                                              num(nm.drag_safety)
                                        : std::string()));
  for (const std::string& w : s.warnings) out << "warning: " << w << "\n";
  return out.str();
}

}  // namespace cgd
