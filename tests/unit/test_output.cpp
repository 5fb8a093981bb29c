// The file schema (ARCHITECTURE.md "Files", docs/schema-run.md) in one process: a snapshot read back
// field by field, the series round trip and truncation, a run's series columns, the checkpoint round
// trip, and run.xmf.
//
// Set CGD_KEEP_TEST_FILES=1 to keep the files (the folder is printed) for a look with h5dump,
// h5py, tools/inspect_snapshot.py or ParaView.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "core/schema/checkpoint.hpp"
#include "core/error.hpp"
#include "core/h5.hpp"
#include "core/schema/series.hpp"
#include "core/schema/snapshot.hpp"
#include "core/xdmf.hpp"
#include "core/scene.hpp"
#include "core/schema/series.hpp"
#include "temp_dir.hpp"

namespace fs = std::filesystem;
using cgd::h5::File;

namespace {

/// A scene filled by hand (independent of the scene loader), with fluid unless `dry`.
cgd::Scene test_scene(bool dry = false) {
  cgd::Scene s;
  s.name = "unit_snapshot";
  s.source_path = "tests/unit/test_output.cpp";
  s.effective_toml = "[domain]\nsize_dp = [4, 5, 3]\n\n[particles]\ndiameter = 1e-3  # m\n";
  s.domain.size_m = {4e-3, 5e-3, 3e-3};
  s.particles.diameter_m = 1e-3;
  s.particles.seed = 42;
  s.contact.gamma_star = 1e-3;
  if (!dry) {
    s.fluid.emplace();
    s.fluid->cells = {4, 5, 3};
    s.fluid->coupling = cgd::Coupling::OneWay;
  }
  s.run.end_time_s = 0.5;
  s.derived.u_t_m_s = 0.2185;
  s.derived.k_n_N_m = 1.27;
  s.derived.t_c_s = 3.59e-5;
  s.derived.dt_dem_s = 7.18e-7;
  s.derived.particle_count = 3;
  s.derived.cells = {4, 5, 3};
  return s;
}

class OutputTest : public ::testing::Test {
 protected:
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  cgd::testing::TempDir tmp_{"cgd_test_output"};
  const fs::path& dir_ = tmp_.path();
};

/// Three particles with every optional array, and a (n_x, n_y, n_z) = (4, 5, 3) fluid grid whose
/// fields vary along y only (value = y index), so a picture of it shows horizontal bands.
struct SnapshotData {
  std::vector<std::int64_t> id{11, 12, 13};
  std::vector<double> position{0.5e-3, 0.5e-3, 0.5e-3, 2.0e-3, 2.5e-3, 1.5e-3, 3.5e-3, 4.5e-3, 2.5e-3};
  std::vector<double> velocity{0.1, -0.2, 0.3, 0.0, -0.1, 0.0, -0.1, -0.3, 0.2};
  std::vector<double> angular_velocity{1, 2, 3, 4, 5, 6, 7, 8, 9};
  std::vector<double> diameter{1e-3, 1e-3, 1e-3};
  std::vector<double> drag_coefficient{1e5, 2e5, 3e5};
  std::vector<double> fluid_velocity{0, 1, 0, 0, 2, 0, 0, 3, 0};
  std::vector<double> pressure_gradient{1, 0, 0, 0, 1, 0, 0, 0, 1};
  std::array<int, 3> cells{4, 5, 3};
  std::vector<double> void_fraction, fluid_vel, pressure;

  SnapshotData() {
    for (int z = 0; z < cells[2]; ++z)
      for (int y = 0; y < cells[1]; ++y)
        for (int x = 0; x < cells[0]; ++x) {
          void_fraction.push_back(0.5 + 0.1 * y);
          pressure.push_back(100.0 * y);
          for (int c = 0; c < 3; ++c) fluid_vel.push_back(c == 1 ? 0.01 * y : 0.0);
        }
  }
  cgd::schema::ParticleFields particles(bool optional = true) const {
    cgd::schema::ParticleFields p;
    p.count = 3;
    p.id = id.data();
    p.position = position.data();
    p.velocity = velocity.data();
    p.diameter = diameter.data();
    if (optional) {
      p.angular_velocity = angular_velocity.data();
      p.drag_coefficient = drag_coefficient.data();
      p.fluid_velocity = fluid_velocity.data();
      p.pressure_gradient = pressure_gradient.data();
      p.pressure_gradient_mean = {0.0, 1.25e4, 0.0};
    }
    return p;
  }
  cgd::schema::FluidFields fluid() const {
    cgd::schema::FluidFields f;
    f.cells = cells;
    f.spacing_m = {1e-3, 1e-3, 1e-3};
    f.origin_m = {0, 0, 0};
    f.y_offset = 0;
    f.y_count = cells[1];
    f.void_fraction = void_fraction.data();
    f.velocity = fluid_vel.data();
    f.pressure = pressure.data();
    return f;
  }
};

}  // namespace

