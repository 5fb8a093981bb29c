// The fitter (fit/fitter.hpp) recovers known master curves h(phi), a(phi) from synthetic filtered data
// (fit_test_util.hpp: truth + correlated AR(1) noise of a known size), its bands cover the truth at
// about the nominal rate, its error shrinks with the noise, and it refuses inputs it cannot fit.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/filtered_drag.hpp"
#include "fit/filtered_input.hpp"
#include "fit/fitter.hpp"
#include "fit_test_util.hpp"
#include "expect_input_error.hpp"

namespace {

namespace fs = std::filesystem;
using cgd::fit::FitOptions;
using cgd::fit::FitResult;
using cgd::fit::testing::make_synthetic;
using cgd::fit::testing::SyntheticSpec;
using cgd::fit::testing::truth_a;
using cgd::fit::testing::truth_h;

std::vector<double> test_points() {
  std::vector<double> phi;
  for (double p = 0.04; p <= 0.48 + 1e-9; p += 0.02) phi.push_back(p);
  return phi;
}

/// Index of the band grid point nearest to phi (the grid has 121 points on [0, phi_max]: spacing 0.004).
std::size_t nearest(const FitResult& r, double phi) {
  std::size_t best = 0;
  for (std::size_t i = 0; i < r.band_phi.size(); ++i)
    if (std::abs(r.band_phi[i] - phi) < std::abs(r.band_phi[best] - phi)) best = i;
  return best;
}

FitResult fit(const std::vector<cgd::fit::FilteredFile>& files, int bootstrap, bool cv = false) {
  FitOptions o;
  o.bootstrap = bootstrap;
  o.cross_validate = cv;
  return cgd::fit::fit_filtered_drag(files, o, nullptr);
}

// With little noise (sd 0.01 per snapshot: H known to ~1e-3 per bin) the fit must return the truth:
// h within 0.01 and a within 5 % at every test point (smoothing bias of the P-spline at this noise
// level, measured: 0.004 and 2 %); the per-bin estimates too (0.02, 10 %: one bin, 6 widths).
TEST(Fit, RecoversKnownMasterCurves) {
  SyntheticSpec s;
  s.noise = 0.01;
  const FitResult r = fit({make_synthetic(s)}, 0);
  const cgd::SplineCurves c{&r.model};
  double worst_h = 0, worst_a = 0;
  for (double phi : test_points()) {
    worst_h = std::max(worst_h, std::abs(c.h(phi) - truth_h(phi)));
    worst_a = std::max(worst_a, std::abs(c.a(phi) / truth_a(phi) - 1));
  }
  std::printf("[ fit recovery ] noise 0.01: max |h - h_true| %.4f, max |a/a_true - 1| %.4f\n", worst_h,
              worst_a);
  EXPECT_LT(worst_h, 0.01);
  EXPECT_LT(worst_a, 0.05);
  for (const auto& b : r.bins) {
    if (!b.used) continue;
    EXPECT_NEAR(b.h, truth_h(b.phi), 0.02) << "bin " << b.phi;
    EXPECT_NEAR(std::exp(b.log_a) / truth_a(b.phi), 1.0, 0.1) << "bin " << b.phi;
  }
  // phi_crit: h -> 0 linearly below, a continuous (no jump), as the evaluator says
  EXPECT_NEAR(c.h(0.008), 0.5 * c.h(0.016), 1e-15);
  EXPECT_DOUBLE_EQ(c.a(0.0159), c.a(0.016));
  EXPECT_NEAR(c.a(0.016 + 1e-9), c.a(0.016), 1e-6 * c.a(0.016));  // |a'| < 1e3 a: no jump
}

// 95 % bands (bootstrap over snapshot blocks + the splines' smoothing-bias allowance): over 8 seeds x 23
// test points (h and a separately; H(F, phi) at the 6 data widths too) the truth lies inside the band at
// about 95 % (measured: h 0.92, a 0.90, H 0.88). Expected a little below 95 %: blocks of 10 snapshots with
// AR(1) 0.5 noise hold 87 % of the variance of the mean, and 20 blocks give (n-1)/n: the bootstrap sd is
// ~0.91 of the true one, so a nominal 95 % band covers ~92 %. Accepted: 85-99.5 %; a band far too narrow (<
// 85 %) or far too wide
// (> 99.5 %: the truth never leaves it) fails. The points of one seed are correlated, so the binomial
// sd (1.6 % at 184 points) understates the scatter: the window is wide for that reason.
TEST(Fit, BandsCoverTheTruthAtAboutTheNominalRate) {
  int inside_h = 0, inside_a = 0, total = 0, inside_H = 0, total_H = 0;
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    SyntheticSpec s;
    s.seed = seed;
    const FitResult r = fit({make_synthetic(s)}, 200);
    for (double phi : test_points()) {
      const std::size_t i = nearest(r, phi);
      const double p = r.band_phi[i];
      inside_h += r.h_low[i] <= truth_h(p) && truth_h(p) <= r.h_high[i];
      inside_a += r.a_low[i] <= truth_a(p) && truth_a(p) <= r.a_high[i];
      ++total;
      for (std::size_t j = 0; j < r.band_F.size(); ++j) {
        const std::size_t k = j * r.band_phi.size() + i;
        const double H = truth_h(p) / (1 + truth_a(p) * r.band_F[j]);
        inside_H += r.H_low[k] <= H && H <= r.H_high[k];
        ++total_H;
      }
    }
  }
  const double cov_H = double(inside_H) / total_H;
  std::printf("[ fit bands ] coverage of H(F, phi) at the data's widths: %.3f (%d points)\n", cov_H, total_H);
  EXPECT_GE(cov_H, 0.85);
  EXPECT_LE(cov_H, 0.995);
  const double cov_h = double(inside_h) / total, cov_a = double(inside_a) / total;
  std::printf("[ fit bands ] coverage of the truth by the 95 %% bands: h %.3f, a %.3f (%d points)\n", cov_h,
              cov_a, total);
  EXPECT_GE(cov_h, 0.85);
  EXPECT_LE(cov_h, 0.995);
  EXPECT_GE(cov_a, 0.85);
  EXPECT_LE(cov_a, 0.995);
}

