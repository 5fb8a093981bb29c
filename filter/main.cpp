// cgd-filter: filtered slip and filtered drag coefficient of resolved runs, per filter width, binned by
// the filtered solids fraction (ARCHITECTURE.md "The pipeline and its data flow"; docs/schema-filtered.md). A thin driver.
#include <mpi.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <sstream>

#include "core/cli.hpp"
#include "core/error.hpp"
#include "filter/filter.hpp"

namespace {
std::vector<double> parse_list(const std::string& text, const std::string& option) {
  std::vector<double> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    try {
      std::size_t used = 0;
      out.push_back(std::stod(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw cgd::InputError(option + ": '" + item + "' is not a number (expected a comma-separated list, e.g. 6.67,13.3,26.7)");
    }
  }
  if (out.empty()) throw cgd::InputError(option + ": empty list");
  return out;
}
}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  const int status = cgd::run_tool([&] {
    cgd::filter::FilterOptions o;
    std::string widths, bins;
    double from_time = -1, from_tref = -1;
    CLI::App app{"Filter resolved CFD-DEM runs: filtered slip and filtered drag correction H per filter width, binned by "
                 "the filtered solids fraction (Radl & Sundaresan eqs. 4-5)."};
    app.add_option("RUN_DIR", o.run_dirs, "run directories of cgd-generate (pooled when their physics agree)")->required();
    app.add_option("-o,--output", o.output_path, "filtered file to write (HDF5, cgd_format = filtered)")->required();
    app.add_option("--widths", widths, "filter widths in particle diameters, comma-separated (default: multiples of the cell "
                                       "that fit three times into the shortest box edge; the whole box is always added)");
    std::string grids;
    app.add_option("--grids", grids,
                   "coarse grids, given as cells across the box's x edge (a coarse run's fluid.dx_over_dp = box_x_dp / N), "
                   "comma-separated: the filtered drag correction H_grid of the coarse grid's own operator (TSC deposit "
                   "and interpolation, docs/filter.md) beside the box widths");
    app.add_option("--bins", bins, "phi_bar bins: WIDTH or WIDTH,MAX (default 0.01,0.65: [0, 0.65) in steps of 0.01)");
    std::string slip_bins;
    app.add_option("--slip-bins", slip_bins,
                   "bins of the cell slip |u~ - vbar| / u_t of the drift-velocity closure's sums (with --grids; "
                   "docs/closure.md): WIDTH or WIDTH,MAX (default 0.1,3: [0, 3) u_t in steps of 0.1)");
    app.add_flag("--drift-per-snapshot", o.drift_per_snapshot,
                 "also store the drift sums per snapshot (/grids/<N>/drift/per_snapshot, n_slip times the per-snapshot "
                 "sums of H: about two thirds of the file; cgd-fit --drift-table uses the totals, always stored)");
    app.add_option("--from-time", from_time, "drop snapshots before this time (s)");
    app.add_option("--from-tref", from_tref, "drop snapshots before this time (units of t_ref = u_t/g)");
    app.add_option("--samples", o.samples, "also store N random per-particle records per width");
    app.add_option("--bootstrap", o.bootstrap_replicates, "bootstrap replicates for the 95 % intervals (default 1000)");
    app.add_option("--seed", o.seed, "seed of the bootstrap and of the samples (default 1)");
    app.add_flag("--force", o.force, "overwrite an existing output file");
    app.add_flag("--quiet", o.quiet, "no progress output");
    cgd::parse_command_line(app, argc, argv, "cgd-filter");
    if (!widths.empty()) o.widths_over_dp = parse_list(widths, "--widths");
    if (!grids.empty())
      for (double g : parse_list(grids, "--grids")) {
        if (!(g >= 1 && g <= 1e6 && g == std::floor(g)))
          throw cgd::InputError("--grids: " + std::to_string(g) + " is not allowed (whole numbers of cells across, >= 1)");
        o.grids_cells_across.push_back(static_cast<int>(g));
      }
    if (!bins.empty()) {
      const std::vector<double> b = parse_list(bins, "--bins");
      if (b.size() > 2) throw cgd::InputError("--bins: give WIDTH or WIDTH,MAX, not " + bins);
      o.bin_width = b[0];
      if (b.size() == 2) o.bin_max = b[1];
    }
    if (!slip_bins.empty()) {
      const std::vector<double> b = parse_list(slip_bins, "--slip-bins");
      if (b.size() > 2) throw cgd::InputError("--slip-bins: give WIDTH or WIDTH,MAX, not " + slip_bins);
      o.slip_bin_width = b[0];
      if (b.size() == 2) o.slip_bin_max = b[1];
    }
    if (app.count("--from-time")) o.from_time_s = from_time;
    if (app.count("--from-tref")) o.from_tref = from_tref;
    cgd::filter::run_filter(o, MPI_COMM_WORLD);
    return cgd::kExitOk;
  });
  MPI_Finalize();
  return status;
}
