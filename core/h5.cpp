// cgd::h5 — the HDF5 wrapper (C API over the MPI-IO driver). See h5.hpp for the contract.
//
// Parallel notes:
//  * Files are opened with H5Pset_fapl_mpio on the caller's communicator; metadata writes are
//    collective (H5Pset_coll_metadata_write). Metadata *reads* stay independent so that the read
//    functions documented as "any rank" really can be called by one rank alone.
//  * Raw data of distributed datasets is written with collective transfers (H5FD_MPIO_COLLECTIVE);
//    a rank with nothing to write still takes part with an empty (H5Sselect_none) selection.
//  * Argument checks that could fail on one rank only are reduced over the communicator first, so
//    every rank throws the same error instead of some ranks hanging in a collective call.
//  * HDF5's automatic error printing is switched off; the innermost entry of its error stack goes
//    into the exception message instead.
#include "core/h5.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <type_traits>
#include <utility>

#include "core/checksum.hpp"
#include "core/error.hpp"

namespace cgd::h5 {
namespace {

void silence_hdf5_errors() {
  static const bool silenced = [] {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    return true;
  }();
  (void)silenced;
}

herr_t collect_error(unsigned /*n*/, const H5E_error2_t* err, void* client) {
  auto* entries = static_cast<std::vector<std::string>*>(client);
  std::string text = err->desc ? err->desc : "";
  for (char& c : text)
    if (c == '\n') c = ' ';
  char minor[160] = "";
  if (H5Eget_msg(err->min_num, nullptr, minor, sizeof minor) > 0 && text.find(minor) == std::string::npos)
    text += std::string(text.empty() ? "" : "; ") + minor;
  entries->push_back(std::move(text));
  return 0;
}

/// The innermost (most specific) entry of HDF5's error stack, then clears the stack.
std::string hdf5_error_text() {
  std::vector<std::string> entries;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, collect_error, &entries);
  H5Eclear2(H5E_DEFAULT);
  if (entries.empty() || entries.front().empty()) return "no HDF5 diagnostic";
  return entries.front();
}

/// Owns one HDF5 identifier (dataset, dataspace, attribute, type, property list, group, object).
class Handle {
 public:
  using Closer = herr_t (*)(hid_t);
  Handle() = default;
  Handle(hid_t id, Closer closer) : id_(id), closer_(closer) {}
  Handle(Handle&& o) noexcept : id_(std::exchange(o.id_, -1)), closer_(o.closer_) {}
  Handle& operator=(Handle&& o) noexcept {
    if (this != &o) {
      reset();
      id_ = std::exchange(o.id_, -1);
      closer_ = o.closer_;
    }
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  ~Handle() { reset(); }
  void reset() {
    if (id_ >= 0 && closer_) closer_(id_);
    id_ = -1;
  }
  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }

 private:
  hid_t id_ = -1;
  Closer closer_ = nullptr;
};

std::string normalise(const std::string& path) {
  if (path.empty()) return "/";
  return path.front() == '/' ? path : "/" + path;
}

std::string describe(const std::string& object, const std::string& name) {
  return "attribute '" + name + "' of '" + normalise(object) + "'";
}

[[noreturn]] void throw_read(const std::string& file, const std::string& what) {
  throw InputError(file + ": " + what);
}
[[noreturn]] void throw_write(const std::string& file, const std::string& what) {
  throw RunError(file + ": cannot write " + what + " (" + hdf5_error_text() + ")");
}

/// True on every rank if `local_bad` is true on any rank of `comm` (collective).
bool any_rank(MPI_Comm comm, bool local_bad) {
  int bad = local_bad ? 1 : 0, global = 0;
  MPI_Allreduce(&bad, &global, 1, MPI_INT, MPI_MAX, comm);
  return global != 0;
}

Handle utf8_string_type() {
  Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(type.get(), H5T_VARIABLE);
  H5Tset_cset(type.get(), H5T_CSET_UTF8);
  return type;
}

Handle simple_space(const std::vector<hsize_t>& dims) {
  return Handle(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), H5Sclose);
}

std::uint64_t product(const std::vector<std::uint64_t>& v) {
  std::uint64_t p = 1;
  for (auto x : v) p *= x;
  return p;
}

Handle collective_transfer() {
  Handle dxpl(H5Pcreate(H5P_DATASET_XFER), H5Pclose);
  H5Pset_dxpl_mpio(dxpl.get(), H5FD_MPIO_COLLECTIVE);
  return dxpl;
}

// ---- attributes -----------------------------------------------------------------------------------