// The error shrinks with the noise: noise 0.1 -> 0.025 (4x) must lower the rms error of h and of log a
// over the test points (3 seeds pooled) by more than 2x (ideal 4x; smoothing bias and the GCV choice
// take some of it).
TEST(Fit, ErrorShrinksWithTheNoise) {
  auto rms_error = [](double noise) {
    double eh = 0, ea = 0;
    int n = 0;
    for (std::uint64_t seed = 11; seed <= 13; ++seed) {
      SyntheticSpec s;
      s.noise = noise;
      s.seed = seed;
      const FitResult r = fit({make_synthetic(s)}, 0);
      const cgd::SplineCurves c{&r.model};
      for (double phi : test_points()) {
        eh += std::pow(c.h(phi) - truth_h(phi), 2);
        ea += std::pow(std::log(c.a(phi) / truth_a(phi)), 2);
        ++n;
      }
    }
    return std::pair{std::sqrt(eh / n), std::sqrt(ea / n)};
  };
  const auto [h_big, a_big] = rms_error(0.1);
  const auto [h_small, a_small] = rms_error(0.025);
  std::printf("[ fit noise ] rms error of h: %.4f (noise 0.1) -> %.4f (0.025); of log a: %.4f -> %.4f\n",
              h_big, h_small, a_big, a_small);
  EXPECT_GT(h_big / h_small, 2.0);
  EXPECT_GT(a_big / a_small, 2.0);
}

