// The drag model file filled from a fit (the struct of core/schema/drag_model.hpp, written there;
// docs/schema-drag-model.md; read back by core/filtered_drag.cpp's load_drag_model) and the fit report.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "core/error.hpp"
#include "core/schema/drag_model.hpp"
#include "fit/fitter.hpp"

namespace cgd::fit {

namespace {

std::string format(const char* fmt, double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, x);
  return buf;
}

using schema::DragModelFile;

/// The model's root, curves and c_corr, as the evaluator holds them (DragModel) with their texts.
DragModelFile model_record(const DragModel& M, const std::string& model_form, const std::string& h_meaning,
                           const std::string& log_a_meaning) {
  DragModelFile m;
  m.system = M;
  m.model_form = model_form;
  m.u_t_convention = M.u_t_convention.empty() ? std::string(kUtConvention) : M.u_t_convention;
  m.width_exponent = M.width_exponent;
  m.calibration_operator = M.calibration_operator;
  m.curves = M.table ? schema::ModelCurves::Table : schema::ModelCurves::Splines;
  m.table_cells_across = M.table_cells_across;
  m.phi_crit = M.phi_crit;
  m.phi_max = M.h_spline.upper();
  m.h_max = M.h_max;
  m.log_a_min = M.log_a_min;
  m.log_a_max = M.log_a_max;
  m.h = {M.h_spline.order, M.h_spline.knots, M.h_spline.coefficients, h_meaning};
  m.log_a = {M.log_a_spline.order, M.log_a_spline.knots, M.log_a_spline.coefficients, log_a_meaning};
  m.c_corr = {M.c_corr_a, M.c_corr_k, M.c_corr_source, false, std::nullopt};
  return m;
}

/// /sources: the filtered files a model was made from, with their checksums.
void set_sources(DragModelFile& m, const std::vector<FilteredFile>& files) {
  for (const FilteredFile& ff : files) {
    if (!ff.pooled_paths.empty()) {  // pool_runs: the files it pooled
      m.sources_pooled = true;
      m.source_files.insert(m.source_files.end(), ff.pooled_paths.begin(), ff.pooled_paths.end());
      m.source_checksums.insert(m.source_checksums.end(), ff.pooled_checksums.begin(), ff.pooled_checksums.end());
      continue;
    }
    m.source_files.push_back(ff.path), m.source_checksums.push_back(ff.checksum);
  }
}

/// The Delta fitted (ascending, distinct) and, on grids, their cells across.
void set_calibration(DragModelFile& m, const FitResult& R, const std::vector<FilteredFile>& files, const FitOptions& o) {
  std::vector<double> delta;
  std::vector<std::int64_t> across;
  for (std::size_t i = 0; i < R.data_F.size(); ++i)
    if (R.data_fitted[i]) delta.push_back(R.model.l_char_m / R.data_F[i]);
  for (const FilteredFile& ff : files)
    for (const WidthSeries& w : ff.widths)
      if (w.grid && !(w.width_over_cell < o.min_width_over_cell - 1e-9)) across.push_back(w.cells_across);
  std::sort(delta.begin(), delta.end());
  delta.erase(std::unique(delta.begin(), delta.end(), [](double a, double b) { return std::abs(a - b) <= 1e-9 * a; }),
              delta.end());
  std::sort(across.begin(), across.end());
  across.erase(std::unique(across.begin(), across.end()), across.end());
  m.calibrated_delta_m = delta;
  for (double x : delta) m.calibrated_delta_over_dp.push_back(x / R.model.diameter_m);
  m.calibrated_cells_across = across;
}

DragModelFile::Bands bands_of(const FitResult& R, const FitOptions& o) {
  DragModelFile::Bands b;
  b.replicates = R.replicates;
  b.seed = static_cast<std::int64_t>(o.seed);
  b.confidence = 0.95;
  b.resampling = R.resampling;
  b.phi = R.band_phi, b.h = R.h, b.h_low = R.h_low, b.h_high = R.h_high;
  b.a = R.a, b.a_low = R.a_low, b.a_high = R.a_high, b.F = R.band_F;
  b.H = R.H, b.H_low = R.H_low, b.H_high = R.H_high;
  return b;
}

/// The per-bin estimates (the data points of the paper's Figure 1), NaN where a bin was not fitted.
DragModelFile::Bins bins_of(const FitResult& R) {
  DragModelFile::Bins out;
  for (const BinEstimate& b : R.bins) {
    const auto used = [&](double x) { return b.used ? x : NAN; };
    out.phi.push_back(b.phi);
    out.phi_center.push_back(b.phi_center);
    out.h.push_back(used(b.h));
    out.h_stderr.push_back(used(b.se_h));
    out.a.push_back(used(std::exp(b.log_a)));
    out.log_a_stderr.push_back(used(b.se_log_a));
    out.chi2.push_back(used(b.chi2));
    out.h_stderr_bootstrap.push_back(used(b.boot_se_h));
    out.log_a_stderr_bootstrap.push_back(used(b.boot_se_log_a));
    out.used.push_back(b.used ? 1 : 0);
    out.widths.push_back(b.widths);
    out.at_bound.push_back(b.used && b.at_bound ? 1 : 0);
    out.a_at_cap.push_back(b.used && b.a_at_cap ? 1 : 0);
  }
  return out;
}

DragModelFile::Diagnostics diagnostics_of(const FitResult& R, const FitOptions& o) {
  DragModelFile::Diagnostics d;
  d.min_count = o.min_count;
  d.min_widths = o.min_widths;
  d.min_width_over_cell = o.min_width_over_cell;
  d.breakpoints = R.breakpoints;
  d.lambda_h = R.lambda_h, d.lambda_log_a = R.lambda_log_a, d.edf_h = R.edf_h, d.edf_log_a = R.edf_log_a;
  d.chi2_per_dof = R.chi2_per_dof;
  d.width_exponent_grid = R.exponent_grid;  // step 0's profile (empty unless --width-exponent fit)
  d.width_exponent_chi2 = R.exponent_chi2;
  d.width_exponent_chi2_per_dof = R.exponent_chi2_per_dof;
  d.h_clamped_grid_points = R.h_clamped;
  d.cv_rms_H = R.cv_rms, d.cv_in_sample_rms_H = R.cv_in_sample_rms, d.wall_seconds = R.wall_seconds;
  for (const WidthResiduals& w : R.residuals) {
    d.residual_files.push_back(w.file);
    d.residual_groups.push_back(w.group);
    d.residual_F.push_back(w.F);
    d.residual_mean.push_back(w.mean);
    d.residual_mean_z.push_back(w.mean_z);
    d.residual_rms_z.push_back(w.rms_z);
    d.residual_mean_smoothed.push_back(w.mean_smoothed);
    d.residual_points.push_back(w.points);
  }
  for (const CrossValidationRun& c : R.cv_runs) {
    d.cv_files.push_back(c.file);
    d.cv_run.push_back(c.run);
    d.cv_rms.push_back(c.rms);
    d.cv_mean.push_back(c.mean);
    d.cv_points.push_back(c.points);
  }
  return d;
}

/// The curves of a grid's table (--grid-table, and the fallback /h of a --drift-table file): h the
/// piecewise-linear table H(phi) as an order-2 B-spline (knots = phi, coefficients = H), log a = -700 (a = 0:
/// no width dependence), h_max 0.99, phi_crit the first phi, the grid operator of the grid of `cells_across`, and
/// c_corr = 1 (a = 1, k = 0): the table is the grid's a-priori closure alone; what parcels miss is measured against
/// it, not folded into it.
DragModel grid_table_curves(const PhysicalSystem& physics, const std::vector<double>& phi, const std::vector<double>& H,
                            int cells_across) {
  DragModel M;
  static_cast<PhysicalSystem&>(M) = physics;
  M.h_spline.order = 2;
  M.h_spline.knots.push_back(phi.front());
  M.h_spline.knots.insert(M.h_spline.knots.end(), phi.begin(), phi.end());
  M.h_spline.knots.push_back(phi.back());
  M.h_spline.coefficients = H;
  M.log_a_spline = M.h_spline;
  M.log_a_spline.coefficients.assign(H.size(), -700.0);  // a = exp(-700) ~ 1e-304: 0 for any evaluator of the file
  M.h_max = 0.99;
  M.phi_crit = phi.front();
  M.width_exponent = 1.0;
  M.table_cells_across = cells_across;
  M.calibration_operator = CalibrationOperator::Grid;
  M.c_corr_a = 1.0, M.c_corr_k = 0.0, M.c_corr_source = "none";
  return M;
}

}  // namespace

