// The format rows of core/schema/check.hpp (docs/schema-run.md "Seal and validation"): a reader refuses a
// version outside its row's range naming it, a version-2 checkpoint without its seal, and a file of another
// format; every format but the checkpoint is written without a seal, so an edit with h5py keeps it readable.
// The filtered and drag model schemas (core/schema/filtered.hpp, core/schema/drag_model.hpp;
// docs/schema-filtered.md, docs/schema-drag-model.md): every field survives write -> read, the closed
// choices convert both ways, and damaged files (an attribute removed or of the wrong type, a NaN, a dataset of
// the wrong shape, an unknown choice) are refused with an InputError naming the file and the key.
#include <gtest/gtest.h>
#include <mpi.h>

#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/checksum.hpp"
#include "core/error.hpp"
#include "core/h5.hpp"
#include "core/scene.hpp"
#include "core/schema/calibration.hpp"
#include "core/schema/check.hpp"
#include "core/schema/common.hpp"
#include "core/schema/drag_model.hpp"
#include "core/schema/filtered.hpp"
#include "temp_dir.hpp"
#include "test_scenes.hpp"

namespace {

using cgd::h5::File;

/// A file holding only cgd_format and cgd_format_version, written as cgd writes (optionally sealed).
std::string stamped(const cgd::testing::TempDir& dir, const std::string& name, const std::string& format,
                    std::int64_t version, cgd::h5::Seal seal = cgd::h5::Seal::No) {
  const std::string path = (dir.path() / name).string();
  cgd::h5::write_atomically(path, MPI_COMM_SELF, [&](File& f) {
    f.set_attr("/", "cgd_format", format);
    f.set_attr("/", "cgd_format_version", version);
  }, seal);
  return path;
}

std::string refusal(const std::string& path, const cgd::schema::Format& format) {
  try {
    cgd::schema::check_format(File::open_read(path, MPI_COMM_SELF), format);
  } catch (const cgd::InputError& e) {
    return e.what();
  }
  return "";
}

TEST(SchemaFormat, EveryFormatButTheCheckpointIsUnsealedAndAtItsVersion) {
  for (const cgd::schema::Format* f : {&cgd::schema::kSnapshot, &cgd::schema::kSeries, &cgd::schema::kFiltered,
                                       &cgd::schema::kDragModel, &cgd::schema::kCoarseSummary}) {
    EXPECT_FALSE(f->sealed) << f->name;
    EXPECT_EQ(f->oldest_version, 1) << f->name;
  }
  EXPECT_EQ(cgd::schema::kSnapshot.version, 1);
  EXPECT_EQ(cgd::schema::kSeries.version, 1);
  EXPECT_EQ(cgd::schema::kCoarseSummary.version, 1);
  // 2: one spelling per idea (micro_drag, operator "grid"); version 1 read through one upgrade path
  EXPECT_EQ(cgd::schema::kFiltered.version, 2);
  EXPECT_EQ(cgd::schema::kDragModel.version, 2);
  EXPECT_TRUE(cgd::schema::kCheckpoint.sealed);
  EXPECT_EQ(cgd::schema::kCheckpoint.version, 4);  // 3: the neighbour-list anchors, 4: the DEM slab bounds (issue 25)
  EXPECT_EQ(cgd::schema::kCheckpoint.oldest_version, 1);
}

TEST(SchemaFormat, RefusesAnotherFormatAndAVersionItDoesNotReadNamingThem) {
  cgd::testing::TempDir dir("cgd_test_schema");
  EXPECT_EQ(refusal(stamped(dir, "ok.h5", "filtered", 1), cgd::schema::kFiltered), "");
  const std::string newer = refusal(stamped(dir, "newer.h5", "filtered", 7), cgd::schema::kFiltered);
  EXPECT_NE(newer.find("cgd_format_version = 7: this build reads filtered files of versions 1 to 2"), std::string::npos)
      << newer;
  EXPECT_NE(newer.find("newer cgd"), std::string::npos) << newer;
  const std::string older = refusal(stamped(dir, "older.h5", "checkpoint", 0), cgd::schema::kCheckpoint);
  EXPECT_NE(older.find("checkpoints of versions 1 to 4"), std::string::npos) << older;
  const std::string other = refusal(stamped(dir, "series.h5", "series", 1), cgd::schema::kSnapshot);
  EXPECT_NE(other.find("cgd_format = \"series\": not a snapshot"), std::string::npos) << other;
}

// A checkpoint of version 2 is sealed by its writer; one without a seal (rewritten by another tool) is
// refused, one with its seal is read, and a version-1 checkpoint (before the seal) is read by content.
TEST(SchemaFormat, VersionTwoCheckpointMustCarryItsSeal) {
  cgd::testing::TempDir dir("cgd_test_schema");
  const std::string unsealed = refusal(stamped(dir, "plain.h5", "checkpoint", 2), cgd::schema::kCheckpoint);
  EXPECT_NE(unsealed.find("damaged: a checkpoint of version 2 carries a checksum seal"), std::string::npos)
      << unsealed;
  EXPECT_EQ(refusal(stamped(dir, "sealed.h5", "checkpoint", 2, cgd::h5::Seal::Yes), cgd::schema::kCheckpoint), "");
  EXPECT_EQ(refusal(stamped(dir, "v1.h5", "checkpoint", 1), cgd::schema::kCheckpoint), "");
}

// What a researcher does with h5py: open an unsealed file read-write and add or change an attribute. The
// file stays readable (no seal to break); the same edit of a sealed file is refused as damaged.
TEST(SchemaFormat, AnEditedUnsealedFileIsReadAndAnEditedSealedFileIsRefused) {
  cgd::testing::TempDir dir("cgd_test_schema");
  const std::string summary = stamped(dir, "summary.h5", "coarse_summary", 1);
  const std::string checkpoint = stamped(dir, "checkpoint.h5", "checkpoint", 2, cgd::h5::Seal::Yes);
  for (const std::string& path : {summary, checkpoint}) {
    const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(file, 0) << path;
    const hid_t space = H5Screate(H5S_SCALAR);
    const hid_t attr = H5Acreate2(file, "label", H5T_NATIVE_INT, space, H5P_DEFAULT, H5P_DEFAULT);
    const int one = 1;
    ASSERT_GE(H5Awrite(attr, H5T_NATIVE_INT, &one), 0);
    H5Aclose(attr);
    H5Sclose(space);
    H5Fclose(file);
  }
  EXPECT_EQ(refusal(summary, cgd::schema::kCoarseSummary), "");
  try {
    File::open_read(checkpoint, MPI_COMM_SELF);
    ADD_FAILURE() << "an edited checkpoint was opened";
  } catch (const cgd::InputError& e) {
    EXPECT_NE(std::string(e.what()).find(checkpoint + ": damaged: "), std::string::npos) << e.what();
  }
}

}  // namespace

// ---- the filtered and drag model schemas -------------------------------------------------------------

