// cgd-bench-filter: speed of the filter (filter/filter.hpp) on a snapshot of the paper's Table 1 size
// at phi = 0.05 (457k particles, 32 x 128 x 32 cells, 106 x 426 x 106 d_p), synthetic fields.
// Prints particle-width evaluations per second per core for each width alone (the cost must not
// depend on the width: summed-volume tables) and for five widths together, the table build time,
// the peak memory, and the filter's cost relative to the generator's for the same run.
// Usage: cgd-bench-filter [particles] [repeats]. Never asserted.
#include <mpi.h>
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>

#include "core/mpi_init.hpp"
#include "core/drag.hpp"
#include "filter/box_filter.hpp"
#include "filter/filter.hpp"

using namespace cgd;

namespace {
double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }
double peak_mib() {
  rusage r{};
  getrusage(RUSAGE_SELF, &r);
  return static_cast<double>(r.ru_maxrss) / 1024.0;
}
}  // namespace

int main(int argc, char** argv) {
  cgd::init_mpi(&argc, &argv);
  const long n_particles = argc > 1 ? std::atol(argv[1]) : 457000;
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 3;
  const double d = 75e-6, L[3] = {106 * d, 426 * d, 106 * d};
  schema::Snapshot s;
  s.has_fluid = true;
  s.grid.cells = {32, 128, 32};
  for (int a = 0; a < 3; ++a) s.grid.spacing_m[a] = L[a] / s.grid.cells[a];
  s.physics.diameter_m = d;
  s.physics.particle_density_kg_m3 = 1500;
  s.physics.fluid_density_kg_m3 = 1.3;
  s.physics.fluid_viscosity_Pa_s = 1.8e-5;
  s.physics.drag = "beetstra";
  s.physics.pressure_gradient_force = true;
  s.physics.u_t_m_s = 0.2185;
  s.physics.l_char_m = 3.02e-4;
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> U(0, 1);
  for (std::size_t c = 0; c < s.grid.cell_count(); ++c) {
    const double eps = 0.8 + 0.2 * U(rng);
    s.void_fraction.push_back(eps);
    for (int k = 0; k < 3; ++k) s.eps_velocity.push_back(eps * (U(rng) - 0.5));
    s.pressure.push_back(U(rng));
  }
  for (long i = 0; i < n_particles; ++i) {
    for (int a = 0; a < 3; ++a) {
      s.position.push_back(L[a] * U(rng));
      s.velocity.push_back(0.1 * (U(rng) - 0.5));
      s.fluid_velocity.push_back(0.1 * (U(rng) - 0.5));
      s.pressure_gradient.push_back(U(rng));
    }
    s.drag_coefficient.push_back(1e4 * (1 + U(rng)));
    s.id.push_back(i);
  }
  s.count = n_particles;
  filter::RunPlan run;
  run.physics = s.physics;
  run.grid = s.grid;
  const double h = s.grid.cell_size_m();
  const std::vector<double> widths = {h, 2 * h, 4 * h, 8 * h, 16 * h};
  auto plan_with = [&](std::vector<double> w) {
    filter::FilterPlan p;
    p.runs = {run};
    p.widths_m = std::move(w);
    p.whole_box_width_m = std::cbrt(L[0] * L[1] * L[2]);
    for (int b = 0; b <= 65; ++b) p.bin_edges.push_back(0.01 * b);
    return p;
  };
  filter::FilterOptions o;
  std::printf("cgd-bench-filter: %ld particles, %d x %d x %d cells (Table 1 at phi = 0.05), best of %d\n", n_particles,
              s.grid.cells[0], s.grid.cells[1], s.grid.cells[2], repeats);
  {
    const double t0 = now();
    const filter::PeriodicBoxFilter box(s.grid, s.void_fraction, s.eps_velocity, s.pressure, widths.back());
    std::printf("  summed-volume tables: %.3f s to build, %.1f MiB\n", now() - t0, static_cast<double>(box.bytes()) / 1048576.0);
  }
  std::printf("  %-22s %12s %14s %22s\n", "width", "seconds", "ns/particle", "particle-widths/s/core");
  auto time_plan = [&](const filter::FilterPlan& p, const char* label, double w_dp) {
    double best = 1e300;
    for (int r = 0; r < repeats; ++r) {
      const filter::SnapshotResult res = filter::filter_snapshot(s, p, o, 0, 0);
      best = std::min(best, res.seconds);
    }
    const double evaluations = static_cast<double>(n_particles) * static_cast<double>(p.widths_m.size() + 1);
    char name[64];
    if (w_dp > 0) std::snprintf(name, sizeof name, "%s %.1f d_p", label, w_dp);
    else std::snprintf(name, sizeof name, "%s", label);
    std::printf("  %-22s %12.3f %14.1f %22.3e\n", name, best, 1e9 * best / evaluations, evaluations / best);
    return best;
  };
  for (double w : widths) time_plan(plan_with({w}), "one width +whole box", w / d);
  const double all = time_plan(plan_with(widths), "five widths +whole box", 0);
  // The generator's cost for the same run (measured, bench/README.md): 2 h of wall time per simulated
  // second on 2 cores at phi = 0.05, one snapshot per t_ref = 0.0223 s.
  const double generator_core_s_per_snapshot = 2.0 * 3600.0 * 2.0 * 0.0223;
  std::printf("  filter cost per snapshot (five widths, without reading): %.2f core-s = %.2f %% of the generator's "
              "%.0f core-s per snapshot interval\n",
              all, 100.0 * all / generator_core_s_per_snapshot, generator_core_s_per_snapshot);
  std::printf("  peak memory: %.0f MiB (the snapshot's arrays %.0f MiB)\n", peak_mib(),
              static_cast<double>(n_particles) * 14 * 8 / 1048576.0 + s.grid.cell_count() * 5 * 8 / 1048576.0);
  MPI_Finalize();
  return 0;
}
