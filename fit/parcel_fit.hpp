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
// sides and cancels at first order). When an alpha = 1 run of the same <phi> exists, every c of that
// <phi> is divided by its c(1), so that c_corr describes the parcels alone (c_corr(1) = 1 by definition)
// and not what the grid model misses. Errors: the slips' batch-means standard errors, propagated as
// relative errors (d ln(beta s)/d ln s ~ 1 at Re_p ~ 1), and a parametric bootstrap of the fit.
#include <string>
#include <vector>

#include "core/drag.hpp"

namespace cgd::fit {

struct ParcelRun {
  std::string run_dir;
  double solids_fraction = 0, parcel_size = 1;
  double slip_m_s = 0, slip_se_m_s = 0, reference_m_s = 0, reference_se_m_s = 0;
  double factor = 0, factor_se = 0;  // c needed (normalised by the alpha = 1 run when there is one)
};

struct ParcelFitResult {
  std::vector<ParcelRun> runs;
  double k = 0, k_low = 0, k_high = 0;
  double a = 0, a_low = 0, a_high = 0;
  bool a_fitted = false;   // a kept only when its 95 % interval excludes 0 (else a = 0, the paper's choice)
  double chi2_per_dof = 0;
  bool normalised_by_alpha1 = false;
};

/// Reads RUN_DIR/summary.h5 of a cgd-coarse run. InputError unless it ran drag = "model" with
/// fluid.parcel_correction = false and has a reference.
ParcelRun read_parcel_run(const std::string& run_dir, double u_t_m_s);

/// Fits k (and a) to the runs; `base` is the model's base micro law and its parameters.
ParcelFitResult fit_parcel_correction(std::vector<ParcelRun> runs, DragLaw base, const DragParams& params,
                                      int replicates = 2000, unsigned seed = 1);

/// Writes a copy of `model_path` to `output_path` whose /c_corr holds the fitted a, k, their intervals,
/// source = "parcel-fit", fitted = 1 and the runs used. Atomic.
void write_parcel_fit(const std::string& model_path, const std::string& output_path, const ParcelFitResult& r);

std::string parcel_fit_report(const ParcelFitResult& r);

}  // namespace cgd::fit
