// Verification of the whole-grid TSC operator (core/tsc_grid.hpp) and of the filter's coarse-grid
// operator (filter/filter.hpp, cgd-filter --grids) against answers derived here: conservation of the
// deposited volume, the coupler's own 27-cell loop, the analytic deposit+interpolate transfer function
// of a Fourier mode, the coarse grid a coarse run builds, H_grid = 0 on the resolved run's own grid and
// on uniform fields.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <random>

#include "core/drag.hpp"
#include "core/scene.hpp"
#include "core/schema/snapshot.hpp"
#include "core/tsc_grid.hpp"
#include "filter/filter.hpp"
#include "sim/coupling/exchange.hpp"
#include "test_scenes.hpp"

namespace cgd {
namespace {

PeriodicGrid grid_of(int nx, int ny, int nz, double h) {
  PeriodicGrid g;
  g.cells = {nx, ny, nz};
  g.spacing_m = {h, h, h};
  return g;
}

/// The quadratic B-spline of width 3 (cell units), written out independently of core/tsc_kernel.hpp.
double bspline2(double s) {
  s = std::abs(s);
  if (s <= 0.5) return 0.75 - s * s;
  if (s <= 1.5) return 0.5 * (1.5 - s) * (1.5 - s);
  return 0.0;
}

TEST(TscGrid, DepositConservesTheParticlesVolumeOnAnyGrid) {
  // Partition of unity: sum_c phi_c V_cell = sum_i V_i, to round-off (1e-13 relative for 2000 sums),
  // also on grids of 1 and 2 cells along an axis (the images fold onto the same cells) and for
  // particles outside the box (wrapped).
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(-0.5, 1.5);
  for (const auto& cells : std::vector<std::array<int, 3>>{{7, 5, 9}, {1, 4, 2}, {3, 3, 3}}) {
    PeriodicGrid g = grid_of(cells[0], cells[1], cells[2], 1e-3);
    g.spacing_m = {1e-3, 1.3e-3, 0.7e-3};
    std::vector<double> x, vol;
    double total = 0;
    for (int i = 0; i < 2000; ++i) {
      for (int a = 0; a < 3; ++a) x.push_back(U(rng) * g.edge_m(a));
      vol.push_back(1e-12 * (1 + U(rng)));
      total += vol.back();
    }
    const std::vector<double> phi = tsc_deposit_solids_fraction(g, x, vol);
    double sum = 0;
    for (double p : phi) sum += p * g.cell_volume_m3();
    EXPECT_NEAR(sum / total, 1.0, 1e-13) << cells[0] << "x" << cells[1] << "x" << cells[2];
  }
}

TEST(TscGrid, SameCellsAndWeightsAsTheCouplersSlabLoop) {
  // On one rank the coupler's slab view (sim/coupling/exchange.hpp) holds the whole grid in its owned
  // rows: both loops must visit the same cells with the same weights (bit for bit: the same products).
  const PeriodicGrid g = grid_of(6, 8, 5, 2.5e-4);
  coupling::GridView v;
  v.cells = g.cells;
  v.spacing = g.spacing_m;
  v.j0 = 0;
  v.ny_local = g.cells[1];
  v.ghost = 2;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(0, 1);
  for (int n = 0; n < 200; ++n) {
    double x[3];
    for (int a = 0; a < 3; ++a) x[a] = U(rng) * g.edge_m(a);
    x[1] = std::clamp(x[1], 1.01 * g.spacing_m[1], g.edge_m(1) - 1.01 * g.spacing_m[1]);  // slab rows only
    std::map<std::size_t, double> mine, coupler;
    for_each_tsc_cell(g, x, [&](std::size_t c, double w) { mine[c] += w; });
    coupling::for_each_tsc_cell(v, x, [&](std::size_t c, double w) {
      // slab storage (j + ghost, k, i), y slowest -> file order (k, j, i)
      const int j = static_cast<int>(c / v.plane()) - v.ghost, rest = static_cast<int>(c % v.plane());
      coupler[g.index(rest % g.cells[0], j, rest / g.cells[0])] += w;
    });
    ASSERT_EQ(mine.size(), coupler.size());
    for (const auto& [c, w] : mine) EXPECT_EQ(w, coupler.at(c));
  }
}

TEST(TscGrid, DepositThenInterpolateTransfersAModeByTheAnalyticFactor) {
  // A density cos(k x) along x, sampled by particles on a fine lattice (M points per cell along x, one
  // per cell centre along y and z) with volumes V0 (1 + A cos(k x_p)). Known answers:
  //  (1) each cell's deposit equals the brute-force 1D sum of the B-spline over the lattice (written
  //      out here, 1e-12: round-off of ~10^4 terms), the y-z layers deposit uniformly;
  //  (2) interpolated back at cell centres, the mode's amplitude is A T(k),
  //      T(k) = [sin(kh/2)/(kh/2)]^3 (3/4 + cos(kh)/4) (core/tsc_grid.hpp), the continuous deposit; the
  //      lattice is the midpoint rule on sub-intervals whose ends include the kernel's kinks (M even), so
  //      the quadrature error is <= 3 max|f''| / (24 M^2) with |f''| <= 1 + 2k + (3/4) k^2 <~ 15 (k h <= pi):
  //      5e-4 A at M = 64; tolerance 1e-3 A. The modes include the Nyquist one (k h = pi, T = 0.129).
  const int n = 16, M = 64;
  const double h = 1e-3, A = 0.3, V0 = 1e-12;
  const PeriodicGrid g = grid_of(n, 3, 3, h);
  for (int m : {1, 2, 4, 8}) {
    const double k = 2 * std::numbers::pi * m / (n * h);
    std::vector<double> x, vol;
    for (int p = 0; p < n * M; ++p)
      for (int jz = 0; jz < 3; ++jz)
        for (int jy = 0; jy < 3; ++jy) {
          const double xp = (p + 0.5) * h / M;
          x.insert(x.end(), {xp, (jy + 0.5) * h, (jz + 0.5) * h});
          vol.push_back(V0 * (1 + A * std::cos(k * xp)));
        }
    const std::vector<double> phi = tsc_deposit_solids_fraction(g, x, vol);
    // (1) brute force along x
    for (int i = 0; i < n; ++i) {
      double expect = 0;
      for (int p = 0; p < n * M; ++p) {
        const double s = (p + 0.5) / M - (i + 0.5);
        for (int image = -1; image <= 1; ++image) expect += bspline2(s + image * n) * V0 * (1 + A * std::cos(k * (p + 0.5) * h / M));
      }
      expect /= g.cell_volume_m3();  // the 3 x 3 lines at the y-z cell centres give every y-z cell weight 1 in all
      for (int j = 0; j < 3; ++j)
        for (int kz = 0; kz < 3; ++kz) EXPECT_NEAR(phi[g.index(i, j, kz)] / expect, 1.0, 1e-12) << "m " << m << " cell " << i;
    }
    // (2) the mode's amplitude after interpolation at the cell centres
    const double mean = V0 * M / g.cell_volume_m3();  // n M lattice points x 9 lines over n x 9 cells
    const double kh = k * h, sinc = std::sin(kh / 2) / (kh / 2);
    const double T = sinc * sinc * sinc * (0.75 + 0.25 * std::cos(kh));
    for (int i = 0; i < n; ++i) {
      const double xc[3] = {(i + 0.5) * h, 1.5 * h, 1.5 * h};
      const double back = tsc_interpolate<1>(g, phi.data(), xc)[0];
      EXPECT_NEAR((back - mean) / mean, A * T * std::cos(k * xc[0]), 1e-3 * A) << "m " << m << " cell " << i;
    }
  }
}

TEST(TscGrid, FloorKeepsTheTotalVoidFractionAndRaisesDenseCells) {
  std::vector<double> phi = {0.1, 0.8, 0.75, 0.2, 0.05, 0.3};
  double before = 0;
  for (double p : phi) before += 1 - p;
  EXPECT_EQ(apply_void_fraction_floor(phi, 0.3), 2);
  double after = 0;
  for (double p : phi) {
    after += 1 - p;
    EXPECT_GE(1 - p, 0.3 - 1e-15);
  }
  EXPECT_NEAR(after, before, 1e-14);
  std::vector<double> too_dense = {0.9, 0.9};
  EXPECT_THROW(apply_void_fraction_floor(too_dense, 0.3), RunError);
}

// ---- the filter's coarse-grid operator --------------------------------------------------------------------

TEST(CoarseGrid, IsTheGridACoarseRunBuildsFromCellsAcross) {
  // The demo box 30 x 120 x 30 d_p: N cells across means fluid.dx_over_dp = 30/N, and the scene rounds
  // box/(dx d_p) per axis: N = 4 -> 4 x 16 x 4 cells of 7.5 d_p; N = 7 -> 7 x 28 x 7 (120/(30/7) = 28);
  // N = 9 -> 9 x 36 x 9 (the resolved run's own grid, dx_over_dp = 3.33 in its scene).
  const std::string toml = cgd::testing::test_scene_text("demo_box.toml") + "\n[numerics]\nvoid_fraction_floor = 0.25\n";
  const double d = 7.5e-5;
  const filter::CoarseGrid c4 = filter::coarse_grid_of_scene(toml, "demo", 4);
  EXPECT_EQ(c4.grid.cells, (std::array<int, 3>{4, 16, 4}));
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(c4.grid.spacing_m[a] / d, 7.5, 1e-12);
  EXPECT_NEAR(c4.dx_over_dp, 7.5, 1e-12);
  EXPECT_EQ(c4.void_fraction_floor, 0.25);
  const filter::CoarseGrid c7 = filter::coarse_grid_of_scene(toml, "demo", 7);
  EXPECT_EQ(c7.grid.cells, (std::array<int, 3>{7, 28, 7}));
  EXPECT_NEAR(c7.grid.spacing_m[1] / d, 120.0 / 28, 1e-12);
  const filter::CoarseGrid c9 = filter::coarse_grid_of_scene(toml, "demo", 9);
  EXPECT_EQ(c9.grid.cells, (std::array<int, 3>{9, 36, 9}));
  EXPECT_THROW(filter::coarse_grid_of_scene(toml, "demo", 0), InputError);
}

/// A snapshot as a resolved coupled run writes it, built with the coupler's own operations on grid g:
/// eps = 1 - TSC deposit of the particles, a cell-centred u and a pressure field, and per particle
/// u_i, grad p_i = TSC interpolation of u_c and of the central differences of p, beta_p,i = Beetstra at
/// (TSC-interpolated phi, |u_i - v_i|). `uniform`: u_c, p and v the same everywhere.
schema::Snapshot coupled_snapshot(const PeriodicGrid& g, const std::vector<double>& positions, bool uniform, unsigned seed) {
  schema::Snapshot s;
  const double d = 75e-6;
  s.has_fluid = true;
  s.grid = g;
  s.physics = cgd::testing::air_beetstra_physics(d);
  s.position = positions;
  s.count = static_cast<std::int64_t>(positions.size() / 3);
  const double vp = std::numbers::pi / 6 * d * d * d;
  std::vector<double> phi = tsc_deposit_solids_fraction(g, positions, {vp});
  apply_void_fraction_floor(phi, 0.3);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0, 1);
  for (std::size_t c = 0; c < g.cell_count(); ++c) {
    s.void_fraction.push_back(1 - phi[c]);
    const double u[3] = {uniform ? 0.01 : 0.05 * (U(rng) - 0.5), uniform ? 0.2 : 0.3 * U(rng), uniform ? 0.0 : 0.02 * U(rng)};
    for (int a = 0; a < 3; ++a) {
      s.cell_velocity.push_back(u[a]);
      s.eps_velocity.push_back(s.void_fraction.back() * u[a]);
    }
    s.pressure.push_back(uniform ? 0.0 : 50 * (U(rng) - 0.5));
  }
  const std::vector<double> grad = central_pressure_gradient(g, s.pressure);
  const BeetstraDrag law(1.3, 1.8e-5, d);
  for (std::int64_t i = 0; i < s.count; ++i) {
    const double* x = &positions[3 * i];
    const auto u = tsc_interpolate<3>(g, s.cell_velocity.data(), x);
    const auto gp = tsc_interpolate<3>(g, grad.data(), x);
    const double phi_p = tsc_interpolate<1>(g, phi.data(), x)[0];
    const double v[3] = {0.0, uniform ? -0.01 : -0.1 * U(rng), 0.0};
    double slip2 = 0;
    for (int a = 0; a < 3; ++a) {
      s.velocity.push_back(v[a]);
      s.fluid_velocity.push_back(u[a]);
      s.pressure_gradient.push_back(gp[a]);
      slip2 += (u[a] - v[a]) * (u[a] - v[a]);
    }
    s.drag_coefficient.push_back(law.beta_p(phi_p, std::sqrt(slip2)));
    s.id.push_back(i);
  }
  return s;
}

/// A plan with one box width (one cell) and the coarse grids given (cells across, spacing = box / cells).
filter::FilterPlan plan_with_grids(const schema::Snapshot& s, const std::vector<std::array<int, 3>>& grids) {
  filter::FilterPlan plan;
  filter::RunPlan run;
  run.physics = s.physics;
  run.grid = s.grid;
  for (const auto& cells : grids) {
    filter::CoarseGrid c;
    c.cells_across = cells[0];
    for (int a = 0; a < 3; ++a) {
      c.grid.cells[a] = cells[a];
      c.grid.spacing_m[a] = s.grid.edge_m(a) / cells[a];
    }
    run.coarse.push_back(c);
    plan.grids.push_back(cells[0]);
  }
  plan.runs.push_back(run);
  plan.widths_m = {s.grid.cell_size_m()};
  plan.whole_box_width_m = std::cbrt(s.grid.edge_m(0) * s.grid.edge_m(1) * s.grid.edge_m(2));
  for (int b = 0; b <= 100; ++b) plan.bin_edges.push_back(0.01 * b);
  return plan;
}

TEST(CoarseGridOperator, ResolvedRunsOwnGridGivesHZeroToRoundOff) {
  // The coarse grid equal to the resolved grid: the deposit is the run's eps, the cell restriction is
  // the identity (box of one cell at its centre), u_C = (eps u_c)/eps = u_c, the gradient and the
  // interpolation are the coupler's: phi_i, u_i and grad p_i are reproduced, the pressure terms of N_i
  // cancel and N_i = beta_p,i (u_i - v_i)_y = M_i. H = 0 to round-off: the table differences (1e-14
  // relative) amplified by d ln beta/d phi ~ 10-100: tolerance 1e-11; the slip per particle to 1e-13 m/s.
  const PeriodicGrid g = grid_of(6, 8, 6, 2.5e-4);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> U(0, 1);
  std::vector<double> x;
  for (int i = 0; i < 6 * 8 * 6 * 6; ++i)
    for (int a = 0; a < 3; ++a) x.push_back(U(rng) * g.edge_m(a));
  const schema::Snapshot s = coupled_snapshot(g, x, false, 2);
  const filter::FilterPlan plan = plan_with_grids(s, {{6, 8, 6}});
  filter::FilterOptions o;
  o.samples = 100000;
  const filter::SnapshotResult res = filter::filter_snapshot(s, plan, o, 0, 0);
  const std::size_t nb = plan.bin_edges.size() - 1, col = plan.whole_box_column() + 1;
  double count = 0;
  int bins = 0;
  for (std::size_t b = 0; b < nb; ++b) {
    const filter::BinSums& bs = res.sums[col * nb + b];
    if (bs.count == 0) continue;
    ++bins;
    count += bs.count;
    EXPECT_NEAR(1.0 - bs.numerator / bs.micro, 0.0, 1e-11) << "bin " << b;
  }
  EXPECT_GE(bins, 3);  // random placement spreads phi over several bins
  EXPECT_EQ(count, static_cast<double>(s.count));
  ASSERT_EQ(res.samples[col].size(), static_cast<std::size_t>(s.count));
  for (const filter::Sample& smp : res.samples[col]) {
    const auto i = static_cast<std::size_t>(smp.id);
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(smp.slip[a], s.fluid_velocity[3 * i + a] - s.velocity[3 * i + a], 1e-13);
      EXPECT_NEAR(smp.grad_p_filtered[a], s.pressure_gradient[3 * i + a], 1e-9 * 50 / 2.5e-4);
    }
  }
  // a coarser grid mixes cells: its H is not zero (the test can fail)
  const filter::FilterPlan coarse = plan_with_grids(s, {{3, 4, 3}});
  const filter::SnapshotResult rc = filter::filter_snapshot(s, coarse, o, 0, 0);
  double num = 0, mic = 0;
  for (std::size_t b = 0; b < nb; ++b) num += rc.sums[col * nb + b].numerator, mic += rc.sums[col * nb + b].micro;
  EXPECT_GT(std::abs(1.0 - num / mic), 1e-3);
}