/// (Re)create attribute `name` on `object` (a group, created on demand, or a dataset) and write it.
void write_attribute(File& file, const std::string& object, const std::string& name, hid_t file_type,
                     hid_t mem_type, const std::vector<hsize_t>* dims, const void* data) {
  const std::string obj_path = normalise(object);
  if (!file.exists(obj_path)) file.create_group(obj_path);
  Handle obj(H5Oopen(file.id(), obj_path.c_str(), H5P_DEFAULT), H5Oclose);
  if (!obj.valid()) throw_write(file.path(), describe(object, name));
  const htri_t present = H5Aexists(obj.get(), name.c_str());
  if (present > 0 && H5Adelete(obj.get(), name.c_str()) < 0) throw_write(file.path(), describe(object, name));
  Handle space = dims ? simple_space(*dims) : Handle(H5Screate(H5S_SCALAR), H5Sclose);
  Handle attr(H5Acreate2(obj.get(), name.c_str(), file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT),
              H5Aclose);
  static const std::int64_t dummy = 0;  // an empty vector's data() may be null; HDF5 refuses null buffers
  if (!attr.valid() || H5Awrite(attr.get(), mem_type, data ? data : &dummy) < 0)
    throw_write(file.path(), describe(object, name));
}

struct OpenAttribute {
  Handle obj, attr, space, type;
  hssize_t points = 0;
};

OpenAttribute open_attribute(const File& file, const std::string& object, const std::string& name) {
  OpenAttribute a;
  const std::string obj_path = normalise(object);
  if (!file.exists(obj_path))
    throw_read(file.path(), "no object '" + obj_path + "' (looking for attribute '" + name + "')");
  a.obj = Handle(H5Oopen(file.id(), obj_path.c_str(), H5P_DEFAULT), H5Oclose);
  if (!a.obj.valid()) throw_read(file.path(), "cannot open '" + obj_path + "' (" + hdf5_error_text() + ")");
  if (H5Aexists(a.obj.get(), name.c_str()) <= 0) {
    H5Eclear2(H5E_DEFAULT);
    throw_read(file.path(), "no " + describe(object, name));
  }
  a.attr = Handle(H5Aopen(a.obj.get(), name.c_str(), H5P_DEFAULT), H5Aclose);
  if (!a.attr.valid())
    throw_read(file.path(), "cannot open " + describe(object, name) + " (" + hdf5_error_text() + ")");
  a.space = Handle(H5Aget_space(a.attr.get()), H5Sclose);
  a.type = Handle(H5Aget_type(a.attr.get()), H5Tclose);
  a.points = H5Sget_select_npoints(a.space.get());
  return a;
}

template <class T>
std::vector<T> read_numeric_attribute(const File& file, const std::string& object, const std::string& name,
                                      hid_t mem_type) {
  constexpr bool integer = std::is_integral_v<T>;
  OpenAttribute a = open_attribute(file, object, name);
  const H5T_class_t cls = H5Tget_class(a.type.get());
  if (cls != H5T_INTEGER && cls != H5T_FLOAT)
    throw_read(file.path(), describe(object, name) + " is " + (cls == H5T_STRING ? "a string" : "not a number") +
                                ", expected " + (integer ? "an integer" : "a number"));
  if (integer && cls != H5T_INTEGER)
    throw_read(file.path(), describe(object, name) + " is a floating-point number, expected an integer");
  std::vector<T> values(static_cast<std::size_t>(std::max<hssize_t>(a.points, 0)));
  if (!values.empty() && H5Aread(a.attr.get(), mem_type, values.data()) < 0)
    throw_read(file.path(), "cannot read " + describe(object, name) + " (" + hdf5_error_text() + ")");
  return values;
}

template <class T>
T read_scalar_attribute(const File& file, const std::string& object, const std::string& name,
                        hid_t mem_type) {
  std::vector<T> v = read_numeric_attribute<T>(file, object, name, mem_type);
  if (v.size() != 1)
    throw_read(file.path(),
               describe(object, name) + " has " + std::to_string(v.size()) + " values, expected 1");
  return v.front();
}

