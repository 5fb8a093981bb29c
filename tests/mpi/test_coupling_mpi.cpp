// Deposition over y-slabs: what every rank deposits, after the ghost planes are added to their
// owners, equals the serial deposition cell by cell to round-off (the sums run in a different order),
// and the total equals the number of particles (conservation of particle volume).
#include <gtest/gtest.h>
#include <mpi.h>

#include <random>

#include "sim/coupling/exchange.hpp"

namespace {

cgd::coupling::GridView slab_view(int ranks, int rank) {
  cgd::coupling::GridView g;
  g.cells = {8, 24, 6};
  g.spacing = {1e-3, 1e-3, 1e-3};
  g.j0 = g.cells[1] * rank / ranks;
  g.ny_local = g.cells[1] * (rank + 1) / ranks - g.j0;
  return g;
}

TEST(CouplingMpi, DepositionMatchesSerialAndConservesVolume) {
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const int n = 5000;
  std::vector<double> x(3 * n);
  for (int i = 0; i < n; ++i) {
    x[3 * i] = U(rng) * 8e-3;
    x[3 * i + 1] = U(rng) * 24e-3;
    x[3 * i + 2] = U(rng) * 6e-3;
  }
  auto deposit = [&](const cgd::coupling::GridView& g, MPI_Comm comm) {
    std::vector<double> f(g.storage_size(), 0.0);
    for (int i = 0; i < n; ++i) {
      const int j = static_cast<int>(x[3 * i + 1] / g.spacing[1]);
      if (j < g.j0 || j >= g.j0 + g.ny_local) continue;  // owned by this slab
      cgd::coupling::for_each_tsc_cell(g, &x[3 * i], [&](std::size_t idx, double w) { f[idx] += w; });
    }
    cgd::coupling::accumulate_ghosts(comm, g, {f.data()});
    return f;
  };
  const auto g = slab_view(size, rank);
  const auto mine = deposit(g, MPI_COMM_WORLD);
  double local = 0;
  for (int j = 0; j < g.ny_local; ++j)
    for (int k = 0; k < g.cells[2]; ++k)
      for (int i = 0; i < g.cells[0]; ++i) local += mine[g.index(i, j, k)];
  double total = 0;
  MPI_Allreduce(&local, &total, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_NEAR(total, n, 1e-10);  // 5000 particles x 27 weights: accumulated round-off ~1e-12
  const auto serial = deposit(slab_view(1, 0), MPI_COMM_SELF);
  const auto gs = slab_view(1, 0);
  double max_diff = 0;
  for (int j = 0; j < g.ny_local; ++j)
    for (int k = 0; k < g.cells[2]; ++k)
      for (int i = 0; i < g.cells[0]; ++i)
        max_diff = std::max(max_diff, std::abs(mine[g.index(i, j, k)] - serial[gs.index(i, g.j0 + j, k)]));
  EXPECT_LT(max_diff, 1e-13);  // cell values O(10): a few ulp from summation order
}

}  // namespace
