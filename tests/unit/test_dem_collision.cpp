// Binary collisions of the soft-sphere contact (docs/models.md "Soft-sphere contact", sim/dem/contact.hpp:
// linear spring-dashpot, no attraction, tangential history spring with Coulomb slider) against the
// analytic solutions of the model, run through the whole engine (DemSystem: neighbour list, fused
// leapfrog kernel). Two equal spheres of the paper (d = 75 um, rho_p = 1500 kg/m^3, k_n = 1.27 N/m,
// k_n/k_t = 7/2, gamma_n/gamma_t = 1, m_eff = m/2) meet in the middle of a 20 d periodic box, with
// their centre of mass at rest; every step's state is recorded between advance() and commit().
// Expected values are the exact continuous-time solutions of the model as specified, including its
// no-attraction clip F_n >= 0 (dem_test_util.hpp: clipped_collision): the clip ends the contact force
// before the overlap ends, so the restitution exceeds the nominal e that docs/models.md's gamma_n(e)
// formula assumes (+0.225 % at e = 0.9, +10 % at e = 0.5).
//
// Discretisation errors that set the tolerances (omega = damped contact frequency, beta = gamma_n /
// (2 m_eff) the normal damping rate, dt = t_c/50 unless stated, so omega dt = pi/50 = 0.063):
//  * leapfrog phase error of the spring: (omega dt)^2/24 = 1.6e-4, negligible;
//  * onset quantisation: the dashpot switches on with a jump gamma_n v_0 at the first overlapping
//    sample, which leapfrog applies over [t_k - dt/2, t_k + dt/2] whatever the true touch time in
//    (t_{k-1}, t_k]: an impulse error up to +-gamma_n v_0 dt/2, i.e. a relative error of the rebound
//    speed up to +-beta dt (0.21 % for e = 0.9, 1.4 % for e = 0.5 at dt = t_c/50);
//  * the half-step lag of the dashpot (it uses v_{n-1/2}, integrator.hpp): gamma v_{n-1/2} =
//    gamma v_n - gamma (dt/2) a_n, which stiffens and damps the contact by a factor 1/(1 - beta dt):
//    contact time -beta dt/2, restitution -|ln e| beta dt/2 (relative);
//  * the contact start and end fall between samples; the positions move on straight lines between
//    samples (x_{n+1} = x_n + dt v_{n+1/2}), and the overlap is force-free before the touch and
//    after the normal force has vanished, so linear interpolation of the overlap's zero crossings
//    removes the O(dt/t_c) = 2 % step quantisation of the contact duration.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "dem_test_util.hpp"

