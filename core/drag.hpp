#pragma once
// Microscopic drag laws (docs/models.md, "Drag laws") as evaluators: each is a small struct
// built from its parameters with two inline, non-virtual methods,
//   reynolds(phi, slip_speed)  particle Reynolds number of the law (dimensionless),
//   beta_p(phi, slip_speed)    per-particle drag coefficient, kg m^-3 s^-1,
// in the per-particle convention of docs/models.md (the paper's eq. 3):
//   F_d,i = V_p beta_p,i (u_i - v_i),   eps = 1 - phi,   two-fluid beta = phi beta_p.
// phi is the solids volume fraction at the particle (0 <= phi < 1); slip_speed = |u - v| in m/s
// (its sign is ignored). The same evaluator serves the generator, the filter's normalisation and
// the coarse runner; hot loops choose the law once with visit_drag_law and call the evaluator
// inline. For parcels, beta_p is evaluated with the primary diameter (docs/models.md, "Parcels").
#include <cmath>
#include <functional>
#include <numbers>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>

// ---- The drag-law table ------------------------------------------------------------------------
// One row a law: X(enum value, name in scenes and files, kind, evaluator, what it is). Everything that
// names or chooses a law is derived from it: the enum DragLaw, to_string(DragLaw), drag_law_from_name
// and microscopic_drag_law (the filter, the fit, the model file's base_drag), the allowed values of the
// scene's fluid.drag, the messages that list the laws (drag_law_names), and visit_drag_law. A micro law
// names its evaluator struct (below); a filtered law (kind Filtered) names `void`: it is evaluated by
// visit_any_drag_law in core/filtered_drag.hpp from a model's curves on top of a micro law. The order of
// the rows is the order the laws are offered in messages; the first is the scene's default.
// Adding a microscopic law (docs/howto.md "A new drag law"): its evaluator struct below, one row here,
// and its rows in docs/models.md and docs/scene-keys.md (tests/unit/test_drag.cpp checks the docs).
//
// The filtered law "drift" (issue 28; docs/closure.md "The drift-velocity closure", docs/models.md "Filtered
// drag models") is the drift-velocity (two-marker) closure, evaluated by DriftDrag (core/filtered_drag.hpp) and
// applied by the coupler (sim/coupling/coupler.hpp). Per particle (or parcel) i of a coarse run, with the TSC
// weights w_ic of its grid:
//   vbar_c = sum_i V_i w_ic v_i / sum_i V_i w_ic   (the cell's mean particle velocity; a cell with no deposit: u_c),
//   vbar_i = sum_c w_ic vbar_c,   s~_i = u~_i - vbar_i (the cell slip),   s^_i = |s~_i| / u_t,
//   F_i = V_i beta_micro(phi_i, |u~_i - v_i|) [ (u~_i - v_i) - H(phi_i, s^_i) s~_i ],
// so the cell-mean part of the slip gets the reduced drag (1 - H) beta_micro and the particle's deviation from its
// cell's mean, vbar_i - v_i, the full micro drag (parcel fluctuations stay damped). H(phi, s^) is the table of a
// model file with curves = "drift_table" (cgd-fit --drift-table N): bilinear on its bin centres, held constant
// outside, clamped to [-1, h_max]. The sub-grid drift form of Parmentier, Simonin & Delsart (2012, AIChE J.
// 58:1084) and Ozel, Gu, Milioli, Kolehmainen & Sundaresan (2017, Phys. Fluids 29:103308), with the
// filtered slip as the second marker of Milioli, Milioli, Holloway, Agrawal & Sundaresan (2013, AIChE J.
// 59:3265), who found the filtered drag correction growing with the slip.
#define CGD_DRAG_LAWS(X)                                                                                \
  X(Beetstra, "beetstra", Micro, BeetstraDrag, "Beetstra, van der Hoef & Kuipers (2007)")               \
  X(WenYu, "wen-yu", Micro, WenYuDrag, "Wen & Yu (1966)")                                               \
  X(Stokes, "stokes", Micro, StokesDrag, "Stokes drag on a single sphere")                              \
  X(Radl2014, "radl2014", Filtered, void, "Radl & Sundaresan (2014), the published master curves")      \
  X(Model, "model", Filtered, void, "a model file written by cgd-fit (fluid.drag_model = PATH)")        \
  X(Drift, "drift", Filtered, void,                                                                     \
    "the drift-velocity closure H(phi, cell slip): a drift table of cgd-fit --drift-table (fluid.drag_model = PATH)")

