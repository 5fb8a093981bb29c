// One fluid step (explicit predictor + FFT-preconditioned PCG pressure + correction) on the paper's
// resolved grid, 32 x 128 x 32 cells of 250 um in air, with a realistic void fraction: random eps in
// [0.6, 1] smoothed over a few cells, drag B dt/rho_f up to 30 where eps = 0.6, and eps changing every
// step (two smooth fields with the same total alternate). Reported: cells per second, mean PCG
// iterations per step. Arguments: preconditioner (0 arithmetic mean, 2 diagonally scaled, 3 sandwich, the
// default; see sim/fluid/pressure.hpp), FFTW planning (0 ESTIMATE, the default, 1 MEASURE). Runs on
// MPI_COMM_WORLD (mpirun -np N bench/fluid_bench for the slab split).
#include <benchmark/benchmark.h>
#include <mpi.h>

#include <algorithm>
#include <random>
#include <vector>

#include "core/mpi_init.hpp"
#include "sim/fluid/solver.hpp"

namespace {

using cgd::fluid::FluidGrid;
using cgd::fluid::FluidSettings;
using cgd::fluid::FluidSolver;

constexpr std::array<int, 3> kCells{32, 128, 32};
constexpr double kH = 250e-6, kRho = 1.3, kDt = 2.9e-4;

/// Smooth random eps in [0.6, 1] on the global grid (same on every rank), (j, k, i) order.
std::vector<double> smooth_random_void_fraction(unsigned seed) {
  const int nx = kCells[0], ny = kCells[1], nz = kCells[2];
  std::vector<double> f(static_cast<std::size_t>(nx) * ny * nz), t(f.size());
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  for (double& v : f) v = uni(rng);
  auto at = [&](int i, int j, int k) {
    return ((static_cast<std::size_t>((j + ny) % ny) * nz + (k + nz) % nz) * nx) + (i + nx) % nx;
  };
  for (int pass = 0; pass < 4; ++pass)  // 3-point box filter in x, y and z, four times: ~3-cell blobs
    for (int d = 0; d < 3; ++d) {
      for (int j = 0; j < ny; ++j)
        for (int k = 0; k < nz; ++k)
          for (int i = 0; i < nx; ++i) {
            const int di = d == 0, dj = d == 1, dk = d == 2;
            t[at(i, j, k)] =
                (f[at(i - di, j - dj, k - dk)] + f[at(i, j, k)] + f[at(i + di, j + dj, k + dk)]) / 3.0;
          }
      f.swap(t);
    }
  const auto [lo, hi] = std::minmax_element(f.begin(), f.end());
  const double a = *lo, b = *hi;
  for (double& v : f) v = 0.6 + 0.4 * (v - a) / (b - a);
  return f;
}

void set_void_fraction(FluidSolver& s, const std::vector<double>& global_eps) {
  const FluidGrid& g = s.grid();
  auto& st = s.state();
  const std::size_t offset = static_cast<std::size_t>(g.j0()) * g.plane();
  std::copy(global_eps.begin() + offset, global_eps.begin() + offset + g.owned_size(),
            st.void_fraction.begin() + g.first_owned());
  const double B_max = 30.0 * kRho / kDt;  // B dt / rho_f = 30 at eps = 0.6
  for (std::size_t c = g.first_owned(); c < g.first_owned() + g.owned_size(); ++c)
    st.drag_coefficient[c] = B_max * (1.0 - st.void_fraction[c]) / 0.4;
}

void BM_FluidStep(benchmark::State& state) {
  FluidGrid grid(MPI_COMM_WORLD, kCells, {kCells[0] * kH, kCells[1] * kH, kCells[2] * kH});
  FluidSettings s;
  s.density_kg_m3 = kRho;
  s.viscosity_Pa_s = 1.8e-5;
  s.body_force_per_fluid_volume_N_m3 = {0.0, (kRho - (0.2 * 1500.0 + 0.8 * kRho)) * -9.81, 0.0};
  s.pressure.preconditioner = static_cast<cgd::fluid::Preconditioner>(state.range(0));
  s.pressure.fft_measure = state.range(1) != 0;
  FluidSolver solver(grid, s);
  // Two fields with the same sum: E1 = 0.7 E0 + 0.3 E0 shifted by one cell in y.
  const std::vector<double> e0 = smooth_random_void_fraction(3);
  std::vector<double> e1(e0.size());
  const std::size_t plane = grid.plane(), n = e0.size();
  for (std::size_t c = 0; c < n; ++c) e1[c] = 0.7 * e0[c] + 0.3 * e0[(c + plane) % n];
  // Particles settling at ~0.2 m/s with scatter.
  std::mt19937_64 rng(7 + grid.rank());
  std::normal_distribution<double> gauss(0.0, 0.05);
  auto& st = solver.state();
  for (int d = 0; d < 3; ++d)
    for (std::size_t c = grid.first_owned(); c < grid.first_owned() + grid.owned_size(); ++c)
      st.drag_velocity[d][c] = (d == 1 ? -0.2 : 0.0) + gauss(rng);
  set_void_fraction(solver, e0);
  solver.reset_history();
  long step = 0;
  for (int warm = 0; warm < 10; ++warm, ++step) {
    set_void_fraction(solver, step % 2 ? e0 : e1);
    solver.step(kDt);
  }
  long iterations = 0;
  for (auto _ : state) {
    set_void_fraction(solver, step % 2 ? e0 : e1);
    iterations += solver.step(kDt).pressure.iterations;
    ++step;
  }
  const double cells = static_cast<double>(grid.cells_total());
  state.counters["cells/s"] = benchmark::Counter(cells * state.iterations(), benchmark::Counter::kIsRate);
  state.counters["pcg_iter"] = static_cast<double>(iterations) / state.iterations();
  state.counters["continuity"] = solver.last_report().continuity_relative;
}
BENCHMARK(BM_FluidStep)
    ->ArgNames({"precond", "measure"})
    ->Args({0, 0})
    ->Args({2, 0})
    ->Args({3, 0})
    ->Args({3, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(40);  // fixed: every rank must run the same number of collective steps

/// Ranks other than 0 run the same collective steps silently.
class QuietReporter : public benchmark::BenchmarkReporter {
 public:
  bool ReportContext(const Context&) override { return true; }
  void ReportRuns(const std::vector<Run>&) override {}
};

}  // namespace

int main(int argc, char** argv) {
  cgd::init_mpi(&argc, &argv);
  benchmark::Initialize(&argc, argv);
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank == 0) {
    benchmark::RunSpecifiedBenchmarks();
  } else {
    QuietReporter quiet;
    benchmark::RunSpecifiedBenchmarks(&quiet);
  }
  benchmark::Shutdown();
  MPI_Finalize();
  return 0;
}
