// cgd::h5::File in one process: every attribute type and dataset kind round-trips, errors name the
// file and the object, and write_atomically leaves either the complete file or nothing.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <mpi.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/h5.hpp"
#include "temp_dir.hpp"

namespace fs = std::filesystem;
using cgd::h5::File;

namespace {

class H5Test : public ::testing::Test {
 protected:
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  cgd::testing::TempDir tmp_{"cgd_test_h5"};
  const fs::path& dir_ = tmp_.path();
};

/// The file type HDF5 stores for a dataset, as a class and a size in bytes.
std::pair<H5T_class_t, std::size_t> stored_type(const File& f, const std::string& dataset) {
  const hid_t ds = H5Dopen2(f.id(), dataset.c_str(), H5P_DEFAULT);
  const hid_t type = H5Dget_type(ds);
  const std::pair<H5T_class_t, std::size_t> result{H5Tget_class(type), H5Tget_size(type)};
  H5Tclose(type);
  H5Dclose(ds);
  return result;
}

template <class F>
std::string input_error_message(F&& f) {
  try {
    f();
  } catch (const cgd::InputError& e) {
    return e.what();
  }
  return "(no InputError thrown)";
}

}  // namespace

TEST_F(H5Test, EveryAttributeTypeRoundTrips) {
  const std::string toml = "[particles]\ndiameter = 75e-6   # m, φ_p ≥ 0\n";
  {
    File f = File::create(path("attrs.h5"), MPI_COMM_WORLD);
    f.set_attr("/", "time", 0.125);
    f.set_attr("/", "step", std::int64_t{1234567890123});
    f.set_attr("/", "scene", toml);
    f.set_attr("/", "empty_text", std::string());
    f.set_attr("/params/deep/group", "box_size_m",
               std::vector<double>{1e-3, 2e-3, 3e-3});  // group made on demand
    f.set_attr("/params/deep/group", "cells", std::vector<std::int64_t>{8, -16, 32});
    f.set_attr("/params", "columns", std::vector<std::string>{"time", "slip_velocity", "ε"});
    f.set_attr("/params", "nothing", std::vector<double>{});
    f.set_attr("/", "replaced", 1.5);
    f.set_attr("/", "replaced", std::string("now text"));  // an attribute may change type
    f.close();
    f.close();  // idempotent
  }
  const File f = File::open_read(path("attrs.h5"), MPI_COMM_WORLD);
  EXPECT_EQ(f.attr_double("/", "time"), 0.125);
  EXPECT_EQ(f.attr_int("/", "step"), 1234567890123);
  EXPECT_EQ(f.attr_string("/", "scene"), toml);
  EXPECT_EQ(f.attr_string("/", "empty_text"), "");
  EXPECT_EQ(f.attr_doubles("/params/deep/group", "box_size_m"), (std::vector<double>{1e-3, 2e-3, 3e-3}));
  EXPECT_EQ(f.attr_ints("/params/deep/group", "cells"), (std::vector<std::int64_t>{8, -16, 32}));
  EXPECT_EQ(f.attr_strings("/params", "columns"), (std::vector<std::string>{"time", "slip_velocity", "ε"}));
  EXPECT_TRUE(f.attr_doubles("/params", "nothing").empty());
  EXPECT_EQ(f.attr_string("/", "replaced"), "now text");
  // numeric conversions the reader allows
  EXPECT_EQ(f.attr_double("/", "step"), 1234567890123.0);
  EXPECT_EQ(f.attr_doubles("/", "time"), std::vector<double>{0.125});
  EXPECT_TRUE(f.has_attr("/params/deep/group", "cells"));
  EXPECT_FALSE(f.has_attr("/params/deep/group", "absent"));
  EXPECT_FALSE(f.has_attr("/no/such/group", "cells"));
  EXPECT_TRUE(f.exists("/params/deep"));
  EXPECT_TRUE(f.exists("params/deep/group"));
  EXPECT_FALSE(f.exists("/params/deep/nope"));
  EXPECT_FALSE(f.exists("/nope/deeper/still"));
}

