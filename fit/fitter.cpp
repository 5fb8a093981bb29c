// cgd-fit's fit: per-bin nonlinear least squares, penalised splines, block bootstrap, cross-validation
// (see fitter.hpp for the method and its sources, docs/fit.md for the choices).
#include "fit/fitter.hpp"

#include <gsl/gsl_blas.h>
#include <gsl/gsl_bspline.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_multifit_nlinear.h>
#include <gsl/gsl_randist.h>
#include <gsl/gsl_rng.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <numeric>
#include <ostream>
#include <set>
#include <sstream>

#include "core/error.hpp"

namespace cgd::fit {

namespace {

constexpr double kZ95 = 1.959963984540054;  // two-sided 95 % normal quantile
constexpr double kLogAMin = -6.907755278982137, kLogAMax = 9.210340371976184;  // log(1e-3), log(1e4)
// Bounds of a bin's h: H = h/(1 + aF) <= h, and h >= 1 would make beta_bar <= 0 at F -> 0; h < 0
// (drag increase, seen at very low phi in the paper) is allowed down to -1 per bin, the curve is
// clamped to [0, h_max] afterwards.
constexpr double kHMin = -1.0, kHMax = 1.0;
// Low phi (docs/fit.md "Low phi"): a is identified only where a F^n is O(1) at some width; when
// a F^n >> 1 at every width, H ~ (h/a)/F^n and only h/a is seen. A bin's a is bounded above by
// kIdentifiableAF / min F^n (a F^n <= 10 at the widest width: there H = h/11, and the curve's bend is
// still within the data). Without it, low-phi bins whose H is ~0 at the narrow (precise) widths and
// rises at the wide ones ran to a = 1e4 with h = 1, i.e. H ~ 0 at every width: the correction switched
// off where the wide widths show one.
constexpr double kIdentifiableAF = 10.0;
const double kNaN = std::numeric_limits<double>::quiet_NaN();

// ---- observations: H per (file, width) series and bin ---------------------------------------------------

struct Series {
  std::size_t file = 0, width = 0;
  double F = 0;
  double Fn = 0;  // F^n, n the width exponent: the variable of the form h/(1 + a F^n)
  bool whole_box = false;
  bool fitted = true;  // a box filter at least min_width_over_cell cells wide
  std::vector<double> H, sigma;
  std::vector<double> count;
};

/// Per-snapshot multiplicities of one file; empty = the file's own H (all snapshots once).
using Weights = std::vector<std::vector<double>>;

/// Observations of every width of every file. With weights[f] non-empty, H and count of file f are
/// recomputed from its per-snapshot sums, H = 1 - sum m N / sum m M (docs/schema-filtered.md), and
/// sigma is scaled by sqrt(n_snapshots / sum m) (fewer snapshots, wider interval); weights[f] all zero
/// leaves the file out. n: the width exponent (Series::Fn = F^n).
std::vector<Series> observe(const std::vector<FilteredFile>& files, const Weights* weights,
                            double min_width_over_cell, double n) {
  std::vector<Series> out;
  for (std::size_t f = 0; f < files.size(); ++f) {
    const FilteredFile& file = files[f];
    const std::vector<double>* m = weights && !(*weights)[f].empty() ? &(*weights)[f] : nullptr;
    double scale = 1.0;
    if (m) {
      const double used = std::accumulate(m->begin(), m->end(), 0.0);
      if (used <= 0.0) continue;
      scale = std::sqrt(static_cast<double>(file.snapshots()) / used);
    }
    const std::size_t nb = file.bins(), ns = file.snapshots();
    for (std::size_t w = 0; w < file.widths.size(); ++w) {
      const WidthSeries& ws = file.widths[w];
      Series s;
      s.file = f;
      s.width = w;
      s.F = ws.F;
      s.Fn = std::pow(ws.F, n);
      s.whole_box = ws.whole_box;
      s.fitted = !ws.whole_box && !(ws.width_over_cell < min_width_over_cell - 1e-9);
      s.H.assign(nb, kNaN);
      s.sigma.assign(nb, kNaN);
      s.count.assign(nb, 0.0);
      for (std::size_t b = 0; b < nb; ++b) {
        const double sigma = (ws.H_high[b] - ws.H_low[b]) / (2.0 * kZ95) * scale;
        s.sigma[b] = sigma;
        if (!m) {
          s.H[b] = ws.H[b];
          s.count[b] = static_cast<double>(ws.count[b]);
          continue;
        }
        double num = 0, micro = 0, count = 0;
        for (std::size_t k = 0; k < ns; ++k) {
          const double mk = (*m)[k];
          if (mk == 0.0) continue;
          num += mk * ws.numerator[k * nb + b];
          micro += mk * ws.micro[k * nb + b];
          count += mk * static_cast<double>(ws.snapshot_count[k * nb + b]);
        }
        s.count[b] = count;
        s.H[b] = micro != 0.0 ? 1.0 - num / micro : kNaN;
      }
      out.push_back(std::move(s));
    }
  }
  return out;
}

// A bin whose bootstrap interval has no width (all its samples in one block of snapshots: the demo's 7.5 d_p
// grid at phi = 0.275, 178 samples, H_low = H_high to 1e-16) has no error estimate: left out, not weighted
// by 1/sigma^2 = 1e32.
constexpr double kMinSigma = 1e-6;

bool usable(const Series& s, std::size_t b, double min_count) {
  return s.fitted && s.count[b] >= min_count && std::isfinite(s.H[b]) && std::isfinite(s.sigma[b]) &&
         s.sigma[b] > kMinSigma;
}

// ---- step 1: (h, log a) per bin -------------------------------------------------------------------------

struct BinPoints {
  std::vector<double> F, H, sigma;
};

int residual_f(const gsl_vector* x, void* data, gsl_vector* f) {
  const auto* d = static_cast<const BinPoints*>(data);
  const double h = gsl_vector_get(x, 0), a = std::exp(gsl_vector_get(x, 1));
  for (std::size_t i = 0; i < d->F.size(); ++i)
    gsl_vector_set(f, i, (h / (1.0 + a * d->F[i]) - d->H[i]) / d->sigma[i]);
  return GSL_SUCCESS;
}

int residual_df(const gsl_vector* x, void* data, gsl_matrix* J) {
  const auto* d = static_cast<const BinPoints*>(data);
  const double h = gsl_vector_get(x, 0), a = std::exp(gsl_vector_get(x, 1));
  for (std::size_t i = 0; i < d->F.size(); ++i) {
    const double g = 1.0 / (1.0 + a * d->F[i]);
    gsl_matrix_set(J, i, 0, g / d->sigma[i]);
    gsl_matrix_set(J, i, 1, -h * a * d->F[i] * g * g / d->sigma[i]);  // d/d(log a)
  }
  return GSL_SUCCESS;
}

/// The weighted least-squares h of points (x, H, sigma) with a held fixed: H = h g, g = 1/(1 + a x), so
/// h = sum w g H / sum w g^2 (w = 1/sigma^2), clamped to [kHMin, kHMax]. `sgg` receives sum w g^2, 1/se^2 of
/// that h. Used by the per-bin fit's profile over a and by the h curve (fit_curves).
double h_at_fixed_a(const std::vector<double>& x, const std::vector<double>& H, const std::vector<double>& sigma,
                    double a, double& sgg) {
  double sgh = 0;
  sgg = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double g = 1.0 / (1.0 + a * x[i]), w = 1.0 / (sigma[i] * sigma[i]);
    sgh += w * g * H[i];
    sgg += w * g * g;
  }
  return std::clamp(sgh / sgg, kHMin, kHMax);
}

/// Weighted least squares of H = h/(1 + a F) over one bin's points; returns h, log a, their standard
/// errors from (J^T J)^-1 (residuals are already divided by sigma) and chi^2.
void fit_one_bin(const BinPoints& pts, BinEstimate& out) {
  const std::size_t n = pts.F.size();
  // Start, and the answer when the minimum lies on a bound: for each log a on a grid, chi^2 is a
  // parabola in h, so the best h in [kHMin, kHMax] is the clamped linear solution; a coarse grid over
  // log a in [log 1e-3, log 1e4], then a fine one around its best point.
  auto profile = [&](double t, double& h_out) {
    const double a = std::exp(t);
    double sgg = 0;
    h_out = h_at_fixed_a(pts.F, pts.H, pts.sigma, a, sgg);
    double chi2 = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const double r = (h_out / (1.0 + a * pts.F[i]) - pts.H[i]) / pts.sigma[i];
      chi2 += r * r;
    }
    return chi2;
  };
  double best_chi2 = std::numeric_limits<double>::infinity(), best_h = 0, best_t = 0;
  const double min_F = *std::min_element(pts.F.begin(), pts.F.end());
  const double t_max = std::clamp(std::log(kIdentifiableAF / min_F), kLogAMin + 1.0, kLogAMax);
  const double step = (t_max - kLogAMin) / 60.0;
  for (int k = 0; k <= 60; ++k) {
    double h_k = 0;
    const double t = kLogAMin + step * k, chi2 = profile(t, h_k);
    if (chi2 < best_chi2) best_chi2 = chi2, best_h = h_k, best_t = t;
  }
  const double coarse_t = best_t;
  for (int k = -20; k <= 20; ++k) {
    double h_k = 0;
    const double t = std::clamp(coarse_t + step * k / 20.0, kLogAMin, t_max), chi2 = profile(t, h_k);
    if (chi2 < best_chi2) best_chi2 = chi2, best_h = h_k, best_t = t;
  }
  double h = best_h, t = best_t, se_h = kNaN, se_t = kNaN, chi2 = best_chi2;