namespace {

using cgd::schema::DragModelFile;
using cgd::schema::Filtered;
using cgd::schema::FilteredGroup;
using cgd::schema::FilterKind;

/// Equal element by element, NaN equal to NaN (empty bins, unfitted bins).
bool same(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (!(a[i] == b[i] || (std::isnan(a[i]) && std::isnan(b[i])))) return false;
  return true;
}
bool same(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }

std::vector<double> ramp(std::size_t n, double start, double step) {
  std::vector<double> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = start + step * static_cast<double>(i);
  return v;
}

cgd::PhysicalSystem test_system(cgd::DragLaw law) {
  cgd::PhysicalSystem p;
  p.micro_drag = law;
  p.u_t_m_s = 0.2185, p.l_char_m = 3.02e-4, p.diameter_m = 75e-6, p.particle_density_kg_m3 = 1500;
  p.fluid_density_kg_m3 = 1.3, p.fluid_viscosity_Pa_s = 1.8e-5, p.gravity_m_s2 = 9.81;
  return p;
}

constexpr std::size_t kBins = 4, kSnapshots = 3;

FilteredGroup filtered_group(FilterKind kind, double width, double shift) {
  FilteredGroup g;
  g.kind = kind;
  g.width_m = width, g.width_over_dp = width / 75e-6, g.width_over_cell = width / 2.5e-4, g.F = 3.02e-4 / width;
  g.out_of_range = 7;
  g.count = {5, 0, 9, 2};
  g.H = {0.1 + shift, NAN, 0.3, 0.4};
  g.H_low = ramp(kBins, 0.05, 0.1), g.H_high = ramp(kBins, 0.2, 0.1), g.phi_mean = {0.01, NAN, 0.21, 0.31};
  g.phi_center = ramp(kBins, 0.05, 0.1), g.slip = ramp(kBins, -0.1, 0.01), g.slip_over_ut = ramp(kBins, -0.5, 0.1);
  g.drag = ramp(kBins, 10, 1), g.beta_bar = ramp(kBins, 100, 1), g.beta_micro = ramp(kBins, 200, 1);
  g.H_stderr = ramp(kBins, 0.01, 0.001), g.n_eff = ramp(kBins, 3, 1);
  FilteredGroup::PerSnapshot p;
  p.count = {2, 0, 3, 1, 1, 0, 3, 0, 2, 0, 3, 1};  // sums over the snapshots: 5, 0, 9, 2
  p.numerator = ramp(kSnapshots * kBins, 1, 0.5), p.micro = ramp(kSnapshots * kBins, 2, 0.5);
  p.slip = ramp(kSnapshots * kBins, -1, 0.1), p.phi = ramp(kSnapshots * kBins, 0, 0.01);
  g.per_snapshot = p;
  if (kind == FilterKind::Grid) {
    FilteredGroup::Grid c;
    c.cells_across = 4, c.cells = {4, 16, 4}, c.dx_over_dp = 5, c.cell_spacing_m = {3.75e-4, 3.75e-4, 3.75e-4};
    c.cell_size_m = 3.75e-4, c.cell_size_over_dp = 5, c.void_fraction_floor = 0.3;
    c.equivalent_width_m = 9e-4, c.equivalent_width_over_dp = 12, c.equivalent_width_over_grid_cell = 2.4;
    c.equivalent_width_bins = 2, c.equivalent_width_at_bound = true, c.equivalent_width_rms = 0.02;
    c.equivalent_width_method = "least squares";
    g.grid = c;
  }
  return g;
}

Filtered filtered_record() {
  Filtered s;
  s.scene_toml = "[domain]\n";
  s.system = test_system(cgd::DragLaw::WenYu);
  s.parcel_size = 2, s.cell_size_m = {2.5e-4, 2.5e-4, 2.5e-4}, s.pressure_terms = false;
  s.bootstrap_replicates = 40, s.bootstrap_seed = 9, s.confidence = 0.95, s.bootstrap = "blocks";
  s.run_paths = {"runA", "runB"};
  s.run_mean_solids_fraction = {0.05, 0.1}, s.run_tau_int = {1.5, 2}, s.run_n_eff = {1, 0.5};
  s.run_snapshot_count = {2, 1}, s.run_block_length = {3, 4};
  s.snapshot_files = {"a/1.h5", "a/2.h5", "b/1.h5"}, s.snapshot_checksums = {"01", "02", "03"};
  s.snapshot_run_index = {0, 0, 1}, s.snapshot_step = {10, 20, 10}, s.snapshot_block = {0, 0, 1};
  s.snapshot_time_s = {0.1, 0.2, 0.1};
  s.phi_edges = ramp(kBins + 1, 0, 0.1);
  s.groups = {filtered_group(FilterKind::Box, 2.5e-4, 0), filtered_group(FilterKind::Box, 5e-4, 0.01),
              filtered_group(FilterKind::WholeBox, 2e-3, 0.02), filtered_group(FilterKind::Grid, 3.75e-4, 0.03)};
  FilteredGroup::Samples samples;
  samples.phi = {0.1, 0.2}, samples.slip = ramp(6, -1, 0.1), samples.grad_p_filtered = ramp(6, 5, 1);
  samples.numerator = {1, 2}, samples.beta_micro = {3, 4}, samples.snapshot = {0, 2}, samples.id = {17, 4};
  s.groups[1].samples = samples;
  return s;
}

void expect_same_group(const FilteredGroup& a, const FilteredGroup& b, const std::string& where) {
  EXPECT_EQ(a.kind, b.kind) << where;
  EXPECT_TRUE(same(a.width_m, b.width_m) && same(a.width_over_dp, b.width_over_dp) &&
              same(a.width_over_cell, b.width_over_cell) && a.F == b.F)
      << where;
  EXPECT_EQ(a.out_of_range, b.out_of_range) << where;
  EXPECT_EQ(a.count, b.count) << where;
  for (auto m : {&FilteredGroup::H, &FilteredGroup::H_low, &FilteredGroup::H_high, &FilteredGroup::phi_mean,
                 &FilteredGroup::phi_center, &FilteredGroup::slip, &FilteredGroup::slip_over_ut, &FilteredGroup::drag,
                 &FilteredGroup::beta_bar, &FilteredGroup::beta_micro, &FilteredGroup::H_stderr, &FilteredGroup::n_eff})
    EXPECT_TRUE(same(a.*m, b.*m)) << where;
  ASSERT_EQ(a.per_snapshot.has_value(), b.per_snapshot.has_value()) << where;
  if (a.per_snapshot) {
    EXPECT_EQ(a.per_snapshot->count, b.per_snapshot->count) << where;
    for (auto m : {&FilteredGroup::PerSnapshot::numerator, &FilteredGroup::PerSnapshot::micro,
                   &FilteredGroup::PerSnapshot::slip, &FilteredGroup::PerSnapshot::phi})
      EXPECT_TRUE(same((*a.per_snapshot).*m, (*b.per_snapshot).*m)) << where;
  }
  ASSERT_EQ(a.grid.has_value(), b.grid.has_value()) << where;
  if (a.grid) {
    const auto &x = *a.grid, &y = *b.grid;
    EXPECT_EQ(x.cells_across, y.cells_across);
    EXPECT_EQ(x.cells, y.cells);
    EXPECT_TRUE(same(x.cell_spacing_m, y.cell_spacing_m));
    for (auto m : {&FilteredGroup::Grid::dx_over_dp, &FilteredGroup::Grid::cell_size_m,
                   &FilteredGroup::Grid::cell_size_over_dp, &FilteredGroup::Grid::void_fraction_floor,
                   &FilteredGroup::Grid::equivalent_width_m, &FilteredGroup::Grid::equivalent_width_over_dp,
                   &FilteredGroup::Grid::equivalent_width_over_grid_cell, &FilteredGroup::Grid::equivalent_width_rms})
      EXPECT_TRUE(same(x.*m, y.*m)) << where;
    EXPECT_EQ(x.equivalent_width_bins, y.equivalent_width_bins);
    EXPECT_EQ(x.equivalent_width_at_bound, y.equivalent_width_at_bound);
    EXPECT_EQ(x.equivalent_width_method, y.equivalent_width_method);
  }
  ASSERT_EQ(a.samples.has_value(), b.samples.has_value()) << where;
  if (a.samples) {
    for (auto m : {&FilteredGroup::Samples::phi, &FilteredGroup::Samples::slip, &FilteredGroup::Samples::grad_p_filtered,
                   &FilteredGroup::Samples::numerator, &FilteredGroup::Samples::beta_micro})
      EXPECT_TRUE(same((*a.samples).*m, (*b.samples).*m)) << where;
    EXPECT_EQ(a.samples->snapshot, b.samples->snapshot);
    EXPECT_EQ(a.samples->id, b.samples->id);
  }
}

// ---- damaging a file with the HDF5 C API, as a disk or another tool would ----------------------------

using Damage = std::function<void(hid_t file)>;

std::string damaged_copy(const std::string& good, const std::string& name, const Damage& damage) {
  const std::string path = (std::filesystem::path(good).parent_path() / name).string();
  std::filesystem::copy_file(good, path, std::filesystem::copy_options::overwrite_existing);
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  if (file < 0) throw std::runtime_error("cannot open " + path);
  damage(file);
  H5Fclose(file);
  return path;
}

Damage remove_attribute(const std::string& object, const std::string& name) {
  return [=](hid_t f) { EXPECT_GE(H5Adelete_by_name(f, object.c_str(), name.c_str(), H5P_DEFAULT), 0) << name; };
}

/// The attribute replaced by a string (a number where text was expected, or text where a number was).
Damage attribute_as_text(const std::string& object, const std::string& name, const std::string& text) {
  return [=](hid_t f) {
    H5Adelete_by_name(f, object.c_str(), name.c_str(), H5P_DEFAULT);
    const hid_t type = H5Tcopy(H5T_C_S1);
    H5Tset_size(type, text.size());
    const hid_t space = H5Screate(H5S_SCALAR);
    const hid_t attr = H5Acreate_by_name(f, object.c_str(), name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT,
                                         H5P_DEFAULT);
    EXPECT_GE(H5Awrite(attr, type, text.data()), 0);
    H5Aclose(attr), H5Sclose(space), H5Tclose(type);
  };
}

/// The attribute replaced by one scalar of the native type `type` (the value's bytes).
template <typename T>
Damage scalar_attribute(const std::string& object, const std::string& name, hid_t type, T value) {
  return [=](hid_t f) {
    H5Adelete_by_name(f, object.c_str(), name.c_str(), H5P_DEFAULT);
    const hid_t space = H5Screate(H5S_SCALAR);
    const hid_t attr = H5Acreate_by_name(f, object.c_str(), name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT,
                                         H5P_DEFAULT);
    EXPECT_GE(H5Awrite(attr, type, &value), 0);
    H5Aclose(attr), H5Sclose(space);
  };
}

/// A float attribute replaced by another number (NaN, or a value outside its range).
Damage attribute_number(const std::string& object, const std::string& name, double value) {
  return scalar_attribute(object, name, H5T_NATIVE_DOUBLE, value);
}

/// An attribute replaced by an int64 (an integer outside its allowed values).
Damage attribute_integer(const std::string& object, const std::string& name, std::int64_t value) {
  return scalar_attribute(object, name, H5T_NATIVE_INT64, value);
}

/// A float-array attribute replaced by `values` (another count than the schema's).
Damage removed_attribute_values(const std::string& object, const std::string& name, const std::vector<double>& values) {
  return [=](hid_t f) {
    H5Adelete_by_name(f, object.c_str(), name.c_str(), H5P_DEFAULT);
    const hsize_t n = values.size();
    const hid_t space = H5Screate_simple(1, &n, nullptr);
    const hid_t attr = H5Acreate_by_name(f, object.c_str(), name.c_str(), H5T_NATIVE_DOUBLE, space, H5P_DEFAULT,
                                         H5P_DEFAULT, H5P_DEFAULT);
    EXPECT_GE(H5Awrite(attr, H5T_NATIVE_DOUBLE, values.data()), 0);
    H5Aclose(attr), H5Sclose(space);
  };
}

/// One value of a float dataset overwritten.
Damage value_at(const std::string& dataset, std::size_t index, double value) {
  return [=](hid_t f) {
    const hid_t d = H5Dopen2(f, dataset.c_str(), H5P_DEFAULT);
    const hid_t space = H5Dget_space(d);
    std::vector<double> v(static_cast<std::size_t>(H5Sget_simple_extent_npoints(space)));
    H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
    v.at(index) = value;
    EXPECT_GE(H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), 0);
    H5Sclose(space), H5Dclose(d);
  };
}