TEST_F(OutputTest, SnapshotReadsBackFieldByFieldWithSchemaShapesAndAttributes) {
  const SnapshotData d;
  const cgd::Scene scene = test_scene();
  const auto particles = d.particles();
  const auto fluid = d.fluid();
  const std::string file = path("snap_000000100.h5");
  cgd::schema::write_snapshot(file, MPI_COMM_WORLD, scene, 0.0125, 100, particles, &fluid);
  EXPECT_FALSE(fs::exists(file + ".tmp"));

  const File f = File::open_read(file, MPI_COMM_WORLD);
  // root attributes
  EXPECT_EQ(f.attr_string("/", "cgd_format"), "snapshot");
  EXPECT_EQ(f.attr_int("/", "cgd_format_version"), cgd::schema::kSnapshot.version);
  EXPECT_FALSE(f.attr_string("/", "code_version").empty());
  const std::string created = f.attr_string("/", "created");
  ASSERT_EQ(created.size(), 20u) << created;  // 2025-01-31T12:00:00Z
  EXPECT_EQ(created[10], 'T');
  EXPECT_EQ(created.back(), 'Z');
  EXPECT_EQ(f.attr_string("/", "scene"), scene.effective_toml);
  EXPECT_EQ(f.attr_double("/", "time"), 0.0125);
  EXPECT_EQ(f.attr_int("/", "step"), 100);
  // /params: config and derived numbers with units in their names
  EXPECT_EQ(f.attr_double("/params", "diameter_m"), 1e-3);
  EXPECT_EQ(f.attr_double("/params", "density_kg_m3"), 1500.0);
  EXPECT_EQ(f.attr_double("/params", "solids_fraction"), 0.05);
  EXPECT_EQ(f.attr_int("/params", "seed"), 42);
  EXPECT_EQ(f.attr_doubles("/params", "box_size_m"), (std::vector<double>{4e-3, 5e-3, 3e-3}));
  EXPECT_EQ(f.attr_doubles("/params", "gravity_m_s2"), (std::vector<double>{0.0, -9.81, 0.0}));
  EXPECT_EQ(f.attr_double("/params", "gamma_star"), 1e-3);
  EXPECT_FALSE(f.has_attr("/params", "stiffness_n_N_m"));  // optional, not given
  EXPECT_EQ(f.attr_double("/params", "u_t_m_s"), 0.2185);
  EXPECT_EQ(f.attr_double("/params", "k_n_N_m"), 1.27);
  EXPECT_EQ(f.attr_double("/params", "t_c_s"), 3.59e-5);
  EXPECT_EQ(f.attr_double("/params", "dt_dem_s"), 7.18e-7);
  EXPECT_EQ(f.attr_int("/params", "particle_count"), 3);
  EXPECT_EQ(f.attr_ints("/params", "cells"), (std::vector<std::int64_t>{4, 5, 3}));
  EXPECT_EQ(f.attr_string("/params", "contact_model"), cgd::to_string(cgd::ContactModel::SpringDashpot));
  EXPECT_EQ(f.attr_string("/params", "coupling"), cgd::to_string(cgd::Coupling::OneWay));
  EXPECT_EQ(f.attr_string("/params", "drag"), cgd::to_string(cgd::DragLaw::Beetstra));
  EXPECT_EQ(f.attr_double("/params", "fluid_viscosity_Pa_s"), 1.8e-5);
  EXPECT_EQ(f.attr_int("/params", "has_fluid"), 1);
  // particles
  EXPECT_EQ(f.dims("/particles/id"), (std::vector<std::uint64_t>{3}));
  EXPECT_EQ(f.read_int("/particles/id"), d.id);
  for (const char* name : {"position", "velocity", "angular_velocity", "fluid_velocity", "pressure_gradient"})
    EXPECT_EQ(f.dims(std::string("/particles/") + name), (std::vector<std::uint64_t>{3, 3})) << name;
  for (const char* name : {"diameter", "drag_coefficient"})
    EXPECT_EQ(f.dims(std::string("/particles/") + name), (std::vector<std::uint64_t>{3})) << name;
  EXPECT_EQ(f.read_double("/particles/position"), d.position);
  EXPECT_EQ(f.read_double("/particles/velocity"), d.velocity);
  EXPECT_EQ(f.read_double("/particles/angular_velocity"), d.angular_velocity);
  EXPECT_EQ(f.read_double("/particles/diameter"), d.diameter);
  EXPECT_EQ(f.read_double("/particles/drag_coefficient"), d.drag_coefficient);
  EXPECT_EQ(f.read_double("/particles/fluid_velocity"), d.fluid_velocity);
  EXPECT_EQ(f.read_double("/particles/pressure_gradient"), d.pressure_gradient);
  EXPECT_EQ(f.attr_doubles("/particles", "pressure_gradient_mean"), (std::vector<double>{0.0, 1.25e4, 0.0}));
  EXPECT_EQ(f.attr_string("/particles/velocity", "unit"), "m/s");
  // fluid: (n_z, n_y, n_x), x fastest
  EXPECT_EQ(f.attr_ints("/fluid", "cells"), (std::vector<std::int64_t>{4, 5, 3}));
  EXPECT_EQ(f.attr_doubles("/fluid", "spacing"), (std::vector<double>{1e-3, 1e-3, 1e-3}));
  EXPECT_EQ(f.attr_doubles("/fluid", "origin"), (std::vector<double>{0, 0, 0}));
  EXPECT_EQ(f.dims("/fluid/void_fraction"), (std::vector<std::uint64_t>{3, 5, 4}));
  EXPECT_EQ(f.dims("/fluid/pressure"), (std::vector<std::uint64_t>{3, 5, 4}));
  EXPECT_EQ(f.dims("/fluid/velocity"), (std::vector<std::uint64_t>{3, 5, 4, 3}));
  EXPECT_EQ(f.read_double("/fluid/void_fraction"), d.void_fraction);
  EXPECT_EQ(f.read_double("/fluid/velocity"), d.fluid_vel);
  EXPECT_EQ(f.read_double("/fluid/pressure"), d.pressure);
  // cell (z=2, y=3, x=1): pressure 100 * y
  EXPECT_EQ(f.read_block("/fluid/pressure", {2, 3, 1}, {1, 1, 1}), std::vector<double>{300.0});
}