TEST(CoarseGridOperator, UniformFieldsOnAUniformLatticeGiveTheResolvedSlipAndHZero) {
  // Particles at every fine cell centre, uniform u, p = 0, uniform v: the fine and the coarse (half as
  // many cells per axis) deposits are uniform (the TSC weights of the lattice points around a coarse
  // cell sum to the same value in every cell), so phi~ = phi_i, u~ = u, grad p~ = 0: u_slip~ = u - v
  // exactly (1e-15 m/s) and H = 0 to round-off (1e-12).
  const PeriodicGrid g = grid_of(8, 12, 8, 2.5e-4);
  std::vector<double> x;
  for (int k = 0; k < 8; ++k)
    for (int j = 0; j < 12; ++j)
      for (int i = 0; i < 8; ++i)
        x.insert(x.end(), {(i + 0.5) * 2.5e-4, (j + 0.5) * 2.5e-4, (k + 0.5) * 2.5e-4});
  const schema::Snapshot s = coupled_snapshot(g, x, true, 1);
  const filter::FilterPlan plan = plan_with_grids(s, {{4, 6, 4}, {8, 12, 8}});
  filter::FilterOptions o;
  o.samples = 100000;
  const filter::SnapshotResult res = filter::filter_snapshot(s, plan, o, 0, 0);
  const std::size_t nb = plan.bin_edges.size() - 1;
  for (std::size_t col = plan.whole_box_column() + 1; col < plan.columns(); ++col) {
    int bins = 0;
    for (std::size_t b = 0; b < nb; ++b) {
      const filter::BinSums& bs = res.sums[col * nb + b];
      if (bs.count == 0) continue;
      ++bins;
      EXPECT_NEAR(1.0 - bs.numerator / bs.micro, 0.0, 1e-12);
    }
    EXPECT_EQ(bins, 1);
    for (const filter::Sample& smp : res.samples[col]) {
      EXPECT_NEAR(smp.slip[0], 0.01, 1e-15);
      EXPECT_NEAR(smp.slip[1], 0.21, 1e-15);
      EXPECT_NEAR(smp.grad_p_filtered[1], 0.0, 1e-12);
    }
  }
}