namespace cgd {

#define CGD_DRAG_LAW_ENUM(id, name, kind, evaluator, what) id,
/// The drag laws of the table CGD_DRAG_LAWS, in its order.
enum class DragLaw { CGD_DRAG_LAWS(CGD_DRAG_LAW_ENUM) };
#undef CGD_DRAG_LAW_ENUM

/// Micro: evaluated from DragParams alone (core/drag.hpp). Filtered: a coarse-grid law that needs a
/// model (core/filtered_drag.hpp), refused by resolved runs.
enum class DragKind { Micro, Filtered };

/// One row of the drag-law table.
struct DragLawInfo {
  DragLaw law;
  const char* name;  // as scenes and files spell it
  DragKind kind;
  const char* what;  // a few words for messages and docs
};

#define CGD_DRAG_LAW_INFO(id, name, kind, evaluator, what) DragLawInfo{DragLaw::id, name, DragKind::kind, what},
/// The drag-law table as data, in its order.
inline constexpr DragLawInfo kDragLaws[] = {CGD_DRAG_LAWS(CGD_DRAG_LAW_INFO)};
#undef CGD_DRAG_LAW_INFO

/// The table's row of `law`.
constexpr const DragLawInfo& drag_law_info(DragLaw law) { return kDragLaws[static_cast<int>(law)]; }
/// The law's name in scenes and files ("beetstra", "wen-yu", ...).
constexpr const char* to_string(DragLaw law) { return drag_law_info(law).name; }
constexpr bool is_microscopic(DragLaw law) { return drag_law_info(law).kind == DragKind::Micro; }

/// The law of a name as scenes and files spell it, of any kind; nullopt for an unknown name.
std::optional<DragLaw> drag_law_from_name(std::string_view name);

/// The names of the laws of `kind`, in the table's order, quoted and joined by ", ":
/// "\"beetstra\", \"wen-yu\", \"stokes\"" for DragKind::Micro. For messages that list what is allowed.
std::string drag_law_names(DragKind kind);
/// Every law's name, quoted and joined by ", ", in the table's order.
std::string drag_law_names();

/// Parameters shared by every microscopic law.
struct DragParams {
  double rho_f = 0;  // fluid density, kg/m^3
  double mu_f = 0;   // fluid dynamic viscosity, Pa s
  double d = 0;      // particle (primary) diameter, m
};

/// Stokes drag on a single sphere (Stokes 1851):
///   F_d = 3 pi mu_f d (u - v)   =>   beta_p = 18 mu_f / d^2,
/// independent of phi and Re (no hindrance by neighbours, no inertia). reynolds() is the
/// single-particle Re = rho_f d |u - v| / mu_f, for information only.
struct StokesDrag {
  using Params = DragParams;
  Params params;

  explicit StokesDrag(const Params& p) : params(p), stokes_beta_(18.0 * p.mu_f / (p.d * p.d)) {}
  StokesDrag(double rho_f, double mu_f, double d) : StokesDrag(Params{rho_f, mu_f, d}) {}

  double reynolds(double /*phi*/, double slip_speed) const {
    return params.rho_f * params.d * std::abs(slip_speed) / params.mu_f;
  }
  double beta_p(double /*phi*/, double /*slip_speed*/) const { return stokes_beta_; }
  /// The force per unit slip on one particle, 3 pi mu_f d (kg/s): F_d = force_per_slip() (u - v). The
  /// quiescent-fluid drive (sim/run.cpp) divides it by the particle mass for its linear drag rate.
  double force_per_slip() const { return 3.0 * std::numbers::pi * params.mu_f * params.d; }

 private:
  double stokes_beta_;  // 18 mu_f / d^2, kg m^-3 s^-1
};

/// Schiller & Naumann (1933, Z. Ver. Dtsch. Ing. 77:318) for a single sphere in unbounded fluid:
///   Re = rho_f d |u - v| / mu_f,   C_d = 24/Re (1 + 0.15 Re^0.687),
///   beta_p = (3/4) C_d rho_f |u - v| / d = 18 mu_f / d^2 (1 + 0.15 Re^0.687),
/// independent of phi; fitted for Re <~ 800 (no Newton-regime cap). This is the law of the
/// reference terminal velocity u_t (docs/models.md, core/scales.hpp).
struct SchillerNaumannDrag {
  using Params = DragParams;
  Params params;

  explicit SchillerNaumannDrag(const Params& p) : params(p), stokes_beta_(18.0 * p.mu_f / (p.d * p.d)) {}
  SchillerNaumannDrag(double rho_f, double mu_f, double d) : SchillerNaumannDrag(Params{rho_f, mu_f, d}) {}

  double reynolds(double /*phi*/, double slip_speed) const {
    return params.rho_f * params.d * std::abs(slip_speed) / params.mu_f;
  }
  double beta_p(double phi, double slip_speed) const {
    return stokes_beta_ * (1.0 + 0.15 * std::pow(reynolds(phi, slip_speed), 0.687));
  }