TEST_F(OutputTest, DrySnapshotWithoutOptionalArraysHasNoFluidAndNoOptionalDatasets) {
  const SnapshotData d;
  const cgd::Scene scene = test_scene(/*dry=*/true);
  const std::string file = path("dry.h5");
  cgd::schema::write_snapshot(file, MPI_COMM_WORLD, scene, 1.0, 7, d.particles(/*optional=*/false));
  const File f = File::open_read(file, MPI_COMM_WORLD);
  EXPECT_TRUE(f.exists("/particles/position"));
  EXPECT_TRUE(f.exists("/particles/diameter"));
  for (const char* name : {"angular_velocity", "drag_coefficient", "fluid_velocity", "pressure_gradient"})
    EXPECT_FALSE(f.exists(std::string("/particles/") + name)) << name;
  EXPECT_FALSE(f.has_attr("/particles", "pressure_gradient_mean"));
  EXPECT_FALSE(f.exists("/fluid"));
  EXPECT_EQ(f.attr_int("/params", "has_fluid"), 0);
  EXPECT_FALSE(f.has_attr("/params", "coupling"));
  EXPECT_FALSE(f.has_attr("/params", "fluid_density_kg_m3"));
}

TEST_F(OutputTest, SnapshotWithIncompleteFluidSlabIsRejectedAndNothingIsWritten) {
  const SnapshotData d;
  auto fluid = d.fluid();
  fluid.y_count = 4;  // one layer of 5 missing
  const std::string file = path("bad.h5");
  EXPECT_THROW(cgd::schema::write_snapshot(file, MPI_COMM_WORLD, test_scene(), 0.0, 0, d.particles(), &fluid),
               cgd::RunError);
  auto particles = d.particles();
  particles.position = nullptr;  // required array missing
  EXPECT_THROW(cgd::schema::write_snapshot(file, MPI_COMM_WORLD, test_scene(), 0.0, 0, particles),
               cgd::RunError);
  EXPECT_FALSE(fs::exists(file));
  EXPECT_FALSE(fs::exists(file + ".tmp"));
}

