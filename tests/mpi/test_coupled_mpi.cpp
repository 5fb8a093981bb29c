// A coupled CFD-DEM run (cgd::run_scene) on all ranks of MPI_COMM_WORLD agrees with the same run on one
// rank (rank 0, MPI_COMM_SELF) to round-off, not bit for bit: the fluid's FFTs and global sums (PCG dot
// products, averages) and the coupling's sum of the ranks' deposits add in a different order on slabs
// (sim/fluid/solver.hpp: 4e-15 per fluid step). Differences start at ~1e-16 and are amplified by
// collisions (chaotic) -- measured on this scene, 1 vs 2 ranks, max |dx|/d_p: 2.9e-14 after 2.5 ms
// (~9 fluid steps), 3.2e-13 after 5 ms, 2.1e-12 after 10 ms, 3.3e-11 after 20 ms, 2.9e-10 after 40 ms
// (e-folding ~5 ms); velocities 1e-12 (5 ms) to 7e-10 (40 ms) of max |v|; fluid u, p, eps 1e-15..1e-12.
// (Those figures are of the earlier 16 x 24 x 16 box; in this one after 5 ms: 2.1e-13 with 2 ranks, 4.5e-13
// with 3.) The test runs 5 ms (~18 fluid steps, 829 DEM steps) and requires <= 1e-9 d_p, 3000 times the
// measured difference, so a real decomposition error (a missing ghost contribution, a particle deposited
// twice) shows at O(1e-3) and fails. At 1 rank WORLD is SELF: bit for bit.
// The DEM slabs are balanced at every list rebuild (sim/dem/system.hpp), not the fluid's FFTW rows, and the
// coupler's grid is whole on every rank (sim/coupling/coupler.hpp): the runs on N ranks also check, from their
// final checkpoint, that the slabs in force hold about equal shares of the particles (within 5 %; the FFTW rows of
// this grid, 6 + 5 at 2 ranks, would give 55/45). A restart at N ranks between list rebuilds continues bit for bit.
#include <gtest/gtest.h>
#include <mpi.h>
#include <stdlib.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numeric>
#include <string>
#include <vector>

#include "core/h5.hpp"
#include "core/scene.hpp"
#include "sim/run.hpp"
#include "tests/unit/drift_test_util.hpp"
#include "tests/unit/run_quietly.hpp"

namespace {

namespace fs = std::filesystem;

// 16 x 36 x 16 d_p, 5 x 11 x 5 fluid cells (slabs of unequal height: 2 ranks 6 + 5 rows, 3 ranks
// 4 + 4 + 3), 3,521 particles at phi = 0.2 with
// random velocities of 0.05 m/s rms, soft frictional contacts (t_c = 0.3 ms), Beetstra drag, two-way.
const char* const kScene = R"(
[domain]
size_dp = [16, 36, 16]
gravity = [0.0, -9.81, 0.0]
[particles]
diameter = 75e-6
density = 1500.0
solids_fraction = 0.2
velocity_rms = 0.05
seed = 1
[contact]
model = "spring-dashpot"
stiffness = 1.8e-2
t_star = 0.02
restitution = 0.9
friction = 0.1
[fluid]
density = 1.3
viscosity = 1.8e-5
dx_over_dp = 3.33
courant = 0.3
coupling = "two-way"
drag = "beetstra"
pressure_gradient_force = true
[run]
end_time = 0.005
)";

using cgd::testing::run_quietly;

fs::path last_snapshot(const fs::path& run) {
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(run / "snapshots"))
    if (e.path().filename().string().rfind("snap_", 0) == 0) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files.back();
}

struct Final {
  std::vector<double> x, v;  // sorted by particle id
  std::vector<double> u, p, eps;
  std::int64_t step = 0;
};

Final read_final(const fs::path& run) {
  cgd::h5::File f = cgd::h5::File::open_read(last_snapshot(run).string(), MPI_COMM_SELF);
  const auto id = f.read_int("/particles/id");
  const auto x = f.read_double("/particles/position");
  const auto v = f.read_double("/particles/velocity");
  std::vector<std::size_t> order(id.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return id[a] < id[b]; });
  Final r;
  for (std::size_t k : order)
    for (int d = 0; d < 3; ++d) {
      r.x.push_back(x[3 * k + d]);
      r.v.push_back(v[3 * k + d]);
    }
  r.u = f.read_double("/fluid/velocity");
  r.p = f.read_double("/fluid/pressure");
  r.eps = f.read_double("/fluid/void_fraction");
  r.step = f.attr_int("/", "step");
  return r;
}

double max_abs(const std::vector<double>& a) {
  double m = 0.0;
  for (double x : a) m = std::max(m, std::abs(x));
  return m;
}

double max_diff(const std::vector<double>& a, const std::vector<double>& b) {
  double m = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) m = std::max(m, std::abs(a[i] - b[i]));
  return m;
}

