// The TSC particle<->grid kernel (core/tsc_kernel.hpp): partition of unity (conservation of
// deposited volume and force), continuity of the weights and of their slope when a particle crosses
// a cell face or a cell centre (smooth void fraction), and uniform deposition from a uniform lattice.
#include <gtest/gtest.h>

#include <random>

#include "sim/coupling/exchange.hpp"
#include "core/tsc_kernel.hpp"

namespace {

using cgd::tsc_weights;

TEST(CouplingKernel, WeightsArePartitionOfUnity) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> U(-5.0, 5.0);
  for (int t = 0; t < 1000; ++t) {
    const auto a = tsc_weights(U(rng), 0.0, 0.37);
    EXPECT_NEAR(a.w[0] + a.w[1] + a.w[2], 1.0, 4e-16);  // three terms of O(1): a few ulp
    for (double w : a.w) EXPECT_GE(w, 0.0);
  }
}

TEST(CouplingKernel, WeightsAndSlopeAreContinuousAcrossFacesAndCentres) {
  const double h = 1.0, eps = 1e-9;
  // a face at s = 2 (cell centres at 1.5 and 2.5) and a centre at s = 2.5
  for (double s : {2.0, 2.5}) {
    auto weight_on = [&](double x, int cell) {
      const auto a = tsc_weights(x, 0.0, h);
      const int k = cell - a.first;
      return (k >= 0 && k < 3) ? a.w[k] : 0.0;
    };
    for (int cell = 0; cell < 5; ++cell) {
      const double left = weight_on(s - eps, cell), right = weight_on(s + eps, cell);
      EXPECT_NEAR(left, right, 4 * eps) << "jump at s = " << s << " on cell " << cell;
      const double slope_l = (weight_on(s - eps, cell) - weight_on(s - 2 * eps, cell)) / eps;
      const double slope_r = (weight_on(s + 2 * eps, cell) - weight_on(s + eps, cell)) / eps;
      EXPECT_NEAR(slope_l, slope_r, 1e-5) << "kink at s = " << s << " on cell " << cell;
    }
  }
}

TEST(CouplingKernel, UniformLatticeDepositsUniformly) {
  // one particle per cell at an arbitrary common offset: every cell receives exactly one particle's
  // worth (sum of the three weights), whatever the offset
  cgd::coupling::GridView g;
  g.cells = {6, 8, 5};
  g.spacing = {1.0, 2.0, 0.5};
  g.j0 = 0;
  g.ny_local = 8;
  std::vector<double> field(g.storage_size(), 0.0);
  for (int k = 0; k < 5; ++k)
    for (int j = 0; j < 8; ++j)
      for (int i = 0; i < 6; ++i) {
        const double x[3] = {(i + 0.3) * 1.0, (j + 0.8) * 2.0, (k + 0.55) * 0.5};
        cgd::coupling::for_each_tsc_cell(g, x, [&](std::size_t idx, double w) { field[idx] += w; });
      }
  cgd::coupling::fold_ghost_rows(g, field.data(), 1);
  for (int k = 0; k < 5; ++k)
    for (int j = 0; j < 8; ++j)
      for (int i = 0; i < 6; ++i) EXPECT_NEAR(field[g.index(i, j, k)], 1.0, 1e-14);
}

}  // namespace

// The kept stencil (issue 17: computed once per fluid step) gives the kernel's cells, order and weights bit
// for bit, particles outside the box in x and z (unwrapped positions) and near the slab's faces included.
TEST(CouplingKernel, KeptStencilMatchesTheKernelBitForBit) {
  cgd::coupling::GridView g;
  g.cells = {5, 12, 4};
  g.spacing = {0.31, 0.27, 0.45};
  g.j0 = 3;
  g.ny_local = 6;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> ux(-0.4, 5 * 0.31 + 0.4), uy(3 * 0.27 + 1e-3, 9 * 0.27 - 1e-3),
      uz(-0.5, 4 * 0.45 + 0.5);
  for (int t = 0; t < 2000; ++t) {
    const double x[3] = {ux(rng), uy(rng), uz(rng)};
    std::vector<std::pair<std::size_t, double>> a, b;
    cgd::coupling::for_each_tsc_cell(g, x, [&](std::size_t c, double w) { a.emplace_back(c, w); });
    const cgd::coupling::Stencil st = cgd::coupling::make_stencil(g, x);
    cgd::coupling::for_each_stencil_cell(g, st, [&](std::size_t c, double w) { b.emplace_back(c, w); });
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t k = 0; k < a.size(); ++k) {
      EXPECT_EQ(a[k].first, b[k].first);
      EXPECT_EQ(a[k].second, b[k].second);  // exact
    }
  }
}
