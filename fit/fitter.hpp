#pragma once
// cgd-fit's fit (docs/fit.md): master curves h(phi), a(phi) of the filtered drag model
//   H(F, phi) = h(phi) / (1 + a(phi) F^n),   F = L_char / Delta_filter,   beta_bar / beta_micro = 1 - H
// (Radl & Sundaresan 2014, Chem. Eng. Sci. 117:416, with n = 1; docs/models.md "Filtered drag model") from
// filtered files. n is given (default 1, the paper's form) or fitted (one n for every phi):
//
//  0. with fit_width_exponent: n minimises the chi^2 of step 1 pooled over the bins (a profile over a
//     grid of n; interval where it rises by 3.84 max(1, chi^2/dof)); steps 1-4 then use that n (the
//     bands are conditional on it);
//  1. per phi bin: (h, log a) by weighted nonlinear least squares over every width of every file,
//       min sum_w ((H_w - h/(1 + a F_w)) / sigma_w)^2,  sigma_w = (H_high - H_low)/(2 * 1.96)
//     (GSL gsl_multifit_nlinear, trust region with Levenberg-Marquardt steps, started from the best
//     point of a grid in log a); bins with fewer than min_count samples at a width drop that width,
//     bins with fewer than min_widths distinct widths are dropped;
//  2. over phi: penalised regression splines (P-splines, Eilers & Marx 1996, Stat. Sci. 11:89): cubic
//     B-splines on uniform breakpoints over [phi_crit, phi_max] (GSL gsl_bspline), a second-difference
//     penalty on the coefficients, the smoothing parameter by generalised cross-validation (Craven &
//     Wahba 1979), weights 1/se^2 of the per-bin estimates; penalised normal equations and covariances
//     with Eigen. h is fitted as is and clamped to [0, h_max]; a as log a (a > 0); below phi_crit
//     h -> 0 linearly and a is constant (no jump), as core/filtered_drag.hpp's SplineCurves evaluates;
//  3. bands: bootstrap over the filter's snapshot blocks (resampled with replacement within each run,
//     H recomputed exactly from the per-snapshot sums), steps 1-2 redone per replicate with the
//     smoothing parameters of the main fit; 95 % percentile bands of h, a and H(F, phi);
//  4. checks: leave-one-run-out cross-validation of H, residuals per width (of the per-bin fits: does
//     1/(1 + a F) describe the width dependence?), the whole-box filter as an out-of-sample check.
// The data are the box widths (operator "box") or the coarse grids' H_grid with Delta = the grid's cell
// size (operator "grid": filtered_input.hpp select_operator; docs/fit.md "The coarse grid's operator").
// Low phi (docs/fit.md "Low phi"): a bin's a is bounded by a F^n <= 10 at its widest width (beyond it only
// h/a is identified), and the model's a(phi) is clipped to the range of the bins' log a (log_a_min/max).
// The perfect-closure table (write_grid_table_model) is H_grid of one grid, piecewise linear in phi; the drift
// table (write_drift_table_model) the drift-velocity closure's H(phi, cell slip) of one grid, bilinear.
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "core/filtered_drag.hpp"
#include "fit/filtered_input.hpp"

