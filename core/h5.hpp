#pragma once
// The one HDF5 wrapper of cgd (C API, parallel HDF5 through MPI-IO). Every collective call must be
// made by every rank of the file's communicator in the same order. Errors opening/reading a file
// throw InputError naming the file (and the dataset/attribute); write failures throw RunError.
#include <hdf5.h>
#include <mpi.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace cgd::h5 {

class File;
/// Whether a file gets cgd's checksum seal (kSealBytes below): only the formats that need it (checkpoints,
/// core/schema/check.hpp) ask for it.
enum class Seal { No, Yes };
/// How a dataset is stored: contiguous (the default: snapshots and checkpoints, written in hyperslabs by
/// every rank and read by ParaView through XDMF), or chunked with HDF5's byte shuffle and deflate (zlib level
/// 4), lossless, for small replicated tables full of repeated values and zeros (the filtered file's
/// per-snapshot sums, docs/schema-filtered.md). h5py, h5dump and every HDF5 reader read both the same way.
enum class Storage { Contiguous, Compressed };
void update_copy_atomically(const std::string& source_path, const std::string& final_path,
                            const std::function<void(File&)>& body);

class File {
 public:
  /// Create (truncate) `path` for parallel writing over `comm`; with Seal::Yes it starts with the user
  /// block of the checksum seal (filled by write_atomically). Collective.
  static File create(const std::string& path, MPI_Comm comm, Seal seal = Seal::No);
  /// Open an existing file read-only over `comm`. Collective. InputError if missing or not HDF5.
  static File open_read(const std::string& path, MPI_Comm comm);

  File(File&& other) noexcept;
  File& operator=(File&& other) noexcept;
  File(const File&) = delete;
  File& operator=(const File&) = delete;
  ~File();
  void close();  // collective; idempotent

  hid_t id() const { return file_; }
  /// True if the file carries cgd's checksum seal (verified by open_read; see seal_file below).
  bool sealed() const { return sealed_; }
  const std::string& path() const { return path_; }
  MPI_Comm comm() const { return comm_; }

  /// Attributes on an object path ("/" or a group such as "/params"; groups are created on
  /// demand when writing). Every rank passes the same value; collective.
  void set_attr(const std::string& object, const std::string& name, double value);
  void set_attr(const std::string& object, const std::string& name, std::int64_t value);
  void set_attr(const std::string& object, const std::string& name, const std::string& value);
  void set_attr(const std::string& object, const std::string& name, const std::vector<double>& value);
  void set_attr(const std::string& object, const std::string& name, const std::vector<std::int64_t>& value);
  /// A list of strings (1-D array of variable-length UTF-8 strings; h5py reads an array of str).
  void set_attr(const std::string& object, const std::string& name, const std::vector<std::string>& value);
  double attr_double(const std::string& object, const std::string& name) const;
  std::int64_t attr_int(const std::string& object, const std::string& name) const;
  std::string attr_string(const std::string& object, const std::string& name) const;
  std::vector<double> attr_doubles(const std::string& object, const std::string& name) const;
  std::vector<std::int64_t> attr_ints(const std::string& object, const std::string& name) const;
  std::vector<std::string> attr_strings(const std::string& object, const std::string& name) const;
  bool has_attr(const std::string& object, const std::string& name) const;

  bool exists(const std::string& path) const;      // a group or dataset
  void create_group(const std::string& path);      // with intermediate groups; collective
  std::vector<std::uint64_t> dims(const std::string& dataset) const;
  /// True if `dataset` is stored as integers (false: floating point or anything else).
  bool is_integer(const std::string& dataset) const;

  /// Distributed rows: a (total_rows x cols) dataset (cols = 1 gives a 1-D dataset) whose rows are
  /// the concatenation of every rank's `local_rows` rows in rank order. Collective.
  void write_rows(const std::string& dataset, const double* local, std::int64_t local_rows, int cols);
  void write_rows(const std::string& dataset, const std::int64_t* local, std::int64_t local_rows, int cols);
  /// Read rows [first_row, first_row + rows) of a 1-D or 2-D dataset (any rank, independent).
  std::vector<double> read_rows_double(const std::string& dataset, std::int64_t first_row, std::int64_t rows) const;
  std::vector<std::int64_t> read_rows_int(const std::string& dataset, std::int64_t first_row, std::int64_t rows) const;
  /// Whole dataset, flattened (any rank).
  std::vector<double> read_double(const std::string& dataset) const;
  std::vector<std::int64_t> read_int(const std::string& dataset) const;

