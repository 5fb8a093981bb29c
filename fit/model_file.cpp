// The drag model file (docs/schema-drag-model.md; read back by core/filtered_drag.cpp's
// load_drag_model) and the fit report.
#include <cmath>
#include <cstdio>
#include <sstream>

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
    schema::write_common(f, "drag_model", scene);
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
    f.set_attr("/", "base_drag", std::string(to_string(M.base_law)));
    f.set_attr("/", "u_t_convention", M.u_t_convention);
    f.set_attr("/", "u_t_m_s", M.u_t_m_s);
    f.set_attr("/", "l_char_m", M.l_char_m);
    f.set_attr("/", "phi_crit", M.phi_crit);
    f.set_attr("/", "phi_max", M.h_spline.upper());
    f.set_attr("/", "h_max", M.h_max);
    f.set_attr("/", "diameter_m", M.diameter_m);
    f.set_attr("/", "particle_density_kg_m3", M.particle_density_kg_m3);
    f.set_attr("/", "fluid_density_kg_m3", M.fluid_density_kg_m3);
    f.set_attr("/", "fluid_viscosity_Pa_s", M.fluid_viscosity_Pa_s);
    f.set_attr("/", "gravity_m_s2", M.gravity_m_s2);
    write_spline(
        f, "/h", M.h_spline,
        "S_h(phi); h = clip(S_h(phi), 0, h_max) on [phi_crit, phi_max], h(phi_crit) phi/phi_crit below, "
        "h(phi_max) above");
    write_spline(f, "/log_a", M.log_a_spline,
                 "S(phi) = log a(phi); a = exp(S(clip(phi, phi_crit, phi_max)))");
    f.create_group("/c_corr");
    f.set_attr("/c_corr", "a", M.c_corr_a);
    f.set_attr("/c_corr", "k", M.c_corr_k);
    f.set_attr("/c_corr", "source", M.c_corr_source);
    f.set_attr("/c_corr", "fitted", std::int64_t{0});
    f.set_attr("/c_corr", "formula", std::string("c_corr = a + (1 - a) exp(-k (alpha - 1))"));

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
    std::vector<std::int64_t> used, widths, at_bound;
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

    // sources
    f.create_group("/sources");
    std::vector<std::string> paths, sums;
    for (const FilteredFile& ff : files) paths.push_back(ff.path), sums.push_back(ff.checksum);
    f.set_attr("/sources", "files", paths);
    f.set_attr("/sources", "checksums", sums);
    f.set_attr("/sources", "checksum_kind", std::string("FNV-1a 64-bit of the file's bytes, hex"));
  });
}

std::string fit_report(const FitResult& R, const std::vector<FilteredFile>& files, const FitOptions& o) {
  std::ostringstream out;
  const SplineCurves curves{&R.model};
  const Radl2014Curves radl;
  const bool n1 = R.model.width_exponent == 1.0;
  const std::string form = n1 ? "1/(1 + aF)" : "1/(1 + aF^n)";
  out << "cgd-fit: H(F, phi) = h(phi)/(1 + a(phi) F" << (n1 ? "" : "^n") << "), F = L_char/Delta";
  if (!n1 || o.fit_width_exponent) out << ", n = " << format("%.3f", R.model.width_exponent);
  out << "; " << files.size()
      << " filtered file(s), base law " << to_string(R.model.base_law)
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
      out << "  " << c.file << " run " << c.run << ": " << c.points << " points, rms "
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
