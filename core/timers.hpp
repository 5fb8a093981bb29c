#pragma once
// Phase timers: the one timer of cgd. A run names its phases once; ScopedPhase adds wall time to one.
#include <chrono>
#include <cstddef>
#include <string>
#include <vector>

namespace cgd {

class PhaseTimers {
 public:
  /// Register a phase; returns its index (register every phase before the time loop).
  std::size_t add(const std::string& name) {
    names_.push_back(name);
    seconds_.push_back(0.0);
    return names_.size() - 1;
  }
  void add_seconds(std::size_t phase, double s) { seconds_[phase] += s; }
  double seconds(std::size_t phase) const { return seconds_[phase]; }
  const std::vector<std::string>& names() const { return names_; }
  const std::vector<double>& all_seconds() const { return seconds_; }
  void set_all_seconds(const std::vector<double>& s) {
    for (std::size_t i = 0; i < s.size() && i < seconds_.size(); ++i) seconds_[i] = s[i];
  }
  double total() const {
    double t = 0;
    for (double s : seconds_) t += s;
    return t;
  }

 private:
  std::vector<std::string> names_;
  std::vector<double> seconds_;
};

inline double wall_seconds() {
  using clock = std::chrono::steady_clock;
  return std::chrono::duration<double>(clock::now().time_since_epoch()).count();
}

/// Adds the wall time of its scope to one phase.
class ScopedPhase {
 public:
  ScopedPhase(PhaseTimers& timers, std::size_t phase) : timers_(timers), phase_(phase), start_(wall_seconds()) {}
  ~ScopedPhase() { timers_.add_seconds(phase_, wall_seconds() - start_); }
  ScopedPhase(const ScopedPhase&) = delete;
  ScopedPhase& operator=(const ScopedPhase&) = delete;

 private:
  PhaseTimers& timers_;
  std::size_t phase_;
  double start_;
};

}  // namespace cgd