TEST_F(OutputTest, SeriesRoundTripKeepsColumnOrderWidthsUnitsAndValues) {
  cgd::schema::Series s;
  s.add_column("time", 1, "s");
  s.add_column("slip_velocity", 3, "m/s");
  s.add_column("solids_fraction", 1, "1");
  EXPECT_EQ(s.row_width(), 5);
  for (int r = 0; r < 4; ++r) s.append({0.1 * r, 1.0 * r, 2.0 * r, 3.0 * r, 0.05});
  EXPECT_THROW(s.append({1.0, 2.0}), std::invalid_argument);
  EXPECT_THROW(s.add_column("late", 1, "1"), std::logic_error);
  const std::string file = path("series.h5");
  s.write(file, MPI_COMM_WORLD, test_scene());
  EXPECT_FALSE(fs::exists(file + ".tmp"));

  {
    const File f = File::open_read(file, MPI_COMM_WORLD);
    EXPECT_EQ(f.attr_string("/", "cgd_format"), "series");
    EXPECT_EQ(f.attr_strings("/", "columns"),
              (std::vector<std::string>{"time", "slip_velocity", "solids_fraction"}));
    EXPECT_EQ(f.dims("/time"), (std::vector<std::uint64_t>{4}));
    EXPECT_EQ(f.dims("/slip_velocity"), (std::vector<std::uint64_t>{4, 3}));
    EXPECT_EQ(f.attr_string("/slip_velocity", "unit"), "m/s");
    EXPECT_TRUE(f.exists("/params"));
  }
  const cgd::schema::Series r = cgd::schema::Series::read(file, MPI_COMM_WORLD);
  EXPECT_EQ(r.rows(), 4u);
  EXPECT_EQ(r.row_width(), 5);
  EXPECT_EQ(r.column("time"), s.column("time"));
  EXPECT_EQ(r.column("slip_velocity"), s.column("slip_velocity"));
  EXPECT_EQ(r.column("solids_fraction"), (std::vector<double>{0.05, 0.05, 0.05, 0.05}));
  EXPECT_THROW(r.column("no_such_column"), cgd::InputError);
}

TEST_F(OutputTest, SeriesTruncateAfterDropsRowsLaterThanTheRestartTime) {
  cgd::schema::Series s;
  s.add_column("time", 1, "s");
  s.add_column("particle_velocity_mean", 3, "m/s");
  for (int r = 0; r < 6; ++r) s.append({0.5 * r, 1.0 * r, 0, -1.0 * r});
  s.truncate_after(1.0);  // keeps t = 0, 0.5, 1.0
  EXPECT_EQ(s.rows(), 3u);
  EXPECT_EQ(s.column("time"), (std::vector<double>{0, 0.5, 1.0}));
  EXPECT_EQ(s.column("particle_velocity_mean"), (std::vector<double>{0, 0, 0, 1, 0, -1, 2, 0, -2}));
  s.append({1.5, 9, 9, 9});  // appending continues after the truncation
  const std::string file = path("series.h5");
  s.write(file, MPI_COMM_WORLD, test_scene());
  const auto r = cgd::schema::Series::read(file, MPI_COMM_WORLD);
  EXPECT_EQ(r.column("time"), (std::vector<double>{0, 0.5, 1.0, 1.5}));
  s.truncate_after(-1.0);
  EXPECT_EQ(s.rows(), 0u);
}

TEST_F(OutputTest, SeriesReadOfASnapshotOrMissingFileThrowsInputError) {
  const SnapshotData d;
  const std::string snap = path("snap.h5");
  cgd::schema::write_snapshot(snap, MPI_COMM_WORLD, test_scene(), 0.0, 0, d.particles());
  try {
    cgd::schema::Series::read(snap, MPI_COMM_WORLD);
    FAIL() << "no InputError";
  } catch (const cgd::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not a series file"), std::string::npos) << e.what();
  }
  EXPECT_THROW(cgd::schema::Series::read(path("none.h5"), MPI_COMM_WORLD), cgd::InputError);
}

