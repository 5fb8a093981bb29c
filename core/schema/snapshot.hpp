#pragma once
// The snapshot file (cgd_format "snapshot", docs/schema-run.md "Snapshot"): its one home. The names of its
// datasets and attributes (each spelled once, below; the common root attributes and /params are
// core/schema/common.hpp's), the views a writer fills (ParticleFields, FluidFields: each rank's own rows),
// the struct a reader gets (Snapshot), one write (write_snapshot, collective) and one validating read
// (read_snapshot). cgd-generate and cgd-coarse (sim/run.cpp, coarse/coarse.cpp) write, cgd-filter reads;
// run.xmf (core/xdmf.cpp) refers to the datasets by these names.
#include <mpi.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/periodic_grid.hpp"
#include "core/schema/common.hpp"
#include "core/scene.hpp"  // Vec3

namespace cgd::schema::names {

// snapshot: root attributes
inline constexpr const char* kTime = "time";
inline constexpr const char* kStep = "step";

// snapshot: /particles, N rows each
inline constexpr const char* kParticles = "/particles";
inline constexpr const char* kId = "/particles/id";
inline constexpr const char* kPosition = "/particles/position";
inline constexpr const char* kVelocity = "/particles/velocity";
inline constexpr const char* kAngularVelocity = "/particles/angular_velocity";
inline constexpr const char* kParticleDiameter = "/particles/diameter";
inline constexpr const char* kDragCoefficient = "/particles/drag_coefficient";
inline constexpr const char* kFluidVelocityAtParticles = "/particles/fluid_velocity";
inline constexpr const char* kPressureGradient = "/particles/pressure_gradient";
inline constexpr const char* kPressureGradientMean = "pressure_gradient_mean";  // of /particles

// snapshot: /fluid, fields (n_z, n_y, n_x[, 3])
inline constexpr const char* kFluid = "/fluid";
inline constexpr const char* kCells = "cells";      // of /fluid
inline constexpr const char* kSpacing = "spacing";  // of /fluid
inline constexpr const char* kOrigin = "origin";    // of /fluid
inline constexpr const char* kLayout = "layout";    // of /fluid
inline constexpr const char* kVoidFraction = "/fluid/void_fraction";
inline constexpr const char* kCellVelocity = "/fluid/velocity";
inline constexpr const char* kPressure = "/fluid/pressure";
inline constexpr const char* kEpsVelocity = "/fluid/eps_velocity";

inline constexpr const char* kTimeLevel = "time_level";  // of /particles and /fluid

}  // namespace cgd::schema::names

namespace cgd::schema {

/// This rank's owned particles as views (SoA, vectors interleaved xyz). Optional fields are nullptr
/// when the run does not simulate them (then the dataset is absent from the file).
struct ParticleFields {
  std::int64_t count = 0;
  const std::int64_t* id = nullptr;
  const double* position = nullptr;          // count x 3, m
  const double* velocity = nullptr;          // count x 3, m/s
  const double* angular_velocity = nullptr;  // count x 3, rad/s (rotation simulated)
  const double* diameter = nullptr;          // count, m
  const double* drag_coefficient = nullptr;  // count, beta_p,i (kg m^-3 s^-1)
  const double* fluid_velocity = nullptr;    // count x 3, u at the particle
  const double* pressure_gradient = nullptr; // count x 3, grad p at the particle, mean removed
  Vec3 pressure_gradient_mean{};             // the removed mean (attribute)
};

/// This rank's slab of the fluid grid: cells [y_offset, y_offset + y_count) along y, all of x and z.
/// Arrays are in file order (z, y_local, x), x fastest; velocity has a trailing 3.
struct FluidFields {
  std::array<int, 3> cells{};   // global (n_x, n_y, n_z)
  Vec3 spacing_m{};
  Vec3 origin_m{};
  int y_offset = 0, y_count = 0;
  const double* void_fraction = nullptr;
  const double* velocity = nullptr;
  const double* pressure = nullptr;
  /// Cell-centred eps u (trailing 3): the mean of the two faces' fluxes eps_f u_f, so that its sum
  /// over the cells equals the solver's sum over the faces (the series' <eps u>) exactly. Optional.
  const double* eps_velocity = nullptr;
};

/// Write a snapshot file atomically (attributes time, step; /params; /particles; /fluid if given). Checks
/// over the ranks that every rank that owns particles gives the same arrays and that the fluid slabs tile
/// the grid (RunError otherwise: a bug of the caller, nothing written). Collective.
void write_snapshot(const std::string& path, MPI_Comm comm, const Scene& scene, double time_s, std::int64_t step,
                    const ParticleFields& particles, const FluidFields* fluid = nullptr);

/// One snapshot: particles (owned by the file, all of them) and, in coupled runs, the fluid fields.
/// Time levels (the file's attributes say the same): positions x_n at t_n; velocity the leapfrog
/// v_{n-1/2} in coupled runs (synchronous v_n in dry runs); drag_coefficient, fluid_velocity and
/// pressure_gradient the fluid level n at x_n; the fluid fields level n.
struct Snapshot {
  std::string path;
  double time_s = 0;
  std::int64_t step = 0;
  RunPhysics physics;
  std::int64_t count = 0;
  std::vector<std::int64_t> id;
  std::vector<double> position, velocity;                                // count x 3
  std::vector<double> drag_coefficient;                                  // count (coupled runs)
  std::vector<double> fluid_velocity, pressure_gradient;                 // count x 3 (coupled runs)
  bool has_fluid = false;
  PeriodicGrid grid;
  std::vector<double> void_fraction, pressure;                           // cells, file order
  std::vector<double> eps_velocity;                                      // cells x 3
  /// Cell-centred u (/fluid/velocity: the mean of the two faces, what the coupler interpolates to the
  /// particles), cells x 3.
  std::vector<double> cell_velocity;
  /// True when eps_velocity was stored (face-consistent); false: formed here as eps_c u_c from the
  /// cell-centred velocity of an older snapshot (differs from the solver's face sum at O(h^2)).
  bool eps_velocity_from_file = false;
};

/// What to read: everything, or the attributes, /params and the grid description only (fast; no arrays).
enum class SnapshotContent { Everything, HeaderOnly };

/// Read a snapshot over `comm` (MPI_COMM_SELF for a rank reading alone). Validates what it reads (docs/schema-run.md
/// "What the readers check"): the format and version, /params (read_run_physics), N = the length of
/// /particles/id rows in every particle array, the grid's cells (attribute cells of /fluid) in every field,
/// integer ids 0..N-1 each once, finite values, void fractions > 0. InputError naming the file, the dataset
/// or attribute, what was found and what was expected.
Snapshot read_snapshot(const std::string& path, SnapshotContent content = SnapshotContent::Everything,
                       MPI_Comm comm = MPI_COMM_SELF);

}  // namespace cgd::schema
