#pragma once
// cgd-filter's library: filtered slip and filtered drag coefficient of resolved runs, per filter
// width, binned by the filtered solids fraction (the paper's eqs. 4-5; docs/models.md "Filtering").
//
// For every particle i of every snapshot and every filter width Delta (a cube of edge Delta centred
// on the particle, on the periodic grid, exact for the cell values: filter/box_filter.hpp):
//   phi_bar_i  = 1 - filter(eps)                                  filtered solids fraction
//   u_bar_i    = filter(eps u) / filter(eps)                      Favre-filtered fluid velocity (eq. 4)
//   s_i        = u_bar_i - v_i                                    filtered slip (v_i not filtered)
//   N_i        = [-grad p_i + grad p_bar_i + beta_p,i (u_i - v_i)]_y     numerator of eq. 5
//   M_i        = beta_micro(phi_bar_i, |s_i|) s_i,y               what the micro law would give
// with grad p_i, beta_p,i, u_i, v_i the snapshot's per-particle values (fluid level n at x_n) and
// grad p_bar_i the exact gradient of the box-filtered pressure. (Runs without the pressure-gradient
// force leave out both pressure terms: the particle never felt them.) Per phi_bar bin:
//   beta_bar = sum N_i / sum s_i,y   (a ratio of sums, never a mean of ratios: s_i,y -> 0 is harmless)
//   H        = 1 - sum N_i / sum M_i   (how a coarse run uses it: beta_bar = (1 - H) beta_micro)
// and a 95 % interval of H from a block bootstrap over snapshots (see statistics.hpp).
//
// The drift-velocity closure's sums (issue 28; docs/closure.md "The drift-velocity closure"), per coarse grid (--grids)
// and per (phi_tilde, s_hat) bin: vbar_c = sum_i w_ic v_i / sum_i w_ic, the TSC deposit of the snapshot's particle
// velocities on the grid (equal volumes: V cancels; a cell with no deposit: u_C, zero slip), interpolated back,
// vbar_i = sum_c w_ic vbar_c; the cell slip s~_i = u~_i - vbar_i, s_hat_i = |s~_i| / u_t; with the grid's M_i and N_i
// above (M_i = beta_micro(phi~_i, |u~_i - v_i|) (u~_i - v_i)_y, N_i the resolved drag with the sub-grid pressure part),
//   numerator   = sum_i (M_i - N_i),   denominator = sum_i beta_micro,i s~_i,y,   magnitude = sum_i beta_micro,i |s~_i|,
// so that the closure F_i = V beta_micro [(u~_i - v_i) - H s~_i] reproduces each bin's total drag when
// H = numerator / denominator (with v_i = vbar_i it is H_grid).
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <mpi.h>

#include "core/run_directory.hpp"
#include "core/schema/snapshot.hpp"

