// run.xmf (core/xdmf.cpp) against the snapshots it points to: every dataset of a snapshot's /particles
// and /fluid groups is an attribute of its frame, with the dataset's shape, so ParaView shows every
// per-particle field (beta_p, the fluid velocity and pressure gradient at the particle, ...) and every
// fluid field (issue 11, item 6). The check lists the datasets from the files themselves (HDF5's own
// listing), so a field added to the schema later is covered without touching this test.
//
// Set CGD_KEEP_TEST_FILES=1 to keep the run directories (the folder is printed) for a look in ParaView.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <mpi.h>

#include <array>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "core/h5.hpp"
#include "core/schema/series.hpp"
#include "core/schema/snapshot.hpp"
#include "core/xdmf.hpp"
#include "core/scene.hpp"
#include "temp_dir.hpp"

namespace fs = std::filesystem;

namespace {

/// A scene filled by hand (the XDMF writer reads nothing of it but the effective TOML written to files).
cgd::Scene xdmf_scene() {
  cgd::Scene s;
  s.name = "unit_xdmf";
  s.effective_toml = "[domain]\nsize_dp = [4, 5, 3]\n";
  s.domain.size_m = {4e-3, 5e-3, 3e-3};
  s.particles.diameter_m = 1e-3;
  s.run.end_time_s = 0.5;
  s.derived.particle_count = 2;
  return s;
}

/// Two particles with every optional per-particle array; a (n_x, n_y, n_z) = (2, 3, 2) fluid grid with
/// every field, eps_velocity included.
struct Fields {
  std::vector<std::int64_t> id{1, 2};
  std::vector<double> vec3{0.5e-3, 0.5e-3, 0.5e-3, 1.5e-3, 2.5e-3, 1.5e-3};
  std::vector<double> scalar{1e-3, 1e-3};
  std::array<int, 3> cells{2, 3, 2};
  std::vector<double> cell_scalar = std::vector<double>(12, 0.9), cell_vec3 = std::vector<double>(36, 0.01);

  cgd::schema::ParticleFields particles(bool coupled) const {
    cgd::schema::ParticleFields p;
    p.count = 2;
    p.id = id.data();
    p.position = vec3.data();
    p.velocity = vec3.data();
    p.diameter = scalar.data();
    if (coupled) {
      p.angular_velocity = vec3.data();
      p.drag_coefficient = scalar.data();
      p.fluid_velocity = vec3.data();
      p.pressure_gradient = vec3.data();
    }
    return p;
  }
  cgd::schema::FluidFields fluid() const {
    cgd::schema::FluidFields f;
    f.cells = cells;
    f.spacing_m = {2e-3, 5e-3 / 3, 1.5e-3};
    f.y_count = cells[1];
    f.void_fraction = cell_scalar.data();
    f.velocity = cell_vec3.data();
    f.pressure = cell_scalar.data();
    f.eps_velocity = cell_vec3.data();
    return f;
  }
};

class XdmfTest : public ::testing::Test {
 protected:

  /// A run directory `name` with snapshots at steps 0 and 10 and its run.xmf; returns the xmf text.
  std::string write_run(const std::string& name, bool coupled) {
    const fs::path run = dir_ / name;
    fs::create_directories(run / "snapshots");
    const Fields d;
    std::vector<cgd::schema::XdmfFrame> frames;
    for (const int step : {0, 10}) {
      char file[64];
      std::snprintf(file, sizeof file, "snapshots/snap_%09d.h5", step);
      const auto fluid = d.fluid();
      cgd::schema::write_snapshot((run / file).string(), MPI_COMM_WORLD, xdmf_scene(), step * 1e-3, step,
                                  d.particles(coupled), coupled ? &fluid : nullptr);
      cgd::schema::XdmfFrame fr;
      fr.snapshot_file = file;
      fr.time_s = step * 1e-3;
      fr.particle_count = 2;
      fr.has_angular_velocity = coupled;
      fr.has_fluid = coupled;
      fr.cells = d.cells;
      fr.spacing_m = d.fluid().spacing_m;
      frames.push_back(fr);
    }
    cgd::schema::write_xdmf(run.string(), frames);
    std::stringstream text;
    text << std::ifstream(run / "run.xmf").rdbuf();
    return text.str();
  }

  cgd::testing::TempDir tmp_{"cgd_test_xdmf"};
  const fs::path& dir_ = tmp_.path();
};

/// The datasets of `group` in an HDF5 file, listed by HDF5 itself.
std::vector<std::string> datasets(const std::string& path, const char* group) {
  cgd::h5::File file = cgd::h5::File::open_read(path, MPI_COMM_SELF);
  std::vector<std::string> out;
  if (!file.exists(group)) return out;
  const hid_t g = H5Gopen2(file.id(), group, H5P_DEFAULT);
  H5G_info_t info;
  H5Gget_info(g, &info);
  for (hsize_t i = 0; i < info.nlinks; ++i) {
    char name[256];
    H5Lget_name_by_idx(g, ".", H5_INDEX_NAME, H5_ITER_INC, i, name, sizeof name, H5P_DEFAULT);
    out.emplace_back(name);
  }
  H5Gclose(g);
  return out;
}

}  // namespace

