// The run's progress on stderr (sim/progress.hpp).
#include "sim/progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/timers.hpp"

namespace cgd {

std::string format_duration(double s) {
  if (!std::isfinite(s) || s < 0) return "--:--";
  const long t = std::lround(s);
  char buf[32];
  if (t >= 3600)
    std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", t / 3600, (t / 60) % 60, t % 60);
  else
    std::snprintf(buf, sizeof buf, "%02ld:%02ld", t / 60, t % 60);
  return buf;
}

Progress::Mode Progress::mode_for(bool quiet) {
  if (quiet) return Mode::Off;
  return isatty(STDERR_FILENO) ? Mode::Terminal : Mode::Batch;
}

void Progress::begin(std::int64_t step) {
  begin_step_ = step;
  last_line_wall_ = wall_seconds();
  if (s_.mode != Mode::Batch) return;
  std::fprintf(stderr, "%s: progress every %g s of wall time (--progress-interval)\n%s\n", s_.tool.c_str(),
               s_.interval_s, columns_header().c_str());
  std::fflush(stderr);
}

// Batch columns: the header is formatted with the widths of the rows, so the columns line up.
std::string Progress::columns_header() const {
  char buf[256];
  std::string h;
  std::snprintf(buf, sizeof buf, "#%10s  %11s", "step", "time_s");
  h += buf;
  if (s_.t_ref_s > 0) {
    std::snprintf(buf, sizeof buf, "  %9s", "time_tref");
    h += buf;
  }
  std::snprintf(buf, sizeof buf, "  %8s  %8s", "steps/s", "ETA");
  h += buf;
  if (s_.fluid_scene) {
    std::snprintf(buf, sizeof buf, "  %10s", "slip_y/u_t");
    h += buf;
  }
  std::snprintf(buf, sizeof buf, "  %9s  %9s", "kinetic_J", "overlap/d");
  h += buf;
  if (s_.solves_fluid) {
    std::snprintf(buf, sizeof buf, "  %7s  %10s", "max_phi", "dt_fluid_s");
    h += buf;
  }
  return h;
}

Progress::Rate Progress::rate(std::int64_t step, double now) const {
  Rate r;
  const std::int64_t since = reference_step_ >= 0 ? step - reference_step_ : 0;
  const double wall = now - reference_wall_;
  if (reference_step_ >= 0 && since >= kEtaMinSteps && wall >= kEtaMinSeconds) {
    r.steps_per_s = static_cast<double>(since) / wall;
    r.eta_s = static_cast<double>(s_.end_step - step) / std::max(r.steps_per_s, 1e-30);
  }
  return r;
}

std::string Progress::batch_row(std::int64_t step, const ProgressPhysics& p, double now) const {
  const Rate r = rate(step, now);
  char buf[256];
  std::string out;
  std::snprintf(buf, sizeof buf, " %10lld  %11.5e", static_cast<long long>(step),
                static_cast<double>(step) * s_.dt_s);
  out += buf;
  if (s_.t_ref_s > 0) {
    std::snprintf(buf, sizeof buf, "  %9.4g", static_cast<double>(step) * s_.dt_s / s_.t_ref_s);
    out += buf;
  }
  if (std::isfinite(r.steps_per_s))
    std::snprintf(buf, sizeof buf, "  %8.4g  %8s", r.steps_per_s, format_duration(r.eta_s).c_str());
  else
    std::snprintf(buf, sizeof buf, "  %8s  %8s", "-", "--:--");
  out += buf;
  if (s_.fluid_scene) {
    std::snprintf(buf, sizeof buf, "  %10.4g", p.slip_y_over_u_t);
    out += buf;
  }
  std::snprintf(buf, sizeof buf, "  %9.3e  %9.3e", p.kinetic_energy_J, p.max_overlap_rel);
  out += buf;
  if (s_.solves_fluid) {
    std::snprintf(buf, sizeof buf, "  %7.4f  %10.3e", p.max_solids_fraction, p.dt_fluid_s);
    out += buf;
  }
  return out;
}

// The terminal line: the same numbers, each with its label (there is no header above it).
std::string Progress::terminal_line(std::int64_t step, const ProgressPhysics& p, double now) const {
  const Rate r = rate(step, now);
  char buf[512];
  const double t = static_cast<double>(step) * s_.dt_s;
  std::snprintf(buf, sizeof buf, "%s: step %lld/%lld (%.1f %%)  t = %.4g s", s_.tool.c_str(),
                static_cast<long long>(step), static_cast<long long>(s_.end_step),
                100.0 * static_cast<double>(step) / std::max<double>(1, static_cast<double>(s_.end_step)), t);
  std::string out = buf;
  if (s_.t_ref_s > 0) {
    std::snprintf(buf, sizeof buf, " = %.3g t_ref", t / s_.t_ref_s);
    out += buf;
  }
  if (std::isfinite(r.steps_per_s))
    std::snprintf(buf, sizeof buf, "  %.3g steps/s  ETA %s", r.steps_per_s, format_duration(r.eta_s).c_str());
  else
    std::snprintf(buf, sizeof buf, "  - steps/s  ETA --:--");
  out += buf;
  if (s_.fluid_scene) {
    std::snprintf(buf, sizeof buf, "  slip_y/u_t %.3g", p.slip_y_over_u_t);
    out += buf;
  }
  std::snprintf(buf, sizeof buf, "  KE %.3g J  overlap %.3g d", p.kinetic_energy_J, p.max_overlap_rel);
  out += buf;
  if (s_.solves_fluid) {
    std::snprintf(buf, sizeof buf, "  max phi %.3f  dt_fluid %.3g s", p.max_solids_fraction, p.dt_fluid_s);
    out += buf;
  }
  return out;
}

void Progress::update(std::int64_t step, const ProgressPhysics& physics, bool force) {
  if (s_.mode == Mode::Off) return;
  const double now = wall_seconds();
  if (reference_step_ < 0 && step > begin_step_) {
    reference_step_ = step;
    reference_wall_ = now;
  }
  if (s_.mode == Mode::Terminal) {
    if (!force && now - last_line_wall_ < 1.0) return;
    last_line_wall_ = now;
    std::fprintf(stderr, "\r%s%s", terminal_line(step, physics, now).c_str(), force ? "\n" : "   ");
  } else {
    if (!force && now - last_line_wall_ < s_.interval_s) return;
    last_line_wall_ = now;
    std::fprintf(stderr, "%s\n", batch_row(step, physics, now).c_str());
  }
  std::fflush(stderr);
}

}  // namespace cgd
