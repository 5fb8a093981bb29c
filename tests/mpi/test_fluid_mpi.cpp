// Fluid solver on y-slabs: the same variable-eps problem (moving eps in [0.4, 1], drag up to
// B dt/rho_f = 30, sedimentation body force) on all ranks of MPI_COMM_WORLD and serially on rank 0.
// The parallel run is not bit-identical to the serial one: FFTW-MPI transposes and the global sums of
// PCG's dot products add the same numbers in a different order. With the pressure solved down to its
// round-off floor (tolerance 1e-13), that difference stays at round-off: the fields must agree to
// 1e-12 of their maximum.
#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "sim/fluid/solver.hpp"
#include "tests/unit/fluid_test_util.hpp"

namespace {

using cgd::fluid::FluidGrid;
using cgd::fluid::FluidSettings;
using cgd::fluid::FluidSolver;
using cgd::fluid::test::fill_cells;
using cgd::fluid::test::fill_faces;
constexpr double kPi = std::numbers::pi;

/// The variable-eps problem of tests/unit/test_fluid.cpp, on any grid.
struct Problem {
  std::array<int, 3> cells;
  double h = 250e-6, rho = 1.3, mu = 1.8e-5, dt = 2.9e-4;
  std::array<double, 3> box() const { return {cells[0] * h, cells[1] * h, cells[2] * h}; }
  double eps_at(double x, double y, double z, int level) const {
    const auto L = box();
    return 0.7 + 0.3 * std::sin(2 * kPi * x / L[0]) * std::cos(2 * kPi * (y + 0.1 * h * level) / L[1]) *
                     std::cos(2 * kPi * z / L[2] + 0.4);
  }
  void set_level(FluidSolver& s, int level) const {
    const FluidGrid& g = s.grid();
    auto& st = s.state();
    fill_cells(g, st.void_fraction, [&](double x, double y, double z) { return eps_at(x, y, z, level); });
    for (std::size_t c = g.first_owned(); c < g.first_owned() + g.owned_size(); ++c)
      st.drag_coefficient[c] = 30.0 * rho / dt * (1.0 - st.void_fraction[c]) / 0.6;
    fill_cells(g, st.drag_velocity[1],
               [&](double x, double, double) { return -0.25 + 0.05 * std::sin(2 * kPi * x / box()[0]); });
  }
  /// Run `steps` steps on `comm`; returns u_x, u_y, u_z, p of the owned cells gathered on rank 0 of comm
  /// in global (j, k, i) order, each block of n_cells values.
  std::vector<double> run(MPI_Comm comm, int steps) const {
    FluidGrid grid(comm, cells, box());
    FluidSettings s;
    s.density_kg_m3 = rho;
    s.viscosity_Pa_s = mu;
    s.body_force_per_fluid_volume_N_m3 = {0.0, (rho - (0.3 * 1500.0 + 0.7 * rho)) * -9.81, 0.0};
    s.pressure.tolerance = 1e-13;  // down to the round-off floor, see the file comment
    FluidSolver solver(grid, s);
    const auto L = box();
    set_level(solver, 0);
    fill_faces(grid, 0, solver.state().velocity[0], [&](double, double y, double z) {
      return 0.1 * std::sin(2 * kPi * y / L[1]) * std::cos(2 * kPi * z / L[2]);
    });
    fill_faces(grid, 1, solver.state().velocity[1], [&](double x, double, double z) {
      return -0.2 + 0.1 * std::cos(2 * kPi * x / L[0]) * std::sin(2 * kPi * z / L[2]);
    });
    solver.reset_history();
    for (int level = 1; level <= steps; ++level) {
      set_level(solver, level);
      const auto rep = solver.step(dt);
      EXPECT_LT(rep.continuity_relative, 1e-12);
    }
    int rank = 0, size = 1;
    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &size);
    const int owned = static_cast<int>(grid.owned_size());
    std::vector<int> counts(size), displs(size, 0);
    MPI_Allgather(&owned, 1, MPI_INT, counts.data(), 1, MPI_INT, comm);
    for (int r = 1; r < size; ++r) displs[r] = displs[r - 1] + counts[r - 1];
    const std::size_t n = static_cast<std::size_t>(grid.cells_total());
    std::vector<double> out(rank == 0 ? 4 * n : 0);
    const auto& st = solver.state();
    const std::vector<double>* fields[4] = {&st.velocity[0], &st.velocity[1], &st.velocity[2], &st.pressure};
    for (int f = 0; f < 4; ++f)
      MPI_Gatherv(fields[f]->data() + grid.first_owned(), owned, MPI_DOUBLE,
                  rank == 0 ? out.data() + f * n : nullptr, counts.data(), displs.data(), MPI_DOUBLE, 0,
                  comm);
    return out;
  }
};

