// Slab decomposition: the same scene on all ranks of MPI_COMM_WORLD and serially on rank 0 must give
// the same trajectories. The engine sums each particle's contact forces in partner-id order over a
// full neighbour list (sim/dem/neighbor.hpp), so the expected agreement is bit for bit, not merely
// to round-off: any difference at all means ghosts, migration or history transfer lost something.
#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <set>
#include <numbers>

#include "core/scales.hpp"
#include "sim/dem/placement.hpp"
#include "sim/dem/system.hpp"

namespace {

using cgd::dem::DemSettings;
using cgd::dem::DemSystem;

DemSettings frictional_gas_settings(const std::array<double, 3>& box, double d) {
  const double m = 1500.0 * std::numbers::pi / 6.0 * d * d * d;
  const cgd::SpringDashpot sd = cgd::spring_dashpot(1.27, 0.9, 0.5 * m, 3.5, 1.0);
  DemSettings s;
  s.box_m = box;
  s.diameter_m = d;
  s.mass_kg = m;
  s.dt_s = sd.t_c / 50.0;
  s.contacts = true;
  s.friction = true;
  s.contact = {sd.k_n, sd.k_t, sd.gamma_n, sd.gamma_t, 0.1, s.dt_s};
  s.skin_m = 0.15 * d;
  s.drive.accel = {0.0, -9.81, 0.0};
  s.drive.drag_rate = 3.0 * std::numbers::pi * 1.8e-5 * d / m;
  s.sort_interval_steps = 300;  // exercise re-sorting during the test
  return s;
}

/// Particles of diameter d filling `box` at solids fraction 0.3.
std::int64_t gas_count(const std::array<double, 3>& box, double d) {
  return std::llround(0.3 * box[0] * box[1] * box[2] / (std::numbers::pi / 6.0 * d * d * d));
}

/// Run `steps` steps on `comm` from the placement; return id -> (x, v, w) gathered on rank 0.
/// With all_on_rank0, rank 0 starts with every particle and the first rebuild's migration sends each to
/// its owner: across two or more slab boundaries for the far slabs.
/// Book of a run: neighbour-list rebuilds and the skin of the last list (the same on every rank).
struct ListBook {
  std::int64_t rebuilds = 0;
  double skin_m = 0;
};

std::map<std::int64_t, std::array<double, 9>> run(MPI_Comm comm, const DemSettings& s, const cgd::dem::Placement& pl,
                                                   int steps, bool all_on_rank0 = false, ListBook* book = nullptr,
                                                   const std::function<void(const DemSystem&)>& after_step = {}) {
  DemSystem sys(s, comm);
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  std::vector<std::int64_t> ids;
  std::vector<double> x, v;
  const std::int64_t n = static_cast<std::int64_t>(pl.position.size() / 3);
  for (std::int64_t i = 0; i < n; ++i) {
    if (all_on_rank0 ? rank != 0 : sys.slabs().owner(pl.position[3 * i + 1]) != rank) continue;
    ids.push_back(i);
    x.insert(x.end(), &pl.position[3 * i], &pl.position[3 * i + 3]);
    v.insert(v.end(), &pl.velocity[3 * i], &pl.velocity[3 * i + 3]);
  }
  sys.set_particles(ids, x, v, {});
  for (int k = 0; k < steps; ++k) {
    sys.step();
    if (after_step) after_step(sys);
  }
  if (book) *book = {sys.rebuilds(), sys.skin()};
  const auto& p = sys.particles();
  std::vector<double> local;
  for (std::size_t i = 0; i < p.n_owned; ++i) {
    local.push_back(static_cast<double>(p.id[i]));
    for (int c = 0; c < 3; ++c) local.push_back(p.x[3 * i + c]);
    for (int c = 0; c < 3; ++c) local.push_back(p.v[3 * i + c]);
    for (int c = 0; c < 3; ++c) local.push_back(p.w[3 * i + c]);
  }
  int size = 1;
  MPI_Comm_size(comm, &size);
  int count = static_cast<int>(local.size());
  std::vector<int> counts(size), displs(size);
  MPI_Gather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, comm);
  int total = 0;
  for (int r = 0; r < size; ++r) {
    displs[r] = total;
    total += counts[r];
  }
  std::vector<double> all(rank == 0 ? total : 0);
  MPI_Gatherv(local.data(), count, MPI_DOUBLE, all.data(), counts.data(), displs.data(), MPI_DOUBLE, 0, comm);
  std::map<std::int64_t, std::array<double, 9>> out;
  for (std::size_t k = 0; k + 10 <= all.size(); k += 10) {
    std::array<double, 9> row;
    std::copy(all.begin() + static_cast<std::ptrdiff_t>(k + 1), all.begin() + static_cast<std::ptrdiff_t>(k + 10),
              row.begin());
    out[static_cast<std::int64_t>(all[k])] = row;
  }
  return out;
}

