#pragma once
// Validating reads, shared by every format's reader (docs/schema-run.md "What the readers check"): the
// format and its version, the checksum seal of a version-2 file, a dataset's shape, finite values. Each
// check throws an InputError of one line naming the file, the dataset or attribute, what was found and
// what was expected; the tools turn it into exit status 2 before they write anything.
#include <mpi.h>

#include <cstdint>
#include <string>
#include <vector>

#include "core/h5.hpp"

namespace cgd::schema {

/// One file format of cgd (docs/schema-*.md): its cgd_format name, the version this build writes, the
/// oldest version it reads, whether the file carries the checksum seal (core/h5.hpp), and for messages
/// what it is and who writes it. Every writer stamps a format with write_common (core/schema/common.hpp), every
/// reader checks it with check_format, from these rows alone.
struct Format {
  const char* name;
  std::int64_t version;
  std::int64_t oldest_version;
  bool sealed;
  const char* what;
  const char* written_by;
};

/// Checkpoints are sealed (since version 2: the seal's user block; version 3 holds the neighbour-list
/// anchors instead of one displacement bound, version 4 the DEM slab bounds in force) because a restart must not run on damaged
/// bytes and users have no reason to edit them; every other format is read and validated by its content,
/// so a file a researcher edited with h5py stays readable (docs/schema-run.md "Seal and validation").
/// The filtered and drag model files are at version 2 since they spell each idea once (the micro law
/// `micro_drag`, the calibration operator "box"/"grid"); their version-1 files are read through one upgrade
/// path each (upgrade_version1 in core/schema/filtered.cpp and drag_model.cpp; docs/schema-filtered.md and
/// docs/schema-drag-model.md "Versions"), because filtered files cost hours to make again and model files'
/// checksums are recorded by the runs and exports that used them (data/models/half_box.h5 among them).
inline constexpr Format kSnapshot{"snapshot", 1, 1, false, "snapshot", "cgd-generate or cgd-coarse"};
inline constexpr Format kSeries{"series", 1, 1, false, "series file", "cgd-generate or cgd-coarse"};
inline constexpr Format kCheckpoint{"checkpoint", 4, 1, true, "checkpoint",
                                    "the checkpoint.h5 of a run directory, written by cgd-generate or cgd-coarse"};
inline constexpr Format kFiltered{"filtered", 2, 1, false, "filtered file", "cgd-filter"};
inline constexpr Format kDragModel{"drag_model", 2, 1, false, "drag model file", "cgd-fit"};
inline constexpr Format kCoarseSummary{"coarse_summary", 1, 1, false, "coarse summary",
                                       "cgd-coarse (a coarse run's summary.h5, or --summarise)"};

/// A dimension that may take any extent in an expected shape.
inline constexpr std::uint64_t kAnyExtent = ~std::uint64_t{0};

/// Checks the root attributes cgd_format (= format.name) and cgd_format_version (format.oldest_version ..
/// format.version), and that a sealed format's file of version 2 or later carries a valid seal (open_read
/// has refused a seal that does not match). Returns the version.
std::int64_t check_format(const h5::File& f, const Format& format);

/// "(1408, 3)".
std::string shape_text(const std::vector<std::uint64_t>& dims);

/// The dataset's shape, checked against `expected` (kAnyExtent matches any extent). InputError "no
/// dataset" / "has shape (...), expected (...)"; `why` (e.g. "N = 1408 particles") is appended.
std::vector<std::uint64_t> require_shape(const h5::File& f, const std::string& dataset,
                                         const std::vector<std::uint64_t>& expected, const std::string& why = "");

/// Where values must be finite: nowhere, everywhere, or in the rows whose `count` is positive (per-bin
/// arrays of the filtered file: empty bins hold NaN).
enum class Finite { Not, Everywhere };

/// Reads a float64 dataset of shape `expected` (require_shape) and checks it finite when asked.
std::vector<double> read_doubles(const h5::File& f, const std::string& dataset,
                                 const std::vector<std::uint64_t>& expected, Finite finite,
                                 const std::string& why = "");
/// Reads an integer dataset of shape `expected`; InputError if it is stored as floating point.
std::vector<std::int64_t> read_ints(const h5::File& f, const std::string& dataset,
                                    const std::vector<std::uint64_t>& expected, const std::string& why = "");

/// InputError naming `dataset` of `path` and the first non-finite value (its row of `row_width` values,
/// counted from `first_row` when `values` is a slice of the dataset), unless every value is finite.
void require_finite(const std::string& path, const std::string& dataset, const double* values, std::size_t n,
                    std::size_t row_width = 1, std::size_t first_row = 0);
/// The same for the rows whose count[i] > 0 (per-bin arrays: values.size() == count.size()).
void require_finite_where_counted(const std::string& path, const std::string& dataset,
                                  const std::vector<double>& values, const std::vector<std::int64_t>& count);

/// A float attribute that must be finite (attr_double, then the check).
double finite_attr(const h5::File& f, const std::string& object, const std::string& name);
/// Float-array attribute with `n` values (n = kAnyExtent: any number), each finite.
std::vector<double> finite_attrs(const h5::File& f, const std::string& object, const std::string& name,
                                 std::uint64_t n = kAnyExtent);

/// Collective: if any rank of `comm` has a non-empty `local_error`, every rank throws InputError with the
/// message of the lowest such rank (so all ranks end with the same status and nobody waits in a collective).
void throw_if_any(MPI_Comm comm, const std::string& local_error);

}  // namespace cgd::schema