/// A dataset replaced by a float one of `dims` (zeros): the wrong shape, or floats where integers belong.
Damage replaced_dataset(const std::string& dataset, const std::vector<hsize_t>& dims) {
  return [=](hid_t f) {
    EXPECT_GE(H5Ldelete(f, dataset.c_str(), H5P_DEFAULT), 0) << dataset;
    const hid_t space = H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr);
    const hid_t d = H5Dcreate2(f, dataset.c_str(), H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    hsize_t n = 1;
    for (hsize_t x : dims) n *= x;
    const std::vector<double> zeros(n, 0.0);
    EXPECT_GE(H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, zeros.data()), 0);
    H5Dclose(d), H5Sclose(space);
  };
}

Damage removed_dataset(const std::string& dataset) {
  return [=](hid_t f) { EXPECT_GE(H5Ldelete(f, dataset.c_str(), H5P_DEFAULT), 0) << dataset; };
}

/// One damage, the key the refusal must name, and a few words it must say.
struct Case {
  std::string name;
  Damage damage;
  std::string key;
  std::string says;
};

/// Every damaged copy of `good` is refused by `read` with an InputError naming the file and the key.
void expect_refused(const std::string& good, const std::vector<Case>& cases,
                    const std::function<void(const std::string&)>& read) {
  ASSERT_NO_THROW(read(good)) << "the undamaged file must read";
  for (const Case& c : cases) {
    const std::string path = damaged_copy(good, c.name + ".h5", c.damage);
    try {
      read(path);
      ADD_FAILURE() << c.name << ": the damaged file was read";
    } catch (const cgd::InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(path), std::string::npos) << c.name << ": " << what;
      EXPECT_NE(what.find(c.key), std::string::npos) << c.name << ": " << what;
      EXPECT_NE(what.find(c.says), std::string::npos) << c.name << ": " << what;
    }
  }
}

}  // namespace

