// cgd-generate: resolved CFD-DEM runs of a scene (design.md "Command lines"). A thin driver:
// parse, load and validate the scene (nothing is written before that succeeds), run it.
#include <mpi.h>

#include "core/cli.hpp"
#include "core/error.hpp"
#include "core/scene.hpp"
#include "sim/run.hpp"

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  const int status = cgd::run_tool([&] {
    const cgd::RunOptions options = cgd::parse_run_command_line(
        argc, argv, "cgd-generate", "Resolved CFD-DEM run of a scene: snapshots of particles (and fluid) for filtering");
    const cgd::Scene scene = cgd::load_scene(options.scene_path, options.overrides);
    // A resolved run resolves the clusters: it uses a microscopic law. The filtered laws (radl2014,
    // model) belong to coarse-grid runs (cgd-coarse); the engine itself accepts them.
    if (scene.fluid && (scene.fluid->drag == cgd::DragLaw::Radl2014 || scene.fluid->drag == cgd::DragLaw::Model))
      throw cgd::InputError(scene.source_path + ": fluid.drag = \"" + cgd::to_string(scene.fluid->drag) +
                            "\": a filtered drag model belongs to coarse-grid runs (cgd-coarse); resolved runs "
                            "allow \"beetstra\", \"wen-yu\", \"stokes\"");
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