  gsl_multifit_nlinear_fdf fdf;
  fdf.f = residual_f;
  fdf.df = residual_df;
  fdf.fvv = nullptr;
  fdf.n = n;
  fdf.p = 2;
  fdf.params = const_cast<BinPoints*>(&pts);
  gsl_multifit_nlinear_parameters params = gsl_multifit_nlinear_default_parameters();
  gsl_multifit_nlinear_workspace* w = gsl_multifit_nlinear_alloc(gsl_multifit_nlinear_trust, &params, n, 2);
  double x0[2] = {best_h, best_t};
  gsl_vector_view xv = gsl_vector_view_array(x0, 2);
  int info = 0;
  gsl_error_handler_t* old = gsl_set_error_handler_off();
  if (gsl_multifit_nlinear_init(&xv.vector, &fdf, w) == GSL_SUCCESS) {
    gsl_multifit_nlinear_driver(200, 1e-10, 1e-10, 0.0, nullptr, nullptr, &info, w);
    const gsl_vector* x = gsl_multifit_nlinear_position(w);
    const double h1 = gsl_vector_get(x, 0), t1 = gsl_vector_get(x, 1);
    double c2 = 0;
    gsl_blas_ddot(gsl_multifit_nlinear_residual(w), gsl_multifit_nlinear_residual(w), &c2);
    // the unconstrained refinement is kept when it stays inside the bounds and does not lose
    if (std::isfinite(h1) && std::isfinite(t1) && h1 >= kHMin && h1 <= kHMax && t1 >= kLogAMin &&
        t1 <= t_max && c2 <= best_chi2 * (1 + 1e-12)) {
      h = h1;
      t = t1;
      chi2 = c2;
    }
  }
  // covariance at the solution (with t clamped, evaluate J there)
  {
    double xs[2] = {h, t};
    gsl_vector_view xsv = gsl_vector_view_array(xs, 2);
    gsl_matrix* J = gsl_matrix_alloc(n, 2);
    gsl_matrix* cov = gsl_matrix_alloc(2, 2);
    residual_df(&xsv.vector, const_cast<BinPoints*>(&pts), J);
    if (gsl_multifit_nlinear_covar(J, 0.0, cov) == GSL_SUCCESS) {
      se_h = std::sqrt(gsl_matrix_get(cov, 0, 0));
      se_t = std::sqrt(gsl_matrix_get(cov, 1, 1));
    }
    gsl_matrix_free(J);
    gsl_matrix_free(cov);
  }
  gsl_set_error_handler(old);
  gsl_multifit_nlinear_free(w);
  // An unidentifiable a (h ~ 0, or H flat in F) or a at its bound carries little information on a:
  // give it a weak weight in the spline (se of log a >= 2, a factor 7) instead of dropping the bin's h.
  const bool at_bound = t <= kLogAMin + 1e-9 || t >= t_max - 1e-9 || h <= kHMin || h >= kHMax;
  out.at_bound = at_bound;
  out.a_at_cap = t_max < kLogAMax && t >= t_max - 1e-9;
  if (!std::isfinite(se_t) || at_bound) se_t = std::max(std::isfinite(se_t) ? se_t : 0.0, 2.0);
  if (!std::isfinite(se_h)) se_h = kNaN;
  out.h = h;
  out.log_a = t;
  out.se_h = se_h;
  out.se_log_a = std::max(se_t, 1e-6);
  out.chi2 = chi2;
  out.widths = static_cast<int>(n);
}