TEST(FilteredSchema, RoundTripKeepsEveryField) {
  cgd::testing::TempDir dir("cgd_test_schema");
  const std::string path = (dir.path() / "filtered.h5").string();
  const Filtered s = filtered_record();
  cgd::schema::write_filtered(path, nullptr, s);
  const Filtered r = cgd::schema::read_filtered(path);
  EXPECT_EQ(r.scene_toml, s.scene_toml);
  EXPECT_FALSE(cgd::compare_systems(r.system, s.system, true, 0.0)) << "the physical system, law included";
  EXPECT_EQ(r.system.micro_drag, cgd::DragLaw::WenYu);
  EXPECT_EQ(r.parcel_size, s.parcel_size);
  EXPECT_TRUE(same(r.cell_size_m, s.cell_size_m));
  EXPECT_EQ(r.pressure_terms, s.pressure_terms);
  EXPECT_EQ(r.bootstrap_replicates, s.bootstrap_replicates);
  EXPECT_EQ(r.bootstrap_seed, s.bootstrap_seed);
  EXPECT_EQ(r.confidence, s.confidence);
  EXPECT_EQ(r.bootstrap, s.bootstrap);
  EXPECT_EQ(r.run_paths, s.run_paths);
  EXPECT_TRUE(same(r.run_mean_solids_fraction, s.run_mean_solids_fraction) && same(r.run_tau_int, s.run_tau_int) &&
              same(r.run_n_eff, s.run_n_eff));
  EXPECT_EQ(r.run_snapshot_count, s.run_snapshot_count);
  EXPECT_EQ(r.run_block_length, s.run_block_length);
  EXPECT_EQ(r.snapshot_files, s.snapshot_files);
  EXPECT_EQ(r.snapshot_checksums, s.snapshot_checksums);
  EXPECT_EQ(r.snapshot_run_index, s.snapshot_run_index);
  EXPECT_EQ(r.snapshot_step, s.snapshot_step);
  EXPECT_EQ(r.snapshot_block, s.snapshot_block);
  EXPECT_TRUE(same(r.snapshot_time_s, s.snapshot_time_s));
  EXPECT_TRUE(same(r.phi_edges, s.phi_edges));
  ASSERT_EQ(r.groups.size(), s.groups.size());
  const std::vector<std::string> paths = cgd::schema::group_paths(r);
  EXPECT_EQ(paths, (std::vector<std::string>{"/width_0", "/width_1", "/whole_box", "/grids/4"}));
  for (std::size_t i = 0; i < s.groups.size(); ++i) expect_same_group(r.groups[i], s.groups[i], paths[i]);
  // the format's closed choices as stored: the kinds and the grids' operator
  File f = File::open_read(path, MPI_COMM_SELF);
  EXPECT_EQ(f.attr_string("/whole_box", "kind"), "whole_box");
  EXPECT_EQ(f.attr_string("/grids/4", "kind"), "grid");
  EXPECT_EQ(f.attr_string("/grids", "operator"), "grid");
  EXPECT_EQ(f.attr_string("/grids/4", "operator"), "grid");
  EXPECT_EQ(f.attr_int("/", "cgd_format_version"), 2);
  EXPECT_EQ(f.attr_string("/", "micro_drag"), "wen-yu");
}

TEST(FilteredSchema, RefusesDamagedFilesNamingTheFileAndTheKey) {
  cgd::testing::TempDir dir("cgd_test_schema");
  const std::string good = (dir.path() / "filtered.h5").string();
  cgd::schema::write_filtered(good, nullptr, filtered_record());
  const std::vector<Case> cases = {
      {"no_l_char", remove_attribute("/", "l_char_m"), "l_char_m", ""},
      {"no_F", remove_attribute("/width_1", "F"), "'F'", "/width_1"},
      {"F_text", attribute_as_text("/width_0", "F", "wide"), "F", "expected a number"},
      {"law_number", attribute_number("/", "micro_drag", 1.0), "micro_drag", ""},
      {"F_nan", attribute_number("/whole_box", "F", NAN), "'F'", "finite"},
      {"edge_nan", value_at("/bins/phi_edges", 2, NAN), "/bins/phi_edges", "finite"},
      {"edges_unsorted", value_at("/bins/phi_edges", 2, 0.05), "/bins/phi_edges", "increasing"},
      {"H_nan", value_at("/width_0/H", 2, NAN), "/width_0/H", "bin 2"},
      {"slip_nan", value_at("/grids/4/slip", 0, NAN), "/grids/4/slip", "bin 0"},
      {"numerator_nan", value_at("/width_1/per_snapshot/numerator", 5, NAN), "/width_1/per_snapshot/numerator",
       "finite"},
      {"H_shape", replaced_dataset("/width_1/H", {kBins + 1}), "/width_1/H", "shape (5,)"},
      {"sums_shape", replaced_dataset("/whole_box/per_snapshot/micro", {kSnapshots, kBins - 1}),
       "/whole_box/per_snapshot/micro", "shape (3, 3)"},
      {"count_floats", replaced_dataset("/width_0/count", {kBins}), "/width_0/count", "integers"},
      {"no_H_low", removed_dataset("/grids/4/H_low"), "/grids/4/H_low", "no dataset"},
      {"block_rows", replaced_dataset("/snapshots/block", {kSnapshots + 1}), "/snapshots/block", "shape (4,)"},
      {"counts_disagree", value_at("/runs/mean_solids_fraction", 0, 0.2), "", ""},  // a value change: still valid
      {"grid_operator", attribute_as_text("/grids", "operator", "tent"), "operator", "expected \"grid\""},
      // version 1's spelling in a version-2 file: refused (the upgrade path is for version-1 files only)
      {"old_operator", attribute_as_text("/grids/4", "operator", "tsc-deposit-interpolate"), "operator",
       "expected \"grid\" (cgd_format_version 2)"},
      {"kind", attribute_as_text("/width_1", "kind", "grid"), "kind", "\"box\""},
      {"no_grid_size", remove_attribute("/grids/4", "cell_size_over_dp"), "cell_size_over_dp", "/grids/4"},
  };
  // a damage that leaves the file valid (a mean solids fraction changed) must read: it is not in the list
  std::vector<Case> refused;
  for (const Case& c : cases)
    if (c.name != "counts_disagree") refused.push_back(c);
  expect_refused(good, refused, [](const std::string& p) { cgd::schema::read_filtered(p); });
  EXPECT_NO_THROW(cgd::schema::read_filtered(damaged_copy(good, "edited.h5", cases[15].damage)));
}