TEST_F(H5Test, RowsRoundTripAsFloat64AndInt64WithTheirShapes) {
  const std::int64_t n = 5;
  std::vector<double> position(n * 3);
  std::vector<double> diameter(n);
  std::vector<std::int64_t> id(n);
  for (std::int64_t i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) position[i * 3 + c] = 10.0 * i + c + 0.5;
    diameter[i] = 1e-4 * (i + 1);
    id[i] = (std::int64_t{1} << 40) + i;  // needs 64 bits
  }
  {
    File f = File::create(path("rows.h5"), MPI_COMM_WORLD);
    f.write_rows("/particles/position", position.data(), n, 3);  // intermediate group created
    f.write_rows("/particles/diameter", diameter.data(), n, 1);
    f.write_rows("/particles/id", id.data(), n, 1);
    f.write_rows("/particles/none", static_cast<const double*>(nullptr), 0, 3);
    f.close();
  }
  const File f = File::open_read(path("rows.h5"), MPI_COMM_WORLD);
  EXPECT_EQ(f.dims("/particles/position"), (std::vector<std::uint64_t>{5, 3}));
  EXPECT_EQ(f.dims("/particles/diameter"), (std::vector<std::uint64_t>{5}));
  EXPECT_EQ(f.dims("/particles/none"), (std::vector<std::uint64_t>{0, 3}));
  EXPECT_EQ(stored_type(f, "/particles/id"), std::make_pair(H5T_INTEGER, std::size_t{8}));
  EXPECT_EQ(stored_type(f, "/particles/position"), std::make_pair(H5T_FLOAT, std::size_t{8}));
  EXPECT_EQ(f.read_double("/particles/position"), position);
  EXPECT_EQ(f.read_double("/particles/diameter"), diameter);
  EXPECT_EQ(f.read_int("/particles/id"), id);
  EXPECT_TRUE(f.read_double("/particles/none").empty());
  EXPECT_EQ(f.read_rows_double("/particles/position", 2, 2),
            std::vector<double>(position.begin() + 6, position.begin() + 12));
  EXPECT_EQ(f.read_rows_int("/particles/id", 4, 1), std::vector<std::int64_t>{id[4]});
  EXPECT_TRUE(f.read_rows_double("/particles/diameter", 5, 0).empty());
}

// Storage::Compressed is lossless and shrinks a table of mostly zeros (the filtered file's per-snapshot
// sums); a table too small to gain (under 256 values) and an empty one stay contiguous, as does the default.
TEST_F(H5Test, CompressedTablesReadBackBitForBitAndShrink) {
  const std::uint64_t rows = 300, cols = 65;  // chunked in 1 MiB pieces: 300 x 65 x 8 B = 156 kB, one chunk
  std::vector<double> sums(rows * cols, 0.0);
  std::vector<std::int64_t> counts(rows * cols, 0);
  for (std::uint64_t r = 0; r < rows; ++r)
    for (std::uint64_t c = 10; c < 20; ++c) {  // a band of occupied bins, the rest empty
      sums[r * cols + c] = 1.0 / (1.0 + static_cast<double>(r * c)) - 1e-300;
      counts[r * cols + c] = static_cast<std::int64_t>(r + c);
    }
  const std::vector<double> small{1.5, -2.25, 3.0};
  {
    File f = File::create(path("packed.h5"), MPI_COMM_WORLD);
    f.write_replicated("/t/sums", sums, {rows, cols}, cgd::h5::Storage::Compressed);
    f.write_replicated("/t/counts", counts, {rows, cols}, cgd::h5::Storage::Compressed);
    f.write_replicated("/t/plain", sums, {rows, cols});
    f.write_replicated("/t/small", small, {3}, cgd::h5::Storage::Compressed);
    f.write_replicated("/t/empty", std::vector<double>{}, {0, cols}, cgd::h5::Storage::Compressed);
    f.close();
  }
  const File f = File::open_read(path("packed.h5"), MPI_COMM_WORLD);
  EXPECT_EQ(f.read_double("/t/sums"), sums);  // bit for bit (operator== on doubles)
  EXPECT_EQ(f.read_int("/t/counts"), counts);
  EXPECT_EQ(f.read_double("/t/small"), small);
  EXPECT_EQ(f.dims("/t/sums"), (std::vector<std::uint64_t>{rows, cols}));
  EXPECT_EQ(f.dims("/t/empty"), (std::vector<std::uint64_t>{0, cols}));
  EXPECT_EQ(f.read_rows_double("/t/sums", 7, 2),
            std::vector<double>(sums.begin() + 7 * cols, sums.begin() + 9 * cols));
  EXPECT_EQ(f.storage_filter("/t/sums"), "deflate");
  EXPECT_EQ(f.storage_filter("/t/counts"), "deflate");
  EXPECT_EQ(f.storage_filter("/t/plain"), "none");
  EXPECT_EQ(f.storage_filter("/t/small"), "none");
  EXPECT_EQ(f.storage_filter("/t/empty"), "none");
  const auto stored = [&](const char* name) {
    const hid_t ds = H5Dopen2(f.id(), name, H5P_DEFAULT);
    const hsize_t bytes = H5Dget_storage_size(ds);
    H5Dclose(ds);
    return bytes;
  };
  // 85 % of the values are zero: deflate after shuffle keeps well under half (zlib on such runs of zero bytes
  // reaches ~1/10; one half leaves room for any zlib version)
  EXPECT_LT(stored("/t/sums"), stored("/t/plain") / 2);
  EXPECT_EQ(stored("/t/plain"), rows * cols * sizeof(double));
}

