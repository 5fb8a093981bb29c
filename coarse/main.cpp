// cgd-coarse: coarse-grid CFD-DEM and CFD-DPM (parcels) runs of a scene, with a microscopic or a
// filtered drag law, and the time-averaged slip they give against a resolved reference (design.md
// "Command lines"; docs/coarse.md). A thin driver over the engine of cgd-generate.
#include <mpi.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <iostream>

#include "coarse/coarse.hpp"
#include "core/cli.hpp"
#include "core/error.hpp"
#include "core/scene.hpp"
#include "sim/run.hpp"

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  const int status = cgd::run_tool([&] {
    std::string reference, model;
    int batches = 10;
    const cgd::RunOptions options = cgd::parse_run_command_line(
        argc, argv, "cgd-coarse",
        "Coarse-grid CFD-DEM / CFD-DPM (parcels) of a scene; prints the time-averaged slip over the sampling "
        "window and, with --reference, its error against a resolved run",
        [&](CLI::App& app) {
          app.add_option("--model", model, "drag model file of cgd-fit: the same as --set fluid.drag=model "
                                           "--set fluid.drag_model=MODEL.h5");
          app.add_option("--reference", reference, "resolved run directory (cgd-generate) to compare the slip with");
          app.add_option("--batches", batches, "batches of the standard error of the mean slip (default 10)");
        });
    int ranks = 1;
    MPI_Comm_size(MPI_COMM_WORLD, &ranks);
    std::vector<std::string> overrides = options.overrides;
    if (!model.empty()) {
      overrides.push_back("fluid.drag=model");
      overrides.push_back("fluid.drag_model=" + model);
    }
    const cgd::Scene scene = cgd::load_scene(options.scene_path, overrides);
    cgd::coarse::check_coarse_scene(scene, ranks);
    if (!reference.empty() && !std::filesystem::exists(std::filesystem::path(reference) / "series.h5"))
      throw cgd::InputError("--reference " + reference + ": no series.h5 there (expected a run directory of cgd-generate)");
    if (batches < 2) throw cgd::InputError("--batches: " + std::to_string(batches) + " is not allowed (>= 2)");
    cgd::RunSettings settings;
    settings.output_dir =
        options.output_dir.empty() ? cgd::default_run_directory("coarse", options.scene_path) : options.output_dir;
    settings.restart = options.restart;
    settings.quiet = options.quiet;
    settings.progress_interval_s = options.progress_interval_s;
    settings.tool = "cgd-coarse";
    cgd::run_scene(scene, settings, MPI_COMM_WORLD);

    if (cgd::is_output_rank()) {
      // The run is complete and kept whatever happens here: a window too short for batch means is a
      // warning (the summary is then not written), not a failed run.
      try {
        const double u_t = scene.derived.u_t_m_s;
        const auto s = cgd::coarse::summarise_run(settings.output_dir, u_t, scene.run.sampling_start_s, ranks, batches);
        std::optional<cgd::coarse::Comparison> cmp;
        if (!reference.empty())
          cmp = cgd::coarse::compare(s, cgd::coarse::summarise_reference(reference, batches));
        // "model": the file is in the scene's drag_model; "model-raw": the model with c_corr off (parcel fit)
        std::string drag = to_string(scene.fluid->drag);
        if (scene.fluid->drag == cgd::DragLaw::Model && !scene.fluid->parcel_correction) drag = "model-raw";
        cgd::coarse::write_summary((std::filesystem::path(settings.output_dir) / "summary.h5").string(), scene, s, cmp, drag);
        std::cout << "cgd-coarse: " << cgd::coarse::describe(s) << "\n";
        if (cmp) std::cout << "cgd-coarse: " << cgd::coarse::describe(*cmp) << "\n";
      } catch (const cgd::InputError& e) {
        std::cerr << "warning: the run is complete, but no slip summary was written: " << e.what() << "\n";
      }
    }
    MPI_Barrier(MPI_COMM_WORLD);
    return cgd::kExitOk;
  });
  MPI_Finalize();
  return status;
}
