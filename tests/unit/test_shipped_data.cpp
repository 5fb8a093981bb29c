// What the repository ships for users who do not run the resolved simulations (README "A ready model"): the
// half box's drag model (data/models/half_box.h5) and the filtered statistics of the resolved runs it was fitted
// on (data/filtered/half_phi*.h5, one run each). Two claims are tested: the model is the fit of those files (a user
// refitting with other options starts from the model's own data), and it reproduces the H the runs measured on
// the coarse grid it was validated on (docs/fit.md "Pooled runs").
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/checksum.hpp"
#include "core/filtered_drag.hpp"
#include "core/schema/drag_model.hpp"
#include "fit/filtered_input.hpp"
#include "fit/fitter.hpp"

namespace {

std::string source_dir() {
  const char* s = std::getenv("CGD_SOURCE_DIR");
  return s ? s : CGD_SOURCE_DIR_DEFAULT;
}

std::string model_path() { return source_dir() + "/data/models/half_box.h5"; }

/// The filtered files the model records in /sources (paths relative to the repository, as the fit was run from
/// its root), read; each must be shipped with the bytes the fit read (its FNV-1a checksum as recorded).
std::vector<cgd::fit::FilteredFile> shipped_sources(const cgd::schema::DragModelFile& m) {
  std::vector<cgd::fit::FilteredFile> files;
  for (std::size_t i = 0; i < m.source_files.size(); ++i) {
    const std::string& name = m.source_files[i];
    EXPECT_EQ(name.rfind("data/filtered/", 0), 0u) << name << ": a source outside data/filtered/ is not shipped";
    const std::string path = source_dir() + "/" + name;
    EXPECT_EQ(cgd::file_checksum_fnv1a(path), m.source_checksums[i]) << name << ": not the bytes the fit read";
    files.push_back(cgd::fit::read_filtered_file(path));
  }
  return files;
}

// Every file the model was fitted on is in data/filtered/ with the bytes the fit read, and cgd-fit's fit of them
// with the model's options as the file records them (the operator, the width exponent fitted or given, phi_crit,
// h_max, the runs pooled or not, the bootstrap seed that made the pooled intervals, min_count, min_widths,
// min_width_over_cell and the spline breakpoints) gives the
// model's curves again: knots and coefficients of h and log a, and n. The bands, the bootstrap and the
// cross-validation are not redone: the curves do not depend on them (fitter.hpp, steps 3-4). Tolerance 1e-9: the
// fit is deterministic (the same files give the same bytes); a rebuild may only reorder floating-point sums, where
// a change of the data or of an option moves the coefficients by 1e-3 or more.
TEST(ShippedData, HalfBoxModelIsTheFitOfTheShippedFilteredFiles) {
  const cgd::schema::DragModelFile m = cgd::schema::read_drag_model(model_path());
  ASSERT_GE(m.source_files.size(), 2u);
  const std::vector<cgd::fit::FilteredFile> files = shipped_sources(m);
  if (::testing::Test::HasFailure()) return;
  cgd::fit::FitOptions o;
  o.calibration_operator = m.calibration_operator;
  o.fit_width_exponent = m.width_exponent_fitted;
  o.width_exponent = m.width_exponent;
  o.phi_crit = m.phi_crit;
  o.h_max = m.h_max;
  ASSERT_TRUE(m.bands && m.diagnostics) << "the shipped model has its /bands and /diagnostics";
  o.seed = static_cast<std::uint64_t>(m.bands->seed);
  o.min_count = m.diagnostics->min_count;
  o.min_widths = static_cast<int>(m.diagnostics->min_widths);
  o.min_width_over_cell = m.diagnostics->min_width_over_cell;
  o.breakpoints = static_cast<int>(m.diagnostics->breakpoints);
  o.bootstrap = 0;
  o.cross_validate = false;
  // as cgd-fit: the operator's series selected, then the runs pooled
  std::vector<cgd::fit::FilteredFile> fitted = cgd::fit::select_operator(files, o.calibration_operator);
  if (m.sources_pooled) fitted = {cgd::fit::pool_runs(fitted, o.seed)};
  const cgd::fit::FitResult r = cgd::fit::fit_filtered_drag(fitted, o, nullptr);
  EXPECT_NEAR(r.width_exponent, m.width_exponent, 1e-9);
  const auto same = [](const std::vector<double>& refit, const std::vector<double>& shipped, const char* what) {
    ASSERT_EQ(refit.size(), shipped.size()) << what;
    for (std::size_t i = 0; i < refit.size(); ++i) EXPECT_NEAR(refit[i], shipped[i], 1e-9) << what << " [" << i << "]";
  };
  same(r.model.h_spline.knots, m.h.knots, "h knots");
  same(r.model.h_spline.coefficients, m.h.coefficients, "h coefficients");
  same(r.model.log_a_spline.knots, m.log_a.knots, "log a knots");
  same(r.model.log_a_spline.coefficients, m.log_a.coefficients, "log a coefficients");
}

// The model reproduces the H the runs measured on the grid it was validated on: the 4-cell grid of the half box
// (13.25 d_p cells; docs/coarse.md), H_grid pooled over the shipped runs (the ratio of the sums over every run, what
// the fit of the pooled runs is fitted to, with its 95 % block-bootstrap band), against H = h/(1 + a F^n) at the
// grid's F, in the bins of >= 1e5 samples at phi-bar >= 2 phi_crit (below, h -> 0 linearly and a is capped by
// identifiability: docs/fit.md "Low phi"; the pooled H at phi-bar 0.024 is 0.23, the six-run model's 0.14).
// Tolerance: the band's half-width + 0.03, what the splines' smoothing across the bins leaves between the model and
// the data it was fitted to (measured on the five runs pooled: up to 0.020 at phi-bar 0.05-0.49, 0.032 at 0.035).
// The band is 0.01-0.05 up to phi-bar 0.45 and 0.06-0.4 up to 0.59; a bin whose band is wider than 0.5 (one,
// at 0.594: +-1.2) cannot test anything and is counted, not checked. Near packing the six runs measure H < 0
// (more drag than the micro law at the cell's mean phi) in three bins whose whole band lies below 0: -0.067 +-
// 0.062 at phi-bar 0.555, -0.114 +- 0.096 at 0.574, -0.226 [-0.54, -0.05] at 0.583. The form cannot follow them
// (h >= 0, so H >= 0; docs/fit.md "The six-run model"): there, at phi-bar >= 0.5 only, the model is asked to come
// as close as the form allows, H <= 0.03 (the same 0.03 of smoothing above the form's best, H = 0), and the number
// of such bins is pinned (a change of the data, of the pooling or of the bootstrap shows).
TEST(ShippedData, HalfBoxModelReproducesTheRunsGridH) {
  const cgd::schema::DragModelFile file = cgd::schema::read_drag_model(model_path());
  const std::vector<cgd::fit::FilteredFile> files = shipped_sources(file);
  if (::testing::Test::HasFailure()) return;
  ASSERT_TRUE(file.bands) << "the shipped model has its /bands";
  // pooled as the fit pooled them: the bootstrap seed the model records
  const cgd::fit::FilteredFile pooled = cgd::fit::pool_runs(files, static_cast<std::uint64_t>(file.bands->seed));
  const cgd::fit::WidthSeries* grid = nullptr;
  for (const cgd::fit::WidthSeries& g : pooled.grids)
    if (g.cells_across == 4) grid = &g;
  ASSERT_NE(grid, nullptr) << "the shipped filtered files lack /grids/4";
  const cgd::DragModel m = cgd::load_drag_model(model_path());
  const cgd::SplineCurves curves{&m};
  const double Fn = std::pow(grid->F, m.width_exponent);
  int checked = 0, below_zero = 0, too_wide = 0;
  for (std::size_t b = 0; b < pooled.bins(); ++b) {
    const double phi = grid->phi_mean[b], H = grid->H[b];
    const double band = 0.5 * (grid->H_high[b] - grid->H_low[b]);
    const double model = curves.h(phi) / (1.0 + curves.a(phi) * Fn);
    if (grid->count[b] < 100000 || phi < 2 * m.phi_crit) continue;
    if (band > 0.5) {
      ++too_wide;
      continue;
    }
    ++checked;
    const std::string where = "phi-bar " + std::to_string(phi) + " (" + std::to_string(grid->count[b]) +
                              " samples, H_grid " + std::to_string(H) + " +- " + std::to_string(band) + ")";
    if (phi >= 0.5 && grid->H_high[b] < 0.0) {  // H < 0 established near packing: the form's best is H = 0
      ++below_zero;
      EXPECT_LE(model, 0.03) << where;
      continue;
    }
    EXPECT_NEAR(model, H, band + 0.03) << where;
  }
  EXPECT_EQ(below_zero, 3) << "bins near packing whose H_grid band lies below 0 (0.555, 0.574, 0.583)";
  EXPECT_LE(too_wide, 1) << "bins whose band is wider than 0.5";
  EXPECT_GE(checked, 40);
}

}  // namespace