TEST_F(H5Test, BlocksWrittenInPiecesAssembleAndReadBackAsSubBlocks) {
  // A (n_z, n_y, n_x, 3) = (2, 3, 4, 3) field written as two y-slabs into the same dataset.
  const std::vector<std::uint64_t> dims{2, 3, 4, 3};
  auto value = [](std::uint64_t z, std::uint64_t y, std::uint64_t x, std::uint64_t c) {
    return 1000.0 * z + 100.0 * y + 10.0 * x + c;
  };
  auto slab = [&](std::uint64_t y0, std::uint64_t ny) {
    std::vector<double> v;
    for (std::uint64_t z = 0; z < 2; ++z)
      for (std::uint64_t y = y0; y < y0 + ny; ++y)
        for (std::uint64_t x = 0; x < 4; ++x)
          for (std::uint64_t c = 0; c < 3; ++c) v.push_back(value(z, y, x, c));
    return v;
  };
  {
    File f = File::create(path("block.h5"), MPI_COMM_WORLD);
    f.write_block("/fluid/velocity", slab(0, 1).data(), dims, {0, 0, 0, 0}, {2, 1, 4, 3});
    f.write_block("/fluid/velocity", slab(1, 2).data(), dims, {0, 1, 0, 0}, {2, 2, 4, 3});
    f.write_replicated("/table", std::vector<double>{1, 2, 3, 4, 5, 6}, {2, 3});
    f.write_replicated("/counts", std::vector<std::int64_t>{7, 8, 9}, {3});
    f.close();
  }
  const File f = File::open_read(path("block.h5"), MPI_COMM_WORLD);
  EXPECT_EQ(f.dims("/fluid/velocity"), dims);
  EXPECT_EQ(f.read_double("/fluid/velocity"), slab(0, 3));
  EXPECT_EQ(f.read_block("/fluid/velocity", {0, 1, 0, 0}, {2, 2, 4, 3}), slab(1, 2));
  const std::vector<double> one = f.read_block("/fluid/velocity", {1, 2, 3, 1}, {1, 1, 1, 2});
  EXPECT_EQ(one, (std::vector<double>{value(1, 2, 3, 1), value(1, 2, 3, 2)}));
  EXPECT_EQ(f.dims("/table"), (std::vector<std::uint64_t>{2, 3}));
  EXPECT_EQ(f.read_double("/table"), (std::vector<double>{1, 2, 3, 4, 5, 6}));
  EXPECT_EQ(f.read_int("/counts"), (std::vector<std::int64_t>{7, 8, 9}));
}

TEST_F(H5Test, BadWritesThrowRunErrorNamingFileAndDataset) {
  File f = File::create(path("bad.h5"), MPI_COMM_WORLD);
  const std::vector<double> v(6, 1.0);
  try {
    f.write_block("/fluid/pressure", v.data(), {2, 3}, {1, 0}, {2, 3});  // past the end
    FAIL() << "no RunError";
  } catch (const cgd::RunError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.h5"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("/fluid/pressure"), std::string::npos) << e.what();
  }
  EXPECT_THROW(f.write_replicated("/table", v, {4, 2}), cgd::RunError);  // 6 values for 8 places
  f.write_block("/field", v.data(), {2, 3}, {0, 0}, {2, 3});
  EXPECT_THROW(f.write_block("/field", v.data(), {3, 2}, {0, 0}, {3, 2}), cgd::RunError);  // other dims
}

