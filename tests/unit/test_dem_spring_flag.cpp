// The list entries' spring flags (sim/dem/neighbor.hpp, issue 25 third round): the force pass reads an
// entry's tangential spring only where its pair touches or the entry is flagged, so the flag must never be
// clear on an entry whose spring is other than +0.0 -- else an ended contact's spring would survive into its
// next contact. Checked at every step of a dense frictional gas, across list rebuilds that carry the springs
// through the contact store (save_history / load_history, which flags what it loads); and every touching
// entry is flagged after the force pass.
#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <vector>

#include "dem_test_util.hpp"
#include "sim/dem/integrator.hpp"
#include "sim/dem/neighbor.hpp"
#include "sim/dem/placement.hpp"

namespace {

using namespace cgd::dem;
using namespace cgd::dem::test;

bool spring_is_plus_zero(const NeighborList& list, std::size_t e) {
  return (std::bit_cast<std::uint64_t>(list.xi[3 * e]) | std::bit_cast<std::uint64_t>(list.xi[3 * e + 1]) |
          std::bit_cast<std::uint64_t>(list.xi[3 * e + 2])) == 0;
}

TEST(DemSpringFlag, ClearFlagMeansAZeroSpringAtEveryStepAndAcrossRebuilds) {
  const PaperParticle pp;
  const DemSettings s = paper_settings(0.9, 0.1, 12.0);
  const std::int64_t n = 700;  // phi ~ 0.21 in the 12 d cube (no ghosts: the box's edges are walls of nothing)
  const Placement pl = place_particles(s.box_m, pp.d, n, 0.05, 7);
  Particles p;
  p.rotation = true;
  p.resize(n, n);
  for (std::int64_t i = 0; i < n; ++i) p.id[i] = i;
  p.x = pl.position;
  p.v = pl.velocity;
  std::fill(p.w.begin(), p.w.end(), 0.0);
  KernelConstants k;
  k.dt = s.dt_s;
  k.radius = pp.radius;
  k.inv_mass = 1.0 / pp.mass;
  k.inv_inertia = 1.0 / pp.inertia;
  ContactParams cp = s.contact;
  cp.dt = s.dt_s;
  const SpringDashpot<true> law{cp};
  const double skin = 0.3 * pp.d;
  const std::vector<float> half_skin(n, static_cast<float>(0.5 * skin));
  const std::vector<float> anchor(4 * n, 0.0f);  // reach 0: left_reach is set, and not used here
  std::vector<std::int32_t> all(n);
  for (std::int64_t i = 0; i < n; ++i) all[i] = static_cast<std::int32_t>(i);
  NeighborList list;
  ContactStore store;
  list.build(p, pp.d + skin, pp.d, half_skin.data(), true);
  std::size_t touching_seen = 0, loaded = 0;
  for (int step = 0; step < 600; ++step) {
    if (step % 25 == 0 && step > 0) {  // a rebuild carries the springs through the store
      list.save_history(p, store);
      list.build(p, pp.d + skin, pp.d, half_skin.data(), true);
      list.load_history(p, store);
      for (std::size_t e = 0; e < list.index.size(); ++e) loaded += NeighborList::spring_flagged(list.index[e]);
    }
    std::vector<std::int32_t> rows;
    for (std::int64_t i = 0; i < n; ++i)
      if (list.offset[i + 1] > list.offset[i]) rows.push_back(static_cast<std::int32_t>(i));
    std::vector<double> force(3 * rows.size()), torque(3 * rows.size());
    KernelStats st;
    compute_forces(p, list, law, k, rows.data(), rows.size(), force.data(), torque.data(), st);
    for (std::size_t e = 0; e < list.index.size(); ++e) {
      const bool flagged = NeighborList::spring_flagged(list.index[e]);
      if (!flagged) {
        ASSERT_TRUE(spring_is_plus_zero(list, e)) << "entry " << e << " at step " << step;
      }
    }
    for (std::int64_t i = 0; i < n; ++i)
      for (std::int64_t e = list.offset[i]; e < list.offset[i + 1]; ++e) {
        const std::int32_t j = list.partner(static_cast<std::size_t>(e));
        double r2 = 0;
        for (int c = 0; c < 3; ++c) r2 += (p.x[3 * i + c] - p.x[3 * j + c]) * (p.x[3 * i + c] - p.x[3 * j + c]);
        if (r2 < pp.d * pp.d) {
          ++touching_seen;
          ASSERT_TRUE(NeighborList::spring_flagged(list.index[e])) << "touching entry " << e << " at step " << step;
        }
      }
    integrate(p, force.data(), torque.data(), UniformDrive{}, k, all.data(), all.size(), rows.data(), rows.size(),
              anchor.data(), st);
  }
  EXPECT_GT(touching_seen, 1000u);  // the gas collides: the checks above were exercised
  EXPECT_GT(loaded, 0u);            // and springs were carried through rebuilds
}

}  // namespace
