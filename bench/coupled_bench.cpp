// cgd-bench-coupled: the cost of the resolved CFD-DEM run of a scene, per coupled (fluid) step and
// by phase, and the wall time it projects for 1 s of physical time and for the scene's whole run, at
// the rank count it runs with. Figures only; never asserted anywhere.
//
//   cgd-bench-coupled [SCENE.toml] [--set KEY=VALUE]... [--warmup 1] [--fluid-steps 5] [--keep DIR]
//   cgd-bench-coupled SCENE.toml --describe      # load and validate only: derived numbers, no run
//
// How: the scene runs through cgd::run_scene itself (the same driver as cgd-generate, nothing copied)
// with its end time cut to warmup + fluid-steps (+ 1) fluid steps, no snapshots but the first and the
// last, no checkpoint but the final one; its series file has one row per fluid step with the
// cumulative phase timers (rank 0's), so the difference of two consecutive rows is one coupled step.
// The first `warmup` steps (the first holds the snapshot at step 0) and the last (final checkpoint
// and snapshot) are not counted. I/O is charged separately: the step-0 snapshot's write time times
// the scene's snapshots per second of physical time. Placement (random sequential addition, or
// growth above 0.30) is part of setup and is timed on its own by calling the same placement the run
// calls (so it runs twice; --no-placement-timing skips the extra one).
//
// Caveat: the run starts from rest (particles placed at random, fluid at rest), so the steps timed are
// those of a homogeneous suspension: few contacts, fluid step limited by viscosity not by a developed
// flow. A clustered suspension has more contacts (DEM dearer per step) and faster fluid (smaller
// Courant steps): the projections are for the start of the run.
#include <mpi.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "core/mpi_init.hpp"
#include "core/cli.hpp"
#include "core/error.hpp"
#include "core/schema/series.hpp"
#include "core/schema/snapshot.hpp"
#include "core/scene.hpp"
#include "core/timers.hpp"
#include "core/version.hpp"
#include "sim/dem/placement.hpp"
#include "sim/run.hpp"

namespace fs = std::filesystem;

namespace {

std::string hms(double s) {
  if (!std::isfinite(s)) return "--";
  char buf[64];
  if (s >= 3600) std::snprintf(buf, sizeof buf, "%.0f s = %.2f h", s, s / 3600);
  else std::snprintf(buf, sizeof buf, "%.1f s", s);
  return buf;
}

// Per-step figures from the series: mean over the counted steps of the increments of each column.
struct StepCosts {
  int steps = 0;
  double dem_substeps = 0;   // DEM steps per fluid step (mean)
  double dt_fluid_s = 0;     // mean fluid step
  double wall_s = 0;         // wall per coupled step (series wall_seconds)
  std::map<std::string, double> phase_s;  // per step, by timer name
};

}  // namespace

