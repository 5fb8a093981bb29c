// Verification of the filter (filter/box_filter.hpp, filter/filter.hpp) against answers derived here:
// uniform fields, a sinusoid (discrete overlap sums and the continuous box average), one-cell boxes on
// per-cell fields, periodic images, and the exact gradient of the filtered pressure.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "core/drag.hpp"
#include "core/schema/snapshot.hpp"
#include "filter/box_filter.hpp"
#include "filter/filter.hpp"
#include "filter/statistics.hpp"
#include "test_scenes.hpp"

namespace cgd::filter {
namespace {

PeriodicGrid make_grid(int nx, int ny, int nz, double h) {
  PeriodicGrid g;
  g.cells = {nx, ny, nz};
  g.spacing_m = {h, h, h};
  g.origin_m = {0, 0, 0};
  return g;
}

/// Overlap of [a, b] with the periodic images of cell [i h, (i+1) h] on a ring of n cells (b - a <= n h).
double overlap_1d(double a, double b, int i, int n, double h) {
  const double L = n * h;
  double total = 0;
  for (int image = -2; image <= 2; ++image) {
    const double lo = i * h + image * L, hi = lo + h;
    total += std::max(0.0, std::min(b, hi) - std::max(a, lo));
  }
  return total;
}

/// Brute-force box average of a cell field: sum over every cell of its overlap volume times its value.
double brute_box_average(const PeriodicGrid& g, const std::vector<double>& f, const double* x, double width) {
  double sum = 0;
  for (int k = 0; k < g.cells[2]; ++k) {
    const double oz = overlap_1d(x[2] - width / 2, x[2] + width / 2, k, g.cells[2], g.spacing_m[2]);
    if (oz == 0) continue;
    for (int j = 0; j < g.cells[1]; ++j) {
      const double oy = overlap_1d(x[1] - width / 2, x[1] + width / 2, j, g.cells[1], g.spacing_m[1]);
      if (oy == 0) continue;
      for (int i = 0; i < g.cells[0]; ++i) {
        const double ox = overlap_1d(x[0] - width / 2, x[0] + width / 2, i, g.cells[0], g.spacing_m[0]);
        sum += ox * oy * oz * f[g.index(i, j, k)];
      }
    }
  }
  return sum / (width * width * width);
}

struct Fields {
  std::vector<double> eps, eps_u, p;
};

// A random field: eps in [0.5, 1], u and p random; every test point and width also checked by brute force.
Fields random_fields(const PeriodicGrid& g, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0, 1);
  Fields f;
  const std::size_t n = g.cell_count();
  for (std::size_t c = 0; c < n; ++c) {
    f.eps.push_back(0.5 + 0.5 * U(rng));
    for (int d = 0; d < 3; ++d) f.eps_u.push_back(f.eps.back() * (U(rng) - 0.5));
    f.p.push_back(100 * (U(rng) - 0.5));
  }
  return f;
}

TEST(BoxFilter, MatchesBruteForceOverlapSumsAtAnyWidthAndPosition) {
  // Exactness claim: partial cells count by their overlap, for any width from one cell to the box.
  // Tolerance 1e-12 relative: the table's 4-point differences lose ~log10(cells) digits at most.
  const PeriodicGrid g = make_grid(7, 11, 5, 0.1);
  const Fields f = random_fields(g, 3);
  const PeriodicBoxFilter box(g, f.eps, f.eps_u, f.p, 0.5);
  std::vector<double> u_y(g.cell_count());
  for (std::size_t c = 0; c < u_y.size(); ++c) u_y[c] = f.eps_u[3 * c + 1];
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(0, 1);
  for (double width : {0.1, 0.137, 0.25, 0.3333, 0.5}) {
    for (int trial = 0; trial < 20; ++trial) {
      const double x[3] = {0.7 * U(rng), 1.1 * U(rng), 0.5 * U(rng)};
      const FilteredPoint fp = box.at(x, width);
      const double eps = brute_box_average(g, f.eps, x, width);
      const double epsu = brute_box_average(g, u_y, x, width);
      EXPECT_NEAR(fp.void_fraction, eps, 1e-12) << "width " << width;
      EXPECT_NEAR(fp.velocity[1], epsu / eps, 1e-12) << "width " << width;
    }
  }
}

TEST(BoxFilter, SinusoidGivesTheContinuousBoxAverageWhenTheBoxEdgesLieOnFaces) {
  // Cell values are the cell averages of A sin(k x); a box whose edges lie on cell faces then averages
  // the continuous sinusoid exactly: A sin(k x) sin(k D/2)/(k D/2). Off the faces, the discrete answer
  // (brute-force overlaps) is the reference and the continuous one is within O((k h)^2).
  const int n = 24;
  const double h = 0.05, L = n * h, k = 2 * std::numbers::pi / L, A = 0.3;
  const PeriodicGrid g = make_grid(n, 4, 4, h);
  Fields f;
  std::vector<double> uy(g.cell_count());
  for (std::size_t c = 0; c < g.cell_count(); ++c) {
    const int i = static_cast<int>(c % n);
    const double cell_mean = A * (std::cos(k * i * h) - std::cos(k * (i + 1) * h)) / (k * h);
    f.eps.push_back(1.0);
    f.eps_u.insert(f.eps_u.end(), {0.0, cell_mean, 0.0});
    f.p.push_back(0.0);
    uy[c] = cell_mean;
  }
  const PeriodicBoxFilter box(g, f.eps, f.eps_u, f.p, 4 * h);
  for (int cells = 1; cells <= 4; ++cells) {
    const double D = cells * h;
    for (int face = 0; face < n; ++face) {
      const double x[3] = {face * h + D / 2, 0.1, 0.1};  // lower edge on a face
      const double continuous = A * std::sin(k * x[0]) * std::sin(k * D / 2) / (k * D / 2);
      EXPECT_NEAR(box.at(x, D).velocity[1], continuous, 1e-13) << cells << " cells at face " << face;
    }
    const double x[3] = {0.123, 0.1, 0.1};
    const double discrete = brute_box_average(g, uy, x, D);
    const double continuous = A * std::sin(k * x[0]) * std::sin(k * D / 2) / (k * D / 2);
    EXPECT_NEAR(box.at(x, D).velocity[1], discrete, 1e-13);
    EXPECT_NEAR(discrete, continuous, A * (k * h) * (k * h));
  }
}

TEST(BoxFilter, PressureGradientIsTheExactDerivativeOfTheFilteredPressure) {
  // The box average is piecewise linear in the box centre between face crossings, so a central
  // difference with a step that crosses no face is exact up to round-off (1e-8 relative for a 1e-6
  // step on values of O(100)).
  const PeriodicGrid g = make_grid(6, 9, 7, 0.1);
  const Fields f = random_fields(g, 8);
  const PeriodicBoxFilter box(g, f.eps, f.eps_u, f.p, 0.6);
  const double delta = 1e-6;
  for (double width : {0.1, 0.27, 0.6}) {
    const double x[3] = {0.3141, 0.4159, 0.2653};
    const FilteredPoint fp = box.at(x, width);
    for (int a = 0; a < 3; ++a) {
      double xp[3] = {x[0], x[1], x[2]}, xm[3] = {x[0], x[1], x[2]};
      xp[a] += delta;
      xm[a] -= delta;
      const double dp = (brute_box_average(g, f.p, xp, width) - brute_box_average(g, f.p, xm, width)) / (2 * delta);
      EXPECT_NEAR(fp.grad_p[a], dp, 1e-6 * std::max(1.0, std::abs(dp))) << "axis " << a << " width " << width;
    }
  }
}

TEST(BoxFilter, ParticleAtTheBoxEdgeSeesTheSameFilterAsItsImage) {
  // Periodic wrap: x and x + L (and x - L) are the same point; only round-off of the wrap differs.
  const PeriodicGrid g = make_grid(8, 8, 8, 0.1);
  const Fields f = random_fields(g, 11);
  const PeriodicBoxFilter box(g, f.eps, f.eps_u, f.p, 0.8);
  for (double width : {0.1, 0.35, 0.8}) {
    const double x[3] = {0.7999, 1e-9, 0.4};
    const double img[3] = {x[0] - 0.8, x[1] + 0.8, x[2] + 1.6};
    const FilteredPoint a = box.at(x, width), b = box.at(img, width);
    EXPECT_NEAR(a.void_fraction, b.void_fraction, 1e-13);
    for (int d = 0; d < 3; ++d) {
      EXPECT_NEAR(a.velocity[d], b.velocity[d], 1e-13);
      EXPECT_NEAR(a.grad_p[d], b.grad_p[d], 1e-9);
    }
  }
}

TEST(BoxFilter, WholeBoxWidthEqualsTheDomainAverage) {
  // A box as wide as the (cubic) domain covers every cell exactly once, wherever it is centred.
  const PeriodicGrid g = make_grid(6, 6, 6, 0.1);
  const Fields f = random_fields(g, 2);
  const PeriodicBoxFilter box(g, f.eps, f.eps_u, f.p, 0.6);
  const FilteredPoint whole = box.domain_average();
  const double x[3] = {0.123, 0.456, 0.0789};
  const FilteredPoint fp = box.at(x, 0.6);
  EXPECT_NEAR(fp.void_fraction, whole.void_fraction, 1e-14);
  for (int d = 0; d < 3; ++d) {
    EXPECT_NEAR(fp.velocity[d], whole.velocity[d], 1e-14);
    EXPECT_NEAR(fp.grad_p[d], 0.0, 1e-10);
  }
}

// ---- the per-particle filter and the bins -----------------------------------------------------------

struct SyntheticRun {
  schema::Snapshot snap;
  FilterPlan plan;
  FilterOptions options;
};

/// A snapshot whose particles sit at cell centres, with fluid_velocity = the cell's u and beta_p = the
/// micro law's value at the cell's phi and slip: what the resolved drag would be on a per-cell field.
SyntheticRun per_cell_run(bool uniform) {
  SyntheticRun r;
  const double d = 75e-6, h = 2.5e-4;
  PeriodicGrid g = make_grid(6, 8, 6, h);
  schema::Snapshot& s = r.snap;
  s.has_fluid = true;
  s.grid = g;
  s.physics = cgd::testing::air_beetstra_physics(d);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(0, 1);
  const BeetstraDrag law(1.3, 1.8e-5, d);
  for (std::size_t c = 0; c < g.cell_count(); ++c) {
    const double eps = uniform ? 0.9 : 0.6 + 0.4 * U(rng);
    const double u[3] = {uniform ? 0.01 : 0.05 * (U(rng) - 0.5), uniform ? 0.2 : 0.3 * U(rng), 0.0};
    s.void_fraction.push_back(eps);
    for (double ud : u) s.eps_velocity.push_back(eps * ud);
    s.pressure.push_back(0.0);
  }
  for (int k = 0; k < 6; ++k)
    for (int j = 0; j < 8; ++j)
      for (int i = 0; i < 6; ++i) {
        const std::size_t c = g.index(i, j, k);
        const double x[3] = {(i + 0.5) * h, (j + 0.5) * h, (k + 0.5) * h};
        const double v[3] = {0.0, uniform ? -0.01 : -0.1 * U(rng), 0.0};
        const double eps = s.void_fraction[c];
        double slip2 = 0;
        for (int dd = 0; dd < 3; ++dd) {
          const double sl = s.eps_velocity[3 * c + dd] / eps - v[dd];
          slip2 += sl * sl;
          s.fluid_velocity.push_back(s.eps_velocity[3 * c + dd] / eps);
          s.position.push_back(x[dd]);
          s.velocity.push_back(v[dd]);
          s.pressure_gradient.push_back(0.0);
        }
        s.drag_coefficient.push_back(law.beta_p(1 - eps, std::sqrt(slip2)));
        s.id.push_back(s.count++);
      }
  RunPlan run;
  run.physics = s.physics;
  run.grid = g;
  r.plan.runs.push_back(run);
  r.plan.widths_m = {h, 2 * h, 3 * h};
  r.plan.whole_box_width_m = std::cbrt(6 * 8 * 6.0) * h;
  for (int b = 0; b <= 100; ++b) r.plan.bin_edges.push_back(0.01 * b);
  return r;
}

TEST(Filter, UniformFieldsGiveHZero) {
  // Uniform eps and u: every filtered value equals the resolved one, so sum N = sum M and H = 0 up to
  // round-off: the mean of 288 equal values is off by ~1e-16 relative, and beta_micro amplifies a phi
  // error by d ln beta / d phi ~ 10-100 at phi = 0.1 (Beetstra's 10 phi/eps^2 term): tolerance 1e-13.
  SyntheticRun r = per_cell_run(true);
  const SnapshotResult res = filter_snapshot(r.snap, r.plan, r.options, 0, 0);
  const std::size_t n_bins = r.plan.bin_edges.size() - 1;
  int filled = 0;
  for (std::size_t w = 0; w < 4; ++w)
    for (std::size_t b = 0; b < n_bins; ++b) {
      const BinSums& s = res.sums[w * n_bins + b];
      if (s.count == 0) continue;
      ++filled;
      EXPECT_EQ(s.count, 288);
      EXPECT_NEAR(1.0 - s.numerator / s.micro, 0.0, 1e-13) << "width " << w;
      EXPECT_NEAR(s.phi / s.count, 0.1, 1e-14);
      EXPECT_NEAR(s.slip / s.count, 0.21, 1e-14);
    }
  EXPECT_EQ(filled, 4);  // one bin per width (3 boxes + whole box)
}

TEST(Filter, OneCellBoxOnPerCellFieldsReproducesTheUnfilteredSlip) {
  // Particles at cell centres: a box of one cell is exactly that cell, so u_bar = (eps u)_c/eps_c = u_i,
  // phi_bar = phi_c, and N_i = beta_p,i (u_i - v_i)_y = M_i: per bin H = 0 and the mean filtered slip is
  // the mean unfiltered slip (round-off 1e-14 of the table differences).
  SyntheticRun r = per_cell_run(false);
  r.options.samples = 1000;
  const SnapshotResult res = filter_snapshot(r.snap, r.plan, r.options, 0, 0);
  const std::size_t n_bins = r.plan.bin_edges.size() - 1;
  double count = 0, slip = 0;
  for (std::size_t b = 0; b < n_bins; ++b) {
    const BinSums& s = res.sums[b];  // width 0 = one cell
    if (s.count == 0) continue;
    EXPECT_NEAR(1.0 - s.numerator / s.micro, 0.0, 1e-12) << "bin " << b;
    count += s.count;
    slip += s.slip;
  }
  double unfiltered = 0;
  for (std::int64_t i = 0; i < r.snap.count; ++i) unfiltered += r.snap.fluid_velocity[3 * i + 1] - r.snap.velocity[3 * i + 1];
  EXPECT_EQ(count, static_cast<double>(r.snap.count));
  EXPECT_NEAR(slip / count, unfiltered / static_cast<double>(r.snap.count), 1e-14);
  // per particle too (the samples hold every particle here)
  ASSERT_EQ(res.samples[0].size(), static_cast<std::size_t>(r.snap.count));
  for (const Sample& smp : res.samples[0]) {
    const auto i = static_cast<std::size_t>(smp.id);
    EXPECT_NEAR(smp.slip[1], r.snap.fluid_velocity[3 * i + 1] - r.snap.velocity[3 * i + 1], 1e-14);
  }
  // wider boxes mix cells: the drag they see differs from the micro law at phi_bar (H != 0)
  double num = 0, mic = 0;
  for (std::size_t b = 0; b < n_bins; ++b) {
    num += res.sums[2 * n_bins + b].numerator;
    mic += res.sums[2 * n_bins + b].micro;
  }
  EXPECT_GT(std::abs(1.0 - num / mic), 1e-3);
}

TEST(FilterStatistics, AutocorrelationTimeOfWhiteNoiseAndOfAnAR1Process) {
  // White noise: tau = 1/2. AR(1) with coefficient r: tau = 1/2 + r/(1 - r) (= 4.5 for r = 0.8); with
  // 20000 samples the estimate's relative error is ~sqrt(2 (2W+1)/n) ~ 10 %, tolerance 20 %.
  std::mt19937 rng(1);
  std::normal_distribution<double> N(0, 1);
  std::vector<double> white(20000), ar(20000);
  double x = 0;
  for (std::size_t t = 0; t < white.size(); ++t) {
    white[t] = N(rng);
    x = 0.8 * x + N(rng);
    ar[t] = x;
  }
  EXPECT_NEAR(integrated_autocorrelation_time(white), 0.5, 0.05);
  EXPECT_NEAR(integrated_autocorrelation_time(ar), 4.5, 0.9);
  EXPECT_EQ(block_length(0.5, 100), 1);
  EXPECT_EQ(block_length(4.5, 100), 9);
  EXPECT_EQ(block_length(40, 10), 5);
  std::vector<double> v{3, 1, 2, 4};
  EXPECT_DOUBLE_EQ(percentile(v, 0.5), 2.5);
}

}  // namespace
}  // namespace cgd::filter

