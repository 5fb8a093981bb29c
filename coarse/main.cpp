// cgd-coarse: coarse-grid CFD-DEM and CFD-DPM (parcels) runs of a scene, with a microscopic or a
// filtered drag law, and the time-averaged slip they give against a resolved reference (README.md
// "Command lines"; docs/coarse.md). A thin driver over the engine of cgd-generate.
#include <mpi.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <iostream>

#include "core/mpi_init.hpp"
#include "coarse/coarse.hpp"
#include "core/cli.hpp"
#include "core/error.hpp"
#include "core/schema/checkpoint.hpp"
#include "core/scene.hpp"
#include "sim/run.hpp"

namespace {

// cgd-coarse --summarise RUN_DIR -o FILE: the slip summary of a finished run (a resolved run of cgd-generate or a
// coarse run) over a window chosen here, written as a coarse_summary file, by the code that summarises every
// coarse run (coarse::summarise_run: the mean, its batch-means error, the drift between the window's halves,
// the cost). Nothing is simulated. Makefile.pipeline uses it for the resolved references of the study.
// cgd-coarse --summarise FILTERED.h5 -o FILE: the same from a resolved run's filtered file (the shipped
// data/filtered/ files: coarse::summarise_filtered), over the filter's window, when the run directory is gone.
int summarise_main(int argc, char** argv) {
  std::string run_dir, output;
  double from_tref = -1;
  int ranks = 0, batches = 10;
  bool force = false;
  CLI::App app{"cgd-coarse --summarise: the time-averaged slip of a finished run (resolved or coarse) over a window, "
               "its batch-means error, the drift between the window's halves and the cost, as a coarse_summary file",
               "cgd-coarse"};
  app.add_option("--summarise", run_dir, "run directory (with scene.toml and series.h5), or a resolved run's filtered "
                 "file (cgd-filter of that run alone: the whole box's slip at its snapshots, over the filter's window)")
      ->required()->type_name("RUN_DIR|FILTERED.h5");
  app.add_option("--from-tref", from_tref, "start of the window in t_ref (default: the run's run.sampling_start)");
  app.add_option("--ranks", ranks, "ranks the run used, for the cost (default: the checkpoint's `ranks`, else 1)");
  app.add_option("--batches", batches, "batches of the standard error (default 10)");
  app.add_option("-o,--output", output, "summary file to write (cgd_format coarse_summary)")->required()->type_name("FILE");
  app.add_flag("--force", force, "overwrite FILE if it exists");
  cgd::parse_command_line(app, argc, argv, "cgd-coarse");
  if (batches < 2) throw cgd::InputError("--batches: " + std::to_string(batches) + " is not allowed (>= 2)");
  if (std::filesystem::is_regular_file(run_dir)) {
    if (from_tref >= 0)
      throw cgd::InputError("--from-tref: not with a filtered file (" + run_dir + "): its window is the filter's (cgd-filter --from-tref)");
    if (ranks > 0)
      throw cgd::InputError("--ranks: not with a filtered file (" + run_dir + "): it carries no wall time, so no cost");
    cgd::check_output_file(output, force, {run_dir});
    cgd::Scene scene;
    const auto s = cgd::coarse::summarise_filtered(run_dir, batches, &scene);
    if (cgd::is_output_rank()) cgd::coarse::write_summary(output, scene, s, std::nullopt, to_string(scene.fluid->drag));
    std::cout << "cgd-coarse: " << run_dir << ": " << cgd::coarse::describe(s) << "\nwrote " << output << "\n";
    return cgd::kExitOk;
  }
  const std::filesystem::path dir(run_dir);
  if (!std::filesystem::exists(dir / "scene.toml") || !std::filesystem::exists(dir / "series.h5"))
    throw cgd::InputError("--summarise " + run_dir + ": no scene.toml and series.h5 there (expected a run directory or a filtered file)");
  cgd::check_output_file(output, force);
  const cgd::Scene scene = cgd::load_scene((dir / "scene.toml").string(), {});
  if (!scene.fluid) throw cgd::InputError("--summarise " + run_dir + ": the run solved no fluid: it has no slip to summarise");
  if (ranks <= 0) {
    ranks = 1;
    const std::filesystem::path checkpoint = dir / "checkpoint.h5";
    if (std::filesystem::exists(checkpoint))
      ranks = static_cast<int>(cgd::checkpoint::read_header(checkpoint.string(), MPI_COMM_SELF).ranks);
  }
  const double start = from_tref >= 0 ? from_tref * scene.derived.t_ref_s : scene.run.sampling_start_s;
  const auto s = cgd::coarse::summarise_run(run_dir, scene.derived.u_t_m_s, start, ranks, batches);
  std::string drag = to_string(scene.fluid->drag);
  if (scene.fluid->drag == cgd::DragLaw::Model && !scene.fluid->parcel_correction) drag = "model-raw";
  if (cgd::is_output_rank()) cgd::coarse::write_summary(output, scene, s, std::nullopt, drag);
  std::cout << "cgd-coarse: " << run_dir << ": " << cgd::coarse::describe(s) << "\nwrote " << output << "\n";
  return cgd::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  cgd::init_mpi(&argc, &argv);
  bool summarise = false;
  for (int i = 1; i < argc; ++i) summarise = summarise || std::string(argv[i]) == "--summarise";
  const int status = cgd::run_tool([&] {
    if (summarise) return summarise_main(argc, argv);
    std::string reference, model, summarise_dir;  // summarise_dir: only for --help (the mode is chosen above)
    int batches = 10;
    const cgd::RunOptions options = cgd::parse_run_command_line(
        argc, argv, "cgd-coarse",
        "Coarse-grid CFD-DEM / CFD-DPM (parcels) of a scene; prints the time-averaged slip over the sampling "
        "window and, with --reference, its error against a resolved run",
        [&](CLI::App& app) {
          // the shared example (a dry scene) is one cgd-coarse refuses: name one it runs
          app.get_option("scene")->description("Scene file (TOML) with a coupled fluid, e.g. data/scenes/pipeline_demo.toml; "
                                                "with --restart -o DIR it may be left out (DIR/scene.toml is used)");
          app.add_option("--model", model, "drag model file of cgd-fit: the same as --set fluid.drag=model "
                                           "--set fluid.drag_model=MODEL.h5");
          app.add_option("--reference", reference, "resolved run directory (cgd-generate) to compare the slip with, or "
                                                   "that run's filtered file (e.g. data/filtered/half_phi0.05.h5)");
          app.add_option("--batches", batches, "batches of the standard error of the mean slip (default 10)");
          app.add_option("--summarise", summarise_dir,
                         "instead of running: the slip summary of a finished run (resolved or coarse) over a window, "
                         "as a coarse_summary file: cgd-coarse --summarise RUN_DIR [--from-tref T] [--ranks N] "
                         "[--batches N] -o FILE [--force], or --summarise FILTERED.h5 [--batches N] -o FILE [--force] "
                         "(cgd-coarse --summarise X --help)")
              ->type_name("RUN_DIR|FILTERED.h5");
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
    if (!reference.empty() && !std::filesystem::is_regular_file(reference) &&
        !std::filesystem::exists(std::filesystem::path(reference) / "series.h5"))
      throw cgd::InputError("--reference " + reference + ": no series.h5 there (expected a run directory of cgd-generate "
                            "or its filtered file)");
    if (batches < 2) throw cgd::InputError("--batches: " + std::to_string(batches) + " is not allowed (>= 2)");
    // a filtered file is summarised now (on every rank, so that all refuse a wrong one together), before the run,
    // and its summary kept for the comparison after it
    std::optional<cgd::coarse::SlipSummary> filtered_reference;
    if (!reference.empty() && std::filesystem::is_regular_file(reference))
      filtered_reference = cgd::coarse::summarise_filtered(reference, batches);
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
          cmp = cgd::coarse::compare(s, filtered_reference ? *filtered_reference
                                                           : cgd::coarse::summarise_reference(reference, batches));
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
