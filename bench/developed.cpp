// cgd-bench-developed: the engine's speed in the developed (clustered) state of a sedimenting
// suspension, by phase, and the wall time it projects for the Table 1 runs. Figures only; never
// asserted anywhere (bench/README.md, "Developed state").
//
//   cgd-bench-developed [--scene data/scenes/table1_phi005.toml] [--base 4] [--tile 4]
//                       [--develop-tref 8] [--warmup 2] [--fluid-steps 10] [--cache DIR] [--set KEY=VALUE]...
//   cgd-bench-developed --from-run RUN_DIR ...       (the state of a run's own checkpoint, e.g. a Table 1
//                                                     run stopped with SIGTERM after its clusters formed)
//   mpirun -np 2 ... cgd-bench-developed ...         (2 ranks; bench/developed.sh runs both)
//
// Why: a run from rest (cgd-bench-coupled) times a homogeneous suspension; a developed one has
// clusters (contacts, fast particles, more list rebuilds) and a Courant-bound fluid step, and costs
// more per particle-step. Developing the Table 1 box itself takes hours, so:
//   1. develop (once, cached): the scene's box shrunk by `base` in every direction (the Table 1
//      phi = 0.05 box / 4 = 26.5 x 106.5 x 26.5 d_p, 8 x 32 x 8 cells, ~7,100 particles) is run
//      with cgd::run_scene (the generator's driver) for `develop-tref` t_ref from rest; its final
//      checkpoint is kept under the cache directory (default $CGD_BENCH_CACHE, else
//      $XDG_CACHE_HOME/cgd-bench, else ~/.cache/cgd-bench), keyed by the small scene's text;
//   2. tile: every rank reads that checkpoint and tiles it `tile` times in each direction
//      (positions, velocities, spins, tangential springs -- partners re-identified through the
//      periodic images --, fluid velocity, pressure, eps_old and the AB2 history), which gives a
//      clustered state of the box `tile/base` times the scene's (4/4: the Table 1 box itself); each
//      rank keeps the particles of its first (equal) slab, and the first list rebuild balances the slabs;
//   3. time: warm-up fluid steps, then `fluid-steps` coupled steps (the run's loop: prepare, deposit
//      and drag, fluid step, particle forces, DEM sub-steps) with the engine's phase timers. No
//      output, no series rows (their cost is in bench/README.md's coupled figures).
// Printed: particle-steps/s/core, CPU-ns per particle-step per phase (seconds summed over ranks /
// particle-steps), DEM steps per neighbour-list rebuild, the fluid step, and the projected hours of
// each Table 1 run (data/scenes/table1_*.toml: 1.11 s each) and each PROFILE=half resolved run
// (Makefile.pipeline: 53 x 213 x 53 d_p, 50 t_ref, phi = 0.02-0.40) at this rank count, assuming the
// measured cost per particle-step and per fluid step (the same 32 x 128 x 32 grid) and the measured
// fluid step -- a proxy for the denser scenes, whose clusters have more contacts.
// The tiled small box is calmer than the Table 1 box developed in place (issue 17, third round: 35 DEM
// steps per rebuild against 12 in the real run at 7 t_ref, its larger clusters fall and rise faster):
// --from-run times the real state; the projection then is that state's.
// Under valgrind --tool=callgrind --instr-atstart=no only the timed steps are instrumented.
#include <mpi.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#define CGD_CALLGRIND_START() CALLGRIND_START_INSTRUMENTATION
#define CGD_CALLGRIND_STOP() CALLGRIND_STOP_INSTRUMENTATION
#else
#define CGD_CALLGRIND_START() (void)0
#define CGD_CALLGRIND_STOP() (void)0
#endif

#include "core/mpi_init.hpp"
#include "core/schema/checkpoint.hpp"
#include "core/cli.hpp"
#include "core/error.hpp"
#include "core/scene.hpp"
#include "core/timers.hpp"
#include "core/version.hpp"
#include "sim/coupled_step.hpp"
#include "sim/dem/system.hpp"
#include "sim/fluid/grid.hpp"
#include "sim/run.hpp"

namespace fs = std::filesystem;