std::vector<BinEstimate> fit_bins(const std::vector<FilteredFile>& files, const std::vector<Series>& series,
                                  const FitOptions& o) {
  const std::size_t nb = files.front().bins();
  const std::vector<double>& edges = files.front().phi_edges;
  std::vector<BinEstimate> bins(nb);
  for (std::size_t b = 0; b < nb; ++b) {
    BinEstimate& e = bins[b];
    e.phi_center = 0.5 * (edges[b] + edges[b + 1]);
    BinPoints pts;
    std::set<double> distinct_F;
    double phi_sum = 0, count_sum = 0;
    for (const Series& s : series) {
      if (!usable(s, b, static_cast<double>(o.min_count))) continue;
      pts.F.push_back(s.Fn);  // the bin fit sees F^n: H = h/(1 + a F^n) is h/(1 + a x) in x = F^n
      pts.H.push_back(s.H[b]);
      pts.sigma.push_back(s.sigma[b]);
      distinct_F.insert(s.F);
      const double pm = files[s.file].widths[s.width].phi_mean[b];
      if (std::isfinite(pm)) phi_sum += s.count[b] * pm, count_sum += s.count[b];
    }
    e.phi = count_sum > 0 ? phi_sum / count_sum : e.phi_center;
    if (static_cast<int>(distinct_F.size()) < o.min_widths) {
      e.dropped = "samples >= " + std::to_string(o.min_count) + " at " + std::to_string(distinct_F.size()) +
                  " width(s) only";
      continue;
    }
    if (e.phi < o.phi_crit) {
      e.dropped = "below phi_crit (h -> 0 linearly there)";
      continue;
    }
    fit_one_bin(pts, e);
    e.x = pts.F;
    e.H = pts.H;
    e.sigma = pts.sigma;
    if (!std::isfinite(e.h) || !std::isfinite(e.se_h) || !(e.se_h > 0)) {
      e.dropped = "fit failed (singular)";
      continue;
    }
    e.used = true;
  }
  return bins;
}

// ---- step 2: penalised regression splines ---------------------------------------------------------------

struct SplineFit {
  BSpline spline;
  double lambda = 0;  // absolute penalty weight
  double edf = 0, gcv = 0;
  double scale2 = 1;  // sigma^2 = RSS_w / (n - edf): the weights' scale as the residuals show it
  // Bias allowance of the coefficients, sigma^2 A^-1 (lambda P) A^-1 with A = X'WX + lambda P: the part of
  // the Bayesian posterior covariance sigma^2 A^-1 of a penalised spline (Wahba 1983, J. R. Stat. Soc. B
  // 45:133; Nychka 1988, JASA 83:1134) that the frequentist (sampling) covariance sigma^2 A^-1 X'WX A^-1
  // lacks. Nychka showed that intervals from the posterior covariance have close to nominal coverage
  // averaged over x because this term accounts for the smoothing bias; the bootstrap estimates the
  // sampling part (with the data's true correlations), this term is added to it.
  Eigen::MatrixXd bias_cov;
};

