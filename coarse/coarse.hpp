#pragma once
// cgd-coarse's library: the checks a coarse-grid CFD-DEM / CFD-DPM (parcel) scene must pass before it
// runs, and the slip summary of a run (the paper's Figures 2 and 3: the time-averaged domain slip
// <u_slip,y>/u_t over the sampling window, its batch-means standard error, the relative error against a
// resolved reference run and the cost in core-seconds per simulated second).
#include <mpi.h>

#include <optional>
#include <string>

#include "core/scene.hpp"
#include "core/time_average.hpp"

namespace cgd::coarse {

/// Smallest parcel count accepted: the domain slip is an average over the parcels, and below ~100
/// parcels its fluctuation from parcel-scale noise alone (~1/sqrt(N) of the slip's spread) reaches
/// the 5-10 % level the coarse runs are meant to resolve.
inline constexpr long long kMinimumParcels = 100;

/// Refuses (InputError, exit 2, nothing written) what cgd-coarse cannot run well: no solved fluid, a
/// parcel wider than a fluid cell (the point-parcel mapping of the drag and the void fraction no
/// longer holds), fewer than kMinimumParcels parcels, a slab thinner than the contact cutoff on some
/// rank, a sampling window that starts after the end of the run.
void check_coarse_scene(const Scene& scene, int ranks);

/// The time-averaged slip of one run directory.
struct SlipSummary {
  std::string run_dir;
  double u_t_m_s = 0;
  WindowAverage slip;                 // <u_slip,y> / u_t over the sampling window
  double simulated_s = 0, wall_s = 0; // the whole run
  int ranks = 0;
  double core_seconds_per_simulated_second = 0;
};

/// Reads RUN_DIR/series.h5 and averages slip_velocity_y/u_t over [sampling_start_s, end] with
/// `batches` batch means; `ranks` is the number of ranks the run used (for the cost). InputError if the
/// series is missing or the window holds too few rows.
SlipSummary summarise_run(const std::string& run_dir, double u_t_m_s, double sampling_start_s, int ranks,
                          int batches = 10);

/// The comparison of a coarse run with a resolved reference.
struct Comparison {
  SlipSummary coarse, reference;
  double relative_error = 0;          // (coarse - reference) / reference
  double relative_error_stderr = 0;   // both runs' standard errors combined (independent runs)
};
Comparison compare(const SlipSummary& coarse, const SlipSummary& reference);

/// Text a researcher reads at the end of a run.
std::string describe(const SlipSummary& s);
std::string describe(const Comparison& c);

/// RUN_DIR/summary.h5 (cgd_format = "coarse_summary"): the numbers above as attributes, written
/// atomically by the calling rank alone.
void write_summary(const std::string& path, const Scene& scene, const SlipSummary& s,
                   const std::optional<Comparison>& comparison, const std::string& drag_description);

}  // namespace cgd::coarse
