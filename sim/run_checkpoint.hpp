#pragma once
// The run's checkpoint.h5 (layout: core/schema/checkpoint.hpp) as the run driver (sim/run.cpp) writes and loads
// it: the particles with their contact histories, the DEM's rebuild state, the fluid (CoupledStep), and
// the run's book-keeping (wall time, phase seconds, snapshot frames, placement method). A restart at any
// rank count reads it back; at the same rank count each rank takes its own rows (bit-for-bit restarts).
#include <mpi.h>

#include <cstdint>
#include <string>
#include <vector>

#include "core/schema/checkpoint.hpp"
#include "core/scene.hpp"
#include "sim/coupled_step.hpp"
#include "sim/dem/system.hpp"

namespace cgd {

/// What a checkpoint keeps of the run besides its physical state.
struct RunBook {
  double wall_seconds = 0;                 // the whole run's wall time so far (rank 0's)
  std::vector<double> phase_seconds;       // DEM phases, then the run's (RunDriver::phase_seconds order)
  std::vector<checkpoint::Frame> frames;   // the snapshots written (run.xmf)
  std::string placement_method;
};

/// Writes `path` with the DEM state of `dem` (positions unwrapped, leapfrog velocities, contact store),
/// the fluid of `coupled` (may be null) and `book`, at the DEM's current step (time step * dt_s).
/// Collective; `book` must be the same on every rank.
void write_run_checkpoint(const std::string& path, MPI_Comm comm, const Scene& scene, const dem::DemSystem& dem,
                          double dt_s, CoupledStep* coupled, const RunBook& book);

/// The state a restart continues from: the checkpoint's step and book.
struct RestoredRun {
  std::int64_t step = 0;
  RunBook book;
};

/// Loads `path` into `dem` (particles, contact store, rebuild state, the rebuild counter) and `coupled`
/// (may be null): each rank its own rows and the slabs in force at the checkpoint's rank count, else the particles
/// of its slab (rebuilt, so balanced anew, at the first step).
/// InputError naming the file for a checkpoint after `end_step`, friction switched since, or another
/// particle count. Collective.
RestoredRun load_run_checkpoint(const std::string& path, MPI_Comm comm, const Scene& scene, dem::DemSystem& dem,
                                double dt_s, std::int64_t end_step, CoupledStep* coupled);

}  // namespace cgd
