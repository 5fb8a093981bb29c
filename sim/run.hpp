#pragma once
// A resolved run of one scene: assembles the effects the scene calls for into one time loop and
// owns the run directory (design.md "Files"): scene.toml, snapshots/snap_<step>.h5, series.h5,
// checkpoint.h5, run.xmf and the completion marker DONE, written last.
#include <mpi.h>

#include <string>

#include "core/scene.hpp"
#include "sim/dem/system.hpp"

namespace cgd {

/// DEM settings of a scene (contact parameters, drive, time step). Throws InputError for a
/// combination this build cannot simulate.
dem::DemSettings dem_settings_from_scene(const Scene& scene);

struct RunSettings {
  std::string output_dir;
  bool restart = false;
  bool quiet = false;          // no progress line
  std::string tool = "cgd-generate";
};

/// Runs the scene to its end time; returns normally when done. Throws InputError before writing
/// anything for bad input (an existing run directory without --restart, a missing checkpoint),
/// and RunError for a failed run, after writing a diagnostic snapshot and keeping the last
/// checkpoint. SIGINT/SIGTERM write a checkpoint and end the run with RunError ("interrupted").
void run_scene(const Scene& scene, const RunSettings& settings, MPI_Comm comm);

}  // namespace cgd