  /// Distributed N-D block (row-major `global_dims`, e.g. {n_z, n_y, n_x, 3}); this rank writes the
  /// hyperslab starting at `offset` with extent `count` from contiguous `local`. Collective.
  void write_block(const std::string& dataset, const double* local, const std::vector<std::uint64_t>& global_dims,
                   const std::vector<std::uint64_t>& offset, const std::vector<std::uint64_t>& count);
  std::vector<double> read_block(const std::string& dataset, const std::vector<std::uint64_t>& offset,
                                 const std::vector<std::uint64_t>& count) const;

  /// A small dataset that every rank holds identically (rank 0's copy is written). Collective.
  void write_replicated(const std::string& dataset, const std::vector<double>& data,
                        const std::vector<std::uint64_t>& dims, Storage storage = Storage::Contiguous);
  void write_replicated(const std::string& dataset, const std::vector<std::int64_t>& data,
                        const std::vector<std::uint64_t>& dims, Storage storage = Storage::Contiguous);
  /// The filter a dataset is stored with: "none", "deflate" (with or without shuffle), or "other". Any rank.
  std::string storage_filter(const std::string& dataset) const;

 private:
  friend void update_copy_atomically(const std::string&, const std::string&, const std::function<void(File&)>&);
  File(hid_t file, std::string path, MPI_Comm comm) : file_(file), path_(std::move(path)), comm_(comm) {}
  hid_t file_ = -1;
  std::string path_;
  MPI_Comm comm_ = MPI_COMM_NULL;
  bool sealed_ = false;
};

/// The checksum seal (checkpoints of version 2, docs/schema-run.md "Seal and validation"): File::create
/// with Seal::Yes reserves an HDF5 user block of kSealBytes at the start of the file (HDF5 and h5py skip
/// it); write_atomically fills it, once the file is closed, with one line
///   "cgd-seal fnv1a64 <16 hex digits> bytes <n>\n"
/// -- the FNV-1a 64-bit hash (core/checksum.hpp) and length of every byte after the user block --
/// padded with zeros. File::open_read checks it before HDF5 parses anything, so a file cut short or with
/// overwritten bytes is refused with an InputError instead of reaching the library (which can crash on
/// damaged metadata) or the tool (which would take damaged numbers as data).
inline constexpr std::size_t kSealBytes = 512;
inline constexpr const char* kSealMagic = "cgd-seal fnv1a64 ";

/// Rewrites the seal of `path` (a closed file with a kSealBytes user block; no-op for a file without
/// one). Returns false if the file has no user block. Throws RunError when the file cannot be written.
bool seal_file(const std::string& path);

/// What the start of `path` says: no seal (no user block, or one not written by cgd), or a seal whose
/// hash and length match (ok) or not. `problem` gets a one-line description of a mismatch.
enum class SealState { None, Valid, Damaged };
SealState check_seal(const std::string& path, std::string* problem);

/// Write `final_path` atomically: `body` fills a file created at a temporary name in the same
/// folder; after a collective close rank 0 fsyncs and renames it into place, so a reader (or a
/// run killed at any moment) never sees a half-written file; with Seal::Yes the file is sealed before it is
/// renamed. Collective.
void write_atomically(const std::string& final_path, MPI_Comm comm, const std::function<void(File&)>& body,
                      Seal seal = Seal::No);

/// Write `final_path` atomically as a modified copy of `source_path`: the source is copied to a temporary
/// name, opened read-write for `body`, then moved into place as write_atomically does. Calling rank
/// only (MPI_COMM_SELF). The source is never modified.
void update_copy_atomically(const std::string& source_path, const std::string& final_path,
                            const std::function<void(File&)>& body);

/// True if `path` exists and is a readable HDF5 file.
bool is_hdf5(const std::string& path);

}  // namespace cgd::h5
