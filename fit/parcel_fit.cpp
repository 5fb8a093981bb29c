#include "fit/parcel_fit.hpp"

#include <gsl/gsl_cdf.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_min.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <random>
#include <set>
#include <sstream>

#include "core/error.hpp"
#include "core/schema/coarse_summary.hpp"
#include "core/schema/drag_model.hpp"

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

constexpr double kMaxK = 5;  // exp(-5) at alpha = 2: the correction complete by then

/// k minimising chi2 at fixed a, on [lo, kMaxK] (GSL Brent after a coarse scan for the bracket).
double best_k(const std::vector<double>& alpha, const std::vector<double>& c, const std::vector<double>& sigma, double a,
              double lo) {
  const double hi = kMaxK;
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
                                   const std::vector<double>& sigma, double k_lo) {
  double ba = 0, bk = 0, bf = 1e300;
  for (int i = 0; i <= 19; ++i) {
    const double a = i * 0.05, k = best_k(alpha, c, sigma, a, k_lo), f = chi2(alpha, c, sigma, a, k);
    if (f < bf) bf = f, ba = a, bk = k;
  }
  for (int i = -4; i <= 4; ++i) {  // refine around the best grid point
    const double a = std::clamp(ba + i * 0.0125, 0.0, 0.95), k = best_k(alpha, c, sigma, a, k_lo),
                 f = chi2(alpha, c, sigma, a, k);
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
  const schema::CoarseSummary s = schema::read_coarse_summary(path);
  if (s.drag != "model" && s.drag != "model-raw")
    throw InputError(path + ": the run used drag '" + s.drag +
                     "'; the parcel fit needs runs with the grid model (drag = \"model\")");
  // alpha = 1 runs are the same with c_corr on or off (c_corr(1) = 1)
  const bool primary = std::abs(s.parcel_size - 1.0) < 1e-12;
  if (!primary && s.parcel_correction.value_or(true))
    throw InputError(path + ": the run applied c_corr; the parcel fit needs runs with fluid.parcel_correction = false");
  if (!s.reference)
    throw InputError(path + ": the run has no reference (run cgd-coarse with --reference RESOLVED_RUN)");
  // the fit weighs each run by its errors
  if (!(s.slip_stderr > 0) || !(s.reference->slip_stderr > 0) || !(s.solids_fraction > 0))
    throw InputError(path + ": slip_stderr = " + std::to_string(s.slip_stderr) + ", reference_slip_stderr = " +
                     std::to_string(s.reference->slip_stderr) + ", /params solids_fraction = " +
                     std::to_string(s.solids_fraction) + ": the parcel fit needs all three positive");
  ParcelRun r;
  r.run_dir = run_dir;
  r.solids_fraction = s.solids_fraction;
  r.parcel_size = s.parcel_size;
  r.slip_m_s = s.slip_over_ut * u_t;
  r.slip_se_m_s = s.slip_stderr * u_t;
  r.reference_m_s = s.reference->slip_over_ut * u_t;
  r.reference_se_m_s = s.reference->slip_stderr * u_t;
  r.seed = static_cast<int>(s.seed);
  return r;
}

ParcelFitResult fit_parcel_correction(std::vector<ParcelRun> runs, DragLaw base, const DragParams& params,
                                      int replicates, unsigned seed) {
  if (runs.empty()) throw InputError("parcel fit: no coarse runs given");
  auto is_one = [](double alpha) { return std::abs(alpha - 1) < 1e-12; };
  auto same = [](double x, double y) { return std::abs(x - y) <= 1e-9 * std::max(std::abs(x), std::abs(y)); };
  ParcelFitResult R;
  // g = beta_m(phi, s) s of every run (and of its reference, for the un-normalised factor in the report)
  std::vector<double> g(runs.size()), g_se(runs.size());
  visit_drag_law(base, params, [&](const auto& law) {
    for (std::size_t i = 0; i < runs.size(); ++i) {
      ParcelRun& r = runs[i];
      const double phi = r.solids_fraction;
      g[i] = law.beta_p(phi, r.slip_m_s) * r.slip_m_s;
      // the error of g from the slip's: a central difference (d ln(beta s)/d ln s > 1 once beta grows with Re_p)
      const double sp = r.slip_m_s + r.slip_se_m_s, sm = std::max(r.slip_m_s - r.slip_se_m_s, 0.0);
      g_se[i] = std::abs(law.beta_p(phi, sp) * sp - law.beta_p(phi, sm) * sm) * r.slip_se_m_s / (sp - sm);
      r.factor = g[i] / (law.beta_p(phi, r.reference_m_s) * r.reference_m_s);
      r.factor_se = r.factor * std::hypot(r.slip_se_m_s / r.slip_m_s, r.reference_se_m_s / r.reference_m_s);
    }
  });
  // groups: the realisations of one (phi, alpha), pooled into the mean of g with the larger of the
  // between-realisation standard error and the batch-means one
  struct Group { double phi, alpha; std::vector<std::size_t> members; double mean = 0, se = 0; int one = -1; };
  std::vector<Group> groups;
  std::vector<std::size_t> group_of(runs.size());
  for (std::size_t i = 0; i < runs.size(); ++i) {
    std::size_t j = 0;
    while (j < groups.size() && !(same(groups[j].phi, runs[i].solids_fraction) && same(groups[j].alpha, runs[i].parcel_size))) ++j;
    if (j == groups.size()) groups.push_back({runs[i].solids_fraction, runs[i].parcel_size, {}});
    groups[j].members.push_back(i);
    group_of[i] = j;
  }
  for (Group& G : groups) {
    const double n = static_cast<double>(G.members.size());
    double sum = 0, var_within = 0;
    for (std::size_t i : G.members) sum += g[i], var_within += g_se[i] * g_se[i];
    G.mean = sum / n;
    double ss = 0;
    for (std::size_t i : G.members) ss += (g[i] - G.mean) * (g[i] - G.mean);
    const double se_between = G.members.size() > 1 ? std::sqrt(ss / (n - 1) / n) : 0.0;
    G.se = std::max(se_between, std::sqrt(var_within) / n);
  }
  // every phi with parcels needs its alpha = 1 runs (c_corr(1) = 1): un-normalised factors would mix what the
  // grid model misses with what the parcels do
  for (Group& G : groups) {
    if (is_one(G.alpha)) continue;
    for (std::size_t j = 0; j < groups.size(); ++j)
      if (is_one(groups[j].alpha) && same(groups[j].phi, G.phi)) G.one = static_cast<int>(j);
    if (G.one < 0) {
      std::ostringstream o;
      o << "parcel fit: <phi> = " << G.phi << " has runs with alpha = " << G.alpha
        << " but no alpha = 1 run: its factors cannot be normalised by c(1) (they would mix what the grid model "
           "misses with what the parcels do); add an alpha = 1 model run of that <phi> or leave its runs out";
      throw InputError(o.str());
    }
  }
  R.normalised_by_alpha1 = true;
  std::vector<double> alpha, c, sigma;
  std::vector<std::size_t> fit_groups;
  double alpha_max = 1;
  for (std::size_t j = 0; j < groups.size(); ++j) {
    const Group& G = groups[j];
    if (is_one(G.alpha)) continue;
    const Group& one = groups[static_cast<std::size_t>(G.one)];
    ParcelPoint p;
    p.solids_fraction = G.phi;
    p.parcel_size = G.alpha;
    p.realisations = static_cast<int>(G.members.size());
    p.factor = G.mean / one.mean;
    p.factor_se = std::abs(p.factor) * std::hypot(G.se / G.mean, one.se / one.mean);
    R.points.push_back(p);
    alpha.push_back(G.alpha);
    c.push_back(p.factor);
    sigma.push_back(std::max(p.factor_se, 1e-3));
    fit_groups.push_back(j);
    alpha_max = std::max(alpha_max, G.alpha);
  }
  if (alpha.empty()) throw InputError("parcel fit: no run with a parcel size above 1 (give runs at several alpha)");
  // the runs as given, each factor normalised by the mean of its phi's alpha = 1 runs
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const Group& G = groups[group_of[i]];
    const double one_mean = is_one(G.alpha) ? G.mean : groups[static_cast<std::size_t>(G.one)].mean;
    runs[i].factor = g[i] / one_mean;
    runs[i].factor_se = runs[i].factor * g_se[i] / g[i];
  }
  R.runs = runs;
  R.k_lower_bound = -std::log(ParcelFitResult::kMaxCcorr) / (alpha_max - 1);
  const double k_lo = R.k_lower_bound;
  R.k = best_k(alpha, c, sigma, 0.0, k_lo);
  R.dof = static_cast<int>(alpha.size()) - 1;
  double chi2_value = chi2(alpha, c, sigma, 0.0, R.k);
  std::mt19937 rng(seed);
  std::vector<double> ks, as, ks2;
  std::set<double> distinct(alpha.begin(), alpha.end());
  const bool try_a = distinct.size() >= 3;
  std::vector<double> gb(groups.size()), cb(alpha.size());
  for (int b = 0; b < replicates; ++b) {
    // perturb every group's mean (the alpha = 1 groups too: their error is shared by every alpha of their phi)
    for (std::size_t j = 0; j < groups.size(); ++j) gb[j] = std::normal_distribution<double>(groups[j].mean, groups[j].se)(rng);
    for (std::size_t m = 0; m < fit_groups.size(); ++m) {
      const Group& G = groups[fit_groups[m]];
      cb[m] = gb[fit_groups[m]] / gb[static_cast<std::size_t>(G.one)];
    }
    ks.push_back(best_k(alpha, cb, sigma, 0.0, k_lo));
    if (try_a && b < 200) {
      const auto [a2, k2] = best_a_k(alpha, cb, sigma, k_lo);
      as.push_back(a2);
      ks2.push_back(k2);
    }
  }
  R.k_low = quantile(ks, 0.025);
  R.k_high = quantile(ks, 0.975);
  if (try_a) {
    const auto [a2, k2] = best_a_k(alpha, c, sigma, k_lo);
    const double a_low = quantile(as, 0.025);
    if (a_low > 0.0) {  // the data tell a from 0
      R.a_fitted = true;
      R.a = a2;
      R.k = k2;
      R.a_low = a_low;
      R.a_high = quantile(as, 0.975);
      R.k_low = quantile(ks2, 0.025);
      R.k_high = quantile(ks2, 0.975);
      R.dof = static_cast<int>(alpha.size()) - 2;
      chi2_value = chi2(alpha, c, sigma, R.a, R.k);
    } else {
      R.a_high = quantile(as, 0.975);
    }
  }
  R.chi2_per_dof = R.dof > 0 ? chi2_value / R.dof : 0.0;
  R.p_value = R.dof > 0 ? gsl_cdf_chisq_Q(chi2_value, R.dof) : 1.0;
  R.rejected = R.p_value < ParcelFitResult::kRejectP;
  const double tol = 1e-6 * (kMaxK - k_lo);
  R.k_at_bound = R.k <= k_lo + tol || R.k >= kMaxK - tol;
  const bool resolved = R.a_fitted ? true : (R.k_low > 0 || R.k_high < 0);
  std::ostringstream why;
  why.precision(3);
  if (R.rejected) {
    why << "not applied: the form a + (1 - a) exp(-k (alpha - 1)) is rejected (chi2/dof = " << R.chi2_per_dof << ", dof "
        << R.dof << ", p = " << R.p_value << " < " << ParcelFitResult::kRejectP << "); c_corr = 1 written";
  } else if (!resolved) {
    why << "not applied: k's 95 % interval [" << R.k_low << ", " << R.k_high
        << "] holds 0 (no parcel correction the data can resolve); c_corr = 1 written";
  } else {
    R.applied = true;
    why << "applied: k's 95 % interval excludes 0 and the form is not rejected (p = " << R.p_value << ")";
    if (R.k_at_bound) why << "; k sits on a bound of its range [" << k_lo << ", " << kMaxK << "]";
  }
  R.decision = why.str();
  return R;
}