namespace {

std::string fmt_vec(const std::array<double, 3>& v) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "[%.17g, %.17g, %.17g]", v[0], v[1], v[2]);
  return buf;
}
std::string fmt_cells(const std::array<int, 3>& c) {
  return "[" + std::to_string(c[0]) + ", " + std::to_string(c[1]) + ", " + std::to_string(c[2]) + "]";
}

fs::path cache_root() {
  if (const char* c = std::getenv("CGD_BENCH_CACHE"); c && *c) return c;
  if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x) return fs::path(x) / "cgd-bench";
  if (const char* h = std::getenv("HOME"); h && *h) return fs::path(h) / ".cache" / "cgd-bench";
  return fs::temp_directory_path() / "cgd-bench-cache";
}

/// FNV-1a of a text: the cache key of a small scene.
std::string text_hash(const std::string& s) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : s) h = (h ^ c) * 1099511628211ull;
  char buf[32];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

int floor_mod(int a, int n) { return ((a % n) + n) % n; }

}  // namespace

int main(int argc, char** argv) {
  cgd::init_mpi(&argc, &argv);
  const int status = cgd::run_tool([&] {
    CLI::App app{"Developed-state engine benchmark: cost per particle-step by phase, projected Table 1 hours"};
    std::string scene_path = std::string(CGD_SOURCE_DIR) + "/data/scenes/table1_phi005.toml";
    int base = 4, tile = 4, warmup = 2, fluid_steps = 10;
    double develop_tref = 8;
    std::string cache, from_run;
    std::vector<std::string> sets;
    bool no_projection = false;
    app.add_option("--scene", scene_path, "the scene whose box is developed small and tiled (default table1_phi005)");
    app.add_option("--base", base, "the developed box is the scene's divided by this in every direction");
    app.add_option("--tile", tile, "copies of the developed box in every direction (tile = base: the scene's box)");
    app.add_option("--develop-tref", develop_tref, "t_ref the small box runs from rest (once; cached)");
    app.add_option("--warmup", warmup, "fluid steps run first and not timed");
    app.add_option("--fluid-steps", fluid_steps, "fluid (coupled) steps timed");
    app.add_option("--cache", cache, "cache directory of developed states");
    app.add_flag("--no-projection", no_projection, "do not print the Table 1 projection");
    app.add_option("--from-run", from_run,
                   "time the state of a run's own checkpoint (RUN_DIR/checkpoint.h5 and its scene.toml) instead of a "
                   "developed small box tiled: the real developed state of a Table 1 run (--base, --tile ignored)");
    app.add_option("--set", sets, "KEY=VALUE overrides of the timed scene (e.g. contact.skin_over_dp=0.3)");
    cgd::parse_command_line(app, argc, argv, "cgd-bench-developed");
    if (!from_run.empty()) {
      scene_path = (fs::path(from_run) / "scene.toml").string();
      base = tile = 1;
    }
    if (base < 1 || tile < 1 || warmup < 0 || fluid_steps < 1 || !(develop_tref > 0))
      throw cgd::InputError("--base, --tile, --fluid-steps >= 1, --warmup >= 0, --develop-tref > 0");
    int rank = 0, ranks = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &ranks);

    // ---- 1. the small box, developed once -------------------------------------------------------
    const cgd::Scene full = cgd::load_scene(scene_path, {});
    if (!full.solves_fluid()) throw cgd::InputError(scene_path + ": the scene solves no fluid");
    std::array<double, 3> small_dp{};
    std::array<int, 3> small_cells{};
    for (int d = 0; d < 3; ++d) {
      small_dp[d] = full.domain.size_m[d] / full.particles.diameter_m / base;
      if (full.derived.cells[d] % base != 0)
        throw cgd::InputError("--base " + std::to_string(base) + " does not divide the scene's cells " +
                              fmt_cells(full.derived.cells));
      small_cells[d] = full.derived.cells[d] / base;
    }
    char buf[200];
    std::vector<std::string> small_set = {"domain.size_dp=" + fmt_vec(small_dp), "fluid.cells=" + fmt_cells(small_cells),
                                          "run.dump_interval_tref=0.0", "run.checkpoint_wall_s=1e9"};
    std::snprintf(buf, sizeof buf, "run.end_time_tref=%.17g", develop_tref);
    small_set.push_back(buf);
    const cgd::Scene small = cgd::load_scene(scene_path, small_set);
    const fs::path dev_dir = !from_run.empty() ? fs::path(from_run)
                                               : (cache.empty() ? cache_root() : fs::path(cache)) /
                                                     ("developed_" + full.name + "_" + text_hash(small.effective_toml));
    int have = rank == 0 && (!from_run.empty() || fs::exists(dev_dir / "DONE")) && fs::exists(dev_dir / "checkpoint.h5")
                   ? 1
                   : 0;
    MPI_Bcast(&have, 1, MPI_INT, 0, MPI_COMM_WORLD);
    if (!have && !from_run.empty())
      throw cgd::InputError((dev_dir / "checkpoint.h5").string() + ": no checkpoint (--from-run wants the directory of "
                            "a run that wrote one: SIGTERM a cgd-generate run, or wait for its checkpoint_wall_s)");
    if (!have) {
      if (rank == 0) {
        std::printf("developing %s: %lld particles, %.4g x %.4g x %.4g d_p, %d x %d x %d cells, %.3g t_ref from rest "
                    "(once; cached in %s)\n",
                    full.name.c_str(), static_cast<long long>(small.derived.particle_count), small_dp[0], small_dp[1],
                    small_dp[2], small_cells[0], small_cells[1], small_cells[2], develop_tref, dev_dir.c_str());
        std::fflush(stdout);
        fs::remove_all(dev_dir);
        fs::create_directories(dev_dir.parent_path());
      }
      MPI_Barrier(MPI_COMM_WORLD);
      cgd::RunSettings rs;
      rs.output_dir = dev_dir.string();
      rs.quiet = true;
      rs.tool = "cgd-bench-developed";
      const double t0 = cgd::wall_seconds();
      {
        std::ostringstream sink;
        std::streambuf* old = std::cout.rdbuf(sink.rdbuf());
        try {
          cgd::run_scene(small, rs, MPI_COMM_WORLD);
        } catch (...) {
          std::cout.rdbuf(old);
          throw;
        }
        std::cout.rdbuf(old);
      }
      if (rank == 0) std::printf("developed in %.0f s\n", cgd::wall_seconds() - t0);
    }

    // ---- 2. the tiled state ---------------------------------------------------------------------
    std::array<double, 3> tiled_dp{};
    std::array<int, 3> tiled_cells{};
    for (int d = 0; d < 3; ++d) {
      tiled_dp[d] = small_dp[d] * tile;
      tiled_cells[d] = small_cells[d] * tile;
    }
    cgd::checkpoint::Reader reader((dev_dir / "checkpoint.h5").string(), MPI_COMM_WORLD);
    std::int64_t n0 = 0, c0 = 0;
    for (auto c : reader.rank_particle_counts()) n0 += c;
    for (auto c : reader.rank_contact_counts()) c0 += c;
    const bool rotation = reader.has_angular_velocity();
    const cgd::checkpoint::ParticleData d0 = reader.particles(0, n0, 0, c0, rotation);
    const std::int64_t nt = n0 * tile * tile * tile;
    // the tiled scene holds exactly nt particles: its solids fraction is the small box's actual one
    const double small_volume = small.domain.size_m[0] * small.domain.size_m[1] * small.domain.size_m[2];
    const double phi0 = static_cast<double>(n0) * small.derived.particle_volume_m3 / small_volume;
    std::vector<std::string> tiled_set = {"domain.size_dp=" + fmt_vec(tiled_dp), "fluid.cells=" + fmt_cells(tiled_cells)};
    std::snprintf(buf, sizeof buf, "particles.solids_fraction=%.17g", phi0);
    tiled_set.push_back(buf);
    tiled_set.insert(tiled_set.end(), sets.begin(), sets.end());
    const cgd::Scene scene = cgd::load_scene(scene_path, tiled_set);
    if (scene.derived.particle_count != nt)
      throw cgd::RunError("tiled scene: " + std::to_string(scene.derived.particle_count) + " particles, tiles hold " +
                          std::to_string(nt));

    cgd::fluid::FluidGrid grid(MPI_COMM_WORLD, scene.derived.cells, scene.domain.size_m);
    const cgd::dem::DemSettings ds = cgd::dem_settings_from_scene(scene);  // balanced slabs, as the engine's
    cgd::dem::DemSystem dem(ds, MPI_COMM_WORLD);
    cgd::PhaseTimers run_timers;
    cgd::CoupledStep coupled(scene, grid, ds.dt_s, run_timers);

    // particles: wrap the small box's state, index it by id, then tile (ids a + n0 * tile index)
    const std::array<double, 3> L0 = small.domain.size_m, L = scene.domain.size_m;
    std::vector<double> xw(d0.position);
    std::int64_t max_id = 0;
    for (std::int64_t i = 0; i < n0; ++i) {
      for (int d = 0; d < 3; ++d) {
        double& q = xw[3 * i + d];
        q -= L0[d] * std::floor(q / L0[d]);
        if (q >= L0[d]) q = 0.0;
      }
      max_id = std::max(max_id, d0.id[i]);
    }
    std::vector<std::int64_t> index_of(static_cast<std::size_t>(max_id) + 1, -1);
    for (std::int64_t i = 0; i < n0; ++i) index_of[d0.id[i]] = i;
    std::vector<std::int64_t> contact_first(n0 + 1, 0);
    for (std::int64_t i = 0; i < n0; ++i) contact_first[i + 1] = contact_first[i] + d0.contact_count[i];
    std::vector<std::int64_t> ids;
    std::vector<double> x, v, w;
    cgd::dem::ContactStore store;
    store.offset.assign(1, 0);
    const double y_lo = dem.slabs().y_lo(), y_hi = dem.slabs().y_hi();
    for (int tz = 0; tz < tile; ++tz)
      for (int ty = 0; ty < tile; ++ty)
        for (int tx = 0; tx < tile; ++tx) {
          const int t[3] = {tx, ty, tz};
          const std::int64_t tile_index = (static_cast<std::int64_t>(tz) * tile + ty) * tile + tx;
          for (std::int64_t i = 0; i < n0; ++i) {
            double q[3];
            for (int d = 0; d < 3; ++d) q[d] = xw[3 * i + d] + t[d] * L0[d];
            dem.slabs().wrap(q);
            if (q[1] < y_lo || q[1] >= y_hi) continue;
            ids.push_back(d0.id[i] + n0 * tile_index);
            x.insert(x.end(), q, q + 3);
            v.insert(v.end(), &d0.velocity[3 * i], &d0.velocity[3 * i + 3]);
            if (rotation) w.insert(w.end(), &d0.angular_velocity[3 * i], &d0.angular_velocity[3 * i + 3]);
            for (std::int64_t k = contact_first[i]; k < contact_first[i + 1]; ++k) {
              const std::int64_t j = index_of[d0.partner[k]];
              int pt[3];
              for (int d = 0; d < 3; ++d) {
                const double dx = xw[3 * j + d] - xw[3 * i + d];
                pt[d] = t[d] + (dx > 0.5 * L0[d] ? -1 : dx < -0.5 * L0[d] ? 1 : 0);
                pt[d] = floor_mod(pt[d], tile);
              }
              const std::int64_t ptile = (static_cast<std::int64_t>(pt[2]) * tile + pt[1]) * tile + pt[0];
              store.partner.push_back(d0.partner[k] + n0 * ptile);
              store.xi.insert(store.xi.end(), &d0.spring[3 * k], &d0.spring[3 * k + 3]);
            }
            store.offset.push_back(static_cast<std::int64_t>(store.partner.size()));
          }
        }
    (void)L;
    dem.set_particles(std::move(ids), std::move(x), std::move(v), std::move(w));
    dem.restore(std::move(store), {}, true, reader.state().step, -1);  // -1: sort by cell at the first rebuild

    // fluid: the small box's fields (global y, z, x order), tiled over this rank's rows
    {
      const std::int64_t cells0 = static_cast<std::int64_t>(small_cells[0]) * small_cells[1] * small_cells[2];
      cgd::fluid::FluidState& st = coupled.fluid().state();
      std::array<std::vector<double>*, cgd::checkpoint::kFluidFieldNames.size()> fields = {
          &st.velocity[0],       &st.velocity[1],          &st.velocity[2],          &st.pressure,
          &st.void_fraction_old, &st.explicit_rate_old[0], &st.explicit_rate_old[1], &st.explicit_rate_old[2]};
      std::vector<double> f0(static_cast<std::size_t>(cells0));
      for (std::size_t k = 0; k < fields.size(); ++k) {
        reader.read_fluid_field(k, 0, cells0, f0.data());
        for (int j = 0; j < grid.ny_local(); ++j)
          for (int kz = 0; kz < tiled_cells[2]; ++kz)
            for (int i = 0; i < tiled_cells[0]; ++i) {
              const int jj = (grid.j0() + j) % small_cells[1], kk = kz % small_cells[2], ii = i % small_cells[0];
              (*fields[k])[grid.index(i, j, kz)] =
                  f0[(static_cast<std::size_t>(jj) * small_cells[2] + kk) * small_cells[0] + ii];
            }
      }
      st.dt_previous_s = reader.fluid_dt_previous_s();
      coupled.set_fluid_steps(std::max<std::int64_t>(1, reader.fluid_steps()));
      grid.exchange_ghosts({st.velocity[0].data(), st.velocity[1].data(), st.velocity[2].data(), st.pressure.data(),
                            st.void_fraction_old.data()});
    }
    reader.close();

    // ---- 3. time ----------------------------------------------------------------------------------
    // the run's coupled loop (sim/run.cpp time_loop_coupled) without output: fluid steps of the
    // Courant length (one snapshot interval divided evenly, as the run does)
    const std::int64_t dump_steps = std::llround(full.run.dump_interval_s / ds.dt_s);
    auto fluid_step = [&] {
      dem.prepare();
      coupled.begin(dem.particles());
      const std::int64_t step = dem.step_index();
      const std::int64_t n_sub = coupled.substeps(step, std::max<std::int64_t>(1, dump_steps));
      coupled.advance(dem, n_sub, [] {});
      return n_sub;
    };
    for (int s = 0; s < warmup; ++s) fluid_step();
    const std::vector<double> dem0 = dem.timers().all_seconds(), run0 = run_timers.all_seconds();
    const std::int64_t step0 = dem.step_index(), rebuilds0 = dem.rebuilds();
    const std::size_t entries0 = dem.neighbor_entries();
    MPI_Barrier(MPI_COMM_WORLD);
    // CPU time besides wall time: on a shared machine the wall time counts the time other processes
    // had the core; the process CPU time does not (it still pays for what they do to the caches)
    const auto cpu_now = [] {
      timespec ts{};
      clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
      return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
    };
    CGD_CALLGRIND_START();
    const double t0 = cgd::wall_seconds(), cpu0 = cpu_now();
    for (int s = 0; s < fluid_steps; ++s) fluid_step();
    const double wall_local = cgd::wall_seconds() - t0, cpu_local = cpu_now() - cpu0;
    CGD_CALLGRIND_STOP();
    double cpu = 0;
    MPI_Allreduce(&cpu_local, &cpu, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
    double wall = 0;
    MPI_Allreduce(&wall_local, &wall, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    const std::int64_t dem_steps = dem.step_index() - step0, rebuilds = dem.rebuilds() - rebuilds0;
    // phase seconds summed over ranks (CPU seconds) and the largest rank's
    std::vector<std::string> names = dem.timers().names();
    std::vector<double> secs;
    for (std::size_t k = 0; k < dem0.size(); ++k) secs.push_back(dem.timers().all_seconds()[k] - dem0[k]);
    for (std::size_t k = 0; k < run0.size(); ++k) {
      names.push_back(run_timers.names()[k]);
      secs.push_back(run_timers.all_seconds()[k] - run0[k]);
    }
    std::vector<double> sum(secs.size()), max(secs.size());
    MPI_Allreduce(secs.data(), sum.data(), static_cast<int>(secs.size()), MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
    MPI_Allreduce(secs.data(), max.data(), static_cast<int>(secs.size()), MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    double entries[2] = {static_cast<double>(entries0), static_cast<double>(dem.neighbor_entries())};
    MPI_Allreduce(MPI_IN_PLACE, entries, 2, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
    // how the particles of the last step split (free flight: sim/dem/system.hpp; 0 before issue 17)
    double split[2] = {static_cast<double>(dem.free_flight_particles()), static_cast<double>(dem.integrated_particles())};
    MPI_Allreduce(MPI_IN_PLACE, split, 2, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
    // touching pairs at the last step (collective): the contact load of the state
    const double touching_pairs = dem.diagnostics().contacts;
    // the particles each rank owns at the last step, and its slab (balanced at each list rebuild, sim/dem/system.hpp)
    std::vector<std::int64_t> owned(static_cast<std::size_t>(ranks));
    const std::int64_t owned_local = static_cast<std::int64_t>(dem.particles().n_owned);
    MPI_Gather(&owned_local, 1, MPI_INT64_T, owned.data(), 1, MPI_INT64_T, 0, MPI_COMM_WORLD);
    const double bytes_local = static_cast<double>(dem.bytes());
    double bytes = 0;
    MPI_Allreduce(&bytes_local, &bytes, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);

    if (rank == 0) {
      const double N = static_cast<double>(nt), ps = N * static_cast<double>(dem_steps);
      const double dt_fluid = static_cast<double>(dem_steps) * ds.dt_s / fluid_steps;
      double fluid_cpu = 0, dem_cpu = 0;
      for (std::size_t k = 0; k < names.size(); ++k) {
        if (names[k].rfind("fluid", 0) == 0) fluid_cpu += sum[k];
        else dem_cpu += sum[k];
      }
      const double untimed_cpu = wall * ranks - fluid_cpu - dem_cpu;
      if (!from_run.empty())
        std::printf("cgd-bench-developed %s: %s, the state of the run %s at step %lld (t = %.4g s)\n", cgd::code_version(),
                    full.name.c_str(), from_run.c_str(), static_cast<long long>(step0), step0 * ds.dt_s);
      else
        std::printf("cgd-bench-developed %s: %s developed %.3g t_ref in a box of %.4g x %.4g x %.4g d_p, tiled %d^3\n",
                    cgd::code_version(), full.name.c_str(), develop_tref, small_dp[0], small_dp[1], small_dp[2], tile);
      std::printf("state: %lld particles, %.4g x %.4g x %.4g d_p, %d x %d x %d cells, ranks %d, friction %s\n",
                  static_cast<long long>(nt), tiled_dp[0], tiled_dp[1], tiled_dp[2], tiled_cells[0], tiled_cells[1],
                  tiled_cells[2], ranks, rotation ? "on" : "off");
      std::printf("timed: %d fluid steps after %d warm-up, %lld DEM steps (%.1f per fluid step, dt_fluid %.4g s), "
                  "wall %.3f s\n",
                  fluid_steps, warmup, static_cast<long long>(dem_steps),
                  static_cast<double>(dem_steps) / fluid_steps, dt_fluid, wall);
      std::printf("neighbour list: %lld rebuilds, %.1f DEM steps per rebuild; %.2f entries per particle\n",
                  static_cast<long long>(rebuilds), rebuilds > 0 ? static_cast<double>(dem_steps) / rebuilds : 0.0,
                  entries[1] / N);
      std::printf("last step: %.1f %% of the particles in free flight, %.1f %% integrated every step; "
                  "%.3f contacts per particle (touching pairs x 2 / N)\n",
                  100.0 * split[0] / N, 100.0 * split[1] / N, 2.0 * touching_pairs / N);
      std::printf("engine arrays: %.0f B per particle (DemSystem::bytes, all ranks)\n", bytes / N);
      std::printf("particles per rank at the last step (slab from y/d_p):");
      for (int r = 0; r < ranks; ++r)
        std::printf(" %.1f %% (%.1f)", 100.0 * static_cast<double>(owned[r]) / N,
                    dem.slab_bounds()[static_cast<std::size_t>(r)] / scene.particles.diameter_m);
      std::printf("\n");
      std::printf("\n%-22s %12s %14s %8s\n", "phase", "CPU s", "ns/part-step", "share");
      for (std::size_t k = 0; k < names.size(); ++k)
        std::printf("%-22s %12.4f %14.3f %7.1f %%\n", names[k].c_str(), sum[k], 1e9 * sum[k] / ps,
                    100.0 * sum[k] / (wall * ranks));
      std::printf("%-22s %12.4f %14.3f %7.1f %%\n", "untimed", untimed_cpu, 1e9 * untimed_cpu / ps,
                  100.0 * untimed_cpu / (wall * ranks));
      std::printf("%-22s %12.4f %14.3f\n", "total (wall x ranks)", wall * ranks, 1e9 * wall * ranks / ps);
      std::printf("%-22s %12.4f %14.3f\n", "process CPU time", cpu, 1e9 * cpu / ps);
      std::printf("\nparticle-steps/s/core: %.4g (wall), %.4g (process CPU time)\n", ps / (wall * ranks), ps / cpu);
      // projection: per particle-step cost (everything but the fluid) and per fluid step (fluid)
      const double c_particle = (wall * ranks - fluid_cpu) / ps;  // CPU s per particle-step
      const double c_fluid = fluid_cpu / fluid_steps;             // CPU s per fluid step (this grid)
      std::printf("summary: ranks=%d N=%lld ns_per_ps=%.3f ns_cpu_per_ps=%.3f ps_per_s_per_core=%.4g steps_per_rebuild=%.1f "
                  "dt_fluid=%.4g",
                  ranks, static_cast<long long>(nt), 1e9 * wall * ranks / ps, 1e9 * cpu / ps, ps / (wall * ranks),
                  rebuilds > 0 ? static_cast<double>(dem_steps) / rebuilds : 0.0, dt_fluid);
      std::printf(" contacts_per_particle=%.3f entries_per_particle=%.2f", 2.0 * touching_pairs / N, entries[1] / N);
      for (std::size_t k = 0; k < names.size(); ++k) {
        std::string key = names[k];
        for (char& c : key)
          if (c == ' ' || c == '+') c = '_';
        std::printf(" ns_%s=%.3f", key.c_str(), 1e9 * sum[k] / ps);
      }
      std::printf("\n");
      if (!no_projection) {
        // the same from the process CPU time: what the cores would take had they been this program's alone
        // (the wall time of a shared machine counts the other processes' turns; MPI's busy waiting is CPU)
        const double cpu_share = cpu / (wall * ranks);
        std::printf("\nprojected wall time at %d rank(s) (measured ns per particle-step and dt_fluid of this state; "
                    "fluid per step scaled by cells), from the wall time and from the process CPU time:\n",
                    ranks);
        const fs::path scenes = fs::path(CGD_SOURCE_DIR) / "data" / "scenes";
        // the Table 1 scenes, then the PROFILE=half resolved runs (Makefile.pipeline: pipeline_demo.toml with
        // its GENERATE_SET, at the six solids fractions of the full-range model, each with its gamma*: PHI_SET_<phi>
        // gives the dense runs 1e-3, twice the DEM steps of the dilute runs' 2e-3, docs/stiffness.md)
        std::vector<std::pair<std::string, std::vector<std::string>>> runs;
        std::vector<fs::path> files;
        for (const auto& e : fs::directory_iterator(scenes))
          if (e.path().filename().string().rfind("table1_", 0) == 0) files.push_back(e.path());
        std::sort(files.begin(), files.end());
        for (const fs::path& f : files) runs.push_back({f.string(), {}});
        constexpr std::pair<const char*, const char*> kHalfRuns[] = {
            {"0.02", "2e-3"}, {"0.05", "2e-3"}, {"0.10", "2e-3"}, {"0.20", "1e-3"}, {"0.30", "1e-3"}, {"0.40", "1e-3"}};
        for (const auto& [phi, gamma_star] : kHalfRuns)
          runs.push_back({(scenes / "pipeline_demo.toml").string(),
                          {"domain.size_dp=[53,213,53]", std::string("contact.gamma_star=") + gamma_star,
                           "run.end_time_tref=50", std::string("particles.solids_fraction=") + phi}});
        const double cells_here = static_cast<double>(tiled_cells[0]) * tiled_cells[1] * tiled_cells[2];
        for (const auto& [path, overrides] : runs) {
          const cgd::Scene s = cgd::load_scene(path, overrides);
          const std::string label =
              overrides.empty() ? s.name : "half phi=" + overrides.back().substr(overrides.back().find('=') + 1);
          const double n = static_cast<double>(s.derived.particle_count);
          const double steps = std::round(s.run.end_time_s / s.derived.dt_dem_s);
          const double cells = static_cast<double>(s.derived.cells[0]) * s.derived.cells[1] * s.derived.cells[2];
          const double hours =
              (n * steps * c_particle + s.run.end_time_s / dt_fluid * c_fluid * cells / cells_here) / ranks / 3600;
          std::printf("  %-16s %9.0f particles  %.4g s  %.3g h (wall)  %.3g h (CPU time)\n", label.c_str(), n,
                      s.run.end_time_s, hours, hours * cpu_share);
        }
      }
    }
    return cgd::kExitOk;
  });
  MPI_Finalize();
  return status;
}