namespace cgd::fit {

struct FitOptions {
  double phi_crit = 0.016;       // below it h -> 0 linearly (Radl & Sundaresan 2014)
  std::int64_t min_count = 100;  // particle samples a (width, bin) needs to be used
  int min_widths = 3;            // distinct widths a bin needs (2 parameters + 1 degree of freedom)
  int bootstrap = 400;           // replicates (0: no bands)
  std::uint64_t seed = 1;
  int breakpoints = 0;               // spline breakpoints (0: from the number of bins, 5..15)
  double min_width_over_cell = 2.0;  // narrower filters are not fitted (a one-cell filter averages nothing)
  double h_max = 0.99;               // upper clamp of h (beta_bar > 0)
  bool cross_validate = true;        // leave-one-run-out
  double width_exponent = 1.0;       // n of 1/(1 + a F^n) (1: Radl & Sundaresan 2014)
  bool fit_width_exponent = false;   // step 0: fit n instead
  // Box: the box widths (/width_<k>); Grid (--operator grid): the coarse grids' H_grid (/grids/<N>,
  // Delta = the grid's cell size; select_operator) — the model file's operator is then "grid"
  CalibrationOperator calibration_operator = CalibrationOperator::Box;
};

/// cgd-fit's min_width_over_cell on the grid operator (when --min-width-over-cell is not given): every grid coarser
/// than the resolved one is data (the 12-across grid of the half box is 1.33 resolved cells); a grid of the resolved
/// cells is the identity (H_grid = 0 by construction), a check.
inline constexpr double kGridMinWidthOverCell = 1.01;

/// The per-bin estimate of step 1.
struct BinEstimate {
  double phi = 0;  // count-weighted mean phi of the bin's samples
  double phi_center = 0;
  bool used = false;    // fitted and passed to the splines
  std::string dropped;  // why not ("" when used)
  int widths = 0;       // points in the fit
  double h = 0, log_a = 0, se_h = 0, se_log_a = 0, chi2 = 0;
  bool at_bound = false;  // h at -1 or 1, or a at 1e-3 or its upper bound: the form does not fit this bin well
  // a at its identifiability cap a <= 10 / min F^n (a F^n <= 10 at the widest width: beyond it only h/a is
  // seen, H ~ (h/a)/F^n; docs/fit.md "Low phi")
  bool a_at_cap = false;
  // bootstrap standard deviations (over the replicates that fitted the bin): unlike se_h, se_log_a from
  // (J^T J)^-1 they include the correlation of the widths' errors (NaN without a bootstrap)
  double boot_se_h = NAN, boot_se_log_a = NAN;
  // the points the bin's fit used (x = F^n, H, its sigma): the h curve is fitted to each bin's h at the
  // smoothed a (fitter.cpp fit_curves), which needs them
  std::vector<double> x, H, sigma;
};

/// Residual statistics of one width of one file (step 4).
struct WidthResiduals {
  std::string file, group;
  double F = 0;
  bool whole_box = false;
  bool fitted = true;  // false: whole box or narrower than min_width_over_cell (a check, not data)
  int points = 0;
  double mean = 0;               // mean of H - H_model (per-bin fits; for the whole box the smoothed model)
  double mean_z = 0, rms_z = 0;  // of (H - H_model)/sigma
  double mean_smoothed = 0;      // mean of H - H_model with the smoothed h(phi), a(phi)
};

struct CrossValidationRun {
  std::string file;
  std::int64_t run = 0;
  std::string run_path;  // the resolved run's directory (/runs/paths): names it by its <phi> and seed
  int points = 0;
  double rms = 0, mean = 0;  // of H_run - H_model(fit without this run)
};

struct FitResult {
  DragModel model;  // splines, phi_crit, h_max, physics, c_corr (paper values)
  std::vector<BinEstimate> bins;
  double lambda_h = 0, lambda_log_a = 0, edf_h = 0, edf_log_a = 0;
  int breakpoints = 0;
  double chi2_per_dof = 0;  // of the per-bin fits, pooled
  // the width exponent n (given or fitted in step 0), its 95 % interval and the chi^2 profile behind it
  double width_exponent = 1, width_exponent_low = NAN, width_exponent_high = NAN;
  double exponent_chi2_per_dof = NAN;
  bool width_exponent_at_bound = false;  // the profile's minimum at the grid's end (0.25 or 6)
  std::vector<double> exponent_grid, exponent_chi2;
  int h_clamped = 0;        // band grid points where the raw h spline left [0, h_max]
  // bands (step 3) on a grid
  std::vector<double> band_phi, h, h_low, h_high, a, a_low, a_high;
  std::vector<double> band_F;            // F of every width in the data, ascending
  std::vector<double> H, H_low, H_high;  // band_F.size() x band_phi.size(), row-major
  int replicates = 0;                    // bootstrap replicates used
  int replicates_skipped = 0;            // replicates that left fewer than 4 bins to fit
  std::string resampling;                // "snapshot blocks" or "normal intervals" (no per-snapshot sums)
  // the data as fitted: one row per (file, width) series, one column per bin
  std::vector<std::string> data_series;    // "file:group"
  std::vector<double> data_F, data_phi;    // per series; per bin (the bins' mean phi)
  std::vector<double> data_H, data_sigma;  // series x bins, row-major (NaN where empty)
  std::vector<std::int64_t> data_fitted;   // per series: 1 fitted, 0 a check (whole box, narrow)
  std::vector<WidthResiduals> residuals;
  std::vector<CrossValidationRun> cv_runs;
  double cv_rms = NAN, cv_in_sample_rms = NAN;
  double wall_seconds = 0;
};

/// Runs steps 1-4 on `files` (already checked with check_same_physics). InputError when too few
/// widths or bins remain to fit, naming the files and the threshold. Progress lines go to `log`
/// when given.
FitResult fit_filtered_drag(const std::vector<FilteredFile>& files, const FitOptions& options,
                            std::ostream* log);

/// The fit report (a page a researcher can judge in a minute), with Radl 2014 beside the fit.
std::string fit_report(const FitResult& result, const std::vector<FilteredFile>& files,
                       const FitOptions& options);

/// The perfect-closure model (cgd-fit --grid-table N, docs/fit.md): H_grid of the grid of N cells across,
/// pooled over the files (sums of the per-snapshot numerator and micro sums per bin), as the table of a
/// model file with curves = "table": (phi_k, H_k) at the bins' mean phi with >= min_count samples, h the
/// order-2 (piecewise-linear) B-spline through them, a = 0 (log a = -700 in /log_a). InputError naming
/// the files when a file lacks /grids/N or fewer than 2 bins qualify. Writes atomically; returns the
/// report.
std::string write_grid_table_model(const std::string& path, const std::vector<FilteredFile>& files, int cells_across,
                                   std::int64_t min_count, const Scene& scene);

/// The drift-velocity closure's table (cgd-fit --drift-table N, docs/closure.md "The drift-velocity closure"): the drift sums of
/// the grid of N cells across (`/grids/<N>/drift` of cgd-filter --grids), pooled over the files, as the table
/// H(phi_k, s_m) = numerator / denominator of a model file with curves = "drift_table" on the bins' centres. Rows:
/// the phi bins whose phi-only H_grid has >= min_count samples (with a non-zero micro sum); a (phi, slip) bin is
/// measured when it has >= min_count samples and |denominator| >= min_alignment x magnitude (the cell slip mostly
/// vertical, so the ratio is well conditioned); columns: the slip bins from the first to the last measured one of any
/// row. A bin not measured takes the H of the nearest measured slip bin of its row (the lower one on a tie), and a
/// row with none the row's phi-only H_grid (`filled` = 1, 2). InputError naming the files when a file lacks the
/// sums, the files' slip bins differ, fewer than 2 rows or no measured bin. Writes atomically; returns the report.
std::string write_drift_table_model(const std::string& path, const std::vector<FilteredFile>& files, int cells_across,
                                    std::int64_t min_count, double min_alignment, const Scene& scene);

/// Write the model file (docs/schema-drag-model.md) atomically; `scene` supplies the common root
/// attributes and /params (the first filtered file's scene).
void write_model_file(const std::string& path, const FitResult& result,
                      const std::vector<FilteredFile>& files, const FitOptions& options, const Scene& scene);

}  // namespace cgd::fit