/// The B-spline basis (order 4) on uniform breakpoints over [lo, hi]; knots as stored in model files.
struct Basis {
  std::unique_ptr<gsl_bspline_workspace, decltype(&gsl_bspline_free)> ws{nullptr, &gsl_bspline_free};
  std::size_t ncoef = 0;
  std::vector<double> knots;
  Basis(double lo, double hi, int nbreak) {
    ws.reset(gsl_bspline_alloc(4, static_cast<std::size_t>(nbreak)));
    gsl_bspline_knots_uniform(lo, hi, ws.get());
    ncoef = gsl_bspline_ncoeffs(ws.get());
    knots.assign(ws->knots->data, ws->knots->data + ws->knots->size);
  }
  Eigen::MatrixXd matrix(const std::vector<double>& x) const {
    Eigen::MatrixXd X(static_cast<Eigen::Index>(x.size()), static_cast<Eigen::Index>(ncoef));
    gsl_vector* B = gsl_vector_alloc(ncoef);
    const double lo = knots.front(), hi = knots.back();
    for (std::size_t i = 0; i < x.size(); ++i) {
      gsl_bspline_eval(std::clamp(x[i], lo, hi), B, ws.get());
      for (std::size_t j = 0; j < ncoef; ++j)
        X(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = gsl_vector_get(B, j);
    }
    gsl_vector_free(B);
    return X;
  }
};

/// Minimises sum w (y - X c)^2 + lambda |D2 c|^2 (P-spline). lambda < 0: chosen by GCV,
/// V = n RSS_w / (n - edf)^2, edf = tr((X'WX + lambda P)^-1 X'WX), over a log grid.
SplineFit pspline(const Basis& basis, const std::vector<double>& x, const std::vector<double>& y,
                  const std::vector<double>& w, double lambda) {
  const Eigen::Index n = static_cast<Eigen::Index>(x.size()), m = static_cast<Eigen::Index>(basis.ncoef);
  const Eigen::MatrixXd X = basis.matrix(x);
  const Eigen::Map<const Eigen::VectorXd> Y(y.data(), n), Wv(w.data(), n);
  const Eigen::MatrixXd XtWX = X.transpose() * Wv.asDiagonal() * X;
  const Eigen::VectorXd XtWy = X.transpose() * (Wv.array() * Y.array()).matrix();
  Eigen::MatrixXd D = Eigen::MatrixXd::Zero(m - 2, m);
  for (Eigen::Index i = 0; i < m - 2; ++i) D(i, i) = 1, D(i, i + 1) = -2, D(i, i + 2) = 1;
  const Eigen::MatrixXd P = D.transpose() * D;
  auto solve = [&](double lam, SplineFit& out) {
    const Eigen::MatrixXd A = XtWX + lam * P;
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(A);
    const Eigen::VectorXd c = ldlt.solve(XtWy);
    const double edf = ldlt.solve(XtWX).trace();
    const Eigen::VectorXd r = Y - X * c;
    const double rss = (Wv.array() * r.array().square()).sum();
    out.lambda = lam;
    out.edf = edf;
    out.gcv = n - edf > 0.5 ? static_cast<double>(n) * rss / ((n - edf) * (n - edf))
                            : std::numeric_limits<double>::infinity();
    out.spline.order = 4;
    out.spline.knots = basis.knots;
    out.spline.coefficients.assign(c.data(), c.data() + m);
    out.scale2 = n - edf > 0.5 ? rss / (static_cast<double>(n) - edf) : 1.0;
    const Eigen::MatrixXd Ainv = ldlt.solve(Eigen::MatrixXd::Identity(m, m));
    out.bias_cov = out.scale2 * Ainv * (lam * P) * Ainv;
  };
  SplineFit best;
  if (lambda >= 0) {
    solve(lambda, best);
    return best;
  }
  const double scale = XtWX.trace() / P.trace();  // makes the grid dimensionless
  best.gcv = std::numeric_limits<double>::infinity();
  for (int k = 0; k <= 60; ++k) {
    SplineFit trial;
    solve(scale * std::pow(10.0, -6.0 + 12.0 * k / 60.0), trial);
    if (trial.gcv < best.gcv) best = trial;
  }
  if (!std::isfinite(best.gcv)) solve(scale * 1e6, best);
  return best;
}

struct Curves {
  SplineFit h, log_a;
};

/// The curves: log a(phi) smoothed over the bins' log a (weights 1/se^2), then h(phi) smoothed over each bin's
/// h *at the smoothed a*: with a fixed to a(phi_b), the bin's h is the linear least-squares h of its points,
/// h_b = sum w g H / sum w g^2 with g = 1/(1 + a x), w = 1/sigma^2, se = (sum w g^2)^-1/2 (docs/fit.md
/// "Low phi"). Smoothing h_b and log a_b separately (before 2026-12-02) ignored that within a bin they trade
/// off (only H = h g is measured): where a is weakly identified (low phi, a at its cap) the log a curve
/// follows the neighbours while the bin's h kept the value that went with its own a, and the h curve's end
/// coefficient, held by that bin alone, ran off: the demo's H at phi = 0.017 was 0.80 against a measured 0.02
/// on the 7.5 d_p grid (coarse runs at <phi> = 0.02 +20 % in slip). Conditional on a, h_b is well identified
/// wherever H is measured, and the curves reproduce the bins' H.
Curves fit_curves(const std::vector<BinEstimate>& bins, double lo, double hi, int nbreak, double lambda_h,
                  double lambda_a) {
  std::vector<double> x, yh, wh, ya, wa;
  for (const BinEstimate& b : bins) {
    if (!b.used) continue;
    x.push_back(b.phi);
    ya.push_back(b.log_a);
    wa.push_back(1.0 / (b.se_log_a * b.se_log_a));
  }
  const Basis basis(lo, hi, nbreak);
  SplineFit log_a = pspline(basis, x, ya, wa, lambda_a);
  for (const BinEstimate& b : bins) {
    if (!b.used) continue;
    const double a = std::exp(std::clamp(log_a.spline(b.phi), kLogAMin, kLogAMax));
    double sgg = 0;  // a used bin has >= min_widths points (fit_bins), so sgg > 0
    yh.push_back(h_at_fixed_a(b.x, b.H, b.sigma, a, sgg));
    wh.push_back(sgg);
  }
  return {pspline(basis, x, yh, wh, lambda_h), std::move(log_a)};
}

/// Variance b(x)' C b(x) of a spline with coefficient covariance C at x (clamped into the knot range).
double spline_variance(const BSpline& s, const Eigen::MatrixXd& C, double x) {
  const std::size_t n = s.coefficients.size();
  Eigen::VectorXd b = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(n));
  BSpline unit = s;
  for (std::size_t j = 0; j < n; ++j) {  // basis function j = the spline with coefficient e_j
    std::fill(unit.coefficients.begin(), unit.coefficients.end(), 0.0);
    unit.coefficients[j] = 1.0;
    b(static_cast<Eigen::Index>(j)) = unit(x);
  }
  return b.dot(C * b);
}

double quantile(std::vector<double>& v, double q) {
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const std::size_t i = static_cast<std::size_t>(pos);
  const double frac = pos - static_cast<double>(i);
  return i + 1 < v.size() ? v[i] * (1 - frac) + v[i + 1] * frac : v[i];
}

/// chi^2 of each bin's fit at width exponent n (NaN where the bin is not fitted) and its point count.
struct BinChi2 {
  std::vector<double> chi2;
  std::vector<int> widths;
};
BinChi2 bin_chi2(const std::vector<FilteredFile>& files, const FitOptions& o, double n) {
  BinChi2 out;
  for (const BinEstimate& b : fit_bins(files, observe(files, nullptr, o.min_width_over_cell, n), o)) {
    out.chi2.push_back(b.used ? b.chi2 : kNaN);
    out.widths.push_back(b.widths);
  }
  return out;
}

