// The closure calibrated on the coarse grid's own operator (docs/fit.md "--operator grid", "The perfect-
// closure model", "Low phi"), against answers known here: cgd-fit --operator grid fits the grids' H_grid
// (not the box widths'), the model file says what it was calibrated for and the run warns when that does
// not fit its Delta, the --grid-table model reproduces its table, and a low-phi correction is kept.
#include <gtest/gtest.h>
#include <hdf5.h>

#include <cmath>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/filtered_drag.hpp"
#include "core/scene.hpp"
#include "fit/filtered_input.hpp"
#include "fit/fitter.hpp"
#include "fit_test_util.hpp"
#include "temp_dir.hpp"
#include "test_scenes.hpp"

namespace {

using cgd::fit::FilteredFile;
using cgd::fit::FitOptions;
using cgd::fit::FitResult;
using cgd::fit::WidthSeries;
using cgd::fit::testing::make_synthetic;
using cgd::fit::testing::SyntheticSpec;
using cgd::fit::testing::truth_a;
using cgd::fit::testing::truth_h;

/// The pipeline demo's box (tests/scenes/demo_box.toml).
std::string demo_scene() { return cgd::testing::test_scene_text("demo_box.toml"); }

/// A synthetic filtered file whose box widths become coarse grids (H_grid follows the truth at
/// F = L_char / cell size), with box widths that carry `box_scale` x the truth (a different operator).
FilteredFile with_grids(const SyntheticSpec& s, double box_scale) {
  FilteredFile f = make_synthetic(s);
  const double d = f.physics.diameter_m;
  std::vector<WidthSeries> boxes;
  int k = 0;
  for (const WidthSeries& w : f.widths) {
    if (w.whole_box) {
      boxes.push_back(w);
      continue;
    }
    WidthSeries g = w;
    g.grid = true;
    g.cells_across = 10 - k;  // any labels: the fit uses F
    g.group = "/grids/" + std::to_string(g.cells_across);
    g.cell_size_over_dp = w.width_m / d;
    g.width_over_cell = 2.0 + k;  // coarser than the resolved grid
    f.grids.push_back(g);
    WidthSeries b = w;
    for (double& h : b.H) h *= box_scale;
    for (double& h : b.H_low) h *= box_scale;
    for (double& h : b.H_high) h *= box_scale;
    b.width_over_cell = 2.0 + k;
    boxes.insert(boxes.begin() + k, b);
    ++k;
  }
  f.widths = boxes;
  return f;
}

using cgd::CalibrationOperator;

FitResult fit(const std::vector<FilteredFile>& files, CalibrationOperator op, FitOptions o = {}) {
  o.bootstrap = 0;
  o.cross_validate = false;
  o.calibration_operator = op;
  return cgd::fit::fit_filtered_drag(cgd::fit::select_operator(files, op), o, nullptr);
}

// --operator grid fits H_grid: with the box widths at half the truth, the grid fit recovers the truth
// (h within 0.01 at noise 0.01, the tolerance of Fit.RecoversKnownMasterCurves) and the box fit does not
// (its h is half: off by > 0.1 where h_true > 0.3).
TEST(FitOperator, GridFitsTheGridsHAndBoxTheBoxWidths) {
  SyntheticSpec s;
  s.noise = 0.01;
  const FilteredFile f = with_grids(s, 0.5);
  const FitResult g = fit({f}, CalibrationOperator::Grid), b = fit({f}, CalibrationOperator::Box);
  const cgd::SplineCurves cg{&g.model}, cb{&b.model};
  for (double phi = 0.1; phi <= 0.4 + 1e-9; phi += 0.05) {
    EXPECT_NEAR(cg.h(phi), truth_h(phi), 0.01) << phi;
    EXPECT_GT(std::abs(cb.h(phi) - truth_h(phi)), 0.1) << phi;
  }
  FilteredFile none = make_synthetic(s);
  try {
    cgd::fit::select_operator({none}, CalibrationOperator::Grid);
    ADD_FAILURE() << "no InputError";
  } catch (const cgd::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--grids"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(cgd::parse_calibration_operator("tent"));
  EXPECT_EQ(cgd::parse_calibration_operator("grid"), CalibrationOperator::Grid);
}

// The model file records its calibration: operator grid, kernel tsc, the cell sizes fitted; a run
// whose Delta lies within them gets no warning, outside it one naming both; a box model always warns
// (the coarse run applies its grid's operator); a file without the attribute reads as "box".
TEST(FitOperator, ModelFileSaysWhatItWasCalibratedForAndTheRunWarns) {
  cgd::testing::TempDir dir;
  SyntheticSpec s;
  s.noise = 0.02;
  const FilteredFile f = with_grids(s, 0.5);
  const cgd::Scene scene = cgd::load_scene_from_string(demo_scene(), "closure_test.toml");
  FitOptions o;
  o.calibration_operator = CalibrationOperator::Grid;
  const FitResult g = fit({f}, CalibrationOperator::Grid, o);
  const std::string grid_path = (dir / "grid.h5").string(), box_path = (dir / "box.h5").string();
  cgd::fit::write_model_file(grid_path, g, cgd::fit::select_operator({f}, CalibrationOperator::Grid), o, scene);
  const cgd::DragModel m = cgd::load_drag_model(grid_path);
  EXPECT_EQ(m.calibration_operator, CalibrationOperator::Grid);
  ASSERT_EQ(m.calibrated_delta_m.size(), s.F.size());
  const double lo = f.physics.l_char_m / s.F.front(), hi = f.physics.l_char_m / s.F.back();  // F descending
  EXPECT_NEAR(m.calibrated_delta_m.front(), lo, 1e-12 * lo);
  EXPECT_NEAR(m.calibrated_delta_m.back(), hi, 1e-12 * hi);
  EXPECT_TRUE(cgd::model_calibration_warnings(m, 0.5 * (lo + hi)).empty());
  const auto outside = cgd::model_calibration_warnings(m, 2 * hi);
  ASSERT_EQ(outside.size(), 1u);
  EXPECT_NE(outside[0].find("outside"), std::string::npos) << outside[0];
  {
    cgd::h5::File h = cgd::h5::File::open_read(grid_path, MPI_COMM_SELF);
    EXPECT_EQ(h.attr_string("/", "kernel"), "tsc");
    EXPECT_EQ(h.attr_string("/", "operator"), "grid");
  }
  o.calibration_operator = CalibrationOperator::Box;
  const FitResult b = fit({f}, CalibrationOperator::Box, o);
  cgd::fit::write_model_file(box_path, b, {f}, o, scene);
  const cgd::DragModel mb = cgd::load_drag_model(box_path);
  EXPECT_EQ(mb.calibration_operator, CalibrationOperator::Box);
  const auto w = cgd::model_calibration_warnings(mb, 0.5 * (lo + hi));
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("box filter"), std::string::npos) << w[0];
  // an old file (no operator attribute) is a box model
  const hid_t file = H5Fopen(grid_path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  ASSERT_GE(H5Adelete(file, "operator"), 0);
  H5Fclose(file);
  EXPECT_EQ(cgd::load_drag_model(grid_path).calibration_operator, CalibrationOperator::Box);
}

// The perfect-closure model (--grid-table N): evaluated at its table points it returns H_grid of grid N
// exactly (1e-12: one linear interpolation at a knot), a = 0 so the law is (1 - H_grid) beta_micro at
// any Delta, linear between the points and constant beyond them; the run warns at another cell size.
TEST(GridTable, ModelReproducesTheTableAtItsPointsAndAppliesIt) {
  cgd::testing::TempDir dir;
  SyntheticSpec s;
  s.noise = 0.02;
  const FilteredFile f = with_grids(s, 0.5);
  const cgd::Scene scene = cgd::load_scene_from_string(demo_scene(), "closure_test.toml");
  const std::string path = (dir / "perfect.h5").string();
  const WidthSeries& grid = f.grids[2];
  cgd::fit::write_grid_table_model(path, {f}, static_cast<int>(grid.cells_across), 100, scene);
  const cgd::DragModel m = cgd::load_drag_model(path);
  EXPECT_TRUE(m.table);
  EXPECT_EQ(m.table_cells_across, grid.cells_across);
  EXPECT_EQ(m.calibration_operator, CalibrationOperator::Grid);
  const cgd::SplineCurves c{&m};
  int points = 0;
  for (std::size_t b = 0; b < f.bins(); ++b) {
    if (grid.count[b] < 100) continue;
    ++points;
    EXPECT_NEAR(c.h(grid.phi_mean[b]), grid.H[b], 1e-12) << "bin " << b;
    EXPECT_EQ(c.a(grid.phi_mean[b]), 0.0);
  }
  EXPECT_EQ(points, static_cast<int>(f.bins()));
  // linear between points, constant outside
  const double p0 = grid.phi_mean[3], p1 = grid.phi_mean[4];
  EXPECT_NEAR(c.h(0.5 * (p0 + p1)), 0.5 * (grid.H[3] + grid.H[4]), 1e-12);
  EXPECT_NEAR(c.h(0.0), grid.H[0], 1e-15);
  EXPECT_NEAR(c.h(0.9), grid.H.back(), 1e-15);
  // the law: (1 - H_grid) beta_micro at alpha = 1, whatever Delta
  cgd::FilteredDragSetup setup;
  setup.model = std::make_shared<cgd::DragModel>(m);
  setup.l_char_m = m.l_char_m;
  const cgd::DragParams air{1.3, 1.8e-5, 75e-6};
  const double delta = grid.cell_size_over_dp * 75e-6;
  for (double width : {delta, 3 * delta}) {
    setup.filter_width_m = width;
    const double phi = grid.phi_mean[5];
    const double ratio = cgd::beta_p(cgd::DragLaw::Model, air, setup, phi, 0.1) /
                         cgd::beta_p(cgd::DragLaw::Beetstra, air, setup, phi, 0.1);
    EXPECT_NEAR(ratio, 1.0 - grid.H[5], 1e-12);
  }
  // c_corr = 1: parcels get the grid's closure alone (the paper's k = 0.05 would give 0.905 at alpha = 3)
  setup.filter_width_m = delta;
  setup.parcel_size = 3;
  EXPECT_NEAR(cgd::beta_p(cgd::DragLaw::Model, air, setup, grid.phi_mean[5], 0.1) /
                  cgd::beta_p(cgd::DragLaw::Beetstra, air, setup, grid.phi_mean[5], 0.1),
              1.0 - grid.H[5], 1e-12);
  EXPECT_TRUE(cgd::model_calibration_warnings(m, delta).empty());
  EXPECT_EQ(cgd::model_calibration_warnings(m, 1.5 * delta).size(), 1u);
  EXPECT_THROW(cgd::fit::write_grid_table_model((dir / "x.h5").string(), {f}, 77, 100, scene), cgd::InputError);
}

// Low phi (docs/fit.md "Low phi"). Truth with a correction at low phi: h = 0.5, a = 4 on [0.016, 0.04)
// (H = 0.12-0.23 at the grids' F), the usual curves above; the lowest fitted bin ([0.016, 0.02)) holds
// H = 0 at every width (its a is not identified: se of log a ~ 1e4), as on the demo runs' grids, and the
// four widths span F = 0.4 ... 0.8 (the coarse grids of 3-6 cells across). The fitted model must keep
// the correction at phi = 0.025 and 0.035 (H within 0.04 of the truth at every F: 4 bins of noise 0.02
// per snapshot, measured 0.01-0.02), and a(phi) must stay within the range of the per-bin estimates
// everywhere (without the bound, the log a spline ran to a ~ 1e20 at phi = 0.02 on the demo data: H = 0).
TEST(Fit, LowPhiCorrectionIsNotSwitchedOff) {
  auto truth = [](double phi, double F) {
    if (phi < 0.02) return 0.0;
    if (phi < 0.04) return 0.5 / (1 + 4 * F);
    return truth_h(phi) / (1 + truth_a(phi) * F);
  };
  SyntheticSpec s;
  s.truth = truth;
  s.bins = 50;
  s.phi_max = 0.25;  // bins 0.005 wide: [0.015, 0.02) is fitted (its mean phi 0.0175 > phi_crit)
  s.F = {0.8, 0.67, 0.54, 0.4};
  s.noise = 0.02;
  s.noise_scale = {0.3, 0.5, 0.8, 1.0, 1.0};  // the narrow widths are the precise ones, as in filtered data
  FitOptions o;
  o.bootstrap = 0;
  o.cross_validate = false;
  o.min_widths = 3;
  const FitResult r = cgd::fit::fit_filtered_drag({make_synthetic(s)}, o, nullptr);
  const cgd::SplineCurves c{&r.model};
  double lo = 1e300, hi = 0;
  for (const auto& b : r.bins)
    if (b.used) lo = std::min(lo, std::exp(b.log_a)), hi = std::max(hi, std::exp(b.log_a));
  for (double phi = 0.0; phi <= 0.25; phi += 0.0025) {
    EXPECT_GE(c.a(phi), lo * (1 - 1e-12)) << phi;
    EXPECT_LE(c.a(phi), hi * (1 + 1e-12)) << phi;
  }
  for (double phi : {0.025, 0.035})
    for (double F : s.F) {
      const double model = c.h(phi) / (1 + c.a(phi) * F);
      EXPECT_NEAR(model, truth(phi, F), 0.04) << "phi " << phi << " F " << F;
    }
}

}  // namespace

namespace {

// Regression on real data: H_grid of the demo runs' coarse grids (6, 5, 4, 3 cells across of the 30 x 120
// x 30 d_p box; phi = 0.02 and 0.05 runs, 71 snapshots each, cgd-filter --grids), bins 0-0.16. The first
// fitted bin (phi 0.017) has H ~ 0 and an unidentified a (se of log a ~ 1e4); before the bound, GCV
// picked almost no smoothing for log a and the spline ran to a = 1e20 at phi = 0.02 (1e57 at 0.01):
// H = 0 at every Delta where the grids show 0.05-0.17. Now a stays within the bins' range and the model's
// H at phi = 0.024 on the 4-across grid is >= 0.05 (data 0.12 +- 0.014; the smoothed model need not pass
// through one bin, but it must not be off).
struct DemoGrid {
  int across;
  double F;
  std::vector<double> H, lo, hi, phi;
  std::vector<std::int64_t> count;
};
const std::vector<DemoGrid> kDemoGrids = {
    {6, 0.8035920675788036, {-0.07163, -0.007416, 0.04487, 0.05227, 0.05313, 0.08261, 0.1276, 0.148, 0.1635, 0.178, 0.1895, 0.1908, 0.1957, 0.2066, 0.2272, 0.2485}, {-0.08211, -0.01146, 0.03896, 0.04273, 0.04002, 0.06688, 0.1191, 0.1397, 0.1527, 0.1612, 0.172, 0.1693, 0.1641, 0.1661, 0.1743, 0.1766}, {-0.06283, -0.002888, 0.05037, 0.06126, 0.06613, 0.09908, 0.1356, 0.1568, 0.1752, 0.1959, 0.2093, 0.216, 0.2301, 0.2541, 0.2912, 0.311}, {0.008506, 0.01645, 0.02473, 0.0348, 0.04547, 0.05461, 0.06482, 0.07476, 0.08469, 0.09463, 0.1045, 0.1145, 0.1245, 0.1344, 0.1445, 0.1546}, {4175, 91849, 166000, 118865, 134985, 152866, 111282, 86087, 62218, 41414, 25102, 14079, 7931, 3926, 1867, 1020}},
    {5, 0.6696600563156696, {-0.1046, -0.0008182, 0.07609, 0.06537, 0.07096, 0.1225, 0.1838, 0.2077, 0.2291, 0.2412, 0.2497, 0.2553, 0.2651, 0.3137, 0.3226, 0.281}, {-0.1224, -0.008293, 0.06704, 0.04896, 0.053, 0.1001, 0.1719, 0.1955, 0.2105, 0.2184, 0.2196, 0.2109, 0.1985, 0.2253, 0.2484, 0.2316}, {-0.09116, 0.006789, 0.08449, 0.08102, 0.08916, 0.1454, 0.195, 0.2208, 0.2498, 0.2676, 0.2847, 0.3039, 0.3483, 0.3959, 0.4076, 0.3848}, {0.008706, 0.01673, 0.02453, 0.03482, 0.04566, 0.05451, 0.06479, 0.07468, 0.08456, 0.09444, 0.1045, 0.1143, 0.1243, 0.1345, 0.1446, 0.1544}, {2613, 94513, 174209, 108449, 145032, 173560, 120303, 88325, 56170, 31858, 16354, 7523, 3196, 1399, 725, 419}},
    {4, 0.5357280450525357, {-0.15, 0.02089, 0.1215, 0.0624, 0.09615, 0.1724, 0.2458, 0.2701, 0.2824, 0.2973, 0.3168, 0.3484, 0.3666, 0.3543, 0.2592, 0.09743}, {-0.1788, 0.00741, 0.1082, 0.03717, 0.07402, 0.1418, 0.2316, 0.2493, 0.2505, 0.251, 0.2421, 0.2529, 0.2493, 0.2853, 0.1941, 0.09743}, {-0.1179, 0.03354, 0.1353, 0.08652, 0.1185, 0.2034, 0.2599, 0.2932, 0.3214, 0.3477, 0.4064, 0.4679, 0.5061, 0.52, 0.4644, 0.09743}, {0.008992, 0.01712, 0.02417, 0.03505, 0.04588, 0.05437, 0.06471, 0.07447, 0.08439, 0.09425, 0.1041, 0.1139, 0.1246, 0.1349, 0.1445, 0.1517}, {1017, 99055, 181702, 89390, 166110, 204886, 133667, 81651, 40645, 17170, 6278, 1928, 739, 506, 313, 41}},
    {3, 0.4017960337894018, {-0.2828, 0.07438, 0.1697, 0.0605, 0.1491, 0.2367, 0.2982, 0.2949, 0.3075, 0.3428, 0.4697, 0.3794, 0.31, NAN, NAN, NAN}, {-0.3967, 0.05342, 0.1513, 0.02163, 0.1171, 0.1984, 0.277, 0.2466, 0.2355, 0.1471, 0.4213, 0.3794, 0.31, NAN, NAN, NAN}, {-0.2051, 0.09438, 0.1895, 0.09265, 0.1807, 0.2713, 0.3206, 0.3518, 0.4073, 0.6009, 0.6211, 0.3794, 0.31, NAN, NAN, NAN}, {0.009569, 0.01766, 0.02346, 0.036, 0.04612, 0.05431, 0.06437, 0.07412, 0.08384, 0.09389, 0.1041, 0.1145, 0.1214, NAN, NAN, NAN}, {82, 108640, 181465, 62690, 208473, 257893, 129948, 55891, 15928, 2777, 869, 376, 66, 0, 0, 0}},
};

/// The demo grids above as the filtered file cgd-fit reads.
FilteredFile demo_grids_file() {
  FilteredFile f;
  f.path = "demo_grids";
  f.physics = {cgd::DragLaw::Beetstra, 0.2185, 0.0003013470253420513, 75e-6, 1500.0, 1.3, 1.8e-5,
               cgd::gravity_from_scales(0.2185, 0.0003013470253420513, 75e-6)};
  for (int b = 0; b <= 16; ++b) f.phi_edges.push_back(0.01 * b);
  f.run_paths = {"demo/phi0.02", "demo/phi0.05"};
  for (const DemoGrid& g : kDemoGrids) {
    WidthSeries w;
    w.group = "/grids/" + std::to_string(g.across);
    w.grid = true;
    w.cells_across = g.across;
    w.F = g.F;
    w.width_m = f.physics.l_char_m / g.F;
    w.width_over_cell = 9.0 / g.across;
    w.H = g.H;
    w.H_low = g.lo;
    w.H_high = g.hi;
    w.phi_mean = g.phi;
    w.count = g.count;
    f.grids.push_back(w);
  }
  return f;
}

TEST(Fit, LowPhiOnTheDemoGridsKeepsTheCorrection) {
  const FilteredFile f = demo_grids_file();
  FitOptions o;
  o.min_width_over_cell = 1.01;
  const FitResult r = fit({f}, CalibrationOperator::Grid, o);
  const cgd::SplineCurves c{&r.model};
  double hi = 0;
  for (const auto& b : r.bins)
    if (b.used) hi = std::max(hi, std::exp(b.log_a));
  for (double phi = 0.0; phi <= 0.16; phi += 0.002) EXPECT_LE(c.a(phi), hi * (1 + 1e-12)) << phi;
  EXPECT_GE(c.h(0.024) / (1 + c.a(0.024) * kDemoGrids[2].F), 0.05);
}

// The h curve is fitted to each bin's h at the smoothed a (fitter.cpp fit_curves), so the model reproduces the
// bins' H, the lowest bins included. With h and log a smoothed separately (before 2026-12-02), the lowest
// bin's h (0.5-0.7, going with its own unidentified a ~ 400) held the h curve's end coefficient while the
// log a curve followed the neighbours (a ~ 9): on the 3-run demo the model's H at phi = 0.017 on the
// 4-across grid was 0.80 against a measured 0.02, and the coarse runs at <phi> = 0.02 were 20 % fast. Here,
// on the demo grids above with the fitted n (as the demo profile fits; at n = 1 the form itself is rejected
// on these grids, chi2/dof 12, and misses by up to 0.19), the model's H at the first two fitted bins must be
// within 0.05 of the measured H on every grid (the data's 95 % intervals are +-0.01-0.03 there; 0.05 leaves
// the smoothing its due; the old fit misses by up to 0.29).
TEST(Fit, LowPhiModelReproducesTheBinsH) {
  const FilteredFile f = demo_grids_file();
  {
    FitOptions o;
    o.min_width_over_cell = 1.01;
    o.fit_width_exponent = true;
    const FitResult r = fit({f}, CalibrationOperator::Grid, o);
    const cgd::SplineCurves c{&r.model};
    const double n = r.model.width_exponent;
    for (std::size_t b : {std::size_t{1}, std::size_t{2}}) {  // phi 0.017 and 0.024: the first fitted bins
      for (const DemoGrid& g : kDemoGrids) {
        const double phi = g.phi[b], model = c.h(phi) / (1 + c.a(phi) * std::pow(g.F, n));
        EXPECT_NEAR(model, g.H[b], 0.05) << "n " << n << ", grid " << g.across << " across, phi " << phi;
      }
    }
  }
}

}  // namespace