/// The particles whose state (x, v, w) differs in any bit between two runs' results (`serial`'s ids).
std::int64_t differing_particles(const std::map<std::int64_t, std::array<double, 9>>& serial,
                                 const std::map<std::int64_t, std::array<double, 9>>& parallel) {
  std::int64_t differing = 0;
  for (const auto& [id, a] : serial)
    if (a != parallel.at(id)) ++differing;
  return differing;
}

TEST(DemMpi, SlabDecompositionMatchesSerialRunBitForBit) {
  const double d = 75e-6;
  // 12 x 24 x 12 d at solids fraction 0.3 with rms speed 0.5 m/s: many frictional contacts,
  // rebuilds and migrations in 1000 steps.
  const std::array<double, 3> box{12 * d, 24 * d, 12 * d};
  const std::int64_t n = gas_count(box, d);
  const cgd::dem::Placement pl = cgd::dem::place_particles(box, d, n, 0.5, 7);
  const DemSettings s = frictional_gas_settings(box, d);
  const auto parallel = run(MPI_COMM_WORLD, s, pl, 1000);
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank != 0) return;
  const auto serial = run(MPI_COMM_SELF, s, pl, 1000);
  ASSERT_EQ(parallel.size(), static_cast<std::size_t>(n));
  ASSERT_EQ(serial.size(), static_cast<std::size_t>(n));
  double max_diff = 0, max_speed = 0;
  std::int64_t differing = 0;
  for (const auto& [id, a] : serial) {
    const auto& b = parallel.at(id);
    bool same = true;
    for (int c = 0; c < 9; ++c) {
      if (a[c] != b[c]) same = false;
      if (c < 3 || c >= 6) continue;  // velocity components
      max_diff = std::max(max_diff, std::abs(a[c] - b[c]));
      max_speed = std::max(max_speed, std::abs(a[c]));
    }
    if (!same) ++differing;
  }
  EXPECT_LT(max_speed, 5.0) << "a gas started at 0.5 m/s rms cannot speed up: energy is only dissipated";
  EXPECT_EQ(differing, 0) << "max velocity difference " << max_diff << " m/s of max speed " << max_speed;
}

// Slabs of unequal height (as the fluid grid's FFTW blocks give them: heights ~ (r/size)^1.3 of the box, at
// 3 ranks 5.5, 8.6 and 9.9 d) and every particle starting on rank 0, so that the first rebuild migrates
// particles across two slab boundaries and more (GhostExchange::migrate moves them hop by hop; at 3 ranks
// the far slab is also the periodic neighbour). Bit for bit against one rank, as above.
TEST(DemMpi, UnevenSlabsAndLongMigrationsMatchSerialRunBitForBit) {
  const double d = 75e-6;
  const std::array<double, 3> box{12 * d, 24 * d, 12 * d};
  const std::int64_t n = gas_count(box, d);
  const cgd::dem::Placement pl = cgd::dem::place_particles(box, d, n, 0.5, 11);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  DemSettings s = frictional_gas_settings(box, d);
  for (int r = 0; r < size; ++r) s.slab_lower_bounds.push_back(box[1] * std::pow(static_cast<double>(r) / size, 1.3));
  const auto parallel = run(MPI_COMM_WORLD, s, pl, 600, true);
  if (rank != 0) return;
  DemSettings serial_settings = s;
  serial_settings.slab_lower_bounds = {0.0};
  const auto serial = run(MPI_COMM_SELF, serial_settings, pl, 600);
  ASSERT_EQ(parallel.size(), static_cast<std::size_t>(n));
  ASSERT_EQ(serial.size(), static_cast<std::size_t>(n));
  const std::int64_t differing = differing_particles(serial, parallel);
  EXPECT_EQ(differing, 0) << "of " << n << " particles after 600 steps on " << size << " uneven slabs";
}