 private:
  double stokes_beta_;  // 18 mu_f / d^2, kg m^-3 s^-1
};

/// Wen & Yu (1966, Chem. Eng. Prog. Symp. Ser. 62:100), as written in docs/models.md:
///   Re = eps rho_f d |u - v| / mu_f,
///   C_d = 24/Re (1 + 0.15 Re^0.687) for Re <= 1000, else 0.44,
///   beta_p = (3/4) C_d rho_f eps |u - v| eps^-2.65 / d.
/// For Re <= 1000 the eps |u - v| of beta_p cancels against the one in Re:
///   beta_p = 18 mu_f eps^-2.65 / d^2 (1 + 0.15 Re^0.687),
/// which is how it is evaluated, so |u - v| -> 0 is exact and finite: beta_p -> 18 mu_f eps^-2.65 / d^2.
/// At phi = 0 it is Schiller-Naumann (for Re <= 1000). C_d jumps at Re = 1000 by the factor
/// 0.44 / C_d(1000) = 1.0039 (the published law is not continuous there).
struct WenYuDrag {
  using Params = DragParams;
  Params params;

  explicit WenYuDrag(const Params& p)
      : params(p), stokes_beta_(18.0 * p.mu_f / (p.d * p.d)), re_per_slip_(p.rho_f * p.d / p.mu_f) {}
  WenYuDrag(double rho_f, double mu_f, double d) : WenYuDrag(Params{rho_f, mu_f, d}) {}

  double reynolds(double phi, double slip_speed) const {
    return (1.0 - phi) * re_per_slip_ * std::abs(slip_speed);
  }
  double beta_p(double phi, double slip_speed) const {
    const double eps = 1.0 - phi;
    const double re = reynolds(phi, slip_speed);
    const double hindrance = std::pow(eps, -2.65);
    if (re <= 1000.0) return stokes_beta_ * hindrance * (1.0 + 0.15 * std::pow(re, 0.687));
    return 0.75 * 0.44 * params.rho_f * eps * std::abs(slip_speed) * hindrance / params.d;  // Newton regime
  }

 private:
  double stokes_beta_;  // 18 mu_f / d^2, kg m^-3 s^-1
  double re_per_slip_;  // rho_f d / mu_f, s/m
};

/// Beetstra, van der Hoef & Kuipers (2007, AIChE J. 53:489), monodisperse, as written in docs/models.md:
///   Re = eps rho_f d |u - v| / mu_f,
///   F(phi, Re) = 10 phi/eps^2 + eps^2 (1 + 1.5 sqrt(phi))
///              + [0.413 Re / (24 eps^2)] (1/eps + 3 eps phi + 8.4 Re^-0.343)
///                / (1 + 10^(3 phi) Re^(-(1 + 4 phi)/2)),
///   F_d = 3 pi mu_f d eps F (u - v)  (model A: excludes -V_p grad p)   =>   beta_p = 18 mu_f eps F / d^2.
/// The last term is 0 * inf at Re = 0; it is evaluated multiplied through by Re^a, a = (1 + 4 phi)/2:
///   [0.413 / (24 eps^2)] (Re (1/eps + 3 eps phi) + 8.4 Re^0.657) Re^a / (Re^a + 10^(3 phi)),
/// which is finite and tends to 0 like Re^(1.157 + 2 phi); valid for Re < ~1e100 (Re^a must not overflow).
/// Limits: F(0, 0) = 1 (Stokes); F(phi, 0) = 10 phi/eps^2 + eps^2 (1 + 1.5 sqrt(phi)).
struct BeetstraDrag {
  using Params = DragParams;
  Params params;

  explicit BeetstraDrag(const Params& p)
      : params(p), stokes_beta_(18.0 * p.mu_f / (p.d * p.d)), re_per_slip_(p.rho_f * p.d / p.mu_f) {}
  BeetstraDrag(double rho_f, double mu_f, double d) : BeetstraDrag(Params{rho_f, mu_f, d}) {}

  /// The dimensionless drag force F(phi, Re) = F_d / (3 pi mu_f d eps |u - v|).
  static double normalized_force(double phi, double re) {
    const double eps = 1.0 - phi;
    const double eps2 = eps * eps;
    const double viscous = 10.0 * phi / eps2 + eps2 * (1.0 + 1.5 * std::sqrt(phi));
    const double re_a = std::pow(re, 0.5 + 2.0 * phi);
    const double inertial = 0.413 / (24.0 * eps2) *
                            (re * (1.0 / eps + 3.0 * eps * phi) + 8.4 * std::pow(re, 0.657)) * re_a /
                            (re_a + std::pow(10.0, 3.0 * phi));
    return viscous + inertial;
  }