void write_model_file(const std::string& path, const FitResult& R, const std::vector<FilteredFile>& files,
                      const FitOptions& o, const Scene& scene) {
  DragModelFile m = model_record(
      R.model,
      "beta_bar/beta_micro = c_corr(alpha) [1 - h(phi)/(1 + a(phi) F^n)], F = l_char_m / Delta, "
      "Delta = cube root of the fluid cell volume, n = width_exponent (Radl & Sundaresan 2014: n = 1)",
      "S_h(phi); h = clip(S_h(phi), 0, h_max) on [phi_crit, phi_max], h(phi_crit) phi/phi_crit below, "
      "h(phi_max) above",
      "S(phi) = log a(phi); a = exp(clip(S(clip(phi, phi_crit, phi_max)), log_a_min, log_a_max))");
  m.calibration_operator = o.calibration_operator;
  m.curves = schema::ModelCurves::Splines;
  m.width_exponent_fitted = o.fit_width_exponent;
  m.width_exponent_low = R.width_exponent_low;
  m.width_exponent_high = R.width_exponent_high;
  set_calibration(m, R, files, o);
  m.bands = bands_of(R, o);
  m.bins = bins_of(R);
  if (!R.data_F.empty())
    m.data = DragModelFile::Data{R.data_series, R.data_F, R.data_phi, R.data_H, R.data_sigma, R.data_fitted};
  m.diagnostics = diagnostics_of(R, o);
  set_sources(m, files);
  schema::write_drag_model(path, scene, m);
}

