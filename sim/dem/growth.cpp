// Growth of a loose random packing to a dense one (used by placement.cpp for solids fractions above
// what random sequential addition reaches). The spheres are grown in small geometric stages; after
// each stage a frictionless, strongly damped soft-sphere relaxation (this project's own DEM, run
// serially on every rank so that all ranks get the same packing) removes the overlaps it created.
// Units are scaled so that the target diameter, the particle mass and the stiffness are 1.
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "core/scales.hpp"
#include "sim/dem/system.hpp"

namespace cgd::dem {

bool grow_packing(const std::array<double, 3>& L, double d_start, double d_target, std::vector<double>& x) {
  const std::int64_t n = static_cast<std::int64_t>(x.size() / 3);
  // scaled units: lengths in d_target
  std::array<double, 3> box{L[0] / d_target, L[1] / d_target, L[2] / d_target};
  std::vector<double> xs(x.size());
  for (std::size_t k = 0; k < x.size(); ++k) xs[k] = x[k] / d_target;
  std::vector<std::int64_t> ids(static_cast<std::size_t>(n));
  for (std::int64_t i = 0; i < n; ++i) ids[i] = i;

  constexpr int kStages = 60;
  constexpr double kTolerance = 2e-4;  // residual overlap / diameter accepted after a stage
  const double ratio = std::pow(d_target / d_start, 1.0 / kStages);
  double d = d_start / d_target;
  for (int stage = 0; stage <= kStages + 20; ++stage) {
    // the last stage lands on the target exactly (repeated multiplication may stop an ulp short)
    if (stage > 0 && stage <= kStages) d = stage == kStages ? 1.0 : std::min(1.0, d * ratio);
    const double mass = 1.0, k_n = 1.0;
    const cgd::SpringDashpot sd = spring_dashpot(k_n, 0.1, 0.5 * mass, 3.5, 1.0);
    DemSettings s;
    s.box_m = box;
    s.diameter_m = d;
    s.mass_kg = mass;
    s.dt_s = sd.t_c / 25.0;
    s.contacts = true;
    s.friction = false;
    s.contact.k_n = sd.k_n;
    s.contact.gamma_n = sd.gamma_n;
    s.skin_m = 0.1 * d;
    s.drive.drag_rate = 2.0 / sd.t_c;  // overdamped motion: relaxes overlaps in a few contact times
    s.overlap_limit = 0.5;
    DemSystem sys(s, MPI_COMM_SELF);
    sys.set_particles(ids, xs, std::vector<double>(xs.size(), 0.0), {});
    double overlap = 1.0;
    for (int it = 0; it < 2000 && overlap > kTolerance; ++it) {
      sys.step();
      overlap = sys.last_max_overlap_rel();
    }
    // positions back in the original id order (the system sorts particles spatially)
    const Particles& p = sys.particles();
    for (std::size_t i = 0; i < p.n_owned; ++i)
      for (int c = 0; c < 3; ++c) {
        double q = p.x[3 * i + c];
        q -= box[c] * std::floor(q / box[c]);
        xs[3 * p.id[i] + c] = q;
      }
    if (d >= 1.0 && overlap <= kTolerance) {
      for (std::size_t k = 0; k < x.size(); ++k) x[k] = xs[k] * d_target;
      return true;
    }
  }
  return false;
}

}  // namespace cgd::dem
