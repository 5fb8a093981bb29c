// cgd-fit: filtered files -> drag model file (README.md "Command lines"; docs/fit.md). A thin driver:
// parse, read and check every input (nothing is written before that succeeds), fit, report, write.
#include <mpi.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "core/mpi_init.hpp"
#include "core/cli.hpp"
#include "core/error.hpp"
#include "core/scene.hpp"
#include "fit/filtered_input.hpp"
#include "fit/fitter.hpp"
#include "fit/parcel_fit.hpp"
#include "core/filtered_drag.hpp"

int main(int argc, char** argv) {
  cgd::init_mpi(&argc, &argv);
  const int status = cgd::run_tool([&] {
    std::vector<std::string> inputs;
    std::string output;
    bool quiet = false;
    cgd::fit::FitOptions options;
    CLI::App app{
        "Fit the filtered drag model H(F, phi) = h(phi)/(1 + a(phi) F^n) to filtered files (cgd-filter) "
        "and write a drag model file (docs/fit.md)",
        "cgd-fit"};
    app.add_option("filtered", inputs, "Filtered files (cgd-filter), pooled into one fit")
        ->required()
        ->type_name("FILTERED.h5...");
    app.add_option("-o,--output", output, "Model file to write")->required()->type_name("MODEL.h5");
    app.add_option("--min-count", options.min_count,
                   "Particle samples a (width, bin) needs to be used (default 100)")
        ->check(CLI::PositiveNumber);
    app.add_option("--min-widths", options.min_widths, "Distinct widths a bin needs (default 3, at least 3)")
        ->check(CLI::Range(3, 1000));
    app.add_option("--bootstrap", options.bootstrap,
                   "Bootstrap replicates for the bands (default 400; 0: none)")
        ->check(CLI::Range(0, 100000));
    app.add_option("--seed", options.seed, "Seed of the bootstrap (default 1)");
    app.add_option(
           "--min-width-over-cell", options.min_width_over_cell,
           "Narrower filters (in fluid cells) are not fitted, only checked (default 2: a one-cell filter "
           "averages nothing below the grid)")
        ->check(CLI::Range(0.0, 1e6));
    app.add_option("--phi-crit", options.phi_crit, "Below it h -> 0 linearly (default 0.016, the paper's)")
        ->check(CLI::Range(1e-6, 0.5));
    app.add_option("--breakpoints", options.breakpoints,
                   "Spline breakpoints (default: from the bin count, 5..15)")
        ->check(CLI::Range(4, 100));
    std::string width_exponent = "1";
    app.add_option("--width-exponent", width_exponent,
                   "n of the width dependence H = h(phi)/(1 + a(phi) F^n): a number in (0, 10] or \"fit\" (one n "
                   "for every phi, from the profile of the pooled chi2; default 1, Radl & Sundaresan's form)")
        ->type_name("N|fit");
    app.add_flag(
        "--no-cross-validation", [&](std::int64_t) { options.cross_validate = false; },
        "Skip the leave-one-run-out cross-validation");
    app.add_flag("--quiet", quiet, "Print no report");
    bool force = false;
    app.add_flag("--force", force, "Overwrite an existing output file (never one of the inputs)");
    bool pool = false;
    app.add_flag("--pool-runs", pool,
                 "Fit the runs' pooled H: per width and bin the ratio of the sums over every run of every file (each "
                 "run weighted by its share of the bin's drag, as one filtered file of all the runs holds it) instead of "
                 "each file's H as a series of its own (docs/fit.md \"Pooled runs\")");
    std::string op = "box";
    app.add_option("--operator", op,
                   "What the model is calibrated on: \"box\" (the box widths /width_<k>, default) or \"grid\" (H_grid "
                   "of the coarse grids /grids/<N> of cgd-filter --grids, Delta = the grid's cell size: what a coarse "
                   "run applies; the model file's operator is then \"grid\" too)")
        ->type_name("box|grid");
    int grid_table = 0;
    app.add_option("--grid-table", grid_table,
                   "Perfect-closure model: write H_grid of the grid of N cells across as a table model (curves = table, "
                   "a = 0): a coarse run on that grid applies exactly the a-priori correction (docs/fit.md)")
        ->type_name("N");
    int drift_table = 0;
    app.add_option("--drift-table", drift_table,
                   "Drift-velocity closure: write the drift sums of the grid of N cells across (cgd-filter --grids) as a "
                   "drift table H(phi, cell slip) (curves = drift_table), used with fluid.drag = \"drift\" (docs/closure.md \"The drift-velocity closure\")")
        ->type_name("N");
    double drift_min_alignment = 0.25;
    app.add_option("--drift-min-alignment", drift_min_alignment,
                   "With --drift-table: a (phi, slip) bin is measured when |sum beta s~_y| >= X sum beta |s~| (the cell "
                   "slip mostly vertical: H = N/S well conditioned) and it has --min-count samples (default 0.25)")
        ->check(CLI::Range(0.0, 1.0));
    std::string parcel_model;
    app.add_option("--parcel-fit", parcel_model,
                   "Parcel fit: the inputs are cgd-coarse run directories run with this model and "
                   "fluid.parcel_correction = false (and --reference); fits c_corr(alpha) and writes a copy of "
                   "MODEL.h5 with it (docs/fit.md)")
        ->type_name("MODEL.h5");
    cgd::parse_command_line(app, argc, argv, "cgd-fit");
    if (width_exponent == "fit") {
      options.fit_width_exponent = true;
    } else {
      std::size_t used = 0;
      double n = 0;
      try {
        n = std::stod(width_exponent, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used != width_exponent.size() || !(n > 0 && n <= 10))
        throw cgd::InputError("cgd-fit: --width-exponent " + width_exponent +
                              ": allowed a number in (0, 10] or \"fit\"");
      options.width_exponent = n;
    }

    if (pool && (app.count("--drift-table") || app.count("--grid-table") || !parcel_model.empty()))
      throw cgd::InputError(std::string("cgd-fit: --pool-runs with ") +
                            (app.count("--grid-table") ? "--grid-table" : app.count("--drift-table") ? "--drift-table"
                                                                                                    : "--parcel-fit") +
                            ": --pool-runs pools the runs of a spline fit; --grid-table and --drift-table pool the "
                            "files' sums already, --parcel-fit reads coarse runs: give it without them");
    if (parcel_model.empty())  // a run directory is filtered first: say so (not "not a regular file")
      for (const std::string& in : inputs)
        if (std::filesystem::is_directory(in))
          throw cgd::InputError("cgd-fit: " + in + " is a run directory, not a filtered file: filter it first (cgd-filter " +
                                in + " -o FILTERED.h5, docs/filter.md), then fit FILTERED.h5");
    {
      std::vector<std::string> read = inputs;
      if (!parcel_model.empty()) read.push_back(parcel_model);
      cgd::check_output_file(output, force, read);
      const std::filesystem::path dir = std::filesystem::absolute(output).parent_path();
      if (!std::filesystem::is_directory(dir))
        throw cgd::InputError(output + ": cannot write the model file: no directory " + dir.string());
    }
    if (!parcel_model.empty()) {
      if (width_exponent != "1")
        throw cgd::InputError("cgd-fit: --width-exponent " + width_exponent +
                              " with --parcel-fit: the parcel fit keeps the model's own width_exponent");
      const cgd::DragModel model = cgd::load_drag_model(parcel_model);
      std::vector<cgd::fit::ParcelRun> runs;
      for (const std::string& dir : inputs) runs.push_back(cgd::fit::read_parcel_run(dir, model.u_t_m_s));
      const cgd::DragParams params = model.drag_params();
      const cgd::fit::ParcelFitResult r =
          cgd::fit::fit_parcel_correction(runs, model.micro_drag, params, 2000, static_cast<unsigned>(options.seed));
      cgd::fit::write_parcel_fit(parcel_model, output, r);
      if (!quiet) std::cout << cgd::fit::parcel_fit_report(r) << "wrote " << output << "\n";
      return cgd::kExitOk;
    }

    const auto calibration = cgd::parse_calibration_operator(op);
    if (!calibration)
      throw cgd::InputError("cgd-fit: --operator " + op + ": allowed " +
                            cgd::calibration_operator_choices());
    if (app.count("--grid-table") && grid_table < 1)
      throw cgd::InputError("cgd-fit: --grid-table " + std::to_string(grid_table) + ": allowed a number of cells across >= 1");
    if (app.count("--drift-table") && drift_table < 1)
      throw cgd::InputError("cgd-fit: --drift-table " + std::to_string(drift_table) + ": allowed a number of cells across >= 1");
    if (app.count("--drift-table") && app.count("--grid-table"))
      throw cgd::InputError("cgd-fit: --drift-table and --grid-table each write one table model: give one");
    options.calibration_operator = *calibration;
    if (*calibration == cgd::CalibrationOperator::Grid && !app.count("--min-width-over-cell"))
      options.min_width_over_cell = cgd::fit::kGridMinWidthOverCell;
    // every input read and checked before anything is written
    std::vector<cgd::fit::FilteredFile> files;
    for (const std::string& path : inputs) files.push_back(cgd::fit::read_filtered_file(path));
    cgd::fit::check_same_physics(files);
    if (app.count("--drift-table")) {
      const cgd::Scene table_scene =
          cgd::load_scene_from_string(files.front().scene_toml, files.front().path + " (scene)");
      const std::string report = cgd::fit::write_drift_table_model(output, files, drift_table, options.min_count,
                                                                   drift_min_alignment, table_scene);
      if (!quiet) std::cout << report << "wrote " << output << "\n";
      return cgd::kExitOk;
    }
    if (app.count("--grid-table")) {
      const cgd::Scene table_scene =
          cgd::load_scene_from_string(files.front().scene_toml, files.front().path + " (scene)");
      const std::string report =
          cgd::fit::write_grid_table_model(output, files, grid_table, options.min_count, table_scene);
      if (!quiet) std::cout << report << "wrote " << output << "\n";
      return cgd::kExitOk;
    }
    files = cgd::fit::select_operator(files, *calibration);  // first: its refusals name the file
    if (pool) files = {cgd::fit::pool_runs(files, options.seed)};
    const cgd::Scene scene =
        cgd::load_scene_from_string(files.front().scene_toml, files.front().path + " (scene)");
    const cgd::fit::FitResult result = cgd::fit::fit_filtered_drag(files, options, nullptr);
    cgd::fit::write_model_file(output, result, files, options, scene);
    if (!quiet) std::cout << cgd::fit::fit_report(result, files, options) << "wrote " << output << "\n";
    return cgd::kExitOk;
  });
  MPI_Finalize();
  return status;
}