void write_parcel_fit(const std::string& model_path, const std::string& output_path, const ParcelFitResult& r) {
  schema::DragModelFile::CCorr c;
  // the c_corr the model applies: the fitted one, or 1 at every alpha (a = 0, k = 0) when not applied
  c.a = r.applied ? r.a : 0.0;
  c.k = r.applied ? r.k : 0.0;
  c.source = "parcel-fit";
  c.fitted = true;
  schema::DragModelFile::CCorr::ParcelFit p;
  p.a_fit = r.a, p.k_fit = r.k, p.p_value = r.p_value, p.k_lower_bound = r.k_lower_bound;
  p.chi2_per_dof = r.chi2_per_dof, p.dof = r.dof;
  p.applied = r.applied, p.rejected = r.rejected, p.a_fitted = r.a_fitted;
  p.decision = r.decision;
  p.method =
      "c needed per run = beta_m(phi, s) s / (beta_m(phi, s_ref) s_ref) from coarse runs with "
      "c_corr off, realisations of one (phi, alpha) pooled, normalised by the alpha = 1 runs of the same phi; "
      "weighted least squares with k >= k_lower_bound (c_corr(alpha_max) <= 3); 95 % intervals from "
      "a parametric bootstrap; a kept only when its interval excludes 0; applied only when k's "
      "interval excludes 0 and the chi2 p-value is >= 0.001";
  p.k_interval = {r.k_low, r.k_high};
  p.a_interval = {r.a_fitted ? r.a_low : 0.0, r.a_high};
  for (const ParcelRun& run : r.runs) {
    p.runs.push_back(run.run_dir);
    p.runs_seed.push_back(run.seed);
    p.runs_alpha.push_back(run.parcel_size);
    p.runs_phi.push_back(run.solids_fraction);
    p.runs_factor.push_back(run.factor);
    p.runs_factor_stderr.push_back(run.factor_se);
  }
  c.parcel_fit = std::move(p);
  schema::write_c_corr_copy(model_path, output_path, c);
}

