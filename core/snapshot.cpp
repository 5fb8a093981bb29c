#include "core/snapshot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <regex>

#include "core/error.hpp"
#include "core/h5.hpp"

namespace cgd {

namespace fs = std::filesystem;

namespace {

RunPhysics read_physics(const h5::File& f) {
  RunPhysics p;
  const std::string g = "/params";
  if (!f.exists(g)) throw InputError(f.path() + ": no /params group (not a cgd file of schema version 1)");
  auto vec3 = [&](const char* name) {
    const std::vector<double> v = f.attr_doubles(g, name);
    if (v.size() != 3) throw InputError(f.path() + ": /params attribute '" + name + "' has " + std::to_string(v.size()) + " values, expected 3");
    return std::array<double, 3>{v[0], v[1], v[2]};
  };
  p.scene_name = f.attr_string(g, "scene_name");
  p.scene_toml = f.has_attr("/", "scene") ? f.attr_string("/", "scene") : "";
  p.diameter_m = f.attr_double(g, "diameter_m");
  p.particle_density_kg_m3 = f.attr_double(g, "density_kg_m3");
  p.parcel_size = f.attr_double(g, "parcel_size");
  p.solids_fraction = f.attr_double(g, "solids_fraction");
  p.box_size_m = vec3("box_size_m");
  p.gravity_m_s2 = vec3("gravity_m_s2");
  p.has_fluid = f.attr_int(g, "has_fluid") != 0;
  if (p.has_fluid) {
    p.fluid_density_kg_m3 = f.attr_double(g, "fluid_density_kg_m3");
    p.fluid_viscosity_Pa_s = f.attr_double(g, "fluid_viscosity_Pa_s");
    p.drag = f.attr_string(g, "drag");
    p.coupling = f.attr_string(g, "coupling");
    p.pressure_gradient_force = f.attr_int(g, "pressure_gradient_force") != 0;
    p.u_t_m_s = f.attr_double(g, "u_t_m_s");
    p.l_char_m = f.attr_double(g, "l_char_m");
    p.t_ref_s = f.attr_double(g, "t_ref_s");
  }
  return p;
}

}  // namespace

PhysicalSystem RunPhysics::system() const {
  const auto law = microscopic_drag_law(drag);
  if (!has_fluid || !law)
    throw InputError(scene_name + ": the run's drag law is '" + drag + "': its physical system needs a fluid and a "
                     "microscopic law (" + drag_law_names(DragKind::Micro) + ")");
  const auto& g = gravity_m_s2;
  return PhysicalSystem{*law,          u_t_m_s,
                        l_char_m,      diameter_m,
                        particle_density_kg_m3, fluid_density_kg_m3,
                        fluid_viscosity_Pa_s,   std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2])};
}

namespace {

template <class T>
void check_rows(const std::string& path, const std::string& name, const std::vector<T>& v, std::int64_t rows, int cols) {
  if (static_cast<std::int64_t>(v.size()) != rows * cols)
    throw InputError(path + ": dataset '" + name + "' holds " + std::to_string(v.size()) + " values, expected " +
                     std::to_string(rows) + " x " + std::to_string(cols));
}

}  // namespace

