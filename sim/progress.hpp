#pragma once
// The run's progress on stderr (rank 0): on a terminal, one line rewritten in place about once a second;
// in a batch job (stderr not a terminal), a line every `interval_s` seconds of wall time under a header
// naming the columns, like LAMMPS' thermo output, so that a log read the next morning shows how far the
// run got and what the physics did. Both show the same numbers: step, time (s and t_ref), steps per
// second, ETA, and the physics of the latest series row (slip, kinetic energy, overlap, phi, fluid step).
#include <cmath>
#include <cstdint>
#include <string>

namespace cgd {

/// The physics a progress line shows, from the latest series row (already reduced over the ranks).
/// Fields the run does not have (Progress::Settings says which) are not shown.
struct ProgressPhysics {
  double slip_y_over_u_t = 0;      // <u_slip,y>/u_t (scenes with a fluid)
  double kinetic_energy_J = 0;     // translational kinetic energy of the particles
  double max_overlap_rel = 0;      // largest overlap / diameter
  double max_solids_fraction = 0;  // largest cell phi (fluid solved)
  double dt_fluid_s = 0;           // the last fluid step (fluid solved)
};

class Progress {
 public:
  enum class Mode { Off, Terminal, Batch };

  struct Settings {
    std::string tool;  // "cgd-generate", prefix of the terminal line and the header
    Mode mode = Mode::Off;
    double interval_s = 60;  // wall seconds between batch lines
    std::int64_t end_step = 0;
    double dt_s = 0;            // DEM step: time = step dt
    double t_ref_s = 0;         // u_t/g; 0: no t_ref column
    bool fluid_scene = false;   // slip column
    bool solves_fluid = false;  // max phi and fluid-step columns
  };

  /// Terminal when stderr is a terminal, Batch otherwise, Off with --quiet.
  static Mode mode_for(bool quiet);

  explicit Progress(Settings settings) : s_(std::move(settings)) {}

  /// The loop starts at `step` (0, or the checkpoint's step): prints the batch header.
  void begin(std::int64_t step);
  /// After a loop iteration that reached `step`: a line when one is due (force: always, e.g. at the
  /// end or an interruption; a batch line then ends the log's progress with the final state).
  void update(std::int64_t step, const ProgressPhysics& physics, bool force);

 private:
  struct Rate {
    double steps_per_s = NAN, eta_s = NAN;  // NaN until measured
  };
  Rate rate(std::int64_t step, double now) const;
  std::string columns_header() const;
  std::string batch_row(std::int64_t step, const ProgressPhysics& physics, double now) const;
  std::string terminal_line(std::int64_t step, const ProgressPhysics& physics, double now) const;

  Settings s_;
  std::int64_t begin_step_ = 0;
  // The rate and the ETA are measured from the end of the first iteration (which carries the first
  // neighbour build and the solvers' warm-up), and the ETA is shown once kEtaMinSteps DEM steps and
  // kEtaMinSeconds have passed since then: the first steps' rate is not the run's.
  static constexpr std::int64_t kEtaMinSteps = 10;
  static constexpr double kEtaMinSeconds = 1.0;
  std::int64_t reference_step_ = -1;
  double reference_wall_ = 0;
  double last_line_wall_ = 0;
};

/// "mm:ss" or "h:mm:ss"; "--:--" for a negative or non-finite duration.
std::string format_duration(double seconds);

}  // namespace cgd