TEST_F(OutputTest, RunXmfIsWellFormedXdmf3ListingEveryFrameFile) {
  const SnapshotData d;
  const cgd::Scene scene = test_scene();
  fs::create_directories(dir_ / "snapshots");
  std::vector<cgd::schema::XdmfFrame> frames;
  for (const int step : {0, 100}) {
    const double time_s = step == 0 ? 0.0 : 0.01;
    char name[64];
    std::snprintf(name, sizeof name, "snapshots/snap_%09d.h5", step);
    const auto fluid = d.fluid();
    cgd::schema::write_snapshot(path(name), MPI_COMM_WORLD, scene, time_s, step, d.particles(), &fluid);
    cgd::schema::XdmfFrame fr;
    fr.snapshot_file = name;
    fr.time_s = time_s;
    fr.particle_count = 3;
    fr.has_angular_velocity = true;
    fr.has_fluid = true;
    fr.cells = d.cells;
    fr.spacing_m = {1e-3, 2e-3, 3e-3};
    fr.origin_m = {0.1, 0.2, 0.3};
    frames.push_back(fr);
  }
  cgd::schema::write_xdmf(dir_.string(), frames);
  const std::string xmf = path("run.xmf");
  ASSERT_TRUE(fs::exists(xmf));
  EXPECT_FALSE(fs::exists(xmf + ".tmp"));
  std::stringstream buffer;
  buffer << std::ifstream(xmf).rdbuf();
  const std::string text = buffer.str();
  for (const char* expected :
       {"<Xdmf", "Version=\"3.0\"", "CollectionType=\"Temporal\"", "CollectionType=\"Spatial\"",
        "snapshots/snap_000000000.h5:/particles/position", "snapshots/snap_000000100.h5:/fluid/velocity",
        "TopologyType=\"Polyvertex\" NumberOfElements=\"3\"", "GeometryType=\"XYZ\"",
        "Name=\"angular_velocity\"",
        "TopologyType=\"3DCoRectMesh\" Dimensions=\"4 6 5\"",  // nodes (n_z+1, n_y+1, n_x+1)
        "GeometryType=\"ORIGIN_DXDYDZ\"", ">0.3 0.2 0.1<",     // origin, z y x
        ">0.003 0.002 0.001<", "Dimensions=\"3 5 4 3\"", "Center=\"Cell\"", "<Time Value=\"0.01\"/>"})
    EXPECT_NE(text.find(expected), std::string::npos) << expected;

  // Well-formed XML by a real parser, when the system Python is there (it is in the dev setup).
  if (!fs::exists("/usr/bin/python3")) GTEST_SKIP() << "no /usr/bin/python3 to parse the XML";
  const std::string cmd =
      "/usr/bin/python3 -c \"import sys, xml.etree.ElementTree as ET; r = ET.parse(sys.argv[1])"
      ".getroot(); sys.exit(0 if len(r.findall('./Domain/Grid/Grid')) == 2 else 3)\" '" +
      xmf + "'";
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
}

TEST_F(OutputTest, H5pyReadsStringAttributesAsStrAndIdsAsInt64) {
  if (!fs::exists("/usr/bin/python3") || std::system("/usr/bin/python3 -c 'import h5py' 2>/dev/null") != 0)
    GTEST_SKIP() << "no /usr/bin/python3 with h5py";
  const SnapshotData d;
  const auto fluid = d.fluid();
  const std::string file = path("snap.h5");
  cgd::schema::write_snapshot(file, MPI_COMM_WORLD, test_scene(), 0.0, 0, d.particles(), &fluid);
  cgd::schema::Series s;
  s.add_column("time", 1, "s");
  s.append({0.0});
  s.write(path("series.h5"), MPI_COMM_WORLD, test_scene());
  const std::string script = path("check.py");
  std::ofstream(script) << R"(import sys, h5py, numpy as np
with h5py.File(sys.argv[1], 'r') as f:
    for k in ('cgd_format', 'code_version', 'created', 'scene'):
        assert isinstance(f.attrs[k], str), (k, type(f.attrs[k]))
    assert isinstance(f['params'].attrs['contact_model'], str)
    assert f.attrs['cgd_format_version'] == 1 and f.attrs['cgd_format_version'].dtype == np.int64
    assert f['particles/id'].dtype == np.int64 and f['particles/position'].dtype == np.float64
    assert f['fluid/velocity'].shape == (3, 5, 4, 3)
with h5py.File(sys.argv[2], 'r') as f:
    assert [str(c) for c in f.attrs['columns']] == ['time'] and isinstance(f.attrs['columns'][0], str)
)";
  const std::string cmd = "/usr/bin/python3 '" + script + "' '" + file + "' '" + path("series.h5") + "'";
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
}