/// Step 0 with --width-exponent fit: n minimises the chi^2 of the per-bin fits of H = h/(1 + a F^n) pooled over
/// the bins (one n for every phi: the profile over n of the joint fit of (h_b, a_b, n)), summed over the bins
/// fitted at every n tried (a bin whose fit fails at some n would otherwise make a false dip). A grid
/// n = 0.25 ... 6 in steps of 0.05, then steps of 0.005 within 0.05 of the best point. The 95 % interval is
/// where the profile rises by 3.84 s^2 above its minimum, s^2 = max(1, chi^2_min/dof) (the bins' intervals
/// scaled by the misfit, as for a weighted fit whose sigmas are relative), its ends interpolated linearly
/// between grid points; it treats the widths of a bin as independent (they are nested filters of the same
/// snapshots), so it is a lower bound. Records the profile in R.
double fit_width_exponent(const std::vector<FilteredFile>& files, const FitOptions& o, FitResult& R) {
  std::vector<std::pair<double, BinChi2>> tried;
  for (int k = 0; k <= 115; ++k) tried.push_back({0.25 + 0.05 * k, bin_chi2(files, o, 0.25 + 0.05 * k)});
  auto pooled = [&](const std::vector<char>& common, const BinChi2& b) {
    double sum = 0;
    for (std::size_t i = 0; i < common.size(); ++i)
      if (common[i]) sum += b.chi2[i];
    return sum;
  };
  auto common_bins = [&]() {
    std::vector<char> common(tried.front().second.chi2.size(), 1);
    for (const auto& [n, b] : tried)
      for (std::size_t i = 0; i < common.size(); ++i) common[i] = common[i] && std::isfinite(b.chi2[i]);
    return common;
  };
  std::vector<char> common = common_bins();
  std::size_t best = 0;
  for (std::size_t i = 1; i < tried.size(); ++i)
    if (pooled(common, tried[i].second) < pooled(common, tried[best].second)) best = i;
  const double coarse = tried[best].first;
  for (int k = -9; k <= 9; ++k)  // the coarse grid's neighbours (k = +-10) are already there
    if (k != 0 && coarse + 0.005 * k > 0.2) tried.push_back({coarse + 0.005 * k, bin_chi2(files, o, coarse + 0.005 * k)});
  std::sort(tried.begin(), tried.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  common = common_bins();
  std::vector<double>& grid = R.exponent_grid;
  std::vector<double>& chi2 = R.exponent_chi2;
  grid.clear();
  chi2.clear();
  for (const auto& [n, b] : tried) grid.push_back(n), chi2.push_back(pooled(common, b));
  best = static_cast<std::size_t>(std::min_element(chi2.begin(), chi2.end()) - chi2.begin());
  int dof = -1;  // n, shared
  for (std::size_t i = 0; i < common.size(); ++i)
    if (common[i]) dof += tried[best].second.widths[i] - 2;  // h, a per bin
  R.exponent_chi2_per_dof = dof > 0 ? chi2[best] / dof : kNaN;
  const double s2 = std::max(1.0, std::isfinite(R.exponent_chi2_per_dof) ? R.exponent_chi2_per_dof : 1.0);
  const double threshold = chi2[best] + 3.84 * s2;
  std::size_t lo = best, hi = best;
  while (lo > 0 && chi2[lo - 1] <= threshold) --lo;
  while (hi + 1 < grid.size() && chi2[hi + 1] <= threshold) ++hi;
  auto crossing = [&](std::size_t in, std::size_t out) {  // where the profile crosses the threshold
    return grid[in] + (grid[out] - grid[in]) * (threshold - chi2[in]) / (chi2[out] - chi2[in]);
  };
  R.width_exponent_low = lo > 0 ? crossing(lo, lo - 1) : grid[lo];
  R.width_exponent_high = hi + 1 < grid.size() ? crossing(hi, hi + 1) : grid[hi];
  // the minimum, or an end of the interval, at the grid's end: the interval is open there
  R.width_exponent_at_bound = best == 0 || best + 1 == grid.size() || lo == 0 || hi + 1 == grid.size();
  return grid[best];
}

std::string file_list(const std::vector<FilteredFile>& files) {
  std::string s;
  for (std::size_t i = 0; i < files.size(); ++i) s += (i ? ", " : "") + files[i].path;
  return s;
}

/// The distinct widths (F = L_char/Delta) of the files at least o.min_width_over_cell cells wide, whole-box
/// series aside; InputError when there are fewer than o.min_widths of them (2 parameters per bin + 1).
std::set<double> usable_widths(const std::vector<FilteredFile>& files, const FitOptions& o) {
  std::set<double> widths;
  int narrow = 0;
  for (const FilteredFile& f : files)
    for (const WidthSeries& w : f.widths) {
      if (w.whole_box) continue;
      if (w.width_over_cell < o.min_width_over_cell - 1e-9) {
        ++narrow;
        continue;
      }
      widths.insert(w.F);
    }
  if (static_cast<int>(widths.size()) < o.min_widths)
    throw InputError(file_list(files) + ": too few filter widths to fit h(phi) and a(phi): " +
                     std::to_string(widths.size()) + " distinct width(s) (groups /width_<k>) of at least " +
                     [&] { std::ostringstream m; m << o.min_width_over_cell; return m.str(); }() + " cells (" + std::to_string(narrow) +
                     " narrower not used), at least " + std::to_string(o.min_widths) +
                     " needed (2 parameters per bin + 1 degree of freedom)");

  return widths;
}

/// The model file's header of a fit: the files' physical system (the first file's; fit_filtered_drag's
/// callers checked that the files agree), the options' phi_crit and h_max, the exponent n, the fitted
/// curves, the range of log a the bins identified and the paper's c_corr.
void fill_model(DragModel& M, const std::vector<BinEstimate>& bins, const PhysicalSystem& p, const FitOptions& o,
                double n, const Curves& main) {
  static_cast<PhysicalSystem&>(M) = p;  // |g| as the files store it (older files: from u_t and L_char)
  M.u_t_convention = kUtConvention;
  M.phi_crit = o.phi_crit;
  M.h_max = o.h_max;
  M.width_exponent = n;
  M.h_spline = main.h.spline;
  M.log_a_spline = main.log_a.spline;
  // the log a curve stays within the range the bins identified (docs/fit.md "Low phi")
  M.log_a_min = HUGE_VAL;
  M.log_a_max = -HUGE_VAL;
  for (const BinEstimate& b : bins)
    if (b.used) M.log_a_min = std::min(M.log_a_min, b.log_a), M.log_a_max = std::max(M.log_a_max, b.log_a);
  M.c_corr_a = Radl2014Curves::kCcorrA;
  M.c_corr_k = Radl2014Curves::kCcorrK;
  M.c_corr_source = "paper";

}

/// The bands' grid (121 phi from 0 to phi_max, the data's widths) and the fitted h, a and H on it.
void fill_band(FitResult& R, const std::set<double>& widths, const FitOptions& o, double n, double phi_max) {
  const DragModel& M = R.model;
  const int n_phi = 121;
  for (int i = 0; i < n_phi; ++i) R.band_phi.push_back(phi_max * i / (n_phi - 1.0));
  R.band_F.assign(widths.begin(), widths.end());
  const SplineCurves curves{&M};
  for (double phi : R.band_phi) {
    R.h.push_back(curves.h(phi));
    R.a.push_back(curves.a(phi));
    if (phi >= o.phi_crit) {
      const double raw = M.h_spline(phi);
      if (raw < 0.0 || raw > o.h_max) ++R.h_clamped;
    }
  }
  std::vector<double> band_Fn;  // F^n of the data's widths
  for (double F : R.band_F) band_Fn.push_back(std::pow(F, n));
  for (double Fn : band_Fn)
    for (std::size_t i = 0; i < R.band_phi.size(); ++i) R.H.push_back(R.h[i] / (1.0 + R.a[i] * Fn));

}

/// Step 3: the bootstrap of the curves (snapshot blocks, or normal intervals for files without per-snapshot
/// sums; o.bootstrap replicates), the percentile bands widened by the main fit's smoothing-bias allowance,
/// and the bins' bootstrap standard errors. Without replicates the bands are NaN.
void bootstrap_bands(const std::vector<FilteredFile>& files, const FitOptions& o, double n, double phi_max,
                     const std::vector<Series>& series, const Curves& main, FitResult& R) {
  const DragModel& M = R.model;
  std::vector<double> band_Fn;  // F^n of the data's widths
  for (double F : R.band_F) band_Fn.push_back(std::pow(F, n));
  const std::size_t nphi = R.band_phi.size(), nF = R.band_F.size();
  R.h_low = R.h_high = R.a_low = R.a_high = std::vector<double>(nphi, kNaN);
  R.H_low = R.H_high = std::vector<double>(nphi * nF, kNaN);
  const bool blocks =
      std::all_of(files.begin(), files.end(), [](const FilteredFile& f) { return f.has_per_snapshot; });
  R.resampling = blocks ? "snapshot blocks" : "normal intervals";
  if (o.bootstrap > 0) {
    std::unique_ptr<gsl_rng, decltype(&gsl_rng_free)> rng(gsl_rng_alloc(gsl_rng_mt19937), &gsl_rng_free);
    gsl_rng_set(rng.get(), o.seed);
    // per file, per run, its blocks (each the snapshot rows it holds); blocks never straddle runs
    std::vector<std::vector<std::vector<std::vector<std::size_t>>>> blocks_of(files.size());
    for (std::size_t f = 0; f < files.size(); ++f) {
      std::map<std::int64_t, std::map<std::int64_t, std::vector<std::size_t>>> tree;
      for (std::size_t k = 0; k < files[f].snapshots(); ++k)
        tree[files[f].snapshot_run[k]][files[f].snapshot_block[k]].push_back(k);
      for (auto& [run, bl] : tree) {
        (void)run;
        blocks_of[f].push_back({});
        for (auto& [id, rows] : bl) (void)id, blocks_of[f].back().push_back(rows);
      }
    }
    std::vector<std::vector<double>> rep_h(nphi), rep_a(nphi), rep_H(nphi * nF);
    std::vector<std::vector<double>> bin_h(R.bins.size()), bin_log_a(R.bins.size());
    DragModel replica = M;
    const SplineCurves replica_curves{&replica};
    for (int r = 0; r < o.bootstrap; ++r) {
      std::vector<Series> rs;
      if (blocks) {
        Weights wts(files.size());
        for (std::size_t f = 0; f < files.size(); ++f) {
          wts[f].assign(files[f].snapshots(), 0.0);
          for (const auto& run : blocks_of[f])
            for (std::size_t j = 0; j < run.size(); ++j) {
              const auto& pick = run[gsl_rng_uniform_int(rng.get(), run.size())];
              for (std::size_t k : pick) wts[f][k] += 1.0;
            }
        }
        rs = observe(files, &wts, o.min_width_over_cell, n);
        // keep the data's intervals (not rescaled by the resampled snapshot count: it is n on average)
        for (std::size_t i = 0; i < rs.size(); ++i) rs[i].sigma = series[i].sigma;
      } else {
        rs = series;
        for (Series& s : rs)
          for (std::size_t b = 0; b < s.H.size(); ++b)
            if (std::isfinite(s.sigma[b])) s.H[b] += gsl_ran_gaussian(rng.get(), s.sigma[b]);
      }
      std::vector<BinEstimate> rb = fit_bins(files, rs, o);
      // the replicate uses the bins the main fit used (a bin the replicate cannot fit is left out)
      int replica_bins = 0;
      for (std::size_t b = 0; b < rb.size(); ++b) replica_bins += rb[b].used = rb[b].used && R.bins[b].used;
      for (std::size_t b = 0; b < rb.size(); ++b)
        if (rb[b].used) bin_h[b].push_back(rb[b].h), bin_log_a[b].push_back(rb[b].log_a);
      if (replica_bins < 4) {  // too few bins to fit (rare: a resample that empties bins); not counted
        ++R.replicates_skipped;
        continue;
      }
      const Curves c = fit_curves(rb, o.phi_crit, phi_max, R.breakpoints, R.lambda_h, R.lambda_log_a);
      replica.h_spline = c.h.spline;
      replica.log_a_spline = c.log_a.spline;
      for (std::size_t i = 0; i < nphi; ++i) {
        const double h = replica_curves.h(R.band_phi[i]), a = replica_curves.a(R.band_phi[i]);
        rep_h[i].push_back(h);
        rep_a[i].push_back(a);
        for (std::size_t j = 0; j < nF; ++j) rep_H[j * nphi + i].push_back(h / (1.0 + a * band_Fn[j]));
      }
    }
    if (rep_h.front().empty()) throw RunError("bootstrap: every replicate lost too many bins to fit");
    auto sd = [](const std::vector<double>& v) {
      if (v.size() < 2) return kNaN;
      const double mean = std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
      double ss = 0;
      for (double x : v) ss += (x - mean) * (x - mean);
      return std::sqrt(ss / static_cast<double>(v.size() - 1));
    };
    for (std::size_t b = 0; b < R.bins.size(); ++b) {
      R.bins[b].boot_se_h = sd(bin_h[b]);
      R.bins[b].boot_se_log_a = sd(bin_log_a[b]);
    }
    for (std::size_t i = 0; i < nphi; ++i) {
      R.h_low[i] = quantile(rep_h[i], 0.025);
      R.h_high[i] = quantile(rep_h[i], 0.975);
      R.a_low[i] = quantile(rep_a[i], 0.025);
      R.a_high[i] = quantile(rep_a[i], 0.975);
    }
    for (std::size_t k = 0; k < nphi * nF; ++k) {
      R.H_low[k] = quantile(rep_H[k], 0.025);
      R.H_high[k] = quantile(rep_H[k], 0.975);
    }
    R.replicates = o.bootstrap - R.replicates_skipped;
    // Widen the percentile bands by the smoothing-bias allowance of the main fit (SplineFit::bias_cov),
    // added in quadrature to each side, in the fitted variables (h; log a); below phi_crit h's
    // allowance scales like h (phi/phi_crit), a's is constant.
    auto widen = [](double est, double& lo, double& hi, double var) {
      lo = est - std::sqrt((est - lo) * (est - lo) + kZ95 * kZ95 * var);
      hi = est + std::sqrt((hi - est) * (hi - est) + kZ95 * kZ95 * var);
    };
    for (std::size_t i = 0; i < nphi; ++i) {
      const double phi = R.band_phi[i], at = std::clamp(phi, o.phi_crit, phi_max);
      const double f = phi < o.phi_crit ? phi / o.phi_crit : 1.0;
      const double vh = f * f * spline_variance(M.h_spline, main.h.bias_cov, at);
      const double va = spline_variance(M.log_a_spline, main.log_a.bias_cov, at);
      widen(R.h[i], R.h_low[i], R.h_high[i], vh);
      R.h_low[i] = std::max(R.h_low[i], 0.0);
      R.h_high[i] = std::min(R.h_high[i], o.h_max);
      double log_lo = std::log(R.a_low[i]), log_hi = std::log(R.a_high[i]);
      widen(std::log(R.a[i]), log_lo, log_hi, va);
      R.a_low[i] = std::exp(std::max(log_lo, kLogAMin));  // the per-bin bounds of a
      R.a_high[i] = std::exp(std::min(log_hi, kLogAMax));
      for (std::size_t j = 0; j < nF; ++j) {
        const double g = 1.0 / (1.0 + R.a[i] * band_Fn[j]);
        const double dH_dlog_a = -R.h[i] * R.a[i] * band_Fn[j] * g * g;
        const std::size_t k = j * nphi + i;
        widen(R.H[k], R.H_low[k], R.H_high[k], g * g * vh + dH_dlog_a * dH_dlog_a * va);
      }
    }
  }

}

/// The data as fitted (per series: F, fitted or not, H and its sigma per bin) for the report.
void record_data(const std::vector<FilteredFile>& files, const std::vector<Series>& series, FitResult& R) {
  for (const Series& s : series) {
    R.data_series.push_back(files[s.file].path + ":" + files[s.file].widths[s.width].group);
    R.data_F.push_back(s.F);
    R.data_fitted.push_back(s.fitted ? 1 : 0);
    R.data_H.insert(R.data_H.end(), s.H.begin(), s.H.end());
    R.data_sigma.insert(R.data_sigma.end(), s.sigma.begin(), s.sigma.end());
  }
  for (const BinEstimate& b : R.bins) R.data_phi.push_back(b.phi);

}

/// Step 4: residuals per width against the per-bin fits (fitted widths) or the smoothed model (the
/// others, whole box included, as a check).
void width_residuals(const std::vector<FilteredFile>& files, const FitOptions& o, const std::vector<Series>& series,
                     FitResult& R) {
  const SplineCurves curves{&R.model};
  for (const Series& s : series) {
    WidthResiduals wr;
    wr.file = files[s.file].path;
    wr.group = files[s.file].widths[s.width].group;
    wr.F = s.F;
    wr.whole_box = s.whole_box;
    wr.fitted = s.fitted;
    double sum = 0, sum_z = 0, sum_z2 = 0, sum_s = 0;
    for (std::size_t b = 0; b < s.H.size(); ++b) {
      const BinEstimate& e = R.bins[b];
      const bool ok = !s.fitted ? (s.count[b] >= static_cast<double>(o.min_count) && std::isfinite(s.H[b]) &&
                                   std::isfinite(s.sigma[b]) && s.sigma[b] > 0 && e.phi >= o.phi_crit)
                                : (e.used && usable(s, b, static_cast<double>(o.min_count)));
      if (!ok) continue;
      const double smooth = curves.h(e.phi) / (1.0 + curves.a(e.phi) * s.Fn);
      const double model = !s.fitted ? smooth : e.h / (1.0 + std::exp(e.log_a) * s.Fn);
      const double r = s.H[b] - model;
      sum += r;
      sum_z += r / s.sigma[b];
      sum_z2 += (r / s.sigma[b]) * (r / s.sigma[b]);
      sum_s += s.H[b] - smooth;
      ++wr.points;
    }
    if (wr.points > 0) {
      wr.mean = sum / wr.points;
      wr.mean_z = sum_z / wr.points;
      wr.rms_z = std::sqrt(sum_z2 / wr.points);
      wr.mean_smoothed = sum_s / wr.points;
    }
    R.residuals.push_back(wr);
  }

}

/// Step 4: leave-one-run-out cross-validation (with o.cross_validate and at least two runs): each run's
/// points against curves fitted without it, and the in-sample rms of the same points.
void cross_validate(const std::vector<FilteredFile>& files, const FitOptions& o, double n, double phi_max,
                    const std::vector<Series>& series, FitResult& R) {
  const DragModel& M = R.model;
  const SplineCurves curves{&M};
  std::vector<std::pair<std::size_t, std::int64_t>> runs;
  for (std::size_t f = 0; f < files.size(); ++f) {
    if (files[f].has_per_snapshot) {
      std::set<std::int64_t> present(files[f].snapshot_run.begin(), files[f].snapshot_run.end());
      for (std::int64_t r : present) runs.push_back({f, r});
    } else if (files[f].runs() <= 1) {
      runs.push_back({f, -1});  // the whole file is one run
    }
  }
  if (o.cross_validate && runs.size() >= 2) {
    double sq = 0, sq_in = 0;
    int total = 0;
    for (const auto& [f, run] : runs) {
      Weights train(files.size()), test(files.size());
      for (std::size_t g = 0; g < files.size(); ++g) {
        if (!files[g].has_per_snapshot) continue;
        train[g].assign(files[g].snapshots(), 1.0);
        test[g].assign(files[g].snapshots(), 0.0);
      }
      if (run >= 0) {
        for (std::size_t k = 0; k < files[f].snapshots(); ++k)
          if (files[f].snapshot_run[k] == run) train[f][k] = 0.0, test[f][k] = 1.0;
      }
      std::vector<Series> tr = observe(files, &train, o.min_width_over_cell, n);
      if (run < 0)  // file without per-snapshot sums: leave the whole file out
        tr.erase(std::remove_if(tr.begin(), tr.end(), [&](const Series& s) { return s.file == f; }),
                 tr.end());
      CrossValidationRun cv;
      cv.file = files[f].path;
      cv.run = run;
      if (run >= 0 && static_cast<std::size_t>(run) < files[f].run_paths.size())
        cv.run_path = files[f].run_paths[static_cast<std::size_t>(run)];
      std::vector<BinEstimate> tb = fit_bins(files, tr, o);
      int n_used = 0;
      for (const BinEstimate& b : tb) n_used += b.used;
      if (n_used < 4) {
        R.cv_runs.push_back(cv);
        continue;
      }
      const Curves c = fit_curves(tb, o.phi_crit, phi_max, R.breakpoints, -1, -1);
      DragModel held = M;
      held.h_spline = c.h.spline;
      held.log_a_spline = c.log_a.spline;
      const SplineCurves hc{&held};
      std::vector<Series> te;
      if (run < 0) {
        for (const Series& s : series)
          if (s.file == f) te.push_back(s);
      } else {
        Weights only(files.size());
        only[f] = test[f];
        for (std::size_t g = 0; g < files.size(); ++g)
          if (g != f) only[g].assign(files[g].snapshots(), 0.0);
        te = observe(files, &only, o.min_width_over_cell, n);
      }
      double s2 = 0, s1 = 0;
      for (const Series& s : te) {
        if (!s.fitted) continue;
        for (std::size_t b = 0; b < s.H.size(); ++b) {
          const BinEstimate& e = R.bins[b];
          if (!e.used || !(s.count[b] >= static_cast<double>(o.min_count)) || !std::isfinite(s.H[b]))
            continue;
          const double r = s.H[b] - hc.h(e.phi) / (1.0 + hc.a(e.phi) * s.Fn);
          const double r_in = s.H[b] - curves.h(e.phi) / (1.0 + curves.a(e.phi) * s.Fn);
          s1 += r;
          s2 += r * r;
          sq_in += r_in * r_in;
          ++cv.points;
        }
      }
      if (cv.points > 0) cv.rms = std::sqrt(s2 / cv.points), cv.mean = s1 / cv.points;
      sq += s2;
      total += cv.points;
      R.cv_runs.push_back(cv);
    }
    if (total > 0) R.cv_rms = std::sqrt(sq / total), R.cv_in_sample_rms = std::sqrt(sq_in / total);
  }
}

}  // namespace