int main(int argc, char** argv) {
  cgd::init_mpi(&argc, &argv);
  const int status = cgd::run_tool([&] {
    CLI::App app{"Coupled CFD-DEM benchmark: time per fluid step by phase and projected wall times"};
    std::string scene_path = std::string(CGD_SOURCE_DIR) + "/data/scenes/table1_phi005.toml";
    std::vector<std::string> overrides;
    int warmup = 1, fluid_steps = 5;
    std::string keep;
    bool describe = false, no_placement_timing = false, verbose = false;
    double dt_developed = 0;
    app.add_option("scene", scene_path, "scene (default data/scenes/table1_phi005.toml)");
    app.add_option("--set", overrides, "override a scene key, SECTION.KEY=VALUE (repeatable)")->take_all();
    app.add_option("--warmup", warmup, "fluid steps run first and not counted (>= 1)");
    app.add_option("--fluid-steps", fluid_steps, "fluid (coupled) steps timed");
    app.add_option("--keep", keep, "run directory to keep (default: a temporary one, removed)");
    app.add_option("--dt-fluid-developed", dt_developed,
                   "also project with this fluid step (s), e.g. the one a developed (clustered) flow reaches");
    app.add_flag("--describe", describe, "load and validate the scene, print its derived numbers, run nothing");
    app.add_flag("--no-placement-timing", no_placement_timing, "do not time the placement separately");
    app.add_flag("--verbose", verbose, "show the run's own banner and timing table");
    cgd::parse_command_line(app, argc, argv, "cgd-bench-coupled");
    if (warmup < 1 || fluid_steps < 1) throw cgd::InputError("--warmup and --fluid-steps must be >= 1");
    int rank = 0, ranks = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &ranks);

    // The scene as the user would run it: its end time and snapshot interval are what we project.
    const cgd::Scene full = cgd::load_scene(scene_path, overrides);
    if (describe) {
      if (rank == 0) std::cout << cgd::describe_scene(full) << std::flush;
      return cgd::kExitOk;
    }
    if (!full.solves_fluid())
      throw cgd::InputError(scene_path + ": the scene solves no fluid; use cgd-bench-dem or cgd-generate");
    const cgd::DerivedScales& x = full.derived;
    const double n_particles = static_cast<double>(x.particle_count);
    const double n_cells = static_cast<double>(x.cells[0]) * x.cells[1] * x.cells[2];

    // Placement, timed alone (distributed over the ranks, as the run does).
    double placement_s = NAN;
    std::string placement_method;
    if (!no_placement_timing) {
      MPI_Barrier(MPI_COMM_WORLD);
      const double t0 = cgd::wall_seconds();
      const cgd::dem::LocalPlacement pl = cgd::dem::place_particles_distributed(
          MPI_COMM_WORLD, full.domain.size_m, x.parcel_diameter_m, x.particle_count,
          full.particles.velocity_rms_m_s, full.particles.seed);
      placement_s = cgd::wall_seconds() - t0;
      placement_method = pl.method;
      MPI_Allreduce(MPI_IN_PLACE, &placement_s, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    }

    // The short run: end time = (warmup + steps + 1) estimated fluid steps. At rest the viscous limit
    // (< the Courant estimate for the Table 1 grid) sets the step, so this gives at least as many.
    const int wanted = warmup + fluid_steps + 1;
    std::vector<std::string> run_overrides = overrides;
    // --set cannot delete a key: a scene that gives its times in t_ref units gets them overridden so
    const auto uses = [&](const char* key) { return full.effective_toml.find(key) != std::string::npos; };
    char buf[160];
    const double end_s = (wanted + 0.5) * x.dt_fluid_s;
    if (uses("end_time_tref")) std::snprintf(buf, sizeof buf, "run.end_time_tref=%.17g", end_s / x.t_ref_s);
    else std::snprintf(buf, sizeof buf, "run.end_time=%.17g", end_s);
    run_overrides.push_back(buf);
    run_overrides.push_back(uses("dump_interval_tref") ? "run.dump_interval_tref=0.0" : "run.dump_interval=0.0");
    run_overrides.push_back("run.checkpoint_wall_s=1e9");
    const cgd::Scene scene = cgd::load_scene(scene_path, run_overrides);

    fs::path dir;
    if (!keep.empty()) dir = keep;
    else {
      std::string tmpl = (fs::temp_directory_path() / "cgd-bench-coupled-XXXXXX").string();
      if (rank == 0 && !mkdtemp(tmpl.data())) throw cgd::RunError("cannot create a temporary directory");
      int len = static_cast<int>(tmpl.size());
      MPI_Bcast(&len, 1, MPI_INT, 0, MPI_COMM_WORLD);
      tmpl.resize(len);
      MPI_Bcast(tmpl.data(), len, MPI_CHAR, 0, MPI_COMM_WORLD);
      dir = fs::path(tmpl) / "run";
    }
    cgd::RunSettings settings;
    settings.output_dir = dir.string();
    settings.quiet = true;
    settings.tool = "cgd-bench-coupled";
    MPI_Barrier(MPI_COMM_WORLD);
    const double t_run0 = cgd::wall_seconds();
    {
      std::ostringstream sink;
      std::streambuf* old = verbose ? nullptr : std::cout.rdbuf(sink.rdbuf());
      try {
        cgd::run_scene(scene, settings, MPI_COMM_WORLD);
      } catch (...) {
        if (old) std::cout.rdbuf(old);
        throw;
      }
      if (old) std::cout.rdbuf(old);
    }
    const double run_wall = cgd::wall_seconds() - t_run0;

    const cgd::schema::Series series = cgd::schema::Series::read((dir / "series.h5").string(), MPI_COMM_WORLD);
    const std::size_t rows = series.rows();
    // rows r_0 .. r_{M}: r_M is the final state (its interval holds the final checkpoint). Step k
    // (between rows k and k+1) is counted for warmup <= k <= M - 2.
    const int first = warmup, last = static_cast<int>(rows) - 2;
    if (last < first)
      throw cgd::RunError("the run made only " + std::to_string(rows > 0 ? rows - 1 : 0) +
                          " fluid steps: too few to time; raise --fluid-steps");
    const std::vector<double>& time = series.column("time");
    const std::vector<double>& step = series.column("step");
    const std::vector<double>& wall = series.column("wall_seconds");
    StepCosts c;
    c.steps = last - first + 1;
    const auto per_step = [&](const std::vector<double>& col) { return (col[last + 1] - col[first]) / c.steps; };
    c.dem_substeps = per_step(step);
    c.dt_fluid_s = per_step(time);
    c.wall_s = per_step(wall);
    const char* names[] = {"neighbor",        "comm",           "force_integrate",  "coupling",   "fluid_predictor",
                           "fluid_pressure",  "fluid_correction", "diagnostics",     "output",     "checkpoint"};
    for (const char* n : names) c.phase_s[n] = per_step(series.column(cgd::schema::phase_column(n)));
    // the step-0 snapshot (and series write) lands in the first interval's "output"
    const std::vector<double>& out = series.column("time_output_s");
    const double snapshot_s = out[1] - out[0];
    const double setup_s = wall[0];  // RunDriver construction .. first row: FFTW plans, placement, first deposit

    if (rank == 0) {
      const double dem = c.phase_s["neighbor"] + c.phase_s["comm"] + c.phase_s["force_integrate"];
      const double coupling = c.phase_s["coupling"];
      const double fluid = c.phase_s["fluid_predictor"] + c.phase_s["fluid_pressure"] + c.phase_s["fluid_correction"];
      const double other = c.phase_s["diagnostics"] + c.phase_s["output"] + c.phase_s["checkpoint"];
      const double untimed = c.wall_s - dem - coupling - fluid - other;
      const double dumps_per_s = full.run.dump_interval_s > 0 ? 1.0 / full.run.dump_interval_s : 0.0;
      const double io_per_step = snapshot_s * dumps_per_s * c.dt_fluid_s;
      const double per_step_total = c.wall_s + io_per_step;
      const double steps_per_phys_s = 1.0 / c.dt_fluid_s;
      // projected also with a given fluid step (a developed, clustered flow is faster: smaller steps)
      const double dem_per_dem_step = dem / c.dem_substeps;
      const double io_per_phys_s = snapshot_s * dumps_per_s;
      const double proj1 = per_step_total * steps_per_phys_s;
      const double dt_dev = dt_developed > 0 ? dt_developed : c.dt_fluid_s;
      const double proj1_dev = dem_per_dem_step / x.dt_dem_s + (c.wall_s - dem) / dt_dev + io_per_phys_s;
      const double end = full.run.end_time_s;
      std::printf("cgd-bench-coupled %s: %s\n", cgd::code_version(), full.name.c_str());
      std::printf("scene %s: %.0f particles (%s), %d x %d x %d = %.0f cells, ranks %d\n", full.source_path.c_str(),
                  n_particles, full.particles.parcel_size == 1.0 ? "resolved" : "parcels", x.cells[0], x.cells[1],
                  x.cells[2], n_cells, ranks);
      std::printf("dt_DEM %.4g s, measured dt_fluid %.4g s (%.1f DEM sub-steps per fluid step; scene's Courant "
                  "estimate %.4g s)\n",
                  x.dt_dem_s, c.dt_fluid_s, c.dem_substeps, x.dt_fluid_s);
      if (!no_placement_timing)
        std::printf("setup: placement (%s) %.2f s timed alone; run setup to first step (placement, plans, first "
                    "deposit) %.2f s\n",
                    placement_method.c_str(), placement_s, setup_s);
      else
        std::printf("setup: run setup to first step (placement, plans, first deposit) %.2f s\n", setup_s);
      std::printf("timed: %d coupled steps after %d warm-up (whole short run %.1f s)\n", c.steps, warmup, run_wall);
      std::printf("\nper coupled (fluid) step, wall s (rank 0):\n");
      const auto line = [&](const char* what, double s) {
        std::printf("  %-36s %10.4f  %5.1f %%\n", what, s, 100.0 * s / per_step_total);
      };
      line("DEM sub-steps (all)", dem);
      line("  neighbour list + ghosts", c.phase_s["neighbor"]);
      line("  ghost exchange + reductions", c.phase_s["comm"]);
      line("  force + integrate", c.phase_s["force_integrate"]);
      line("coupling / mapping (deposit, drag, forces)", coupling);
      line("fluid predictor", c.phase_s["fluid_predictor"]);
      line("fluid pressure solve", c.phase_s["fluid_pressure"]);
      line("fluid correction", c.phase_s["fluid_correction"]);
      line("series diagnostics", c.phase_s["diagnostics"]);
      line("I/O (snapshots, amortised)", io_per_step);
      line("untimed (loop overhead)", untimed);
      line("total", per_step_total);
      std::printf("  fluid + coupling / DEM sub-steps: %.3f\n", (fluid + coupling) / std::max(dem, 1e-30));
      std::printf("  snapshot write: %.2f s each, %.3g per s of physical time\n", snapshot_s, dumps_per_s);
      std::printf("\nrates:\n");
      std::printf("  DEM particle-steps per second per core: %.3e (DEM phases only), %.3e (whole coupled step)\n",
                  n_particles * c.dem_substeps / std::max(dem, 1e-30) / ranks,
                  n_particles * c.dem_substeps / per_step_total / ranks);
      std::printf("  fluid cells per second: %.3e (%.3e per core; predictor + pressure + correction)\n",
                  n_cells / std::max(fluid, 1e-30), n_cells / std::max(fluid, 1e-30) / ranks);
      std::printf("\nprojected wall time at %d rank(s):\n", ranks);
      std::printf("  1 s of physical time: %s at the measured dt_fluid; %s at dt_fluid = %.3g s\n",
                  hms(proj1).c_str(), hms(proj1_dev).c_str(), dt_dev);
      std::printf("  the scene's run (%.4g s = %.1f t_ref): %s (%s), plus setup %s\n", end,
                  x.t_ref_s > 0 ? end / x.t_ref_s : 0.0, hms(proj1 * end).c_str(), hms(proj1_dev * end).c_str(),
                  hms(setup_s).c_str());
      std::printf("summary: ranks=%d N=%.0f dem_s=%.4f coupling_s=%.4f fluid_s=%.4f io_s=%.4f step_s=%.4f "
                  "ps_per_s_per_core=%.3e proj_1s_h=%.3f proj_run_h=%.3f proj_1s_dev_h=%.3f proj_run_dev_h=%.3f "
                  "placement_s=%.2f\n",
                  ranks, n_particles, dem, coupling, fluid, io_per_step, per_step_total,
                  n_particles * c.dem_substeps / std::max(dem, 1e-30) / ranks, proj1 / 3600, proj1 * end / 3600,
                  proj1_dev / 3600, proj1_dev * end / 3600, placement_s);
    }
    MPI_Barrier(MPI_COMM_WORLD);
    if (keep.empty() && rank == 0) fs::remove_all(dir.parent_path());
    return cgd::kExitOk;
  });
  MPI_Finalize();
  return status;
}
