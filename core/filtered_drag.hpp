#pragma once
// Filtered (coarse-grid) drag laws as evaluators, like the microscopic laws of core/drag.hpp.
//
// Model (Radl & Sundaresan 2014, Chem. Eng. Sci. 117:416, the journal version of the paper's eqs. 6-9;
// docs/models.md, "Filtered drag model"):
//   beta_bar_p = c_corr(alpha) [1 - h(phi) / (1 + a(phi) F^n)] beta_p,micro(phi, |u - v|),
//   F = L_char / Delta,   Delta = cube root of the fluid cell volume of the run using the law,
//   n = 1 (the paper's form; Radl2014Curves) or the exponent fitted by cgd-fit (--width-exponent fit),
//   c_corr(alpha) = a_c + (1 - a_c) exp(-k_c (alpha - 1)),   alpha = d_parcel / d_prim,
// phi the solids fraction at the particle, L_char = (u_t^2/g) Fr_p^(-2/3) with docs/models.md's u_t
// (Schiller-Naumann). The correction factor depends on phi only, not on the slip, so the filtered
// law keeps every property of its microscopic base law that the engine relies on (beta_p w increasing
// in w; beta_p(w) >= beta_p(0)), and 0 < beta_bar <= beta_micro when 0 <= h < 1, a > 0, alpha >= 1,
// 0 <= a_c <= 1, k_c >= 0 (a parcel fit may give k_c < 0, c_corr > 1: beta_bar above beta_micro, which the
// engine's stability bound sees, since it evaluates this law).
//
// Two sources of the master curves h(phi), a(phi):
//   Radl2014Curves  the published piecewise cubics (data/reference/radl2014-filtered-drag.csv), base
//                   law Beetstra, c_corr with the paper's a_c = 0, k_c = 0.05;
//   SplineCurves    a model file written by cgd-fit (docs/schema-drag-model.md): B-splines of h and
//                   log a with their extensions below phi_crit and above the fitted range.
// Hot loops choose the law once with visit_any_drag_law (no virtual call per particle).
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/checksum.hpp"
#include "core/drag.hpp"
#include "core/physical_system.hpp"
#include "core/schema/calibration.hpp"  // CalibrationOperator
#include "core/scene.hpp"