namespace {

cgd::schema::SplineRecord spline(int order, std::size_t n, double start) {
  cgd::schema::SplineRecord s;
  s.order = order;
  s.coefficients = ramp(n, start, 0.1);
  s.knots.assign(static_cast<std::size_t>(order), 0.016);
  for (std::size_t i = 1; i + static_cast<std::size_t>(order) < n + 1; ++i)
    s.knots.push_back(0.016 + 0.5 * static_cast<double>(i) / static_cast<double>(n - order + 1));
  s.knots.insert(s.knots.end(), static_cast<std::size_t>(order), 0.516);
  s.meaning = "a test spline";
  return s;
}

DragModelFile model_record() {
  DragModelFile m;
  m.system = test_system(cgd::DragLaw::Stokes);
  m.model_form = "the form";
  m.width_exponent = 1.5, m.width_exponent_fitted = true, m.width_exponent_low = 1.2, m.width_exponent_high = 1.9;
  m.calibration_operator = cgd::CalibrationOperator::Grid;
  m.curves = cgd::schema::ModelCurves::Splines;
  m.calibrated_delta_m = {3e-4, 6e-4}, m.calibrated_delta_over_dp = {4, 8}, m.calibrated_cells_across = {6, 3};
  m.phi_crit = 0.016, m.phi_max = 0.516, m.h_max = 0.99, m.log_a_min = -0.5, m.log_a_max = 5;
  m.h = spline(4, 6, 0.1), m.log_a = spline(4, 6, 1.0);
  m.c_corr = {0.2, 0.04, "parcel-fit", true, std::nullopt};
  DragModelFile::CCorr::ParcelFit p;
  p.a_fit = 0.2, p.k_fit = 0.04, p.p_value = 0.3, p.k_lower_bound = -0.1, p.chi2_per_dof = 1.2, p.dof = 3;
  p.applied = true, p.rejected = false, p.a_fitted = true, p.decision = "applied", p.method = "least squares";
  p.k_interval = {0.01, 0.07}, p.a_interval = {0.05, 0.4};
  p.runs = {"r1", "r2"}, p.runs_alpha = {1, 2}, p.runs_phi = {0.05, 0.05}, p.runs_factor = {1, 0.9};
  p.runs_factor_stderr = {0.01, 0.02}, p.runs_seed = {1, 2};
  m.c_corr.parcel_fit = p;
  DragModelFile::Bands b;
  b.replicates = 50, b.seed = 3, b.confidence = 0.95, b.resampling = "snapshot blocks";
  b.phi = ramp(5, 0, 0.1), b.h = ramp(5, 0, 0.2), b.h_low = ramp(5, -0.1, 0.2), b.h_high = ramp(5, 0.1, 0.2);
  b.a = ramp(5, 1, 1), b.a_low = ramp(5, 0.5, 1), b.a_high = ramp(5, 1.5, 1), b.F = {0.5, 1};
  b.H = ramp(10, 0, 0.05), b.H_low = ramp(10, -0.1, 0.05), b.H_high = ramp(10, 0.1, 0.05);
  m.bands = b;
  DragModelFile::Bins bins;
  bins.phi = {0.01, 0.05, 0.1}, bins.phi_center = {0.01, 0.05, 0.1}, bins.h = {NAN, 0.5, 0.6};
  bins.h_stderr = {NAN, 0.01, 0.02}, bins.a = {NAN, 2, 3}, bins.log_a_stderr = {NAN, 0.1, 0.1};
  bins.chi2 = {NAN, 1, 2}, bins.h_stderr_bootstrap = {NAN, 0.02, 0.03}, bins.log_a_stderr_bootstrap = {NAN, 0.2, 0.2};
  bins.used = {0, 1, 1}, bins.widths = {1, 4, 5}, bins.at_bound = {0, 0, 1}, bins.a_at_cap = {0, 1, 0};
  m.bins = bins;
  m.data = DragModelFile::Data{{"f.h5:/grids/6", "f.h5:/whole_box"}, {2, 0.1}, {0.01, 0.05, 0.1},
                               ramp(6, 0, 0.1), ramp(6, 0.01, 0.01), {1, 0}};
  DragModelFile::Diagnostics d;
  d.min_count = 100, d.min_widths = 3, d.breakpoints = 15, d.h_clamped_grid_points = 2;
  d.min_width_over_cell = 1.01, d.lambda_h = 0.1, d.lambda_log_a = 0.2, d.edf_h = 5, d.edf_log_a = 6;
  d.chi2_per_dof = 1.1, d.cv_rms_H = NAN, d.cv_in_sample_rms_H = 0.1, d.wall_seconds = 0.5;
  d.width_exponent_grid = {1, 1.5, 2}, d.width_exponent_chi2 = {3, 2, 4}, d.width_exponent_chi2_per_dof = 1.2;
  d.residual_files = {"f.h5", "f.h5"}, d.residual_groups = {"/grids/6", "/whole_box"};
  d.residual_F = {2, 0.1}, d.residual_mean = {0.01, 0.02}, d.residual_mean_z = {0.1, 0.2};
  d.residual_rms_z = {1, 2}, d.residual_mean_smoothed = {0.03, 0.04}, d.residual_points = {10, 12};
  d.cv_files = {"f.h5", "f.h5"}, d.cv_run = {0, 1}, d.cv_points = {5, 6}, d.cv_rms = {0.2, 0.3}, d.cv_mean = {0, 0.1};
  m.diagnostics = d;
  m.source_files = {"f.h5"}, m.source_checksums = {"0123456789abcdef"};
  m.sources_pooled = true;
  return m;
}

cgd::Scene schema_scene() {
  return cgd::load_scene_from_string(cgd::testing::test_scene_text("unit_suspension.toml"), "schema_test.toml");
}

}  // namespace

