// Filtered drag laws (see filtered_drag.hpp) and a drag model file as the evaluator holds it (the file
// itself is read and validated by core/schema/drag_model.cpp; docs/schema-drag-model.md).
#include "core/filtered_drag.hpp"

#include <mpi.h>

#include <algorithm>
#include <array>
#include <iostream>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <utility>

#include "core/error.hpp"
#include "core/schema/drag_model.hpp"

namespace cgd {

namespace {

/// One piece of a published master curve: value = c0 + c1 x + c2 x^2 + c3 x^3, x = phi - phi0, on
/// [phi_lo, phi_hi). Transcribed from data/reference/radl2014-filtered-drag.csv (a test compares the
/// two line by line).
struct CubicPiece {
  double phi_lo, phi_hi, phi0, c0, c1, c2, c3;
};

constexpr std::array<CubicPiece, 6> kRadlA{{
    {0.0, 0.016, 0.0, 21.51, 0.0, 0.0, 0.0},
    {0.016, 0.10, 0.0, 1.96, 29.40, 164.91, -1923.0},
    {0.10, 0.18, 0.10, 4.63, 4.68, -412.04, 2254.0},
    {0.18, 0.25, 0.18, 3.52, -17.99, 128.80, -603.0},
    {0.25, 0.40, 0.25, 2.68, -8.82, 2.18, 112.33},  // c1 = -8.82 (MFiX), not -8.20 (CFDEMcoupling-PFM)
    {0.40, 1.0, 0.0, 1.79, 0.0, 0.0, 0.0},
}};

constexpr std::array<CubicPiece, 9> kRadlH{{
    {0.0, 0.03, 0.0, 0.0, 7.97, 0.0, 0.0},
    {0.03, 0.08, 0.03, 0.239, 4.640, -4.410, 253.630},
    {0.08, 0.12, 0.08, 0.492, 6.100, 33.630, -789.600},
    {0.12, 0.18, 0.12, 0.739, 5.010, -61.100, 310.800},
    {0.18, 0.34, 0.18, 0.887, 1.030, -5.170, 5.990},
    {0.34, 0.48, 0.34, 0.943, -0.170, -2.290, -9.120},
    {0.48, 0.55, 0.48, 0.850, -1.350, -6.130, -132.600},
    {0.55, 0.60, 0.55, 0.680, -2.340, -225.200, 0.0},
    {0.60, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0},
}};

template <std::size_t N>
double piecewise(const std::array<CubicPiece, N>& pieces, double phi) {
  phi = std::clamp(phi, 0.0, 1.0);
  const CubicPiece* p = &pieces.back();
  for (const CubicPiece& q : pieces)
    if (phi < q.phi_hi) {
      p = &q;
      break;
    }
  const double x = phi - p->phi0;
  return p->c0 + x * (p->c1 + x * (p->c2 + x * p->c3));
}

std::string number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", x);
  return buf;
}

}  // namespace

double parcel_correction(double alpha, double a_c, double k_c) {
  return a_c + (1.0 - a_c) * std::exp(-k_c * (alpha - 1.0));
}

double Radl2014Curves::h(double phi) const {
  return piecewise(kRadlH, phi);
}
double Radl2014Curves::a(double phi) const {
  return piecewise(kRadlA, phi);
}

namespace {
template <std::size_t N>
std::vector<Radl2014Curves::Piece> pieces_of(const std::array<CubicPiece, N>& pieces) {
  std::vector<Radl2014Curves::Piece> out;
  for (const CubicPiece& p : pieces) out.push_back({p.phi_lo, p.phi_hi, p.phi0, p.c0, p.c1, p.c2, p.c3});
  return out;
}
}  // namespace
std::vector<Radl2014Curves::Piece> Radl2014Curves::h_pieces() {
  return pieces_of(kRadlH);
}
std::vector<Radl2014Curves::Piece> Radl2014Curves::a_pieces() {
  return pieces_of(kRadlA);
}

double BSpline::operator()(double x) const {
  const int k = order;
  const std::size_t n = coefficients.size();
  x = std::clamp(x, lower(), upper());
  // knot span i: t_i <= x < t_{i+1}, k-1 <= i <= n-1 (x = t_n belongs to the last span)
  std::size_t i =
      static_cast<std::size_t>(std::upper_bound(knots.begin(), knots.begin() + static_cast<long>(n), x) -
                               knots.begin()) -
      1;
  i = std::clamp<std::size_t>(i, static_cast<std::size_t>(k - 1), n - 1);
  // de Boor: d_j = c_{j+i-p}, p = k - 1; d_j <- (1 - alpha) d_{j-1} + alpha d_j
  double d[16];
  const int p = k - 1;
  for (int j = 0; j <= p; ++j) d[j] = coefficients[i + j - p];
  for (int r = 1; r <= p; ++r)
    for (int j = p; j >= r; --j) {
      const double left = knots[i + j - p], right = knots[i + j + 1 - r];
      const double alpha = right > left ? (x - left) / (right - left) : 0.0;
      d[j] = (1.0 - alpha) * d[j - 1] + alpha * d[j];
    }
  return d[p];
}

