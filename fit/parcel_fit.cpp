#include "fit/parcel_fit.hpp"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_min.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <random>
#include <sstream>

#include "core/error.hpp"
#include "core/h5.hpp"

namespace cgd::fit {

namespace {

double c_corr(double alpha, double a, double k) { return a + (1 - a) * std::exp(-k * (alpha - 1)); }

double chi2(const std::vector<double>& alpha, const std::vector<double>& c, const std::vector<double>& sigma, double a,
            double k) {
  double s = 0;
  for (std::size_t i = 0; i < c.size(); ++i) {
    const double r = (c[i] - c_corr(alpha[i], a, k)) / sigma[i];
    s += r * r;
  }
  return s;
}

/// k minimising chi2 at fixed a, on [0, 5] (GSL Brent after a coarse scan for the bracket).
double best_k(const std::vector<double>& alpha, const std::vector<double>& c, const std::vector<double>& sigma, double a) {
  const double lo = 0, hi = 5;
  double k0 = lo, f0 = 1e300;
  constexpr int kScan = 100;
  for (int i = 0; i <= kScan; ++i) {
    const double k = lo + (hi - lo) * i / kScan, f = chi2(alpha, c, sigma, a, k);
    if (f < f0) f0 = f, k0 = k;
  }
  if (k0 <= lo || k0 >= hi) return k0;
  struct P { const std::vector<double>*al, *c, *s; double a; } p{&alpha, &c, &sigma, a};
  gsl_function F;
  F.function = [](double k, void* v) {
    auto* q = static_cast<P*>(v);
    return chi2(*q->al, *q->c, *q->s, q->a, k);
  };
  F.params = &p;
  gsl_set_error_handler_off();
  gsl_min_fminimizer* m = gsl_min_fminimizer_alloc(gsl_min_fminimizer_brent);
  const double step = (hi - lo) / kScan;
  if (gsl_min_fminimizer_set(m, &F, k0, std::max(lo, k0 - step), std::min(hi, k0 + step)) != GSL_SUCCESS) {
    gsl_min_fminimizer_free(m);
    return k0;
  }
  for (int it = 0; it < 100; ++it) {
    gsl_min_fminimizer_iterate(m);
    if (gsl_min_test_interval(gsl_min_fminimizer_x_lower(m), gsl_min_fminimizer_x_upper(m), 1e-10, 0) == GSL_SUCCESS) break;
  }
  const double k = gsl_min_fminimizer_x_minimum(m);
  gsl_min_fminimizer_free(m);
  return k;
}

/// (a, k) jointly: a on a grid in [0, 0.95] with the best k for each, refined around the best a.
std::pair<double, double> best_a_k(const std::vector<double>& alpha, const std::vector<double>& c,
                                   const std::vector<double>& sigma) {
  double ba = 0, bk = 0, bf = 1e300;
  for (int i = 0; i <= 19; ++i) {
    const double a = i * 0.05, k = best_k(alpha, c, sigma, a), f = chi2(alpha, c, sigma, a, k);
    if (f < bf) bf = f, ba = a, bk = k;
  }
  for (int i = -4; i <= 4; ++i) {  // refine around the best grid point
    const double a = std::clamp(ba + i * 0.0125, 0.0, 0.95), k = best_k(alpha, c, sigma, a), f = chi2(alpha, c, sigma, a, k);
    if (f < bf) bf = f, ba = a, bk = k;
  }
  return {ba, bk};
}

double quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const auto i = static_cast<std::size_t>(pos);
  const std::size_t j = std::min(i + 1, v.size() - 1);
  return v[i] + (pos - static_cast<double>(i)) * (v[j] - v[i]);
}

}  // namespace

