#pragma once
// Reference scales and contact parameters of docs/models.md ("Reference scales", "Soft-sphere contact").
// Pure functions: the scene loader, the DEM and the tests all derive their numbers here.
#include <cmath>
#include <numbers>

namespace cgd {

/// Volume of a sphere of diameter d.
inline double sphere_volume(double d) { return std::numbers::pi / 6.0 * d * d * d; }

/// Single-particle terminal velocity with Schiller-Naumann drag at eps = 1 (docs/models.md convention):
///   u = (rho_p - rho_f) g d^2 / (18 mu (1 + 0.15 Re^0.687)),  Re = rho_f d u / mu,
/// solved by fixed-point iteration (a contraction for Re < ~1e3; converges to 1e-14 relative).
double schiller_naumann_terminal_velocity(double d_m, double rho_p, double rho_f, double mu_f, double g);

/// Stiffness from the paper's dimensionless shear rate gamma* = (g/u_t) sqrt(rho_p d^3 / k_n):
///   k_n = rho_p d^3 (g / (u_t gamma*))^2     (docs/models.md; 1.27 N/m for gamma* = 1e-3).
inline double stiffness_from_gamma_star(double gamma_star, double rho_p, double d_m, double g, double u_t) {
  const double r = g / (u_t * gamma_star);
  return rho_p * d_m * d_m * d_m * r * r;
}

/// Linear spring-dashpot parameters for one pair type (docs/models.md, Cundall-Strack):
///   gamma_n = 2 sqrt(m_eff k_n) |ln e| / sqrt(pi^2 + ln^2 e),
///   t_c = pi / sqrt(k_n/m_eff - gamma_n^2/(4 m_eff^2)),  k_t = k_n/(kn/kt),  gamma_t = gamma_n/(gn/gt).
struct SpringDashpot {
  double k_n = 0, k_t = 0;          // N/m
  double gamma_n = 0, gamma_t = 0;  // kg/s (force = gamma * relative velocity)
  double t_c = 0;                   // s, duration of a head-on contact
};

inline SpringDashpot spring_dashpot(double k_n, double restitution, double m_eff, double kn_over_kt,
                                    double gamman_over_gammat) {
  SpringDashpot p;
  const double ln_e = std::log(restitution);
  p.k_n = k_n;
  p.k_t = k_n / kn_over_kt;
  p.gamma_n = 2.0 * std::sqrt(m_eff * k_n) * std::abs(ln_e) / std::sqrt(std::numbers::pi * std::numbers::pi + ln_e * ln_e);
  p.gamma_t = p.gamma_n / gamman_over_gammat;
  p.t_c = std::numbers::pi / std::sqrt(k_n / m_eff - p.gamma_n * p.gamma_n / (4.0 * m_eff * m_eff));
  return p;
}

}  // namespace cgd
