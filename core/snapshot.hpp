#pragma once
// The one reader of snapshot files and run directories (ARCHITECTURE.md "Files"; the writer is
// core/output.hpp). Used by the filter and by anything else that reads what cgd-generate wrote.
#include <mpi.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/periodic_grid.hpp"
#include "core/physical_system.hpp"

namespace cgd {

/// The physics of the run a file came from, from its /params group (SI).
struct RunPhysics {
  std::string scene_name, scene_toml;
  double diameter_m = 0, particle_density_kg_m3 = 0, parcel_size = 1;
  double solids_fraction = 0;                 // the scene's <phi_p>
  std::array<double, 3> box_size_m{}, gravity_m_s2{};
  bool has_fluid = false;
  double fluid_density_kg_m3 = 0, fluid_viscosity_Pa_s = 0;
  std::string drag, coupling;                  // e.g. "beetstra", "two-way" (empty without fluid)
  bool pressure_gradient_force = false;        // the particles feel -V_p grad p
  double u_t_m_s = 0, l_char_m = 0, t_ref_s = 0;

  /// The run's physical system (core/physical_system.hpp), |g| the norm of gravity_m_s2. InputError
  /// naming the scene when the run has no fluid or its law `drag` is not microscopic (a coarse run's).
  PhysicalSystem system() const;
};

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

/// Read a snapshot over `comm` (MPI_COMM_SELF for a rank reading alone). InputError naming the file
/// for a missing, unreadable, truncated or foreign file (cgd_format other than "snapshot"), or an
/// array of the wrong shape.
Snapshot read_snapshot(const std::string& path, SnapshotContent content = SnapshotContent::Everything,
                       MPI_Comm comm = MPI_COMM_SELF);

/// A run directory of cgd-generate/cgd-coarse: its snapshots in step order (snapshots/snap_<step>.h5;
/// temporary and diagnostic files are not snapshots) and whether the run completed (DONE marker).
struct RunDirectory {
  std::string path;
  std::vector<std::string> snapshot_files;
  std::vector<std::int64_t> steps;
  bool complete = false;
};
/// InputError if `path` is not a directory or holds no snapshots/ folder.
RunDirectory list_run_directory(const std::string& path);

}  // namespace cgd
