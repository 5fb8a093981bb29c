// The neighbour list with a skin per particle (sim/dem/system.hpp, neighbor.hpp; issue 25): every pair
// that touches at a step is in the list of both its particles, checked against all pairs by brute force at
// every step of a gas whose speeds span two decades (the slow majority gets a thin skin, the fast few a
// thick one, and particles change speed in collisions after their skins were set), dense and dilute, with
// gravity (the dilute gas keeps particles in free flight, whose moves are bounded rather than checked).
// A list that missed a touching pair would count it half (one row only) or not at all: the diagnostics'
// contact count (0.5 per touching list entry) then differs from the brute-force count.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <memory>
#include <numbers>
#include <utility>
#include <vector>

#include "dem_test_util.hpp"
#include "sim/dem/placement.hpp"

namespace {

using cgd::dem::DemSettings;
using cgd::dem::DemSystem;
using namespace cgd::dem::test;

struct Case {
  double phi;
  double slow_rms, fast_speed;  // m/s; every 20th particle is fast
  int steps;
};

/// Touching pairs by brute force (minimum image in the periodic cube).
double touching_pairs(const cgd::dem::Particles& p, double edge, double d) {
  double pairs = 0;
  for (std::size_t i = 0; i < p.n_owned; ++i)
    for (std::size_t j = i + 1; j < p.n_owned; ++j) {
      double r2 = 0;
      for (int c = 0; c < 3; ++c) {
        double dx = p.x[3 * i + c] - p.x[3 * j + c];
        dx -= edge * std::round(dx / edge);
        r2 += dx * dx;
      }
      pairs += r2 < d * d;
    }
  return pairs;
}

void check_no_touching_pair_is_missed(const Case& k) {
  const PaperParticle pp;
  const std::int64_t n = 600;
  const double edge = std::cbrt(static_cast<double>(n) * std::numbers::pi / 6.0 * pp.d * pp.d * pp.d / k.phi);
  DemSettings s = paper_settings(0.9, 0.1, 1.0);
  s.box_m = {edge, edge, edge};
  s.skin_target_steps = 20;  // adaptive skins per particle, as a resolved run has them (scene.hpp)
  s.skin_min_m = 0.05 * pp.d;
  s.skin_max_m = 0.5 * pp.d;
  s.drive.accel = {0.0, -9.81, 0.0};
  const cgd::dem::Placement pl = cgd::dem::place_particles(s.box_m, pp.d, n, k.slow_rms, 3);
  std::vector<double> v = pl.velocity;
  for (std::int64_t i = 0; i < n; i += 20) {  // the fast few, in random directions
    const double* u = &pl.velocity[3 * i];
    const double norm = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (int c = 0; c < 3; ++c) v[3 * i + c] = k.fast_speed * u[c] / norm;
  }
  std::vector<std::int64_t> ids(static_cast<std::size_t>(n));
  for (std::int64_t i = 0; i < n; ++i) ids[i] = i;
  auto sys = std::make_unique<DemSystem>(s, MPI_COMM_SELF);
  sys->set_particles(ids, pl.position, v, {});
  double contacts = 0, entries = 0, free_flight = 0;
  int missed_steps = 0;
  for (int step = 0; step < k.steps; ++step) {
    sys->prepare();
    sys->advance();
    const double listed = sys->diagnostics().contacts;
    const double all = touching_pairs(std::as_const(*sys).particles(), edge, pp.d);  // const: no new selection
    if (listed != all && ++missed_steps <= 3)
      ADD_FAILURE() << "step " << step << ": " << all << " touching pairs, the list holds " << listed;
    contacts += all;
    entries += static_cast<double>(sys->neighbor_entries());
    sys->commit();
    free_flight += static_cast<double>(sys->free_flight_particles());
  }
  EXPECT_EQ(missed_steps, 0);
  const double steps = k.steps;
  std::printf("phi %.2f: %.2f contacts, %.2f list entries, %.0f %% in free flight per particle-step; %lld rebuilds "
              "in %d steps, largest pair skin %.3f d\n",
              k.phi, 2 * contacts / (steps * n), entries / (steps * n), 100 * free_flight / (steps * n),
              static_cast<long long>(sys->rebuilds()), k.steps, sys->skin() / pp.d);
  // the test must see what it is about: contacts, and lists rebuilt many times over
  EXPECT_GT(contacts, 0.0);
  EXPECT_GT(sys->rebuilds(), 10);
}

TEST(DemNeighbor, PerParticleSkinsMissNoTouchingPairInADenseGas) {
  check_no_touching_pair_is_missed({0.30, 0.02, 0.5, 1500});
}

TEST(DemNeighbor, PerParticleSkinsMissNoTouchingPairInADiluteGasWithFreeFlight) {
  check_no_touching_pair_is_missed({0.05, 0.05, 1.0, 1500});
}

}  // namespace
