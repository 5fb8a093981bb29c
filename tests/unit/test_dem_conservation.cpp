// Conservation laws of the DEM engine (sim/dem/system.hpp, integrator.hpp, contact.hpp): energy of an
// elastic frictionless gas under the symplectic leapfrog, linear momentum of a dissipative frictional
// gas to round-off (pair forces are odd under exchange bit for bit), angular momentum (spin + orbital)
// across frictional collisions, and the overlap-free initial placement (placement.hpp) these runs
// start from. Particles and contact as in the paper (dem_test_util.hpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <memory>
#include <numbers>
#include <vector>

#include "dem_test_util.hpp"
#include "sim/dem/placement.hpp"

namespace {

using cgd::dem::DemSettings;
using cgd::dem::DemSystem;
using cgd::dem::Diagnostics;
using cgd::dem::load3;
using cgd::dem::V3;
using namespace cgd::dem::test;

/// Cubic box edge holding `count` spheres of diameter d at solids fraction `phi`.
double box_edge(std::int64_t count, double d, double phi) {
  return std::cbrt(static_cast<double>(count) * std::numbers::pi / 6.0 * d * d * d / phi);
}

/// A random gas of the paper's particles (placement.hpp) in a periodic cube at solids fraction `phi`.
/// (Held by pointer: DemSystem's ghost exchange refers to its own slab decomposition, so the object
/// must not be moved or copied.)
std::unique_ptr<DemSystem> make_gas(DemSettings s, std::int64_t count, double phi, double velocity_rms,
                                    std::uint64_t seed) {
  const PaperParticle pp;
  const double edge = box_edge(count, pp.d, phi);
  s.box_m = {edge, edge, edge};
  const cgd::dem::Placement placement = cgd::dem::place_particles(s.box_m, pp.d, count, velocity_rms, seed);
  std::vector<std::int64_t> ids(static_cast<std::size_t>(count));
  for (std::int64_t i = 0; i < count; ++i) ids[i] = i;
  auto sys = std::make_unique<DemSystem>(s, MPI_COMM_SELF);
  sys->set_particles(ids, placement.position, placement.velocity, {});
  return sys;
}

Diagnostics step_with_diagnostics(DemSystem& sys) {
  sys.prepare();
  sys.advance();
  const Diagnostics d = sys.diagnostics();
  sys.commit();
  return d;
}

double total_energy(const Diagnostics& d) {
  return d.kinetic_translational_J + d.kinetic_rotational_J + d.contact_energy_J;
}

// Elastic (e = 1: gamma_n = gamma_t = 0), frictionless gas at solids fraction 0.3, 2000 particles,
// rms speed 0.1 m/s, 5000 steps (~100 contact times; ~1e4 collisions). The contact force k_n delta is
// conservative and leapfrog is symplectic, so the total energy (kinetic from the synchronous
// velocities + spring energy k_n delta^2/2 at x_n) has no secular drift. Its error has two parts:
//  * a bounded oscillation while contacts are in progress, O((omega dt)^2) = 4e-3 of the energy held
//    in the springs (a leapfrog oscillator's energy error amplitude is (omega dt)^2/8 of its energy;
//    the synchronous velocity (v_{n-1/2} + v_{n+1/2})/2 adds a like term); the springs hold a fraction
//    f = E_contact/E of the energy (printed; ~4e-2 here), so this part is below 2 (omega dt)^2 f_max;
//  * the force's kinks at touch and release break the smooth shadow Hamiltonian: each collision leaves
//    an energy error of zero mean and random sign, rms ~2e-5 (head-on) to ~2e-4 (oblique) of the
//    pair's relative kinetic energy at dt = t_c/50 (leapfrog on the clipped spring, computed
//    separately; its mean is < 1e-3 of its rms). Over N_c ~ 1e4 collisions, each with ~2E/N = 1e-3 E,
//    this random walk reaches sqrt(N_c) 2e-4 1e-3 E ~ 2e-5 E (1 sigma; measured 1e-5..4e-5 for six
//    seeds).
// Bounds: every sample within 2 (omega dt)^2 f_max + 1e-4 of the initial energy; the means of the
// first and the last 10 % of the samples within 1e-4 (5 sigma of the random walk). A systematic
// change would show as a drift: 1e-4 E over 1e4 collisions is a loss of 1e-5 of each pair's energy,
// i.e. a restitution of 1 - 5e-6.
TEST(DemConservation, ElasticGasConservesEnergy) {
  const PaperParticle pp;
  DemSettings s = paper_settings(1.0, 0.0, 1.0);
  ASSERT_EQ(s.contact.gamma_n, 0.0);
  const auto gas = make_gas(s, 2000, 0.3, 0.1, 12345);
  DemSystem& sys = *gas;
  const cgd::SpringDashpot sd = paper_contact(1.0, pp.mass);
  const double omega_dt = std::numbers::pi / 50.0;  // dt = t_c/50, t_c = pi/omega

  constexpr int kSteps = 5000;
  std::vector<double> energy;
  double spring_fraction_max = 0, spring_fraction_sum = 0;
  for (int k = 0; k < kSteps; ++k) {
    const Diagnostics d = step_with_diagnostics(sys);
    energy.push_back(total_energy(d));
    spring_fraction_max = std::max(spring_fraction_max, d.contact_energy_J / energy.back());
    spring_fraction_sum += d.contact_energy_J / energy.back();
  }
  const double e0 = energy.front();
  double worst = 0;
  for (double e : energy) worst = std::max(worst, std::abs(e / e0 - 1.0));
  const std::size_t window = energy.size() / 10;
  double early = 0, late = 0;
  for (std::size_t k = 0; k < window; ++k) {
    early += energy[k] / static_cast<double>(window);
    late += energy[energy.size() - window + k] / static_cast<double>(window);
  }
  const double random_walk = 1e-4;
  const double bound = 2.0 * omega_dt * omega_dt * spring_fraction_max + random_walk;
  EXPECT_LT(spring_fraction_max, 0.1) << "the springs hold more energy than the estimate assumes";
  EXPECT_GT(spring_fraction_sum / kSteps, 1e-3) << "the gas must be colliding for the test to mean anything";
  EXPECT_LT(worst, bound);
  EXPECT_LT(std::abs(late / early - 1.0), random_walk);
  std::printf(
      "[ energy   ] %d steps, t_c = %.3e s: spring fraction mean %.2e max %.2e; max |E/E0 - 1| = %.2e "
      "(bound %.2e), drift of the 10 %% means %.2e (bound %.2e), %lld rebuilds\n",
      kSteps, sd.t_c, spring_fraction_sum / kSteps, spring_fraction_max, worst, bound, late / early - 1.0,
      random_walk, static_cast<long long>(sys.rebuilds()));
}

// Dissipative frictional gas (e = 0.9, mu = 0.1, rotation on), no gravity or drag, 2000 particles
// at solids fraction 0.3: the total momentum stays at its initial value (zero up to the rounding of
// the placement's mean removal). The pair force is odd under exchange bit for bit (contact.hpp), so
// sum_i F_i = 0 up to the rounding of each particle's force sum and of each v + dt a: at most a few
// eps |m v| per particle and step, so after S steps |P| <= ~S eps sum|m v| / sqrt(N) even if the
// errors all added up (2000 eps = 4e-13); bound 1e-12 sum|m v|.
TEST(DemConservation, LinearMomentumToRoundOff) {
  const PaperParticle pp;
  const auto gas = make_gas(paper_settings(0.9, 0.1, 1.0), 2000, 0.3, 0.1, 777);
  DemSystem& sys = *gas;
  ASSERT_TRUE(sys.particles().rotation);
  constexpr int kSteps = 2000;
  double worst = 0;
  double contacts = 0;
  for (int k = 0; k < kSteps; ++k) {
    const bool sample = k % 100 == 0 || k == kSteps - 1;
    if (!sample) {
      sys.step();
      continue;
    }
    sys.prepare();
    sys.advance();
    const Diagnostics d = sys.diagnostics();
    const std::vector<double> v = sys.synchronous_velocity();
    sys.commit();
    double scale = 0;  // sum |m v|
    for (std::size_t i = 0; i < v.size(); i += 3)
      scale += pp.mass * std::sqrt(v[i] * v[i] + v[i + 1] * v[i + 1] + v[i + 2] * v[i + 2]);
    const double p = std::sqrt(d.momentum[0] * d.momentum[0] + d.momentum[1] * d.momentum[1] +
                               d.momentum[2] * d.momentum[2]);
    EXPECT_LE(p, 1e-12 * scale) << "step " << k;
    worst = std::max(worst, p / scale);
    contacts = std::max(contacts, d.contacts);
  }
  EXPECT_GT(contacts, 100) << "the gas must be colliding for the test to mean anything";
  std::printf("[ momentum ] %d steps, up to %.0f contacts: max |P| / sum|m v| = %.2e (bound 1e-12)\n", kSteps,
              contacts, worst);
}

V3 total_angular_momentum(const Diagnostics& d) {
  return V3{d.angular_momentum_spin[0] + d.angular_momentum_orbital[0],
            d.angular_momentum_spin[1] + d.angular_momentum_orbital[1],
            d.angular_momentum_spin[2] + d.angular_momentum_orbital[2]};
}

// Angular momentum about the origin, sum I w + sum m x x v, across frictional collisions far from the
// periodic boundaries. Leapfrog conserves Lambda_n = sum m x_n x v_{n+1/2} + I w_{n+1/2} exactly
// when every pair's forces and torques add up to zero net moment, because
//   Lambda_{n+1} - Lambda_n = dt [sum_i x_i x F_i + sum_i T_i]_{n+1}
// (x_{n+1} x v_{n+1/2} = x_n x v_{n+1/2}); for a pair, with n from j to i and r = |x_i - x_j|, the
// forces give r n x F_t and the torques -(R_i + R_j) n x F_t if each lever arm is the full radius
// (contact.hpp: T_i = (-R_i n) x F_t). While the particles are apart the synchronous diagnostics
// equal Lambda (no force at that step: v_n = v_{n+1/2}), so between a step before and a step after
// the collisions the change of the total must be round-off (1e-10 of |L|, whose largest part is the
// orbital moment about the origin, |x| ~ 10 d) -- provided the contact forces of a pair act at one
// common point. With the full radius as lever arm on both sides they act at two points a distance
// delta (the overlap) apart, and the total changes by
//   Delta L = -sum_steps dt sum_pairs delta n x F_t,
// which the test computes from the recorded steps to show where any difference comes from.
TEST(DemConservation, AngularMomentumAcrossFrictionalCollisions) {
  const PaperParticle pp;
  const DemSettings s = paper_settings(0.9, 0.1, 20.0);
  const V3 centre{10.0 * pp.d, 10.0 * pp.d, 10.0 * pp.d};

  // (a) one oblique binary collision: v_n = 0.1 m/s, v_t = 0.3 m/s, touch 3.5 steps after the start
  {
    const V3 n = normalized(V3{1, 2, 2}), t = normalized(V3{2, 1, -2});
    const V3 u = (-0.1) * n + 0.3 * t;
    const V3 separation = pp.d * n - (3.5 * s.dt_s) * u;
    const V3 x0 = centre + 0.5 * separation, x1 = centre - 0.5 * separation;
    // give the pair a drift so that the orbital moment about the origin is not trivially aligned
    const V3 drift{0.02, -0.05, 0.03};
    const V3 v0 = drift + 0.5 * u, v1 = drift - 0.5 * u;
    DemSystem sys(s, MPI_COMM_SELF);
    sys.set_particles({0, 1}, {x0.x, x0.y, x0.z, x1.x, x1.y, x1.z}, {v0.x, v0.y, v0.z, v1.x, v1.y, v1.z}, {});
    V3 predicted{0, 0, 0};
    Diagnostics first{}, last{};
    constexpr int kSteps = 80;
    for (int k = 0; k < kSteps; ++k) {
      sys.prepare();
      sys.advance();
      const Diagnostics d = sys.diagnostics();
      const cgd::dem::Particles& p = sys.particles();
      const std::size_t i0 = local_index(sys, 0), i1 = local_index(sys, 1);
      const V3 xi = load3(&p.x[3 * i0]), xj = load3(&p.x[3 * i1]);
      const V3 impulse = pp.mass * (load3(&sys.next_velocity()[3 * i0]) - load3(&p.v[3 * i0]));  // on particle 0
      const double overlap = pp.d - norm(xi - xj);
      if (overlap > 0) {
        const V3 nk = normalized(xi - xj);
        const V3 jt = impulse - dot(impulse, nk) * nk;
        predicted = predicted - overlap * cross(nk, jt);
      }
      sys.commit();
      if (k == 0) first = d;
      last = d;
    }
    ASSERT_EQ(first.contacts, 0.0);
    ASSERT_EQ(last.contacts, 0.0);
    const V3 change = total_angular_momentum(last) - total_angular_momentum(first);
    const double scale = norm(total_angular_momentum(first));
    const double spin =
        norm(V3{last.angular_momentum_spin[0], last.angular_momentum_spin[1], last.angular_momentum_spin[2]});
    std::printf(
        "[ ang.mom. ] binary: |L| = %.3e, spin after %.3e, |Delta L| = %.3e (%.2e of |L|), full-radius "
        "lever-arm term %.3e, |Delta L - term| = %.2e\n",
        scale, spin, norm(change), norm(change) / scale, norm(predicted), norm(change - predicted));
    EXPECT_GT(spin, 1e-3 * scale * pp.d / norm(centre)) << "the collision must spin the spheres";
    EXPECT_LT(norm(change), 1e-10 * scale)
        << "angular momentum changed across one frictional collision; the change equals the term of forces "
           "and torques acting at two points a distance delta apart, -sum dt delta n x F_t, to a relative "
        << norm(change - predicted) / norm(predicted)
        << " (the torque's lever arm should be R - delta/2, the contact point in the middle of the overlap)";
  }

  // (b) a small cluster: three spheres converging in a tilted plane with impact offsets, colliding
  // obliquely with each other at once, then flying apart.
  {
    const double speed = 0.1, offset = 0.3 * pp.d;
    std::vector<std::int64_t> ids;
    std::vector<double> x, v;
    for (int k = 0; k < 3; ++k) {
      const double phi = 2.0 * std::numbers::pi * k / 3.0 + 0.1 * k;
      const V3 radial{std::cos(phi), std::sin(phi), 0.2 * (k - 1)};
      const V3 r = normalized(radial);
      const V3 side = normalized(cross(r, V3{0.1, 0.2, 1.0}));
      const V3 pos = centre + (0.62 * pp.d + 3.0 * speed * s.dt_s) * r + offset * side;
      const V3 vel = (-speed) * r + (0.1 * speed * (k + 1)) * side;
      ids.push_back(k);
      x.insert(x.end(), {pos.x, pos.y, pos.z});
      v.insert(v.end(), {vel.x, vel.y, vel.z});
    }
    DemSystem sys(s, MPI_COMM_SELF);
    sys.set_particles(ids, x, v, {});
    Diagnostics first{}, last{};
    double contact_steps = 0;
    std::vector<double> spin;
    constexpr int kSteps = 300;
    for (int k = 0; k < kSteps; ++k) {
      sys.prepare();
      sys.advance();
      const Diagnostics d = sys.diagnostics();
      spin = sys.synchronous_angular_velocity();
      sys.commit();
      if (k == 0) first = d;
      last = d;
      contact_steps += d.contacts;
    }
    ASSERT_EQ(first.contacts, 0.0);
    ASSERT_EQ(last.contacts, 0.0) << "the cluster must have flown apart";
    for (std::size_t i = 0; i < 3; ++i)  // every sphere took part in a frictional collision
      EXPECT_GT(norm(load3(&spin[3 * i])), 0.0)
          << "particle at local index " << i << " never touched another";
    const V3 change = total_angular_momentum(last) - total_angular_momentum(first);
    const double scale = norm(total_angular_momentum(first));
    std::printf("[ ang.mom. ] cluster of 3: %.0f pair-steps in contact, |Delta L| / |L| = %.2e\n",
                contact_steps, norm(change) / scale);
    EXPECT_LT(norm(change), 1e-10 * scale) << "angular momentum changed across the cluster's collisions";
  }
}

/// Smallest periodic centre distance / d by brute force.
double min_distance_rel(const std::array<double, 3>& box, double d, const std::vector<double>& x) {
  const std::size_t n = x.size() / 3;
  double best2 = HUGE_VAL;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j) {
      double r2 = 0;
      for (int c = 0; c < 3; ++c) {
        double dx = x[3 * i + c] - x[3 * j + c];
        dx -= box[c] * std::round(dx / box[c]);
        r2 += dx * dx;
      }
      best2 = std::min(best2, r2);
    }
  return std::sqrt(best2) / d;
}

