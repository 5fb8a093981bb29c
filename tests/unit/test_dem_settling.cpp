// A single particle settling in a quiescent fluid under the engine's uniform drive (integrator.hpp:
// a = g - lambda v, lambda = 3 pi mu_f d / m for Stokes drag), and the effects that are switched off
// generate no state: no rotation without friction, no neighbour list or ghosts without contacts.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "dem_test_util.hpp"
#include "sim/dem/placement.hpp"

namespace {

using cgd::dem::DemSettings;
using cgd::dem::DemSystem;
using cgd::dem::Diagnostics;
using namespace cgd::dem::test;

// Stokes settling of one paper particle (d = 75 um, rho_p = 1500 kg/m^3) in air-like viscosity
// mu_f = 1.8e-5 Pa s, g = 9.81 m/s^2 (no buoyancy: the drive's accel is g itself). Drag rate
// lambda = 3 pi mu_f d / m = 1/tau, terminal velocity u_t = m g/(3 pi mu_f d) = g/lambda.
// The kernel updates the half-step velocity explicitly, v_{k+1/2} = v_{k-1/2} + dt (g - lambda
// v_{k-1/2}), so from rest v after k steps is exactly u_t (1 - (1 - h)^k), h = dt/tau: its fixed
// point is u_t exactly, and it is checked to round-off at every step. Against the continuous
// solution u_t (1 - e^{-t/tau}) at t = k dt the difference e^{-kh} - (1-h)^k lies in
// [0, k h^2 e^{-kh}/(2(1-h))], whose largest value over k is h/(2e(1-h)): the history follows the
// exponential within that first-order bound. The contact time step (t_c/50 = 7.2e-7 s) is 3.6e4 times
// smaller than tau = 0.026 s; the drag alone does not need it, and h = 1/100 keeps the run at 2000
// steps and the O(dt/tau) term measurable. After 20 tau, (1-h)^2000 = e^{-20.1} = 2e-9 < 1e-6.
TEST(DemSettling, StokesTerminalVelocity) {
  const PaperParticle pp;
  const double mu_f = 1.8e-5, g = 9.81;
  const double drag_rate = 3.0 * std::numbers::pi * mu_f * pp.d / pp.mass;  // 1/s
  const double tau = 1.0 / drag_rate;
  const double u_t = pp.mass * g / (3.0 * std::numbers::pi * mu_f * pp.d);
  const double h = 0.01;

  DemSettings s = paper_settings(0.9, 0.1, 20.0);
  s.contacts = false;  // one particle: nothing to touch
  s.dt_s = h * tau;
  s.drive.accel = {0.0, -g, 0.0};
  s.drive.drag_rate = drag_rate;
  DemSystem sys(s, MPI_COMM_SELF);
  const double x0 = 10.0 * pp.d;
  sys.set_particles({0}, {x0, x0, x0}, {0.0, 0.0, 0.0}, {});

  const int steps = static_cast<int>(std::lround(20.0 / h));
  const double history_bound = h / (2.0 * std::numbers::e * (1.0 - h));
  double worst_history = 0, worst_discrete = 0;
  double decay = 1.0;  // (1 - h)^k
  for (int k = 1; k <= steps; ++k) {
    sys.step();
    decay *= 1.0 - h;
    const double v = -sys.particles().v[1] / u_t;  // settling speed / u_t (downward: -y)
    worst_discrete = std::max(worst_discrete, std::abs(v - (1.0 - decay)));
    worst_history = std::max(worst_history, std::abs(v - (1.0 - std::exp(-k * h))));
    ASSERT_EQ(sys.particles().v[0], 0.0);
    ASSERT_EQ(sys.particles().v[2], 0.0);
  }
  const double final_speed = -sys.particles().v[1];
  EXPECT_NEAR(final_speed / u_t, 1.0, 1e-6);
  // round-off: each step rounds v to eps |v| and the error is contracted by (1 - h) per step, so it
  // stays below ~eps/h = 2e-14
  EXPECT_LT(worst_discrete, 1e-12);
  EXPECT_LE(worst_history, history_bound);
  std::printf(
      "[ settling ] tau = %.4e s, u_t = %.6f m/s: after 20 tau v/u_t - 1 = %.2e; max deviation from the "
      "exact discrete solution %.1e, from 1 - exp(-t/tau) %.3e (bound h/(2e(1-h)) = %.3e)\n",
      tau, u_t, final_speed / u_t - 1.0, worst_discrete, worst_history, history_bound);
}

// Friction off (settings.friction = false, as the scene loader sets it for mu = 0): no angular
// velocity is allocated or reported, and stepping a colliding gas works. Contacts off: no neighbour
// list and no ghosts are built, no rotation even with friction requested, and overlapping particles
// pass through each other unaffected (ballistic motion, velocities unchanged bit for bit).
TEST(DemEffects, FrictionOffAllocatesNoRotation) {
  const PaperParticle pp;
  const std::int64_t count = 300;
  const double edge = std::cbrt(count * std::numbers::pi / 6.0 * pp.d * pp.d * pp.d / 0.2);
  const cgd::dem::Placement placement = cgd::dem::place_particles({edge, edge, edge}, pp.d, count, 0.1, 5);
  std::vector<std::int64_t> ids(count);
  for (std::int64_t i = 0; i < count; ++i) ids[i] = i;

  {
    DemSettings s = paper_settings(0.9, 0.0, 1.0);
    s.box_m = {edge, edge, edge};
    ASSERT_FALSE(s.friction);
    DemSystem sys(s, MPI_COMM_SELF);
    sys.set_particles(ids, placement.position, placement.velocity, {});
    double contacts = 0;
    for (int k = 0; k < 200; ++k) {
      sys.prepare();
      sys.advance();
      const Diagnostics d = sys.diagnostics();
      EXPECT_TRUE(sys.synchronous_angular_velocity().empty());
      EXPECT_EQ(d.kinetic_rotational_J, 0.0);
      for (int c = 0; c < 3; ++c) EXPECT_EQ(d.angular_momentum_spin[c], 0.0);
      contacts += d.contacts;
      sys.commit();
    }
    EXPECT_FALSE(sys.particles().rotation);
    EXPECT_TRUE(sys.particles().w.empty());
    EXPECT_TRUE(sys.next_angular_velocity().empty());
    EXPECT_GT(sys.neighbor_entries(), 0u);
    EXPECT_GT(contacts, 0.0) << "the gas should have collided";
  }

  {
    DemSettings s = paper_settings(0.9, 0.1, 20.0);
    s.contacts = false;
    ASSERT_TRUE(s.friction);
    DemSystem sys(s, MPI_COMM_SELF);
    // two particles overlapping by half a diameter and approaching: with contacts they would repel
    const double c = 10.0 * pp.d;
    sys.set_particles({0, 1}, {c, c, c, c + 0.5 * pp.d, c, c}, {0.05, 0.01, 0.0, -0.05, 0.0, 0.02}, {});
    for (int k = 0; k < 100; ++k) sys.step();
    EXPECT_FALSE(sys.particles().rotation);
    EXPECT_TRUE(sys.particles().w.empty());
    EXPECT_EQ(sys.neighbor_entries(), 0u);
    EXPECT_EQ(sys.ghosts(), 0u);
    const std::size_t i0 = local_index(sys, 0), i1 = local_index(sys, 1);
    ASSERT_LT(i0, 2u);
    ASSERT_LT(i1, 2u);
    const std::vector<double>& v = sys.particles().v;
    EXPECT_EQ(v[3 * i0], 0.05);
    EXPECT_EQ(v[3 * i0 + 1], 0.01);
    EXPECT_EQ(v[3 * i1], -0.05);
    EXPECT_EQ(v[3 * i1 + 2], 0.02);
    // ballistic: x = x0 + k dt v (to the rounding of 100 additions)
    EXPECT_NEAR(sys.particles().x[3 * i0], c + 100 * s.dt_s * 0.05, 1e-12 * c);
  }
}

}  // namespace
