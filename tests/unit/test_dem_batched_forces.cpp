// The frictional force pass evaluates the contact law in batches (compute_forces_batched,
// SpringDashpot<true>::force_batch: four entries per AVX2 instruction); the per-entry pass
// (compute_forces_per_entry) is its reference. Both must give the same forces, torques, springs, spring
// flags and overlap statistics bit for bit, here over a few steps of a hand-made list with the corner cases
// the runs' tests may not reach: rows with more touching entries than a batch holds (a cluster of 40 whose
// members all touch, so a row's sums go on over several batches), batches of 4, 8 and 32 entries, sliding
// and sticking contacts, contacts whose normal force is clipped to +0 (separating fast: the slider's limit
// is 0), flagged entries that no longer touch (their springs zeroed), springs of -0.0, and a time step of
// 0 (the spring stays 0 while the contact slides: the rescaling's s_mag > 0 test). And the law alone
// (force_batch against SpringDashpot<true>::force) on inputs and parameters drawn from the values where a
// select could differ from a branch: +-0, NaN, infinities, equal operands.
#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "dem_test_util.hpp"
#include "sim/dem/integrator.hpp"
#include "sim/dem/neighbor.hpp"

namespace {

using namespace cgd::dem;
using namespace cgd::dem::test;

struct Scene {
  Particles p;
  NeighborList list;
  std::vector<std::int32_t> rows;
};

/// A cluster of `n_cluster` particles within one radius of the origin (every pair touches) and a gas of
/// `n_gas` in a box of `box` diameters, random velocities and spins; the full list of every pair closer
/// than 1.3 d, with random springs (a third zero, some -0.0), every other entry flagged.
Scene make_scene(std::size_t n_cluster, std::size_t n_gas, double box, std::uint32_t seed) {
  const PaperParticle pp;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Scene sc;
  const std::size_t n = n_cluster + n_gas;
  sc.p.rotation = true;
  sc.p.resize(n, n);
  for (std::size_t i = 0; i < n; ++i) {
    sc.p.id[i] = static_cast<std::int64_t>(1000 + i);
    for (int c = 0; c < 3; ++c) {
      sc.p.x[3 * i + c] = i < n_cluster ? 0.5 * pp.radius * u(rng) : (5.0 + 0.5 * box * (1.0 + u(rng))) * pp.d;
      sc.p.v[3 * i + c] = 0.05 * u(rng);  // m/s: fast enough to slide and to separate
      sc.p.w[3 * i + c] = 500.0 * u(rng);
    }
  }
  const double cut2 = (1.3 * pp.d) * (1.3 * pp.d);
  sc.list.offset.assign(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      if (j == i) continue;
      double r2 = 0;
      for (int c = 0; c < 3; ++c) r2 += (sc.p.x[3 * i + c] - sc.p.x[3 * j + c]) * (sc.p.x[3 * i + c] - sc.p.x[3 * j + c]);
      if (r2 >= cut2) continue;
      std::int32_t raw = static_cast<std::int32_t>(j);
      const int kind = static_cast<int>(rng() % 6);
      double s[3] = {0.0, 0.0, 0.0};
      if (kind == 1) s[0] = s[1] = s[2] = -0.0;
      if (kind >= 2)
        for (double& c : s) c = (kind == 5 ? 1e-4 : 1e-7) * u(rng);  // m: some far past the slider's limit
      if (kind != 0) raw = NeighborList::with_spring_flag(raw);
      sc.list.index.push_back(raw);
      for (double c : s) sc.list.xi.push_back(c);
    }
    sc.list.offset[i + 1] = static_cast<std::int64_t>(sc.list.index.size());
    if (sc.list.offset[i + 1] > sc.list.offset[i]) sc.rows.push_back(static_cast<std::int32_t>(i));
  }
  return sc;
}

template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

template <std::size_t kBatch>
void expect_batched_equals_per_entry(double dt, std::uint32_t seed) {
  const PaperParticle pp;
  ContactParams cp = paper_settings(0.9, 0.3, 12.0).contact;
  cp.dt = dt;
  const SpringDashpot<true> law{cp};
  KernelConstants k;
  k.dt = 1e-7;
  k.radius = pp.radius;
  k.inv_mass = 1.0 / pp.mass;
  k.inv_inertia = 1.0 / pp.inertia;
  Scene a = make_scene(40, 400, 8.0, seed);
  NeighborList list_b = a.list;
  std::size_t touching = 0, slid = 0, longest_row = 0;
  for (int step = 0; step < 4; ++step) {
    const std::size_t n_rows = a.rows.size();
    std::vector<double> fa(3 * n_rows, 1.0), ta(3 * n_rows, 1.0), fb(3 * n_rows, 2.0), tb(3 * n_rows, 2.0);
    KernelStats sa, sb;
    const NeighborList before = a.list;
    compute_forces_per_entry(a.p, a.list, law, k, a.rows.data(), n_rows, fa.data(), ta.data(), sa);
    compute_forces_batched<kBatch>(a.p, list_b, law, k, a.rows.data(), n_rows, fb.data(), tb.data(), sb);
    ASSERT_TRUE(same_bits(fa, fb)) << "forces, step " << step;
    ASSERT_TRUE(same_bits(ta, tb)) << "torques, step " << step;
    ASSERT_TRUE(same_bits(a.list.xi, list_b.xi)) << "springs, step " << step;
    ASSERT_TRUE(same_bits(a.list.index, list_b.index)) << "flags, step " << step;
    EXPECT_EQ(std::bit_cast<std::uint64_t>(sa.max_overlap), std::bit_cast<std::uint64_t>(sb.max_overlap));
    EXPECT_EQ(sa.overlap_particle, sb.overlap_particle);
    EXPECT_EQ(sa.overlap_partner, sb.overlap_partner);
    // what the step exercised: touching entries, rows longer than a batch, springs cut back by the slider
    for (std::int32_t i : a.rows) {
      std::size_t row_touching = 0;
      for (std::int64_t e = a.list.offset[i]; e < a.list.offset[i + 1]; ++e) {
        if (!NeighborList::spring_flagged(a.list.index[e])) continue;
        ++row_touching;
        double s_new = 0, s_old = 0;
        for (int c = 0; c < 3; ++c) {
          s_new += a.list.xi[3 * e + c] * a.list.xi[3 * e + c];
          s_old += before.xi[3 * e + c] * before.xi[3 * e + c];
        }
        slid += s_old > 1e-12 && s_new < 0.5 * s_old;
      }
      touching += row_touching;
      longest_row = std::max(longest_row, row_touching);
    }
    // move the particles a little (their velocities, a large step), so that contacts start and end
    for (std::size_t c = 0; c < a.p.x.size(); ++c) a.p.x[c] += 2e-4 * a.p.v[c];
  }
  EXPECT_GT(touching, 1000u);
  EXPECT_GT(longest_row, kBatch);
  if (dt > 0) {
    EXPECT_GT(slid, 10u);
  }
}