namespace cgd {

/// Parcel-size correction of the paper's eq. 9: c_corr = a_c + (1 - a_c) exp(-k_c (alpha - 1)).
/// (Radl & Sundaresan 2014, proceedings paper, eq. 9; paper values a_c = 0, k_c = 0.05.)
double parcel_correction(double alpha, double a_c, double k_c);

/// The published master curves of Radl & Sundaresan (2014), as implemented in MFiX (drag_gs.f,
/// DRAG_RADL) and CFDEMcoupling-PFM (forceModel BeetstraDrag): piecewise cubics in x = phi - phi0,
/// value = c0 + c1 x + c2 x^2 + c3 x^3 on phi_lo <= phi < phi_hi. The two implementations disagree
/// in one coefficient, a(phi) on 0.25-0.40: c1 = -8.82 (MFiX) or -8.20 (CFDEMcoupling-PFM). This code
/// uses c1 = -8.82, as data/reference/radl2014-filtered-drag.csv does: it keeps a(phi) continuous at
/// 0.40 (1.785 against the next piece's 1.79; -8.20 would jump 1.878 -> 1.79). Kept as published:
/// a(phi) jumps at phi_crit = 0.016 (21.51 -> 1.96 + 29.4 * 0.016 + ... = 2.465), h = 7.97 phi below
/// 0.03 and h = 0 at phi >= 0.60. phi outside [0, 1) is clamped into it.
struct Radl2014Curves {
  static constexpr double kPhiCrit = 0.016;
  static constexpr double kCcorrA = 0.0, kCcorrK = 0.05;  // the paper's c_corr parameters
  double h(double phi) const;
  double a(double phi) const;
  /// One piece as evaluated: c0 + c1 x + c2 x^2 + c3 x^3, x = phi - phi0, on phi_lo <= phi < phi_hi (the
  /// last piece also takes phi >= phi_hi). For the exporter (fit/export_model.hpp).
  struct Piece {
    double phi_lo, phi_hi, phi0, c0, c1, c2, c3;
  };
  static std::vector<Piece> h_pieces();
  static std::vector<Piece> a_pieces();
};

/// A B-spline s(x) = sum_j c_j B_j,k(x) of order k (degree k - 1) on the full knot vector t
/// (n + k knots, non-decreasing, the first and last k equal: clamped), evaluated with de Boor's
/// algorithm. x outside [t_{k-1}, t_n] is clamped into it. The same numbers evaluated with numpy's
/// de Boor (docs/schema-drag-model.md) give the same value to round-off.
struct BSpline {
  int order = 4;                     // k
  std::vector<double> knots;         // t, size n + k
  std::vector<double> coefficients;  // c, size n
  double operator()(double x) const;
  double lower() const { return knots[static_cast<std::size_t>(order - 1)]; }
  double upper() const { return knots[coefficients.size()]; }
};

/// The table of the drift-velocity closure (DragLaw::Drift; a model file with curves = "drift_table", written by
/// cgd-fit --drift-table N; docs/schema-drag-model.md "/drift_table"): H on the bin centres phi_k (filtered solids
/// fraction) and s_m (the cell slip |u~ - vbar| in units of u_t), row-major (n_phi, n_slip). Evaluated bilinearly,
/// held constant outside the table (phi and s clamped to its ends), the result clamped to [-1, h_max] as the
/// --grid-table table is.
struct DriftTable {
  std::vector<double> phi;   // ascending, at least one
  std::vector<double> slip;  // ascending, at least one, in u_t
  std::vector<double> H;     // phi.size() x slip.size(), row-major
  double h_max = 0.99;
  /// H(phi, s_hat): bilinear in (phi, s_hat) between the bin centres, constant beyond the ends, clamped.
  double operator()(double phi_value, double slip_over_ut) const;
};

/// A drag model file (cgd_format = "drag_model", docs/schema-drag-model.md) as read by
/// load_drag_model: what the evaluator needs and what a run checks against its own scene. It extends
/// the physical system it was made for (core/physical_system.hpp: d, densities, viscosity, |g|, u_t,
/// L_char, and the base law as micro_drag, stored as `base_drag`).
struct DragModel : PhysicalSystem {
  std::string path;      // as given
  std::string checksum;  // FNV-1a 64-bit of the file's bytes, 16 hex digits
  std::string u_t_convention;  // "schiller-naumann" (docs/models.md)
  double phi_crit = 0.016;
  BSpline h_spline;         // h on [phi_crit, phi_max] (identity, clamped to [0, h_max])
  BSpline log_a_spline;     // log a on [phi_crit, phi_max]
  // the range of log a the per-bin fits identified (attributes log_a_min, log_a_max; absent in older
  // files: no bound): a = exp(clamp(S(phi), log_a_min, log_a_max)), so the spline's ends cannot run away
  // where the bins carry little weight on a (docs/fit.md "Low phi")
  double log_a_min = -HUGE_VAL, log_a_max = HUGE_VAL;
  double h_max = 0.99;      // upper clamp of h (h < 1 keeps beta_bar > 0)
  double width_exponent = 1;  // n of the width dependence 1/(1 + a F^n); 1 = Radl & Sundaresan's form
  double c_corr_a = 0.0, c_corr_k = 0.05;
  std::string c_corr_source;  // "paper" (Radl & Sundaresan 2014) or "parcel-fit"
  // What the model was calibrated for (docs/schema-drag-model.md "Calibration"): the particle-centred box
  // filter of width Delta (files without the attribute) or H_grid of coarse grids, the TSC deposit+interpolate
  // operator of the grid a coarse run uses, Delta = its cell size.
  CalibrationOperator calibration_operator = CalibrationOperator::Box;
  std::vector<double> calibrated_delta_m;  // the Delta (box widths or grid cell sizes) fitted; may be empty
  // curves = "table" (cgd-fit --grid-table N): h is the piecewise-linear table of H_grid of one grid
  // (the order-2 B-spline /h through (phi_k, H_k)), held constant outside it, clamped to [-1, h_max], with
  // no phi_crit rule, and a = 0: the correction is 1 - H_grid(phi) at any Delta (meant for grid N's Delta).
  bool table = false;
  std::int64_t table_cells_across = 0;  // the grid of a table or drift table (cells across x)
  // curves = "drift_table" (cgd-fit --drift-table N): the drift-velocity closure's H(phi, cell slip) of one grid, for
  // fluid.drag = "drift" only (DriftDrag); h_spline then holds the phi-only H_grid of the same grid (the table's
  // fallback rows), not used by the law. fluid.drag = "model" refuses such a file, and "drift" any other.
  bool drift = false;
  DriftTable drift_table;