/// Steps (docs/fit.md): the usable widths, step 0 the width exponent, steps 1-2 the per-bin fits and the
/// P-splines, the model's header and the band grid, step 3 the bootstrap, step 4 residuals and
/// cross-validation; each step is a function above.
FitResult fit_filtered_drag(const std::vector<FilteredFile>& files, const FitOptions& o, std::ostream* log) {
  const auto start = std::chrono::steady_clock::now();
  if (files.empty()) throw InputError("cgd-fit: no filtered files given");
  FitResult R;
  const std::set<double> widths = usable_widths(files, o);
  // ---- step 0: the width exponent n (given, or the minimum of the pooled chi^2 of the bin fits)
  const double n = o.fit_width_exponent ? fit_width_exponent(files, o, R) : o.width_exponent;
  R.width_exponent = n;
  if (log && o.fit_width_exponent)
    *log << "cgd-fit: width exponent n = " << n << " [" << R.width_exponent_low << ", " << R.width_exponent_high
         << "] (profile of the pooled chi^2 over " << R.exponent_grid.size() << " values)\n";

  // ---- steps 1 and 2 on the data as filtered
  const std::vector<Series> series = observe(files, nullptr, o.min_width_over_cell, n);
  R.bins = fit_bins(files, series, o);
  int used = 0;
  double phi_max = o.phi_crit;
  for (const BinEstimate& b : R.bins)
    if (b.used) ++used, phi_max = std::max(phi_max, b.phi);
  if (used < 4)
    throw InputError(file_list(files) + ": too few phi bins to fit: " + std::to_string(used) + " of " +
                     std::to_string(R.bins.size()) + " bins have >= " + std::to_string(o.min_count) +
                     " samples at >= " + std::to_string(o.min_widths) +
                     " widths above phi_crit = " + std::to_string(o.phi_crit) +
                     "; at least 4 needed (lower --min-count or filter longer runs)");
  R.breakpoints = o.breakpoints > 0 ? o.breakpoints : std::clamp(used / 2 + 2, 5, 15);
  const Curves main = fit_curves(R.bins, o.phi_crit, phi_max, R.breakpoints, -1, -1);
  R.lambda_h = main.h.lambda;
  R.lambda_log_a = main.log_a.lambda;
  R.edf_h = main.h.edf;
  R.edf_log_a = main.log_a.edf;
  {
    double chi2 = 0;
    int dof = 0;
    for (const BinEstimate& b : R.bins)
      if (b.used) chi2 += b.chi2, dof += b.widths - 2;
    R.chi2_per_dof = dof > 0 ? chi2 / dof : kNaN;
  }

  fill_model(R.model, R.bins, files.front().physics, o, n, main);
  fill_band(R, widths, o, n, phi_max);
  bootstrap_bands(files, o, n, phi_max, series, main, R);
  record_data(files, series, R);
  width_residuals(files, o, series, R);
  cross_validate(files, o, n, phi_max, series, R);
  R.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (log) *log << "cgd-fit: fitted in " << R.wall_seconds << " s\n";
  return R;
}

}  // namespace cgd::fit