TEST_F(XdmfTest, EveryParticleAndFluidDatasetOfACoupledSnapshotIsInRunXmf) {
  const std::string xmf = write_run("coupled", /*coupled=*/true);
  for (const char* file : {"snapshots/snap_000000000.h5", "snapshots/snap_000000010.h5"}) {
    const std::string h5 = (dir_ / "coupled" / file).string();
    const auto particle_sets = datasets(h5, "/particles");
    const auto fluid_sets = datasets(h5, "/fluid");
    EXPECT_EQ(particle_sets.size(), 8u) << "the test snapshot holds every per-particle array of the schema";
    EXPECT_EQ(fluid_sets.size(), 4u) << "and every fluid field, eps_velocity included";
    for (const auto& name : particle_sets)
      EXPECT_NE(xmf.find(std::string(file) + ":/particles/" + name), std::string::npos)
          << file << " " << name;
    for (const auto& name : fluid_sets)
      EXPECT_NE(xmf.find(std::string(file) + ":/fluid/" + name), std::string::npos) << file << " " << name;
  }
  for (const char* expected :
       {"<Attribute Name=\"drag_coefficient\" AttributeType=\"Scalar\" Center=\"Node\">",
        "<Attribute Name=\"fluid_velocity\" AttributeType=\"Vector\" Center=\"Node\">",
        "<Attribute Name=\"pressure_gradient\" AttributeType=\"Vector\" Center=\"Node\">",
        "<Attribute Name=\"eps_velocity\" AttributeType=\"Vector\" Center=\"Cell\">",
        "Dimensions=\"2 3 2 3\" NumberType=\"Float\"",  // a fluid vector: (n_z, n_y, n_x, 3)
        "Dimensions=\"2\" NumberType=\"Int\""})         // the ids
    EXPECT_NE(xmf.find(expected), std::string::npos) << expected;
  EXPECT_EQ(xmf.find("Name=\"position\""), std::string::npos) << "position is the geometry, not an attribute";
}

TEST_F(XdmfTest, DryRunListsOnlyTheDatasetsItsSnapshotsHold) {
  const std::string xmf = write_run("dry", /*coupled=*/false);
  for (const char* present : {"/particles/velocity", "/particles/diameter", "/particles/id"})
    EXPECT_NE(xmf.find(present), std::string::npos) << present;
  for (const char* absent :
       {"drag_coefficient", "fluid_velocity", "angular_velocity", "/fluid/", "3DCoRectMesh"})
    EXPECT_EQ(xmf.find(absent), std::string::npos) << absent << " is not in a dry snapshot";
}

// An independent reader (Python's XML parser and h5py) agrees: every DataItem names a dataset that
// exists, with the dataset's shape, and every dataset is named by one DataItem of its frame.
TEST_F(XdmfTest, DataItemsMatchTheDatasetsShapesByH5py) {
  if (!fs::exists("/usr/bin/python3") || std::system("/usr/bin/python3 -c 'import h5py' 2>/dev/null") != 0)
    GTEST_SKIP() << "no /usr/bin/python3 with h5py";
  write_run("coupled", /*coupled=*/true);
  const fs::path script = dir_ / "check.py";
  std::ofstream(script) << R"(import os, sys, h5py, xml.etree.ElementTree as ET
run = sys.argv[1]
root = ET.parse(os.path.join(run, "run.xmf")).getroot()
frames = root.findall("./Domain/Grid/Grid")
assert len(frames) == 2, len(frames)
for frame in frames:
    named = {}
    for item in frame.iter("DataItem"):
        if item.get("Format") != "HDF":
            continue
        file, dataset = item.text.split(":")
        with h5py.File(os.path.join(run, file), "r") as f:
            shape = " ".join(str(n) for n in f[dataset].shape)
            assert shape == item.get("Dimensions"), (dataset, shape, item.get("Dimensions"))
        named.setdefault(file, set()).add(dataset)
    assert len(named) == 1, named
    file, datasets = next(iter(named.items()))
    with h5py.File(os.path.join(run, file), "r") as f:
        everything = {"/%s/%s" % (g, name) for g in ("particles", "fluid") for name in f[g]}
    assert everything == datasets, everything ^ datasets
)";
  const std::string cmd = "/usr/bin/python3 '" + script.string() + "' '" + (dir_ / "coupled").string() + "'";
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
}