/// Equal bits, or both NaN (a NaN's payload is not part of the contract).
bool same_value(double a, double b) {
  return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b) || (a != a && b != b);
}

TEST(DemBatchedForces, LawOnSpecialValuesEqualsTheScalarLaw) {
#if !defined(__AVX2__)
  // without AVX2 force_batch is the scalar law itself: the comparison would pass without testing anything
  GTEST_SKIP() << "built without AVX2 (-march below x86-64-v3): force_batch is the scalar law";
#endif
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  const double special[] = {0.0, -0.0, 1.0, -1.0, 0.5, 2.0, 1e-300, -1e-300, 1e300, inf, -inf, nan, 3.0, -3.0};
  std::mt19937_64 rng(11);
  const auto pick = [&] { return special[rng() % std::size(special)]; };
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  const auto draw = [&] { return rng() % 3 == 0 ? pick() : u(rng); };
  std::size_t compared = 0, negative_zero_fn = 0;
  for (int round = 0; round < 4000; ++round) {
    ContactParams cp;
    cp.k_n = draw(), cp.k_t = draw(), cp.gamma_n = draw(), cp.gamma_t = draw(), cp.friction = draw();
    cp.dt = draw();
    if (round % 4 == 0) cp.k_n = -0.0, cp.gamma_n = 0.0;  // k_n overlap - gamma_n v_n = -0.0: max gives +0.0
    const SpringDashpot<true> law{cp};
    const double contact_dist = rng() % 2 ? 1.0 : draw(), radius = 0.5 * contact_dist;
    FrictionBatch<8> b;
    b.count = 1 + rng() % 8;
    for (std::size_t e = 0; e < b.count; ++e) {
      b.r2[e] = rng() % 4 == 0 ? pick() : 0.25 + 0.5 * std::abs(u(rng));
      for (int c = 0; c < 3; ++c) {
        b.dx[c][e] = draw(), b.dv[c][e] = draw(), b.wi[c][e] = draw(), b.wj[c][e] = draw();
        b.xi[c][e] = rng() % 2 ? 0.0 : draw();
      }
    }
    FrictionBatch<8> ref = b;
    law.force_batch(b, contact_dist, radius);
    for (std::size_t e = 0; e < b.count; ++e) {
      const double rr = std::sqrt(ref.r2[e]), overlap = contact_dist - rr;
      double s[3] = {ref.xi[0][e], ref.xi[1][e], ref.xi[2][e]};
      V3 t{0, 0, 0};
      const V3 f = law.force({ref.dx[0][e], ref.dx[1][e], ref.dx[2][e]}, rr, overlap,
                             {ref.dv[0][e], ref.dv[1][e], ref.dv[2][e]}, {ref.wi[0][e], ref.wi[1][e], ref.wi[2][e]},
                             {ref.wj[0][e], ref.wj[1][e], ref.wj[2][e]}, radius, radius, s, t);
      ASSERT_TRUE(same_value(b.overlap[e], overlap)) << "round " << round;
      const double fs[3] = {f.x, f.y, f.z}, ts[3] = {t.x, t.y, t.z};
      for (int c = 0; c < 3; ++c) {
        ASSERT_TRUE(same_value(b.f[c][e], fs[c])) << "force " << c << ", round " << round << ", entry " << e;
        ASSERT_TRUE(same_value(b.xi[c][e], s[c])) << "spring " << c << ", round " << round << ", entry " << e;
        // the pass adds the increment to a row sum that starts at +0.0, as `force` adds it to t = 0
        ASSERT_TRUE(same_value(0.0 + b.t[c][e], ts[c])) << "torque " << c << ", round " << round << ", entry " << e;
      }
      ++compared;
      negative_zero_fn += cp.k_n == 0.0 && std::signbit(cp.k_n);
    }
  }
  EXPECT_GT(compared, 10000u);
  EXPECT_GT(negative_zero_fn, 1000u);
}

TEST(DemBatchedForces, BatchOf32EqualsPerEntryBitForBit) { expect_batched_equals_per_entry<32>(1e-7, 1); }
TEST(DemBatchedForces, BatchOf8EqualsPerEntryBitForBit) { expect_batched_equals_per_entry<8>(1e-7, 2); }
TEST(DemBatchedForces, BatchOf4EqualsPerEntryBitForBit) { expect_batched_equals_per_entry<4>(1e-7, 3); }
TEST(DemBatchedForces, ZeroTimeStepSpringsEqualPerEntryBitForBit) { expect_batched_equals_per_entry<32>(0.0, 4); }

}  // namespace
