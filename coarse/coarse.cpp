#include "coarse/coarse.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "core/error.hpp"
#include "core/h5.hpp"
#include "core/schema/coarse_summary.hpp"
#include "core/schema/filtered.hpp"
#include "core/schema/series.hpp"
#include "core/schema/snapshot.hpp"

namespace cgd::coarse {

namespace {
std::string num(double v, int precision = 4) {
  std::ostringstream o;
  o.precision(precision);
  o << v;
  return o.str();
}

/// The slip's time average over [start, the last row] with `batches` batch means into s.slip, and the drift
/// between the window's halves (each with max(2, batches/2) batch means) into s.drift, s.drift_stderr: what
/// summarise_run does with series rows and summarise_filtered with snapshots. std::invalid_argument from
/// window_average when the rows are too few.
void average_slip(const std::vector<double>& t, const std::vector<double>& slip, double start, int batches,
                  SlipSummary& s) {
  const double end = t.empty() ? start : t.back() * (1 + 1e-12) + 1e-300;  // the whole run after the start
  s.slip = window_average(t, slip, start, end, batches);
  const int half_batches = std::max(2, batches / 2);
  const double mid = 0.5 * (s.slip.start_s + s.slip.end_s);
  const WindowAverage first = window_average(t, slip, start, mid, half_batches);
  const WindowAverage second = window_average(t, slip, mid, end, half_batches);
  s.drift = second.mean - first.mean;
  s.drift_stderr = std::hypot(first.standard_error, second.standard_error);
}
}  // namespace

void check_coarse_scene(const Scene& s, int ranks) {
  const std::string& file = s.source_path;
  if (!s.solves_fluid())
    throw InputError(file + ": [fluid] with coupling \"two-way\" or \"one-way\" is required: cgd-coarse runs "
                            "coarse-grid CFD-DEM / CFD-DPM (a dry or quiescent scene is a cgd-generate job)");
  const DerivedScales& x = s.derived;
  double cell_min = 1e300;
  for (int a = 0; a < 3; ++a) cell_min = std::min(cell_min, s.domain.size_m[a] / x.cells[a]);
  if (x.parcel_diameter_m > cell_min * (1 + 1e-12))
    throw InputError(file + ": particles.parcel_size = " + num(s.particles.parcel_size) + " gives parcels of " +
                     num(x.parcel_diameter_m / s.particles.diameter_m) + " d_p, wider than a fluid cell (" +
                     num(cell_min / s.particles.diameter_m) +
                     " d_p): the point-parcel mapping of drag and void fraction no longer holds; allowed: "
                     "parcel_size <= cell/d_p (coarsen the grid or use smaller parcels)");
  if (x.particle_count < kMinimumParcels)
    throw InputError(file + ": the scene holds " + std::to_string(x.particle_count) + " parcels; at least " +
                     std::to_string(kMinimumParcels) +
                     " are needed for a domain slip with a few-per-cent statistical error (rule: N >= " +
                     std::to_string(kMinimumParcels) + "); use smaller parcels, a larger box or a higher solids fraction");
  // the particles' slabs along y start equal and are balanced at each list rebuild, none thinner than the cutoff
  // or, in a box too low for that, all equal (sim/dem/system.hpp): L_y / ranks must hold the cutoff
  const double slab = s.domain.size_m[1] / ranks;
  const double cutoff = x.parcel_diameter_m * (1.0 + s.contact.smallest_skin_over_dp());
  if (s.has_contacts() && slab < cutoff)
    throw InputError(file + ": with " + std::to_string(ranks) + " ranks the thinnest slab along y is " +
                     num(slab / s.particles.diameter_m) + " d_p, thinner than the contact cutoff " +
                     num(cutoff / s.particles.diameter_m) + " d_p (parcel diameter + skin): use at most " +
                     std::to_string(std::max(1, static_cast<int>(s.domain.size_m[1] / cutoff))) +
                     " ranks");
  if (!(s.run.sampling_start_s < s.run.end_time_s))
    throw InputError(file + ": run.sampling_start (" + num(s.run.sampling_start_s) + " s = " +
                     num(s.run.sampling_start_s / x.t_ref_s) + " t_ref; default 15 t_ref) must be before run.end_time (" +
                     num(s.run.end_time_s) + " s): the slip is averaged over the window in between");
}

SlipSummary summarise_run(const std::string& run_dir, double u_t, double start, int ranks, int batches) {
  const std::string path = (std::filesystem::path(run_dir) / "series.h5").string();
  const schema::Series series = schema::Series::read(path, MPI_COMM_SELF);
  const std::vector<double>& t = series.column("time");
  const std::vector<double>& slip3 = series.column("slip_velocity");
  const std::vector<double>& wall = series.column("wall_seconds");
  std::vector<double> slip(t.size());
  for (std::size_t i = 0; i < t.size(); ++i) slip[i] = slip3[3 * i + 1] / u_t;
  SlipSummary s;
  s.run_dir = run_dir;
  s.u_t_m_s = u_t;
  try {
    average_slip(t, slip, start, batches, s);
  } catch (const std::invalid_argument& e) {
    throw InputError(path + ": cannot average the slip: " + e.what());
  }
  s.simulated_s = t.empty() ? 0 : t.back();
  s.wall_s = wall.empty() ? 0 : wall.back();
  s.ranks = ranks;
  s.core_seconds_per_simulated_second = s.simulated_s > 0 ? s.wall_s * ranks / s.simulated_s : 0;
  return s;
}

SlipSummary summarise_reference(const std::string& run_dir, int batches) {
  const std::string scene_path = (std::filesystem::path(run_dir) / "scene.toml").string();
  if (!std::filesystem::exists(scene_path))
    throw InputError("--reference " + run_dir + ": no scene.toml there (expected a run directory of cgd-generate)");
  const Scene reference = load_scene(scene_path, {});
  return summarise_run(run_dir, reference.derived.u_t_m_s, reference.run.sampling_start_s, 1, batches);
}

SlipSummary summarise_filtered(const std::string& path, int batches, Scene* scene_out) {
  const schema::Filtered f = schema::read_filtered(path);
  if (f.run_paths.size() != 1)
    throw InputError(path + ": a filtered file of " + std::to_string(f.run_paths.size()) +
                     " runs; the slip of a resolved run needs the filtered file of that run alone (cgd-filter RUN_DIR)");
  const schema::FilteredGroup* whole = nullptr;
  for (const schema::FilteredGroup& g : f.groups)
    if (g.kind == schema::FilterKind::WholeBox) whole = &g;
  if (!whole || !whole->per_snapshot || whole->per_snapshot->slip.empty())
    throw InputError(path + ": /whole_box/per_snapshot/slip is missing (expected a filtered file of cgd-filter, which "
                            "always writes it)");
  const Scene scene = load_scene_from_string(f.scene_toml, path + " (its scene attribute)");
  if (!scene.fluid) throw InputError(path + ": the run's scene solved no fluid: it has no slip");
  const double u_t = scene.derived.u_t_m_s;
  if (f.snapshot_time_s.size() != f.snapshot_run_index.size())
    throw InputError(path + ": /snapshots/time_s is missing (a file of an older cgd-filter): filter the run again");
  const std::size_t n = f.snapshot_time_s.size(), bins = f.bins();
  const schema::FilteredGroup::PerSnapshot& ps = *whole->per_snapshot;
  std::vector<double> t(n), slip(n);
  for (std::size_t k = 0; k < n; ++k) {
    double sum = 0;
    std::int64_t count = 0;
    for (std::size_t b = 0; b < bins; ++b) {
      count += ps.count[k * bins + b];
      if (ps.count[k * bins + b] > 0) sum += ps.slip[k * bins + b];
    }
    if (count <= 0) throw InputError(path + ": snapshot " + std::to_string(k) + " of /whole_box/per_snapshot has no particle");
    t[k] = f.snapshot_time_s[k];
    slip[k] = sum / static_cast<double>(count) / u_t;
    if (k > 0 && !(t[k] > t[k - 1]))
      throw InputError(path + ": /snapshots/time_s is not increasing at row " + std::to_string(k));
  }
  SlipSummary s;
  s.run_dir = path;
  s.u_t_m_s = u_t;
  try {
    average_slip(t, slip, n ? t.front() : 0, batches, s);
  } catch (const std::invalid_argument& e) {
    throw InputError(path + ": cannot average the whole box's slip over its " + std::to_string(n) + " snapshots: " +
                     e.what() + " (fewer --batches)");
  }
  s.simulated_s = n ? t.back() : 0;
  s.wall_s = 0;  // the filtered file does not carry the run's wall time
  s.ranks = 1;
  s.core_seconds_per_simulated_second = 0;
  if (scene_out) *scene_out = scene;
  return s;
}

Comparison compare(const SlipSummary& coarse, const SlipSummary& reference) {
  Comparison c{coarse, reference, 0, 0};
  const double a = coarse.slip.mean, b = reference.slip.mean;
  c.relative_error = (a - b) / b;
  // error propagation of a/b - 1 with independent standard errors
  c.relative_error_stderr = std::abs(a / b) * std::hypot(coarse.slip.standard_error / a, reference.slip.standard_error / b);
  return c;
}

std::string describe(const SlipSummary& s) {
  std::ostringstream o;
  o << "slip <u_slip,y>/u_t = " << num(s.slip.mean) << " +- " << num(s.slip.standard_error, 2) << " (batch means, "
    << s.slip.batches << " batches over " << num(s.slip.start_s) << "-" << num(s.slip.end_s) << " s); ";
  if (s.wall_s > 0)
    o << "cost " << num(s.core_seconds_per_simulated_second) << " core-s per simulated s (" << s.ranks << " rank(s))";
  else
    o << "cost not known (no wall time: a filtered file's snapshots)";
  if (!s.stationary())
    o << "\nwarning: the window is not stationary: its second half averages " << num(s.drift, 3) << " +- "
      << num(s.drift_stderr, 2) << " u_t above its first (beyond " << SlipSummary::kDriftSigmas
      << " standard errors): the transient is not over; start sampling later (run.sampling_start_tref) or run longer";
  return o.str();
}

std::string describe(const Comparison& c) {
  std::ostringstream o;
  o << "reference " << c.reference.run_dir << ": " << num(c.reference.slip.mean) << " +- "
    << num(c.reference.slip.standard_error, 2) << "; relative error " << num(100 * c.relative_error, 3) << " % +- "
    << num(100 * c.relative_error_stderr, 2) << " %";
  return o.str();
}

void write_summary(const std::string& path, const Scene& scene, const SlipSummary& s,
                   const std::optional<Comparison>& cmp, const std::string& drag) {
  schema::CoarseSummary out;
  out.drag = drag;
  out.parcel_size = scene.particles.parcel_size;
  const auto& box = scene.domain.size_m;
  const auto& cells = scene.derived.cells;
  out.cell_over_dp = std::cbrt(box[0] * box[1] * box[2] / (1.0 * cells[0] * cells[1] * cells[2])) /
                     scene.particles.diameter_m;
  out.slip_over_ut = s.slip.mean;
  out.slip_stderr = s.slip.standard_error;
  out.window_start_s = s.slip.start_s;
  out.window_end_s = s.slip.end_s;
  out.batches = static_cast<std::int64_t>(s.slip.batches);
  out.drift_over_ut = s.drift;
  out.drift_stderr = s.drift_stderr;
  out.stationary = s.stationary();
  out.simulated_s = s.simulated_s;
  out.wall_s = s.wall_s;
  out.ranks = s.ranks;
  out.core_seconds_per_simulated_second = s.core_seconds_per_simulated_second;
  if (cmp) {
    const WindowAverage& ref = cmp->reference.slip;
    out.reference = schema::CoarseSummary::Reference{cmp->reference.run_dir, ref.mean,  ref.standard_error,
                                                     ref.start_s,            ref.end_s, cmp->relative_error,
                                                     cmp->relative_error_stderr};
  }
  schema::write_coarse_summary(path, scene, out);
}

}  // namespace cgd::coarse