namespace {

using cgd::dem::DemSettings;
using cgd::dem::DemSystem;
using cgd::dem::V3;
using namespace cgd::dem::test;

struct Collision {
  double restitution = 0.9;
  double friction = 0.0;
  double steps_per_contact = 50.0;  // dt = t_c / steps_per_contact
  V3 normal{1, 0, 0};               // line of centres at the touch, unit, from particle 1 to particle 0
  V3 tangent{0, 1, 0};              // unit, perpendicular to `normal`
  double approach_speed = 0.1;      // relative normal speed of the centres, m/s
  double tangential_speed = 0.0;    // relative tangential speed of the centres (no spin), m/s
  double phase = 0.5;               // the touch falls this fraction of a step after sample 3
};

struct CollisionRun {
  DemSettings settings;
  std::vector<std::vector<StepState>> frames;  // frames[k][id]: particle id at step k
  std::vector<double> overlap;                 // d - |x_0 - x_1| at step k
  std::size_t first_overlap = 0;               // first step with overlap > 0
  std::size_t first_apart = 0;                 // first step after it with overlap <= 0
  double contact_time_s = 0;                   // from the interpolated zero crossings
  V3 normal_at_touch{0, 0, 0}, normal_at_release{0, 0, 0};
  V3 relative_velocity_before{0, 0, 0}, relative_velocity_after{0, 0, 0};  // v_0 - v_1
  V3 spin_before[2]{}, spin_after[2]{};
};

CollisionRun run_collision(const Collision& c) {
  CollisionRun run;
  const PaperParticle pp;
  run.settings = paper_settings(c.restitution, c.friction, 20.0, c.steps_per_contact);
  const double dt = run.settings.dt_s;
  const V3 u = (-c.approach_speed) * c.normal + c.tangential_speed * c.tangent;  // v_0 - v_1
  const V3 separation = pp.d * c.normal - ((3.0 + c.phase) * dt) * u;            // x_0 - x_1 at t = 0
  const V3 centre{10.0 * pp.d, 10.0 * pp.d, 10.0 * pp.d};
  const V3 x0 = centre + 0.5 * separation, x1 = centre - 0.5 * separation;
  const V3 v0 = 0.5 * u, v1 = -0.5 * u;
  DemSystem sys(run.settings, MPI_COMM_SELF);
  sys.set_particles({0, 1}, {x0.x, x0.y, x0.z, x1.x, x1.y, x1.z}, {v0.x, v0.y, v0.z, v1.x, v1.y, v1.z}, {});
  const auto steps = static_cast<std::size_t>(1.5 * c.steps_per_contact) + 10;
  for (std::size_t k = 0; k < steps; ++k) {
    run.frames.push_back(recorded_step(sys, 2));
    run.overlap.push_back(pp.d - norm(run.frames[k][0].x - run.frames[k][1].x));
  }
  while (run.first_overlap < steps && !(run.overlap[run.first_overlap] > 0)) ++run.first_overlap;
  run.first_apart = run.first_overlap;
  while (run.first_apart < steps && run.overlap[run.first_apart] > 0) ++run.first_apart;
  EXPECT_EQ(run.first_overlap, 4u) << "the touch was placed between samples 3 and 4";
  EXPECT_LT(run.first_apart, steps) << "the spheres did not separate within the run";
  if (run.first_apart >= steps || run.first_overlap == 0) return run;
  const std::size_t a = run.first_overlap, b = run.first_apart;
  const double start = zero_crossing(run.overlap[a - 1], run.overlap[a], a);
  const double end = zero_crossing(run.overlap[b - 1], run.overlap[b], b);
  run.contact_time_s = (end - start) * dt;
  run.normal_at_touch = normalized(run.frames[a][0].x - run.frames[a][1].x);
  run.normal_at_release = normalized(run.frames[b][0].x - run.frames[b][1].x);
  const auto& first = run.frames.front();
  const auto& last = run.frames.back();
  run.relative_velocity_before = first[0].v_half_before - first[1].v_half_before;
  run.relative_velocity_after = last[0].v_half_after - last[1].v_half_after;
  for (int i = 0; i < 2; ++i) {
    run.spin_before[i] = first[i].w_half_before;
    run.spin_after[i] = last[i].w_half_after;
  }
  return run;
}

double relative_error(double measured, double expected) {
  return measured / expected - 1.0;
}

// Head-on: e_measured = (rebound normal speed)/(approach speed) and the overlap duration, against the
// exact solution of the clipped linear model (dem_test_util.hpp: clipped_collision). The model's
// e and t_c are independent of the impact speed (linear force law); with the touch at the same
// fraction of a step and the initial gap scaled with the speed, the discrete problem is the same up to
// scale, so e and t_c must agree across speeds to round-off. A head-on impact has no tangential
// slip, so friction must change nothing.
TEST(DemBinaryCollision, HeadOnRestitutionAndContactTime) {
  const PaperParticle pp;
  const V3 n = normalized(V3{1, 2, 2});  // off-axis: exercises all three components
  const V3 t = normalized(V3{2, 1, -2});
  struct Series {
    double restitution, steps_per_contact;
  };
  // e = 0.5 has beta dt = 1.4 % at t_c/50 (see the header), above the 0.5 % asked of the contact;
  // it is checked at t_c/200 here (beta dt = 0.35 %) and at t_c/50 below with its first-order bound.
  const Series series[] = {{0.5, 200.0}, {0.9, 50.0}, {0.99, 50.0}};
  const double speeds[] = {0.01, 0.1, 1.0};  // m/s, relative; max overlap v/omega = 15 % of d at 1 m/s
  const double phases[] = {0.125, 0.375, 0.625, 0.875};
  for (const Series& s : series) {
    const cgd::SpringDashpot sd = paper_contact(s.restitution, pp.mass);
    const ClippedCollision model = clipped_collision(sd.k_n, sd.gamma_n, 0.5 * pp.mass);
    double worst_e = 0, worst_t = 0, min_e = HUGE_VAL, max_e = 0;
    for (double phase : phases) {
      double e_ref = 0, t_ref = 0;  // mu = 0, slowest impact: the reference for speed and friction
      for (double mu : {0.0, 0.1}) {
        for (double speed : speeds) {
          Collision c;
          c.restitution = s.restitution;
          c.friction = mu;
          c.steps_per_contact = s.steps_per_contact;
          c.normal = n;
          c.tangent = t;
          c.approach_speed = speed;
          c.phase = phase;
          const CollisionRun run = run_collision(c);
          const double e_measured = dot(run.relative_velocity_after, run.normal_at_release) / speed;
          SCOPED_TRACE(::testing::Message() << "e = " << s.restitution << ", mu = " << mu << ", v = " << speed
                                            << " m/s, phase = " << phase);
          // 0.5 %: the onset quantisation (<= beta dt = 0.21 % at e = 0.9, 0.35 % at e = 0.5 with
          // t_c/200) plus the dashpot lag (|ln e| beta dt/2 <= 0.13 %) and the interpolation residual.
          EXPECT_NEAR(relative_error(e_measured, model.restitution), 0.0, 5e-3);
          EXPECT_NEAR(relative_error(run.contact_time_s, model.overlap_time_s), 0.0, 5e-3);
          if (s.restitution >= 0.9) {
            // Against the nominal e and t_c of docs/models.md: the clip raises e by 0.225 % at e = 0.9
            // (0.002 % at 0.99) and shortens the overlap by < 2e-5, so with the discretisation above
            // both stay within 0.5 % (at e = 0.5 the clip alone raises e by 10 %: see the printout).
            EXPECT_NEAR(relative_error(e_measured, s.restitution), 0.0, 5e-3);
            EXPECT_NEAR(relative_error(run.contact_time_s, sd.t_c), 0.0, 5e-3);
          }
          worst_e = std::max(worst_e, std::abs(relative_error(e_measured, model.restitution)));
          worst_t = std::max(worst_t, std::abs(relative_error(run.contact_time_s, model.overlap_time_s)));
          min_e = std::min(min_e, e_measured);
          max_e = std::max(max_e, e_measured);
          if (e_ref == 0) {
            e_ref = e_measured;
            t_ref = run.contact_time_s;
          } else {
            // round-off: positions carry an absolute error ~eps |x| = 2e-19 m against overlaps of
            // >= 1e-7 m (v = 0.01 m/s), i.e. <= 1e-12 per step over <= 300 steps.
            EXPECT_NEAR(e_measured / e_ref, 1.0, 1e-9) << "restitution depends on speed or friction";
            EXPECT_NEAR(run.contact_time_s / t_ref, 1.0, 1e-9) << "contact time depends on speed or friction";
          }
          // no tangential slip, so no spin: only round-off of the tangential projection of a force
          // along n (~1e-16 of the normal impulse) can turn the spheres.
          if (mu > 0) {
            const double spin_scale = speed / pp.radius;
            for (int i = 0; i < 2; ++i) EXPECT_LT(norm(run.spin_after[i]), 1e-12 * spin_scale);
          }
        }
      }
    }
    std::printf(
        "[ head-on  ] e = %.2f (dt = t_c/%g): model e_clip = %.6f (nominal %+.3f %%), overlap time "
        "T = %.6e s = t_c %+.3f %%; worst measured deviation from the model: e %.3f %%, T %.3f %%; "
        "measured e / nominal e - 1 in [%+.3f, %+.3f] %%\n",
        s.restitution, s.steps_per_contact, model.restitution,
        100 * relative_error(model.restitution, s.restitution), model.overlap_time_s,
        100 * relative_error(model.overlap_time_s, sd.t_c), 100 * worst_e, 100 * worst_t,
        100 * relative_error(min_e, s.restitution), 100 * relative_error(max_e, s.restitution));
  }

  // e = 0.5 at the paper's dt = t_c/50: the first-order errors of the header are beta dt = 1.4 %.
  // Bounds: restitution <= beta dt (onset) + |ln e| beta dt/2 (lag) = 1.35 beta dt; contact time
  // <= beta dt/2 (lag stiffening) + beta dt/2 (onset shifts the compression phase) = beta dt.
  {
    const cgd::SpringDashpot sd = paper_contact(0.5, pp.mass);
    const ClippedCollision model = clipped_collision(sd.k_n, sd.gamma_n, 0.5 * pp.mass);
    const double beta_dt = sd.gamma_n / pp.mass * (sd.t_c / 50.0);  // gamma_n/(2 m_eff) dt
    double worst_e = 0, worst_t = 0;
    for (double phase : phases) {
      Collision c;
      c.restitution = 0.5;
      c.normal = n;
      c.tangent = t;
      c.phase = phase;
      const CollisionRun run = run_collision(c);
      const double e_measured = dot(run.relative_velocity_after, run.normal_at_release) / c.approach_speed;
      EXPECT_LE(std::abs(relative_error(e_measured, model.restitution)), 1.35 * beta_dt) << "phase " << phase;
      EXPECT_LE(std::abs(relative_error(run.contact_time_s, model.overlap_time_s)), beta_dt)
          << "phase " << phase;
      worst_e = std::max(worst_e, std::abs(relative_error(e_measured, model.restitution)));
      worst_t = std::max(worst_t, std::abs(relative_error(run.contact_time_s, model.overlap_time_s)));
    }
    std::printf(
        "[ head-on  ] e = 0.50 (dt = t_c/50): beta dt = %.3f %%; worst deviation e %.3f %%, T %.3f %%\n",
        100 * beta_dt, 100 * worst_e, 100 * worst_t);
  }
}

/// Per-step impulse on particle 0, split along the line of centres of that step (the engine's n).
struct ImpulseSplit {
  double normal = 0;             // sum of the normal components, N s
  double tangential = 0;         // sum of the tangential magnitudes, N s
  V3 spin_predicted[2]{};        // sum of dt T_k / I, T_k = -(R - delta_k/2) n_k x F_t,k, per particle
  V3 spin_full_radius{0, 0, 0};  // the same with lever arm R (for the failure message)
  std::size_t sliding_steps = 0, contact_steps = 0;
};

ImpulseSplit split_impulses(const CollisionRun& run, double friction) {
  const PaperParticle pp;
  ImpulseSplit s;
  for (const auto& f : run.frames) {
    const V3 impulse = pp.mass * (f[0].v_half_after - f[0].v_half_before);  // F dt on particle 0
    if (dot(impulse, impulse) == 0) continue;
    const V3 n = normalized(f[0].x - f[1].x);  // from 1 to 0, as in the kernel
    const double jn = dot(impulse, n);
    const V3 jt = impulse - jn * n;
    s.normal += jn;
    s.tangential += norm(jt);
    ++s.contact_steps;
    if (norm(jt) > (1 - 1e-9) * friction * jn) ++s.sliding_steps;
    // The tangential force acts at the contact point, in the middle of the overlap, at lever arm
    // R - delta/2 from each centre (the two arms add up to the centre distance r, which is what makes
    // the pair's forces and torques conserve angular momentum; test_dem_conservation.cpp):
    // T_0 = (-(R - delta/2) n) x F_t and T_1 = ((R - delta/2) n) x (-F_t), the same torque on both.
    const double lever = pp.radius - 0.5 * (pp.d - norm(f[0].x - f[1].x));
    const V3 angular = (-lever / pp.inertia) * cross(n, jt);
    s.spin_predicted[0] = s.spin_predicted[0] + angular;
    s.spin_predicted[1] = s.spin_predicted[1] + angular;
    s.spin_full_radius = s.spin_full_radius + (-pp.radius / pp.inertia) * cross(n, jt);
  }
  return s;
}

// Oblique impact at tan(angle) = v_t/v_n = 5 with mu = 0.1: the contact point slides throughout
// (the tangential contact-point velocity changes by at most 3.5 mu (1 + e) v_n = 0.67 v_n < 5 v_n,
// the factor 3.5 = 1 + m R^2/I being the rotational contribution; at the onset the trial tangential
// force gamma_t v_t = 5 gamma_n v_n already exceeds mu F_n), so every step's tangential force is the
// Coulomb limit mu F_n and the tangential impulse is mu times the normal impulse.
TEST(DemBinaryCollision, ObliqueSlidingTangentialImpulse) {
  const PaperParticle pp;
  const double mu = 0.1;
  const V3 n = normalized(V3{1, 2, 2});
  const V3 t = normalized(V3{2, 1, -2});

  // (a) Per step, split along that step's line of centres (reconstructed from x_n exactly as the
  // kernel forms it): |J_t| = mu J_n at every step, to round-off. A fast impact (v_n = 0.1 m/s)
  // turns the line of centres by v_t t_c/d ~ 0.2 rad during the contact, which must not matter.
  // Tolerance 1e-9: the impulses are recovered from differences of half-step velocities, each
  // rounded to eps |v| ~ 3e-17 m/s against per-step changes >= 1e-5 m/s of the larger ones.
  // Spin: each step's torque is the tangential force at the contact point, so I dw = sum_k -(R -
  // delta_k/2) n_k x J_t,k for each sphere, to round-off (1e-10); the overlap delta_k reaches 1.5 %
  // of d here, so a lever arm of the full radius R would differ by ~1 %.
  {
    Collision c;
    c.friction = mu;
    c.normal = n;
    c.tangent = t;
    c.approach_speed = 0.1;
    c.tangential_speed = 0.5;
    const CollisionRun run = run_collision(c);
    const ImpulseSplit s = split_impulses(run, mu);
    EXPECT_EQ(s.sliding_steps, s.contact_steps) << "the contact stuck at some step";
    EXPECT_NEAR(s.tangential / (mu * s.normal), 1.0, 1e-9);
    for (int i = 0; i < 2; ++i) {
      const V3 spin_change = run.spin_after[i] - run.spin_before[i];
      EXPECT_LT(norm(spin_change - s.spin_predicted[i]), 1e-10 * norm(spin_change))
          << "particle " << i << ": |dw| / |contact-point prediction| - 1 = "
          << norm(spin_change) / norm(s.spin_predicted[i]) - 1.0
          << ", |dw - full-radius-lever prediction| / |dw| = "
          << norm(spin_change - s.spin_full_radius) / norm(spin_change);
    }
    std::printf(
        "[ sliding  ] per-step split, v_n = 0.1 m/s: J_t/(mu J_n) - 1 = %.2e over %zu steps (all sliding: "
        "%zu)\n",
        s.tangential / (mu * s.normal) - 1.0, s.contact_steps, s.sliding_steps);
  }

  // (b) The whole collision from the velocity changes, split along the line of centres at the touch.
  // The line of centres turns by dtheta = v_t t_c/d during the contact, which tilts the normal force
  // into the fixed tangent direction (against the friction): J_t/(mu J_n) ~ 1 - <theta>/mu with
  // <theta> ~ dtheta/2. A slow impact (v_n = 4e-4 m/s, v_t = 2e-3 m/s) keeps dtheta = 1e-3 rad, so
  // the deficit is ~0.5 %; tolerance 1.5 %. The spin change is then R J_t/I for each particle to the
  // same tolerance (the vector form is checked exactly in (a)).
  for (double phase : {0.125, 0.375, 0.625, 0.875}) {
    Collision c;
    c.friction = mu;
    c.normal = n;
    c.tangent = t;
    c.approach_speed = 4e-4;
    c.tangential_speed = 2e-3;
    c.phase = phase;
    const CollisionRun run = run_collision(c);
    const V3 impulse = (0.5 * pp.mass) * (run.relative_velocity_after - run.relative_velocity_before);
    const V3 n_touch = run.normal_at_touch;
    const double jn = dot(impulse, n_touch);
    const double jt = norm(impulse - jn * n_touch);
    const double dtheta = c.tangential_speed * run.contact_time_s / pp.d;
    EXPECT_NEAR(jt / (mu * jn), 1.0, 1.5e-2);
    for (int i = 0; i < 2; ++i) {
      const double spin_change = norm(run.spin_after[i] - run.spin_before[i]);
      EXPECT_NEAR(spin_change / (pp.radius * jt / pp.inertia), 1.0, 1.5e-2) << "particle " << i;
    }
    const ImpulseSplit s = split_impulses(run, mu);
    EXPECT_EQ(s.sliding_steps, s.contact_steps) << "the contact stuck at some step";
    EXPECT_NEAR(s.tangential / (mu * s.normal), 1.0, 1e-9);
    std::printf(
        "[ sliding  ] whole-collision split, v_n = 4e-4 m/s, phase %.3f: J_t/(mu J_n) = %.5f, "
        "dtheta/(2 mu) = %.5f, |dw| I/(R J_t) = %.5f\n",
        phase, jt / (mu * jn), dtheta / (2 * mu),
        norm(run.spin_after[0] - run.spin_before[0]) * pp.inertia / (pp.radius * jt));
  }
}

/// Velocity and acceleration of a damped oscillator x'' + 2 beta x' + omega0^2 x = 0 with x(0) = 0,
/// x'(0) = 1, at time t (underdamped, beta < omega0, w^2 = omega0^2 - beta^2):
///   x = e^{-beta t} sin(w t)/w,  x' = e^{-beta t} (cos w t - (beta/w) sin w t),  x'' = -2 beta x' - omega0^2
///   x.
struct OscillatorState {
  double velocity, acceleration;
};
OscillatorState damped_oscillator(double omega0, double beta, double t) {
  const double w = std::sqrt(omega0 * omega0 - beta * beta);
  const double x = std::exp(-beta * t) * std::sin(w * t) / w;
  const double v = std::exp(-beta * t) * (std::cos(w * t) - beta / w * std::sin(w * t));
  return {v, -2.0 * beta * v - omega0 * omega0 * x};
}

// Small-angle oblique impact (v_t/v_n = 0.5) with mu = 10: the tangential spring never reaches the
// Coulomb limit while the normal force is positive (at the onset gamma_t v_t = 0.5 gamma_n v_n <
// 10 F_n; checked at every step below), so the contact point's tangential motion is the damped
// oscillator
//   m_t x'' + gamma_t x' + k_t x = 0,  m_t = m_eff/(1 + m R^2/I) = (2/7) m_eff
// (a tangential force F on the pair changes the contact-point velocity through both translation,
// 1/m_eff, and the spins, 2 R^2/I = 5/(2 m_eff)). With k_n/k_t = 7/2 its undamped frequency equals the
// normal one; its damping rate is gamma_t/(2 m_t) = 3.5 beta_n. It acts while the normal force is
// positive, i.e. for the clipped model's t* (dem_test_util.hpp), not the full t_c: after t* the
// Coulomb limit mu F_n = 0 releases the spring (for e = 0.9, t* = 0.979 t_c; the oscillator over t_c
// would give a 1.2 % smaller ratio). The tangential restitution of the contact point is
// x'(t*)/x'(0) (negative: the contact point's tangential velocity reverses).
// Tolerance: the tangential force acts at the whole steps with F_n > 0, so its duration is quantised
// to dt, which moves the ratio by up to |x''(t*)| dt (0.65 % of x'(0) here, depending on where the
// touch falls in a step), plus 1 % for the rest: onset of the tangential spring at the first overlapping
// sample, half-step lag of its increment (xi += dt v_{n-1/2}) and dashpot, and the turn of the line of
// centres (v_t t_c/d = 2.4e-3 rad at v_t = 5e-3 m/s).
TEST(DemBinaryCollision, ObliqueStickingTangentialRestitution) {
  const PaperParticle pp;
  const double e = 0.9, mu = 10.0;
  const cgd::SpringDashpot sd = paper_contact(e, pp.mass);
  const double m_eff = 0.5 * pp.mass;
  const double m_t = m_eff / (1.0 + pp.mass * pp.radius * pp.radius / pp.inertia);  // (2/7) m_eff
  const double omega_t = std::sqrt(sd.k_t / m_t), beta_t = sd.gamma_t / (2.0 * m_t);
  const ClippedCollision normal = clipped_collision(sd.k_n, sd.gamma_n, m_eff);
  const OscillatorState at_release = damped_oscillator(omega_t, beta_t, normal.force_time_s);
  const double expected_tstar = at_release.velocity;
  const double expected_tc = damped_oscillator(omega_t, beta_t, sd.t_c).velocity;
  const double quantisation = std::abs(at_release.acceleration) * (sd.t_c / 50.0);

  // tangential velocity of the contact points, v_0 - v_1 - (R w_0 + R w_1) x n, without its n part
  auto contact_point_tangential = [&](V3 dv, const V3* w, V3 nrm) {
    const V3 vc = dv - cross(pp.radius * w[0] + pp.radius * w[1], nrm);
    return vc - dot(vc, nrm) * nrm;
  };
  for (double phase : {0.125, 0.375, 0.625, 0.875}) {
    Collision c;
    c.restitution = e;
    c.friction = mu;
    c.normal = normalized(V3{1, 2, 2});
    c.tangent = normalized(V3{2, 1, -2});
    c.approach_speed = 0.01;
    c.tangential_speed = 5e-3;
    c.phase = phase;
    const CollisionRun run = run_collision(c);
    const V3 before =
        contact_point_tangential(run.relative_velocity_before, run.spin_before, run.normal_at_touch);
    const V3 after =
        contact_point_tangential(run.relative_velocity_after, run.spin_after, run.normal_at_release);
    const double measured = dot(after, before) / dot(before, before);
    EXPECT_NEAR(measured, expected_tstar, quantisation + 1e-2 * std::abs(expected_tstar))
        << "phase " << phase;
    EXPECT_EQ(split_impulses(run, mu).sliding_steps, 0u) << "the contact slid at some step, phase " << phase;
    // the normal restitution is unaffected by the sticking friction (same bound as head-on)
    EXPECT_NEAR(
        dot(run.relative_velocity_after, run.normal_at_release) / c.approach_speed / normal.restitution, 1.0,
        5e-3)
        << "phase " << phase;
    std::printf(
        "[ sticking ] phase %.3f: tangential contact-point restitution measured %.5f, oscillator over t* "
        "%.5f (quantisation bound %.4f), over t_c %.5f\n",
        phase, measured, expected_tstar, quantisation, expected_tc);
  }
}

}  // namespace