TEST_F(H5Test, OpeningAMissingOrNonHdf5FileThrowsInputErrorNamingIt) {
  const std::string missing = path("missing.h5");
  std::string msg = input_error_message([&] { File::open_read(missing, MPI_COMM_WORLD); });
  EXPECT_NE(msg.find(missing + ": cannot open as HDF5"), std::string::npos) << msg;
  EXPECT_NE(msg.find("no such file"), std::string::npos) << msg;

  const std::string text = path("scene.toml");
  std::ofstream(text) << "[domain]\nsize_dp = [10, 10, 10]\n";
  msg = input_error_message([&] { File::open_read(text, MPI_COMM_WORLD); });
  EXPECT_NE(msg.find(text + ": cannot open as HDF5"), std::string::npos) << msg;
  EXPECT_NE(msg.find("not an HDF5 file"), std::string::npos) << msg;

  msg = input_error_message([&] { File::open_read(dir_.string(), MPI_COMM_WORLD); });
  EXPECT_NE(msg.find("not a regular file"), std::string::npos) << msg;

  EXPECT_FALSE(cgd::h5::is_hdf5(missing));
  EXPECT_FALSE(cgd::h5::is_hdf5(text));
  EXPECT_FALSE(cgd::h5::is_hdf5(dir_.string()));
  File::create(path("real.h5"), MPI_COMM_WORLD).close();
  EXPECT_TRUE(cgd::h5::is_hdf5(path("real.h5")));
}

TEST_F(H5Test, MissingDatasetOrAttributeThrowsInputErrorNamingFileAndObject) {
  {
    File f = File::create(path("some.h5"), MPI_COMM_WORLD);
    f.set_attr("/", "cgd_format", std::string("snapshot"));
    const std::vector<double> d{1, 2};
    f.write_rows("/particles/diameter", d.data(), 2, 1);
    f.close();
  }
  const File f = File::open_read(path("some.h5"), MPI_COMM_WORLD);
  std::string msg = input_error_message([&] { f.read_double("/particles/velocity"); });
  EXPECT_NE(msg.find("some.h5"), std::string::npos) << msg;
  EXPECT_NE(msg.find("/particles/velocity"), std::string::npos) << msg;
  msg = input_error_message([&] { f.dims("/fluid/pressure"); });
  EXPECT_NE(msg.find("/fluid/pressure"), std::string::npos) << msg;
  msg = input_error_message([&] { f.attr_double("/", "time"); });
  EXPECT_NE(msg.find("some.h5"), std::string::npos) << msg;
  EXPECT_NE(msg.find("'time'"), std::string::npos) << msg;
  msg = input_error_message([&] { f.attr_string("/params", "scene"); });
  EXPECT_NE(msg.find("/params"), std::string::npos) << msg;
  msg = input_error_message([&] { f.attr_double("/", "cgd_format"); });  // a string is not a number
  EXPECT_NE(msg.find("is a string, expected a number"), std::string::npos) << msg;
  msg = input_error_message([&] { f.read_rows_double("/particles/diameter", 1, 5); });
  EXPECT_NE(msg.find("/particles/diameter"), std::string::npos) << msg;
}

TEST_F(H5Test, CreatingInAMissingFolderThrowsRunErrorNamingIt) {
  const std::string where = path("no/such/folder/out.h5");
  try {
    File::create(where, MPI_COMM_WORLD);
    FAIL() << "no RunError";
  } catch (const cgd::RunError& e) {
    EXPECT_NE(std::string(e.what()).find(where), std::string::npos) << e.what();
  }
}

TEST_F(H5Test, AtomicWriteLeavesOnlyTheCompleteFile) {
  const std::string final_path = path("snap.h5");
  cgd::h5::write_atomically(final_path, MPI_COMM_WORLD, [&](File& f) {
    EXPECT_EQ(f.path(), final_path + ".tmp");  // written beside the final name
    EXPECT_FALSE(fs::exists(final_path));
    f.set_attr("/", "step", std::int64_t{7});
  });
  EXPECT_TRUE(fs::exists(final_path));
  EXPECT_FALSE(fs::exists(final_path + ".tmp"));
  EXPECT_EQ(File::open_read(final_path, MPI_COMM_WORLD).attr_int("/", "step"), 7);
}

