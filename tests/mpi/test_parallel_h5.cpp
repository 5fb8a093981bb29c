// Parallel HDF5 through cgd::h5 at any rank count (CTest runs 1 and 2): distributed rows arrive in
// rank order (ranks without rows included), y-slabs assemble the full field, a snapshot written by
// every rank reads back as one, and errors are thrown on every rank alike (no rank left hanging).
#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/h5.hpp"
#include "core/schema/series.hpp"
#include "core/schema/snapshot.hpp"
#include "core/scene.hpp"

namespace fs = std::filesystem;
using cgd::h5::File;

namespace {

int comm_rank() {
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}
int comm_size() {
  int s = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &s);
  return s;
}

/// A temporary folder made by rank 0 and shared with every rank; removed after the test.
class ParallelH5 : public ::testing::Test {
 protected:
  void SetUp() override {
    char name[256] = {};
    if (comm_rank() == 0) {
      std::string templ = (fs::temp_directory_path() / "cgd_test_parallel_h5_XXXXXX").string();
      if (mkdtemp(templ.data())) std::snprintf(name, sizeof name, "%s", templ.c_str());
    }
    MPI_Bcast(name, sizeof name, MPI_CHAR, 0, MPI_COMM_WORLD);
    ASSERT_NE(name[0], '\0');
    dir_ = name;
  }
  void TearDown() override {
    MPI_Barrier(MPI_COMM_WORLD);
    if (comm_rank() == 0) {
      std::error_code ec;
      fs::remove_all(dir_, ec);
    }
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

/// Split `n` layers over the ranks as evenly as possible; with more ranks than layers some own none.
std::pair<int, int> slab(int n, int rank, int size) {
  const int base = n / size, extra = n % size;
  const int count = base + (rank < extra ? 1 : 0);
  const int offset = rank * base + std::min(rank, extra);
  return {offset, count};
}

/// 400 values, mostly zero, the same on every rank.
std::vector<double> full_table() {
  std::vector<double> t(400, 0.0);
  for (std::size_t i = 0; i < t.size(); i += 7) t[i] = 0.1 * static_cast<double>(i);
  return t;
}

}  // namespace

TEST_F(ParallelH5, DistributedRowsComeBackInRankOrderIncludingRanksWithoutRows) {
  const int rank = comm_rank(), size = comm_size();
  // Layout A: rank 1 has no rows (at np >= 2). Layout B: rank 0 has no rows (at np = 1: an empty dataset).
  auto rows_a = [](int r) { return r == 1 ? 0 : r + 2; };
  auto rows_b = [](int r) { return r == 0 ? 0 : r + 1; };
  auto value = [](int r, int i, int c) { return 1000.0 * r + 10.0 * i + c; };
  auto local_rows = [&](int n) {
    std::vector<double> v;
    for (int i = 0; i < n; ++i)
      for (int c = 0; c < 3; ++c) v.push_back(value(rank, i, c));
    return v;
  };
  const std::vector<double> a = local_rows(rows_a(rank)), b = local_rows(rows_b(rank));
  std::vector<std::int64_t> ids;
  for (int i = 0; i < rows_a(rank); ++i) ids.push_back(std::int64_t{rank} << 32 | i);
  {
    File f = File::create(path("rows.h5"), MPI_COMM_WORLD);
    f.write_rows("/a/position", a.empty() ? nullptr : a.data(), rows_a(rank), 3);
    f.write_rows("/a/id", ids.empty() ? nullptr : ids.data(), rows_a(rank), 1);
    f.write_rows("/b/position", b.empty() ? nullptr : b.data(), rows_b(rank), 3);
    f.close();
  }
  // Expected: every rank's rows in rank order; every rank reads the whole file independently.
  std::vector<double> expect_a, expect_b;
  std::vector<std::int64_t> expect_ids;
  for (int r = 0; r < size; ++r) {
    for (int i = 0; i < rows_a(r); ++i) {
      for (int c = 0; c < 3; ++c) expect_a.push_back(value(r, i, c));
      expect_ids.push_back(std::int64_t{r} << 32 | i);
    }
    for (int i = 0; i < rows_b(r); ++i)
      for (int c = 0; c < 3; ++c) expect_b.push_back(value(r, i, c));
  }
  const File f = File::open_read(path("rows.h5"), MPI_COMM_WORLD);
  EXPECT_EQ(f.dims("/a/position"), (std::vector<std::uint64_t>{expect_a.size() / 3, 3}));
  EXPECT_EQ(f.dims("/b/position"), (std::vector<std::uint64_t>{expect_b.size() / 3, 3}));
  EXPECT_EQ(f.read_double("/a/position"), expect_a);
  EXPECT_EQ(f.read_int("/a/id"), expect_ids);
  EXPECT_EQ(f.read_double("/b/position"), expect_b);
}

TEST_F(ParallelH5, YSlabBlocksFromEveryRankAssembleTheFullField) {
  const int rank = comm_rank(), size = comm_size();
  const int nx = 5, ny = 7, nz = 3;
  auto value = [](int z, int y, int x, int c) { return 1000.0 * z + 100.0 * y + 10.0 * x + c; };
  const auto [y0, yc] = slab(ny, rank, size);
  std::vector<double> local;
  for (int z = 0; z < nz; ++z)
    for (int y = y0; y < y0 + yc; ++y)
      for (int x = 0; x < nx; ++x)
        for (int c = 0; c < 3; ++c) local.push_back(value(z, y, x, c));
  const auto uy0 = static_cast<std::uint64_t>(y0), uyc = static_cast<std::uint64_t>(yc);
  {
    File f = File::create(path("field.h5"), MPI_COMM_WORLD);
    f.write_block("/fluid/velocity", local.empty() ? nullptr : local.data(), {nz, ny, nx, 3}, {0, uy0, 0, 0},
                  {nz, uyc, nx, 3});
    f.write_replicated("/table", std::vector<double>{1.0, 2.0, 3.0}, {3});
    // a compressed table (the filtered file's sums): HDF5's parallel filtered write, collective, rank 0's copy
    f.write_replicated("/packed", full_table(), {40, 10}, cgd::h5::Storage::Compressed);
    f.set_attr("/fluid", "layout", std::string("z, y, x"));
    f.close();
  }
  std::vector<double> full;
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x)
        for (int c = 0; c < 3; ++c) full.push_back(value(z, y, x, c));
  const File f = File::open_read(path("field.h5"), MPI_COMM_WORLD);
  EXPECT_EQ(f.dims("/fluid/velocity"), (std::vector<std::uint64_t>{nz, ny, nx, 3}));
  EXPECT_EQ(f.read_double("/fluid/velocity"), full);
  EXPECT_EQ(f.read_block("/fluid/velocity", {0, uy0, 0, 0}, {nz, uyc, nx, 3}), local);
  EXPECT_EQ(f.read_double("/table"), (std::vector<double>{1.0, 2.0, 3.0}));  // written once, not per rank
  EXPECT_EQ(f.read_double("/packed"), full_table());
  EXPECT_EQ(f.storage_filter("/packed"), "deflate");
  EXPECT_EQ(f.attr_string("/fluid", "layout"), "z, y, x");
}

