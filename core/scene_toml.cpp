// The generic TOML machinery of scenes (core/scene_toml.hpp).
#include "core/scene_toml.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace cgd::scene_toml {

// ---- schema --------------------------------------------------------------------------------------

const std::vector<SectionSpec>& schema() {
  static const std::vector<SectionSpec> sections = {
      {"domain",
       {{"size_dp", Kind::Vec3Number, "box edges (x, y = vertical, z) in primary diameters"},
        {"size", Kind::Vec3Number, "box edges (x, y = vertical, z) in m"},
        {"gravity", Kind::Vec3Number, "gravitational acceleration in m/s^2"}}},
      {"particles",
       {{"diameter", Kind::Number, "m, primary particle diameter d_p"},
        {"density", Kind::Number, "kg/m^3, particle density"},
        {"solids_fraction", Kind::Number, "domain-averaged solids volume fraction"},
        {"parcel_size", Kind::Number, "alpha = d_parcel / d_prim"},
        {"velocity_rms", Kind::Number, "m/s, rms speed of the random initial velocities"},
        {"seed", Kind::Integer, "seed of the random placement and velocities"}}},
      {"contact",
       {{"model", Kind::String, "contact law"},
        {"gamma_star", Kind::Number, "dimensionless stiffness (docs/models.md, \"Contact law\")"},
        {"stiffness", Kind::Number, "N/m, normal spring stiffness of two primaries"},
        {"t_star", Kind::Number, "dt_DEM / t_c"},
        {"restitution", Kind::Number, "normal coefficient of restitution"},
        {"friction", Kind::Number, "Coulomb friction coefficient"},
        {"kn_over_kt", Kind::Number, "normal over tangential stiffness"},
        {"gamman_over_gammat", Kind::Number, "normal over tangential damping"},
        {"skin_over_dp", Kind::Number, "Verlet neighbour skin in parcel diameters (absent: adaptive)"}}},
      {"fluid",
       {{"density", Kind::Number, "kg/m^3, fluid density"},
        {"viscosity", Kind::Number, "Pa s, dynamic viscosity of the fluid"},
        {"cells", Kind::Vec3Integer, "fluid cells along x, y, z"},
        {"dx_over_dp", Kind::Number, "fluid cell size in primary diameters"},
        {"courant", Kind::Number, "Courant number of the fluid step"},
        {"coupling", Kind::String, "fluid-particle coupling"},
        {"drag", Kind::String, "microscopic drag law"},
        {"drag_model", Kind::String, "path of the drag model file (cgd-fit) used by drag = \"model\" (or of the drift table of cgd-fit --drift-table, used by drag = \"drift\")"},
        {"drag_model_checksum", Kind::String, "FNV-1a checksum of fluid.drag_model (recorded by cgd)"},
        {"pressure_gradient_force", Kind::Boolean, "apply -V_p grad p to the particles"},
        {"parcel_correction", Kind::Boolean,
         "apply c_corr(alpha) of a filtered law (false: the parcel fit's runs)"},
        {"drag_own_deposit", Kind::Boolean,
         "the drag's phi at a particle includes its own deposit (false: taken out; a diagnostic)"},
        {"filter_to_grid_ratio", Kind::Number,
         "filtered laws: Delta of the correction in fluid cells (1: the cell, the paper's rule)"}}},
      {"particle_stress",
       {{"model", Kind::String, "particle-phase pressure on the particles (\"none\" or \"harris-crighton\")"},
        {"p_s", Kind::Number, "Pa, the pressure scale P_s of tau = P_s phi^beta / max(phi_cp - phi, eps (1 - phi))"},
        {"beta", Kind::Number, "exponent beta of phi in the particle-phase pressure"},
        {"phi_packed", Kind::Number, "close packing phi_cp of the particle-phase pressure"},
        {"epsilon", Kind::Number, "floor eps of the pressure's denominator, relative to 1 - phi"}}},
      {"run",
       {{"end_time", Kind::Number, "s, simulated time"},
        {"end_time_tref", Kind::Number, "simulated time in units of t_ref = u_t/g"},
        {"dump_interval", Kind::Number, "s between snapshots"},
        {"dump_interval_tref", Kind::Number, "snapshot interval in units of t_ref = u_t/g"},
        {"series_interval", Kind::Number, "s between time-series rows"},
        {"series_interval_tref", Kind::Number, "time-series interval in units of t_ref = u_t/g"},
        {"checkpoint_wall_s", Kind::Number, "wall-clock seconds between checkpoints"},
        {"sampling_start", Kind::Number, "s, start of the window of time averages (after the transient)"},
        {"sampling_start_tref", Kind::Number,
         "start of the window of time averages in units of t_ref = u_t/g"},
        {"dt", Kind::Number, "s, explicit DEM time step"}}},
      {"numerics",
       {{"void_fraction_floor", Kind::Number, "smallest void fraction the fluid sees (conservative floor)"},
        {"overlap_limit", Kind::Number, "largest relative overlap (of the diameter) before a run error"},
        {"overlap_warning_fraction", Kind::Number, "fraction of overlap_limit at which the run warns once"},
        {"viscous_safety", Kind::Number, "fluid step over AB2's explicit-viscosity limit"},
        {"drag_safety", Kind::Number, "largest fluid step x beta_max / rho_p (explicit particle drag)"},
        {"sort_interval_steps", Kind::Integer, "DEM steps between reorderings of the particles by cell"},
        {"skin_target_steps", Kind::Integer, "adaptive skin: DEM steps a neighbour list lasts"},
        {"particle_stress_courant", Kind::Number,
         "particle-phase pressure: longest fluid step x its wave speed sqrt(tau'/rho_p) / cell edge, at most"}}},
  };
  return sections;
}