std::string write_grid_table_model(const std::string& path, const std::vector<FilteredFile>& files, int cells_across,
                                   std::int64_t min_count, const Scene& scene) {
  const std::string group = "/grids/" + std::to_string(cells_across);
  const FilteredFile& first = files.front();
  const std::size_t nb = first.bins();
  std::vector<double> num(nb, 0.0), mic(nb, 0.0), count(nb, 0.0), phi_sum(nb, 0.0);
  double cell_over_dp = 0;
  for (const FilteredFile& f : files) {
    const WidthSeries* g = nullptr;
    for (const WidthSeries& w : f.grids)
      if (w.cells_across == cells_across) g = &w;
    if (!g)
      throw InputError(f.path + ": --grid-table " + std::to_string(cells_across) + ": the file has no " + group +
                       " (filter the runs with cgd-filter --grids " + std::to_string(cells_across) + ")");
    if (!f.has_per_snapshot)
      throw InputError(f.path + ": --grid-table needs the per-snapshot sums (" + group + "/per_snapshot)");
    if (cell_over_dp == 0) cell_over_dp = g->cell_size_over_dp;
    if (std::abs(g->cell_size_over_dp - cell_over_dp) > 1e-6 * cell_over_dp)
      throw InputError(f.path + ": " + group + " has cells of " + format("%.6g", g->cell_size_over_dp) + " d_p, " +
                       first.path + " of " + format("%.6g", cell_over_dp) + " d_p: a table is for one grid");
    for (std::size_t k = 0; k < f.snapshots(); ++k)
      for (std::size_t b = 0; b < nb; ++b) {
        num[b] += g->numerator[k * nb + b];
        mic[b] += g->micro[k * nb + b];
      }
    for (std::size_t b = 0; b < nb; ++b)
      if (g->count[b] > 0 && std::isfinite(g->phi_mean[b])) {
        count[b] += static_cast<double>(g->count[b]);
        phi_sum[b] += static_cast<double>(g->count[b]) * g->phi_mean[b];
      }
  }
  std::vector<double> phi, H, n;
  for (std::size_t b = 0; b < nb; ++b)
    if (count[b] >= static_cast<double>(min_count) && mic[b] != 0.0) {
      phi.push_back(phi_sum[b] / count[b]);
      H.push_back(1.0 - num[b] / mic[b]);
      n.push_back(count[b]);
    }
  if (phi.size() < 2)
    throw InputError(first.path + ": --grid-table " + std::to_string(cells_across) + ": " + std::to_string(phi.size()) +
                     " bin(s) of " + group + " have >= " + std::to_string(min_count) +
                     " samples; a table needs at least 2 (lower --min-count or filter longer runs)");
  DragModel M = grid_table_curves(first.physics, phi, H, cells_across);
  const double delta = cell_over_dp * M.diameter_m;
  M.table = true;
  DragModelFile m = model_record(
      M,
      "beta_bar/beta_micro = c_corr(alpha) [1 - H_grid(phi)], H_grid the a-priori filtered drag "
      "correction of one coarse grid (curves = table): piecewise linear in phi through the table, "
      "constant outside it, clamped to [-1, h_max]; no width dependence (a = 0)",
      "H_grid(phi): order-2 B-spline = the piecewise-linear table (knots = the bins' mean phi, "
      "coefficients = H_grid); clamped to [-1, h_max], constant outside the knots",
      "log a = -700: a = 0 (the table has no width dependence)");
  m.calibrated_delta_m = {delta};
  m.calibrated_delta_over_dp = {cell_over_dp};
  m.calibrated_cells_across = {cells_across};
  m.table = DragModelFile::Table{phi, H, n, group, min_count};
  set_sources(m, files);
  schema::write_drag_model(path, scene, m);
  std::ostringstream out;
  out << "cgd-fit --grid-table " << cells_across << ": the a-priori H_grid of the grid of " << cells_across
      << " cells across (cell " << format("%.4g", cell_over_dp) << " d_p) as a table model (curves = table, a = 0), "
      << phi.size() << " bins with >= " << min_count << " samples, pooled over " << files.size() << " file(s)\n"
      << "    phi     H_grid   samples\n";
  for (std::size_t i = 0; i < phi.size(); ++i)
    out << format("  %6.4f", phi[i]) << format("  %8.4f", H[i]) << format("  %8.0f", n[i]) << "\n";
  return out.str();
}

