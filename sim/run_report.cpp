// The banner and the timing report of a run (sim/run_report.hpp).
#include "sim/run_report.hpp"
#include "core/version.hpp"

#include <algorithm>
#include <cstdio>
#include <sstream>

namespace cgd {

std::string run_banner(const RunBanner& b) {
  std::ostringstream o;
  o.precision(4);
  o << b.tool << " " << cgd::code_version() << "\n";
  // The scene's table with the engine's memory estimate (the scene alone cannot know what the libraries,
  // the placement and the solvers take): one memory row, the one compared with the measured peak at the end.
  Scene shown = *b.scene;
  shown.derived.memory_estimate_bytes = b.memory_estimate_bytes;
  o << describe_scene(shown);
  o << "run\n";
  o << "  MPI ranks                 " << b.ranks << " (slabs along y)\n";
  if (b.restarted_from >= 0) o << "  restart                   from the checkpoint at step " << b.restarted_from << "\n";
  else
    o << "  placement                 " << b.placement_method << ", smallest gap " << b.placement_gap << " d, "
      << b.placement_seconds << " s\n";
  o << "  DEM steps                 " << b.end_step << " of " << b.dt_s << " s";
  if (b.restarted_from >= 0) o << " (" << b.end_step - b.restarted_from << " to do)";
  o << "\n";
  if (b.coupled) {
    const std::string indent(28, ' ');
    o << "  fluid step                adaptive, CFL-limited: Co dx / max|u| (Co = " << b.scene->fluid->courant
      << "), at most the drag limit " << b.drag_dt_cap_s << " s (dt beta_max/rho_p <= "
      << b.scene->numerics.drag_safety << ")\n"
      << indent << "and the viscous limit " << b.viscous_dt_limit_s
      << " s; a whole number of DEM steps, evened out to land on the snapshot times.\n"
      << indent << "The first step is at most " << b.fluid_limit_now_s << " s (the flow now); dt_fluid above is the Courant "
      << "step at u = u_t only.\n"
      << indent << "It shrinks as clusters speed the flow up: series.h5 column dt_fluid, progress column dt_fluid_s\n";
  }
  o << "  snapshots                 ";
  if (b.dump_every > 0) o << "every " << b.dump_every << " DEM steps (" << static_cast<double>(b.dump_every) * b.dt_s << " s)";
  else o << "the initial and final states only";
  o << "\n  series.h5                 ";
  if (b.coupled) {
    o << "a row every fluid step";
    if (b.scene->run.series_interval_s > 0) o << " (run.series_interval applies to runs without a solved fluid)";
  } else {
    o << "a row every " << b.series_every << " DEM steps (" << static_cast<double>(b.series_every) * b.dt_s << " s)";
  }
  o << "; rewritten at each snapshot and checkpoint\n";
  o << "  memory                    " << b.resident_at_start_bytes / kMiB << " MiB resident after setup + "
    << (b.memory_estimate_bytes - b.resident_at_start_bytes) / kMiB
    << " MiB to come (neighbour lists, coupling fields, output buffers) = the estimate above\n";
  o << "  output                    " << b.output_dir << "\n";
  return o.str();
}

std::string timing_report(const RunReport& r) {
  const double steps = static_cast<double>(r.end_step - r.loop_start_step);
  const double loop_wall = r.loop_wall_s;
  const bool restarted = r.restarted;
  std::ostringstream o;
  char line[256];
  o << "\ntiming (wall seconds, slowest rank)";
  if (restarted)
    o << ": this session (steps " << r.loop_start_step << " to " << r.end_step << ", restarted from the checkpoint) "
      << "and the whole run (all sessions, from step 0)\n";
  else
    o << ": the whole run (steps 0 to " << r.end_step << ")\n";
  if (restarted)
    std::snprintf(line, sizeof line, "  %-18s %12s  %12s  %7s\n", "phase", "this session", "whole run", "of run");
  else
    std::snprintf(line, sizeof line, "  %-18s %12s  %7s\n", "phase", "seconds", "of run");
  o << line;
  const std::vector<std::string>& names = r.phase_names;
  for (std::size_t k = 0; k < names.size(); ++k) {
    if (restarted)
      std::snprintf(line, sizeof line, "  %-18s %10.3f s  %10.3f s  %5.1f %%\n", names[k].c_str(), r.session_phase_seconds[k],
                    r.whole_run_phase_seconds[k], 100.0 * r.whole_run_phase_seconds[k] / std::max(r.wall_s, 1e-12));
    else
      std::snprintf(line, sizeof line, "  %-18s %10.3f s  %5.1f %%\n", names[k].c_str(), r.whole_run_phase_seconds[k],
                    100.0 * r.whole_run_phase_seconds[k] / std::max(r.wall_s, 1e-12));
    o << line;
  }
  if (restarted) std::snprintf(line, sizeof line, "  %-18s %10.3f s  %10.3f s\n", "total", r.session_wall_s, r.wall_s);
  else std::snprintf(line, sizeof line, "  %-18s %10.3f s\n", "total", r.wall_s);
  o << line;
  std::snprintf(line, sizeof line, "  particle-steps per second per core%s: %.3e (%.0f steps in %.3f s)\n",
                restarted ? " (this session)" : "",
                static_cast<double>(r.particles) * steps / std::max(loop_wall, 1e-12) / r.ranks, steps, loop_wall);
  o << line;
  std::snprintf(line, sizeof line, "  DEM memory: %.0f bytes per particle (%.1f MiB)\n",
                r.dem_bytes / std::max<double>(1, static_cast<double>(r.particles)), r.dem_bytes / kMiB);
  o << line;
  std::snprintf(line, sizeof line,
                "  memory (all ranks): estimated %.1f MiB, measured peak %.1f MiB (this session's peak resident "
                "set, getrusage)\n",
                r.memory_estimate_bytes / kMiB, r.peak_bytes / kMiB);
  o << line;
  return o.str();
}

}  // namespace cgd