namespace {
/// The interval [i, i + 1] of the ascending `x` holding v (clamped into the ends) and the weight of i + 1; one point:
/// (0, 0).
std::pair<std::size_t, double> bracket(const std::vector<double>& x, double v) {
  const std::size_t n = x.size();
  if (n < 2 || !(v > x.front())) return {0, 0.0};  // below the first (or NaN): the first value
  if (!(v < x.back())) return {n - 2, 1.0};
  const std::size_t i = static_cast<std::size_t>(std::upper_bound(x.begin(), x.end(), v) - x.begin()) - 1;
  return {i, (v - x[i]) / (x[i + 1] - x[i])};
}
}  // namespace

double DriftTable::operator()(double phi_value, double slip_over_ut) const {
  const auto [i, a] = bracket(phi, phi_value);
  const auto [j, b] = bracket(slip, slip_over_ut);
  const std::size_t ns = slip.size();
  const std::size_t i1 = phi.size() > 1 ? i + 1 : i, j1 = ns > 1 ? j + 1 : j;
  const double lo = (1.0 - b) * H[i * ns + j] + b * H[i * ns + j1];
  const double hi = (1.0 - b) * H[i1 * ns + j] + b * H[i1 * ns + j1];
  return std::clamp((1.0 - a) * lo + a * hi, -1.0, h_max);
}

double SplineCurves::h(double phi) const {
  const DragModel& m = *model;
  if (m.table) return std::clamp(m.h_spline(phi), -1.0, m.h_max);  // the spline clamps phi to its ends
  const double lo = m.phi_crit, hi = m.h_spline.upper();
  if (phi < lo) return std::clamp(m.h_spline(lo), 0.0, m.h_max) * std::max(phi, 0.0) / lo;
  return std::clamp(m.h_spline(std::min(phi, hi)), 0.0, m.h_max);
}

double SplineCurves::a(double phi) const {
  const DragModel& m = *model;
  if (m.table) return 0.0;
  return std::exp(std::clamp(m.log_a_spline(std::clamp(phi, m.phi_crit, m.log_a_spline.upper())), m.log_a_min, m.log_a_max));
}

FilteredDragSetup filtered_drag_setup(const Scene& scene, const Vec3& cell_spacing_m) {
  FilteredDragSetup setup;
  if (!scene.fluid || is_microscopic(scene.fluid->drag)) return setup;
  setup.filter_width_m =
      scene.fluid->filter_to_grid_ratio * std::cbrt(cell_spacing_m[0] * cell_spacing_m[1] * cell_spacing_m[2]);
  setup.l_char_m = scene.derived.l_char_m;
  setup.parcel_size = scene.particles.parcel_size;
  setup.parcel_correction = scene.fluid->parcel_correction;
  if ((scene.fluid->drag == DragLaw::Model || scene.fluid->drag == DragLaw::Drift) && scene.fluid->drag_model) {
    // read and checked against the scene by load_scene: nothing is read here
    setup.model = scene.fluid->drag_model;
    setup.warnings = model_calibration_warnings(*setup.model, setup.filter_width_m);
    int initialised = 0, rank = 0;
    MPI_Initialized(&initialised);
    if (initialised) MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    if (rank == 0)
      for (const std::string& w : setup.warnings) std::cerr << "warning: " << w << "\n";
  }
  check_filtered_setup(scene.fluid->drag, setup);
  return setup;
}

std::vector<std::string> model_calibration_warnings(const DragModel& m, double delta_m) {
  std::vector<std::string> out;
  const double d = m.diameter_m > 0 ? m.diameter_m : 1.0;
  if (m.calibration_operator == CalibrationOperator::Box) {
    out.push_back(m.path + " was calibrated with the particle-centred box filter (operator = \"box\"), but this run "
                  "sees phi, u and grad p through its grid's TSC deposit and interpolation, which filters like a box of "
                  "1.8-2.45 cells (docs/filter.md); its Delta = " + number(delta_m / d) + " d_p means a different filter than in the "
                  "calibration. Calibrate on the coarse grids' operator: cgd-filter --grids, cgd-fit --operator grid "
                  "(docs/fit.md)");
    return out;
  }
  if (m.calibrated_delta_m.empty()) return out;
  const auto [lo, hi] = std::minmax_element(m.calibrated_delta_m.begin(), m.calibrated_delta_m.end());
  if (m.table || m.drift) {
    if (std::abs(delta_m - *lo) > 1e-6 * *lo)
      out.push_back(m.path + (m.drift ? " is the drift table H(phi, cell slip)" : " is the a-priori H_grid table") +
                    " of the grid of " + std::to_string(m.table_cells_across) +
                    " cells across (cell " + number(*lo / d) + " d_p), but this run's Delta (its cell times fluid.filter_to_grid_ratio) is " + number(delta_m / d) +
                    " d_p: the table is applied unchanged (it has no width dependence)");
  } else if (delta_m < *lo * (1 - 1e-6) || delta_m > *hi * (1 + 1e-6)) {
    out.push_back(m.path + " was calibrated on coarse grids of cell " + number(*lo / d) + " to " + number(*hi / d) +
                  " d_p (operator grid), and this run's Delta (its cell times fluid.filter_to_grid_ratio) of " + number(delta_m / d) +
                  " d_p lies outside: the width dependence 1/(1 + a F^n) is extrapolated");
  }
  return out;
}

