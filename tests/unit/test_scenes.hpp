#pragma once
// The shared test scenes of tests/scenes/ as text, for load_scene_from_string with the test's own origin
// (the name its messages and files show) and --set overrides: one scene a purpose instead of TOML pasted
// into each test.
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include "core/schema/snapshot.hpp"

namespace cgd::testing {

/// The /params of a snapshot of a resolved two-way Beetstra run in air (the scene's numbers: 1500 kg/m^3
/// particles of diameter d, u_t and L_char of 75 um particles), for snapshots built by hand.
inline schema::RunPhysics air_beetstra_physics(double d) {
  schema::RunPhysics p;
  p.diameter_m = d;
  p.particle_density_kg_m3 = 1500;
  p.fluid_density_kg_m3 = 1.3;
  p.fluid_viscosity_Pa_s = 1.8e-5;
  p.drag = "beetstra";
  p.pressure_gradient_force = true;
  p.u_t_m_s = 0.2185;
  p.l_char_m = 3.02e-4;
  return p;
}

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
