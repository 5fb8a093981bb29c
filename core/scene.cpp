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

#include <toml++/toml.h>
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
#include "core/scales.hpp"

namespace cgd {

const char* to_string(ContactModel m) {
  switch (m) {
    case ContactModel::SpringDashpot:
      return "spring-dashpot";
    case ContactModel::None:
      return "none";
  }
  return "?";
}

const char* to_string(Coupling c) {
  switch (c) {
    case Coupling::TwoWay:
      return "two-way";
    case Coupling::OneWay:
      return "one-way";
    case Coupling::Quiescent:
      return "quiescent";
  }
  return "?";
}

namespace {

// ---- schema --------------------------------------------------------------------------------------

enum class Kind { Number, Integer, Boolean, String, Vec3Number, Vec3Integer };

struct KeySpec {
  const char* name;
  Kind kind;
  const char* meaning;  // unit and meaning, quoted in messages
};

struct SectionSpec {
  const char* name;
  std::vector<KeySpec> keys;
};

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
        {"skin_over_dp", Kind::Number, "Verlet neighbour skin in primary diameters"}}},
      {"fluid",
       {{"density", Kind::Number, "kg/m^3, fluid density"},
        {"viscosity", Kind::Number, "Pa s, dynamic viscosity of the fluid"},
        {"cells", Kind::Vec3Integer, "fluid cells along x, y, z"},
        {"dx_over_dp", Kind::Number, "fluid cell size in primary diameters"},
        {"courant", Kind::Number, "Courant number of the fluid step"},
        {"coupling", Kind::String, "fluid-particle coupling"},
        {"drag", Kind::String, "microscopic drag law"},
        {"drag_model", Kind::String, "path of the drag model file (cgd-fit) used by drag = \"model\""},
        {"drag_model_checksum", Kind::String, "FNV-1a checksum of fluid.drag_model (recorded by cgd)"},
        {"pressure_gradient_force", Kind::Boolean, "apply -V_p grad p to the particles"},
        {"parcel_correction", Kind::Boolean,
         "apply c_corr(alpha) of a filtered law (false: the parcel fit's runs)"}}},
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
        {"sort_interval_steps", Kind::Integer, "DEM steps between reorderings of the particles by cell"}}},
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