// The initial placement: at solids fraction 0.5 (random sequential addition of smaller spheres, then
// frictionless growth) and 0.1 (random sequential addition), the requested number of particles,
// inside the box, and no two closer than d (the placement aims at a gap of 1e-3 d, the growth
// accepts a residual overlap of 2e-4 of that target, so the gap is >= 0 with margin). The reported
// min_gap_rel is cross-checked by brute force.
TEST(DemPlacement, DenseGrowthHasNoOverlap) {
  const PaperParticle pp;
  struct Case {
    std::int64_t count;
    double phi;
  };
  for (const Case c : {Case{3000, 0.5}, Case{3000, 0.1}}) {
    const double edge = box_edge(c.count, pp.d, c.phi);
    const std::array<double, 3> box{edge, edge, edge};
    cgd::dem::Placement placement;
    try {
      placement = cgd::dem::place_particles(box, pp.d, c.count, 0.1, 42);
    } catch (const std::exception& e) {
      ADD_FAILURE() << "solids fraction " << c.phi << ": " << e.what();
      continue;
    }
    SCOPED_TRACE(::testing::Message() << "solids fraction " << c.phi << " (" << placement.method << ")");
    ASSERT_EQ(placement.position.size(), 3u * c.count);
    ASSERT_EQ(placement.velocity.size(), 3u * c.count);
    for (std::size_t k = 0; k < placement.position.size(); ++k) {
      ASSERT_GE(placement.position[k], 0.0);
      ASSERT_LT(placement.position[k], edge);
    }
    EXPECT_GE(placement.min_gap_rel, 0.0);
    const double brute = min_distance_rel(box, pp.d, placement.position) - 1.0;
    EXPECT_NEAR(brute, placement.min_gap_rel, 1e-12);
    EXPECT_GE(brute, 0.0);
    std::printf("[ placement] phi = %.2f, %lld particles: min gap / d = %.3e (%s)\n", c.phi,
                static_cast<long long>(c.count), brute, placement.method.c_str());
  }
}

}  // namespace