const SectionSpec* find_section(std::string_view name) {
  for (const auto& s : schema())
    if (name == s.name) return &s;
  return nullptr;
}

const KeySpec* find_key(const SectionSpec& section, std::string_view name) {
  for (const auto& k : section.keys)
    if (name == k.name) return &k;
  return nullptr;
}

const KeySpec& key_spec(std::string_view section, std::string_view key) {
  const SectionSpec* s = find_section(section);
  const KeySpec* k = s ? find_key(*s, key) : nullptr;
  if (!k) throw std::logic_error("scene schema has no key " + std::string(section) + "." + std::string(key));
  return *k;
}

// ---- alternatives --------------------------------------------------------------------------------

const std::vector<Alternative>& alternatives() {
  static const std::vector<Alternative> pairs = {
      {"domain", "size_dp", "size", "primary diameters", "m"},
      {"contact", "gamma_star", "stiffness", "dimensionless", "N/m"},
      {"fluid", "cells", "dx_over_dp", "cell counts", "cell size in primary diameters"},
      {"run", "end_time", "end_time_tref", "s", "units of t_ref = u_t/g"},
      {"run", "dump_interval", "dump_interval_tref", "s", "units of t_ref = u_t/g"},
      {"run", "series_interval", "series_interval_tref", "s", "units of t_ref = u_t/g"},
      {"run", "sampling_start", "sampling_start_tref", "s", "units of t_ref = u_t/g"},
  };
  return pairs;
}

/// The other key of the pair `section.key` belongs to, if it belongs to one.
const char* alternative_of(std::string_view section, std::string_view key) {
  for (const auto& a : alternatives())
    if (section == a.section) {
      if (key == a.first) return a.second;
      if (key == a.second) return a.first;
    }
  return nullptr;
}

// ---- did-you-mean --------------------------------------------------------------------------------

std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      const std::size_t substitution = diagonal + (a[i - 1] == b[j - 1] ? 0 : 1);
      row[j] = std::min({above + 1, row[j - 1] + 1, substitution});
      diagonal = above;
    }
  }
  return row[b.size()];
}

/// The candidate closest to `given`, if it is close enough to be a plausible typo.
std::optional<std::string> closest(std::string_view given, const std::vector<std::string>& candidates) {
  std::optional<std::string> best;
  std::size_t best_distance = std::max<std::size_t>(2, given.size() / 3) + 1;
  for (const auto& c : candidates) {
    const std::size_t d = edit_distance(given, c);
    if (d < best_distance) {
      best_distance = d;
      best = c;
    }
  }
  return best;
}

std::string join(const std::vector<std::string>& items, const std::string& separator) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) out += (i ? separator : "") + items[i];
  return out;
}

std::vector<std::string> section_names() {
  std::vector<std::string> names;
  for (const auto& s : schema()) names.emplace_back(s.name);
  return names;
}

std::vector<std::string> key_names(const SectionSpec& section) {
  std::vector<std::string> names;
  for (const auto& k : section.keys) names.emplace_back(k.name);
  return names;
}

std::string section_key_list(const SectionSpec& section) {
  return "keys of [" + std::string(section.name) + "]: " + join(key_names(section), ", ");
}