// ---- the drift-velocity closure's sums (cgd-filter --grids; docs/closure.md "The drift-velocity closure") ---------

/// Every cell's TSC weight of a point x on the periodic grid g, dense (file order), from bspline2 and the periodic
/// images: independent of core/tsc_kernel.hpp and core/tsc_grid.hpp.
std::vector<double> dense_weights(const PeriodicGrid& g, const double* x) {
  std::vector<double> axis[3];
  for (int a = 0; a < 3; ++a) {
    const int n = g.cells[a];
    axis[a].assign(static_cast<std::size_t>(n), 0.0);
    const double s = x[a] / g.spacing_m[a];
    for (int c = 0; c < n; ++c)
      for (int k = -2; k <= 2; ++k) axis[a][static_cast<std::size_t>(c)] += bspline2(s - (c + 0.5) - k * n);
  }
  std::vector<double> w(g.cell_count());
  for (int k = 0; k < g.cells[2]; ++k)
    for (int j = 0; j < g.cells[1]; ++j)
      for (int i = 0; i < g.cells[0]; ++i)
        w[g.index(i, j, k)] = axis[0][static_cast<std::size_t>(i)] * axis[1][static_cast<std::size_t>(j)] *
                              axis[2][static_cast<std::size_t>(k)];
  return w;
}