ParcelRun read_parcel_run(const std::string& run_dir, double u_t) {
  const std::string path = (std::filesystem::path(run_dir) / "summary.h5").string();
  h5::File f = h5::File::open_read(path, MPI_COMM_SELF);
  if (!f.has_attr("/", "cgd_format") || f.attr_string("/", "cgd_format") != "coarse_summary")
    throw InputError(path + ": not a cgd-coarse summary (cgd_format 'coarse_summary' expected)");
  const std::string drag = f.attr_string("/", "drag");
  if (drag != "model" && drag != "model-raw")
    throw InputError(path + ": the run used drag '" + f.attr_string("/", "drag") +
                     "'; the parcel fit needs runs with the grid model (drag = \"model\")");
  // alpha = 1 runs are the same with c_corr on or off (c_corr(1) = 1)
  const bool primary = std::abs(f.attr_double("/", "parcel_size") - 1.0) < 1e-12;
  if (!primary && (!f.has_attr("/params", "parcel_correction") || f.attr_int("/params", "parcel_correction") != 0))
    throw InputError(path + ": the run applied c_corr; the parcel fit needs runs with fluid.parcel_correction = false");
  if (!f.has_attr("/", "reference_slip_over_ut"))
    throw InputError(path + ": the run has no reference (run cgd-coarse with --reference RESOLVED_RUN)");
  ParcelRun r;
  r.run_dir = run_dir;
  r.solids_fraction = f.attr_double("/params", "solids_fraction");
  r.parcel_size = f.attr_double("/", "parcel_size");
  r.slip_m_s = f.attr_double("/", "slip_over_ut") * u_t;
  r.slip_se_m_s = f.attr_double("/", "slip_stderr") * u_t;
  r.reference_m_s = f.attr_double("/", "reference_slip_over_ut") * u_t;
  r.reference_se_m_s = f.attr_double("/", "reference_slip_stderr") * u_t;
  return r;
}

ParcelFitResult fit_parcel_correction(std::vector<ParcelRun> runs, DragLaw base, const DragParams& params,
                                      int replicates, unsigned seed) {
  if (runs.empty()) throw InputError("parcel fit: no coarse runs given");
  ParcelFitResult R;
  visit_drag_law(base, params, [&](const auto& law) {
    for (ParcelRun& r : runs) {
      const double phi = r.solids_fraction;
      r.factor = law.beta_p(phi, r.slip_m_s) * r.slip_m_s / (law.beta_p(phi, r.reference_m_s) * r.reference_m_s);
      r.factor_se = r.factor * std::hypot(r.slip_se_m_s / r.slip_m_s, r.reference_se_m_s / r.reference_m_s);
    }
  });
  // normalise by the alpha = 1 run of the same <phi>, where there is one; the fit's points are the runs
  // with alpha > 1. `raw` are the un-normalised factors (perturbed in the bootstrap, so that the alpha = 1
  // run's error, shared by every alpha of its phi, is propagated with its correlation).
  std::vector<int> one_of(runs.size(), -1);
  for (std::size_t i = 0; i < runs.size(); ++i)
    for (std::size_t j = 0; j < runs.size(); ++j)
      if (std::abs(runs[j].parcel_size - 1) < 1e-12 && runs[j].solids_fraction == runs[i].solids_fraction)
        one_of[i] = static_cast<int>(j);
  auto normalised = [&](const std::vector<double>& raw, std::vector<double>& c_out) {
    c_out.clear();
    for (std::size_t i = 0; i < runs.size(); ++i) {
      if (std::abs(runs[i].parcel_size - 1) < 1e-12) continue;  // c(1) = 1 by definition
      c_out.push_back(one_of[i] >= 0 ? raw[i] / raw[static_cast<std::size_t>(one_of[i])] : raw[i]);
    }
  };
  std::vector<double> raw, raw_se;
  for (const ParcelRun& r : runs) {
    raw.push_back(r.factor);
    raw_se.push_back(r.factor_se);
  }
  std::vector<double> alpha, c, sigma;
  std::vector<double> distinct;
  std::vector<ParcelRun> used = runs;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    ParcelRun& r = used[i];
    if (one_of[i] >= 0 && std::abs(r.parcel_size - 1) > 1e-12) {
      const ParcelRun& one = runs[static_cast<std::size_t>(one_of[i])];
      const double rel = std::hypot(r.factor_se / r.factor, one.factor_se / one.factor);
      r.factor /= one.factor;
      r.factor_se = std::abs(r.factor) * rel;
      R.normalised_by_alpha1 = true;
    }
    if (std::abs(r.parcel_size - 1) < 1e-12) continue;
    alpha.push_back(r.parcel_size);
    c.push_back(r.factor);
    sigma.push_back(std::max(r.factor_se, 1e-3));
    if (std::none_of(distinct.begin(), distinct.end(), [&](double x) { return std::abs(x - r.parcel_size) < 1e-12; }))
      distinct.push_back(r.parcel_size);
  }
  R.runs = used;
  if (alpha.empty()) throw InputError("parcel fit: no run with a parcel size above 1 (give runs at several alpha)");
  R.k = best_k(alpha, c, sigma, 0.0);
  const int dof_k = static_cast<int>(alpha.size()) - 1;
  R.chi2_per_dof = dof_k > 0 ? chi2(alpha, c, sigma, 0.0, R.k) / dof_k : 0.0;
  std::mt19937 rng(seed);
  std::vector<double> ks, as, ks2;
  const bool try_a = distinct.size() >= 3;
  std::vector<double> rb(raw.size()), cb;
  for (int b = 0; b < replicates; ++b) {
    for (std::size_t i = 0; i < raw.size(); ++i) rb[i] = std::normal_distribution<double>(raw[i], raw_se[i])(rng);
    normalised(rb, cb);
    ks.push_back(best_k(alpha, cb, sigma, 0.0));
    if (try_a && b < 200) {
      const auto [a2, k2] = best_a_k(alpha, cb, sigma);
      as.push_back(a2);
      ks2.push_back(k2);
    }
  }
  R.k_low = quantile(ks, 0.025);
  R.k_high = quantile(ks, 0.975);
  if (try_a) {
    const auto [a2, k2] = best_a_k(alpha, c, sigma);
    const double a_low = quantile(as, 0.025);
    if (a_low > 0.0) {  // the data tell a from 0
      R.a_fitted = true;
      R.a = a2;
      R.k = k2;
      R.a_low = a_low;
      R.a_high = quantile(as, 0.975);
      R.k_low = quantile(ks2, 0.025);
      R.k_high = quantile(ks2, 0.975);
      R.chi2_per_dof = alpha.size() > 2 ? chi2(alpha, c, sigma, R.a, R.k) / (alpha.size() - 2.0) : 0.0;
    } else {
      R.a_high = quantile(as, 0.975);
    }
  }
  return R;
}