// The adaptive skins (sim/dem/system.hpp DemSettings::skin_target_steps): each particle's skin follows its
// own speed and the rebuild predicate is exact per particle (a ghost's skin comes from the same bits as its
// owner's), so every rank count rebuilds at the same steps, and the run on all ranks equals the serial one bit
// for bit, as with a fixed skin. (Against a fixed-skin run the
// trajectories differ at round-off: positions are wrapped into the box at each rebuild, and x - L rounds
// differently at another step; in this frictional gas the round-off then grows like any perturbation.)
// The gas (0.5 m/s rms, its fastest particles ~1.5 m/s; dt = t_c/50 = 7.2e-7 s) asks for pair skins of
// up to 2 * 20 * dt * v ~ 0.5 d, so the adaptive run must rebuild less often than the fixed one (checked:
// otherwise the skins would not have moved) and end with its largest skin inside its bounds.
TEST(DemMpi, AdaptiveSkinMatchesSerialRunBitForBit) {
  const double d = 75e-6;
  const std::array<double, 3> box{12 * d, 24 * d, 12 * d};
  const std::int64_t n = gas_count(box, d);
  const cgd::dem::Placement pl = cgd::dem::place_particles(box, d, n, 0.5, 11);
  const DemSettings fixed = frictional_gas_settings(box, d);
  DemSettings adaptive = fixed;
  adaptive.skin_target_steps = 20;
  adaptive.skin_min_m = 0.05 * d;
  adaptive.skin_max_m = 0.5 * d;
  adaptive.skin_m = adaptive.skin_min_m;
  ListBook parallel_book, serial_book, fixed_book;
  const auto parallel = run(MPI_COMM_WORLD, adaptive, pl, 600, false, &parallel_book);
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank != 0) return;
  const auto serial = run(MPI_COMM_SELF, adaptive, pl, 600, false, &serial_book);
  run(MPI_COMM_SELF, fixed, pl, 600, false, &fixed_book);
  ASSERT_EQ(parallel.size(), static_cast<std::size_t>(n));
  const std::int64_t differing = differing_particles(serial, parallel);
  EXPECT_EQ(differing, 0) << "of " << n << " particles";
  EXPECT_EQ(parallel_book.rebuilds, serial_book.rebuilds);
  EXPECT_EQ(parallel_book.skin_m, serial_book.skin_m);
  EXPECT_LT(serial_book.rebuilds, fixed_book.rebuilds) << "the adaptive skin should outgrow 0.15 d here";
  EXPECT_GE(serial_book.skin_m, 0.05 * d);
  EXPECT_LE(serial_book.skin_m, 0.5 * d);
  EXPECT_NE(serial_book.skin_m, 0.15 * d);
}

// Balanced slabs (DemSettings::balance_slabs, the engine's choice): the bounds move at every full rebuild to
// the quantiles of the particles' heights, each weighted by its expected list entries (from the particles in its
// coarse cell). A gas placed in the lower two thirds of the box (a 12 x 24 x 12 d placement in a 12 x 36 x 12 d box)
// and falling under 20 g spreads and sinks, so the bounds move; the run on all ranks still equals the serial one bit
// for bit, and right after each rebuild every rank holds about an equal share of the work, particles + list entries
// (an estimate balanced, a measure checked: within 20 %; equal slabs would leave the top rank nearly empty).
TEST(DemMpi, BalancedMovingSlabsMatchSerialRunBitForBit) {
  const double d = 75e-6;
  const std::array<double, 3> placed{12 * d, 24 * d, 12 * d}, box{12 * d, 36 * d, 12 * d};
  const std::int64_t n = gas_count(placed, d);
  const cgd::dem::Placement pl = cgd::dem::place_particles(placed, d, n, 0.5, 13);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  DemSettings s = frictional_gas_settings(box, d);
  s.drive.accel = {0.0, -20 * 9.81, 0.0};
  s.balance_slabs = true;
  std::set<std::vector<double>> bound_sets;
  std::int64_t last_rebuilds = -1;
  double worst_share = 0;  // the largest |work - mean| / mean right after a rebuild, work = owned + list entries
  const auto parallel = run(MPI_COMM_WORLD, s, pl, 1000, false, nullptr, [&](const DemSystem& sys) {
    if (sys.rebuilds() == last_rebuilds) return;
    last_rebuilds = sys.rebuilds();
    bound_sets.insert(sys.slab_bounds());
    const double work = static_cast<double>(sys.particles().n_owned + sys.neighbor_entries());
    double total = 0, top = 0;
    MPI_Allreduce(&work, &total, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
    const double share = total / size, mine = std::abs(work - share) / share;
    MPI_Allreduce(&mine, &top, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    worst_share = std::max(worst_share, top);
  });
  if (size > 1) {
    EXPECT_GT(bound_sets.size(), 2u) << "the slab bounds should move with the particles";
    EXPECT_LT(worst_share, 0.2) << "a rank's work right after a rebuild, of an equal share";
  }
  if (rank == 0) std::printf("[ balanced slabs, %d ranks ] %zu sets of bounds, the work of a rank off an equal share by up to %.1f %%\n",
                             size, bound_sets.size(), 100.0 * worst_share);
  if (rank != 0) return;
  const auto serial = run(MPI_COMM_SELF, s, pl, 1000);
  ASSERT_EQ(parallel.size(), static_cast<std::size_t>(n));
  ASSERT_EQ(serial.size(), static_cast<std::size_t>(n));
  const std::int64_t differing = differing_particles(serial, parallel);
  EXPECT_EQ(differing, 0) << "of " << n << " particles after 1000 steps on " << size << " balanced slabs ("
                          << bound_sets.size() << " sets of bounds)";
}

}  // namespace