/// Two keys that give one quantity in two ways (e.g. a time in s or in units of t_ref). A scene file
/// gives at most one of them; a --set of either replaces the other (any key can be overridden from the
/// command line, whichever of the pair the file uses).
struct Alternative {
  const char* section;
  const char* first;  // the key named first in messages
  const char* second;
  const char* first_unit;  // how each gives the quantity, quoted in messages
  const char* second_unit;
};

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
std::string unknown_key_message(const SectionSpec& section, std::string_view given,
                                bool with_key_list = true) {
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

/// Reads validated values out of the (overridden) root table and words every error.
class SceneReader {
 public:
  SceneReader(std::string origin, const toml::table& root, std::set<std::string> overridden)
      : origin_(std::move(origin)), root_(root), overridden_(std::move(overridden)) {}

  [[noreturn]] void fail(const std::string& message) const { throw InputError(origin_ + ": " + message); }

  /// "file: section.key = value (from --set): rule"
  [[noreturn]] void fail_value(std::string_view section, std::string_view key,
                               const std::string& rule) const {
    fail(value_message(section, key, rule));
  }

  /// "section.key = value (from --set): rule"
  std::string value_message(std::string_view section, std::string_view key, const std::string& rule) const {
    const std::string name = std::string(section) + "." + std::string(key);
    const toml::node* n = node(section, key);
    std::string message = name + " = " + (n ? format_node(*n) : std::string("?"));
    if (overridden_.count(name)) message += " (from --set)";
    return message + ": " + rule;
  }

  /// Both keys of an alternative pair in the scene: which to keep, and how --set chooses one.
  std::string conflict_message(const Alternative& pair) const {
    const std::string section = pair.section;
    const std::string first = section + "." + pair.first, second = section + "." + pair.second;
    return first + " = " + format_node(*node(section, pair.first)) + " and " + second + " = " +
           format_node(*node(section, pair.second)) + ": give either " + first + " (" + pair.first_unit +
           ") or " + second + " (" + pair.second_unit +
           "), not both: delete one of them from the scene (on the command line, --set " + first +
           "=VALUE replaces " + second + ", and the other way round)";
  }

  const toml::node* node(std::string_view section, std::string_view key) const {
    const toml::table* table = root_[section].as_table();
    return table ? table->get(key) : nullptr;
  }
  bool has(std::string_view section, std::string_view key) const { return node(section, key) != nullptr; }
  bool has_section(std::string_view section) const { return root_[section].as_table() != nullptr; }

  /// Unknown, misplaced and mistyped keys (wrong types, array lengths) and alternatives given twice
  /// (alternatives()), all of them in one InputError: a scene with three misplaced keys is fixed in one go.
  void check_structure() const {
    std::vector<std::string> problems;
    std::vector<const SectionSpec*> sections_with_unknown_keys;  // their key lists close the message
    for (const auto& [section_key, section_node] : root_) {
      const std::string_view section_name = section_key.str();
      const SectionSpec* section = find_section(section_name);
      if (!section_node.is_table()) {
        if (section) {
          problems.push_back(std::string(section_name) + " = " + format_node(section_node) +
                             ": must be a section [" + std::string(section_name) + "]");
          continue;
        }
        // a bare key at the top level: perhaps a key that belongs in a section
        std::string message = "unknown top-level key " + std::string(section_name);
        for (const auto& s : schema())
          if (find_key(s, section_name)) {
            message += "; did you mean " + std::string(s.name) + "." + std::string(section_name) + " (in [" +
                       s.name + "])?";
            break;
          }
        problems.push_back(message + " (every key belongs in a section: " + join(section_names(), ", ") +
                           ")");
        continue;
      }
      if (!section) {
        problems.push_back(unknown_section_message(section_name));
        continue;
      }
      for (const auto& [key, value] : *section_node.as_table()) {
        const KeySpec* spec = find_key(*section, key.str());
        if (!spec) {
          problems.push_back(unknown_key_message(*section, key.str(), false));
          if (std::find(sections_with_unknown_keys.begin(), sections_with_unknown_keys.end(), section) ==
              sections_with_unknown_keys.end())
            sections_with_unknown_keys.push_back(section);
          continue;
        }
        if (!has_kind(value, spec->kind))
          problems.push_back(value_message(section->name, key.str(), type_rule(*spec, value)));
      }
      for (const auto& pair : alternatives())
        if (section_name == pair.section && has(pair.section, pair.first) && has(pair.section, pair.second))
          problems.push_back(conflict_message(pair));
    }
    if (problems.empty()) return;
    if (problems.size() == 1) {
      std::string message = problems.front();
      if (!sections_with_unknown_keys.empty())
        message += " (" + section_key_list(*sections_with_unknown_keys.front()) + ")";
      fail(message);
    }
    std::string message = std::to_string(problems.size()) + " problems:";
    for (const auto& problem : problems) message += "\n  " + problem;
    for (const SectionSpec* section : sections_with_unknown_keys)
      message += "\n  (" + section_key_list(*section) + ")";
    fail(message);
  }

  std::optional<double> number(std::string_view section, std::string_view key) const {
    const toml::node* n = node(section, key);
    return n ? std::optional<double>(as_double(*n)) : std::nullopt;
  }

  double required(std::string_view section, std::string_view key) const {
    if (auto v = number(section, key)) return *v;
    fail_missing(section, key, "");
  }

  [[noreturn]] void fail_missing(std::string_view section, std::string_view key,
                                 const std::string& why) const {
    const KeySpec& spec = key_spec(section, key);
    fail(std::string(section) + "." + std::string(key) + " is missing: required" + why + " (" + spec.meaning +
         ")");
  }

  std::optional<Vec3> vec3(std::string_view section, std::string_view key) const {
    const toml::node* n = node(section, key);
    if (!n) return std::nullopt;
    const auto& a = *n->as_array();
    return Vec3{as_double(*a.get(0)), as_double(*a.get(1)), as_double(*a.get(2))};
  }

  std::optional<std::array<std::int64_t, 3>> ivec3(std::string_view section, std::string_view key) const {
    const toml::node* n = node(section, key);
    if (!n) return std::nullopt;
    const auto& a = *n->as_array();
    return std::array<std::int64_t, 3>{a.get(0)->as_integer()->get(), a.get(1)->as_integer()->get(),
                                       a.get(2)->as_integer()->get()};
  }

  std::optional<std::string> string(std::string_view section, std::string_view key) const {
    const toml::node* n = node(section, key);
    return n ? std::optional<std::string>(n->as_string()->get()) : std::nullopt;
  }

  std::optional<bool> boolean(std::string_view section, std::string_view key) const {
    const toml::node* n = node(section, key);
    return n ? std::optional<bool>(n->as_boolean()->get()) : std::nullopt;
  }

  std::optional<std::int64_t> integer(std::string_view section, std::string_view key) const {
    const toml::node* n = node(section, key);
    return n ? std::optional<std::int64_t>(n->as_integer()->get()) : std::nullopt;
  }

  // Range-checked numbers: `rule` is the allowed range as shown to the user.
  double positive(std::string_view section, std::string_view key, double value) const {
    if (!(value > 0.0))
      fail_value(section, key, "must be > 0 (" + std::string(key_spec(section, key).meaning) + ")");
    return value;
  }
  double non_negative(std::string_view section, std::string_view key, double value) const {
    if (!(value >= 0.0))
      fail_value(section, key, "must be >= 0 (" + std::string(key_spec(section, key).meaning) + ")");
    return value;
  }
  /// lower < value <= upper (or < upper when !upper_inclusive)
  double in_range(std::string_view section, std::string_view key, double value, double lower, double upper,
                  bool upper_inclusive, const std::string& why = "") const {
    const bool ok = value > lower && (upper_inclusive ? value <= upper : value < upper);
    if (!ok)
      fail_value(section, key,
                 "must be in (" + format_short(lower) + ", " + format_short(upper) +
                     (upper_inclusive ? "]" : ")") + " (" + key_spec(section, key).meaning + why + ")");
    return value;
  }

  template <typename Enum>
  Enum choice(std::string_view section, std::string_view key,
              const std::vector<std::pair<std::string, Enum>>& choices, Enum fallback) const {
    const auto given = string(section, key);
    if (!given) return fallback;
    std::vector<std::string> names;
    for (const auto& [name, value] : choices) {
      if (*given == name) return value;
      names.push_back(name);
    }
    std::vector<std::string> quoted;
    for (const auto& n : names) quoted.push_back(quote(n));
    std::string rule = "must be one of " + join(quoted, ", ");
    if (auto near = closest(*given, names)) rule += "; did you mean " + quote(*near) + "?";
    fail_value(section, key, rule + " (" + key_spec(section, key).meaning + ")");
  }

  static std::string format_short(double v) {
    std::string text = format_float(v);
    if (text.size() > 2 && text.ends_with(".0")) text.resize(text.size() - 2);
    return text;
  }

 private:
  std::string origin_;
  const toml::table& root_;
  std::set<std::string> overridden_;
};

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

Scene build_scene(const SceneReader& in, const ToolAccepts& accepts) {
  Scene s;

  // [particles]
  ParticlesConfig& p = s.particles;
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
  const double d = p.diameter_m;
  const double parcel_d = p.parcel_size * d;

  // [domain]
  const bool has_size_dp = in.has("domain", "size_dp"), has_size = in.has("domain", "size");
  if (!has_size_dp && !has_size)
    in.fail(
        "domain.size_dp is missing: required, the box edges [x, y, z] in primary diameters (or domain.size "
        "in m)");
  const char* size_key = has_size_dp ? "size_dp" : "size";
  const Vec3 size_given = *in.vec3("domain", size_key);
  for (int i = 0; i < 3; ++i) {
    const double edge_m = has_size_dp ? size_given[i] * d : size_given[i];
    s.domain.size_m[i] = edge_m;
    if (!(edge_m >= 4.0 * parcel_d)) {
      const std::string minimum = has_size_dp
                                      ? SceneReader::format_short(4.0 * p.parcel_size) + " primary diameters"
                                      : SceneReader::format_short(4.0 * parcel_d) + " m";
      in.fail_value("domain", size_key,
                    "every edge must be >= 4 parcel diameters (4 alpha d_p = " + minimum + "); edge " +
                        "xyz"[i] + " is too small");
    }
  }
  if (auto g = in.vec3("domain", "gravity")) s.domain.gravity_m_s2 = *g;
  const double g = norm(s.domain.gravity_m_s2);

  // [contact]
  ContactConfig& c = s.contact;
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
    c.skin_over_dp = in.non_negative("contact", "skin_over_dp", *v);
  if (c.model != ContactModel::None && !c.gamma_star && !c.stiffness_n_N_m)
    in.fail(std::string("contact.stiffness is missing: with contact.model = \"") + to_string(c.model) +
            "\" give contact.stiffness (N/m) or contact.gamma_star (dimensionless, needs a [fluid] section)");

  // [fluid]
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
    if (auto v = in.string("fluid", "drag_model")) f.drag_model_path = *v;
    if (auto v = in.string("fluid", "drag_model_checksum")) f.drag_model_checksum = *v;
    if (f.drag == DragLaw::Model && f.drag_model_path.empty())
      in.fail_missing("fluid", "drag_model", " with fluid.drag = \"model\"");
    if (f.drag != DragLaw::Model && !f.drag_model_path.empty())
      in.fail_value("fluid", "drag_model", std::string("is only used with fluid.drag = \"model\" (the scene has \"") +
                                               to_string(f.drag) + "\"); remove it or set fluid.drag = \"model\"");
    if (!f.drag_model_path.empty()) {
      std::error_code ec;
      if (!std::filesystem::is_regular_file(f.drag_model_path, ec))
        in.fail_value("fluid", "drag_model", "no such file");
      // The checksum identifies the model in every output file (the effective scene records it); a
      // scene that pins one refuses a model file that has changed since.
      const std::string sum = file_checksum_fnv1a(f.drag_model_path);
      if (!f.drag_model_checksum.empty() && f.drag_model_checksum != sum)
        in.fail_value("fluid", "drag_model_checksum",
                      "differs from the checksum of " + f.drag_model_path + " (" + sum +
                          "): the model file has changed since this scene recorded it");
      f.drag_model_checksum = sum;
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
    s.fluid = f;
  } else {
    if (c.gamma_star)
      in.fail_value(
          "contact", "gamma_star",
          "needs a [fluid] section: gamma* is defined with the terminal velocity u_t, which is undefined "
          "without a fluid; give contact.stiffness (N/m) instead");
  }

  // [run]
  RunConfig& r = s.run;
  for (const char* key : {"end_time_tref", "dump_interval_tref", "series_interval_tref", "sampling_start_tref"})
    if (in.has("run", key) && !s.fluid)
      in.fail_value("run", key,
                    "needs a [fluid] section: t_ref = u_t/g is undefined without a fluid; give run." +
                        std::string(key).substr(0, std::string(key).size() - 5) + " in s instead");
  if (auto v = in.number("run", "checkpoint_wall_s"))
    r.checkpoint_wall_s = in.positive("run", "checkpoint_wall_s", *v);
  if (auto v = in.number("run", "dt")) r.dt_s = in.positive("run", "dt", *v);

  // [numerics]
  NumericsConfig& nm = s.numerics;
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

  // ---- derived numbers (docs/models.md) ----
  DerivedScales& x = s.derived;
  x.particle_volume_m3 = sphere_volume(d);
  x.particle_mass_kg = p.density_kg_m3 * x.particle_volume_m3;
  x.parcel_diameter_m = parcel_d;
  x.parcel_mass_kg = std::pow(p.parcel_size, 3) * x.particle_mass_kg;

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

  // run times, possibly in units of t_ref; one rule per key: the end time > 0, the intervals and the
  // start of the sampling window >= 0
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
      std::round(p.solids_fraction * box_volume / (std::pow(p.parcel_size, 3) * x.particle_volume_m3));
  if (count < 1.0)
    in.fail_value("particles", "solids_fraction",
                  "gives no particle in a box of " + SceneReader::format_short(box_volume) +
                      " m^3; raise it or enlarge the box");
  if (count > 9e15) in.fail_value("particles", "solids_fraction", "gives more particles than can be counted");
  x.particle_count = static_cast<std::int64_t>(count);

  // ---- nonsense that validates key by key but cannot be run (issue 10, item 5) ----
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
  // Measured peak per particle (bench/README.md): ~300 B of DEM arrays (state, neighbour list with
  // history, ghosts; measured before the in-place integration of issue 17 dropped the second state buffer, so now
  // a little high) plus placement and I/O buffers: 450 B is the peak seen at 200k-600k particles.
  x.memory_estimate_bytes = count * 450.0;
  if (s.solves_fluid())
    x.memory_estimate_bytes +=
        16.0 * sizeof(double) * double(x.cells[0]) * double(x.cells[1]) * double(x.cells[2]);
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
                        num(s.contact.skin_over_dp) + " d_p)");
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