// core/schema/series.hpp: a run's columns are named, in the documented order, with the optional ones only
// where the layout calls for them, and a row lands under its names.
TEST_F(OutputTest, RunSeriesColumnsFollowTheLayoutAndRowsLandUnderTheirNames) {
  cgd::schema::RunSeriesLayout dry{false, false, {"neighbor", "output"}};
  cgd::schema::Series s;
  cgd::schema::declare_run_columns(s, dry);
  cgd::schema::RunSeriesRow r;
  r.time_s = 1.5;
  r.step = 7;
  r.particle_velocity_mean_m_s = {0.0, -0.25, 0.0};
  r.max_overlap_rel = 0.01;
  r.phase_seconds = {2.0, 3.0};
  cgd::schema::append_run_row(s, dry, r);
  EXPECT_EQ(s.column("step")[0], 7.0);
  EXPECT_EQ(s.column("particle_velocity_mean")[1], -0.25);
  EXPECT_EQ(s.column("max_overlap_rel")[0], 0.01);
  EXPECT_EQ(s.column("time_output_s")[0], 3.0);
  EXPECT_THROW(s.column("slip_velocity"), cgd::InputError);  // no fluid: no slip column
  EXPECT_THROW(s.column("dt_fluid"), cgd::InputError);
  r.phase_seconds = {2.0};  // a row that does not match the layout is refused
  EXPECT_THROW(cgd::schema::append_run_row(s, dry, r), std::invalid_argument);

  cgd::schema::RunSeriesLayout coupled{true, true, {"coupling"}};
  cgd::schema::Series c;
  cgd::schema::declare_run_columns(c, coupled);
  r.slip_velocity_m_s = {0.0, 0.2, 0.0};
  r.dt_fluid_s = 6e-5;
  r.floored_cells = 4;
  r.phase_seconds = {1.0};
  cgd::schema::append_run_row(c, coupled, r);
  EXPECT_EQ(c.column("slip_velocity")[1], 0.2);
  EXPECT_EQ(c.column("dt_fluid")[0], 6e-5);
  EXPECT_EQ(c.column("floored_cells")[0], 4.0);
}

