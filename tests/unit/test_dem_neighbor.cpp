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
#include <random>
#include <utility>
#include <vector>

#include "dem_test_util.hpp"
#include "sim/dem/neighbor.hpp"
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

// NeighborList::build against the definition, pair by pair: particle i lists exactly the j != i (owned or
// ghost) with |x_i - x_j| < d + h_i + h_j, in increasing id, for every owned i. Clustered positions (cells
// holding from none to many particles, so that the candidate scan's groups of four end at every offset within
// a row, issue 25 fourth round), ghosts, random half-skins and ids in shuffled order. The same arithmetic as
// the build's ((dx dx + dy dy) + dz dz against (d + h_i + h_j)^2 in double, the half-skins as floats), so the
// comparison is exact.
TEST(DemNeighbor, BuildListsExactlyThePairsWithinTheirReachInIdOrder) {
  const double d = 1.0, cell = 1.6;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  cgd::dem::Particles p;
  const std::size_t owned = 1500, total = 1800;  // the last 300 stand for ghosts
  p.resize(owned, total);
  for (std::size_t i = 0; i < total; ++i) {
    // half in a few tight clusters, half spread over a 12 d cube
    const bool clustered = i % 2 == 0;
    const double c0 = 3.0 * static_cast<double>(i % 5);
    for (int c = 0; c < 3; ++c)
      p.x[3 * i + c] = clustered ? c0 + 1.5 * u01(rng) : 12.0 * u01(rng);
  }
  std::vector<std::int64_t> ids(total);
  for (std::size_t i = 0; i < total; ++i) ids[i] = static_cast<std::int64_t>(i);
  std::shuffle(ids.begin(), ids.end(), rng);
  for (std::size_t i = 0; i < total; ++i) p.id[i] = ids[i];
  std::vector<float> h(total);
  for (auto& hi : h) hi = static_cast<float>(0.3 * (cell - d) * u01(rng));  // each at most (cell - d) / 2
  cgd::dem::NeighborList list;
  list.build(p, cell, d, h.data(), false);
  std::size_t entries = 0, max_row = 0;
  for (std::size_t i = 0; i < owned; ++i) {
    std::vector<std::int32_t> want;
    for (std::size_t j = 0; j < total; ++j) {
      if (j == i) continue;
      const double dx = p.x[3 * i] - p.x[3 * j], dy = p.x[3 * i + 1] - p.x[3 * j + 1],
                   dz = p.x[3 * i + 2] - p.x[3 * j + 2];
      const double cut = (d + static_cast<double>(h[i])) + static_cast<double>(h[j]);
      if (dx * dx + dy * dy + dz * dz < cut * cut) want.push_back(static_cast<std::int32_t>(j));
    }
    std::sort(want.begin(), want.end(), [&](std::int32_t a, std::int32_t b) { return p.id[a] < p.id[b]; });
    std::vector<std::int32_t> got;
    for (std::int64_t e = list.offset[i]; e < list.offset[i + 1]; ++e) got.push_back(list.partner(e));
    ASSERT_EQ(got, want) << "owned particle " << i;
    entries += got.size();
    max_row = std::max(max_row, got.size());
  }
  EXPECT_EQ(list.entries(), entries);
  // the test must see what it is about: empty, short and long lists
  EXPECT_GT(max_row, 20u);
  EXPECT_GT(entries, 5 * owned);
}

TEST(DemNeighbor, PerParticleSkinsMissNoTouchingPairInADenseGas) {
  check_no_touching_pair_is_missed({0.30, 0.02, 0.5, 1500});
}

TEST(DemNeighbor, PerParticleSkinsMissNoTouchingPairInADiluteGasWithFreeFlight) {
  check_no_touching_pair_is_missed({0.05, 0.05, 1.0, 1500});
}

}  // namespace