// Leave-one-run-out: the held-out runs' H are predicted about as well as the noise allows. One run's
// H per (width, bin) has sd ~ noise / sqrt(n_eff) = 0.1 / sqrt(100/3) = 0.017 (AR(1) 0.5: tau = 3); the
// CV rms adds the model's own error: it must be within 0.9..1.6x of that (below: impossible; far above: the
// fit does not generalise), and above the in-sample rms on the same points. The per-width residuals of the
// per-bin fits have mean z near 0 (|.| < 0.5: the form is exact in the synthetic data).
TEST(Fit, CrossValidationAndResiduals) {
  SyntheticSpec s;
  s.runs = 3;
  const FitResult r = fit({make_synthetic(s)}, 0, true);
  ASSERT_EQ(r.cv_runs.size(), 3u);
  const double expected = 0.1 / std::sqrt(s.snapshots / 3.0);
  std::printf("[ fit cv ] LORO rms %.4f (in-sample %.4f, one run's noise %.4f)\n", r.cv_rms,
              r.cv_in_sample_rms, expected);
  EXPECT_GT(r.cv_rms, 0.9 * expected);
  EXPECT_LT(r.cv_rms, 1.6 * expected);
  EXPECT_GT(r.cv_rms, r.cv_in_sample_rms);
  int boxes = 0;
  for (const auto& w : r.residuals) {
    if (w.whole_box) continue;
    ++boxes;
    EXPECT_GT(w.points, 10);
    EXPECT_LT(std::abs(w.mean_z), 0.5) << w.group;
  }
  EXPECT_EQ(boxes, 6);
}

// A width dependence that is not 1/(1 + aF) shows in the residuals per width: data made with
// H = h/(1 + a F)^2 give per-bin fits whose mean residual changes sign between the smallest and the
// largest F (the z means differ by more than 1).
TEST(Fit, ResidualsRevealAWrongWidthDependence) {
  SyntheticSpec s;
  s.noise = 0.02;
  cgd::fit::FilteredFile f = make_synthetic(s);
  for (auto& w : f.widths)
    for (std::size_t b = 0; b < w.H.size(); ++b) {
      const double phi = w.phi_mean[b];
      const double g = 1.0 / (1.0 + truth_a(phi) * w.F);
      const double shift = truth_h(phi) * g * g - truth_h(phi) * g;  // from 1/(1+aF) to 1/(1+aF)^2
      w.H[b] += shift, w.H_low[b] += shift, w.H_high[b] += shift;
      for (std::size_t k = 0; k < f.snapshots(); ++k) {
        const std::size_t i = k * f.bins() + b;
        w.numerator[i] -= shift * w.micro[i];
      }
    }
  const FitResult r = fit({f}, 0);
  double z_small_F = 0, z_large_F = 0;
  for (const auto& w : r.residuals) {
    if (w.group == "/width_0") z_large_F = w.mean_z;  // F = 0.6
    if (w.group == "/width_5") z_small_F = w.mean_z;  // F = 0.1
  }
  std::printf("[ fit residuals ] wrong form: mean z at F = 0.6: %+.2f, at F = 0.1: %+.2f\n", z_large_F,
              z_small_F);
  EXPECT_GT(std::abs(z_large_F - z_small_F), 1.0);
}

/// The synthetic file with its truth moved from h/(1 + aF) to h/(1 + aF^n): H, its interval and the
/// per-snapshot numerators shifted alike (the noise is kept).
cgd::fit::FilteredFile with_width_exponent(const SyntheticSpec& s, double n) {
  cgd::fit::FilteredFile f = make_synthetic(s);
  for (auto& w : f.widths)
    for (std::size_t b = 0; b < w.H.size(); ++b) {
      const double phi = w.phi_mean[b];
      const double shift = truth_h(phi) / (1.0 + truth_a(phi) * std::pow(w.F, n)) -
                           truth_h(phi) / (1.0 + truth_a(phi) * w.F);
      w.H[b] += shift, w.H_low[b] += shift, w.H_high[b] += shift;
      for (std::size_t k = 0; k < f.snapshots(); ++k) w.numerator[k * f.bins() + b] -= shift * w.micro[k * f.bins() + b];
    }
  return f;
}

