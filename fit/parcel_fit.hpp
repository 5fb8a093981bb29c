#pragma once
// The parcel fit (the paper's eq. 9; docs/models.md "Parcels"): c_corr(alpha) = a + (1 - a) exp(-k (alpha - 1))
// learnt from coarse CFD-DPM runs that used the grid model with c_corr switched off
// (fluid.parcel_correction = false), each compared with its resolved reference (cgd-coarse --reference).
//
// The drag factor a run needed: a coarse run with the grid model alone settles at slip s instead of the
// reference's s_ref. Treating the suspension's mean momentum balance as homogeneous with an effective
// drag, the weight is carried by beta(phi, s) s, so the factor c that recovers s_ref satisfies
//   c beta_m(phi, s_ref) s_ref = beta_m(phi, s) s      =>      c = beta_m(phi, s) s / (beta_m(phi, s_ref) s_ref),
// with beta_m the model's base micro law at the run's <phi> (the filtered factor 1 - H is common to both
// sides and cancels at first order). Every c of a <phi> is divided by that <phi>'s c(1) (the mean over its
// alpha = 1 runs), so that c_corr describes the parcels alone (c_corr(1) = 1 by definition) and not what the
// grid model misses; the reference cancels in that ratio. A <phi> without an alpha = 1 run is refused.
// Realisations (runs of one <phi> and alpha with different particles.seed) are pooled into one point: the
// mean of beta_m(s) s, with the larger of the between-realisation standard error (sd/sqrt(R)) and the
// batch-means one. k may be negative (c_corr > 1, the parcels need more drag) down to the bound that keeps
// c_corr(alpha_max) <= kMaxCcorr; the form is rejected when its chi2 p-value is below kRejectP. The fitted
// c_corr is applied (written) only when it is resolved (k's 95 % interval excludes 0) and the form is not
// rejected; otherwise the output's c_corr is 1 at every alpha (k = 0, a = 0) and `applied` = 0.
#include <string>
#include <vector>

#include "core/drag.hpp"

namespace cgd::fit {

struct ParcelRun {
  std::string run_dir;
  double solids_fraction = 0, parcel_size = 1;
  double slip_m_s = 0, slip_se_m_s = 0, reference_m_s = 0, reference_se_m_s = 0;
  double factor = 0, factor_se = 0;  // c needed, normalised by the mean of the alpha = 1 runs of its phi
  int seed = 1;                      // particles.seed of the run (its realisation)
};

/// One fitted point: the realisations of one (phi, alpha > 1) pooled.
struct ParcelPoint {
  double solids_fraction = 0, parcel_size = 1;
  int realisations = 0;
  double factor = 0, factor_se = 0;
};

struct ParcelFitResult {
  std::vector<ParcelRun> runs;
  double k = 0, k_low = 0, k_high = 0;
  double a = 0, a_low = 0, a_high = 0;
  bool a_fitted = false;   // a kept only when its 95 % interval excludes 0 (else a = 0, the paper's choice)
  double chi2_per_dof = 0;
  int dof = 0;
  double p_value = 1;        // P(chi2 >= observed) for dof degrees of freedom (1 with dof = 0: nothing to test)
  bool rejected = false;     // p_value < kRejectP: the form does not describe the factors
  double k_lower_bound = 0;  // -ln(kMaxCcorr) / (alpha_max - 1)
  bool k_at_bound = false;   // the best k sits on a bound of its search range
  bool applied = false;      // the fitted c_corr is written; false: c_corr = 1 is written (see `decision`)
  std::string decision;      // why the fit was or was not applied
  bool normalised_by_alpha1 = false;  // always true for a successful fit (kept for the report)
  std::vector<ParcelPoint> points;
  static constexpr double kMaxCcorr = 3.0;   // c_corr(alpha_max) above 3 is outside what the search allows
  static constexpr double kRejectP = 1e-3;   // a 0.1 % test: batch-means errors run low, only gross misfits reject
};

/// Reads RUN_DIR/summary.h5 of a cgd-coarse run. InputError unless it ran drag = "model" with
/// fluid.parcel_correction = false and has a reference.
ParcelRun read_parcel_run(const std::string& run_dir, double u_t_m_s);

/// Fits k (and a) to the runs; `base` is the model's base micro law and its parameters. InputError when a
/// <phi> has runs with alpha > 1 but none with alpha = 1, or when no run has alpha > 1.
ParcelFitResult fit_parcel_correction(std::vector<ParcelRun> runs, DragLaw base, const DragParams& params,
                                      int replicates = 2000, unsigned seed = 1);

/// Writes a copy of `model_path` to `output_path` whose /c_corr holds the applied a, k (the fitted ones, or
/// 0, 0 = c_corr 1 when not applied), the fitted values and intervals, chi2/dof, p_value, applied, decision,
/// source = "parcel-fit", fitted = 1 and the runs used. Atomic.
void write_parcel_fit(const std::string& model_path, const std::string& output_path, const ParcelFitResult& r);

std::string parcel_fit_report(const ParcelFitResult& r);

}  // namespace cgd::fit