// The checksum seal (h5.hpp, the checkpoints' format): written by write_atomically with Seal::Yes, checked
// by open_read before HDF5 parses the file, so an overwritten byte anywhere after the user block, or a file
// cut short, is an InputError.
TEST_F(H5Test, SealedFileIsRefusedOnceAByteChangesOrItIsCutShort) {
  const std::string final_path = path("sealed.h5");
  cgd::h5::write_atomically(final_path, MPI_COMM_WORLD, [&](File& f) {
    const std::vector<double> x{1, 2, 3, 4};
    f.write_replicated("/data", x, {4});
  }, cgd::h5::Seal::Yes);
  EXPECT_TRUE(File::open_read(final_path, MPI_COMM_WORLD).sealed());
  std::string problem;
  EXPECT_EQ(cgd::h5::check_seal(final_path, &problem), cgd::h5::SealState::Valid) << problem;
  const auto size = fs::file_size(final_path);
  const std::string damaged = path("damaged.h5"), short_file = path("short.h5");
  fs::copy_file(final_path, damaged);
  {
    std::fstream io(damaged, std::ios::in | std::ios::out | std::ios::binary);
    io.seekp(static_cast<std::streamoff>(size - 3));
    io.put('\x7f');
  }
  fs::copy_file(final_path, short_file);
  fs::resize_file(short_file, size - 100);
  for (const auto& [file, expected] : {std::pair<std::string, std::string>{damaged, "do not match the checksum"},
                                       {short_file, "cut short"}}) {
    try {
      File::open_read(file, MPI_COMM_WORLD);
      ADD_FAILURE() << file << ": no InputError";
    } catch (const cgd::InputError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(file + ": damaged: "), std::string::npos) << msg;
      EXPECT_NE(msg.find(expected), std::string::npos) << msg;
    }
  }
  // a file without the user block (every format but the checkpoint, or one written by another tool) is
  // read as before, unsealed
  cgd::h5::write_atomically(path("plain.h5"), MPI_COMM_WORLD, [&](File&) {});
  EXPECT_FALSE(File::open_read(path("plain.h5"), MPI_COMM_WORLD).sealed());
  EXPECT_EQ(cgd::h5::check_seal(path("plain.h5"), &problem), cgd::h5::SealState::None);
}

TEST_F(H5Test, AtomicWriteWithAFailingBodyLeavesNeitherFinalNorTmp) {
  const std::string final_path = path("snap.h5");
  EXPECT_THROW(cgd::h5::write_atomically(final_path, MPI_COMM_WORLD,
                                         [](File& f) {
                                           f.set_attr("/", "step", std::int64_t{1});
                                           throw cgd::RunError("simulated failure");
                                         }),
               cgd::RunError);
  EXPECT_FALSE(fs::exists(final_path));
  EXPECT_FALSE(fs::exists(final_path + ".tmp"));
}

TEST_F(H5Test, AtomicRewriteWithAFailingBodyKeepsThePreviousFile) {
  const std::string final_path = path("series.h5");
  cgd::h5::write_atomically(final_path, MPI_COMM_WORLD,
                            [](File& f) { f.set_attr("/", "rows", std::int64_t{10}); });
  EXPECT_THROW(cgd::h5::write_atomically(final_path, MPI_COMM_WORLD,
                                         [](File&) { throw std::runtime_error("disk full"); }),
               std::runtime_error);
  EXPECT_EQ(File::open_read(final_path, MPI_COMM_WORLD).attr_int("/", "rows"), 10);
  EXPECT_FALSE(fs::exists(final_path + ".tmp"));
}

TEST_F(H5Test, MovedFileKeepsItsHandleAndTheSourceIsEmpty) {
  File a = File::create(path("moved.h5"), MPI_COMM_WORLD);
  File b = std::move(a);
  EXPECT_LT(a.id(), 0);  // NOLINT(bugprone-use-after-move): the moved-from state is the point
  b.set_attr("/", "x", 1.0);
  b.close();
  EXPECT_EQ(File::open_read(path("moved.h5"), MPI_COMM_WORLD).attr_double("/", "x"), 1.0);
}
