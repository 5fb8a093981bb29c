#include "core/snapshot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <regex>

#include "core/error.hpp"
#include "core/h5.hpp"
#include "core/schema/check.hpp"

namespace cgd {

namespace fs = std::filesystem;

namespace {

/// /params of a snapshot: every attribute the reader takes, of its type, finite, and positive where a
/// size or a density must be.
RunPhysics read_physics(const h5::File& f) {
  RunPhysics p;
  const std::string g = "/params";
  if (!f.exists(g)) throw InputError(f.path() + ": no group /params, expected the scene's parameters there");
  auto positive = [&](const char* name) {
    const double v = schema::finite_attr(f, g, name);
    if (!(v > 0))
      throw InputError(f.path() + ": attribute '" + name + "' of '/params' is " + std::to_string(v) +
                       ", expected a positive number");
    return v;
  };
  auto vec3 = [&](const char* name) {
    const std::vector<double> v = schema::finite_attrs(f, g, name, 3);
    return std::array<double, 3>{v[0], v[1], v[2]};
  };
  p.scene_name = f.attr_string(g, "scene_name");
  p.scene_toml = f.has_attr("/", "scene") ? f.attr_string("/", "scene") : "";
  p.diameter_m = positive("diameter_m");
  p.particle_density_kg_m3 = positive("density_kg_m3");
  p.parcel_size = positive("parcel_size");
  p.solids_fraction = schema::finite_attr(f, g, "solids_fraction");
  p.box_size_m = vec3("box_size_m");
  for (double edge : p.box_size_m)
    if (!(edge > 0))
      throw InputError(f.path() + ": attribute 'box_size_m' of '/params' holds " + std::to_string(edge) +
                       ", expected positive edges");
  p.gravity_m_s2 = vec3("gravity_m_s2");
  p.has_fluid = f.attr_int(g, "has_fluid") != 0;
  if (p.has_fluid) {
    p.fluid_density_kg_m3 = positive("fluid_density_kg_m3");
    p.fluid_viscosity_Pa_s = positive("fluid_viscosity_Pa_s");
    p.drag = f.attr_string(g, "drag");
    p.coupling = f.attr_string(g, "coupling");
    p.pressure_gradient_force = f.attr_int(g, "pressure_gradient_force") != 0;
    p.u_t_m_s = positive("u_t_m_s");
    p.l_char_m = positive("l_char_m");
    p.t_ref_s = positive("t_ref_s");
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

Snapshot read_snapshot(const std::string& path, SnapshotContent content, MPI_Comm comm) {
  using schema::Finite;
  h5::File f = h5::File::open_read(path, comm);
  schema::check_format(f, schema::kSnapshot);
  Snapshot s;
  s.path = path;
  s.time_s = schema::finite_attr(f, "/", "time");
  s.step = f.attr_int("/", "step");
  if (s.step < 0) throw InputError(path + ": attribute 'step' of '/' is " + std::to_string(s.step) + ", expected >= 0");
  s.physics = read_physics(f);

  // Every particle array holds N rows, N the length of /particles/id.
  const std::string n_rows = "N particles, the length of /particles/id";
  const std::uint64_t n = schema::require_shape(f, "/particles/id", {schema::kAnyExtent}).at(0);
  s.count = static_cast<std::int64_t>(n);
  const bool coupled = f.exists("/particles/drag_coefficient");
  const std::vector<std::pair<const char*, std::vector<std::uint64_t>>> particle_shapes = {
      {"/particles/position", {n, 3}}, {"/particles/velocity", {n, 3}}, {"/particles/diameter", {n}}};
  for (const auto& [name, shape] : particle_shapes) schema::require_shape(f, name, shape, n_rows);
  if (f.exists("/particles/angular_velocity")) schema::require_shape(f, "/particles/angular_velocity", {n, 3}, n_rows);
  if (coupled)  // the fluid's values at the particles come together (core/output.cpp)
    for (const auto& [name, shape] : std::vector<std::pair<const char*, std::vector<std::uint64_t>>>{
             {"/particles/fluid_velocity", {n, 3}}, {"/particles/pressure_gradient", {n, 3}}})
      schema::require_shape(f, name, shape, n_rows + "; written with /particles/drag_coefficient");

  s.has_fluid = f.exists("/fluid");
  std::vector<std::uint64_t> cells3, cells3x3;  // (n_z, n_y, n_x) and (n_z, n_y, n_x, 3)
  if (s.has_fluid) {
    const std::vector<std::int64_t> cells = f.attr_ints("/fluid", "cells");
    if (cells.size() != 3)
      throw InputError(path + ": attribute 'cells' of '/fluid' holds " + std::to_string(cells.size()) +
                       " values, expected 3 (x, y, z)");
    const std::vector<double> spacing = schema::finite_attrs(f, "/fluid", "spacing", 3);
    const std::vector<double> origin = schema::finite_attrs(f, "/fluid", "origin", 3);
    for (int a = 0; a < 3; ++a) {
      if (cells[a] <= 0 || cells[a] > (1 << 20) || !(spacing[a] > 0))
        throw InputError(path + ": /fluid has cells " + std::to_string(cells[a]) + " and spacing " +
                         std::to_string(spacing[a]) + " along axis " + std::to_string(a) +
                         ", expected a positive cell count and spacing");
      s.grid.cells[a] = static_cast<int>(cells[a]);
      s.grid.spacing_m[a] = spacing[a];
      s.grid.origin_m[a] = origin[a];
    }
    cells3 = {static_cast<std::uint64_t>(cells[2]), static_cast<std::uint64_t>(cells[1]),
              static_cast<std::uint64_t>(cells[0])};
    cells3x3 = cells3;
    cells3x3.push_back(3);
    const std::string grid = "the grid's cells, /fluid attribute 'cells' = (" + std::to_string(cells[0]) + ", " +
                             std::to_string(cells[1]) + ", " + std::to_string(cells[2]) + ")";
    schema::require_shape(f, "/fluid/void_fraction", cells3, grid);
    schema::require_shape(f, "/fluid/pressure", cells3, grid);
    schema::require_shape(f, "/fluid/velocity", cells3x3, grid);
    if (f.exists("/fluid/eps_velocity")) schema::require_shape(f, "/fluid/eps_velocity", cells3x3, grid);
  }
  if (content == SnapshotContent::HeaderOnly) return s;

  s.id = schema::read_ints(f, "/particles/id", {n});
  std::vector<char> seen(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const std::int64_t id = s.id[i];
    if (id < 0 || static_cast<std::uint64_t>(id) >= n || seen[static_cast<std::size_t>(id)])
      throw InputError(path + ": dataset '/particles/id' holds " + std::to_string(id) + " at row " + std::to_string(i) +
                       ", expected distinct ids in [0, " + std::to_string(n) + ")");
    seen[static_cast<std::size_t>(id)] = 1;
  }
  s.position = schema::read_doubles(f, "/particles/position", {n, 3}, Finite::Everywhere, n_rows);
  s.velocity = schema::read_doubles(f, "/particles/velocity", {n, 3}, Finite::Everywhere, n_rows);
  if (coupled) {
    s.drag_coefficient = schema::read_doubles(f, "/particles/drag_coefficient", {n}, Finite::Everywhere, n_rows);
    s.fluid_velocity = schema::read_doubles(f, "/particles/fluid_velocity", {n, 3}, Finite::Everywhere, n_rows);
    s.pressure_gradient = schema::read_doubles(f, "/particles/pressure_gradient", {n, 3}, Finite::Everywhere, n_rows);
  }
  if (!s.has_fluid) return s;
  const auto cells = static_cast<std::int64_t>(s.grid.cell_count());
  s.void_fraction = schema::read_doubles(f, "/fluid/void_fraction", cells3, Finite::Everywhere);
  for (std::int64_t c = 0; c < cells; ++c)
    if (!(s.void_fraction[c] > 0))
      throw InputError(path + ": dataset '/fluid/void_fraction' holds " + std::to_string(s.void_fraction[c]) +
                       " at cell " + std::to_string(c) + ", expected values > 0");
  s.pressure = schema::read_doubles(f, "/fluid/pressure", cells3, Finite::Everywhere);
  s.cell_velocity = schema::read_doubles(f, "/fluid/velocity", cells3x3, Finite::Everywhere);
  if (f.exists("/fluid/eps_velocity")) {
    s.eps_velocity = schema::read_doubles(f, "/fluid/eps_velocity", cells3x3, Finite::Everywhere);
    s.eps_velocity_from_file = true;
  } else {
    const std::vector<double>& u = s.cell_velocity;
    s.eps_velocity.resize(u.size());
    for (std::int64_t c = 0; c < cells; ++c)
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
