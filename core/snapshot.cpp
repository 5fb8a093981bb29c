#include "core/snapshot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <regex>

#include "core/error.hpp"
#include "core/h5.hpp"
#include "core/schema/check.hpp"
#include "core/schema/snapshot_names.hpp"

namespace cgd {

namespace fs = std::filesystem;
using namespace schema::names;

namespace {

/// /params of a snapshot: every attribute the reader takes, of its type, finite, and positive where a
/// size or a density must be.
RunPhysics read_physics(const h5::File& f) {
  RunPhysics p;
  const std::string g = kParams;
  if (!f.exists(g)) throw InputError(f.path() + ": no group " + g + ", expected the scene's parameters there");
  auto positive = [&](const char* name) {
    const double v = schema::finite_attr(f, g, name);
    if (!(v > 0))
      throw InputError(f.path() + ": attribute '" + name + "' of '" + g + "' is " + std::to_string(v) +
                       ", expected a positive number");
    return v;
  };
  auto vec3 = [&](const char* name) {
    const std::vector<double> v = schema::finite_attrs(f, g, name, 3);
    return std::array<double, 3>{v[0], v[1], v[2]};
  };
  p.scene_name = f.attr_string(g, kSceneName);
  p.scene_toml = f.has_attr(kRoot, kScene) ? f.attr_string(kRoot, kScene) : "";
  p.diameter_m = positive(kDiameter);
  p.particle_density_kg_m3 = positive(kDensity);
  p.parcel_size = positive(kParcelSize);
  p.solids_fraction = schema::finite_attr(f, g, kSolidsFraction);
  p.box_size_m = vec3(kBoxSize);
  for (double edge : p.box_size_m)
    if (!(edge > 0))
      throw InputError(f.path() + ": attribute '" + std::string(kBoxSize) + "' of '" + g + "' holds " + std::to_string(edge) +
                       ", expected positive edges");
  p.gravity_m_s2 = vec3(kGravity);
  p.has_fluid = f.attr_int(g, kHasFluid) != 0;
  if (p.has_fluid) {
    p.fluid_density_kg_m3 = positive(kFluidDensity);
    p.fluid_viscosity_Pa_s = positive(kFluidViscosity);
    p.drag = f.attr_string(g, kDrag);
    p.coupling = f.attr_string(g, kCoupling);
    p.pressure_gradient_force = f.attr_int(g, kPressureGradientForce) != 0;
    p.u_t_m_s = positive(kUt);
    p.l_char_m = positive(kLChar);
    p.t_ref_s = positive(kTref);
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
  s.time_s = schema::finite_attr(f, kRoot, kTime);
  s.step = f.attr_int(kRoot, kStep);
  if (s.step < 0) throw InputError(path + ": attribute '" + kStep + "' of '/' is " + std::to_string(s.step) + ", expected >= 0");
  s.physics = read_physics(f);

  // Every particle array holds N rows, N the length of /particles/id.
  const std::string n_rows = std::string("N particles, the length of ") + kId;
  const std::uint64_t n = schema::require_shape(f, kId, {schema::kAnyExtent}).at(0);
  s.count = static_cast<std::int64_t>(n);
  const bool coupled = f.exists(kDragCoefficient);
  const std::vector<std::pair<const char*, std::vector<std::uint64_t>>> particle_shapes = {
      {kPosition, {n, 3}}, {kVelocity, {n, 3}}, {kParticleDiameter, {n}}};
  for (const auto& [name, shape] : particle_shapes) schema::require_shape(f, name, shape, n_rows);
  if (f.exists(kAngularVelocity)) schema::require_shape(f, kAngularVelocity, {n, 3}, n_rows);
  if (coupled)  // the fluid's values at the particles come together (core/output.cpp)
    for (const auto& [name, shape] : std::vector<std::pair<const char*, std::vector<std::uint64_t>>>{
             {kFluidVelocityAtParticles, {n, 3}}, {kPressureGradient, {n, 3}}})
      schema::require_shape(f, name, shape, n_rows + "; written with " + kDragCoefficient);

  s.has_fluid = f.exists(kFluid);
  std::vector<std::uint64_t> cells3, cells3x3;  // (n_z, n_y, n_x) and (n_z, n_y, n_x, 3)
  if (s.has_fluid) {
    const std::vector<std::int64_t> cells = f.attr_ints(kFluid, kCells);
    if (cells.size() != 3)
      throw InputError(path + ": attribute '" + std::string(kCells) + "' of '" + kFluid + "' holds " + std::to_string(cells.size()) +
                       " values, expected 3 (x, y, z)");
    const std::vector<double> spacing = schema::finite_attrs(f, kFluid, kSpacing, 3);
    const std::vector<double> origin = schema::finite_attrs(f, kFluid, kOrigin, 3);
    for (int a = 0; a < 3; ++a) {
      if (cells[a] <= 0 || cells[a] > (1 << 20) || !(spacing[a] > 0))
        throw InputError(path + ": " + kFluid + " has cells " + std::to_string(cells[a]) + " and spacing " +
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
    const std::string grid = std::string("the grid's cells, ") + kFluid + " attribute '" + kCells + "' = (" + std::to_string(cells[0]) + ", " +
                             std::to_string(cells[1]) + ", " + std::to_string(cells[2]) + ")";
    schema::require_shape(f, kVoidFraction, cells3, grid);
    schema::require_shape(f, kPressure, cells3, grid);
    schema::require_shape(f, kCellVelocity, cells3x3, grid);
    if (f.exists(kEpsVelocity)) schema::require_shape(f, kEpsVelocity, cells3x3, grid);
  }
  if (content == SnapshotContent::HeaderOnly) return s;

  s.id = schema::read_ints(f, kId, {n});
  std::vector<char> seen(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const std::int64_t id = s.id[i];
    if (id < 0 || static_cast<std::uint64_t>(id) >= n || seen[static_cast<std::size_t>(id)])
      throw InputError(path + ": dataset '" + kId + "' holds " + std::to_string(id) + " at row " + std::to_string(i) +
                       ", expected distinct ids in [0, " + std::to_string(n) + ")");
    seen[static_cast<std::size_t>(id)] = 1;
  }
  s.position = schema::read_doubles(f, kPosition, {n, 3}, Finite::Everywhere, n_rows);
  s.velocity = schema::read_doubles(f, kVelocity, {n, 3}, Finite::Everywhere, n_rows);
  if (coupled) {
    s.drag_coefficient = schema::read_doubles(f, kDragCoefficient, {n}, Finite::Everywhere, n_rows);
    s.fluid_velocity = schema::read_doubles(f, kFluidVelocityAtParticles, {n, 3}, Finite::Everywhere, n_rows);
    s.pressure_gradient = schema::read_doubles(f, kPressureGradient, {n, 3}, Finite::Everywhere, n_rows);
  }
  if (!s.has_fluid) return s;
  const auto cells = static_cast<std::int64_t>(s.grid.cell_count());
  s.void_fraction = schema::read_doubles(f, kVoidFraction, cells3, Finite::Everywhere);
  for (std::int64_t c = 0; c < cells; ++c)
    if (!(s.void_fraction[c] > 0))
      throw InputError(path + ": dataset '" + kVoidFraction + "' holds " + std::to_string(s.void_fraction[c]) +
                       " at cell " + std::to_string(c) + ", expected values > 0");
  s.pressure = schema::read_doubles(f, kPressure, cells3, Finite::Everywhere);
  s.cell_velocity = schema::read_doubles(f, kCellVelocity, cells3x3, Finite::Everywhere);
  if (f.exists(kEpsVelocity)) {
    s.eps_velocity = schema::read_doubles(f, kEpsVelocity, cells3x3, Finite::Everywhere);
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