Snapshot read_snapshot(const std::string& path, SnapshotContent content, MPI_Comm comm) {
  h5::File f = h5::File::open_read(path, comm);
  Snapshot s;
  s.path = path;
  if (!f.has_attr("/", "cgd_format"))
    throw InputError(path + ": not a cgd file (no root attribute 'cgd_format'; expected 'snapshot')");
  const std::string format = f.attr_string("/", "cgd_format");
  if (format != "snapshot")
    throw InputError(path + ": cgd_format is '" + format + "', expected 'snapshot'");
  s.time_s = f.attr_double("/", "time");
  s.step = f.attr_int("/", "step");
  s.physics = read_physics(f);
  if (!f.exists("/particles/id")) throw InputError(path + ": no dataset /particles/id");
  s.count = static_cast<std::int64_t>(f.dims("/particles/id").at(0));
  s.has_fluid = f.exists("/fluid");
  if (s.has_fluid) {
    const std::vector<std::int64_t> cells = f.attr_ints("/fluid", "cells");
    const std::vector<double> spacing = f.attr_doubles("/fluid", "spacing"), origin = f.attr_doubles("/fluid", "origin");
    if (cells.size() != 3 || spacing.size() != 3 || origin.size() != 3)
      throw InputError(path + ": /fluid attributes cells, spacing, origin must hold 3 values each");
    for (int a = 0; a < 3; ++a) {
      if (cells[a] <= 0 || !(spacing[a] > 0))
        throw InputError(path + ": /fluid has cells " + std::to_string(cells[a]) + " and spacing " +
                         std::to_string(spacing[a]) + " along axis " + std::to_string(a) + "; both must be > 0");
      s.grid.cells[a] = static_cast<int>(cells[a]);
      s.grid.spacing_m[a] = spacing[a];
      s.grid.origin_m[a] = origin[a];
    }
  }
  if (content == SnapshotContent::HeaderOnly) return s;

  s.id = f.read_int("/particles/id");
  s.position = f.read_double("/particles/position");
  s.velocity = f.read_double("/particles/velocity");
  check_rows(path, "/particles/position", s.position, s.count, 3);
  check_rows(path, "/particles/velocity", s.velocity, s.count, 3);
  if (f.exists("/particles/drag_coefficient")) {
    s.drag_coefficient = f.read_double("/particles/drag_coefficient");
    s.fluid_velocity = f.read_double("/particles/fluid_velocity");
    s.pressure_gradient = f.read_double("/particles/pressure_gradient");
    check_rows(path, "/particles/drag_coefficient", s.drag_coefficient, s.count, 1);
    check_rows(path, "/particles/fluid_velocity", s.fluid_velocity, s.count, 3);
    check_rows(path, "/particles/pressure_gradient", s.pressure_gradient, s.count, 3);
  }
  if (!s.has_fluid) return s;
  const auto n = static_cast<std::int64_t>(s.grid.cell_count());
  s.void_fraction = f.read_double("/fluid/void_fraction");
  s.pressure = f.read_double("/fluid/pressure");
  check_rows(path, "/fluid/void_fraction", s.void_fraction, n, 1);
  check_rows(path, "/fluid/pressure", s.pressure, n, 1);
  s.cell_velocity = f.read_double("/fluid/velocity");
  check_rows(path, "/fluid/velocity", s.cell_velocity, n, 3);
  if (f.exists("/fluid/eps_velocity")) {
    s.eps_velocity = f.read_double("/fluid/eps_velocity");
    check_rows(path, "/fluid/eps_velocity", s.eps_velocity, n, 3);
    s.eps_velocity_from_file = true;
  } else {
    const std::vector<double>& u = s.cell_velocity;
    s.eps_velocity.resize(u.size());
    for (std::int64_t c = 0; c < n; ++c)
      for (int d = 0; d < 3; ++d) s.eps_velocity[3 * c + d] = s.void_fraction[c] * u[3 * c + d];
  }
  return s;
}

RunDirectory list_run_directory(const std::string& path) {
  std::error_code ec;
  if (!fs::is_directory(path, ec))
    throw InputError(path + ": no such run directory (" + (fs::exists(path, ec) ? "not a directory" : "does not exist") + ")");
  const fs::path snaps = fs::path(path) / "snapshots";
  if (!fs::is_directory(snaps, ec))
    throw InputError(path + ": not a run directory (no snapshots/ folder; expected the output of cgd-generate -o DIR)");
  RunDirectory run;
  run.path = path;
  run.complete = fs::exists(fs::path(path) / "DONE", ec);
  static const std::regex name(R"(snap_(\d+)\.h5)");
  std::vector<std::pair<std::int64_t, std::string>> found;
  for (const auto& entry : fs::directory_iterator(snaps)) {
    std::smatch m;
    const std::string file = entry.path().filename().string();
    if (entry.is_regular_file() && std::regex_match(file, m, name))
      found.emplace_back(std::stoll(m[1].str()), entry.path().string());
  }
  std::sort(found.begin(), found.end());
  for (auto& [step, file] : found) {
    run.steps.push_back(step);
    run.snapshot_files.push_back(file);
  }
  return run;
}

}  // namespace cgd
