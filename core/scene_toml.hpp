#pragma once
// The generic TOML machinery of scenes (core/scene.cpp is its only user; the rest of the code sees the
// plain structs of core/scene.hpp): the schema of sections and keys with their kinds and meanings, the
// alternatives (one quantity, two keys), did-you-mean suggestions, printing values and the effective
// scene, the --set overrides, and SceneReader, which checks a table's structure and reads validated
// values, wording every error "<file>: <section.key> = <value given>: <what is allowed>".
// Adding a scene key: its line in schema() (core/scene_toml.cpp), its reading in the section's reader
// in core/scene.cpp, its row in docs/scene-keys.md.
#include <toml++/toml.h>

#include <array>
#include <cstdint>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "core/scene.hpp"

namespace cgd::scene_toml {

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

const std::vector<SectionSpec>& schema();
const SectionSpec* find_section(std::string_view name);
const KeySpec* find_key(const SectionSpec& section, std::string_view name);
const KeySpec& key_spec(std::string_view section, std::string_view key);
const std::vector<Alternative>& alternatives();
const char* alternative_of(std::string_view section, std::string_view key);
std::size_t edit_distance(std::string_view a, std::string_view b);
std::optional<std::string> closest(std::string_view given, const std::vector<std::string>& candidates);
std::string join(const std::vector<std::string>& items, const std::string& separator);
std::vector<std::string> section_names();
std::vector<std::string> key_names(const SectionSpec& section);
std::string section_key_list(const SectionSpec& section);
std::string unknown_section_message(std::string_view given);
std::string unknown_key_message(const SectionSpec& section, std::string_view given, bool with_key_list = true);
std::string format_float(double v);
std::string quote(std::string_view s);
std::string format_node(const toml::node& node);
std::string emit_scene(const toml::table& root);
std::string kind_text(Kind kind);
bool is_finite_number(const toml::node& node);
double as_double(const toml::node& node);
bool has_kind(const toml::node& node, Kind kind);
std::string type_rule(const KeySpec& spec, const toml::node& value);
std::string trim(std::string_view s);
std::string apply_override(toml::table& root, const std::string& text, const std::string& origin);

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

}  // namespace cgd::scene_toml