// --width-exponent fit (step 0) recovers the exponent of data made with H = h/(1 + a F^n): n = 2 and n = 1
// (the paper's form) within 0.1 (measured: 0.02 at this noise; the interval is a few hundredths wide), the
// interval holds the truth, and with n fitted the per-width residuals show no trend (|mean z| < 0.5, as in
// CrossValidationAndResidualsAreHonest); h and a come back as in RecoversKnownMasterCurves, looser
// (0.03, 10 %: n's error feeds into them).
/// A fit of the synthetic data moved to H = h/(1 + a F^n_true) (noise 0.02), no cross-validation.
FitResult fit_exponent_data(double n_true, bool fit_n, int bootstrap) {
  SyntheticSpec s;
  s.noise = 0.02;
  FitOptions o;
  o.bootstrap = bootstrap;
  o.cross_validate = false;
  o.fit_width_exponent = fit_n;
  return cgd::fit::fit_filtered_drag({with_width_exponent(s, n_true)}, o, nullptr);
}

TEST(Fit, FitsTheWidthExponent) {
  for (const double n_true : {2.0, 1.0}) {
    const FitResult r = fit_exponent_data(n_true, true, 0);
    std::printf("[ fit width exponent ] truth %.1f: n = %.3f [%.3f, %.3f], chi2/dof %.2f\n", n_true,
                r.width_exponent, r.width_exponent_low, r.width_exponent_high, r.exponent_chi2_per_dof);
    EXPECT_NEAR(r.width_exponent, n_true, 0.1);
    EXPECT_LE(r.width_exponent_low, n_true);
    EXPECT_GE(r.width_exponent_high, n_true);
    EXPECT_FALSE(r.width_exponent_at_bound);
    EXPECT_DOUBLE_EQ(r.model.width_exponent, r.width_exponent);
    for (const auto& w : r.residuals) {
      if (w.fitted) {
        EXPECT_LT(std::abs(w.mean_z), 0.5) << w.group;
      }
    }
    const cgd::SplineCurves c{&r.model};
    for (double phi : test_points()) {
      EXPECT_NEAR(c.h(phi), truth_h(phi), 0.03) << phi;
      EXPECT_NEAR(c.a(phi) / truth_a(phi), 1.0, 0.1) << phi;
    }
  }
  // with bands: the central H and its band use F^n at the data's widths, and the band holds the truth at
  // most points (conditional on the fitted n, so below the ~90 % that BandsCoverTheTruthAtAboutTheNominalRate
  // measures with n known; measured 85 % here with 50 replicates; at least 80 %)
  {
    const FitResult r = fit_exponent_data(2.0, true, 50);
    const std::size_t nphi = r.band_phi.size();
    int inside = 0, total = 0;
    for (std::size_t j = 0; j < r.band_F.size(); ++j)
      for (std::size_t i = 0; i < nphi; ++i) {
        const std::size_t k = j * nphi + i;
        EXPECT_NEAR(r.H[k], r.h[i] / (1.0 + r.a[i] * std::pow(r.band_F[j], r.width_exponent)), 1e-12);
        EXPECT_LE(r.H_low[k], r.H[k] + 1e-12);
        EXPECT_GE(r.H_high[k], r.H[k] - 1e-12);
        const double phi = r.band_phi[i];
        if (phi < 0.04 || phi > 0.48) continue;
        const double truth = truth_h(phi) / (1.0 + truth_a(phi) * std::pow(r.band_F[j], 2.0));
        inside += r.H_low[k] <= truth && truth <= r.H_high[k];
        ++total;
      }
    std::printf("[ fit width exponent ] bands with n fitted: truth inside at %d of %d points\n", inside, total);
    EXPECT_GE(inside, 0.8 * total);
  }
  // the paper's fixed form on n = 2 data misfits: chi2/dof far above the fitted form's
  const FitResult fixed = fit_exponent_data(2.0, false, 0), fitted = fit_exponent_data(2.0, true, 0);
  EXPECT_GT(fixed.chi2_per_dof, 3 * fitted.chi2_per_dof);
}

using cgd::testing::expect_input_error;

TEST(FitBadInput, TooFewWidthsOrBins) {
  SyntheticSpec two;
  two.F = {0.6, 0.1};
  expect_input_error([&] { fit({make_synthetic(two)}, 0); },
                     {"synthetic_1.h5", "too few filter widths", "2 distinct"});
  SyntheticSpec sparse;
  sparse.count = 1;  // 1 sample per snapshot, 2 x 20 snapshots: 40 per bin and width < min_count = 100
  sparse.snapshots = 20;
  sparse.block = 5;
  expect_input_error([&] { fit({make_synthetic(sparse)}, 0); }, {"too few phi bins", ">= 100 samples"});
}

