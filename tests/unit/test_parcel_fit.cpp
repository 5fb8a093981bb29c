// The parcel fit (fit/parcel_fit.hpp) recovers a known c_corr(alpha) from synthetic coarse runs whose
// slips were made to need exactly that drag factor.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "core/drag.hpp"
#include "core/error.hpp"
#include "fit/parcel_fit.hpp"

namespace cgd::fit {
namespace {

/// The slip s with beta(phi, s) s = c beta(phi, s_ref) s_ref (bisection: beta(s) s increases with s).
double slip_needing(double c, double phi, double s_ref, const BeetstraDrag& law) {
  const double target = c * law.beta_p(phi, s_ref) * s_ref;
  double lo = 0, hi = 10 * s_ref;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (law.beta_p(phi, mid) * mid < target ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

/// Runs at phi 0.02, 0.05, 0.10 and alpha 1, 2, 3, 4, 6 whose slips need the factor c(alpha) (times a grid
/// miss of 0.97 common to a phi), with relative noise `noise` drawn per run and quoted as its standard error
/// (`quoted` overrides the quoted error, e.g. a batch-means error smaller than the real scatter), `seeds`
/// realisations per (phi, alpha).
template <class C>
std::vector<ParcelRun> synthetic_c(C c_of_alpha, double noise, unsigned seed, int seeds = 1, double quoted = -1) {
  const BeetstraDrag law(1.3, 1.8e-5, 75e-6);
  std::mt19937 rng(seed);
  std::normal_distribution<double> N(0, 1);
  std::vector<ParcelRun> runs;
  for (double phi : {0.02, 0.05, 0.10}) {
    const double s_ref = 0.2;
    const double grid_miss = 0.97;  // the grid model alone is 3 % off at alpha = 1: the normalisation removes it
    for (double alpha : {1.0, 2.0, 3.0, 4.0, 6.0}) {
      for (int s = 1; s <= seeds; ++s) {
        ParcelRun r;
        r.run_dir = "synthetic";
        r.seed = s;
        r.solids_fraction = phi;
        r.parcel_size = alpha;
        r.reference_m_s = s_ref;
        r.reference_se_m_s = noise * s_ref;
        r.slip_m_s = slip_needing(grid_miss * c_of_alpha(alpha), phi, s_ref, law) * (1 + noise * N(rng));
        r.slip_se_m_s = (quoted >= 0 ? quoted : noise) * r.slip_m_s;
        runs.push_back(r);
      }
    }
  }
  return runs;
}

std::vector<ParcelRun> synthetic(double k_true, double noise, unsigned seed) {
  return synthetic_c([&](double alpha) { return std::exp(-k_true * (alpha - 1)); }, noise, seed);
}

TEST(ParcelFit, RecoversAKnownDecayRateWithinItsInterval) {
  // k = 0.05 (the paper's), slips with 1 % noise: the 95 % interval holds the truth and is a few 0.01
  // wide; without noise k is exact to the minimiser's 1e-6 tolerance.
  const DragParams p{1.3, 1.8e-5, 75e-6};
  const ParcelFitResult exact = fit_parcel_correction(synthetic(0.05, 1e-9, 1), DragLaw::Beetstra, p, 200);
  EXPECT_NEAR(exact.k, 0.05, 1e-5);
  EXPECT_TRUE(exact.normalised_by_alpha1);
  int inside = 0;
  for (unsigned seed = 1; seed <= 10; ++seed) {
    const ParcelFitResult r = fit_parcel_correction(synthetic(0.05, 0.01, seed), DragLaw::Beetstra, p, 300, seed);
    inside += r.k_low <= 0.05 && 0.05 <= r.k_high;
    EXPECT_LT(r.k_high - r.k_low, 0.05);
    EXPECT_FALSE(r.a_fitted);  // a = 0 is the truth: its interval should reach 0
  }
  EXPECT_GE(inside, 8);  // 95 % intervals: 10 of 10 expected, 8 allows two misses (binomial p ~ 0.09)
  EXPECT_TRUE(exact.applied) << exact.decision;
  EXPECT_FALSE(exact.rejected);
}

TEST(ParcelFit, RecoversANegativeDecayRateParcelsNeedingMoreDrag) {
  // c_corr > 1: k = -0.08 (c_corr(6) = 1.49, inside the range: k >= -ln 3 / 5 = -0.22); without noise exact to the
  // minimiser's tolerance, with 1 % noise the 95 % interval holds it in at least 8 of 10 draws and the fit is applied
  const DragParams p{1.3, 1.8e-5, 75e-6};
  const ParcelFitResult exact = fit_parcel_correction(synthetic(-0.08, 1e-9, 1), DragLaw::Beetstra, p, 200);
  EXPECT_NEAR(exact.k, -0.08, 1e-5);
  EXPECT_NEAR(exact.k_lower_bound, -std::log(3.0) / 5, 1e-12);
  EXPECT_FALSE(exact.k_at_bound);
  int inside = 0, applied = 0;
  for (unsigned seed = 1; seed <= 10; ++seed) {
    const ParcelFitResult r = fit_parcel_correction(synthetic(-0.08, 0.01, seed), DragLaw::Beetstra, p, 300, seed);
    inside += r.k_low <= -0.08 && -0.08 <= r.k_high;
    applied += r.applied;
  }
  EXPECT_GE(inside, 8);
  EXPECT_GE(applied, 9);  // |k| / its error ~ 0.08 / 0.01: the interval excludes 0 essentially always
}

TEST(ParcelFit, RefusesAPhiWithoutAnAlphaOneRun) {
  // phi = 0.10 without its alpha = 1 run: the factors cannot be normalised; refused (InputError: exit 2)
  const DragParams p{1.3, 1.8e-5, 75e-6};
  std::vector<ParcelRun> runs = synthetic(0.05, 0.01, 1);
  runs.erase(std::remove_if(runs.begin(), runs.end(),
                            [](const ParcelRun& r) { return r.solids_fraction == 0.10 && r.parcel_size == 1.0; }),
             runs.end());
  try {
    fit_parcel_correction(runs, DragLaw::Beetstra, p, 50);
    FAIL() << "a phi without an alpha = 1 run was fitted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no alpha = 1 run"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("0.1"), std::string::npos) << e.what();
  }
}

TEST(ParcelFit, RejectsAFormTheFactorsDoNotFollow) {
  // non-monotone factors (0.8 at alpha = 2-4, 1.0 at 6) with 1 % errors: no a + (1 - a) exp(-k (alpha - 1)) fits;
  // chi2/dof is large, p far below 1e-3: rejected, c_corr = 1 kept (not applied)
  const DragParams p{1.3, 1.8e-5, 75e-6};
  const ParcelFitResult r = fit_parcel_correction(
      synthetic_c([](double alpha) { return alpha < 5 ? 0.8 : 1.0; }, 0.01, 3), DragLaw::Beetstra, p, 200);
  EXPECT_TRUE(r.rejected) << r.decision;
  EXPECT_LT(r.p_value, 1e-3);
  EXPECT_GT(r.chi2_per_dof, 5);
  EXPECT_FALSE(r.applied);
  EXPECT_NE(r.decision.find("rejected"), std::string::npos) << r.decision;
}

TEST(ParcelFit, LeavesCcorrAtOneWhenTheDataCannotResolveIt) {
  // no parcel effect (c = 1 at every alpha) with 2 % noise: k's interval holds 0 in most draws, and then the fit
  // is not applied (c_corr = 1 written); 95 % intervals: at least 8 of 10 (binomial p of fewer ~ 0.09)
  const DragParams p{1.3, 1.8e-5, 75e-6};
  int holds_zero = 0, not_applied = 0;
  for (unsigned seed = 1; seed <= 10; ++seed) {
    const ParcelFitResult r = fit_parcel_correction(synthetic(0.0, 0.02, seed), DragLaw::Beetstra, p, 300, seed);
    holds_zero += r.k_low <= 0 && 0 <= r.k_high;
    not_applied += !r.applied;
    if (r.k_low <= 0 && 0 <= r.k_high && !r.a_fitted) {
      EXPECT_FALSE(r.applied) << r.decision;
    }
  }
  EXPECT_GE(holds_zero, 8);
  EXPECT_GE(not_applied, 8);
}

TEST(ParcelFit, PoolsRealisationsWithTheirScatter) {
  // three realisations per (phi, alpha) with 5 % scatter between them but a quoted batch-means error of 0.1 %:
  // one point per (phi, alpha) (12 = 3 phi x 4 alpha), each with 3 realisations, and an error from the scatter
  // (the sd/sqrt(3) of 5 %-scattered values, combined over the point and its alpha = 1 normaliser: ~ 0.04),
  // not from the 0.1 % quoted one (~ 0.0014)
  const DragParams p{1.3, 1.8e-5, 75e-6};
  const ParcelFitResult r =
      fit_parcel_correction(synthetic_c([](double) { return 1.0; }, 0.05, 7, 3, 0.001), DragLaw::Beetstra, p, 100);
  ASSERT_EQ(r.points.size(), 12u);
  ASSERT_EQ(r.runs.size(), 45u);
  double mean_se = 0;
  for (const ParcelPoint& q : r.points) {
    EXPECT_EQ(q.realisations, 3);
    mean_se += q.factor_se / 12;
  }
  EXPECT_GT(mean_se, 0.015);  // the scatter's ~0.04, with room for the spread of 3-value sd estimates
  EXPECT_LT(mean_se, 0.1);
}

}  // namespace
}  // namespace cgd::fit