namespace cgd::filter {

struct FilterOptions {
  std::vector<std::string> run_dirs;
  std::vector<double> widths_over_dp;          // empty: the default list (default_widths)
  std::vector<int> grids_cells_across;         // --grids: coarse grids, cells across the box's x edge
  double bin_width = 0.01;                     // phi_bar bins
  double bin_max = 0.65;                       // bins cover [0, bin_max)
  double slip_bin_width = 0.1;                 // --slip-bins: s_hat = |cell slip| / u_t bins of the drift sums (grids)
  double slip_bin_max = 3.0;                   // they cover [0, slip_bin_max)
  std::optional<double> from_time_s, from_tref;  // drop snapshots before this time
  std::int64_t samples = 0;                    // per-particle records kept per width (0: none)
  bool drift_per_snapshot = false;             // --drift-per-snapshot: also the drift sums per snapshot
  int bootstrap_replicates = 1000;
  std::uint64_t seed = 1;
  std::string output_path;
  bool force = false;                          // overwrite an existing output
  bool quiet = false;
};

/// A coarse grid of the coarse-grid operator (docs/filter.md "The coarse grid's operator"): the grid a
/// coarse run of `cells_across` cells along x builds for the run's box (fluid.dx_over_dp =
/// box_x / (cells_across d_p), the cell counts by the scene's own rule, spacing box / cells).
struct CoarseGrid {
  int cells_across = 0;
  double dx_over_dp = 0;                       // the fluid.dx_over_dp a coarse run is given
  PeriodicGrid grid;
  double void_fraction_floor = 0.3;            // numerics.void_fraction_floor of the run's scene
};

/// One run directory as the filter uses it.
struct RunPlan {
  std::string path;
  RunDirectory directory;
  std::vector<std::string> files;              // snapshots used, time order
  std::vector<double> times_s;
  std::vector<std::int64_t> steps;
  schema::RunPhysics physics;
  PeriodicGrid grid;
  std::vector<CoarseGrid> coarse;              // one per FilterPlan::grids entry
};

/// What will be done: the runs, the widths (m; the whole box is separate), the bins.
struct FilterPlan {
  std::vector<RunPlan> runs;
  std::vector<double> widths_m;
  std::vector<int> grids;                      // coarse grids (cells across x), ascending cell size
  double whole_box_width_m = 0;                // cube root of the (first run's) box volume
  std::vector<double> bin_edges;
  std::vector<double> slip_edges;              // s_hat bins of the drift sums (with grids; empty without)
  std::vector<std::string> warnings;
  std::size_t slip_bins() const { return slip_edges.empty() ? 0 : slip_edges.size() - 1; }
  std::size_t snapshot_count() const;
  /// Result columns: the widths, the whole box (index widths_m.size()), then the grids.
  std::size_t columns() const { return widths_m.size() + 1 + grids.size(); }
  std::size_t whole_box_column() const { return widths_m.size(); }
};

/// The coarse grid a coarse run with `cells_across` cells along x builds for the scene `scene_toml`:
/// the scene loaded with fluid.dx_over_dp = box_x / (cells_across d_p) (core/scene.cpp's rule for the
/// cell counts, the same call cgd-coarse makes), spacing = box edge / cells (sim/fluid/grid.cpp).
/// InputError naming `origin` when the scene cannot be loaded with it.
CoarseGrid coarse_grid_of_scene(const std::string& scene_toml, const std::string& origin, int cells_across);

/// The coarse-grid operator's fields on the coarse cells of one snapshot, interleaved 7 per cell:
/// phi (TSC deposit of the particles' volume, conservative floor), Favre velocity u (3: box average
/// of eps u_c over the cell / box average of eps), central-difference gradient of the cell-averaged
/// pressure (3). `fine` is the box filter of (eps, eps u_c, p) of the snapshot.
std::vector<double> coarse_grid_fields(const schema::Snapshot& snapshot, const CoarseGrid& coarse, double particle_volume_m3);

/// The drift sums' cell-mean particle velocity on a coarse grid, 3 per cell (file order): vbar_c = sum_i w_ic v_i /
/// sum_i w_ic, the TSC deposit of the snapshot's particles in their snapshot order (every particle of a snapshot has
/// the same volume, which cancels); a cell with no deposit gets the grid's fluid velocity u_C of `fields` (the 7 per
/// cell of coarse_grid_fields): zero cell slip there.
std::vector<double> coarse_cell_mean_velocity(const schema::Snapshot& snapshot, const CoarseGrid& coarse,
                                              const std::vector<double>& fields);

/// Default widths: the multiples k of the cell size h (cube root of the cell volume) with
/// 3 k h <= the shortest box edge of every run.
std::vector<double> default_widths_m(const PeriodicGrid& grid, double shortest_edge_m);

/// Reads the runs' headers and checks everything before any work: run directories, snapshots,
/// fluid fields, physics that agree, widths between one cell and the shortest box edge, bins, the
/// output path. InputError (exit 2) names the file or option, what was found and what is allowed.
FilterPlan plan_filter(const FilterOptions& options);

/// Per-snapshot sums of one (width, bin): count, sum N, sum M, sum s_y, sum phi_bar.
struct BinSums {
  double count = 0, numerator = 0, micro = 0, slip = 0, phi = 0;
};

/// Per-snapshot sums of one (grid, phi bin, s_hat bin) of the drift table (see the top of this file).
struct DriftSums {
  double count = 0, numerator = 0, denominator = 0, magnitude = 0, phi = 0, slip = 0;  // slip: sum of s_hat
};

/// A per-particle record (--samples).
struct Sample {
  std::uint64_t key = 0;                       // hash of (run, snapshot, id, width): the random choice
  std::int64_t snapshot = 0, id = 0;
  double phi = 0, numerator = 0, beta_micro = 0;
  double slip[3] = {0, 0, 0}, grad_p_filtered[3] = {0, 0, 0};
};

/// The filtered sums of one snapshot: sums[w * n_bins + b] for the widths (w < widths.size()), the
/// whole box (w = widths.size()) and the coarse grids (after it); particles with phi_bar outside the
/// bins in out_of_range[w].
struct SnapshotResult {
  std::vector<BinSums> sums;
  std::vector<std::int64_t> out_of_range;
  std::vector<std::vector<Sample>> samples;    // per width (incl. whole box), at most options.samples
  // drift sums: drift[(g * n_bins + b) * n_slip + m] for grid g, phi bin b, s_hat bin m; samples whose phi is in
  // the bins but s_hat beyond the slip bins in drift_out_of_range[g]
  std::vector<DriftSums> drift;
  std::vector<std::int64_t> drift_out_of_range;
  double seconds = 0;                          // wall time of the filtering (without reading)
  std::int64_t particles = 0;
};

/// Filters one snapshot (already read) for every width of the plan.
SnapshotResult filter_snapshot(const schema::Snapshot& snapshot, const FilterPlan& plan, const FilterOptions& options,
                               std::int64_t snapshot_row, std::size_t run_index);

/// The whole job: snapshots distributed over the ranks of `comm`, statistics and the file on rank 0
/// (written atomically). Collective. Returns the number of snapshots filtered.
std::size_t run_filter(const FilterOptions& options, MPI_Comm comm);

}  // namespace cgd::filter
