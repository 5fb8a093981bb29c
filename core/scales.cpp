#include "core/scales.hpp"

namespace cgd {

double schiller_naumann_terminal_velocity(double d_m, double rho_p, double rho_f, double mu_f, double g) {
  const double stokes = (rho_p - rho_f) * g * d_m * d_m / (18.0 * mu_f);
  double u = stokes;
  for (int it = 0; it < 200; ++it) {
    const double re = rho_f * d_m * u / mu_f;
    const double next = stokes / (1.0 + 0.15 * std::pow(re, 0.687));
    // Damped update: the plain fixed point oscillates for Re of order 10 and above.
    const double updated = 0.5 * (u + next);
    if (std::abs(updated - u) <= 1e-15 * u) return updated;
    u = updated;
  }
  return u;
}

}  // namespace cgd
