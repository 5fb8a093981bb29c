#pragma once
// What a run prints on stdout (rank 0): the banner before the loop (the tool, the scene's table, what
// the engine decides) and the timing report after it (phases, throughput, memory). Text only: the run
// driver (sim/run.cpp) gathers the numbers (the collective parts) and prints what these return.
#include <cstdint>
#include <string>
#include <vector>

#include "core/scene.hpp"

namespace cgd {

inline constexpr double kMiB = 1024.0 * 1024.0;

/// The numbers of the banner.
struct RunBanner {
  std::string tool;
  const Scene* scene = nullptr;
  double memory_estimate_bytes = 0, resident_at_start_bytes = 0;  // all ranks
  int ranks = 1;
  std::int64_t restarted_from = -1;  // -1: a fresh run (placement shown)
  std::string placement_method;
  double placement_gap = 0, placement_seconds = 0;
  std::int64_t end_step = 0, dump_every = 0, series_every = 1;
  double dt_s = 0;
  bool coupled = false;  // the fluid is solved: the fluid-step rows
  double drag_dt_cap_s = 0, viscous_dt_limit_s = 0, fluid_limit_now_s = 0;
  std::string output_dir;
};

/// The banner: "<tool> <version>", describe_scene (with the engine's memory estimate), then the run's
/// rows (ranks, restart or placement, DEM steps, the fluid step rule, snapshots, series, memory, output).
std::string run_banner(const RunBanner& b);

/// The numbers of the timing report (phase seconds are the slowest rank's).
struct RunReport {
  std::vector<std::string> phase_names;
  std::vector<double> whole_run_phase_seconds, session_phase_seconds;
  double wall_s = 0, session_wall_s = 0, loop_wall_s = 0;
  std::int64_t end_step = 0, loop_start_step = 0;
  bool restarted = false;  // this session and the whole run side by side
  std::int64_t particles = 0;
  int ranks = 1;
  double dem_bytes = 0, memory_estimate_bytes = 0, peak_bytes = 0;  // all ranks
};

/// The timing table by phase, the particle-steps per second per core, the DEM's bytes per particle and the
/// estimated against the measured peak memory.
std::string timing_report(const RunReport& r);

}  // namespace cgd