/// One temporary directory, made on rank 0 and shared by every rank.
std::string shared_temp_dir() {
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  std::string base;
  if (rank == 0) {
    std::string pattern = (fs::temp_directory_path() / "cgd_coupled_mpi_XXXXXX").string();
    if (mkdtemp(pattern.data())) base = pattern;
  }
  int len = static_cast<int>(base.size());
  MPI_Bcast(&len, 1, MPI_INT, 0, MPI_COMM_WORLD);
  base.resize(static_cast<std::size_t>(len));
  MPI_Bcast(base.data(), len, MPI_CHAR, 0, MPI_COMM_WORLD);
  return base;
}

/// The DEM slabs of a run's checkpoint: the lower bounds in force and each rank's particles, and whether the
/// list was due for a rebuild.
struct CheckpointSlabs {
  std::vector<double> bounds;
  std::vector<std::int64_t> counts;
  bool rebuild_due = false;
};
CheckpointSlabs read_slabs(const fs::path& run) {
  cgd::h5::File f = cgd::h5::File::open_read((run / "checkpoint.h5").string(), MPI_COMM_SELF);
  return {f.attr_doubles("/", "slab_bounds"), f.attr_ints("/", "rank_particle_counts"), f.attr_int("/", "rebuild_due") != 0};
}

/// `scene` on every rank of MPI_COMM_WORLD and on rank 0 alone, compared (see the top of this file).
void compare_with_one_rank(const cgd::Scene& scene, const std::string& base, const char* label) {
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  run_quietly(scene, fs::path(base) / "world", MPI_COMM_WORLD);
  int failed = 0;
  if (rank == 0) {
    run_quietly(scene, fs::path(base) / "self", MPI_COMM_SELF);
    const Final a = read_final(fs::path(base) / "self");
    const Final b = read_final(fs::path(base) / "world");
    const double d_p = scene.particles.diameter_m;
    EXPECT_EQ(a.step, b.step);
    // (no ASSERT here: the other ranks wait for rank 0's verdict below)
    const bool same_shape = a.x.size() == b.x.size() && a.u.size() == b.u.size();
    EXPECT_TRUE(same_shape) << "particle or grid counts differ";
    if (same_shape) {
      // positions in the snapshot are wrapped into the box: compare periodically
      double dx = 0.0;
      for (std::size_t i = 0; i < a.x.size(); ++i) {
        const double L = scene.domain.size_m[i % 3];
        double e = a.x[i] - b.x[i];
        e -= L * std::round(e / L);
        dx = std::max(dx, std::abs(e));
      }
      const double dv = max_diff(a.v, b.v) / max_abs(a.v);
      const double du = max_diff(a.u, b.u) / max_abs(a.u);
      const double dp = max_diff(a.p, b.p) / max_abs(a.p);
      const double de = max_diff(a.eps, b.eps);
      std::printf(
          "[ %s, 1 vs %d ranks ] after %lld DEM steps: max |dx|/d_p %.2e, max |dv|/max|v| %.2e, fluid u "
          "%.2e, "
          "p %.2e, eps %.2e\n",
          label, size, static_cast<long long>(a.step), dx / d_p, dv, du, dp, de);
      EXPECT_LE(dx / d_p, 1e-9);
      EXPECT_LE(dv, 1e-8);
      EXPECT_LE(du, 1e-8);
      EXPECT_LE(dp, 1e-8);
      EXPECT_LE(de, 1e-12);
      if (size == 1) {  // the same run twice on one process
        EXPECT_EQ(dx, 0.0);
        EXPECT_EQ(du, 0.0);
      }
    }
    // balanced slabs: every rank's particles within 5 % of an equal share at the end (the slabs balance the
    // expected list entries, which follow the particles in this gas; the FFTW rows would be 9 % off)
    const CheckpointSlabs slabs = read_slabs(fs::path(base) / "world");
    EXPECT_EQ(static_cast<int>(slabs.bounds.size()), size);
    EXPECT_EQ(static_cast<int>(slabs.counts.size()), size);
    std::int64_t n = 0;
    for (std::int64_t c : slabs.counts) n += c;
    std::printf("[ %s, %d ranks ] particles per rank:", label, size);
    for (int r = 0; r < size && r < static_cast<int>(slabs.counts.size()); ++r) {
      std::printf(" %lld (slab from %.2f d_p)", static_cast<long long>(slabs.counts[r]),
                  slabs.bounds[r] / scene.particles.diameter_m);
      EXPECT_NEAR(static_cast<double>(slabs.counts[r]), static_cast<double>(n) / size, 0.05 * n / size) << "rank " << r;
    }
    std::printf("\n");
    failed = ::testing::Test::HasFailure() ? 1 : 0;
    std::error_code ec;
    fs::remove_all(base, ec);
  }
  MPI_Bcast(&failed, 1, MPI_INT, 0, MPI_COMM_WORLD);
  EXPECT_EQ(failed, 0);
}