// Two particles in cell (1, 1, 1) of a 4^3 grid, A at its centre, B a quarter cell further along x (the case of
// tests/unit/test_drift.cpp DriftCoupler.CellMeanVelocityAndForceOfTwoParticlesInOneCellByHand): per axis the
// weights on cells 0, 1, 2 are aA = (1/8, 3/4, 1/8) and, along x for B, aB = (1/32, 11/16, 9/32); the y, z weights
// cancel in the mean, so every cell of column ix (iy, iz in 0..2) holds (aA vA + aB vB)/(aA + aB); a cell the two
// do not reach holds the grid's fluid velocity (zero cell slip there).
TEST(DriftSums, CellMeanVelocityOfTwoParticlesByHand) {
  const double h = 3e-4;
  filter::CoarseGrid c;
  c.cells_across = 4;
  c.grid = grid_of(4, 4, 4, h);
  schema::Snapshot s;
  s.count = 2;
  s.position = {1.5 * h, 1.5 * h, 1.5 * h, 1.75 * h, 1.5 * h, 1.5 * h};
  s.velocity = {0.0, -0.1, 0.0, 0.02, -0.3, 0.01};
  std::vector<double> fields(7 * c.grid.cell_count(), 0.0);
  for (std::size_t k = 0; k < c.grid.cell_count(); ++k) fields[7 * k + 1] = 0.5, fields[7 * k + 2] = -0.25;
  const std::vector<double> vbar = filter::coarse_cell_mean_velocity(s, c, fields);
  const double aA[3] = {1.0 / 8, 3.0 / 4, 1.0 / 8}, aB[3] = {1.0 / 32, 11.0 / 16, 9.0 / 32};
  for (int iz = 0; iz < 4; ++iz)
    for (int iy = 0; iy < 4; ++iy)
      for (int ix = 0; ix < 4; ++ix) {
        const std::size_t cell = c.grid.index(ix, iy, iz);
        const bool reached = ix < 3 && iy < 3 && iz < 3;
        for (int d = 0; d < 3; ++d) {
          const double expect = reached ? (aA[ix] * s.velocity[d] + aB[ix] * s.velocity[3 + d]) / (aA[ix] + aB[ix])
                                        : fields[7 * cell + 1 + d];
          EXPECT_NEAR(vbar[3 * cell + d], expect, 1e-15) << ix << " " << iy << " " << iz << " axis " << d;
        }
      }
}