std::vector<std::string> read_string_attribute(const File& file, const std::string& object,
                                               const std::string& name) {
  OpenAttribute a = open_attribute(file, object, name);
  if (H5Tget_class(a.type.get()) != H5T_STRING)
    throw_read(file.path(), describe(object, name) + " is a number, expected a string");
  const auto n = static_cast<std::size_t>(std::max<hssize_t>(a.points, 0));
  std::vector<std::string> out;
  out.reserve(n);
  if (H5Tis_variable_str(a.type.get()) > 0) {
    Handle mem(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(mem.get(), H5T_VARIABLE);
    H5Tset_cset(mem.get(), H5Tget_cset(a.type.get()));
    std::vector<char*> ptrs(n, nullptr);
    if (n > 0 && H5Aread(a.attr.get(), mem.get(), ptrs.data()) < 0)
      throw_read(file.path(), "cannot read " + describe(object, name) + " (" + hdf5_error_text() + ")");
    for (char* p : ptrs) out.emplace_back(p ? p : "");
    if (n > 0) {
      std::vector<hsize_t> dims{n};
      Handle space = simple_space(dims);
      H5Dvlen_reclaim(mem.get(), space.get(), H5P_DEFAULT, ptrs.data());
    }
  } else {
    const std::size_t size = H5Tget_size(a.type.get());
    Handle mem(H5Tcopy(a.type.get()), H5Tclose);
    std::vector<char> buffer(n * size + 1, '\0');
    if (n > 0 && H5Aread(a.attr.get(), mem.get(), buffer.data()) < 0)
      throw_read(file.path(), "cannot read " + describe(object, name) + " (" + hdf5_error_text() + ")");
    const bool space_padded = H5Tget_strpad(a.type.get()) == H5T_STR_SPACEPAD;
    for (std::size_t i = 0; i < n; ++i) {
      std::string s(buffer.data() + i * size, size);
      if (auto nul = s.find('\0'); nul != std::string::npos) s.resize(nul);
      if (space_padded)
        while (!s.empty() && s.back() == ' ') s.pop_back();
      out.push_back(std::move(s));
    }
  }
  return out;
}

// ---- datasets --------------------------------------------------------------------------------------

Handle open_dataset(const File& file, const std::string& name) {
  const std::string path = normalise(name);
  if (!file.exists(path)) throw_read(file.path(), "no dataset '" + path + "'");
  Handle ds(H5Dopen2(file.id(), path.c_str(), H5P_DEFAULT), H5Dclose);
  if (!ds.valid()) throw_read(file.path(), "cannot open dataset '" + path + "' (" + hdf5_error_text() + ")");
  return ds;
}

std::vector<hsize_t> dataset_dims(const Handle& ds) {
  Handle space(H5Dget_space(ds.get()), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(space.get());
  std::vector<hsize_t> dims(static_cast<std::size_t>(std::max(rank, 0)));
  if (rank > 0) H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  return dims;
}

/// The dataset creation property list of `storage` for a dataset of `dims` and `element_bytes`: the default
/// (contiguous) for Storage::Contiguous, for an empty or tiny dataset (under 256 values a chunk costs more
/// than it saves) and where this HDF5 has no deflate filter; otherwise chunks of whole rows of the first
/// dimension of at most 1 MiB, byte shuffle, deflate level 4. Every rank computes the same list (the
/// dataset's creation is collective).
Handle creation_properties(Storage storage, const std::vector<std::uint64_t>& dims, std::size_t element_bytes) {
  Handle dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
  const std::uint64_t values = product(dims);
  if (storage == Storage::Contiguous || values < 256 || H5Zfilter_avail(H5Z_FILTER_DEFLATE) <= 0) return dcpl;
  std::vector<hsize_t> chunk(dims.begin(), dims.end());
  const std::uint64_t row = values / dims[0];  // the values of one index of the first dimension
  const std::uint64_t max_rows = std::max<std::uint64_t>(1, (std::uint64_t{1} << 20) / (row * element_bytes));
  chunk[0] = std::min<hsize_t>(dims[0], max_rows);
  H5Pset_chunk(dcpl.get(), static_cast<int>(chunk.size()), chunk.data());
  H5Pset_shuffle(dcpl.get());
  H5Pset_deflate(dcpl.get(), 4);
  return dcpl;
}

/// Create `name` with `global_dims` (or open it if it already exists with those dims) and write this
/// rank's hyperslab [offset, offset + count) from contiguous `local`; a new dataset is stored as `storage`
/// says. Collective.
void write_hyperslab(File& file, const std::string& name, hid_t mem_type, hid_t file_type,
                     const std::vector<std::uint64_t>& global_dims, const std::vector<std::uint64_t>& offset,
                     const std::vector<std::uint64_t>& count, const void* local,
                     Storage storage = Storage::Contiguous) {
  const std::string path = normalise(name);
  const std::size_t rank = global_dims.size();
  bool bad = offset.size() != rank || count.size() != rank || rank == 0;
  for (std::size_t d = 0; !bad && d < rank; ++d) bad = offset[d] + count[d] > global_dims[d];
  const std::uint64_t points = bad ? 0 : product(count);
  bad = bad || (points > 0 && local == nullptr);
  if (any_rank(file.comm(), bad))
    throw RunError(file.path() + ": cannot write dataset '" + path +
                   "': a rank's hyperslab (offset/count/data) does not fit the dataset's dimensions");

  const std::vector<hsize_t> dims(global_dims.begin(), global_dims.end());
  Handle ds;
  if (file.exists(path)) {
    ds = Handle(H5Dopen2(file.id(), path.c_str(), H5P_DEFAULT), H5Dclose);
    if (!ds.valid()) throw_write(file.path(), "dataset '" + path + "'");
    if (dataset_dims(ds) != dims)
      throw RunError(file.path() + ": cannot write dataset '" + path + "': it exists with other dimensions");
  } else {
    Handle lcpl(H5Pcreate(H5P_LINK_CREATE), H5Pclose);
    H5Pset_create_intermediate_group(lcpl.get(), 1);
    Handle space = simple_space(dims);
    Handle dcpl = creation_properties(storage, global_dims, H5Tget_size(file_type));
    ds = Handle(
        H5Dcreate2(file.id(), path.c_str(), file_type, space.get(), lcpl.get(), dcpl.get(), H5P_DEFAULT),
        H5Dclose);
    if (!ds.valid()) throw_write(file.path(), "dataset '" + path + "' (create)");
  }
  if (product(global_dims) == 0) return;  // nothing to transfer on any rank

  Handle file_space(H5Dget_space(ds.get()), H5Sclose);
  Handle mem_space;
  if (points == 0) {
    H5Sselect_none(file_space.get());
    mem_space = simple_space({1});
    H5Sselect_none(mem_space.get());
  } else {
    const std::vector<hsize_t> start(offset.begin(), offset.end()), extent(count.begin(), count.end());
    H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, start.data(), nullptr, extent.data(), nullptr);
    mem_space = simple_space(extent);
  }
  static const double dummy = 0;  // HDF5 wants a non-null buffer even for an empty selection
  Handle dxpl = collective_transfer();
  if (H5Dwrite(ds.get(), mem_type, mem_space.get(), file_space.get(), dxpl.get(), local ? local : &dummy) < 0)
    throw_write(file.path(), "dataset '" + path + "'");
}

template <class T>
void write_rows_impl(File& file, const std::string& name, const T* local, std::int64_t local_rows, int cols,
                     hid_t mem_type, hid_t file_type) {
  long long rows = local_rows, total = 0, first = 0;
  MPI_Allreduce(&rows, &total, 1, MPI_LONG_LONG, MPI_SUM, file.comm());
  MPI_Exscan(&rows, &first, 1, MPI_LONG_LONG, MPI_SUM, file.comm());
  int rank = 0;
  MPI_Comm_rank(file.comm(), &rank);
  if (rank == 0) first = 0;  // MPI_Exscan leaves rank 0's result undefined
  if (any_rank(file.comm(), local_rows < 0 || cols < 1))
    throw RunError(file.path() + ": cannot write dataset '" + normalise(name) +
                   "': negative row count or width < 1");
  const auto c = static_cast<std::uint64_t>(cols);
  std::vector<std::uint64_t> dims{static_cast<std::uint64_t>(total)},
      offset{static_cast<std::uint64_t>(first)}, count{static_cast<std::uint64_t>(rows)};
  if (cols > 1) {
    dims.push_back(c);
    offset.push_back(0);
    count.push_back(c);
  }
  write_hyperslab(file, name, mem_type, file_type, dims, offset, count, local);
}

template <class T>
std::vector<T> read_selection(const File& file, const std::string& name, hid_t mem_type,
                              const std::vector<std::uint64_t>* offset,
                              const std::vector<std::uint64_t>* count) {
  Handle ds = open_dataset(file, name);
  const std::vector<hsize_t> dims = dataset_dims(ds);
  const std::string path = normalise(name);
  const H5T_class_t cls = [&] {
    Handle type(H5Dget_type(ds.get()), H5Tclose);
    return H5Tget_class(type.get());
  }();
  if (cls != H5T_INTEGER && cls != H5T_FLOAT)
    throw_read(file.path(), "dataset '" + path + "' is not numeric");
  Handle file_space(H5Dget_space(ds.get()), H5Sclose);
  std::uint64_t points = 1;
  Handle mem_space;
  if (offset) {
    bool bad = offset->size() != dims.size() || count->size() != dims.size();
    for (std::size_t d = 0; !bad && d < dims.size(); ++d) bad = (*offset)[d] + (*count)[d] > dims[d];
    if (bad) {
      std::string shape;
      for (auto d : dims) {
        if (!shape.empty()) shape += 'x';
        shape += std::to_string(d);
      }
      throw_read(file.path(), "requested block lies outside dataset '" + path + "' (shape " + shape + ")");
    }
    points = product(*count);
    if (points == 0) return {};
    const std::vector<hsize_t> start(offset->begin(), offset->end()), extent(count->begin(), count->end());
    H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, start.data(), nullptr, extent.data(), nullptr);
    mem_space = simple_space(extent);
  } else {
    for (auto d : dims) points *= d;
    if (points == 0) return {};
    mem_space = simple_space({static_cast<hsize_t>(points)});
  }
  std::vector<T> out(points);
  if (H5Dread(ds.get(), mem_type, mem_space.get(), file_space.get(), H5P_DEFAULT, out.data()) < 0)
    throw_read(file.path(), "cannot read dataset '" + path + "' (" + hdf5_error_text() + ")");
  return out;
}

