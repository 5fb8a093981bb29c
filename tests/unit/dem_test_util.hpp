#pragma once
// Shared helpers for the DEM verification tests (test_dem_collision.cpp, test_dem_conservation.cpp,
// test_dem_settling.cpp): the paper's particle and contact parameters, a DemSettings builder, and a
// recorder that reads one step's state (x_n, v_{n-1/2}, v_{n+1/2}, w_{n-1/2}, w_{n+1/2}) by particle
// id between advance() and commit(), so that per-step impulses can be reconstructed exactly.
#include <mpi.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include "core/scales.hpp"
#include "sim/dem/system.hpp"

namespace cgd::dem::test {

using cgd::dem::V3;

inline double norm(V3 a) {
  return std::sqrt(dot(a, a));
}
inline V3 normalized(V3 a) {
  return (1.0 / norm(a)) * a;
}

/// The paper's particles (docs/models.md, Table 1): d = 75 um, rho_p = 1500 kg/m^3.
struct PaperParticle {
  double d = 75e-6;                                        // m
  double rho = 1500.0;                                     // kg/m^3
  double mass = rho * std::numbers::pi / 6.0 * d * d * d;  // kg
  double radius = 0.5 * d;                                 // m
  double inertia = 0.4 * mass * radius * radius;           // solid sphere, kg m^2
};

/// The paper's contact: k_n = 1.27 N/m, k_n/k_t = 7/2, gamma_n/gamma_t = 1, m_eff = m/2.
inline cgd::SpringDashpot paper_contact(double restitution, double mass) {
  return cgd::spring_dashpot(1.27, restitution, 0.5 * mass, 3.5, 1.0);
}

/// Settings for a dry DEM run of the paper's particles with restitution `e` and friction `mu`
/// (mu = 0 switches the tangential force, the history and the rotation off) in a cubic box of
/// edge `box_d` diameters, dt = t_c / `steps_per_contact`.
inline DemSettings paper_settings(double e, double mu, double box_d, double steps_per_contact = 50.0) {
  const PaperParticle pp;
  const cgd::SpringDashpot sd = paper_contact(e, pp.mass);
  DemSettings s;
  s.box_m = {box_d * pp.d, box_d * pp.d, box_d * pp.d};
  s.diameter_m = pp.d;
  s.mass_kg = pp.mass;
  s.dt_s = sd.t_c / steps_per_contact;
  s.contacts = true;
  s.friction = mu > 0.0;
  s.contact.k_n = sd.k_n;
  s.contact.k_t = sd.k_t;
  s.contact.gamma_n = sd.gamma_n;
  s.contact.gamma_t = sd.gamma_t;
  s.contact.friction = mu;
  s.skin_m = 0.3 * pp.d;
  return s;
}

/// One particle's state at step n, read between advance() and commit().
struct StepState {
  V3 x{0, 0, 0};              // x_n
  V3 v_half_before{0, 0, 0};  // v_{n-1/2}
  V3 v_half_after{0, 0, 0};   // v_{n+1/2}
  V3 w_half_before{0, 0, 0};  // w_{n-1/2} (zero without rotation)
  V3 w_half_after{0, 0, 0};   // w_{n+1/2}
};

/// Runs one step and returns the state of particles 0..count-1 (by id) at that step.
inline std::vector<StepState> recorded_step(DemSystem& sys, std::size_t count) {
  sys.prepare();
  sys.advance();
  const Particles& p = sys.particles();
  const std::vector<double> v_next = sys.next_velocity(), w_next = sys.next_angular_velocity();
  std::vector<StepState> out(count);
  for (std::size_t i = 0; i < p.n_owned; ++i) {
    const auto id = static_cast<std::size_t>(p.id[i]);
    if (id >= count) continue;
    StepState& s = out[id];
    s.x = load3(&p.x[3 * i]);
    s.v_half_before = load3(&p.v[3 * i]);
    s.v_half_after = load3(&v_next[3 * i]);
    if (p.rotation) {
      s.w_half_before = load3(&p.w[3 * i]);
      s.w_half_after = load3(&w_next[3 * i]);
    }
  }
  sys.commit();
  return out;
}

/// Current (committed) position / half-step velocity / angular velocity of particle `id`.
inline std::size_t local_index(const DemSystem& sys, std::int64_t id) {
  const Particles& p = sys.particles();
  for (std::size_t i = 0; i < p.n_owned; ++i)
    if (p.id[i] == id) return i;
  return p.n_owned;
}

/// Time at which a sampled signal crosses zero between samples k-1 and k (linear interpolation),
/// in units of the sample spacing.
inline double zero_crossing(double before, double after, std::size_t k) {
  return static_cast<double>(k - 1) + before / (before - after);
}

/// Exact continuous-time head-on collision of the linear spring-dashpot with the no-attraction clip
/// (docs/models.md: F_n = max(0, k_n delta - gamma_n v_n)). With beta = gamma_n/(2 m_eff) and omega the
/// damped frequency, the overlap obeys delta = (v0/omega) e^{-beta t} sin(omega t) until the force
/// k delta + gamma delta' vanishes, i.e. until delta'' = 0, at omega t* = theta* = pi - atan(2 beta
/// omega / (omega^2 - beta^2)). There |delta'| = v0 e^{-beta t*} (the bracket cos - (beta/omega) sin
/// equals -1 exactly), and the spheres then separate force-free, so
///   e_clip = exp(-(beta/omega) theta*),
/// larger than the nominal e = exp(-(beta/omega) pi) of the unclipped oscillator (Schwager & Poeschel,
/// Granular Matter 9 (2007) 465). The overlap reaches zero (sin theta*)/omega after t*, so the
/// duration of the overlap is T = (theta* + sin theta*)/omega = t_c (theta* + sin theta*)/pi.
struct ClippedCollision {
  double restitution = 0;     // e_clip
  double force_time_s = 0;    // t*: while the normal force is positive
  double overlap_time_s = 0;  // T: while the spheres overlap
};

inline ClippedCollision clipped_collision(double k_n, double gamma_n, double m_eff) {
  const double beta = gamma_n / (2.0 * m_eff);
  const double omega = std::sqrt(k_n / m_eff - beta * beta);
  const double theta = std::numbers::pi - std::atan(2.0 * beta * omega / (omega * omega - beta * beta));
  ClippedCollision c;
  c.restitution = std::exp(-beta / omega * theta);
  c.force_time_s = theta / omega;
  c.overlap_time_s = (theta + std::sin(theta)) / omega;
  return c;
}

}  // namespace cgd::dem::test