// The drift sums of filter_snapshot against an independent sum over the particles: random particles with random
// velocities in random fluid fields (coupled_snapshot), a 3 x 4 x 3 coarse grid; vbar deposited and every field
// interpolated with dense_weights; per (phi bin, slip bin) the count, sum (M - N), sum beta s~_y, sum beta |s~| and
// the sums of phi~ and s_hat (1e-12 relative). And the identity the table rests on: summed over the slip bins,
// numerator = sum M - sum N of the grid's H_grid bin (nothing is out of the slip range here: slip bins to 20 u_t).
TEST(DriftSums, MatchAnIndependentSumOverTheParticles) {
  const PeriodicGrid g = grid_of(6, 8, 6, 2.5e-4);
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> U(0, 1);
  std::vector<double> x;
  for (int i = 0; i < 6 * 8 * 6 * 4; ++i)
    for (int a = 0; a < 3; ++a) x.push_back(U(rng) * g.edge_m(a));
  schema::Snapshot s = coupled_snapshot(g, x, false, 5);
  for (std::int64_t i = 0; i < s.count; ++i) s.velocity[3 * i] = 0.03 * (U(rng) - 0.5);  // velocities in x too
  filter::FilterPlan plan = plan_with_grids(s, {{3, 4, 3}});
  for (int m = 0; m <= 1000; ++m) plan.slip_edges.push_back(0.02 * m);
  filter::FilterOptions o;
  const filter::SnapshotResult res = filter::filter_snapshot(s, plan, o, 0, 0);
  const std::size_t nb = plan.bin_edges.size() - 1, ns = plan.slip_bins();
  ASSERT_EQ(res.drift.size(), nb * ns);
  EXPECT_EQ(res.drift_out_of_range.at(0), 0);

  const filter::CoarseGrid& cg = plan.runs[0].coarse[0];
  const PeriodicGrid& G = cg.grid;
  const double vp = std::numbers::pi / 6 * std::pow(75e-6, 3);
  const std::vector<double> fields = filter::coarse_grid_fields(s, cg, vp);
  std::vector<std::vector<double>> w(static_cast<std::size_t>(s.count));
  std::vector<double> mass(G.cell_count(), 0.0), mv(3 * G.cell_count(), 0.0);
  for (std::int64_t i = 0; i < s.count; ++i) {
    w[static_cast<std::size_t>(i)] = dense_weights(G, &s.position[3 * i]);
    for (std::size_t c = 0; c < G.cell_count(); ++c) {
      mass[c] += w[static_cast<std::size_t>(i)][c];
      for (int d = 0; d < 3; ++d) mv[3 * c + d] += w[static_cast<std::size_t>(i)][c] * s.velocity[3 * i + d];
    }
  }
  const BeetstraDrag law(1.3, 1.8e-5, 75e-6);
  const double u_t = plan.runs[0].physics.u_t_m_s;
  std::vector<filter::DriftSums> expect(nb * ns);
  std::vector<double> grid_micro(nb, 0.0), grid_numerator(nb, 0.0);
  for (std::int64_t i = 0; i < s.count; ++i) {
    const std::vector<double>& wi = w[static_cast<std::size_t>(i)];
    double phi = 0, u[3] = {0, 0, 0}, gp[3] = {0, 0, 0}, vbar[3] = {0, 0, 0};
    for (std::size_t c = 0; c < G.cell_count(); ++c) {
      phi += wi[c] * fields[7 * c];
      for (int d = 0; d < 3; ++d) {
        u[d] += wi[c] * fields[7 * c + 1 + d];
        gp[d] += wi[c] * fields[7 * c + 4 + d];
        vbar[d] += wi[c] * (mass[c] > 0 ? mv[3 * c + d] / mass[c] : fields[7 * c + 1 + d]);
      }
    }
    const double* v = &s.velocity[3 * i];
    const double slip[3] = {u[0] - v[0], u[1] - v[1], u[2] - v[2]};
    const double cell[3] = {u[0] - vbar[0], u[1] - vbar[1], u[2] - vbar[2]};
    const double beta = law.beta_p(phi, std::hypot(slip[0], slip[1], slip[2]));
    const double N = s.drag_coefficient[i] * (s.fluid_velocity[3 * i + 1] - v[1]) - s.pressure_gradient[3 * i + 1] + gp[1];
    const double shat = std::hypot(cell[0], cell[1], cell[2]) / u_t;
    const auto b = static_cast<std::size_t>(std::floor(phi / 0.01));
    const auto m = static_cast<std::size_t>(std::floor(shat / 0.02));
    ASSERT_LT(b, nb);
    ASSERT_LT(m, ns);
    filter::DriftSums& e = expect[b * ns + m];
    e.count += 1;
    e.numerator += beta * slip[1] - N;
    e.denominator += beta * cell[1];
    e.magnitude += beta * std::hypot(cell[0], cell[1], cell[2]);
    e.phi += phi;
    e.slip += shat;
    grid_micro[b] += beta * slip[1];
    grid_numerator[b] += N;
  }
  int bins = 0;
  const std::size_t col = plan.whole_box_column() + 1;
  for (std::size_t b = 0; b < nb; ++b) {
    double num = 0;
    for (std::size_t m = 0; m < ns; ++m) {
      const filter::DriftSums &got = res.drift[b * ns + m], &want = expect[b * ns + m];
      num += got.numerator;
      EXPECT_EQ(got.count, want.count) << "bin " << b << ", " << m;
      if (want.count == 0) continue;
      ++bins;
      const double scale = std::abs(want.magnitude) + 1e-300;
      EXPECT_NEAR(got.numerator, want.numerator, 1e-11 * scale) << "bin " << b << ", " << m;
      EXPECT_NEAR(got.denominator, want.denominator, 1e-11 * scale) << "bin " << b << ", " << m;
      EXPECT_NEAR(got.magnitude, want.magnitude, 1e-11 * scale);
      EXPECT_NEAR(got.phi, want.phi, 1e-12 * want.phi);
      EXPECT_NEAR(got.slip, want.slip, 1e-11 * want.slip);
    }
    const filter::BinSums& bs = res.sums[col * nb + b];
    EXPECT_NEAR(bs.micro, grid_micro[b], 1e-11 * (std::abs(grid_micro[b]) + 1));
    EXPECT_NEAR(num, bs.micro - bs.numerator, 1e-11 * (std::abs(bs.micro) + std::abs(bs.numerator) + 1e-300)) << b;
  }
  EXPECT_GE(bins, 6);  // the sums spread over several (phi, slip) bins
}