TEST(FitBadInput, PoolingDifferentPhysicsIsRefused) {
  SyntheticSpec a, b;
  b.micro_drag = cgd::DragLaw::WenYu;
  b.seed = 2;
  expect_input_error(
      [&] {
        cgd::fit::check_same_physics({make_synthetic(a), make_synthetic(b)});
      },
      {"synthetic_2.h5", "synthetic_1.h5", "different physics", "micro_drag"});
  SyntheticSpec c;
  c.diameter_m = 100e-6;
  c.seed = 3;
  expect_input_error(
      [&] {
        cgd::fit::check_same_physics({make_synthetic(a), make_synthetic(c)});
      },
      {"diameter_m"});
  SyntheticSpec d;
  d.bins = 10;
  d.seed = 4;
  expect_input_error(
      [&] {
        cgd::fit::check_same_physics({make_synthetic(a), make_synthetic(d)});
      },
      {"phi_edges"});
}

TEST(FitInput, FilteredFileRoundTripAndRefusals) {
  std::string pattern = (fs::temp_directory_path() / "cgd_fit_XXXXXX").string();
  ASSERT_TRUE(mkdtemp(pattern.data()));
  const fs::path dir = pattern;
  const char* scene =
      "[domain]\nsize_dp = [12, 12, 12]\n[particles]\ndiameter = 75e-6\n[contact]\nstiffness = 0.018\n"
      "[fluid]\ndx_over_dp = 3.33\n[run]\nend_time = 0.01\n";
  SyntheticSpec s;
  const cgd::fit::FilteredFile f = make_synthetic(s);
  const std::string path = (dir / "f.h5").string();
  cgd::fit::testing::write_filtered(path, f, scene);
  const cgd::fit::FilteredFile back = cgd::fit::read_filtered_file(path);
  EXPECT_EQ(back.widths.size(), f.widths.size());
  EXPECT_EQ(back.widths.back().whole_box, true);
  EXPECT_EQ(back.widths[2].numerator, f.widths[2].numerator);
  EXPECT_EQ(back.snapshot_block, f.snapshot_block);
  EXPECT_EQ(back.checksum.size(), 16u);
  // a file that is not "filtered"
  const std::string foreign = (dir / "snap.h5").string();
  cgd::fit::testing::write_filtered(foreign, f, scene, "snapshot");
  expect_input_error([&] { cgd::fit::read_filtered_file(foreign); },
                     {foreign, "cgd_format", "snapshot", "not a filtered file"});
  expect_input_error([&] { cgd::fit::read_filtered_file((dir / "none.h5").string()); }, {"none.h5"});
  fs::remove_all(dir);
}

}  // namespace

namespace {

// Filters narrower than --min-width-over-cell (default 2 cells: a one-cell filter averages nothing below
// the grid) are not fitted, only checked: adding a one-cell width with nonsense H leaves the curves
// exactly as they were, and the width is listed among the residuals as not fitted.
TEST(Fit, NarrowFiltersAreCheckedNotFitted) {
  SyntheticSpec s;
  s.noise = 0.05;
  cgd::fit::FilteredFile f = make_synthetic(s);
  for (auto& w : f.widths) w.width_over_cell = w.whole_box ? NAN : 2.0 * 0.6 / w.F;  // 2 .. 12 cells
  const FitResult without = fit({f}, 0);
  cgd::fit::WidthSeries narrow = f.widths.front();
  narrow.group = "/width_narrow";
  narrow.F = 1.2;
  narrow.width_over_cell = 1.0;
  for (double& H : narrow.H) H = -0.5;
  for (double& n : narrow.numerator) n *= 2.0;
  f.widths.insert(f.widths.begin(), narrow);
  const FitResult with = fit({f}, 0);
  for (double phi : test_points()) {
    EXPECT_DOUBLE_EQ(cgd::SplineCurves{&with.model}.h(phi), cgd::SplineCurves{&without.model}.h(phi));
    EXPECT_DOUBLE_EQ(cgd::SplineCurves{&with.model}.a(phi), cgd::SplineCurves{&without.model}.a(phi));
  }
  ASSERT_EQ(with.residuals.front().group, "/width_narrow");
  EXPECT_FALSE(with.residuals.front().fitted);
  EXPECT_LT(with.residuals.front().mean, -0.5);  // H = -0.5 against a positive model
}

}  // namespace