template <class T>
std::vector<T> read_rows_impl(const File& file, const std::string& name, std::int64_t first_row,
                              std::int64_t rows, hid_t mem_type) {
  const std::vector<std::uint64_t> dims = file.dims(name);
  if (dims.empty() || dims.size() > 2)
    throw_read(file.path(), "dataset '" + normalise(name) + "' is not a 1-D or 2-D array of rows");
  if (first_row < 0 || rows < 0 || static_cast<std::uint64_t>(first_row + rows) > dims[0])
    throw_read(file.path(), "rows [" + std::to_string(first_row) + ", " + std::to_string(first_row + rows) +
                                ") outside dataset '" + normalise(name) + "' with " +
                                std::to_string(dims[0]) + " rows");
  std::vector<std::uint64_t> offset{static_cast<std::uint64_t>(first_row)},
      count{static_cast<std::uint64_t>(rows)};
  if (dims.size() == 2) {
    offset.push_back(0);
    count.push_back(dims[1]);
  }
  return read_selection<T>(file, name, mem_type, &offset, &count);
}

template <class T>
void write_replicated_impl(File& file, const std::string& name, const std::vector<T>& data,
                           const std::vector<std::uint64_t>& dims, hid_t mem_type, hid_t file_type,
                           Storage storage) {
  if (any_rank(file.comm(), product(dims) != data.size()))
    throw RunError(file.path() + ": cannot write dataset '" + normalise(name) +
                   "': " + std::to_string(data.size()) + " values do not match its dimensions");
  int rank = 0;
  MPI_Comm_rank(file.comm(), &rank);
  const std::vector<std::uint64_t> offset(dims.size(), 0);
  const std::vector<std::uint64_t> count = rank == 0 ? dims : std::vector<std::uint64_t>(dims.size(), 0);
  write_hyperslab(file, name, mem_type, file_type, dims, offset, count, data.data(), storage);
}

}  // namespace

