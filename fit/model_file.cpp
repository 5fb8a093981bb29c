// The drag model file (docs/schema-drag-model.md; read back by core/filtered_drag.cpp's
// load_drag_model) and the fit report.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "core/error.hpp"
#include "core/output.hpp"
#include "fit/fitter.hpp"

namespace cgd::fit {

namespace {

std::string format(const char* fmt, double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, x);
  return buf;
}

void write_vector(h5::File& f, const std::string& name, const std::vector<double>& v) {
  f.write_replicated(name, v, {static_cast<std::uint64_t>(v.size())});
}

/// /c_corr: c_corr = a + (1 - a) exp(-k (alpha - 1)), not fitted here (the parcel fit writes its own copy).
void write_c_corr(h5::File& f, double a, double k, const std::string& source) {
  f.create_group("/c_corr");
  f.set_attr("/c_corr", "a", a);
  f.set_attr("/c_corr", "k", k);
  f.set_attr("/c_corr", "source", source);
  f.set_attr("/c_corr", "fitted", std::int64_t{0});
  f.set_attr("/c_corr", "formula", std::string("c_corr = a + (1 - a) exp(-k (alpha - 1))"));
}

/// /sources: the filtered files a model was made from, with their checksums.
void write_sources(h5::File& f, const std::vector<FilteredFile>& files) {
  f.create_group("/sources");
  std::vector<std::string> paths, sums;
  for (const FilteredFile& ff : files) paths.push_back(ff.path), sums.push_back(ff.checksum);
  f.set_attr("/sources", "files", paths);
  f.set_attr("/sources", "checksums", sums);
  f.set_attr("/sources", "checksum_kind", std::string("FNV-1a 64-bit of the file's bytes, hex"));
}

void write_spline(h5::File& f, const std::string& group, const BSpline& s, const std::string& meaning) {
  f.create_group(group);
  f.set_attr(group, "order", static_cast<std::int64_t>(s.order));
  f.set_attr(group, "meaning", meaning);
  write_vector(f, group + "/knots", s.knots);
  write_vector(f, group + "/coefficients", s.coefficients);
}

}  // namespace

