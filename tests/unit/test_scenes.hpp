#pragma once
// The shared test scenes of tests/scenes/ as text, for load_scene_from_string with the test's own origin
// (the name its messages and files show) and --set overrides: one scene a purpose instead of TOML pasted
// into each test.
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

namespace cgd::testing {

/// tests/scenes/<file> of the source tree ($CGD_SOURCE_DIR, set by CTest, else the configured source dir).
inline std::string test_scene_text(const std::string& file) {
  const char* s = std::getenv("CGD_SOURCE_DIR");
  const std::string path = std::string(s ? s : CGD_SOURCE_DIR_DEFAULT) + "/tests/scenes/" + file;
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read the test scene " + path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace cgd::testing