// ---- File: lifetime -----------------------------------------------------------------------------------

File File::create(const std::string& path, MPI_Comm comm, Seal seal) {
  silence_hdf5_errors();
  Handle fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
  H5Pset_fapl_mpio(fapl.get(), comm, MPI_INFO_NULL);
  H5Pset_coll_metadata_write(fapl.get(), 1);
  Handle fcpl(H5Pcreate(H5P_FILE_CREATE), H5Pclose);
  if (seal == Seal::Yes) H5Pset_userblock(fcpl.get(), kSealBytes);  // room for the seal (write_atomically fills it)
  const hid_t id = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, fcpl.get(), fapl.get());
  if (id < 0) throw RunError(path + ": cannot create HDF5 file (" + hdf5_error_text() + ")");
  return File(id, path, comm);
}

File File::open_read(const std::string& path, MPI_Comm comm) {
  silence_hdf5_errors();
  // Check on rank 0 first and share the verdict, so every rank throws the same clear message.
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  int verdict = 0;  // 0 ok, 1 missing, 2 not a regular file, 3 unreadable, 4 not HDF5, 5 damaged seal
  int sealed = 0;
  std::string seal_problem;
  if (rank == 0) {
    std::error_code ec;
    const auto status = std::filesystem::status(path, ec);
    if (!std::filesystem::exists(status))
      verdict = 1;
    else if (!std::filesystem::is_regular_file(status))
      verdict = 2;
    else if (::access(path.c_str(), R_OK) != 0)
      verdict = 3;
    else {
      // the seal first: a damaged file must not reach the HDF5 library, which may crash on it
      const SealState seal = check_seal(path, &seal_problem);
      if (seal == SealState::Damaged)
        verdict = 5;
      else if (H5Fis_hdf5(path.c_str()) <= 0)
        verdict = 4;
      sealed = seal == SealState::Valid ? 1 : 0;
    }
    H5Eclear2(H5E_DEFAULT);
  }
  int shared[2] = {verdict, sealed};
  MPI_Bcast(shared, 2, MPI_INT, 0, comm);
  verdict = shared[0];
  if (verdict == 5) {
    // every rank throws the same message: rank 0 shares its text
    int length = static_cast<int>(seal_problem.size());
    MPI_Bcast(&length, 1, MPI_INT, 0, comm);
    seal_problem.resize(static_cast<std::size_t>(length));
    MPI_Bcast(seal_problem.data(), length, MPI_CHAR, 0, comm);
    throw InputError(path + ": damaged: " + seal_problem);
  }
  static const char* const reasons[] = {"", "no such file", "not a regular file", "permission denied",
                                        "not an HDF5 file"};
  if (verdict != 0) throw InputError(path + ": cannot open as HDF5 (" + reasons[verdict] + ")");

  Handle fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
  H5Pset_fapl_mpio(fapl.get(), comm, MPI_INFO_NULL);
  const hid_t id = H5Fopen(path.c_str(), H5F_ACC_RDONLY, fapl.get());
  if (id < 0) throw InputError(path + ": cannot open as HDF5 (" + hdf5_error_text() + ")");
  File file(id, path, comm);
  file.sealed_ = shared[1] != 0;
  return file;
}

File::File(File&& other) noexcept
    : file_(std::exchange(other.file_, -1)), path_(std::move(other.path_)), comm_(other.comm_),
      sealed_(other.sealed_) {}

File& File::operator=(File&& other) noexcept {
  if (this != &other) {
    if (file_ >= 0) H5Fclose(file_);
    file_ = std::exchange(other.file_, -1);
    path_ = std::move(other.path_);
    comm_ = other.comm_;
    sealed_ = other.sealed_;
  }
  return *this;
}