std::string parcel_fit_report(const ParcelFitResult& r) {
  std::ostringstream o;
  o.precision(4);
  o << "parcel fit: c_corr(alpha) = a + (1 - a) exp(-k (alpha - 1)) from " << r.runs.size() << " coarse run(s), "
    << r.points.size() << " point(s) (phi, alpha > 1; realisations pooled; factors normalised by the alpha = 1 runs of each phi)\n";
  o << "   phi  alpha  runs   factor needed      fitted c_corr\n";
  for (const ParcelPoint& p : r.points)
    o << "  " << p.solids_fraction << "   " << p.parcel_size << "   " << p.realisations << "   " << p.factor << " +- "
      << p.factor_se << "   " << c_corr(p.parcel_size, r.a, r.k) << "\n";
  o << "k = " << r.k << " [" << r.k_low << ", " << r.k_high << "] (paper 0.05; range [" << r.k_lower_bound << ", " << kMaxK
    << "]); a = " << r.a;
  if (r.a_fitted) o << " [" << r.a_low << ", " << r.a_high << "]";
  else o << " (held at 0: the data cannot tell it from 0" << (r.a_high > 0 ? ", 95 % upper bound " + std::to_string(r.a_high) : std::string()) << ")";
  o << " (paper 0); chi2/dof = " << r.chi2_per_dof << " (dof " << r.dof << ", p = " << r.p_value << ")\n";
  o << "c_corr " << r.decision << "\n";
  return o.str();
}

}  // namespace cgd::fit