// core/schema/checkpoint.hpp: what is written is read back exactly -- the run state, the particles with their
// contact records, and the fluid fields by name -- at one rank.
TEST_F(OutputTest, CheckpointRoundTripKeepsRunStateParticlesContactsAndFluid) {
  const cgd::Scene scene = test_scene();
  cgd::checkpoint::RunState state;
  state.step = 1234;
  state.time_s = 1234 * 7.18e-7;
  state.rebuild_due = true;
  state.last_sort_step = 1000;
  state.neighbor_rebuilds = 17;
  state.slab_bounds = {0.0};  // one rank
  state.wall_seconds = 42.5;
  state.phase_seconds = {1.0, 2.0, 3.5};
  state.frames = {{0, 0.0, 3}, {1000, 1000 * 7.18e-7, 3}};
  state.placement_method = "random sequential addition";
  const std::vector<std::int64_t> id{5, 3, 9}, contact_count{1, 0, 2}, partner{3, 5, 5};
  const std::vector<double> x{0.1, 0.2, 0.3, 1.1, 1.2, 1.3, 2.1, 2.2, 2.3}, v{-1, -2, -3, 4, 5, 6, 7, 8, 9},
      w{0.5, 0.25, 0.125, 1, 2, 3, 4, 5, 6}, spring{1e-6, 2e-6, 3e-6, 4e-6, 5e-6, 6e-6, 7e-6, 8e-6, 9e-6};
  // anchors: floats that are not doubles' round values (0.1f), to show they come back bit for bit
  const std::vector<float> anchor{0.1f, 0.2f, 0.3f, 1e-6f, 1.1f, 1.2f, 1.3f, 2e-6f, 2.1f, 2.2f, 2.3f, 0.0f};
  cgd::checkpoint::ParticleRows rows{3,       id.data(),           x.data(), v.data(),      w.data(),
                                     contact_count.data(), 3, partner.data(), spring.data(), anchor.data()};
  std::vector<std::vector<double>> fields;
  cgd::checkpoint::FluidRows fluid;
  fluid.dt_previous_s = 6.5e-5;
  fluid.steps = 99;
  fluid.cells = 4;
  for (std::size_t k = 0; k < cgd::checkpoint::kFluidFieldNames.size(); ++k)
    fields.push_back({k + 0.5, k + 1.5, k + 2.5, k + 3.5});
  for (std::size_t k = 0; k < fields.size(); ++k) fluid.fields[k] = fields[k].data();
  const std::string path = (dir_ / "checkpoint.h5").string();
  cgd::checkpoint::write(path, MPI_COMM_WORLD, scene, state, rows, &fluid);

  cgd::checkpoint::Reader reader(path, MPI_COMM_WORLD);
  const cgd::checkpoint::RunState& back = reader.state();
  EXPECT_EQ(back.step, 1234);
  EXPECT_EQ(back.time_s, state.time_s);
  EXPECT_TRUE(back.rebuild_due);
  EXPECT_EQ(back.last_sort_step, 1000);
  EXPECT_EQ(back.neighbor_rebuilds, 17);
  EXPECT_EQ(back.slab_bounds, std::vector<double>{0.0});
  EXPECT_EQ(back.wall_seconds, 42.5);
  EXPECT_EQ(back.phase_seconds, state.phase_seconds);
  ASSERT_EQ(back.frames.size(), 2u);
  EXPECT_EQ(back.frames[1].step, 1000);
  EXPECT_EQ(back.frames[1].time_s, state.frames[1].time_s);
  EXPECT_EQ(back.placement_method, state.placement_method);
  EXPECT_EQ(reader.ranks(), 1);
  EXPECT_EQ(reader.rank_particle_counts(), std::vector<std::int64_t>{3});
  EXPECT_EQ(reader.rank_contact_counts(), std::vector<std::int64_t>{3});
  EXPECT_TRUE(reader.has_angular_velocity());
  const cgd::checkpoint::ParticleData p = reader.particles(0, 3, 0, 3, true);
  EXPECT_EQ(p.id, id);
  EXPECT_EQ(p.position, x);
  EXPECT_EQ(p.velocity, v);
  EXPECT_EQ(p.angular_velocity, w);
  EXPECT_EQ(p.contact_count, contact_count);
  EXPECT_EQ(p.partner, partner);
  EXPECT_EQ(p.spring, spring);
  EXPECT_EQ(p.anchor, anchor);
  ASSERT_TRUE(reader.has_fluid());
  EXPECT_EQ(reader.fluid_dt_previous_s(), 6.5e-5);
  EXPECT_EQ(reader.fluid_steps(), 99);
  std::vector<double> pressure(2);
  reader.read_fluid_field(3, 1, 2, pressure.data());  // "pressure", cells 1 and 2
  EXPECT_EQ(pressure, (std::vector<double>{4.5, 5.5}));
}

// The neighbour-list anchors (checkpoint version 3) are validated like the rest: a NaN or a negative reach is
// refused, naming the file, the dataset and the row (a restart must not trust a list bound it cannot hold).
TEST_F(OutputTest, CheckpointWithANonFiniteOrNegativeAnchorIsRefusedNamingTheRow) {
  const cgd::Scene scene = test_scene();
  cgd::checkpoint::RunState state;
  state.placement_method = "random sequential addition";
  const std::vector<std::int64_t> id{0, 1}, contact_count{0, 0}, partner;
  const std::vector<double> x{0.1, 0.2, 0.3, 1.1, 1.2, 1.3}, v(6, 0.0), spring;
  for (const float bad : {std::numeric_limits<float>::quiet_NaN(), -1e-6f}) {
    const std::vector<float> anchor{0.1f, 0.2f, 0.3f, 1e-6f, 1.1f, 1.2f, 1.3f, bad};
    cgd::checkpoint::ParticleRows rows{2, id.data(), x.data(), v.data(), nullptr, contact_count.data(), 0,
                                       partner.data(), spring.data(), anchor.data()};
    const std::string path = (dir_ / "anchor.h5").string();
    cgd::checkpoint::write(path, MPI_COMM_WORLD, scene, state, rows, nullptr);
    try {
      cgd::checkpoint::Reader reader(path, MPI_COMM_WORLD);
      ADD_FAILURE() << "a checkpoint with the anchor value " << bad << " was read";
    } catch (const cgd::InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(path), std::string::npos) << what;
      EXPECT_NE(what.find("/particles/list_anchor"), std::string::npos) << what;
      EXPECT_NE(what.find("row 1"), std::string::npos) << what;
    }
  }
}