std::string write_drift_table_model(const std::string& path, const std::vector<FilteredFile>& files, int cells_across,
                                    std::int64_t min_count, double min_alignment, const Scene& scene) {
  const std::string group = "/grids/" + std::to_string(cells_across);
  const FilteredFile& first = files.front();
  const std::size_t nb = first.bins();
  if (first.slip_edges.size() < 2)
    throw InputError(first.path + ": --drift-table needs the drift sums (" + group + "/drift and /bins/slip_edges of "
                     "cgd-filter --grids " + std::to_string(cells_across) + "); the file has none: filter the runs again "
                     "with this build");
  const std::size_t ns = first.slip_edges.size() - 1, cells = nb * ns;
  std::vector<double> num(nb, 0.0), mic(nb, 0.0), count(nb, 0.0);
  std::vector<double> dnum(cells, 0.0), dden(cells, 0.0), dmag(cells, 0.0);
  std::vector<std::int64_t> dcount(cells, 0);
  double cell_over_dp = 0;
  for (const FilteredFile& f : files) {
    const WidthSeries* g = nullptr;
    for (const WidthSeries& w : f.grids)
      if (w.cells_across == cells_across) g = &w;
    if (!g)
      throw InputError(f.path + ": --drift-table " + std::to_string(cells_across) + ": the file has no " + group +
                       " (filter the runs with cgd-filter --grids " + std::to_string(cells_across) + ")");
    if (!g->drift)
      throw InputError(f.path + ": --drift-table " + std::to_string(cells_across) + ": " + group + " has no drift sums (" +
                       group + "/drift): filter the runs again with this build's cgd-filter --grids");
    if (!f.has_per_snapshot)
      throw InputError(f.path + ": --drift-table needs the per-snapshot sums (" + group + "/per_snapshot) for the rows' "
                       "phi-only H_grid");
    auto same = [](double a, double b) { return std::abs(a - b) <= 1e-9 * std::max(1.0, std::max(std::abs(a), std::abs(b))); };
    if (f.slip_edges.size() != first.slip_edges.size() ||
        !std::equal(f.slip_edges.begin(), f.slip_edges.end(), first.slip_edges.begin(), same))
      throw InputError(f.path + " and " + first.path + " have different slip bins (/bins/slip_edges); filter the runs "
                       "with the same --slip-bins to pool them");
    if (cell_over_dp == 0) cell_over_dp = g->cell_size_over_dp;
    if (std::abs(g->cell_size_over_dp - cell_over_dp) > 1e-6 * cell_over_dp)
      throw InputError(f.path + ": " + group + " has cells of " + format("%.6g", g->cell_size_over_dp) + " d_p, " +
                       first.path + " of " + format("%.6g", cell_over_dp) + " d_p: a table is for one grid");
    for (std::size_t k = 0; k < f.snapshots(); ++k)
      for (std::size_t b = 0; b < nb; ++b) {
        num[b] += g->numerator[k * nb + b];
        mic[b] += g->micro[k * nb + b];
      }
    for (std::size_t b = 0; b < nb; ++b) count[b] += static_cast<double>(g->count[b]);
    for (std::size_t c = 0; c < cells; ++c) {
      dcount[c] += g->drift->count[c];
      dnum[c] += g->drift->numerator[c];
      dden[c] += g->drift->denominator[c];
      dmag[c] += g->drift->magnitude[c];
    }
  }
  auto measured = [&](std::size_t c) {
    return dcount[c] >= min_count && dden[c] != 0.0 && std::abs(dden[c]) >= min_alignment * dmag[c];
  };
  // rows: the phi bins of the phi-only table; columns: the slip bins from the first to the last measured one
  std::vector<std::size_t> rows;
  for (std::size_t b = 0; b < nb; ++b)
    if (count[b] >= static_cast<double>(min_count) && mic[b] != 0.0) rows.push_back(b);
  std::size_t m_lo = ns, m_hi = 0;
  for (std::size_t b : rows)
    for (std::size_t m = 0; m < ns; ++m)
      if (measured(b * ns + m)) m_lo = std::min(m_lo, m), m_hi = std::max(m_hi, m);
  if (rows.size() < 2)
    throw InputError(first.path + ": --drift-table " + std::to_string(cells_across) + ": " + std::to_string(rows.size()) +
                     " phi bin(s) of " + group + " have >= " + std::to_string(min_count) +
                     " samples; a table needs at least 2 (lower --min-count or filter longer runs)");
  if (m_lo > m_hi)
    throw InputError(first.path + ": --drift-table " + std::to_string(cells_across) + ": no (phi, slip) bin of " + group +
                     "/drift has >= " + std::to_string(min_count) + " samples and |denominator| >= " +
                     format("%.3g", min_alignment) + " x magnitude (lower --min-count or --drift-min-alignment)");
  DragModelFile::DriftTable t;
  const double phi_w = first.phi_edges[1] - first.phi_edges[0], slip_w = first.slip_edges[1] - first.slip_edges[0];
  for (std::size_t b : rows) t.phi.push_back(0.5 * (first.phi_edges[b] + first.phi_edges[b + 1]));
  for (std::size_t m = m_lo; m <= m_hi; ++m) t.slip.push_back(0.5 * (first.slip_edges[m] + first.slip_edges[m + 1]));
  const std::size_t nc = t.slip.size();
  std::size_t n_measured = 0, n_nearest = 0, n_phi_only = 0;
  std::size_t n_beyond = 0;
  for (std::size_t b : rows) {
    const double phi_only = 1.0 - num[b] / mic[b];
    t.phi_only_H.push_back(phi_only);
    std::size_t m_last = ns;  // the row's last measured slip bin (ns: none)
    for (std::size_t m = 0; m < ns; ++m)
      if (measured(b * ns + m)) m_last = m;
    for (std::size_t j = 0; j < nc; ++j) {
      const std::size_t m = m_lo + j, c = b * ns + m;
      double H = phi_only;
      std::int64_t filled = 2;
      if (measured(c)) {
        H = dnum[c] / dden[c], filled = 0;
      } else if (m_last < ns && m > m_last) {
        // faster than any measured cell of the row: no more reduction than the phi-only H of the row. H falls with
        // the slip where it is measured; holding the last measured (slow-cell) H out to every slip gave the dense
        // rows H ~ 1 at any slip, and a coarse run's cluster that reached them fell freely (slip 7.5 u_t;
        // docs/closure.md "The drift-velocity closure")
        const std::size_t cl = b * ns + m_last;
        H = std::min(dnum[cl] / dden[cl], phi_only), filled = 3;
        ++n_beyond;
      } else {  // the nearest measured slip bin of the row (the lower one on a tie)
        for (std::size_t dist = 1; dist < ns && filled == 2; ++dist) {
          if (m >= dist && measured(c - dist)) H = dnum[c - dist] / dden[c - dist], filled = 1;
          else if (m + dist < ns && measured(c + dist)) H = dnum[c + dist] / dden[c + dist], filled = 1;
        }
      }
      if (filled < 3) (filled == 0 ? n_measured : filled == 1 ? n_nearest : n_phi_only) += 1;
      t.H.push_back(H);
      t.filled.push_back(filled);
      t.count.push_back(dcount[c]);
      t.numerator.push_back(dnum[c]);
      t.denominator.push_back(dden[c]);
      t.magnitude.push_back(dmag[c]);
    }
  }
  t.source_group = group + "/drift";
  t.min_count = min_count;
  t.min_alignment = min_alignment;
  t.phi_bin_width = phi_w;
  t.slip_bin_width = slip_w;
  t.fill_rule =
      "H = numerator/denominator where count >= min_count and |denominator| >= min_alignment x magnitude (filled = 0); "
      "beyond the row's last such slip bin: the smaller of its H and the row's phi-only H_grid (filled = 3); "
      "else the H of the nearest such slip bin of the same phi row, the lower on a tie (filled = 1); a row with none: "
      "the row's phi-only H_grid = 1 - sum N / sum M of " + group + " (filled = 2). Rows: the phi bins with >= min_count "
      "samples of " + group + "; columns: the slip bins from the first to the last measured one";

  // /h: the rows' phi-only H_grid (the fallback of the table, not used by the law)
  DragModel M = grid_table_curves(first.physics, t.phi, t.phi_only_H, cells_across);
  const double delta = cell_over_dp * M.diameter_m;
  DragModelFile m = model_record(
      M,
      "drift-velocity closure (fluid.drag = \"drift\"): F_i = V_i beta_micro(phi_i, |u_i - v_i|) [(u_i - v_i) - "
      "H(phi_i, s_i) s~_i], s~_i = u_i - vbar_i the cell slip (vbar the TSC cell-mean particle velocity, interpolated), "
      "s_i = |s~_i|/u_t; H of /drift_table, bilinear on its bin centres, constant outside, clamped to [-1, h_max]",
      "the rows' phi-only H_grid (order-2 B-spline through /drift_table/phi_only_H): the table's fallback, not used "
      "by the law",
      "log a = -700: a = 0 (the table has no width dependence)");
  m.curves = schema::ModelCurves::DriftTable;
  m.calibrated_delta_m = {delta};
  m.calibrated_delta_over_dp = {cell_over_dp};
  m.calibrated_cells_across = {cells_across};
  m.drift_table = t;
  set_sources(m, files);
  schema::write_drag_model(path, scene, m);

  std::ostringstream out;
  out << "cgd-fit --drift-table " << cells_across << ": the drift-velocity closure's H(phi, cell slip) of the grid of "
      << cells_across << " cells across (cell " << format("%.4g", cell_over_dp) << " d_p), pooled over " << files.size()
      << " file(s): " << t.phi.size() << " phi rows x " << nc << " slip columns (" << format("%.3g", t.slip.front())
      << " to " << format("%.3g", t.slip.back()) << " u_t); " << n_measured << " bins measured (>= " << min_count
      << " samples, |denominator| >= " << format("%.3g", min_alignment) << " x magnitude), " << n_nearest
      << " filled from the nearest slip bin, " << n_beyond << " beyond the row's measured slips (min of the last "
      << "measured H and the row's phi-only H_grid), " << n_phi_only << " from the row's phi-only H_grid\n"
      << "  H (phi rows, slip columns in u_t; * = filled)\n      phi  phi-only";
  for (double x : t.slip) out << format(" %6.2f ", x);
  out << "\n";
  for (std::size_t i = 0; i < t.phi.size(); ++i) {
    out << format("  %7.4f", t.phi[i]) << format("  %7.3f ", t.phi_only_H[i]);
    for (std::size_t j = 0; j < nc; ++j)
      out << format(" %6.3f", t.H[i * nc + j]) << (t.filled[i * nc + j] ? "*" : " ");
    out << "\n";
  }
  return out.str();
}

