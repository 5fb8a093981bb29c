// The format rows of core/schema/check.hpp (docs/schema-run.md "Seal and validation"): a reader refuses a
// version outside its row's range naming it, a version-2 checkpoint without its seal, and a file of another
// format; every format but the checkpoint is written without a seal, so an edit with h5py keeps it readable.
#include <gtest/gtest.h>
#include <mpi.h>

#include <string>

#include "core/error.hpp"
#include "core/h5.hpp"
#include "core/schema/check.hpp"
#include "temp_dir.hpp"

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

TEST(SchemaFormat, EveryFormatButTheCheckpointIsUnsealedAndAtVersionOne) {
  for (const cgd::schema::Format* f : {&cgd::schema::kSnapshot, &cgd::schema::kSeries, &cgd::schema::kFiltered,
                                       &cgd::schema::kDragModel, &cgd::schema::kCoarseSummary}) {
    EXPECT_FALSE(f->sealed) << f->name;
    EXPECT_EQ(f->version, 1) << f->name;
  }
  EXPECT_TRUE(cgd::schema::kCheckpoint.sealed);
  EXPECT_EQ(cgd::schema::kCheckpoint.version, 3);  // 3: the neighbour-list anchors (issue 25)
  EXPECT_EQ(cgd::schema::kCheckpoint.oldest_version, 1);
}

TEST(SchemaFormat, RefusesAnotherFormatAndAVersionItDoesNotReadNamingThem) {
  cgd::testing::TempDir dir("cgd_test_schema");
  EXPECT_EQ(refusal(stamped(dir, "ok.h5", "filtered", 1), cgd::schema::kFiltered), "");
  const std::string newer = refusal(stamped(dir, "newer.h5", "filtered", 7), cgd::schema::kFiltered);
  EXPECT_NE(newer.find("cgd_format_version = 7: this build reads filtered files of version 1"), std::string::npos)
      << newer;
  EXPECT_NE(newer.find("newer cgd"), std::string::npos) << newer;
  const std::string older = refusal(stamped(dir, "older.h5", "checkpoint", 0), cgd::schema::kCheckpoint);
  EXPECT_NE(older.find("checkpoints of versions 1 to 3"), std::string::npos) << older;
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