File::~File() {
  if (file_ >= 0) {
    H5Fclose(file_);  // errors cannot be reported from a destructor; close() reports them
    H5Eclear2(H5E_DEFAULT);
  }
}

void File::close() {
  if (file_ < 0) return;
  const herr_t status = H5Fclose(file_);
  file_ = -1;
  if (status < 0) throw RunError(path_ + ": cannot close HDF5 file (" + hdf5_error_text() + ")");
}

// ---- File: attributes ---------------------------------------------------------------------------------

void File::set_attr(const std::string& object, const std::string& name, double value) {
  write_attribute(*this, object, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, nullptr, &value);
}
void File::set_attr(const std::string& object, const std::string& name, std::int64_t value) {
  write_attribute(*this, object, name, H5T_STD_I64LE, H5T_NATIVE_INT64, nullptr, &value);
}
void File::set_attr(const std::string& object, const std::string& name, const std::string& value) {
  Handle type = utf8_string_type();
  const char* text = value.c_str();
  write_attribute(*this, object, name, type.get(), type.get(), nullptr, &text);
}
void File::set_attr(const std::string& object, const std::string& name, const std::vector<double>& value) {
  const std::vector<hsize_t> dims{value.size()};
  write_attribute(*this, object, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &dims, value.data());
}
void File::set_attr(const std::string& object, const std::string& name,
                    const std::vector<std::int64_t>& value) {
  const std::vector<hsize_t> dims{value.size()};
  write_attribute(*this, object, name, H5T_STD_I64LE, H5T_NATIVE_INT64, &dims, value.data());
}
void File::set_attr(const std::string& object, const std::string& name,
                    const std::vector<std::string>& value) {
  Handle type = utf8_string_type();
  std::vector<const char*> texts;
  texts.reserve(value.size());
  for (const auto& s : value) texts.push_back(s.c_str());
  const std::vector<hsize_t> dims{value.size()};
  write_attribute(*this, object, name, type.get(), type.get(), &dims, texts.data());
}

double File::attr_double(const std::string& object, const std::string& name) const {
  return read_scalar_attribute<double>(*this, object, name, H5T_NATIVE_DOUBLE);
}
std::int64_t File::attr_int(const std::string& object, const std::string& name) const {
  return read_scalar_attribute<std::int64_t>(*this, object, name, H5T_NATIVE_INT64);
}
std::string File::attr_string(const std::string& object, const std::string& name) const {
  std::vector<std::string> v = read_string_attribute(*this, object, name);
  if (v.size() != 1)
    throw_read(path_, describe(object, name) + " holds " + std::to_string(v.size()) + " strings, expected 1");
  return v.front();
}
std::vector<std::string> File::attr_strings(const std::string& object, const std::string& name) const {
  return read_string_attribute(*this, object, name);
}
std::vector<double> File::attr_doubles(const std::string& object, const std::string& name) const {
  return read_numeric_attribute<double>(*this, object, name, H5T_NATIVE_DOUBLE);
}
std::vector<std::int64_t> File::attr_ints(const std::string& object, const std::string& name) const {
  return read_numeric_attribute<std::int64_t>(*this, object, name, H5T_NATIVE_INT64);
}

bool File::has_attr(const std::string& object, const std::string& name) const {
  const std::string obj_path = normalise(object);
  if (!exists(obj_path)) return false;
  const htri_t present = H5Aexists_by_name(file_, obj_path.c_str(), name.c_str(), H5P_DEFAULT);
  H5Eclear2(H5E_DEFAULT);
  return present > 0;
}

// ---- File: groups and datasets ---------------------------------------------------------------------------

bool File::exists(const std::string& path) const {
  const std::string p = normalise(path);
  if (p == "/") return true;
  // H5Lexists fails (rather than answering false) when an intermediate group is missing: walk down.
  std::size_t pos = 0;
  while (pos != std::string::npos) {
    pos = p.find('/', pos + 1);
    const std::string prefix = p.substr(0, pos);
    if (prefix.size() <= 1 || prefix.back() == '/') continue;
    const htri_t r = H5Lexists(file_, prefix.c_str(), H5P_DEFAULT);
    if (r <= 0) {
      H5Eclear2(H5E_DEFAULT);
      return false;
    }
  }
  return true;
}

