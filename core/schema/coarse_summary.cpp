// The coarse summary's write and read (core/schema/coarse_summary.hpp).
#include "core/schema/coarse_summary.hpp"

#include "core/error.hpp"
#include "core/h5.hpp"
#include "core/schema/common.hpp"
#include "core/schema/check.hpp"

namespace cgd::schema {

namespace {

enum class Range { Any, Positive, NonNegative };

/// A float64 attribute of the summary or of its reference: the name, the member, what it may hold.
template <class Struct>
struct Number {
  const char* name;
  double Struct::*member;
  Range range;
};

constexpr Number<CoarseSummary> kNumbers[] = {
    {"parcel_size", &CoarseSummary::parcel_size, Range::Positive},
    {"cell_over_dp", &CoarseSummary::cell_over_dp, Range::Positive},
    {"slip_over_ut", &CoarseSummary::slip_over_ut, Range::Any},
    {"slip_stderr", &CoarseSummary::slip_stderr, Range::NonNegative},
    {"window_start_s", &CoarseSummary::window_start_s, Range::Any},
    {"window_end_s", &CoarseSummary::window_end_s, Range::Any},
    {"drift_over_ut", &CoarseSummary::drift_over_ut, Range::Any},
    {"drift_stderr", &CoarseSummary::drift_stderr, Range::NonNegative},
    {"simulated_s", &CoarseSummary::simulated_s, Range::NonNegative},
    {"wall_s", &CoarseSummary::wall_s, Range::NonNegative},
    {"core_seconds_per_simulated_second", &CoarseSummary::core_seconds_per_simulated_second, Range::NonNegative},
};

using Reference = CoarseSummary::Reference;
constexpr Number<Reference> kReferenceNumbers[] = {
    {"reference_slip_over_ut", &Reference::slip_over_ut, Range::Any},
    {"reference_slip_stderr", &Reference::slip_stderr, Range::NonNegative},
    {"reference_window_start_s", &Reference::window_start_s, Range::Any},
    {"reference_window_end_s", &Reference::window_end_s, Range::Any},
    {"relative_error", &Reference::relative_error, Range::Any},
    {"relative_error_stderr", &Reference::relative_error_stderr, Range::NonNegative},
};

constexpr const char* kDrag = "drag";
constexpr const char* kBatches = "batches";
constexpr const char* kStationary = "stationary";
constexpr const char* kRanks = "ranks";
constexpr const char* kReferenceDir = "reference";

template <class Struct>
void read_number(const h5::File& f, const Number<Struct>& n, Struct& out) {
  const double v = finite_attr(f, "/", n.name);
  const bool ok = n.range == Range::Any || (n.range == Range::Positive ? v > 0 : v >= 0);
  if (!ok)
    throw InputError(f.path() + ": attribute '" + n.name + "' of '/' is " + std::to_string(v) + ", expected " +
                     (n.range == Range::Positive ? "a positive number" : "a number >= 0"));
  out.*n.member = v;
}

std::int64_t read_at_least(const h5::File& f, const char* name, std::int64_t low) {
  const std::int64_t v = f.attr_int("/", name);
  if (v < low)
    throw InputError(f.path() + ": attribute '" + name + "' of '/' is " + std::to_string(v) + ", expected >= " +
                     std::to_string(low));
  return v;
}

void require_window(const std::string& path, const char* start, double start_s, double end_s) {
  if (end_s < start_s)
    throw InputError(path + ": the window starting at '" + start + "' = " + std::to_string(start_s) +
                     " s ends before it, at " + std::to_string(end_s) + " s");
}

}  // namespace

void write_coarse_summary(const std::string& path, const Scene& scene, const CoarseSummary& s) {
  h5::write_atomically(path, MPI_COMM_SELF, [&](h5::File& f) {
    write_common(f, kCoarseSummary, scene);
    f.set_attr("/", kDrag, s.drag);
    for (const auto& n : kNumbers) f.set_attr("/", n.name, s.*n.member);
    f.set_attr("/", kBatches, s.batches);
    f.set_attr("/", kStationary, std::int64_t{s.stationary ? 1 : 0});
    f.set_attr("/", kRanks, s.ranks);
    if (s.reference) {
      f.set_attr("/", kReferenceDir, s.reference->run_dir);
      for (const auto& n : kReferenceNumbers) f.set_attr("/", n.name, (*s.reference).*n.member);
    }
  });
}

CoarseSummary read_coarse_summary(const std::string& path) {
  h5::File f = h5::File::open_read(path, MPI_COMM_SELF);
  check_format(f, kCoarseSummary);
  CoarseSummary s;
  s.drag = f.attr_string("/", kDrag);
  for (const auto& n : kNumbers) read_number(f, n, s);
  s.batches = read_at_least(f, kBatches, 2);
  s.stationary = f.attr_int("/", kStationary) != 0;
  s.ranks = read_at_least(f, kRanks, 1);
  require_window(path, "window_start_s", s.window_start_s, s.window_end_s);
  // the reference's attributes come together: any one of them asks for all
  bool any = f.has_attr("/", kReferenceDir);
  for (const auto& n : kReferenceNumbers) any = any || f.has_attr("/", n.name);
  if (any) {
    Reference r;
    r.run_dir = f.attr_string("/", kReferenceDir);
    for (const auto& n : kReferenceNumbers) read_number(f, n, r);
    require_window(path, "reference_window_start_s", r.window_start_s, r.window_end_s);
    s.reference = r;
  }
  s.solids_fraction = finite_attr(f, "/params", "solids_fraction");
  if (f.has_attr("/params", "parcel_correction")) s.parcel_correction = f.attr_int("/params", "parcel_correction") != 0;
  if (f.has_attr("/params", "seed")) s.seed = f.attr_int("/params", "seed");
  return s;
}

}  // namespace cgd::schema