std::string unknown_section_message(std::string_view given) {
  std::string msg = "unknown section [" + std::string(given) + "]";
  if (auto near = closest(given, section_names())) msg += "; did you mean [" + *near + "]?";
  return msg + " (sections: " + join(section_names(), ", ") + ")";
}

/// "unknown key section.key; did you mean ...?" A key that exists in another section is taken as
/// misplaced before a near name in its own section is offered as a typo. With `with_key_list`, the
/// keys of the section follow (a message listing several problems lists them once, at its end).
std::string unknown_key_message(const SectionSpec& section, std::string_view given, bool with_key_list) {
  std::string msg = "unknown key " + std::string(section.name) + "." + std::string(given);
  const SectionSpec* home = nullptr;
  for (const auto& other : schema())
    if (&other != &section && find_key(other, given)) home = &other;
  if (home) {
    msg += "; did you mean " + std::string(home->name) + "." + std::string(given) + "?";
  } else if (auto near = closest(given, key_names(section))) {
    msg += "; did you mean " + std::string(section.name) + "." + *near + "?";
  }
  if (with_key_list) msg += " (" + section_key_list(section) + ")";
  return msg;
}

// ---- printing values (messages and the effective scene) -------------------------------------------

/// Shortest text that reads back as the same double, always recognisable as a TOML float.
std::string format_float(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buffer[64];
  // shortest round trip, in fixed or scientific notation whichever is shorter (like %g)
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, v, std::chars_format::general);
  std::string text(buffer, result.ptr);
  if (text.find_first_of(".eE") == std::string::npos) text += ".0";
  return text;
}

std::string quote(std::string_view s) {
  std::string out = "\"";
  for (const char c : s) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      case '\r':
        out += "\\r";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char hex[8];
          std::snprintf(hex, sizeof hex, "\\u%04x", static_cast<unsigned>(c));
          out += hex;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

std::string format_node(const toml::node& node) {
  if (const auto* v = node.as_floating_point()) return format_float(v->get());
  if (const auto* v = node.as_integer()) return std::to_string(v->get());
  if (const auto* v = node.as_boolean()) return v->get() ? "true" : "false";
  if (const auto* v = node.as_string()) return quote(v->get());
  if (const auto* a = node.as_array()) {
    std::vector<std::string> items;
    for (const auto& element : *a) items.push_back(format_node(element));
    return "[" + join(items, ", ") + "]";
  }
  if (const auto* t = node.as_table()) {
    std::vector<std::string> items;
    for (const auto& [key, value] : *t) items.push_back(std::string(key.str()) + " = " + format_node(value));
    return "{" + join(items, ", ") + "}";
  }
  std::ostringstream out;  // dates and times: toml++'s own form
  out << toml::node_view<const toml::node>(node);
  return out.str();
}

/// The effective scene, sections and keys in schema order (the root holds nothing else once
/// the structure has been checked).
std::string emit_scene(const toml::table& root) {
  std::string out;
  for (const auto& section : schema()) {
    const toml::table* table = root[section.name].as_table();
    if (!table) continue;
    if (!out.empty()) out += "\n";
    out += "[" + std::string(section.name) + "]\n";
    for (const auto& key : section.keys)
      if (const toml::node* node = table->get(key.name))
        out += std::string(key.name) + " = " + format_node(*node) + "\n";
  }
  return out;
}

// ---- reading -------------------------------------------------------------------------------------

std::string kind_text(Kind kind) {
  switch (kind) {
    case Kind::Number:
      return "a number";
    case Kind::Integer:
      return "an integer";
    case Kind::Boolean:
      return "true or false";
    case Kind::String:
      return "a string";
    case Kind::Vec3Number:
      return "an array of 3 numbers [x, y, z]";
    case Kind::Vec3Integer:
      return "an array of 3 integers [x, y, z]";
  }
  return "?";
}

bool is_finite_number(const toml::node& node) {
  if (node.is_integer()) return true;
  if (const auto* v = node.as_floating_point()) return std::isfinite(v->get());
  return false;
}

double as_double(const toml::node& node) {
  if (const auto* v = node.as_integer()) return static_cast<double>(v->get());
  return node.as_floating_point()->get();
}

bool has_kind(const toml::node& node, Kind kind) {
  switch (kind) {
    case Kind::Number:
      return is_finite_number(node);
    case Kind::Integer:
      return node.is_integer();
    case Kind::Boolean:
      return node.is_boolean();
    case Kind::String:
      return node.is_string();
    case Kind::Vec3Number:
    case Kind::Vec3Integer: {
      const auto* a = node.as_array();
      if (!a || a->size() != 3) return false;
      for (const auto& element : *a)
        if (kind == Kind::Vec3Integer ? !element.is_integer() : !is_finite_number(element)) return false;
      return true;
    }
  }
  return false;
}

/// What a value of the wrong type breaks: the kind the key takes, the offending array element, its meaning.
std::string type_rule(const KeySpec& spec, const toml::node& value) {
  std::string rule = "must be " + kind_text(spec.kind);
  if (spec.kind == Kind::Number && value.is_floating_point()) rule = "must be a finite number";
  if (const auto* a = value.as_array(); a && a->size() != 3) {
    rule += ", got " + std::to_string(a->size()) + " element" + (a->size() == 1 ? "" : "s");
  } else if (a) {
    for (std::size_t i = 0; i < a->size(); ++i)
      if (!has_kind(*a->get(i), spec.kind == Kind::Vec3Integer ? Kind::Integer : Kind::Number)) {
        rule += "; element " + std::to_string(i + 1) + " (" + format_node(*a->get(i)) + ") is not " +
                (spec.kind == Kind::Vec3Integer ? "an integer" : "a finite number");
        break;
      }
  }
  return rule + " (" + spec.meaning + ")";
}


// ---- overrides -----------------------------------------------------------------------------------

std::string trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t");
  if (first == std::string_view::npos) return "";
  const auto last = s.find_last_not_of(" \t");
  return std::string(s.substr(first, last - first + 1));
}