void File::create_group(const std::string& path) {
  const std::string p = normalise(path);
  if (exists(p)) return;
  Handle lcpl(H5Pcreate(H5P_LINK_CREATE), H5Pclose);
  H5Pset_create_intermediate_group(lcpl.get(), 1);
  Handle group(H5Gcreate2(file_, p.c_str(), lcpl.get(), H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
  if (!group.valid()) throw_write(path_, "group '" + p + "'");
}

bool File::is_integer(const std::string& dataset) const {
  Handle ds = open_dataset(*this, dataset);
  Handle type(H5Dget_type(ds.get()), H5Tclose);
  return H5Tget_class(type.get()) == H5T_INTEGER;
}

std::vector<std::uint64_t> File::dims(const std::string& dataset) const {
  Handle ds = open_dataset(*this, dataset);
  const std::vector<hsize_t> d = dataset_dims(ds);
  return {d.begin(), d.end()};
}

void File::write_rows(const std::string& dataset, const double* local, std::int64_t local_rows, int cols) {
  write_rows_impl(*this, dataset, local, local_rows, cols, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE);
}
void File::write_rows(const std::string& dataset, const std::int64_t* local, std::int64_t local_rows,
                      int cols) {
  write_rows_impl(*this, dataset, local, local_rows, cols, H5T_NATIVE_INT64, H5T_STD_I64LE);
}

std::vector<double> File::read_rows_double(const std::string& dataset, std::int64_t first_row,
                                           std::int64_t rows) const {
  return read_rows_impl<double>(*this, dataset, first_row, rows, H5T_NATIVE_DOUBLE);
}
std::vector<std::int64_t> File::read_rows_int(const std::string& dataset, std::int64_t first_row,
                                              std::int64_t rows) const {
  return read_rows_impl<std::int64_t>(*this, dataset, first_row, rows, H5T_NATIVE_INT64);
}
std::vector<double> File::read_double(const std::string& dataset) const {
  return read_selection<double>(*this, dataset, H5T_NATIVE_DOUBLE, nullptr, nullptr);
}
std::vector<std::int64_t> File::read_int(const std::string& dataset) const {
  return read_selection<std::int64_t>(*this, dataset, H5T_NATIVE_INT64, nullptr, nullptr);
}

void File::write_block(const std::string& dataset, const double* local,
                       const std::vector<std::uint64_t>& global_dims,
                       const std::vector<std::uint64_t>& offset, const std::vector<std::uint64_t>& count) {
  write_hyperslab(*this, dataset, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, global_dims, offset, count, local);
}

std::vector<double> File::read_block(const std::string& dataset, const std::vector<std::uint64_t>& offset,
                                     const std::vector<std::uint64_t>& count) const {
  return read_selection<double>(*this, dataset, H5T_NATIVE_DOUBLE, &offset, &count);
}

void File::write_replicated(const std::string& dataset, const std::vector<double>& data,
                            const std::vector<std::uint64_t>& dims, Storage storage) {
  write_replicated_impl(*this, dataset, data, dims, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, storage);
}
void File::write_replicated(const std::string& dataset, const std::vector<std::int64_t>& data,
                            const std::vector<std::uint64_t>& dims, Storage storage) {
  write_replicated_impl(*this, dataset, data, dims, H5T_NATIVE_INT64, H5T_STD_I64LE, storage);
}

std::string File::storage_filter(const std::string& dataset) const {
  Handle ds = open_dataset(*this, dataset);
  Handle dcpl(H5Dget_create_plist(ds.get()), H5Pclose);
  const int n = H5Pget_nfilters(dcpl.get());
  std::string result = "none";
  for (int i = 0; i < n; ++i) {
    unsigned flags = 0, config = 0;
    std::size_t n_values = 0;
    const H5Z_filter_t id =
        H5Pget_filter2(dcpl.get(), static_cast<unsigned>(i), &flags, &n_values, nullptr, 0, nullptr, &config);
    if (id == H5Z_FILTER_DEFLATE)
      result = "deflate";
    else if (id != H5Z_FILTER_SHUFFLE)
      return "other";
  }
  return result;
}

// ---- free functions
// ----------------------------------------------------------------------------------------

void write_atomically(const std::string& final_path, MPI_Comm comm, const std::function<void(File&)>& body,
                      Seal seal) {
  const std::string tmp_path = final_path + ".tmp";
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  try {
    File file = File::create(tmp_path, comm, seal);
    body(file);
    file.close();
  } catch (...) {
    // The File's destructor has closed the file on every rank (the body's errors are collective).
    if (rank == 0) std::remove(tmp_path.c_str());
    throw;
  }
  int error = 0;
  if (rank == 0) {
    try {
      // the checksum of the complete file into its user block (a no-op for a file without one; a copy of a
      // sealed file made by update_copy_atomically is sealed again)
      seal_file(tmp_path);
    } catch (const RunError&) {
      error = EIO;
    }
    // Data on disk before the name appears: fsync the file, rename, then fsync the folder.
    if (error != 0) {
    } else if (const int fd = ::open(tmp_path.c_str(), O_RDONLY); fd >= 0) {
      if (::fsync(fd) != 0) error = errno;
      ::close(fd);
    } else {
      error = errno;
    }
    if (error == 0 && std::rename(tmp_path.c_str(), final_path.c_str()) != 0) error = errno;
    if (error == 0) {
      const std::filesystem::path folder = std::filesystem::path(final_path).parent_path();
      if (const int dfd = ::open(folder.empty() ? "." : folder.c_str(), O_RDONLY | O_DIRECTORY); dfd >= 0) {
        ::fsync(dfd);
        ::close(dfd);
      }
    } else {
      std::remove(tmp_path.c_str());
    }
  }
  MPI_Bcast(&error, 1, MPI_INT, 0, comm);
  MPI_Barrier(comm);
  if (error != 0)
    throw RunError(final_path + ": cannot move the completed file into place (" + std::strerror(error) + ")");
}

void update_copy_atomically(const std::string& source_path, const std::string& final_path,
                            const std::function<void(File&)>& body) {
  // the copy is the file write_atomically's body fills: open it read-write and let `body` edit it
  File source = File::open_read(source_path, MPI_COMM_SELF);  // a clear InputError if it is not HDF5
  source.close();
  write_atomically(final_path, MPI_COMM_SELF, [&](File& fresh) {
    const std::string tmp = fresh.path();
    fresh.close();
    std::error_code ec;
    std::filesystem::copy_file(source_path, tmp, std::filesystem::copy_options::overwrite_existing, ec);
    if (ec) throw RunError(tmp + ": cannot copy " + source_path + " (" + ec.message() + ")");
    Handle fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
    H5Pset_fapl_mpio(fapl.get(), MPI_COMM_SELF, MPI_INFO_NULL);
    const hid_t id = H5Fopen(tmp.c_str(), H5F_ACC_RDWR, fapl.get());
    if (id < 0) throw RunError(tmp + ": cannot open for update (" + hdf5_error_text() + ")");
    File edit(id, tmp, MPI_COMM_SELF);
    body(edit);
    edit.close();
    fresh = std::move(edit);  // closed: write_atomically's close() is then a no-op
  });
}

namespace {

/// The HDF5 signature (the superblock's first 8 bytes), found at the end of a kSealBytes user block.
constexpr char kHdf5Signature[8] = {'\x89', 'H', 'D', 'F', '\r', '\n', '\x1a', '\n'};

bool has_seal_user_block(std::FILE* f) {
  char sig[8];
  return std::fseek(f, static_cast<long>(kSealBytes), SEEK_SET) == 0 && std::fread(sig, 1, 8, f) == 8 &&
         std::memcmp(sig, kHdf5Signature, 8) == 0;
}

}  // namespace

bool seal_file(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "r+b");
  if (!f) throw RunError(path + ": cannot open to write its checksum seal (" + std::strerror(errno) + ")");
  if (!has_seal_user_block(f)) {
    std::fclose(f);
    return false;  // a copy of a file written without a user block (before version 2): left unsealed
  }
  std::uint64_t bytes = 0;
  const std::string hash = file_checksum_fnv1a_from(path, kSealBytes, &bytes);
  char block[kSealBytes] = {};
  std::snprintf(block, sizeof block, "%s%s bytes %llu\n", kSealMagic, hash.c_str(),
                static_cast<unsigned long long>(bytes));
  const bool ok = std::fseek(f, 0, SEEK_SET) == 0 && std::fwrite(block, 1, kSealBytes, f) == kSealBytes;
  const bool closed = std::fclose(f) == 0;
  if (!ok || !closed) throw RunError(path + ": cannot write its checksum seal");
  return true;
}

SealState check_seal(const std::string& path, std::string* problem) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return SealState::None;  // the caller reports unreadable files
  char block[kSealBytes + 1] = {};
  const std::size_t got = std::fread(block, 1, kSealBytes, f);
  const bool user_block = got == kSealBytes && has_seal_user_block(f);
  std::fclose(f);
  const std::size_t magic = std::strlen(kSealMagic);
  if (got < magic || std::memcmp(block, kSealMagic, magic) != 0) {
    // no seal: a file of another writer, or one created with File::create and never sealed (the format
    // readers refuse an unsealed file of version 2 or later)
    return SealState::None;
  }
  char stored[17] = {};
  unsigned long long stored_bytes = 0;
  if (std::sscanf(block + magic, "%16[0-9a-f] bytes %llu", stored, &stored_bytes) != 2 || !user_block) {
    if (problem) *problem = "its checksum seal (the first 512 bytes) is unreadable; expected \"" +
                            std::string(kSealMagic) + "<16 hex digits> bytes <n>\" followed by the HDF5 file";
    return SealState::Damaged;
  }
  std::uint64_t bytes = 0;
  const std::string hash = file_checksum_fnv1a_from(path, kSealBytes, &bytes);
  if (bytes != stored_bytes) {
    if (problem)
      *problem = "found " + std::to_string(bytes) + " bytes after the seal, expected " +
                 std::to_string(stored_bytes) + (bytes < stored_bytes ? " (cut short)" : " (bytes added)");
    return SealState::Damaged;
  }
  if (hash != stored) {
    if (problem)
      *problem = "its contents do not match the checksum written with it (FNV-1a " + hash + ", expected " +
                 stored + "): bytes were changed since it was written";
    return SealState::Damaged;
  }
  return SealState::Valid;
}

bool is_hdf5(const std::string& path) {
  silence_hdf5_errors();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return false;
  const htri_t r = H5Fis_hdf5(path.c_str());
  H5Eclear2(H5E_DEFAULT);
  return r > 0;
}

}  // namespace cgd::h5