TEST(CoupledMpi, AnyRankCountAgreesWithOneRank) {
  const cgd::Scene scene = cgd::load_scene_from_string(kScene, "coupled_mpi.toml");
  ASSERT_EQ(scene.derived.cells, (std::array<int, 3>{5, 11, 5}));
  const std::string base = shared_temp_dir();
  ASSERT_FALSE(base.empty());
  compare_with_one_rank(scene, base, "coupled");
}

// The drift-velocity law (fluid.drag = "drift"): its cell-mean velocity is deposited with the coupler's weights in
// the particles' order and summed over the ranks as phi's, so slabs change only the order of the same sums:
// 1 vs N ranks agree to the round-off bound of the test above (not bit for bit: the fluid's FFTs and sums differ
// with the slabs, as for every law), and at one rank bit for bit. A table that varies with phi and the cell slip.
TEST(CoupledMpi, DriftLawAgreesWithOneRank) {
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  const cgd::Scene micro = cgd::load_scene_from_string(kScene, "coupled_mpi.toml");
  const std::string base = shared_temp_dir();
  ASSERT_FALSE(base.empty());
  const std::string table = (fs::path(base) / "drift.h5").string();
  if (rank == 0)
    cgd::testing::write_drift_model(table, micro, {0.1, 0.3}, {0.0, 0.5, 1.0}, {0.2, 0.5, 0.7, 0.4, 0.6, 0.9}, 5);
  MPI_Barrier(MPI_COMM_WORLD);
  const cgd::Scene scene = cgd::load_scene_from_string(
      kScene, "coupled_mpi_drift.toml", {"fluid.drag=\"drift\"", "fluid.drag_model=\"" + table + "\""});
  compare_with_one_rank(scene, base, "drift law");
}

// A restart between list rebuilds on all ranks continues bit for bit (the slabs in force are in the checkpoint,
// sim/run_checkpoint.cpp; without them the ranks' particles would not match their slabs, or a rebuild at the restart
// would wrap positions at another step): the run to 5 ms against the run to 2.5 ms continued to 5 ms, with
// snapshots every 2.5 ms in both (the fluid steps are laid out per snapshot interval, so both do the same steps).
TEST(CoupledMpi, RestartBetweenRebuildsContinuesBitForBit) {
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  const std::string base = shared_temp_dir();
  ASSERT_FALSE(base.empty());
  const cgd::Scene full = cgd::load_scene_from_string(kScene, "coupled_mpi.toml", {"run.dump_interval=0.0025"});
  const cgd::Scene half =
      cgd::load_scene_from_string(kScene, "coupled_mpi.toml", {"run.dump_interval=0.0025", "run.end_time=0.0025"});
  const fs::path a = fs::path(base) / "uninterrupted", b = fs::path(base) / "restarted";
  run_quietly(full, a, MPI_COMM_WORLD);
  run_quietly(half, b, MPI_COMM_WORLD);
  int between = 0;
  if (rank == 0) {
    const CheckpointSlabs slabs = read_slabs(b);
    between = slabs.rebuild_due ? 0 : 1;
    std::printf("[ restart, %d ranks ] checkpoint at 2.5 ms: rebuild due %d, slab bounds", size, slabs.rebuild_due ? 1 : 0);
    for (double y : slabs.bounds) std::printf(" %.3f d_p", y / full.particles.diameter_m);
    std::printf("\n");
  }
  MPI_Bcast(&between, 1, MPI_INT, 0, MPI_COMM_WORLD);
  EXPECT_EQ(between, 1) << "the checkpoint should fall between list rebuilds (the case under test)";
  run_quietly(full, b, MPI_COMM_WORLD, /*restart=*/true);
  int failed = 0;
  if (rank == 0) {
    const Final x = read_final(a), y = read_final(b);
    EXPECT_EQ(x.step, y.step);
    EXPECT_TRUE(x.x == y.x) << "positions differ: max " << (x.x.size() == y.x.size() ? max_diff(x.x, y.x) : -1.0);
    EXPECT_TRUE(x.v == y.v) << "velocities differ: max " << (x.v.size() == y.v.size() ? max_diff(x.v, y.v) : -1.0);
    EXPECT_TRUE(x.u == y.u) << "fluid velocities differ";
    EXPECT_TRUE(x.p == y.p) << "pressures differ";
    EXPECT_TRUE(x.eps == y.eps) << "void fractions differ";
    failed = ::testing::Test::HasFailure() ? 1 : 0;
    std::error_code ec;
    fs::remove_all(base, ec);
  }
  MPI_Bcast(&failed, 1, MPI_INT, 0, MPI_COMM_WORLD);
  EXPECT_EQ(failed, 0);
}

}  // namespace