std::string fit_report(const FitResult& R, const std::vector<FilteredFile>& files, const FitOptions& o) {
  std::ostringstream out;
  const SplineCurves curves{&R.model};
  const Radl2014Curves radl;
  const bool n1 = R.model.width_exponent == 1.0;
  const std::string form = n1 ? "1/(1 + aF)" : "1/(1 + aF^n)";
  out << "cgd-fit: H(F, phi) = h(phi)/(1 + a(phi) F" << (n1 ? "" : "^n") << "), F = L_char/Delta";
  out << (o.calibration_operator == CalibrationOperator::Grid ? " (operator grid: H_grid of the coarse grids, Delta = cell size)"
                                           : " (operator box: box filters of width Delta)");
  if (!n1 || o.fit_width_exponent) out << ", n = " << format("%.3f", R.model.width_exponent);
  out << "; " << files.size()
      << " filtered file(s), base law " << to_string(R.model.micro_drag)
      << ", L_char = " << format("%.4g", R.model.l_char_m) << " m\n";
  int used = 0, dropped = 0;
  for (const BinEstimate& b : R.bins) (b.used ? used : dropped)++;
  out << "bins: " << used << " fitted, " << dropped << " dropped (a bin needs >= " << o.min_count
      << " samples at a width for that width to count, and >= " << o.min_widths
      << " such widths of >= " << o.min_width_over_cell << " cells; bins below phi_crit = " << o.phi_crit
      << " are not fitted)\n";
  // dropped bins, consecutive bins with the same reason on one line
  for (std::size_t i = 0; i < R.bins.size();) {
    if (R.bins[i].used) {
      ++i;
      continue;
    }
    std::size_t j = i;
    while (j + 1 < R.bins.size() && !R.bins[j + 1].used && R.bins[j + 1].dropped == R.bins[i].dropped) ++j;
    out << "  dropped phi " << format("%.3f", R.bins[i].phi_center);
    if (j > i) out << " .. " << format("%.3f", R.bins[j].phi_center) << " (" << j - i + 1 << " bins)";
    out << ": " << R.bins[i].dropped << "\n";
    i = j + 1;
  }
  if (o.fit_width_exponent) {
    out << "width exponent: n = " << format("%.3f", R.width_exponent) << " [" << format("%.3f", R.width_exponent_low)
        << ", " << format("%.3f", R.width_exponent_high)
        << "] (95 %, profile of the pooled chi2 of the per-bin fits, scaled by chi2/dof = "
        << format("%.2f", R.exponent_chi2_per_dof) << "; Radl 2014: n = 1)";
    if (R.width_exponent_at_bound)
      out << "  WARNING: the minimum or an end of its interval is at the end of the searched range [0.25, 6] "
             "(the interval is open there)";
    out << "\n  chi2 profile:";
    for (std::size_t i = 0; i < R.exponent_grid.size(); ++i) {
      const double n = R.exponent_grid[i];
      if (std::abs(n - 1.0) < 1e-9 || std::abs(n - R.width_exponent) < 1e-9 ||
          std::abs(std::remainder(n, 0.5)) < 1e-9)
        out << "  n=" << format("%.3g", n) << ": " << format("%.4g", R.exponent_chi2[i]);
    }
    out << "\n";
  }
  if (o.fit_width_exponent) {
    for (std::size_t i = 0; i < R.exponent_grid.size(); ++i)
      if (std::abs(R.exponent_grid[i] - 1.0) < 1e-9 && std::isfinite(R.exponent_chi2_per_dof)) {
        const std::size_t best = static_cast<std::size_t>(
            std::min_element(R.exponent_chi2.begin(), R.exponent_chi2.end()) - R.exponent_chi2.begin());
        const double dof = R.exponent_chi2[best] / R.exponent_chi2_per_dof;
        out << "  chi2/dof at n = 1: " << format("%.3f", R.exponent_chi2[i] / dof) << " against "
            << format("%.3f", R.exponent_chi2_per_dof) << " at n = " << format("%.3f", R.width_exponent)
            << " (the same bins)\n";
      }
  }
  {
    int capped = 0;
    for (const BinEstimate& b : R.bins) capped += b.used && b.a_at_cap;
    if (capped > 0)
      out << "low phi: " << capped << " bin(s) with a at its identifiability bound a F^n <= 10 at the widest width "
          << "(only h/a is seen beyond it; docs/fit.md \"Low phi\")\n";
  }
  out << "per-bin fits: chi2/dof = " << format("%.2f", R.chi2_per_dof)
      << " (about 1 when " << form << " describes the width dependence within the filter's intervals)\n";
  out << "splines: " << R.breakpoints << " breakpoints, GCV smoothing: edf(h) = " << format("%.1f", R.edf_h)
      << ", edf(log a) = " << format("%.1f", R.edf_log_a) << "; h clamped at " << R.h_clamped
      << " grid points\n";
  out << "bands: " << R.replicates << " bootstrap replicates over " << R.resampling
      << ", 95 % percentile, widened by the splines' smoothing-bias allowance";
  if (R.replicates_skipped > 0)
    out << " (" << R.replicates_skipped << " replicates with < 4 fittable bins skipped)";
  out << "\n\n";
  out << "   phi   h fit [95% band]         h Radl2014   a fit [95% band]         a Radl2014\n";
  for (double phi : {0.01, 0.02, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45, 0.5}) {
    if (phi > R.band_phi.back() + 1e-12) break;
    // nearest band grid point
    std::size_t i = 0;
    for (std::size_t k = 0; k < R.band_phi.size(); ++k)
      if (std::abs(R.band_phi[k] - phi) < std::abs(R.band_phi[i] - phi)) i = k;
    out << format("%6.3f", phi) << format("  %6.3f", curves.h(phi)) << format(" [%6.3f,", R.h_low[i])
        << format("%6.3f]", R.h_high[i]) << format("     %6.3f", radl.h(phi))
        << format("     %7.3f", curves.a(phi)) << format(" [%7.3f,", R.a_low[i])
        << format("%7.3f]", R.a_high[i]) << format("   %7.3f", radl.a(phi)) << "\n";
  }
  if (!n1)
    out << "(a multiplies F^n, n = " << format("%.3f", R.model.width_exponent)
        << "; Radl 2014's a multiplies F: compare H(F, phi), not a)\n";
  out << "\nresiduals per width (H - h_bin/(1 + a_bin F" << (n1 ? "" : "^n") << "), per-bin fits; z = residual/sigma):\n";
  out << "  file : group          F     points  mean      mean z   rms z   mean (smoothed model)\n";
  for (const WidthResiduals& w : R.residuals)
    out << "  " << w.file << " : " << w.group << format("  %7.4f", w.F) << format("  %4.0f", double(w.points))
        << format("  %+8.4f", w.mean) << format("  %+6.2f", w.mean_z) << format("  %6.2f", w.rms_z)
        << format("  %+8.4f", w.mean_smoothed)
        << (w.whole_box ? "   (whole box: smoothed model, not fitted)"
            : !w.fitted ? "   (narrow: smoothed model, not fitted)"
                        : "")
        << "\n";
  out << "  (a trend of mean z with F would mean " << form << " is biased at the smallest or largest widths)\n";
  if (R.cv_runs.empty()) {
    out << "\nleave-one-run-out cross-validation: not possible (one run)\n";
  } else {
    out << "\nleave-one-run-out cross-validation of H: rms " << format("%.4f", R.cv_rms)
        << " (in-sample rms on the same points " << format("%.4f", R.cv_in_sample_rms) << ")\n";
    for (const CrossValidationRun& c : R.cv_runs)
      out << "  " << c.file << " run " << c.run << (c.run_path.empty() ? "" : " (" + c.run_path + ")") << ": " << c.points << " points, rms "
          << format("%.4f", c.rms) << ", mean " << format("%+.4f", c.mean) << "\n";
  }
  out << "\nrange: splines on [phi_crit, phi_max] = [" << R.model.phi_crit << ", "
      << format("%.3f", R.model.h_spline.upper())
      << "]; below phi_crit h -> 0 linearly and a is constant; above phi_max both are held constant "
         "(extrapolation: "
         "check the coarse runs' phi)\n";
  out << "c_corr: a = " << R.model.c_corr_a << ", k = " << R.model.c_corr_k << " (" << R.model.c_corr_source
      << " values, until the parcel fit of the coarse stage replaces them)\n";
  out << "fit wall time: " << format("%.2f", R.wall_seconds) << " s\n";
  return out.str();
}

}  // namespace cgd::fit