TEST_F(ParallelH5, SnapshotWrittenByEveryRankReadsBackAsOneFile) {
  const int rank = comm_rank(), size = comm_size();
  cgd::Scene scene;
  scene.name = "mpi_snapshot";
  scene.effective_toml = "[domain]\nsize_dp = [4, 6, 2]\n";
  scene.domain.size_m = {4e-3, 6e-3, 2e-3};
  scene.fluid.emplace();
  scene.fluid->cells = {4, 6, 2};

  // Particles: rank r owns r + 1 of them (ids continue across ranks), except rank 1 which owns none.
  const std::int64_t mine = rank == 1 ? 0 : rank + 1;
  std::int64_t first = 0;
  MPI_Exscan(&mine, &first, 1, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD);
  if (rank == 0) first = 0;
  std::vector<std::int64_t> id;
  std::vector<double> position, velocity, diameter;
  for (std::int64_t i = 0; i < mine; ++i) {
    id.push_back(first + i);
    for (int c = 0; c < 3; ++c) {
      position.push_back(1e-4 * (first + i) + c);
      velocity.push_back(-0.01 * (first + i));
    }
    diameter.push_back(1e-3);
  }
  cgd::schema::ParticleFields p;
  p.count = mine;
  p.id = id.data();  // nullptr on a rank without particles: allowed
  p.position = position.data();
  p.velocity = velocity.data();
  p.diameter = diameter.data();

  // Fluid: y-slabs, values depending on y only.
  const int nx = 4, ny = 6, nz = 2;
  const auto [y0, yc] = slab(ny, rank, size);
  std::vector<double> vf, vel, pr;
  for (int z = 0; z < nz; ++z)
    for (int y = y0; y < y0 + yc; ++y)
      for (int x = 0; x < nx; ++x) {
        vf.push_back(0.9 - 0.01 * y);
        pr.push_back(10.0 * y);
        for (int c = 0; c < 3; ++c) vel.push_back(c == 1 ? 0.1 * y : 0.0);
      }
  cgd::schema::FluidFields fl;
  fl.cells = {nx, ny, nz};
  fl.spacing_m = {1e-3, 1e-3, 1e-3};
  fl.y_offset = y0;
  fl.y_count = yc;
  fl.void_fraction = vf.data();
  fl.velocity = vel.data();
  fl.pressure = pr.data();

  const std::string file = path("snap_000000001.h5");
  cgd::schema::write_snapshot(file, MPI_COMM_WORLD, scene, 0.5, 1, p, &fl);
  // After the collective call the file is in place for every rank, and no temporary is left.
  EXPECT_TRUE(fs::exists(file));
  EXPECT_FALSE(fs::exists(file + ".tmp"));

  std::int64_t total = 0;
  MPI_Allreduce(&mine, &total, 1, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD);
  const File f = File::open_read(file, MPI_COMM_WORLD);
  EXPECT_EQ(f.attr_string("/", "cgd_format"), "snapshot");
  EXPECT_EQ(f.attr_string("/", "scene"), scene.effective_toml);
  EXPECT_EQ(f.attr_int("/", "step"), 1);
  std::vector<std::int64_t> expect_ids(static_cast<std::size_t>(total));
  for (std::int64_t i = 0; i < total; ++i) expect_ids[i] = i;
  EXPECT_EQ(f.read_int("/particles/id"), expect_ids);
  EXPECT_EQ(f.dims("/particles/position"),
            (std::vector<std::uint64_t>{static_cast<std::uint64_t>(total), 3}));
  EXPECT_EQ(f.read_rows_double("/particles/position", first, mine), position);
  std::vector<double> expect_pressure;
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x) expect_pressure.push_back(10.0 * y);
  EXPECT_EQ(f.read_double("/fluid/pressure"), expect_pressure);
  EXPECT_EQ(f.dims("/fluid/velocity"), (std::vector<std::uint64_t>{nz, ny, nx, 3}));
  EXPECT_EQ(f.read_block("/fluid/void_fraction", {0, static_cast<std::uint64_t>(y0), 0},
                         {nz, static_cast<std::uint64_t>(yc), nx}),
            vf);
}

TEST_F(ParallelH5, ErrorsAreThrownOnEveryRankAlike) {
  const int rank = comm_rank();
  // A missing file: InputError everywhere (rank 0 checks, all ranks throw the same message).
  EXPECT_THROW(File::open_read(path("missing.h5"), MPI_COMM_WORLD), cgd::InputError);
  // A hyperslab outside the dataset on one rank only: RunError on every rank, not a hang.
  File f = File::create(path("bad.h5"), MPI_COMM_WORLD);
  const std::vector<double> v(4, 0.0);
  const std::uint64_t offset = rank == 0 ? 1 : 0;
  EXPECT_THROW(f.write_block("/x", v.data(), {4}, {offset}, {4}), cgd::RunError);
  // A body that fails on every rank: no final file and no temporary.
  EXPECT_THROW(cgd::h5::write_atomically(path("never.h5"), MPI_COMM_WORLD,
                                         [](File&) { throw cgd::RunError("simulated failure"); }),
               cgd::RunError);
  MPI_Barrier(MPI_COMM_WORLD);
  EXPECT_FALSE(fs::exists(path("never.h5")));
  EXPECT_FALSE(fs::exists(path("never.h5.tmp")));
  f.close();
}
