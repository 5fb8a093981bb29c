#pragma once
// The fitted model where users run coarse simulations (cgd-export; docs/export.md): a filtered drag model as the
// engine evaluates it (core/filtered_drag.hpp: SplineCurves of a cgd-fit model file, the table model of
// cgd-fit --grid-table, or Radl2014Curves) written as
//   NAME.h          a self-contained C99 header (only <math.h>): the coefficients, the provenance in a comment,
//                   and the functions h(phi), a(phi), H(phi, Delta) = h/(1 + a F^n), c_corr(alpha) and
//                   beta_bar/beta_micro = c_corr(alpha) [1 - H], with the engine's clamps and end behaviour;
//                   static inline by default, external C functions where NAME_IMPLEMENTATION is defined;
//   NAME.f90        a Fortran module of bind(C) interfaces to those functions (for MFiX's usr_drag and the like);
//   NAME_pieces.csv the curves in the piecewise-cubic local form c0 + c1 x + c2 x^2 + c3 x^3, x = phi - phi0,
//                   per interval (the form CFDEMcoupling-PFM's BeetstraDrag and MFiX hard-code Radl 2014 in);
//   NAME_H.csv      H over phi x Delta with the model file's 95 % bands where it has them.
// The splines are converted exactly (in exact arithmetic) from B-spline to local form: on each knot span
// [t_i, t_i+1) the coefficients are the right-hand derivatives c_m = S^(m)(t_i)/m!, computed from the
// derivative B-splines (de Boor, "A Practical Guide to Splines", ch. X: bsplpp). Evaluated by Horner's rule
// they agree with the engine's de Boor evaluation to round-off (tests/export/: 1e-12).
#include <functional>
#include <string>
#include <vector>

#include "core/filtered_drag.hpp"

namespace cgd::exporter {

/// One interval of a curve in local form: c[0] + c[1] x + c[2] x^2 + c[3] x^3, x = phi - phi0, on
/// phi_lo <= phi < phi_hi (the last interval also takes phi >= phi_hi).
struct LocalPiece {
  double phi_lo = 0, phi_hi = 0, phi0 = 0;
  double c[4] = {0, 0, 0, 0};
};

/// A curve as evaluated: the argument is clamped into [x_lo, x_hi], then the first piece with x < phi_hi (else
/// the last) is evaluated. For a B-spline: [x_lo, x_hi] = [t_{k-1}, t_n], as BSpline::operator() clamps.
struct LocalCurve {
  std::vector<LocalPiece> pieces;
  double x_lo = 0, x_hi = 1;
  double operator()(double x) const;
};

/// The local form of a B-spline of order 1..4 (one piece per non-empty knot span).
LocalCurve local_form(const BSpline& s);

/// Which rules turn the curves into h and a (core/filtered_drag.cpp: SplineCurves, Radl2014Curves).
enum class CurveKind { Splines, Table, Radl2014 };

/// Everything a header needs: the curves in local form, the constants and the provenance (comment lines).
struct ExportedModel {
  std::string name;  // C identifier part: functions cgd_<name>_..., macros CGD_<NAME>_...
  CurveKind kind = CurveKind::Splines;
  LocalCurve h;      // S_h (Splines, Table) or h (Radl2014)
  LocalCurve g;      // S_log_a (Splines) or a (Radl2014); empty for Table (a = 0)
  double l_char_m = 0, width_exponent = 1, phi_crit = 0.016, h_max = 0.99;
  double log_a_min = -HUGE_VAL, log_a_max = HUGE_VAL;
  double c_corr_a = 0, c_corr_k = 0.05;
  double diameter_m = 0;  // 0: unknown (--l-char-m without a scene)
  std::string micro_drag;  // the micro law beta_micro (not in the header)
  std::vector<double> calibrated_delta_m;
  std::vector<std::string> provenance;  // one line each, for the header's comment and the CSVs' heads
};

/// From a model file as load_drag_model read it. `provenance` lines are added after the ones made here.
ExportedModel from_model(const DragModel& m, const std::string& name, const std::vector<std::string>& provenance);
/// The published Radl & Sundaresan 2014 curves at a run's L_char (Radl2014Curves: base law Beetstra,
/// c_corr a_c = 0, k_c = 0.05, n = 1).
ExportedModel from_radl2014(double l_char_m, double diameter_m, const std::string& name,
                            const std::vector<std::string>& provenance);

std::string c_header(const ExportedModel& e);
std::string fortran_module(const ExportedModel& e);
std::string pieces_csv(const ExportedModel& e);

/// The 95 % bands of a model file (/bands: H_low, H_high at its phi grid and its F), F-major.
struct Bands {
  std::vector<double> phi, F, H_low, H_high;
};
/// H over phi x Delta from `H_of(phi, delta_m)` (the engine's evaluator), with the bands where (phi, L_char/Delta)
/// is a point of `bands` (same phi, F to 1e-9), else empty band cells.
std::string h_table_csv(const ExportedModel& e, const std::function<double(double, double)>& H_of,
                        const std::vector<double>& phis, const std::vector<double>& deltas_m, const Bands* bands);

/// The engine's H(phi, Delta) = h/(1 + a F^n) of a model (or of Radl 2014 when `model` is null, at `l_char_m`),
/// through visit_any_drag_law as a coarse run sets it up.
double engine_H(const DragModel* model, double l_char_m, double phi, double delta_m);

/// Where a clamp of the h curve is active inside [x_lo, x_hi] (sampled every 1e-5 in phi), as text ("none" or
/// "S_h > h_max on [0.016, 0.0213]; ..."), for the comments.
std::string clamp_report(const ExportedModel& e);

}  // namespace cgd::exporter
