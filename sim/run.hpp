#pragma once
// A run of one scene, shared by cgd-generate and cgd-coarse: assembles the effects the scene calls for
// into one time loop and owns the run directory (ARCHITECTURE.md "Files"): scene.toml, snapshots/snap_<step>.h5,
// series.h5 (columns: core/schema/series.hpp), checkpoint.h5 (core/schema/checkpoint.hpp), run.xmf and the completion
// marker DONE, written last. The coupled step itself is sim/coupled_step.hpp; the run driver only
// orchestrates: output, checkpoints, interruption, progress and the console.
#include <mpi.h>

#include <string>

#include "core/scene.hpp"
#include "sim/dem/system.hpp"

namespace cgd {

/// DEM settings of a scene (contact parameters, drive, time step; slabs balanced at each rebuild). Throws InputError for a
/// combination this build cannot simulate.
dem::DemSettings dem_settings_from_scene(const Scene& scene);

struct RunSettings {
  std::string output_dir;
  bool restart = false;
  bool quiet = false;          // errors, warnings and the final summary only (no banner, no progress)
  double progress_interval_s = 60;  // wall seconds between progress lines when stderr is not a terminal
  std::string tool = "cgd-generate";
};

/// Runs the scene to its end time; returns normally when done. Throws InputError before writing
/// anything for bad input (an output path that is a file, an existing run directory without --restart,
/// a missing checkpoint), and RunError for a failed run, after writing a diagnostic snapshot and keeping
/// the last checkpoint. SIGINT/SIGTERM write a checkpoint at the next step boundary and end the run with
/// Interrupted (exit status 130 / 143).
/// With settings.restart: refuses (InputError, nothing written) a scene whose physics differs from the
/// checkpoint's (restart_differences), an end time before the checkpoint, and does nothing for a run
/// that is already complete (DONE written and the checkpoint at the end).
void run_scene(const Scene& scene, const RunSettings& settings, MPI_Comm comm);

/// The scene a restart of the run in output_dir continues: `scene` with the checkpoint's scene name, after
/// checking that only the keys restart_may_change differ. Throws InputError otherwise. Collective.
Scene restart_scene(const Scene& scene, const std::string& output_dir, MPI_Comm comm);

}  // namespace cgd