void write_model_file(const std::string& path, const FitResult& R, const std::vector<FilteredFile>& files,
                      const FitOptions& o, const Scene& scene) {
  const DragModel& M = R.model;
  h5::write_atomically(path, MPI_COMM_SELF, [&](h5::File& f) {
    schema::write_common(f, schema::kDragModel, scene);
    f.set_attr(
        "/", "model_form",
        std::string("beta_bar/beta_micro = c_corr(alpha) [1 - h(phi)/(1 + a(phi) F^n)], F = l_char_m / Delta, "
                    "Delta = cube root of the fluid cell volume, n = width_exponent (Radl & Sundaresan 2014: n = 1)"));
    f.set_attr("/", "width_exponent", M.width_exponent);
    f.set_attr("/", "width_exponent_fitted", std::int64_t{o.fit_width_exponent ? 1 : 0});
    if (o.fit_width_exponent) {
      f.set_attr("/", "width_exponent_low", R.width_exponent_low);
      f.set_attr("/", "width_exponent_high", R.width_exponent_high);
    }
    // the calibration: the operator the H data came from and the Delta fitted
    {
      const bool grid = o.calibration_operator == CalibrationOperator::TscGrid;
      f.set_attr("/", "operator", std::string(names_of(o.calibration_operator).model_file));
      if (grid) f.set_attr("/", "kernel", std::string("tsc"));
      f.set_attr("/", "curves", std::string("splines"));
      std::vector<double> delta;
      std::vector<std::int64_t> across;
      for (std::size_t i = 0; i < R.data_F.size(); ++i)
        if (R.data_fitted[i]) delta.push_back(M.l_char_m / R.data_F[i]);
      for (const FilteredFile& ff : files)
        for (const WidthSeries& w : ff.widths)
          if (w.grid && !(w.width_over_cell < o.min_width_over_cell - 1e-9)) across.push_back(w.cells_across);
      std::sort(delta.begin(), delta.end());
      delta.erase(std::unique(delta.begin(), delta.end(), [](double a, double b) { return std::abs(a - b) <= 1e-9 * a; }),
                  delta.end());
      std::sort(across.begin(), across.end());
      across.erase(std::unique(across.begin(), across.end()), across.end());
      std::vector<double> over_dp;
      for (double x : delta) over_dp.push_back(x / M.diameter_m);
      if (!delta.empty()) {
        f.set_attr("/", "calibrated_delta_m", delta);
        f.set_attr("/", "calibrated_delta_over_dp", over_dp);
      }
      if (grid && !across.empty()) f.set_attr("/", "calibrated_cells_across", across);
    }
    write_physical_system(f, M, "base_drag");
    f.set_attr("/", "u_t_convention", M.u_t_convention);
    f.set_attr("/", "phi_crit", M.phi_crit);
    f.set_attr("/", "phi_max", M.h_spline.upper());
    f.set_attr("/", "h_max", M.h_max);
    f.set_attr("/", "log_a_min", M.log_a_min);
    f.set_attr("/", "log_a_max", M.log_a_max);
    write_spline(
        f, "/h", M.h_spline,
        "S_h(phi); h = clip(S_h(phi), 0, h_max) on [phi_crit, phi_max], h(phi_crit) phi/phi_crit below, "
        "h(phi_max) above");
    write_spline(f, "/log_a", M.log_a_spline,
                 "S(phi) = log a(phi); a = exp(clip(S(clip(phi, phi_crit, phi_max)), log_a_min, log_a_max))");
    write_c_corr(f, M.c_corr_a, M.c_corr_k, M.c_corr_source);

    // bands
    f.create_group("/bands");
    f.set_attr("/bands", "replicates", static_cast<std::int64_t>(R.replicates));
    f.set_attr("/bands", "seed", static_cast<std::int64_t>(o.seed));
    f.set_attr("/bands", "confidence", 0.95);
    f.set_attr("/bands", "resampling", R.resampling);
    for (const auto& [name, v] : {std::pair<const char*, const std::vector<double>*>{"phi", &R.band_phi},
                                  {"h", &R.h},
                                  {"h_low", &R.h_low},
                                  {"h_high", &R.h_high},
                                  {"a", &R.a},
                                  {"a_low", &R.a_low},
                                  {"a_high", &R.a_high},
                                  {"F", &R.band_F}})
      write_vector(f, std::string("/bands/") + name, *v);
    const std::vector<std::uint64_t> dims{R.band_F.size(), R.band_phi.size()};
    f.write_replicated("/bands/H", R.H, dims);
    f.write_replicated("/bands/H_low", R.H_low, dims);
    f.write_replicated("/bands/H_high", R.H_high, dims);

    // per-bin estimates (the data points of the paper's Figure 1)
    f.create_group("/bins");
    std::vector<double> phi, center, h, se_h, a, se_log_a, chi2, boot_se_h, boot_se_log_a;
    std::vector<std::int64_t> used, widths, at_bound, a_at_cap;
    for (const BinEstimate& b : R.bins) {
      phi.push_back(b.phi);
      center.push_back(b.phi_center);
      h.push_back(b.used ? b.h : NAN);
      se_h.push_back(b.used ? b.se_h : NAN);
      a.push_back(b.used ? std::exp(b.log_a) : NAN);
      se_log_a.push_back(b.used ? b.se_log_a : NAN);
      chi2.push_back(b.used ? b.chi2 : NAN);
      boot_se_h.push_back(b.used ? b.boot_se_h : NAN);
      boot_se_log_a.push_back(b.used ? b.boot_se_log_a : NAN);
      used.push_back(b.used ? 1 : 0);
      widths.push_back(b.widths);
      at_bound.push_back(b.used && b.at_bound ? 1 : 0);
      a_at_cap.push_back(b.used && b.a_at_cap ? 1 : 0);
    }
    for (const auto& [name, v] : {std::pair<const char*, const std::vector<double>*>{"phi", &phi},
                                  {"phi_center", &center},
                                  {"h", &h},
                                  {"h_stderr", &se_h},
                                  {"a", &a},
                                  {"log_a_stderr", &se_log_a},
                                  {"chi2", &chi2},
                                  {"h_stderr_bootstrap", &boot_se_h},
                                  {"log_a_stderr_bootstrap", &boot_se_log_a}})
      write_vector(f, std::string("/bins/") + name, *v);
    f.write_replicated("/bins/used", used, {used.size()});
    f.write_replicated("/bins/widths", widths, {widths.size()});
    f.write_replicated("/bins/at_bound", at_bound, {at_bound.size()});
    f.write_replicated("/bins/a_at_cap", a_at_cap, {a_at_cap.size()});

    // the data as fitted (H of every width of every file per bin)
    if (!R.data_F.empty()) {
      f.create_group("/data");
      f.set_attr("/data", "series", R.data_series);
      write_vector(f, "/data/F", R.data_F);
      write_vector(f, "/data/phi", R.data_phi);
      const std::vector<std::uint64_t> ddims{R.data_F.size(), R.data_phi.size()};
      f.write_replicated("/data/H", R.data_H, ddims);
      f.write_replicated("/data/H_sigma", R.data_sigma, ddims);
      f.write_replicated("/data/fitted", R.data_fitted, {R.data_fitted.size()});
    }

    // diagnostics
    const std::string d = "/diagnostics";
    f.create_group(d);
    f.set_attr(d, "min_count", o.min_count);
    f.set_attr(d, "min_widths", static_cast<std::int64_t>(o.min_widths));
    f.set_attr(d, "min_width_over_cell", o.min_width_over_cell);
    f.set_attr(d, "breakpoints", static_cast<std::int64_t>(R.breakpoints));
    f.set_attr(d, "lambda_h", R.lambda_h);
    f.set_attr(d, "lambda_log_a", R.lambda_log_a);
    f.set_attr(d, "edf_h", R.edf_h);
    f.set_attr(d, "edf_log_a", R.edf_log_a);
    f.set_attr(d, "chi2_per_dof", R.chi2_per_dof);
    if (!R.exponent_grid.empty()) {  // step 0's profile
      write_vector(f, d + "/width_exponent_grid", R.exponent_grid);
      write_vector(f, d + "/width_exponent_chi2", R.exponent_chi2);
      f.set_attr(d, "width_exponent_chi2_per_dof", R.exponent_chi2_per_dof);
    }
    f.set_attr(d, "h_clamped_grid_points", static_cast<std::int64_t>(R.h_clamped));
    f.set_attr(d, "cv_rms_H", R.cv_rms);
    f.set_attr(d, "cv_in_sample_rms_H", R.cv_in_sample_rms);
    f.set_attr(d, "wall_seconds", R.wall_seconds);
    std::vector<std::string> rfile, rgroup, cfile;
    std::vector<double> rF, rmean, rz, rrms, rsm, crms, cmean;
    std::vector<std::int64_t> rpts, cpts, crun;
    for (const WidthResiduals& w : R.residuals) {
      rfile.push_back(w.file);
      rgroup.push_back(w.group);
      rF.push_back(w.F);
      rmean.push_back(w.mean);
      rz.push_back(w.mean_z);
      rrms.push_back(w.rms_z);
      rsm.push_back(w.mean_smoothed);
      rpts.push_back(w.points);
    }
    f.set_attr(d, "residual_files", rfile);
    f.set_attr(d, "residual_groups", rgroup);
    write_vector(f, d + "/residual_F", rF);
    write_vector(f, d + "/residual_mean", rmean);
    write_vector(f, d + "/residual_mean_z", rz);
    write_vector(f, d + "/residual_rms_z", rrms);
    write_vector(f, d + "/residual_mean_smoothed", rsm);
    f.write_replicated(d + "/residual_points", rpts, {rpts.size()});
    for (const CrossValidationRun& c : R.cv_runs) {
      cfile.push_back(c.file);
      crun.push_back(c.run);
      crms.push_back(c.rms);
      cmean.push_back(c.mean);
      cpts.push_back(c.points);
    }
    if (!R.cv_runs.empty()) {
      f.set_attr(d, "cv_files", cfile);
      f.write_replicated(d + "/cv_run", crun, {crun.size()});
      write_vector(f, d + "/cv_rms", crms);
      write_vector(f, d + "/cv_mean", cmean);
      f.write_replicated(d + "/cv_points", cpts, {cpts.size()});
    }

    write_sources(f, files);
  });
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
  const PhysicalSystem& p = first.physics;
  DragModel M;
  static_cast<PhysicalSystem&>(M) = p;
  const double delta = cell_over_dp * p.diameter_m;
  BSpline h;
  h.order = 2;
  h.knots.push_back(phi.front());
  h.knots.insert(h.knots.end(), phi.begin(), phi.end());
  h.knots.push_back(phi.back());
  h.coefficients = H;
  BSpline log_a = h;
  log_a.coefficients.assign(H.size(), -700.0);  // a = exp(-700) ~ 1e-304: 0 for any evaluator of the file
  const double h_max = 0.99;
  h5::write_atomically(path, MPI_COMM_SELF, [&](h5::File& f) {
    schema::write_common(f, schema::kDragModel, scene);
    f.set_attr("/", "model_form",
               std::string("beta_bar/beta_micro = c_corr(alpha) [1 - H_grid(phi)], H_grid the a-priori filtered drag "
                           "correction of one coarse grid (curves = table): piecewise linear in phi through the table, "
                           "constant outside it, clamped to [-1, h_max]; no width dependence (a = 0)"));
    f.set_attr("/", "curves", std::string("table"));
    f.set_attr("/", "operator", std::string(names_of(CalibrationOperator::TscGrid).model_file));
    f.set_attr("/", "kernel", std::string("tsc"));
    f.set_attr("/", "table_cells_across", static_cast<std::int64_t>(cells_across));
    f.set_attr("/", "calibrated_delta_m", std::vector<double>{delta});
    f.set_attr("/", "calibrated_delta_over_dp", std::vector<double>{cell_over_dp});
    f.set_attr("/", "calibrated_cells_across", std::vector<std::int64_t>{cells_across});
    f.set_attr("/", "width_exponent", 1.0);
    f.set_attr("/", "width_exponent_fitted", std::int64_t{0});
    write_physical_system(f, M, "base_drag");
    f.set_attr("/", "u_t_convention", std::string(kUtConvention));
    f.set_attr("/", "phi_crit", phi.front());
    f.set_attr("/", "phi_max", phi.back());
    f.set_attr("/", "h_max", h_max);
    write_spline(f, "/h", h, "H_grid(phi): order-2 B-spline = the piecewise-linear table (knots = the bins' mean phi, "
                             "coefficients = H_grid); clamped to [-1, h_max], constant outside the knots");
    write_spline(f, "/log_a", log_a, "log a = -700: a = 0 (the table has no width dependence)");
    f.create_group("/table");
    write_vector(f, "/table/phi", phi);
    write_vector(f, "/table/H", H);
    write_vector(f, "/table/count", n);
    f.set_attr("/table", "source_group", group);
    f.set_attr("/table", "min_count", min_count);
    // c_corr = 1 (a = 1, k = 0): the table is the grid's a-priori closure alone; what parcels miss is measured
    // against it, not folded into it
    write_c_corr(f, 1.0, 0.0, "none");
    write_sources(f, files);
  });
  std::ostringstream out;
  out << "cgd-fit --grid-table " << cells_across << ": the a-priori H_grid of the grid of " << cells_across
      << " cells across (cell " << format("%.4g", cell_over_dp) << " d_p) as a table model (curves = table, a = 0), "
      << phi.size() << " bins with >= " << min_count << " samples, pooled over " << files.size() << " file(s)\n"
      << "    phi     H_grid   samples\n";
  for (std::size_t i = 0; i < phi.size(); ++i)
    out << format("  %6.4f", phi[i]) << format("  %8.4f", H[i]) << format("  %8.0f", n[i]) << "\n";
  return out.str();
}

std::string fit_report(const FitResult& R, const std::vector<FilteredFile>& files, const FitOptions& o) {
  std::ostringstream out;
  const SplineCurves curves{&R.model};
  const Radl2014Curves radl;
  const bool n1 = R.model.width_exponent == 1.0;
  const std::string form = n1 ? "1/(1 + aF)" : "1/(1 + aF^n)";
  out << "cgd-fit: H(F, phi) = h(phi)/(1 + a(phi) F" << (n1 ? "" : "^n") << "), F = L_char/Delta";
  out << (o.calibration_operator == CalibrationOperator::TscGrid ? " (operator tsc-grid: H_grid of the coarse grids, Delta = cell size)"
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