  double reynolds(double phi, double slip_speed) const {
    return (1.0 - phi) * re_per_slip_ * std::abs(slip_speed);
  }
  double beta_p(double phi, double slip_speed) const {
    return stokes_beta_ * (1.0 - phi) * normalized_force(phi, reynolds(phi, slip_speed));
  }

 private:
  double stokes_beta_;  // 18 mu_f / d^2, kg m^-3 s^-1
  double re_per_slip_;  // rho_f d / mu_f, s/m
};

/// The microscopic law of a name as files and scenes spell it (a row of kind Micro in CGD_DRAG_LAWS);
/// nullopt for any other name, the filtered laws ("radl2014", "model", "drift") included.
std::optional<DragLaw> microscopic_drag_law(std::string_view name);

/// Throws InputError: `law` (kind Filtered) is a filtered model, which needs a model file and
/// cannot be built from DragParams alone.
[[noreturn]] void throw_drag_law_needs_model(DragLaw law);

namespace detail {
template <class Evaluator, class Visitor>
decltype(auto) visit_evaluator(const DragParams& params, Visitor&& visit) {
  return visit(Evaluator(params));
}
}  // namespace detail

/// Chooses the microscopic evaluator for `law` once (the table's evaluator column) and calls
/// visit(evaluator); use it outside hot loops, e.g.
/// visit_drag_law(law, p, [&](const auto& drag) { loop calling drag.beta_p(...); }).
/// Throws InputError for the filtered laws (use visit_any_drag_law, core/filtered_drag.hpp).
template <class Visitor>
decltype(auto) visit_drag_law(DragLaw law, const DragParams& params, Visitor&& visit) {
#define CGD_DRAG_LAW_CASE(id, name, kind, evaluator, what)                                  \
  case DragLaw::id:                                                                         \
    if constexpr (DragKind::kind == DragKind::Micro)                                        \
      return detail::visit_evaluator<evaluator>(params, std::forward<Visitor>(visit));      \
    break;
  switch (law) { CGD_DRAG_LAWS(CGD_DRAG_LAW_CASE) }
#undef CGD_DRAG_LAW_CASE
  throw_drag_law_needs_model(law);
}

/// beta_p of `law` (kg m^-3 s^-1) chosen at run time, for code that is not hot. Throws InputError
/// for the filtered laws (DragLaw::Radl2014, Model, Drift: "needs a filtered model file").
double beta_p(DragLaw law, const DragParams& params, double phi, double slip_speed);

namespace detail {
/// Root w >= 0 of beta_p_of_slip(w) w = eps (rho_p - rho_f) g (bracketed, GSL Brent, 1e-14 relative).
/// Requires beta_p(w) w increasing in w and beta_p(w) >= beta_p(0). Throws InputError for phi outside
/// [0, 1), rho_p <= rho_f, g <= 0 or non-positive DragParams.
double settling_slip_speed(const std::function<double(double)>& beta_p_of_slip, const DragParams& params,
                           double phi, double rho_p, double g);
}  // namespace detail

/// Homogeneous (unclustered) settling slip speed, m/s: the solution w of the balance of docs/models.md
///   V_p eps (rho_p - rho_f) g = F_d = V_p beta_p(phi, w) w,
/// g = |gravity| in m/s^2. beta_p(phi, w) w increases with w for every law here, so the root is
/// unique; it is bracketed by [0, eps (rho_p - rho_f) g / beta_p(phi, 0)] and found with GSL's Brent
/// solver to 1e-14 relative.
template <class Law>
double homogeneous_slip_speed(const Law& law, double phi, double rho_p, double g) {
  return detail::settling_slip_speed([&](double w) { return law.beta_p(phi, w); }, law.params, phi, rho_p, g);
}
double homogeneous_slip_speed(DragLaw law, const DragParams& params, double phi, double rho_p, double g);

/// homogeneous_slip_speed(law, params, phi, rho_p, g) / u_t (u_t in m/s; docs/models.md's convention is the
/// Schiller-Naumann u_t of core/scales.hpp).
double homogeneous_slip_over_ut(DragLaw law, const DragParams& params, double phi, double rho_p, double g,
                                double u_t);

/// Terminal velocity of a single particle (phi = 0), m/s: (rho_p - rho_f) g = beta_p(0, u) u.
/// terminal_velocity(SchillerNaumannDrag(p), ...) and terminal_velocity(DragLaw::WenYu, p, ...) are
/// docs/models.md's u_t (core/scales.hpp); Beetstra gives 0.232 m/s for the paper's case.
template <class Law>
double terminal_velocity(const Law& law, double rho_p, double g) {
  return homogeneous_slip_speed(law, 0.0, rho_p, g);
}
double terminal_velocity(DragLaw law, const DragParams& params, double rho_p, double g);

}  // namespace cgd