namespace {

/// Run r of a synthetic file of several runs as a one-run file of its own (its snapshot rows, its blocks numbered from
/// 0, H from its sums, the interval of the whole file's H: not used by pool_runs, which bootstraps the blocks again).
cgd::fit::FilteredFile one_run(const cgd::fit::FilteredFile& f, std::int64_t r) {
  cgd::fit::FilteredFile o = f;
  o.path = f.path + "#run" + std::to_string(r);
  o.run_paths = {f.run_paths[static_cast<std::size_t>(r)]};
  o.snapshot_run.clear(), o.snapshot_block.clear();
  std::vector<std::size_t> rows;
  std::int64_t first_block = -1;
  for (std::size_t k = 0; k < f.snapshots(); ++k)
    if (f.snapshot_run[k] == r) {
      if (first_block < 0) first_block = f.snapshot_block[k];
      // blocks numbered from 0 in each file, as cgd-filter numbers those of a one-run file (data/filtered/)
      rows.push_back(k), o.snapshot_run.push_back(0), o.snapshot_block.push_back(f.snapshot_block[k] - first_block);
    }
  const std::size_t nb = f.bins();
  for (cgd::fit::WidthSeries& w : o.widths) {
    const std::vector<double> num = w.numerator, mic = w.micro;
    const std::vector<std::int64_t> cnt = w.snapshot_count;
    w.numerator.clear(), w.micro.clear(), w.snapshot_count.clear();
    for (std::size_t b = 0; b < nb; ++b) w.count[b] = 0;
    std::vector<double> n(nb, 0.0), m(nb, 0.0);
    for (std::size_t k : rows)
      for (std::size_t b = 0; b < nb; ++b) {
        w.numerator.push_back(num[k * nb + b]), w.micro.push_back(mic[k * nb + b]);
        w.snapshot_count.push_back(cnt[k * nb + b]);
        n[b] += num[k * nb + b], m[b] += mic[k * nb + b], w.count[b] += cnt[k * nb + b];
      }
    for (std::size_t b = 0; b < nb; ++b) w.H[b] = 1.0 - n[b] / m[b];
  }
  return o;
}

// cgd-fit --pool-runs (fit/filtered_input.hpp pool_runs). A synthetic file of four runs (fit_test_util.hpp), split
// into four one-run files (blocks numbered from 0 in each) and pooled again, is the four-run file: H (the ratio of the
// sums) to 1e-12 at every width and bin, the samples, the runs in order with their snapshot rows, each run's blocks
// its own, the files as the sources. The fit of the pooled files is the four-run file's: h within 0.01 and a within
// 5 % at the test points (the intervals, i.e. the weights, differ: bootstrap against the normal approximation). One
// file is returned as it is.
TEST(FitInput, PoolRunsIsTheFileOfAllTheRuns) {
  SyntheticSpec s;
  s.runs = 4;
  s.noise = 0.02;
  const cgd::fit::FilteredFile all = make_synthetic(s);
  std::vector<cgd::fit::FilteredFile> parts;
  for (std::int64_t r = 0; r < 4; ++r) parts.push_back(one_run(all, r));
  const cgd::fit::FilteredFile p = cgd::fit::pool_runs(parts, 7);
  EXPECT_EQ(p.run_paths, all.run_paths);
  EXPECT_EQ(p.snapshot_run, all.snapshot_run);
  ASSERT_EQ(p.snapshot_block.size(), all.snapshot_block.size());
  for (std::size_t k = 0; k < all.snapshots(); ++k)  // 10 blocks per run: the file's blocks 10 r ... 10 r + 9
    EXPECT_EQ(p.snapshot_block[k], all.snapshot_block[k] - 10 * all.snapshot_run[k]) << k;
  ASSERT_EQ(p.pooled_paths.size(), 4u);
  EXPECT_EQ(p.pooled_paths[3], parts[3].path);
  ASSERT_EQ(p.widths.size(), all.widths.size());
  for (std::size_t w = 0; w < all.widths.size(); ++w) {
    EXPECT_EQ(p.widths[w].numerator, all.widths[w].numerator);
    EXPECT_EQ(p.widths[w].count, all.widths[w].count);
    for (std::size_t b = 0; b < all.bins(); ++b) {
      EXPECT_NEAR(p.widths[w].H[b], all.widths[w].H[b], 1e-12) << w << " " << b;
      EXPECT_NEAR(p.widths[w].phi_mean[b], all.widths[w].phi_mean[b], 1e-12);
      EXPECT_LT(p.widths[w].H_low[b], p.widths[w].H[b]);
      EXPECT_GT(p.widths[w].H_high[b], p.widths[w].H[b]);
    }
  }
  const FitResult a = fit({all}, 0), b = fit({p}, 0);
  const cgd::SplineCurves ca{&a.model}, cb{&b.model};
  for (double phi : test_points()) {
    EXPECT_NEAR(cb.h(phi), ca.h(phi), 0.01) << phi;
    EXPECT_NEAR(cb.a(phi) / ca.a(phi), 1.0, 0.05) << phi;
  }
  const cgd::fit::FilteredFile alone = cgd::fit::pool_runs({all}, 7);
  EXPECT_TRUE(alone.pooled_paths.empty());
  EXPECT_EQ(alone.widths[2].H_low, all.widths[2].H_low);
}

// Pooled, a bin's H weighs the runs by their share of its drag (sum beta_micro u_slip), not by their samples; side
// by side, each run's H is a point weighted by its interval. Two runs of the same curves but the second's H 0.2
// higher, with a quarter of the samples, three times the micro drag per sample and four times the noise per snapshot:
// pooled, H = (4 H1 + 3 H2)/7 = H1 + 0.0857 at every width and bin (to 1e-12 in the data; by samples it would be
// H1 + 0.04) and the fit follows it: its H minus H1, averaged over the test points and the six widths, within 0.005
// of 0.0857 (measured 0.0862), and within 0.02 of it at each (the fit's error at this noise, measured 0.013); side by
// side the weights are 1/sigma^2, 16 : 1, and the fit follows H1 + 0.2/17 = H1 + 0.0118 (on average within 0.005,
// measured 0.0102; at each within 0.02, measured 0.009).
TEST(FitInput, PoolRunsWeighsTheRunsByTheirDrag) {
  SyntheticSpec s1;
  s1.runs = 1, s1.noise = 0.01, s1.count = 400, s1.seed = 3;
  SyntheticSpec s2 = s1;
  s2.noise = 0.04, s2.count = 100, s2.seed = 4;
  s2.truth = [](double phi, double F) { return truth_h(phi) / (1 + truth_a(phi) * F) + 0.2; };
  cgd::fit::FilteredFile f1 = make_synthetic(s1), f2 = make_synthetic(s2);
  f2.run_paths = {"synthetic/other_run"};
  for (cgd::fit::WidthSeries& w : f2.widths) {  // 3 x the micro drag per sample, H (and its interval) unchanged
    for (double& x : w.numerator) x *= 3;
    for (double& x : w.micro) x *= 3;
  }
  const cgd::fit::FilteredFile p = cgd::fit::pool_runs({f1, f2}, 1);
  for (std::size_t w = 0; w < p.widths.size(); ++w)
    for (std::size_t b = 0; b < p.bins(); ++b)
      EXPECT_NEAR(p.widths[w].H[b], (4 * f1.widths[w].H[b] + 3 * f2.widths[w].H[b]) / 7, 1e-12);
  const FitResult pooled = fit({p}, 0), apart = fit({f1, f2}, 0);
  const cgd::SplineCurves cp{&pooled.model}, ca{&apart.model};
  double mean_pooled = 0, mean_apart = 0;
  int points = 0;
  for (double phi : test_points())
    for (double F : s1.F) {
      const double H1 = truth_h(phi) / (1 + truth_a(phi) * F);
      const double off_pooled = cp.h(phi) / (1 + cp.a(phi) * F) - H1, off_apart = ca.h(phi) / (1 + ca.a(phi) * F) - H1;
      EXPECT_NEAR(off_pooled, 0.2 * 3 / 7, 0.02) << phi << " " << F;
      EXPECT_NEAR(off_apart, 0.2 / 17, 0.02) << phi << " " << F;
      mean_pooled += off_pooled, mean_apart += off_apart, ++points;
    }
  EXPECT_NEAR(mean_pooled / points, 0.2 * 3 / 7, 0.005);
  EXPECT_NEAR(mean_apart / points, 0.2 / 17, 0.005);
}

// The pooled interval is a block bootstrap within each run: four one-run files (10 blocks each, numbered from 0 in
// each file as cgd-filter numbers them), two of them with H 0.3 higher. Drawn within each run, every replicate keeps
// each run's share, and the half-width is that of the mean of four independent runs: sqrt(sum_r hw_r^2)/4 from the
// runs' own half-widths (1.96 x the standard error of their block means), times the bootstrap's sqrt((n - 1)/n) =
// 0.949 for n = 10 blocks: on average over the 140 (width, bin) cells within 0.95-1.04 of it (measured 0.992), each
// within 0.85-1.15 (measured 0.91-1.08: the bootstrap's 1000 replicates and its percentile interval against the
// runs' normal ones). Drawn across runs (or with the runs' blocks, all numbered from 0, taken for one), the 0.3
// between the runs would widen it ~10 times.
TEST(FitInput, PoolRunsBootstrapsWithinEachRun) {
  std::vector<cgd::fit::FilteredFile> files;
  for (int r = 0; r < 4; ++r) {
    SyntheticSpec s;
    s.runs = 1, s.noise = 0.02, s.seed = 11 + static_cast<std::uint64_t>(r);
    if (r >= 2) s.truth = [](double phi, double F) { return truth_h(phi) / (1 + truth_a(phi) * F) + 0.3; };
    files.push_back(make_synthetic(s));
    files.back().path = "run" + std::to_string(r) + ".h5";
    files.back().run_paths = {"synthetic/run_" + std::to_string(r)};
  }
  const cgd::fit::FilteredFile p = cgd::fit::pool_runs(files, 5);
  double sum = 0;
  int cells = 0;
  for (std::size_t w = 0; w < p.widths.size(); ++w)
    for (std::size_t b = 0; b < p.bins(); ++b) {
      double expected = 0;
      for (const cgd::fit::FilteredFile& f : files)
        expected += std::pow(0.5 * (f.widths[w].H_high[b] - f.widths[w].H_low[b]), 2);
      expected = std::sqrt(expected) / 4 * std::sqrt(0.9);
      const double ratio = 0.5 * (p.widths[w].H_high[b] - p.widths[w].H_low[b]) / expected;
      EXPECT_GT(ratio, 0.85) << w << " " << b;
      EXPECT_LT(ratio, 1.15) << w << " " << b;
      sum += ratio, ++cells;
    }
  EXPECT_GT(sum / cells, 0.95);
  EXPECT_LT(sum / cells, 1.04);
}

// Files that cannot be pooled are refused naming them: without per-snapshot sums, of other widths.
TEST(FitInput, PoolRunsRefusesFilesItCannotPool) {
  SyntheticSpec s;
  s.runs = 1;
  const cgd::fit::FilteredFile f = make_synthetic(s);
  cgd::fit::FilteredFile other = f, bare = f;
  other.path = "other.h5";
  other.widths[1].F *= 1.5;
  expect_input_error([&] { cgd::fit::pool_runs({f, other}, 1); }, {"other.h5", "same widths and grids"});
  bare.path = "bare.h5";
  bare.has_per_snapshot = false;
  expect_input_error([&] { cgd::fit::pool_runs({f, bare}, 1); }, {"bare.h5", "per-snapshot sums"});
}

}  // namespace
