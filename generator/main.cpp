// cgd-generate: resolved CFD-DEM runs of a scene (README "Command lines"). A thin driver:
// parse, load and validate the scene (nothing is written before that succeeds), run it.
#include <mpi.h>

#include "core/mpi_init.hpp"
#include "core/cli.hpp"
#include "core/error.hpp"
#include "core/scene.hpp"
#include "sim/run.hpp"

int main(int argc, char** argv) {
  cgd::init_mpi(&argc, &argv);
  const int status = cgd::run_tool([&] {
    const cgd::RunOptions options = cgd::parse_run_command_line(
        argc, argv, "cgd-generate", "Resolved CFD-DEM run of a scene: snapshots of particles (and fluid) for filtering");
    // A resolved run resolves the clusters: it uses a microscopic law; the filtered laws (kind Filtered in core/drag.hpp)
    // belong to coarse-grid runs (cgd-coarse), and the scene's drag error offers only what this tool runs.
    const cgd::Scene scene = cgd::load_scene(options.scene_path, options.overrides, cgd::kResolvedRunAccepts);
    cgd::RunSettings settings;
    settings.output_dir =
        options.output_dir.empty() ? cgd::default_run_directory("generate", options.scene_path) : options.output_dir;
    settings.restart = options.restart;
    settings.quiet = options.quiet;
    settings.progress_interval_s = options.progress_interval_s;
    cgd::run_scene(scene, settings, MPI_COMM_WORLD);
    return cgd::kExitOk;
  });
  MPI_Finalize();
  return status;
}