TEST(DragModelSchema, RoundTripKeepsEveryField) {
  cgd::testing::TempDir dir("cgd_test_schema");
  const std::string path = (dir.path() / "model.h5").string();
  const DragModelFile m = model_record();
  cgd::schema::write_drag_model(path, schema_scene(), m);
  const DragModelFile r = cgd::schema::read_drag_model(path);
  EXPECT_FALSE(cgd::compare_systems(r.system, m.system, true, 0.0));
  EXPECT_EQ(r.system.micro_drag, cgd::DragLaw::Stokes);
  EXPECT_EQ(r.model_form, m.model_form);
  EXPECT_EQ(r.u_t_convention, cgd::kUtConvention);
  EXPECT_EQ(r.width_exponent, 1.5);
  EXPECT_TRUE(r.width_exponent_fitted);
  EXPECT_EQ(r.width_exponent_low, 1.2);
  EXPECT_EQ(r.width_exponent_high, 1.9);
  EXPECT_EQ(r.calibration_operator, cgd::CalibrationOperator::Grid);
  EXPECT_EQ(r.curves, cgd::schema::ModelCurves::Splines);
  EXPECT_TRUE(same(r.calibrated_delta_m, m.calibrated_delta_m));
  EXPECT_TRUE(same(r.calibrated_delta_over_dp, m.calibrated_delta_over_dp));
  EXPECT_EQ(r.calibrated_cells_across, m.calibrated_cells_across);
  EXPECT_EQ(r.phi_crit, m.phi_crit);
  EXPECT_EQ(r.phi_max, m.phi_max);
  EXPECT_EQ(r.h_max, m.h_max);
  EXPECT_EQ(r.log_a_min, m.log_a_min);
  EXPECT_EQ(r.log_a_max, m.log_a_max);
  for (auto s : {&DragModelFile::h, &DragModelFile::log_a}) {
    EXPECT_EQ((r.*s).order, (m.*s).order);
    EXPECT_TRUE(same((r.*s).knots, (m.*s).knots));
    EXPECT_TRUE(same((r.*s).coefficients, (m.*s).coefficients));
    EXPECT_EQ((r.*s).meaning, (m.*s).meaning);
  }
  EXPECT_EQ(r.c_corr.a, 0.2);
  EXPECT_EQ(r.c_corr.k, 0.04);
  EXPECT_EQ(r.c_corr.source, "parcel-fit");
  EXPECT_TRUE(r.c_corr.fitted);
  ASSERT_TRUE(r.c_corr.parcel_fit);
  {
    using P = DragModelFile::CCorr::ParcelFit;
    const P &x = *r.c_corr.parcel_fit, &y = *m.c_corr.parcel_fit;
    for (auto v : {&P::a_fit, &P::k_fit, &P::p_value, &P::k_lower_bound, &P::chi2_per_dof}) EXPECT_EQ(x.*v, y.*v);
    EXPECT_EQ(x.dof, y.dof);
    EXPECT_EQ(x.applied, y.applied);
    EXPECT_EQ(x.rejected, y.rejected);
    EXPECT_EQ(x.a_fitted, y.a_fitted);
    EXPECT_EQ(x.decision, y.decision);
    EXPECT_EQ(x.method, y.method);
    EXPECT_EQ(x.runs, y.runs);
    for (auto v : {&P::k_interval, &P::a_interval, &P::runs_alpha, &P::runs_phi, &P::runs_factor,
                   &P::runs_factor_stderr, &P::runs_seed})
      EXPECT_TRUE(same(x.*v, y.*v));
  }
  ASSERT_TRUE(r.bands && r.bins && r.data && r.diagnostics);
  EXPECT_FALSE(r.table);
  using B = DragModelFile::Bands;
  for (auto v : {&B::phi, &B::h, &B::h_low, &B::h_high, &B::a, &B::a_low, &B::a_high, &B::F, &B::H, &B::H_low, &B::H_high})
    EXPECT_TRUE(same((*r.bands).*v, (*m.bands).*v));
  EXPECT_EQ(r.bands->replicates, 50);
  EXPECT_EQ(r.bands->seed, 3);
  EXPECT_EQ(r.bands->resampling, "snapshot blocks");
  using N = DragModelFile::Bins;
  for (auto v : {&N::phi, &N::phi_center, &N::h, &N::h_stderr, &N::a, &N::log_a_stderr, &N::chi2, &N::h_stderr_bootstrap,
                 &N::log_a_stderr_bootstrap})
    EXPECT_TRUE(same((*r.bins).*v, (*m.bins).*v));
  for (auto v : {&N::used, &N::widths, &N::at_bound, &N::a_at_cap}) EXPECT_EQ((*r.bins).*v, (*m.bins).*v);
  EXPECT_EQ(r.data->series, m.data->series);
  EXPECT_TRUE(same(r.data->F, m.data->F) && same(r.data->phi, m.data->phi) && same(r.data->H, m.data->H) &&
              same(r.data->H_sigma, m.data->H_sigma));
  EXPECT_EQ(r.data->fitted, m.data->fitted);
  const auto &x = *r.diagnostics, &y = *m.diagnostics;
  using D = DragModelFile::Diagnostics;
  for (auto v : {&D::min_count, &D::min_widths, &D::breakpoints, &D::h_clamped_grid_points}) EXPECT_EQ(x.*v, y.*v);
  for (auto v : {&D::min_width_over_cell, &D::lambda_h, &D::lambda_log_a, &D::edf_h, &D::edf_log_a, &D::chi2_per_dof,
                 &D::cv_rms_H, &D::cv_in_sample_rms_H, &D::wall_seconds, &D::width_exponent_chi2_per_dof})
    EXPECT_TRUE(same(x.*v, y.*v));
  for (auto v : {&D::width_exponent_grid, &D::width_exponent_chi2, &D::residual_F, &D::residual_mean, &D::residual_mean_z,
                 &D::residual_rms_z, &D::residual_mean_smoothed, &D::cv_rms, &D::cv_mean})
    EXPECT_TRUE(same(x.*v, y.*v));
  for (auto v : {&D::residual_points, &D::cv_run, &D::cv_points}) EXPECT_EQ(x.*v, y.*v);
  EXPECT_EQ(x.residual_files, y.residual_files);
  EXPECT_EQ(x.residual_groups, y.residual_groups);
  EXPECT_EQ(x.cv_files, y.cv_files);
  EXPECT_EQ(r.source_files, m.source_files);
  EXPECT_EQ(r.source_checksums, m.source_checksums);
  EXPECT_TRUE(r.sources_pooled);
  EXPECT_FALSE(r.code_version.empty());
  // the closed choices as stored: the model file's spellings
  File f = File::open_read(path, MPI_COMM_SELF);
  EXPECT_EQ(f.attr_string("/", "operator"), "grid");
  EXPECT_EQ(f.attr_string("/", "curves"), "splines");
  EXPECT_EQ(f.attr_string("/", "micro_drag"), "stokes");
  EXPECT_FALSE(f.has_attr("/", "base_drag"));
  EXPECT_EQ(f.attr_int("/", "cgd_format_version"), 2);
}