namespace cgd::filter {
namespace {

TEST(Filter, ClusterColumnGivesHThatGrowsWithTheWidthAndTheFullPeriodValue) {
  // A known "cluster": along x, a quarter of the period is dense (phi = 0.3, slow gas u_y = 0.05 m/s,
  // particles falling at -0.15 m/s), the rest dilute (phi = 0.02, gas 0.4 m/s, particles -0.05 m/s);
  // uniform in y and z, uniform pressure, the resolved drag the micro law of each cell. The gas bypasses
  // the cluster, so a box reaching past the cluster's edge sees a faster gas: the filtered slip of the
  // cluster's particles exceeds their resolved slip and H > 0 in the dense bins, growing with the box.
  // A box as wide as the period sees the domain average: H there is computed here from the sums.
  const int n = 16;
  const double d = 75e-6, h = 2.5e-4;
  schema::Snapshot s;
  s.has_fluid = true;
  s.grid.cells = {n, 4, 4};
  s.grid.spacing_m = {h, h, h};
  s.physics.diameter_m = d;
  s.physics.fluid_density_kg_m3 = 1.3;
  s.physics.fluid_viscosity_Pa_s = 1.8e-5;
  s.physics.drag = "beetstra";
  s.physics.pressure_gradient_force = true;
  const BeetstraDrag law(1.3, 1.8e-5, d);
  auto dense = [&](int i) { return i < n / 4; };
  for (std::size_t c = 0; c < s.grid.cell_count(); ++c) {
    const int i = static_cast<int>(c % n);
    const double eps = dense(i) ? 0.7 : 0.98, u = dense(i) ? 0.05 : 0.4;
    s.void_fraction.push_back(eps);
    s.eps_velocity.insert(s.eps_velocity.end(), {0.0, eps * u, 0.0});
    s.pressure.push_back(0.0);
  }
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < n; ++i) {
        const int per_cell = dense(i) ? 15 : 1;  // particles in proportion to phi
        for (int q = 0; q < per_cell; ++q) {
          const double x[3] = {(i + 0.5) * h, (j + 0.5) * h, (k + 0.5) * h};
          const double u = dense(i) ? 0.05 : 0.4, v = dense(i) ? -0.15 : -0.05;
          s.position.insert(s.position.end(), x, x + 3);
          s.velocity.insert(s.velocity.end(), {0.0, v, 0.0});
          s.fluid_velocity.insert(s.fluid_velocity.end(), {0.0, u, 0.0});
          s.pressure_gradient.insert(s.pressure_gradient.end(), {0.0, 0.0, 0.0});
          s.drag_coefficient.push_back(law.beta_p(dense(i) ? 0.3 : 0.02, u - v));
          s.id.push_back(s.count++);
        }
      }
  FilterPlan plan;
  RunPlan run;
  run.physics = s.physics;
  run.grid = s.grid;
  plan.runs.push_back(run);
  plan.widths_m = {h, 2 * h, 3 * h, 4 * h, 6 * h, n * h};
  plan.whole_box_width_m = n * h;
  for (int b = 0; b <= 100; ++b) plan.bin_edges.push_back(0.01 * b);
  const SnapshotResult res = filter_snapshot(s, plan, FilterOptions{}, 0, 0);
  const std::size_t n_bins = 100;
  // H of the particles that sit in the cluster's cells: their bins are those with phi_bar >= 0.1
  auto dense_H = [&](std::size_t w) {
    double num = 0, mic = 0;
    for (std::size_t b = 10; b < n_bins; ++b) {
      num += res.sums[w * n_bins + b].numerator;
      mic += res.sums[w * n_bins + b].micro;
    }
    return 1.0 - num / mic;
  };
  EXPECT_NEAR(dense_H(0), 0.0, 1e-12);  // one cell: the resolved field itself
  double previous = dense_H(0);
  for (std::size_t w = 1; w < 5; ++w) {
    EXPECT_GT(dense_H(w), previous + 0.01) << "width " << w;
    previous = dense_H(w);
  }
  // the full period: every particle sees phi_bar = <phi> and the Favre mean gas velocity
  double eps_sum = 0, epsu_sum = 0;
  for (std::size_t c = 0; c < s.grid.cell_count(); ++c) {
    eps_sum += s.void_fraction[c];
    epsu_sum += s.eps_velocity[3 * c + 1];
  }
  const double phi_mean = 1 - eps_sum / static_cast<double>(s.grid.cell_count()), u_mean = epsu_sum / eps_sum;
  double num = 0, mic = 0;
  for (std::int64_t i = 0; i < s.count; ++i) {
    const double slip = u_mean - s.velocity[3 * i + 1];
    num += s.drag_coefficient[i] * (s.fluid_velocity[3 * i + 1] - s.velocity[3 * i + 1]);
    mic += law.beta_p(phi_mean, std::abs(slip)) * slip;
  }
  for (std::size_t w : {std::size_t{5}, std::size_t{6}}) {  // the period-wide box and the whole box
    double n_w = 0, m_w = 0;
    for (std::size_t b = 0; b < n_bins; ++b) {
      n_w += res.sums[w * n_bins + b].numerator;
      m_w += res.sums[w * n_bins + b].micro;
    }
    EXPECT_NEAR(1.0 - n_w / m_w, 1.0 - num / mic, 1e-12) << "width " << w;
  }
  EXPECT_GT(1.0 - num / mic, 0.05);  // clustering lowers the drag a coarse observer sees (0.105 here)
}

}  // namespace
}  // namespace cgd::filter