void write_parcel_fit(const std::string& model_path, const std::string& output_path, const ParcelFitResult& r) {
  h5::update_copy_atomically(model_path, output_path, [&](h5::File& f) {
    const std::string g = "/c_corr";
    f.set_attr(g, "a", r.a);
    f.set_attr(g, "k", r.k);
    f.set_attr(g, "source", std::string("parcel-fit"));
    f.set_attr(g, "fitted", std::int64_t{1});
    f.set_attr(g, "k_interval", std::vector<double>{r.k_low, r.k_high});
    f.set_attr(g, "a_interval", std::vector<double>{r.a_fitted ? r.a_low : 0.0, r.a_high});
    f.set_attr(g, "a_fitted", std::int64_t{r.a_fitted ? 1 : 0});
    f.set_attr(g, "chi2_per_dof", r.chi2_per_dof);
    f.set_attr(g, "method",
               std::string("c needed per run = beta_m(phi, s) s / (beta_m(phi, s_ref) s_ref) from coarse runs with "
                           "c_corr off, normalised by the alpha = 1 run of the same phi; weighted least squares; 95 % "
                           "intervals from a parametric bootstrap; a kept only when its interval excludes 0"));
    std::vector<std::string> dirs;
    std::vector<double> alpha, phi, factor, factor_se;
    for (const ParcelRun& p : r.runs) {
      dirs.push_back(p.run_dir);
      alpha.push_back(p.parcel_size);
      phi.push_back(p.solids_fraction);
      factor.push_back(p.factor);
      factor_se.push_back(p.factor_se);
    }
    f.set_attr(g, "runs", dirs);
    f.set_attr(g, "runs_alpha", alpha);
    f.set_attr(g, "runs_phi", phi);
    f.set_attr(g, "runs_factor", factor);
    f.set_attr(g, "runs_factor_stderr", factor_se);
  });
}

std::string parcel_fit_report(const ParcelFitResult& r) {
  std::ostringstream o;
  o.precision(4);
  o << "parcel fit: c_corr(alpha) = a + (1 - a) exp(-k (alpha - 1)) from " << r.runs.size() << " coarse run(s)"
    << (r.normalised_by_alpha1 ? " (factors normalised by the alpha = 1 run of each phi)" : "") << "\n";
  o << "   phi  alpha   slip/ref      factor needed      fitted c_corr\n";
  for (const ParcelRun& p : r.runs) {
    o << "  " << p.solids_fraction << "   " << p.parcel_size << "   " << p.slip_m_s / p.reference_m_s << "   " << p.factor
      << " +- " << p.factor_se << "   " << c_corr(p.parcel_size, r.a, r.k) << "\n";
  }
  o << "k = " << r.k << " [" << r.k_low << ", " << r.k_high << "] (paper 0.05); a = " << r.a;
  if (r.a_fitted) o << " [" << r.a_low << ", " << r.a_high << "]";
  else o << " (held at 0: the data cannot tell it from 0" << (r.a_high > 0 ? ", 95 % upper bound " + std::to_string(r.a_high) : std::string()) << ")";
  o << " (paper 0); chi2/dof = " << r.chi2_per_dof << "\n";
  return o.str();
}

}  // namespace cgd::fit