// Every particle with the same velocity: vbar = v in every cell it reaches, the cell slip is the particle's slip,
// so per phi bin the drift sums are those of H_grid: sum denominator = sum M, and numerator / denominator = H_grid.
TEST(DriftSums, UniformParticleVelocitiesGiveHGrid) {
  const PeriodicGrid g = grid_of(6, 8, 6, 2.5e-4);
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> U(0, 1);
  std::vector<double> x;
  for (int i = 0; i < 6 * 8 * 6 * 4; ++i)
    for (int a = 0; a < 3; ++a) x.push_back(U(rng) * g.edge_m(a));
  schema::Snapshot s = coupled_snapshot(g, x, false, 7);
  for (std::int64_t i = 0; i < s.count; ++i) s.velocity[3 * i] = 0.01, s.velocity[3 * i + 1] = -0.05, s.velocity[3 * i + 2] = 0;
  filter::FilterPlan plan = plan_with_grids(s, {{3, 4, 3}});
  for (int m = 0; m <= 300; ++m) plan.slip_edges.push_back(0.1 * m);
  const filter::SnapshotResult res = filter::filter_snapshot(s, plan, filter::FilterOptions{}, 0, 0);
  const std::size_t nb = plan.bin_edges.size() - 1, ns = plan.slip_bins(), col = plan.whole_box_column() + 1;
  EXPECT_EQ(res.drift_out_of_range.at(0), 0);
  int bins = 0;
  for (std::size_t b = 0; b < nb; ++b) {
    const filter::BinSums& bs = res.sums[col * nb + b];
    if (bs.count == 0) continue;
    double num = 0, den = 0;
    for (std::size_t m = 0; m < ns; ++m) num += res.drift[b * ns + m].numerator, den += res.drift[b * ns + m].denominator;
    EXPECT_NEAR(den, bs.micro, 1e-12 * std::abs(bs.micro)) << "bin " << b;
    EXPECT_NEAR(num / den, 1.0 - bs.numerator / bs.micro, 1e-10) << "bin " << b;
    ++bins;
  }
  EXPECT_GE(bins, 2);
}
}  // namespace
}  // namespace cgd