void check_filtered_setup(DragLaw law, const FilteredDragSetup& setup) {
  if (is_microscopic(law)) return;
  const std::string name = std::string("drag law \"") + to_string(law) + "\"";
  if (law == DragLaw::Model && !setup.model)
    throw InputError(name + " needs a model file (fluid.drag_model = \"PATH\" or --model PATH)");
  if (law == DragLaw::Drift && !setup.model)
    throw InputError(name + " needs a drift table (fluid.drag_model = \"PATH\" of cgd-fit --drift-table N)");
  if (law == DragLaw::Model && setup.model->drift)
    throw InputError(name + ": " + setup.model->path + " is a drift table (curves = \"drift_table\"), used with "
                     "fluid.drag = \"drift\"; \"model\" takes splines or a --grid-table table");
  if (law == DragLaw::Drift && !setup.model->drift)
    throw InputError(name + ": " + setup.model->path + " is not a drift table (curves = \"drift_table\" of cgd-fit "
                     "--drift-table N); a model of h(phi), a(phi) or a --grid-table table is used with fluid.drag = \"model\"");
  if (law == DragLaw::Drift && !(setup.model->u_t_m_s > 0))
    throw InputError(name + ": " + setup.model->path + " has no terminal velocity u_t > 0 (the drift table's slip unit)");
  if (!(setup.filter_width_m > 0.0))
    throw InputError(name + " needs the filter width Delta > 0 (cube root of the fluid cell volume), got " +
                     number(setup.filter_width_m));
  if (law == DragLaw::Radl2014 && !(setup.l_char_m > 0.0))
    throw InputError(name + " needs L_char > 0 (a fluid and gravity), got " + number(setup.l_char_m));
  if (!(setup.parcel_size >= 1.0))
    throw InputError(name + ": the parcel size alpha must be >= 1, got " + number(setup.parcel_size));
}

double beta_p(DragLaw law, const DragParams& params, const FilteredDragSetup& setup, double phi,
              double slip_speed) {
  return visit_any_drag_law(law, params, setup,
                            [&](const auto& drag) { return drag.beta_p(phi, slip_speed); });
}

namespace {

BSpline spline_of(const schema::SplineRecord& r) {
  BSpline s;
  s.order = r.order;
  s.knots = r.knots;
  s.coefficients = r.coefficients;
  return s;
}

}  // namespace

DragModel load_drag_model(const std::string& path) {
  const schema::DragModelFile file = schema::read_drag_model(path);  // validated there
  DragModel m;
  static_cast<PhysicalSystem&>(m) = file.system;
  m.path = path;
  m.u_t_convention = file.u_t_convention;
  m.phi_crit = file.phi_crit;
  m.h_spline = spline_of(file.h);
  m.log_a_spline = spline_of(file.log_a);
  m.log_a_min = file.log_a_min;
  m.log_a_max = file.log_a_max;
  m.h_max = file.h_max;
  m.width_exponent = file.width_exponent;
  m.c_corr_a = file.c_corr.a;
  m.c_corr_k = file.c_corr.k;
  m.c_corr_source = file.c_corr.source;
  m.calibration_operator = file.calibration_operator;
  m.calibrated_delta_m = file.calibrated_delta_m;
  m.table = file.curves == schema::ModelCurves::Table;
  m.table_cells_across = file.table_cells_across;
  m.drift = file.curves == schema::ModelCurves::DriftTable;
  if (m.drift && file.drift_table)
    m.drift_table = DriftTable{file.drift_table->phi, file.drift_table->slip, file.drift_table->H, file.h_max};
  m.code_version = file.code_version;
  m.created = file.created;
  m.calibrated_cells_across = file.calibrated_cells_across;
  m.source_files = file.source_files;
  m.source_checksums = file.source_checksums;
  m.provenance = file.provenance;
  if (file.bands) m.bands = DragModel::Bands{file.bands->phi, file.bands->F, file.bands->H_low, file.bands->H_high};
  m.checksum = file_checksum_fnv1a(path);
  return m;
}

void check_model_matches_scene(const DragModel& model, const Scene& scene) {
  const std::string where = model.path + " (model) and " + scene.source_path + " (scene)";
  if (!scene.fluid) throw InputError(where + ": the scene has no [fluid] section; a drag model needs one");
  if (const auto d = compare_systems(physical_system(scene, model.micro_drag), model, /*compare_law=*/false))
    throw InputError(where + " are for different particle/fluid systems: " + d->scene_key + " = " + d->first +
                     " in the scene, " + d->file_key + " = " + d->second +
                     " in the model file; fit a model for this system or use its scene");
}

}  // namespace cgd