  // Read for cgd-export, not used by the law: where the file came from and the 95 % bands of H.
  std::string code_version, created;
  std::vector<std::int64_t> calibrated_cells_across;
  std::vector<std::string> source_files, source_checksums;         // /sources: the filtered files fitted
  std::vector<std::pair<std::string, std::string>> provenance;     // /provenance: made_by, resolved_runs, ...
  struct Bands {                                                    // /bands (empty: table models, older files)
    std::vector<double> phi, F, H_low, H_high;                      // H_low, H_high of shape (len(F), len(phi))
  } bands;
};

/// Warnings for a run with filter width `delta_m` (the cube root of its cell volume) using `model`:
/// calibrated for the box filter (a coarse run applies its grid's TSC operator, which filters like a
/// box of ~2.45 cells), or for grids whose cell sizes do not bracket delta_m, or a table of another
/// grid's cell. Empty when the calibration fits the run.
std::vector<std::string> model_calibration_warnings(const DragModel& model, double delta_m);

/// Master curves of a fitted model (docs/schema-drag-model.md, "Evaluating h and a"):
///   h(phi) = clamp(S_h(phi), 0, h_max)                  for phi_crit <= phi <= phi_max,
///          = h(phi_crit) * max(phi, 0) / phi_crit        for phi < phi_crit (linear to 0, the paper's
///                                                        suggestion), h(phi_max) above phi_max;
///   a(phi) = exp(clamp(S_log_a(clamp(phi, phi_crit, phi_max)), log_a_min, log_a_max))   (> 0, continuous,
///            constant outside; log_a_min/max the range the per-bin fits identified, when the file has them).
/// phi_max is the upper end of the splines' knot vectors.
struct SplineCurves {
  const DragModel* model = nullptr;
  double h(double phi) const;
  double a(double phi) const;
};

/// A filtered drag law: the correction of the file's header times the microscopic base law.
/// `params` are the base law's (rho_f, mu_f, primary d), so homogeneous_slip_speed() works on it.
template <class Micro, class Curves>
struct FilteredDrag {
  using Params = DragParams;
  Params params;
  Micro micro;
  Curves curves;
  double filter_term = 0;  // F^n, F = L_char / Delta (n = 1 for Radl 2014)
  double c_corr = 1;       // c_corr(alpha)

  FilteredDrag(const Micro& base, const Curves& c, double F_to_n, double parcel_corr)
      : params(base.params), micro(base), curves(c), filter_term(F_to_n), c_corr(parcel_corr) {}

  /// beta_bar / beta_micro (dimensionless) at solids fraction phi.
  double correction(double phi) const {
    return c_corr * (1.0 - curves.h(phi) / (1.0 + curves.a(phi) * filter_term));
  }
  double reynolds(double phi, double slip_speed) const { return micro.reynolds(phi, slip_speed); }
  double beta_p(double phi, double slip_speed) const {
    return correction(phi) * micro.beta_p(phi, slip_speed);
  }
};

/// The drift-velocity closure (DragLaw::Drift; the equation, its sources and its use by the coupler: core/drag.hpp
/// above the law table, sim/coupling/coupler.hpp). beta_p is the micro law's coefficient at the particle's own slip
/// |u~_i - v_i|, which multiplies the whole force F_i = V_i beta_p [(u~_i - v_i) - H s~_i]; cell_slip_correction
/// is H(phi_i, |s~_i| / u_t) of the model's drift table. In a uniform suspension (every particle moving with its
/// cell's mean, s~_i = u~_i - v_i) the force is (1 - H) beta_p (u~_i - v_i): the phi-only table law with that H.
/// c_corr(alpha) does not enter (the table is the grid's closure alone, as a --grid-table table).
template <class Micro>
struct DriftDrag {
  using Params = DragParams;
  Params params;
  Micro micro;
  const DriftTable* table = nullptr;
  double inv_u_t = 0;  // 1 / u_t (docs/models.md convention: the Schiller-Naumann u_t of the model = the run's)

  DriftDrag(const Micro& base, const DriftTable* t, double u_t)
      : params(base.params), micro(base), table(t), inv_u_t(1.0 / u_t) {}

