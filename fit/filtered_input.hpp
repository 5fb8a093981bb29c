#pragma once
// The fitter's view of filtered files (cgd_format = "filtered", docs/schema-filtered.md): what cgd-fit
// takes from each (read and validated by core/schema/filtered.hpp, the format's one home), and the checks
// that files pooled into one fit describe the same physics.
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/filtered_drag.hpp"  // CalibrationOperator
#include "core/physical_system.hpp"
#include "core/scene.hpp"

namespace cgd::fit {


/// One filter width of one file (`/width_<k>`, or `/whole_box`), per phi bin.
struct WidthSeries {
  std::string group;  // "/width_0", ..., "/whole_box", "/grids/<N>"
  double F = 0;       // L_char / width (a grid: L_char / its cell size)
  double width_m = 0;
  double width_over_cell = NAN;  // attribute width_over_cell (NaN when absent: not checked)
  bool whole_box = false;
  bool grid = false;              // a coarse grid's operator (/grids/<N>, cgd-filter --grids)
  std::int64_t cells_across = 0;  // grid: cells across x
  double cell_size_over_dp = NAN; // grid: its cell size (cube root of the cell volume) / d_p
  std::vector<double> H, H_low, H_high, phi_mean;  // per bin (NaN where the bin is empty)
  std::vector<std::int64_t> count;                 // particle samples per bin
  // per-snapshot sums (n_snapshots x n_bins, row-major), empty when the file has no /per_snapshot
  std::vector<double> numerator, micro;
  std::vector<std::int64_t> snapshot_count;
  // grid: the drift-velocity closure's sums (`drift/`, cgd-filter --grids), totals of shape (n_bins, n_slip)
  // row-major; empty when the file has none
  struct Drift {
    std::vector<std::int64_t> count;
    std::vector<double> numerator, denominator, magnitude;
  };
  std::optional<Drift> drift;
};

struct FilteredFile {
  std::string path, checksum;
  std::string scene_toml;  // root attribute `scene`
  PhysicalSystem physics;  // root attributes (core/physical_system.hpp); the law under micro_drag
  std::vector<double> phi_edges;       // /bins/phi_edges
  std::vector<double> slip_edges;      // /bins/slip_edges (u_t): the drift sums' slip bins; empty without them
  std::vector<WidthSeries> widths;     // the box widths in file order, then /whole_box if present
  std::vector<WidthSeries> grids;      // /grids/<N> (cgd-filter --grids), cells across descending; may be empty
  std::vector<std::string> run_paths;  // /runs paths
  std::vector<std::int64_t> snapshot_run, snapshot_block;  // /snapshots/run_index, block
  bool has_per_snapshot = false;
  // pool_runs: the files pooled into this one (their paths and checksums: the model's /sources); empty otherwise
  std::vector<std::string> pooled_paths, pooled_checksums;
  std::size_t bins() const { return phi_edges.empty() ? 0 : phi_edges.size() - 1; }
  std::size_t snapshots() const { return snapshot_run.size(); }
  std::size_t runs() const { return run_paths.size(); }
};

/// Read one filtered file through schema::read_filtered (InputError naming the file and the attribute or
/// dataset: docs/schema-filtered.md "What the reader checks") and keep what the fit uses.
FilteredFile read_filtered_file(const std::string& path);

/// The runs of several filtered files as one file of all of them (cgd-fit --pool-runs; docs/fit.md "Pooled runs"), as
/// cgd-filter writes a file of several runs: per width and bin the totals over every snapshot of every run (H = 1 -
/// sum N / sum beta_micro u_slip, the samples, their mean phi) and the 95 % interval of H from a block bootstrap as
/// cgd-filter's (`replicates` replicates, each drawing within each run as many of its snapshot blocks as it has, with
/// replacement; percentile interval; std::mt19937_64 seeded with `seed`); the per-snapshot sums one file after the
/// other, the runs numbered on. Fitted, each bin's H then weighs the runs by their share of its drag (the pooled
/// ratio); fitted side by side, each run's H is a point of its own weighted by its interval. path "pooled(A + B + ...)"
/// of the files' paths; pooled_paths, pooled_checksums: the files. The drift sums are not carried (the spline fit does not use
/// them; --drift-table pools the files' sums itself). InputError naming the files when one lacks the per-snapshot
/// sums or the widths and grids differ (group, F, cells across); the physics and bins are check_same_physics'. One
/// file is returned as it is (its H is the pooled H of its runs already).
FilteredFile pool_runs(const std::vector<FilteredFile>& files, std::uint64_t seed, int replicates = 1000);

/// The files as the fitter sees them for an operator: Box leaves them as read; Grid puts each file's
/// coarse grids (/grids/<N>, then /whole_box as a check) in place of its box widths, so that every step
/// of the fit (bins, splines, bootstrap, cross-validation) runs on H_grid with F = L_char / cell size.
/// InputError naming the files when a file has no /grids (filter it with cgd-filter --grids).
std::vector<FilteredFile> select_operator(const std::vector<FilteredFile>& files, CalibrationOperator op);

/// InputError naming both files and the key unless every file has the same physical system
/// (compare_systems: d_p, densities, viscosity, |g|, u_t, L_char to 1e-6 relative, micro_drag exactly)
/// and the same /bins/phi_edges.
void check_same_physics(const std::vector<FilteredFile>& files);

}  // namespace cgd::fit
