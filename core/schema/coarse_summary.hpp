#pragma once
// The coarse summary (summary.h5 of a cgd-coarse run, or cgd-coarse --summarise; cgd_format
// "coarse_summary", docs/schema-coarse-summary.md): its one home. The struct, the attribute names (each
// spelled once, in the tables below), one write and one validating read; cgd-coarse fills the struct,
// cgd-fit --parcel-fit consumes it.
#include <cstdint>
#include <optional>
#include <string>

#include "core/scene.hpp"

namespace cgd::schema {

/// Every value is a root attribute (float64 unless marked); the ones of the reference come together.
struct CoarseSummary {
  std::string drag;  // the law the run used (a drag law's name, or "model-raw": a model without c_corr)
  double parcel_size = 1;
  double cell_over_dp = 0;  // cube root of the fluid cell volume over d_p
  double slip_over_ut = 0, slip_stderr = 0;  // time-averaged <u_slip,y>/u_t over the window, its batch-means error
  double window_start_s = 0, window_end_s = 0;
  std::int64_t batches = 0;
  double drift_over_ut = 0, drift_stderr = 0;  // second half's mean minus the first's, and its error
  bool stationary = true;                      // |drift| <= 3 drift_stderr
  double simulated_s = 0, wall_s = 0;
  std::int64_t ranks = 1;
  double core_seconds_per_simulated_second = 0;

  /// With --reference RUN_DIR: the resolved reference over its own window.
  struct Reference {
    std::string run_dir;
    double slip_over_ut = 0, slip_stderr = 0;
    double window_start_s = 0, window_end_s = 0;
    double relative_error = 0, relative_error_stderr = 0;
  };
  std::optional<Reference> reference;

  /// Read from the scene's /params (written there by write_common, not by write_coarse_summary).
  double solids_fraction = 0;
  std::optional<bool> parcel_correction;  // fluid.parcel_correction; absent without a filtered law
  std::int64_t seed = 1;
};

/// Writes `path` atomically (the calling rank alone): the common attributes and /params of `scene`, and
/// the summary's attributes.
void write_coarse_summary(const std::string& path, const Scene& scene, const CoarseSummary& summary);

/// Reads and validates `path` (docs/schema-coarse-summary.md "What the reader checks"): the format and its
/// version; every attribute present and of its type, finite; parcel_size, cell_over_dp positive, the
/// errors >= 0, batches >= 2, ranks >= 1, each window's end after its start; the reference's attributes all
/// or none. InputError naming the file and the attribute, what was found and what was expected.
CoarseSummary read_coarse_summary(const std::string& path);

}  // namespace cgd::schema