  double reynolds(double phi, double slip_speed) const { return micro.reynolds(phi, slip_speed); }
  /// The micro law's beta_p at the particle's own slip (relaxes the whole slip; the H part is subtracted).
  double beta_p(double phi, double slip_speed) const { return micro.beta_p(phi, slip_speed); }
  /// H(phi, |s~| / u_t), the correction of the cell-mean part s~ of the slip, |s~| = cell_slip_speed in m/s.
  double cell_slip_correction(double phi, double cell_slip_speed) const {
    return (*table)(phi, cell_slip_speed * inv_u_t);
  }
};

/// True for the drift-velocity law's evaluator (the coupler's cell-slip path).
template <class Law>
inline constexpr bool is_drift_drag = requires(const Law& law) { law.cell_slip_correction(0.0, 0.0); };

/// What a filtered law needs besides DragParams, fixed for a run: the model file (for
/// DragLaw::Model and DragLaw::Drift), the filter width Delta and L_char that give F, and the parcel size alpha.
struct FilteredDragSetup {
  std::shared_ptr<const DragModel> model;  // required for DragLaw::Model (splines or table) and Drift (drift table)
  double filter_width_m = 0;               // Delta: fluid.filter_to_grid_ratio x cube root of the cell volume
  double l_char_m = 0;                     // L_char of the run (docs/models.md convention)
  double parcel_size = 1;                  // alpha
  bool parcel_correction = true;           // false: c_corr = 1 (fluid.parcel_correction = false)
  std::vector<std::string> warnings;       // model_calibration_warnings (printed by filtered_drag_setup)
};

/// The setup of a run's drag law from its scene, built once before the engine starts: for drag = "model"
/// the model load_scene read and checked (FluidConfig::drag_model; nothing is read here) and its
/// calibration against the run's Delta (model_calibration_warnings: kept in `warnings` and printed once
/// on stderr, by rank 0 of MPI_COMM_WORLD); Delta = fluid.filter_to_grid_ratio r times the cube root of the
/// cell volume (cell_spacing_m; r = 1, the paper's Delta = the cell, unless the scene says otherwise),
/// L_char from the scene's derived scales, alpha = particles.parcel_size. Microscopic laws get an
/// empty setup. InputError (check_filtered_setup) when the setup is incomplete.
FilteredDragSetup filtered_drag_setup(const Scene& scene, const Vec3& cell_spacing_m);

/// InputError unless `setup` is complete for `law` (model present for Model and Drift, a drift table for Drift and
/// none for Model, Delta, L_char > 0, alpha >= 1). Micro laws need nothing.
void check_filtered_setup(DragLaw law, const FilteredDragSetup& setup);

/// Like visit_drag_law, for every law including the filtered ones: chooses the evaluator once and
/// calls visit(evaluator). For Drift, DriftDrag of the model's micro law and drift table. For Radl2014 the base law is Beetstra (the published model's) and c_corr
/// uses the paper's a_c = 0, k_c = 0.05; for Model, the file's base law, L_char and c_corr. F is
/// setup.l_char_m / setup.filter_width_m for Radl2014 and model->l_char_m / filter_width_m for Model
/// (the model's L_char equals the run's when check_model_matches_scene passed), raised to the file's
/// width_exponent.
template <class Visitor>
decltype(auto) visit_any_drag_law(DragLaw law, const DragParams& params, const FilteredDragSetup& setup,
                                  Visitor&& visit) {
  if (law == DragLaw::Radl2014) {
    check_filtered_setup(law, setup);
    const double F = setup.l_char_m / setup.filter_width_m;
    const double corr = setup.parcel_correction ? parcel_correction(setup.parcel_size, Radl2014Curves::kCcorrA,
                                                                    Radl2014Curves::kCcorrK)
                                                : 1.0;
    return visit(FilteredDrag<BeetstraDrag, Radl2014Curves>(BeetstraDrag(params), Radl2014Curves{}, F, corr));
  }
  if (law == DragLaw::Model) {
    check_filtered_setup(law, setup);
    const DragModel& m = *setup.model;
    const double F_to_n = std::pow(m.l_char_m / setup.filter_width_m, m.width_exponent);
    const double corr = setup.parcel_correction ? parcel_correction(setup.parcel_size, m.c_corr_a, m.c_corr_k) : 1.0;
    const SplineCurves curves{&m};
    return visit_drag_law(m.micro_drag, params, [&](const auto& micro) {
      return visit(FilteredDrag<std::decay_t<decltype(micro)>, SplineCurves>(micro, curves, F_to_n, corr));
    });
  }
  if (law == DragLaw::Drift) {
    check_filtered_setup(law, setup);
    const DragModel& m = *setup.model;
    return visit_drag_law(m.micro_drag, params, [&](const auto& micro) {
      return visit(DriftDrag<std::decay_t<decltype(micro)>>(micro, &m.drift_table, m.u_t_m_s));
    });
  }
  return visit_drag_law(law, params, std::forward<Visitor>(visit));
}

/// beta_p of any law (kg m^-3 s^-1), for code that is not hot.
double beta_p(DragLaw law, const DragParams& params, const FilteredDragSetup& setup, double phi,
              double slip_speed);

/// Read a model file: read and validated by its schema (core/schema/drag_model.hpp: InputError naming the
/// file and the attribute or dataset), then held as the evaluator needs it. Reads on the calling process
/// only (MPI_COMM_SELF).
DragModel load_drag_model(const std::string& path);

/// InputError naming `model.path`, the scene's file and the differing key, unless the model was made
/// for the scene's particle/fluid system (compare_systems of core/physical_system.hpp without the law:
/// particles.diameter, particles.density, fluid.density, fluid.viscosity, |domain.gravity|, and the
/// derived u_t and L_char, relative 1e-6).
void check_model_matches_scene(const DragModel& model, const Scene& scene);


}  // namespace cgd
