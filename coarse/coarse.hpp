#pragma once
// cgd-coarse's library: the checks a coarse-grid CFD-DEM / CFD-DPM (parcel) scene must pass before it
// runs, and the slip summary of a run (the paper's Figures 2 and 3: the time-averaged domain slip
// <u_slip,y>/u_t over the sampling window, its batch-means standard error, the relative error against a
// resolved reference run and the cost in core-seconds per simulated second).
#include <mpi.h>

#include <cmath>
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
  // Stationarity of the window: the mean of its second half minus that of its first (each half with
  // batches/2 batch means) and the standard error of that difference. A coarse grid seeds its
  // clustering instability from little noise (many particles per cell), so the homogeneous state can
  // last tens of t_ref and the slip then climbs: a drift beyond kDriftSigmas standard errors says the
  // window still holds the transient (start sampling later, run longer).
  double drift = 0, drift_stderr = 0;
  bool stationary() const { return std::abs(drift) <= kDriftSigmas * drift_stderr; }
  static constexpr double kDriftSigmas = 3.0;
  double simulated_s = 0, wall_s = 0; // the whole run
  int ranks = 0;
  double core_seconds_per_simulated_second = 0;
};

/// Reads RUN_DIR/series.h5 and averages slip_velocity_y/u_t over [sampling_start_s, end] with
/// `batches` batch means; `ranks` is the number of ranks the run used (for the cost). InputError if the
/// series is missing or the window holds too few rows.
SlipSummary summarise_run(const std::string& run_dir, double u_t_m_s, double sampling_start_s, int ranks,
                          int batches = 10);

/// The resolved reference's summary over its own sampling window: the same definition (from the
/// reference scene's run.sampling_start, default 15 t_ref, to the end of its run) with the reference's
/// own scene (RUN_DIR/scene.toml) and u_t, so that a coarse run may sample later and longer than the
/// resolved run it is compared with. InputError if the scene or the series cannot be read.
SlipSummary summarise_reference(const std::string& run_dir, int batches = 10);

/// The slip of a resolved run from its filtered file (cgd-filter of that one run; the files shipped in
/// data/filtered/): at each snapshot of the filter's window the whole box's mean filtered slip,
/// Σ_i ū_slip,i,y / N with ū = ⟨εu⟩/⟨ε⟩ for every particle (`/whole_box/per_snapshot`, docs/filter.md), over u_t
/// of the file's scene, averaged over those snapshots as summarise_run averages series rows (batch means, the
/// drift of the halves). The series' slip_velocity is the same average taken with the face velocities at every
/// fluid step; the shipped runs' two agree within 0.002 u_t (docs/coarse.md). The cost is unknown there:
/// wall_s = 0, ranks = 1, simulated_s the last snapshot's time. InputError if the file is not a filtered file of
/// one run with the whole box's per-snapshot sums and the snapshots' times, or its window holds too few snapshots
/// for the batch means (2 per batch over the window and over each half: 4 max(2, batches/2) at least).
/// `scene_out`: where given, the file's scene (for write_summary).
SlipSummary summarise_filtered(const std::string& path, int batches = 10, Scene* scene_out = nullptr);

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