TEST(DragModelSchema, TableModelRoundTripsAndIsOrderTwo) {
  cgd::testing::TempDir dir("cgd_test_schema");
  const std::string path = (dir.path() / "table.h5").string();
  DragModelFile m = model_record();
  m.curves = cgd::schema::ModelCurves::Table;
  m.table_cells_across = 6;
  m.h = spline(2, 4, 0.1), m.log_a = spline(2, 4, -700);
  m.table = DragModelFile::Table{{0.1, 0.2, 0.3, 0.4}, {0.5, 0.4, 0.3, 0.2}, {100, 200, 300, 400}, "/grids/6", 100};
  m.bands.reset(), m.bins.reset(), m.data.reset(), m.diagnostics.reset();
  cgd::schema::write_drag_model(path, schema_scene(), m);
  const DragModelFile r = cgd::schema::read_drag_model(path);
  EXPECT_EQ(r.curves, cgd::schema::ModelCurves::Table);
  EXPECT_EQ(r.table_cells_across, 6);
  ASSERT_TRUE(r.table);
  EXPECT_TRUE(same(r.table->phi, m.table->phi) && same(r.table->H, m.table->H) && same(r.table->count, m.table->count));
  EXPECT_EQ(r.table->source_group, "/grids/6");
  EXPECT_EQ(r.table->min_count, 100);
  EXPECT_FALSE(r.bands || r.bins || r.data || r.diagnostics);
  EXPECT_TRUE(std::isinf(r.log_a_min) && std::isinf(r.log_a_max)) << "a table's a = 0 has no log a range";
  // a table whose /h is cubic is not a table
  const std::string cubic = damaged_copy(path, "cubic.h5", [](hid_t f) {
    H5Adelete_by_name(f, "/h", "order", H5P_DEFAULT);
    const std::int64_t four = 4;
    const hid_t space = H5Screate(H5S_SCALAR);
    const hid_t attr = H5Acreate_by_name(f, "/h", "order", H5T_NATIVE_INT64, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    EXPECT_GE(H5Awrite(attr, H5T_NATIVE_INT64, &four), 0);
    H5Aclose(attr), H5Sclose(space);
    // knots for order 4 (4 + 4), so that the order alone is wrong
    H5Ldelete(f, "/h/knots", H5P_DEFAULT);
    const hsize_t n = 8;
    const double knots[8] = {0.1, 0.1, 0.1, 0.1, 0.4, 0.4, 0.4, 0.4};
    const hid_t kspace = H5Screate_simple(1, &n, nullptr);
    const hid_t d = H5Dcreate2(f, "/h/knots", H5T_NATIVE_DOUBLE, kspace, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, knots);
    H5Dclose(d), H5Sclose(kspace);
  });
  try {
    cgd::schema::read_drag_model(cubic);
    ADD_FAILURE() << "a table of order 4 was read";
  } catch (const cgd::InputError& e) {
    EXPECT_NE(std::string(e.what()).find(cubic + ": attribute 'order' of '/h' is 4, expected 2"), std::string::npos)
        << e.what();
  }
}

TEST(DragModelSchema, RefusesDamagedFilesNamingTheFileAndTheKey) {
  cgd::testing::TempDir dir("cgd_test_schema");
  const std::string good = (dir.path() / "model.h5").string();
  cgd::schema::write_drag_model(good, schema_scene(), model_record());
  const std::vector<Case> cases = {
      {"no_phi_crit", remove_attribute("/", "phi_crit"), "phi_crit", "lacks"},
      {"no_law", remove_attribute("/", "micro_drag"), "micro_drag", ""},
      {"h_max_text", attribute_as_text("/", "h_max", "0.99"), "h_max", "expected a number"},
      {"phi_crit_nan", attribute_number("/", "phi_crit", NAN), "phi_crit", "finite"},
      {"phi_crit_one", attribute_number("/", "phi_crit", 1.0), "phi_crit", "(0, 1)"},
      {"exponent_zero", attribute_number("/", "width_exponent", 0.0), "width_exponent", "(0, 10]"},
      {"log_a_nan", attribute_number("/", "log_a_min", NAN), "log_a_min", "NaN"},
      {"c_corr_a_nan", attribute_number("/c_corr", "a", NAN), "'a'", "finite"},
      {"knot_nan", value_at("/h/knots", 3, NAN), "/h/knots", "finite"},
      {"knots_unsorted", value_at("/log_a/knots", 5, 0.0), "/log_a/knots", "non-decreasing"},
      {"coefficient_nan", value_at("/log_a/coefficients", 0, NAN), "/log_a/coefficients", "finite"},
      {"knots_shape", replaced_dataset("/h/knots", {9}), "/h/knots", "shape (9,)"},
      {"band_shape", replaced_dataset("/bands/H_low", {5, 2}), "/bands/H_low", "shape (5, 2)"},
      {"bins_length", replaced_dataset("/bins/h", {4}), "/bins/h", "shape (4,)"},
      {"used_floats", replaced_dataset("/bins/used", {3}), "/bins/used", "integers"},
      {"data_shape", replaced_dataset("/data/H", {3, 2}), "/data/H", "shape (3, 2)"},
      {"no_c_corr_k", remove_attribute("/c_corr", "k"), "'k'", ""},
      {"no_h", removed_dataset("/h/coefficients"), "/h/coefficients", "no dataset"},
      {"operator", attribute_as_text("/", "operator", "tent"), "operator", "\"box\" or \"grid\""},
      // version 1's spelling in a version-2 file: refused (the upgrade path is for version-1 files only)
      {"old_operator", attribute_as_text("/", "operator", "tsc-grid"), "operator",
       "\"box\" or \"grid\" (cgd_format_version 2)"},
      {"curves", attribute_as_text("/", "curves", "lines"), "curves", "\"splines\", \"table\" or \"drift_table\""},
      {"u_t", attribute_as_text("/", "u_t_convention", "stokes"), "u_t_convention", "schiller-naumann"},
      {"order", attribute_number("/h", "order", 4.0), "order", "integer"},
      {"runs_phi", removed_attribute_values("/c_corr", "runs_phi", {0.05}), "runs_phi", "one per entry of 'runs'"},
      {"k_interval", removed_attribute_values("/c_corr", "k_interval", {0.1, 0.2, 0.3}), "k_interval", "expected 2"},
      {"no_decision", remove_attribute("/c_corr", "decision"), "decision", "lacks"},
      {"pooled_runs_float", attribute_number("/sources", "pooled_runs", 1.0), "pooled_runs", ""},
      {"pooled_runs_two", attribute_integer("/sources", "pooled_runs", 2), "pooled_runs", "expected 0 or 1"},
  };
  expect_refused(good, cases, [](const std::string& p) { cgd::schema::read_drag_model(p); });
}

// cgd-fit --parcel-fit's copy: /c_corr replaced, everything else as it was.
TEST(DragModelSchema, CCorrCopyReplacesOnlyTheCorrection) {
  cgd::testing::TempDir dir("cgd_test_schema");
  const std::string model = (dir.path() / "model.h5").string(), copy = (dir.path() / "fitted.h5").string();
  DragModelFile m = model_record();
  m.c_corr = {0, 0.05, "paper", false, std::nullopt};
  cgd::schema::write_drag_model(model, schema_scene(), m);
  DragModelFile::CCorr c = model_record().c_corr;
  c.a = 0.3;
  cgd::schema::write_c_corr_copy(model, copy, c);
  const DragModelFile before = cgd::schema::read_drag_model(model), after = cgd::schema::read_drag_model(copy);
  EXPECT_EQ(before.c_corr.source, "paper");
  EXPECT_FALSE(before.c_corr.parcel_fit);
  EXPECT_EQ(after.c_corr.a, 0.3);
  EXPECT_EQ(after.c_corr.source, "parcel-fit");
  ASSERT_TRUE(after.c_corr.parcel_fit);
  EXPECT_EQ(after.c_corr.parcel_fit->runs, (std::vector<std::string>{"r1", "r2"}));
  EXPECT_TRUE(same(after.h.knots, before.h.knots) && same(after.bands->H, before.bands->H));
  EXPECT_EQ(after.created, before.created);
}

// A version-1 model file a user kept reads through the schema's upgrade path (base_drag, "tsc-grid"): the
// half box's three-run model (<phi> = 0.02-0.10) as data/models/half_box.h5 shipped it, kept as
// tests/data/half_box_v1.h5 (its bytes, and so the checksum its runs and exports recorded, unchanged).
TEST(DragModelSchema, AVersion1ModelStillReads) {
  const char* s = std::getenv("CGD_SOURCE_DIR");
  const std::string path = std::string(s ? s : CGD_SOURCE_DIR_DEFAULT) + "/tests/data/half_box_v1.h5";
  EXPECT_EQ(cgd::file_checksum_fnv1a(path), "d111d2866014b600");  // the bytes data/models/half_box.h5 shipped
  const DragModelFile m = cgd::schema::read_drag_model(path);
  EXPECT_EQ(m.version, 1);
  EXPECT_EQ(m.calibration_operator, cgd::CalibrationOperator::Grid);
  EXPECT_EQ(m.curves, cgd::schema::ModelCurves::Splines);
  EXPECT_EQ(m.system.micro_drag, cgd::DragLaw::Beetstra);
  EXPECT_EQ(m.calibrated_cells_across, (std::vector<std::int64_t>{3, 4, 5, 6, 8, 12}));
  ASSERT_TRUE(m.bands && m.bins && m.data && m.diagnostics);
  EXPECT_EQ(m.bands->H_low.size(), m.bands->F.size() * m.bands->phi.size());
  EXPECT_FALSE(m.provenance.empty());
}

// One enum per closed choice, one spelling each, converted in one place, both ways.
TEST(SchemaChoices, EverySpellingConvertsBackToItsEnum) {
  for (const auto op : {cgd::CalibrationOperator::Box, cgd::CalibrationOperator::Grid})
    EXPECT_EQ(cgd::parse_calibration_operator(cgd::to_string(op)), op) << cgd::to_string(op);
  EXPECT_STREQ(cgd::to_string(cgd::CalibrationOperator::Box), "box");
  EXPECT_STREQ(cgd::to_string(cgd::CalibrationOperator::Grid), "grid");
  // the retired spellings are no spelling of today's files or command line
  for (const char* old : {"tsc-grid", "tsc-deposit-interpolate", "tent"})
    EXPECT_FALSE(cgd::parse_calibration_operator(old)) << old;
  EXPECT_EQ(cgd::calibration_operator_choices(), "\"box\" or \"grid\"");
  EXPECT_STREQ(cgd::schema::to_string(FilterKind::Box), "box");
  EXPECT_STREQ(cgd::schema::to_string(FilterKind::WholeBox), "whole_box");
  EXPECT_STREQ(cgd::schema::to_string(FilterKind::Grid), "grid");
  EXPECT_STREQ(cgd::schema::to_string(cgd::schema::ModelCurves::Splines), "splines");
  EXPECT_STREQ(cgd::schema::to_string(cgd::schema::ModelCurves::Table), "table");
  EXPECT_STREQ(cgd::schema::names::kMicroLawAttribute, "micro_drag");
}

/// The file rewritten as version 1 wrote it: cgd_format_version 1 and, for each (object, new, old) of
/// `renamed`, the string attribute `new` of `object` stored as `old`; each (object, name, text) of `values`
/// set to the old text.
Damage as_version1(const std::vector<std::array<std::string, 3>>& renamed,
                   const std::vector<std::array<std::string, 3>>& values) {
  return [=](hid_t f) {
    EXPECT_GE(H5Adelete_by_name(f, "/", "cgd_format_version", H5P_DEFAULT), 0);
    const std::int64_t one = 1;
    const hid_t space = H5Screate(H5S_SCALAR);
    const hid_t attr = H5Acreate_by_name(f, "/", "cgd_format_version", H5T_STD_I64LE, space, H5P_DEFAULT,
                                         H5P_DEFAULT, H5P_DEFAULT);
    EXPECT_GE(H5Awrite(attr, H5T_NATIVE_INT64, &one), 0);
    H5Aclose(attr), H5Sclose(space);
    for (const auto& [object, now, old] : renamed)
      EXPECT_GE(H5Arename_by_name(f, object.c_str(), now.c_str(), old.c_str(), H5P_DEFAULT), 0) << now;
    for (const auto& [object, name, text] : values) attribute_as_text(object, name, text)(f);
  };
}

// The one upgrade path of each format whose spelling changed: a version-1 file (the micro law under
// base_drag, the grid operator "tsc-grid" / "tsc-deposit-interpolate") reads to the same struct as the
// version-2 file it was made from; its old spellings are accepted there and only there.
TEST(SchemaVersions, VersionOneFilesReadThroughTheirUpgradePath) {
  cgd::testing::TempDir dir("cgd_test_schema");
  {
    const std::string good = (dir.path() / "model.h5").string();
    cgd::schema::write_drag_model(good, schema_scene(), model_record());
    const DragModelFile now = cgd::schema::read_drag_model(good);
    ASSERT_EQ(now.calibration_operator, cgd::CalibrationOperator::Grid);
    const std::string v1 = damaged_copy(good, "model_v1.h5",
                                        as_version1({{"/", "micro_drag", "base_drag"}}, {{"/", "operator", "tsc-grid"}}));
    const DragModelFile old = cgd::schema::read_drag_model(v1);
    EXPECT_EQ(old.version, 1);
    EXPECT_EQ(old.calibration_operator, now.calibration_operator);
    EXPECT_EQ(old.system.micro_drag, now.system.micro_drag);
    EXPECT_TRUE(same(old.h.coefficients, now.h.coefficients));
    // version 1 never wrote "grid" or micro_drag: such a file is refused, naming the version's spelling
    expect_refused(v1, {{"v1_new_operator", attribute_as_text("/", "operator", "grid"), "operator",
                         "\"box\" or \"tsc-grid\" (cgd_format_version 1)"},
                        {"v1_no_base_drag", remove_attribute("/", "base_drag"), "base_drag", ""}},
                   [](const std::string& p) { cgd::schema::read_drag_model(p); });
  }
  {
    const std::string good = (dir.path() / "filtered.h5").string();
    cgd::schema::write_filtered(good, nullptr, filtered_record());
    const Filtered now = cgd::schema::read_filtered(good);
    const std::string v1 = damaged_copy(good, "filtered_v1.h5",
                                        as_version1({}, {{"/grids", "operator", "tsc-deposit-interpolate"},
                                                         {"/grids/4", "operator", "tsc-deposit-interpolate"}}));
    const Filtered old = cgd::schema::read_filtered(v1);
    EXPECT_EQ(old.version, 1);
    ASSERT_EQ(old.groups.size(), now.groups.size());
    for (std::size_t i = 0; i < old.groups.size(); ++i) EXPECT_EQ(old.groups[i].kind, now.groups[i].kind);
    EXPECT_EQ(old.system.micro_drag, now.system.micro_drag);
    expect_refused(v1, {{"v1_new_operator", attribute_as_text("/grids/4", "operator", "grid"), "operator",
                         "expected \"tsc-deposit-interpolate\" (cgd_format_version 1)"}},
                   [](const std::string& p) { cgd::schema::read_filtered(p); });
  }
}
