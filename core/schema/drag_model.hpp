#pragma once
// The drag model file (cgd_format "drag_model", docs/schema-drag-model.md): its one home. The struct, the
// attribute and dataset names (each spelled once, in the tables of drag_model.cpp and the constants below),
// the closed choices as enums (the calibration operator of core/schema/calibration.hpp, the curves), one
// write and one validating read (which upgrades the two spellings of version 1, drag_model.cpp). cgd-fit (fit/model_file.cpp) fills the struct; load_drag_model
// (core/filtered_drag.cpp: cgd-coarse, cgd-export, cgd-fit --parcel-fit) consumes it.
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/physical_system.hpp"
#include "core/schema/calibration.hpp"

namespace cgd {
struct Scene;
}

namespace cgd::schema {

/// The master curves' form (attribute `curves`): B-splines of h and log a, the piecewise-linear table of
/// H_grid of one grid (cgd-fit --grid-table), or the drift-velocity closure's table H(phi, cell slip) of one grid
/// (cgd-fit --drift-table; `/drift_table`, for fluid.drag = "drift" only). Absent in a file: Splines.
enum class ModelCurves { Splines, Table, DriftTable };
const char* to_string(ModelCurves curves);  // "splines", "table", "drift_table"

/// A B-spline group (`/h`, `/log_a`): order k, the full knot vector (n + k), n coefficients, its meaning.
struct SplineRecord {
  int order = 4;
  std::vector<double> knots, coefficients;
  std::string meaning;
};

struct DragModelFile {
  // root attributes
  std::int64_t version = 0;  // cgd_format_version as read (write: kDragModel.version)
  PhysicalSystem system;     // the law under names::kMicroLawAttribute (version 1: base_drag)
  std::string model_form;
  std::string u_t_convention = kUtConvention;
  double width_exponent = 1;            // absent: 1 (files written before it)
  bool width_exponent_fitted = false;
  double width_exponent_low = NAN, width_exponent_high = NAN;  // when fitted
  CalibrationOperator calibration_operator = CalibrationOperator::Box;  // absent: Box
  ModelCurves curves = ModelCurves::Splines;                           // absent: Splines
  std::vector<double> calibrated_delta_m, calibrated_delta_over_dp;   // may be empty
  std::vector<std::int64_t> calibrated_cells_across;                 // may be empty
  std::int64_t table_cells_across = 0;                               // curves = table
  double phi_crit = 0.016, phi_max = NAN, h_max = 0.99;
  double log_a_min = -HUGE_VAL, log_a_max = HUGE_VAL;  // absent: no bound
  SplineRecord h, log_a;

  struct CCorr {  // `/c_corr`
    double a = 0, k = 0.05;
    std::string source = "paper";
    bool fitted = false;
    /// What cgd-fit --parcel-fit adds (source = "parcel-fit"; docs/schema-drag-model.md "/c_corr").
    struct ParcelFit {
      double a_fit = 0, k_fit = 0, p_value = 1, k_lower_bound = 0, chi2_per_dof = 0;
      std::int64_t dof = 0;
      bool applied = false, rejected = false, a_fitted = false;
      std::string decision, method;
      std::vector<double> k_interval, a_interval;  // 2 each
      std::vector<std::string> runs;               // one per coarse run, and the runs_* values of each
      std::vector<double> runs_alpha, runs_phi, runs_factor, runs_factor_stderr, runs_seed;
    };
    std::optional<ParcelFit> parcel_fit;
  } c_corr;

  struct Bands {  // `/bands`: curves on phi, H on (F, phi)
    std::int64_t replicates = 0, seed = 0;
    double confidence = 0.95;
    std::string resampling;
    std::vector<double> phi, h, h_low, h_high, a, a_low, a_high, F;
    std::vector<double> H, H_low, H_high;  // (len(F), len(phi))
  };
  std::optional<Bands> bands;

  struct Bins {  // `/bins`: the per-bin estimates, NaN where not fitted
    std::vector<double> phi, phi_center, h, h_stderr, a, log_a_stderr, chi2, h_stderr_bootstrap,
        log_a_stderr_bootstrap;
    std::vector<std::int64_t> used, widths, at_bound, a_at_cap;
  };
  std::optional<Bins> bins;

  struct Data {  // `/data`: the data as fitted, (series, bins)
    std::vector<std::string> series;
    std::vector<double> F, phi, H, H_sigma;
    std::vector<std::int64_t> fitted;
  };
  std::optional<Data> data;

  struct Diagnostics {  // `/diagnostics`
    std::int64_t min_count = 0, min_widths = 0, breakpoints = 0, h_clamped_grid_points = 0;
    double min_width_over_cell = NAN, lambda_h = NAN, lambda_log_a = NAN, edf_h = NAN, edf_log_a = NAN,
           chi2_per_dof = NAN, cv_rms_H = NAN, cv_in_sample_rms_H = NAN, wall_seconds = NAN;
    std::vector<double> width_exponent_grid, width_exponent_chi2;  // with --width-exponent fit
    double width_exponent_chi2_per_dof = NAN;
    std::vector<std::string> residual_files, residual_groups;
    std::vector<double> residual_F, residual_mean, residual_mean_z, residual_rms_z, residual_mean_smoothed;
    std::vector<std::int64_t> residual_points;
    std::vector<std::string> cv_files;  // with two runs or more
    std::vector<std::int64_t> cv_run, cv_points;
    std::vector<double> cv_rms, cv_mean;
  };
  std::optional<Diagnostics> diagnostics;

  struct Table {  // `/table` (curves = table)
    std::vector<double> phi, H, count;
    std::string source_group;
    std::int64_t min_count = 0;
  };
  std::optional<Table> table;

  struct DriftTable {  // `/drift_table` (curves = drift_table; docs/schema-drag-model.md)
    std::vector<double> phi, slip;                      // bin centres: phi (n_phi), s^ = |s~|/u_t (n_slip)
    std::vector<double> H, numerator, denominator, magnitude;  // (n_phi, n_slip); H finite, the sums pooled
    std::vector<std::int64_t> count, filled;            // (n_phi, n_slip): samples; 0 measured, 1 nearest slip, 2 phi-only, 3 beyond
    std::vector<double> phi_only_H;                     // (n_phi): the phi-only H_grid of each row (the fallback)
    std::string source_group, fill_rule;
    std::int64_t min_count = 0;
    double min_alignment = NAN, phi_bin_width = NAN, slip_bin_width = NAN;
  };
  std::optional<DriftTable> drift_table;

  std::vector<std::string> source_files, source_checksums;  // `/sources`
  bool sources_pooled = false;  // `/sources` pooled_runs: fitted on the files' pooled runs (cgd-fit --pool-runs)

  // read, not written by write_drag_model: the common attributes and /provenance (data/models/*.h5)
  std::string code_version, created, scene_toml;
  std::vector<std::pair<std::string, std::string>> provenance;
};

/// Writes `path` atomically (the calling rank alone): the common attributes and /params of `scene`, and
/// the model.
void write_drag_model(const std::string& path, const Scene& scene, const DragModelFile& model);

/// Writes `output_path` atomically: a copy of the model file `model_path` (everything else unchanged) whose
/// /c_corr attributes are `c_corr` (cgd-fit --parcel-fit).
void write_c_corr_copy(const std::string& model_path, const std::string& output_path, const DragModelFile::CCorr& c_corr);

/// Reads and validates `path` (docs/schema-drag-model.md "What the reader checks"). InputError naming the
/// file and the attribute or dataset, what was found and what was expected.
DragModelFile read_drag_model(const std::string& path);

}  // namespace cgd::schema
