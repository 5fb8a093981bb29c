// The coupling grid replicated on every rank (sim/coupling/exchange.hpp): each rank deposits its particles,
// wherever they lie in y, on the whole grid; fold_ghost_rows and reduce_rows_to_owners give the owners' rows the
// serial deposition cell by cell to round-off (the sums run in another order) and the total equals the number of
// particles (conservation of particle volume); gather_rows gives every rank every row. Also against a hand answer.
#include <gtest/gtest.h>
#include <mpi.h>

#include <array>
#include <cmath>
#include <random>

#include "sim/coupling/exchange.hpp"

namespace {

using cgd::coupling::GridView;
using cgd::coupling::RowOwners;

GridView whole_view(std::array<int, 3> cells) {
  GridView g;
  g.cells = cells;
  g.spacing = {1e-3, 1e-3, 1e-3};
  g.j0 = 0;
  g.ny_local = cells[1];
  return g;
}

/// Rows of every rank as FFTW would split ny, but unequal: rank r owns ny (r/size)^1.2 .. ny ((r+1)/size)^1.2.
RowOwners uneven_rows(int ny, int size, int rank) {
  auto edge = [&](int r) { return static_cast<int>(std::lround(ny * std::pow(static_cast<double>(r) / size, 1.2))); };
  return RowOwners::gather(MPI_COMM_WORLD, edge(rank), edge(rank + 1) - edge(rank));
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
  const GridView g = whole_view({8, 24, 6});
  // the particles dealt to the ranks round-robin, unrelated to their height (as balanced DEM slabs may be)
  auto deposit = [&](MPI_Comm comm, int my_rank, int ranks, const RowOwners& rows) {
    std::vector<double> f(g.storage_size(), 0.0);
    for (int i = my_rank; i < n; i += ranks)
      cgd::coupling::for_each_tsc_cell(g, &x[3 * i], [&](std::size_t idx, double w) { f[idx] += w; });
    cgd::coupling::fold_ghost_rows(g, f.data(), 1);
    cgd::coupling::reduce_rows_to_owners(comm, g, rows, f.data(), 1);
    return f;
  };
  const RowOwners rows = uneven_rows(g.cells[1], size, rank);
  const auto mine = deposit(MPI_COMM_WORLD, rank, size, rows);
  const int j0 = rows.j0[rank], ny = rows.count[rank];
  double local = 0;
  for (int j = j0; j < j0 + ny; ++j)
    for (int k = 0; k < g.cells[2]; ++k)
      for (int i = 0; i < g.cells[0]; ++i) local += mine[g.index(i, j, k)];
  double total = 0;
  MPI_Allreduce(&local, &total, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_NEAR(total, n, 1e-10);  // 5000 particles x 27 weights: accumulated round-off ~1e-12
  const auto serial = deposit(MPI_COMM_SELF, 0, 1, RowOwners{{0}, {g.cells[1]}});
  double max_diff = 0;
  for (int j = j0; j < j0 + ny; ++j)
    for (int k = 0; k < g.cells[2]; ++k)
      for (int i = 0; i < g.cells[0]; ++i)
        max_diff = std::max(max_diff, std::abs(mine[g.index(i, j, k)] - serial[g.index(i, j, k)]));
  EXPECT_LT(max_diff, 1e-13);  // cell values O(10): a few ulp from summation order
  // gather_rows: every rank ends with every owner's rows, and periodic ghost rows
  std::vector<double> all = mine;
  cgd::coupling::gather_rows(MPI_COMM_WORLD, g, rows, all.data(), 1);
  double gathered_diff = 0;
  for (int j = -g.ghost; j < g.cells[1] + g.ghost; ++j)
    for (int k = 0; k < g.cells[2]; ++k)
      for (int i = 0; i < g.cells[0]; ++i) {
        const int jw = (j + g.cells[1]) % g.cells[1];
        gathered_diff = std::max(gathered_diff, std::abs(all[g.index(i, j, k)] - serial[g.index(i, jw, k)]));
      }
  EXPECT_LT(gathered_diff, 1e-13);
}

// A hand answer, 2 values per cell on a 2 x 5 x 1 grid: rank r puts (r + 1) x (10 j + i, 1) into every cell of
// every row j in [-2, 7) (ghosts included); after fold and reduce, row j holds S x (the row's own values plus
// those of the ghost rows wrapping to it), S = sum_r (r + 1) = size (size + 1) / 2; the gather then gives every
// rank every row, ghost rows the periodic copies.
TEST(CouplingMpi, FoldReduceGatherHandAnswer) {
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  const GridView g = whole_view({2, 5, 1});
  const int K = 2;
  std::vector<double> f(K * g.storage_size(), -1.0);
  for (int j = -2; j < 7; ++j)
    for (int i = 0; i < 2; ++i) {
      f[K * g.index(i, j, 0)] = (rank + 1) * (10.0 * j + i);
      f[K * g.index(i, j, 0) + 1] = rank + 1;
    }
  // rows: 5 rows over up to 3 ranks (2 ranks: 3 + 2; 3 ranks: 2 + 2 + 1)
  const int j0 = 5 * rank / size, j1 = 5 * (rank + 1) / size;
  const RowOwners rows = RowOwners::gather(MPI_COMM_WORLD, j0, j1 - j0);
  cgd::coupling::fold_ghost_rows(g, f.data(), K);
  for (int j : {-2, -1, 5, 6})
    for (int i = 0; i < 2; ++i) EXPECT_EQ(f[K * g.index(i, j, 0)], 0.0) << "a folded ghost row is zeroed";
  cgd::coupling::reduce_rows_to_owners(MPI_COMM_WORLD, g, rows, f.data(), K);
  const double S = size * (size + 1) / 2.0;
  auto expected = [&](int j, int i) {  // a row's own value plus its wrapped ghost rows' (rows 3, 4 get -2, -1; 0, 1 get 5, 6)
    double a = 10.0 * j + i, b = 1.0;
    if (j >= 3) a += 10.0 * (j - 5) + i, b += 1.0;
    if (j <= 1) a += 10.0 * (j + 5) + i, b += 1.0;
    return std::array<double, 2>{S * a, S * b};
  };
  for (int j = j0; j < j1; ++j)
    for (int i = 0; i < 2; ++i) {
      EXPECT_EQ(f[K * g.index(i, j, 0)], expected(j, i)[0]) << "row " << j << " cell " << i;
      EXPECT_EQ(f[K * g.index(i, j, 0) + 1], expected(j, i)[1]) << "row " << j << " cell " << i;
    }
  cgd::coupling::gather_rows(MPI_COMM_WORLD, g, rows, f.data(), K);
  for (int j = -2; j < 7; ++j)
    for (int i = 0; i < 2; ++i) {
      const int jw = (j + 5) % 5;
      EXPECT_EQ(f[K * g.index(i, j, 0)], expected(jw, i)[0]) << "row " << j << " cell " << i;
      EXPECT_EQ(f[K * g.index(i, j, 0) + 1], expected(jw, i)[1]) << "row " << j << " cell " << i;
    }
}

}  // namespace