/// Applies one "section.key=value"; returns "section.key".
std::string apply_override(toml::table& root, const std::string& text, const std::string& origin) {
  const std::string shown = "--set " + text;
  const auto fail = [&](const std::string& why) -> void {
    throw InputError(origin + ": " + shown + ": " + why);
  };
  const auto eq = text.find('=');
  if (eq == std::string::npos) fail("expected SECTION.KEY=VALUE, e.g. --set particles.solids_fraction=0.2");
  const std::string name = trim(std::string_view(text).substr(0, eq));
  const std::string value_text = trim(std::string_view(text).substr(eq + 1));
  const auto dot = name.find('.');
  if (dot == std::string::npos || dot == 0 || dot + 1 == name.size())
    fail("the key must be SECTION.KEY (sections: " + join(section_names(), ", ") +
         "), e.g. --set particles.solids_fraction=0.2");
  const std::string section_name = name.substr(0, dot);
  const std::string key_name = name.substr(dot + 1);
  const SectionSpec* section = find_section(section_name);
  if (!section) fail(unknown_section_message(section_name));
  if (!find_key(*section, key_name)) fail(unknown_key_message(*section, key_name));
  if (value_text.empty()) fail("no value after '='");
  if (value_text.find_first_of("\n\r") != std::string::npos) fail("the value must be on one line");

  // The value is read as TOML (numbers, booleans, arrays, quoted strings); text that is not TOML
  // is taken as a bare string (--set fluid.drag=wen-yu), unless it looks like an array, an inline
  // table or a quoted string, where the syntax error is what the user needs to see.
  toml::table parsed;
  bool is_toml = false;
  try {
    parsed = toml::parse("value = " + value_text, std::string_view("--set"));
    is_toml = parsed.size() == 1 && parsed.get("value");
  } catch (const toml::parse_error& e) {
    if (std::string_view("[{\"'").find(value_text.front()) != std::string_view::npos)
      fail("the value is not valid TOML: " + std::string(e.description()));
  }
  if (!is_toml && std::string_view("[{\"'").find(value_text.front()) != std::string_view::npos)
    fail("the value is not valid TOML");

  toml::table* table = root[section_name].as_table();
  if (!root.contains(section_name)) {
    root.insert(section_name, toml::table{});
    table = root[section_name].as_table();
  }
  if (!table)  // the file has "section = value" at the top level; the structure check reports it
    fail("[" + section_name + "] is not a section in the scene file");
  if (is_toml)
    table->insert_or_assign(key_name, parsed["value"]);
  else
    table->insert_or_assign(key_name, value_text);
  // One quantity, two ways to give it (alternatives()): the key set here replaces the other one.
  if (const char* other = alternative_of(section_name, key_name)) table->erase(other);
  return name;
}

}  // namespace cgd::scene_toml
