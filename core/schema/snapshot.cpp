// The snapshot file (docs/schema-run.md "Snapshot"): write_snapshot (collective, each rank its own rows and
// fluid slab) and the validating read_snapshot. The names are core/schema/snapshot.hpp's.
#include "core/schema/snapshot.hpp"

#include <algorithm>
#include <array>
#include <cstring>

#include "core/error.hpp"
#include "core/h5.hpp"
#include "core/schema/check.hpp"

namespace cgd::schema {
namespace {

using namespace names;

std::vector<double> as_vector(const Vec3& v) {
  return {v.begin(), v.end()};
}
std::vector<std::int64_t> as_vector(const std::array<int, 3>& v) {
  return {v.begin(), v.end()};
}

/// One per-particle array of the snapshot: name, data, values per particle, unit.
struct ParticleArray {
  const char* name;  // the dataset's path
  const double* data;
  int width;
  const char* unit;
  bool required;
};

}  // namespace

void write_snapshot(const std::string& path, MPI_Comm comm, const Scene& scene, double time_s,
                    std::int64_t step, const ParticleFields& particles, const FluidFields* fluid) {
  using namespace names;
  const ParticleArray arrays[] = {
      {kPosition, particles.position, 3, "m", true},
      {kVelocity, particles.velocity, 3, "m/s", true},
      {kAngularVelocity, particles.angular_velocity, 3, "rad/s", false},
      {kParticleDiameter, particles.diameter, 1, "m", true},
      {kDragCoefficient, particles.drag_coefficient, 1, "kg/(m^3 s)", false},
      {kFluidVelocityAtParticles, particles.fluid_velocity, 3, "m/s", false},
      {kPressureGradient, particles.pressure_gradient, 3, "Pa/m", false},
  };
  constexpr int kArrays = std::size(arrays);

  // Which optional arrays are present, agreed over all ranks (a rank without particles may pass
  // nullptr); an array given on some ranks but missing on a rank that has particles is a bug.
  const bool has_rows = particles.count > 0;
  std::array<int, 2 * kArrays + 6> local{}, global{};
  for (int i = 0; i < kArrays; ++i) {
    local[2 * i] = arrays[i].data != nullptr;
    local[2 * i + 1] = arrays[i].data == nullptr && has_rows;
  }
  local[2 * kArrays] = particles.id == nullptr && has_rows;
  local[2 * kArrays + 1] = particles.count < 0;
  local[2 * kArrays + 2] = fluid != nullptr;
  local[2 * kArrays + 3] = fluid == nullptr;
  bool bad_slab = false;
  if (fluid) {
    const auto& n = fluid->cells;
    bad_slab = n[0] <= 0 || n[1] <= 0 || n[2] <= 0 || fluid->y_offset < 0 || fluid->y_count < 0 ||
               fluid->y_offset + fluid->y_count > n[1] ||
               (fluid->y_count > 0 && (!fluid->void_fraction || !fluid->velocity || !fluid->pressure));
  }
  local[2 * kArrays + 4] = bad_slab;
  local[2 * kArrays + 5] = fluid ? fluid->cells[1] : 0;
  MPI_Allreduce(local.data(), global.data(), static_cast<int>(local.size()), MPI_INT, MPI_MAX, comm);

  std::string problem;
  for (int i = 0; i < kArrays; ++i) {
    const bool any_given = global[2 * i], missing_somewhere = global[2 * i + 1];
    if (missing_somewhere && (arrays[i].required || any_given))
      problem =
          std::string("particle array '") + arrays[i].name + "' is missing on a rank that owns particles";
  }
  if (global[2 * kArrays]) problem = std::string("particle array '") + kId + "' is missing on a rank that owns particles";
  if (global[2 * kArrays + 1]) problem = "negative particle count";
  const bool with_fluid = global[2 * kArrays + 2];
  if (with_fluid && global[2 * kArrays + 3]) problem = "fluid fields given on some ranks only";
  if (global[2 * kArrays + 4]) problem = "a rank's fluid slab lies outside the grid or lacks a field";
  if (with_fluid && problem.empty()) {
    int y_cells = fluid->y_count, y_total = 0;
    MPI_Allreduce(&y_cells, &y_total, 1, MPI_INT, MPI_SUM, comm);
    if (y_total != global[2 * kArrays + 5])
      problem = "the ranks' fluid slabs hold " + std::to_string(y_total) + " layers along y, the grid has " +
                std::to_string(global[2 * kArrays + 5]);
  }
  if (!problem.empty()) throw RunError(path + ": cannot write snapshot: " + problem);

  h5::write_atomically(path, comm, [&](h5::File& f) {
    write_common(f, kSnapshot, scene);
    f.set_attr(kRoot, kTime, time_s);
    f.set_attr(kRoot, kStep, step);

    f.create_group(kParticles);
    f.write_rows(kId, particles.id, particles.count, 1);
    f.set_attr(kId, kUnit, std::string("1"));
    for (int i = 0; i < kArrays; ++i) {
      if (!global[2 * i]) continue;  // not simulated
      const std::string name = arrays[i].name;
      f.write_rows(name, arrays[i].data, particles.count, arrays[i].width);
      f.set_attr(name, kUnit, std::string(arrays[i].unit));
    }
    const bool wrote_pressure_gradient =
        std::any_of(std::begin(arrays), std::end(arrays), [&](const ParticleArray& a) {
          return std::strcmp(a.name, kPressureGradient) == 0 && global[2 * (&a - arrays)];
        });
    if (wrote_pressure_gradient) {  // record the mean that was removed from it, and the time levels
      f.set_attr(kParticles, kPressureGradientMean, as_vector(particles.pressure_gradient_mean));
      f.set_attr(kParticles, kTimeLevel,
                 std::string("position x_n at t_n; velocity: the leapfrog v_{n-1/2} the drag used (coupled runs); "
                             "drag_coefficient, fluid_velocity, pressure_gradient: fluid level n interpolated to x_n "
                             "with the TSC kernel (the values of the drag evaluation that starts the fluid step at t_n)"));
    }

    if (with_fluid) {
      const auto n = fluid->cells;  // (n_x, n_y, n_z)
      const auto nx = static_cast<std::uint64_t>(n[0]), ny = static_cast<std::uint64_t>(n[1]),
                 nz = static_cast<std::uint64_t>(n[2]);
      const auto y0 = static_cast<std::uint64_t>(fluid->y_offset),
                 yc = static_cast<std::uint64_t>(fluid->y_count);
      f.create_group(kFluid);
      f.set_attr(kFluid, kCells, as_vector(fluid->cells));
      f.set_attr(kFluid, kSpacing, as_vector(fluid->spacing_m));
      f.set_attr(kFluid, kOrigin, as_vector(fluid->origin_m));
      f.set_attr(kFluid, kLayout,
                 std::string("arrays (n_z, n_y, n_x[, 3]), x fastest; cells, spacing, origin as (x, y, z)"));
      f.write_block(kVoidFraction, fluid->void_fraction, {nz, ny, nx}, {0, y0, 0}, {nz, yc, nx});
      f.set_attr(kVoidFraction, kUnit, std::string("1"));
      f.write_block(kCellVelocity, fluid->velocity, {nz, ny, nx, 3}, {0, y0, 0, 0}, {nz, yc, nx, 3});
      f.set_attr(kCellVelocity, kUnit, std::string("m/s"));
      f.write_block(kPressure, fluid->pressure, {nz, ny, nx}, {0, y0, 0}, {nz, yc, nx});
      f.set_attr(kPressure, kUnit, std::string("Pa"));
      if (fluid->eps_velocity) {
        f.write_block(kEpsVelocity, fluid->eps_velocity, {nz, ny, nx, 3}, {0, y0, 0, 0}, {nz, yc, nx, 3});
        f.set_attr(kEpsVelocity, kUnit, std::string("m/s"));
        f.set_attr(kEpsVelocity, kDefinition,
                   std::string("cell-centred eps*u: mean of the two faces' eps_f u_f, eps_f the mean of the two "
                               "cells; sums to the solver's face sum <eps u> exactly"));
      }
      // The time level of every field (the filter combines them; see docs/schema-filtered.md)
      f.set_attr(kFluid, kTimeLevel,
                 std::string("all fluid fields at the snapshot's time t_n = step * dt_DEM (fluid level n, "
                             "before the fluid step that starts at t_n)"));
      f.set_attr(kPressure, kDefinition,
                 std::string("periodic part of the pressure: the mean gradient rho_mix g (/particles attribute "
                             "pressure_gradient_mean) removed"));
    }
  });
}


Snapshot read_snapshot(const std::string& path, SnapshotContent content, MPI_Comm comm) {
  h5::File f = h5::File::open_read(path, comm);
  check_format(f, kSnapshot);
  Snapshot s;
  s.path = path;
  s.time_s = finite_attr(f, kRoot, kTime);
  s.step = f.attr_int(kRoot, kStep);
  if (s.step < 0) throw InputError(path + ": attribute '" + kStep + "' of '/' is " + std::to_string(s.step) + ", expected >= 0");
  s.physics = read_run_physics(f);

  // Every particle array holds N rows, N the length of /particles/id.
  const std::string n_rows = std::string("N particles, the length of ") + kId;
  const std::uint64_t n = require_shape(f, kId, {kAnyExtent}).at(0);
  s.count = static_cast<std::int64_t>(n);
  const bool coupled = f.exists(kDragCoefficient);
  const std::vector<std::pair<const char*, std::vector<std::uint64_t>>> particle_shapes = {
      {kPosition, {n, 3}}, {kVelocity, {n, 3}}, {kParticleDiameter, {n}}};
  for (const auto& [name, shape] : particle_shapes) require_shape(f, name, shape, n_rows);
  if (f.exists(kAngularVelocity)) require_shape(f, kAngularVelocity, {n, 3}, n_rows);
  if (coupled)  // the fluid's values at the particles come together (write_snapshot above)
    for (const auto& [name, shape] : std::vector<std::pair<const char*, std::vector<std::uint64_t>>>{
             {kFluidVelocityAtParticles, {n, 3}}, {kPressureGradient, {n, 3}}})
      require_shape(f, name, shape, n_rows + "; written with " + kDragCoefficient);

  s.has_fluid = f.exists(kFluid);
  std::vector<std::uint64_t> cells3, cells3x3;  // (n_z, n_y, n_x) and (n_z, n_y, n_x, 3)
  if (s.has_fluid) {
    const std::vector<std::int64_t> cells = f.attr_ints(kFluid, kCells);
    if (cells.size() != 3)
      throw InputError(path + ": attribute '" + std::string(kCells) + "' of '" + kFluid + "' holds " + std::to_string(cells.size()) +
                       " values, expected 3 (x, y, z)");
    const std::vector<double> spacing = finite_attrs(f, kFluid, kSpacing, 3);
    const std::vector<double> origin = finite_attrs(f, kFluid, kOrigin, 3);
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
    require_shape(f, kVoidFraction, cells3, grid);
    require_shape(f, kPressure, cells3, grid);
    require_shape(f, kCellVelocity, cells3x3, grid);
    if (f.exists(kEpsVelocity)) require_shape(f, kEpsVelocity, cells3x3, grid);
  }
  if (content == SnapshotContent::HeaderOnly) return s;

  s.id = read_ints(f, kId, {n});
  std::vector<char> seen(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const std::int64_t id = s.id[i];
    if (id < 0 || static_cast<std::uint64_t>(id) >= n || seen[static_cast<std::size_t>(id)])
      throw InputError(path + ": dataset '" + kId + "' holds " + std::to_string(id) + " at row " + std::to_string(i) +
                       ", expected distinct ids in [0, " + std::to_string(n) + ")");
    seen[static_cast<std::size_t>(id)] = 1;
  }
  s.position = read_doubles(f, kPosition, {n, 3}, Finite::Everywhere, n_rows);
  s.velocity = read_doubles(f, kVelocity, {n, 3}, Finite::Everywhere, n_rows);
  if (coupled) {
    s.drag_coefficient = read_doubles(f, kDragCoefficient, {n}, Finite::Everywhere, n_rows);
    s.fluid_velocity = read_doubles(f, kFluidVelocityAtParticles, {n, 3}, Finite::Everywhere, n_rows);
    s.pressure_gradient = read_doubles(f, kPressureGradient, {n, 3}, Finite::Everywhere, n_rows);
  }
  if (!s.has_fluid) return s;
  const auto cells = static_cast<std::int64_t>(s.grid.cell_count());
  s.void_fraction = read_doubles(f, kVoidFraction, cells3, Finite::Everywhere);
  for (std::int64_t c = 0; c < cells; ++c)
    if (!(s.void_fraction[c] > 0))
      throw InputError(path + ": dataset '" + kVoidFraction + "' holds " + std::to_string(s.void_fraction[c]) +
                       " at cell " + std::to_string(c) + ", expected values > 0");
  s.pressure = read_doubles(f, kPressure, cells3, Finite::Everywhere);
  s.cell_velocity = read_doubles(f, kCellVelocity, cells3x3, Finite::Everywhere);
  if (f.exists(kEpsVelocity)) {
    s.eps_velocity = read_doubles(f, kEpsVelocity, cells3x3, Finite::Everywhere);
    s.eps_velocity_from_file = true;
  } else {
    const std::vector<double>& u = s.cell_velocity;
    s.eps_velocity.resize(u.size());
    for (std::int64_t c = 0; c < cells; ++c)
      for (int d = 0; d < 3; ++d) s.eps_velocity[3 * c + d] = s.void_fraction[c] * u[3 * c + d];
  }
  return s;
}

}  // namespace cgd::schema