void compare_world_with_serial(const Problem& pb, int steps) {
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  const auto parallel = pb.run(MPI_COMM_WORLD, steps);
  if (rank != 0) return;
  const auto serial = pb.run(MPI_COMM_SELF, steps);
  ASSERT_EQ(parallel.size(), serial.size());
  const std::size_t n = serial.size() / 4;
  const char* names[4] = {"u_x", "u_y", "u_z", "p"};
  for (int f = 0; f < 4; ++f) {
    double scale = 0.0, diff = 0.0;
    for (std::size_t c = f * n; c < (f + 1) * n; ++c) {
      scale = std::max(scale, std::abs(serial[c]));
      diff = std::max(diff, std::abs(parallel[c] - serial[c]));
    }
    std::printf("[ 1 vs N ranks ] %s: max |diff| / max = %.2e\n", names[f], diff / scale);
    EXPECT_LE(diff, 1e-12 * scale) << names[f];
  }
}

TEST(FluidMpi, SlabsAreFftwBlocksAndTileTheGrid) {
  const std::array<int, 3> cells{8, 33, 6};
  FluidGrid grid(MPI_COMM_WORLD, cells, {1.0, 3.3, 0.6});
  const auto rows = FluidGrid::fftw_slab_rows(MPI_COMM_WORLD, cells);
  EXPECT_EQ(rows.j0, grid.j0());
  EXPECT_EQ(rows.count, grid.ny_local());
  EXPECT_DOUBLE_EQ(grid.y_lo_m(), grid.j0() * 0.1);
  int total = grid.ny_local(), next_j0 = 0;
  MPI_Allreduce(MPI_IN_PLACE, &total, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_EQ(total, 33);
  // Slab r + 1 starts where slab r ends.
  const int end = grid.j0() + grid.ny_local();
  MPI_Sendrecv(&end, 1, MPI_INT, grid.up(), 5, &next_j0, 1, MPI_INT, grid.down(), 5, MPI_COMM_WORLD,
               MPI_STATUS_IGNORE);
  EXPECT_EQ(grid.rank() == 0 ? 33 : grid.j0(), next_j0);
}

// The spectral side is distributed over k_z (FFTW_MPI_TRANSPOSED_OUT): the eigenvalue table must follow
// that layout on every rank, or the constant-coefficient solve would no longer be exact (1 iteration).
TEST(FluidMpi, FftPreconditionerIsExactOnSlabs) {
  FluidGrid grid(MPI_COMM_WORLD, {10, 12, 9}, {1.0, 1.3, 0.8});
  cgd::fluid::PressureSettings ps;
  ps.tolerance = 1e-12;
  cgd::fluid::PressureSolver solver(grid, ps);
  std::array<std::vector<double>, 3> K{grid.make_field(2.5), grid.make_field(2.5), grid.make_field(2.5)};
  std::vector<double> b = grid.make_field(), p = grid.make_field();
  fill_cells(grid, b, [](double x, double y, double z) {
    return std::sin(2 * kPi * x + 0.3) * std::cos(2 * kPi * y / 1.3) + std::sin(4 * kPi * z / 0.8 + 1.0) * x;
  });
  const auto st = solver.solve(K, b, p);
  EXPECT_LE(st.iterations, 1);
  EXPECT_LT(st.residual, 1e-12);
}

TEST(FluidMpi, VariableVoidFractionMatchesSerial) {
  compare_world_with_serial(Problem{{16, 32, 16}}, 5);
}

TEST(FluidMpi, UnevenSlabsMatchSerial) {
  compare_world_with_serial(Problem{{12, 33, 10}}, 4);
}

}  // namespace
