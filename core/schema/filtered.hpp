#pragma once
// The filtered file (cgd_format "filtered", docs/schema-filtered.md): its one home. The struct, the
// attribute and dataset names (each spelled once, in the tables of filtered.cpp and the constants below),
// the group kinds as an enum, one write and one validating read. cgd-filter (filter/run_filter.cpp) fills
// the struct, cgd-fit (fit/filtered_input.cpp) consumes it.
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/physical_system.hpp"

namespace cgd {
struct Scene;
}

namespace cgd::schema {

/// What a width group filters with: a box of width_m (`/width_<k>`), the whole box (`/whole_box`), or a
/// coarse grid's TSC deposit and interpolation (`/grids/<N>`). Stored as the group's attribute `kind`.
enum class FilterKind { Box, WholeBox, Grid };
const char* to_string(FilterKind kind);  // "box", "whole_box", "grid"

/// One width group. Per-bin vectors hold n_bins values (NaN in empty bins); a vector the reader found
/// absent (optional datasets of older or hand-made files) is empty, a number absent is NaN.
struct FilteredGroup {
  FilterKind kind = FilterKind::Box;
  double width_m = NAN, width_over_dp = NAN, width_over_cell = NAN, F = 0;
  std::int64_t out_of_range = 0;

  /// The attributes of a grid group (kind Grid).
  struct Grid {
    std::int64_t cells_across = 0;
    std::vector<std::int64_t> cells;      // 3
    double dx_over_dp = NAN;
    std::vector<double> cell_spacing_m;   // 3
    double cell_size_m = NAN, cell_size_over_dp = 0;
    double void_fraction_floor = NAN;
    double equivalent_width_m = NAN, equivalent_width_over_dp = NAN, equivalent_width_over_grid_cell = NAN;
    std::int64_t equivalent_width_bins = 0;
    bool equivalent_width_at_bound = false;
    double equivalent_width_rms = NAN;
    std::string equivalent_width_method;
  };
  std::optional<Grid> grid;

  std::vector<std::int64_t> count;  // required
  std::vector<double> H, H_low, H_high, phi_mean;  // required
  std::vector<double> phi_center, slip, slip_over_ut, drag, beta_bar, beta_micro, H_stderr, n_eff;  // optional

  /// `per_snapshot/`: sums of shape (n_snapshots, n_bins), row-major.
  struct PerSnapshot {
    std::vector<std::int64_t> count;
    std::vector<double> numerator, micro, slip, phi;  // slip, phi: optional on read
  };
  std::optional<PerSnapshot> per_snapshot;

  /// `drift/` of a grid group (cgd-filter --grids; absent in files written before it): the drift-velocity closure's
  /// sums per (phi bin, s_hat bin), shape (n_bins, n_slip) row-major (docs/schema-filtered.md "/grids/<N>/drift").
  struct Drift {
    std::int64_t out_of_range = 0;  // samples with phi in the bins but s_hat beyond /bins/slip_edges
    std::vector<std::int64_t> count;
    std::vector<double> numerator, denominator, magnitude;  // sum (M - N), sum beta s~_y, sum beta |s~|
    std::vector<double> phi_mean, slip_mean, H, H_stderr;   // NaN where empty (H: also where denominator = 0)
    struct PerSnapshot {  // (n_snapshots, n_bins, n_slip)
      std::vector<std::int64_t> count;
      std::vector<double> numerator, denominator;
    };
    std::optional<PerSnapshot> per_snapshot;
  };
  std::optional<Drift> drift;

  /// `samples/` (cgd-filter --samples): per-particle records; slip and grad_p_filtered (n, 3).
  struct Samples {
    std::vector<double> phi, slip, grad_p_filtered, numerator, beta_micro;
    std::vector<std::int64_t> snapshot, id;
  };
  std::optional<Samples> samples;
};

struct Filtered {
  // root attributes
  std::string scene_toml;  // `scene`
  std::int64_t version = 0;  // cgd_format_version as read (write: kFiltered.version)
  PhysicalSystem system;     // the runs' system; the law under names::kMicroLawAttribute
  double parcel_size = NAN;
  std::vector<double> cell_size_m;  // 3
  std::optional<bool> pressure_terms;
  std::int64_t bootstrap_replicates = 0, bootstrap_seed = 0;
  double confidence = NAN;
  std::string bootstrap;  // text: how the intervals are made

  // /runs (one row per run)
  std::vector<std::string> run_paths;  // as given (a file without the attribute: the file's own path)
  std::vector<double> run_mean_solids_fraction, run_tau_int, run_n_eff;
  std::vector<std::int64_t> run_snapshot_count, run_block_length;

  // /snapshots (one row per snapshot used)
  std::vector<std::string> snapshot_files, snapshot_checksums;
  std::vector<std::int64_t> snapshot_run_index, snapshot_step, snapshot_block;
  std::vector<double> snapshot_time_s;

  std::vector<double> phi_edges;  // /bins/phi_edges, n_bins + 1, strictly increasing
  std::vector<double> slip_edges; // /bins/slip_edges (u_t), n_slip + 1, strictly increasing; empty: no drift sums
  std::size_t slip_bins() const { return slip_edges.empty() ? 0 : slip_edges.size() - 1; }

  /// The box widths in file order, then the whole box (if any), then the grids (cells across descending).
  std::vector<FilteredGroup> groups;

  std::size_t bins() const { return phi_edges.empty() ? 0 : phi_edges.size() - 1; }
};

/// The group's path: "/width_<k>" (k = its rank among the box groups), "/whole_box", "/grids/<N>".
std::string group_path(const FilteredGroup& group, std::size_t box_index);
/// Every group's path, in the order of `file.groups`.
std::vector<std::string> group_paths(const Filtered& file);

/// Writes `path` atomically (the calling rank alone). `scene`: the first run's scene as this build loads it,
/// for the common attributes and /params; nullptr when its text does not load (an older run), then only the
/// format, the code version and `scene_toml` are written at the root.
void write_filtered(const std::string& path, const Scene* scene, const Filtered& file);

/// Reads and validates `path` (docs/schema-filtered.md "What the reader checks"); a file of version 1 has its
/// one old spelling upgraded (the grids' operator, filtered.cpp upgrade_version1). InputError naming the file
/// and the attribute or dataset, what was found and what was expected.
Filtered read_filtered(const std::string& path);

}  // namespace cgd::schema
