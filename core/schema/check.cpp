// Validating reads (core/schema/check.hpp).
#include "core/schema/check.hpp"

#include <cmath>
#include <cstdio>

#include "core/error.hpp"

namespace cgd::schema {

namespace {

std::string number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", x);
  return buf;
}

std::string dataset_name(const std::string& d) {
  return d.empty() || d.front() == '/' ? d : "/" + d;
}

}  // namespace

std::int64_t check_format(const h5::File& f, const Format& format) {
  const std::string& path = f.path();
  const std::string expected = std::string("expected \"") + format.name + "\", a " + format.what + " written by " +
                               format.written_by;
  if (!f.has_attr("/", "cgd_format"))
    throw InputError(path + ": not a cgd file (no root attribute 'cgd_format'; " + expected + ")");
  const std::string given = f.attr_string("/", "cgd_format");
  if (given != format.name)
    throw InputError(path + ": cgd_format = \"" + given + "\": not a " + format.what + " (" + expected + ")");
  const std::string versions = format.oldest_version == format.version
                                   ? "version " + std::to_string(format.version)
                                   : "versions " + std::to_string(format.oldest_version) + " to " +
                                         std::to_string(format.version);
  if (!f.has_attr("/", "cgd_format_version"))
    throw InputError(path + ": " + format.what + " lacks the root attribute cgd_format_version (expected " + versions +
                     ")");
  const std::int64_t version = f.attr_int("/", "cgd_format_version");
  if (version < format.oldest_version || version > format.version)
    throw InputError(path + ": cgd_format_version = " + std::to_string(version) + ": this build reads " + format.what +
                     "s of " + versions +
                     (version > format.version ? " (written by a newer cgd: read it with that build)" : ""));
  if (format.sealed && version >= 2 && !f.sealed())
    throw InputError(path + ": damaged: a " + std::string(format.what) + " of version " + std::to_string(version) +
                     " carries a checksum seal in its first 512 bytes, and this one has none (overwritten, or "
                     "rewritten by another tool)");
  return version;
}

std::string shape_text(const std::vector<std::uint64_t>& dims) {
  std::string s = "(";
  for (std::size_t i = 0; i < dims.size(); ++i) {
    if (i) s += ", ";
    s += dims[i] == kAnyExtent ? std::string("any") : std::to_string(dims[i]);
  }
  return s + (dims.size() == 1 ? ",)" : ")");
}

std::vector<std::uint64_t> require_shape(const h5::File& f, const std::string& dataset,
                                         const std::vector<std::uint64_t>& expected, const std::string& why) {
  const std::string name = dataset_name(dataset);
  const std::string reason = why.empty() ? "" : " (" + why + ")";
  if (!f.exists(name))
    throw InputError(f.path() + ": no dataset '" + name + "', expected one of shape " + shape_text(expected) + reason);
  const std::vector<std::uint64_t> dims = f.dims(name);
  bool ok = dims.size() == expected.size();
  for (std::size_t i = 0; ok && i < dims.size(); ++i) ok = expected[i] == kAnyExtent || dims[i] == expected[i];
  if (!ok)
    throw InputError(f.path() + ": dataset '" + name + "' has shape " + shape_text(dims) + ", expected " +
                     shape_text(expected) + reason);
  return dims;
}

std::vector<double> read_doubles(const h5::File& f, const std::string& dataset,
                                 const std::vector<std::uint64_t>& expected, Finite finite, const std::string& why) {
  const auto dims = require_shape(f, dataset, expected, why);
  std::vector<double> v = f.read_double(dataset_name(dataset));
  if (finite != Finite::Everywhere) return v;
  if (dims.size() <= 2) {
    require_finite(f.path(), dataset_name(dataset), v.data(), v.size(), dims.size() == 2 ? dims[1] : 1);
    return v;
  }
  for (std::size_t i = 0; i < v.size(); ++i)
    if (!std::isfinite(v[i])) {  // a field (n_z, n_y, n_x[, 3]): its index, slowest first
      std::vector<std::uint64_t> index(dims.size());
      std::uint64_t rest = i;
      for (std::size_t k = dims.size(); k-- > 0;) {
        index[k] = rest % std::max<std::uint64_t>(dims[k], 1);
        rest /= std::max<std::uint64_t>(dims[k], 1);
      }
      std::string at = shape_text(index);
      at = "[" + at.substr(1, at.size() - 2) + "]";
      throw InputError(f.path() + ": dataset '" + dataset_name(dataset) + "' holds " + number(v[i]) + " at " + at +
                       ", expected finite values");
    }
  return v;
}

std::vector<std::int64_t> read_ints(const h5::File& f, const std::string& dataset,
                                    const std::vector<std::uint64_t>& expected, const std::string& why) {
  require_shape(f, dataset, expected, why);
  if (!f.is_integer(dataset_name(dataset)))
    throw InputError(f.path() + ": dataset '" + dataset_name(dataset) + "' holds floating-point values, expected "
                     "integers (int64)");
  return f.read_int(dataset_name(dataset));
}

void require_finite(const std::string& path, const std::string& dataset, const double* values, std::size_t n,
                    std::size_t row_width, std::size_t first_row) {
  for (std::size_t i = 0; i < n; ++i)
    if (!std::isfinite(values[i])) {
      const std::size_t w = row_width ? row_width : 1;
      throw InputError(path + ": dataset '" + dataset + "' holds " + number(values[i]) + " at row " +
                       std::to_string(first_row + i / w) + (w > 1 ? " column " + std::to_string(i % w) : std::string()) +
                       ", expected finite values");
    }
}

void require_finite_where_counted(const std::string& path, const std::string& dataset,
                                  const std::vector<double>& values, const std::vector<std::int64_t>& count) {
  for (std::size_t i = 0; i < values.size() && i < count.size(); ++i)
    if (count[i] > 0 && !std::isfinite(values[i]))
      throw InputError(path + ": dataset '" + dataset + "' holds " + number(values[i]) + " in bin " +
                       std::to_string(i) + ", which has " + std::to_string(count[i]) +
                       " samples: expected a finite value (NaN only in empty bins)");
}

double finite_attr(const h5::File& f, const std::string& object, const std::string& name) {
  const double v = f.attr_double(object, name);
  if (!std::isfinite(v))
    throw InputError(f.path() + ": attribute '" + name + "' of '" + object + "' is " + number(v) +
                     ", expected a finite number");
  return v;
}

std::vector<double> finite_attrs(const h5::File& f, const std::string& object, const std::string& name,
                                 std::uint64_t n) {
  const std::vector<double> v = f.attr_doubles(object, name);
  if (n != kAnyExtent && v.size() != n)
    throw InputError(f.path() + ": attribute '" + name + "' of '" + object + "' holds " + std::to_string(v.size()) +
                     " values, expected " + std::to_string(n));
  for (double x : v)
    if (!std::isfinite(x))
      throw InputError(f.path() + ": attribute '" + name + "' of '" + object + "' holds " + number(x) +
                       ", expected finite numbers");
  return v;
}

void throw_if_any(MPI_Comm comm, const std::string& local_error) {
  int rank = 0, ranks = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &ranks);
  int mine = local_error.empty() ? ranks : rank, first = ranks;
  MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, comm);
  if (first == ranks) return;
  std::string message = local_error;
  int length = static_cast<int>(message.size());
  MPI_Bcast(&length, 1, MPI_INT, first, comm);
  message.resize(static_cast<std::size_t>(length));
  MPI_Bcast(message.data(), length, MPI_CHAR, first, comm);
  throw InputError(message);
}

}  // namespace cgd::schema
