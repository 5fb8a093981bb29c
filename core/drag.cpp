#include "core/drag.hpp"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_roots.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "core/error.hpp"

namespace cgd {

std::optional<DragLaw> drag_law_from_name(std::string_view name) {
  for (const DragLawInfo& row : kDragLaws)
    if (name == row.name) return row.law;
  return std::nullopt;
}

std::optional<DragLaw> microscopic_drag_law(std::string_view name) {
  const auto law = drag_law_from_name(name);
  if (law && is_microscopic(*law)) return law;
  return std::nullopt;
}

namespace {
std::string quoted_names(bool (*keep)(const DragLawInfo&)) {
  std::string out;
  for (const DragLawInfo& row : kDragLaws)
    if (keep(row)) out += (out.empty() ? "\"" : ", \"") + std::string(row.name) + "\"";
  return out;
}
}  // namespace

std::string drag_law_names(DragKind kind) {
  return kind == DragKind::Micro ? quoted_names([](const DragLawInfo& r) { return r.kind == DragKind::Micro; })
                                 : quoted_names([](const DragLawInfo& r) { return r.kind == DragKind::Filtered; });
}

std::string drag_law_names() {
  return quoted_names([](const DragLawInfo&) { return true; });
}

void throw_drag_law_needs_model(DragLaw law) {
  throw InputError(std::string("drag law \"") + to_string(law) + "\" needs a filtered model file; only the " +
                   "microscopic laws (" + drag_law_names(DragKind::Micro) +
                   ") can be evaluated from the fluid and particle parameters alone");
}

double beta_p(DragLaw law, const DragParams& params, double phi, double slip_speed) {
  return visit_drag_law(law, params, [&](const auto& drag) { return drag.beta_p(phi, slip_speed); });
}

namespace detail {

namespace {

struct Balance {
  const std::function<double(double)>* beta_p_of_slip;
  double weight_per_volume;  // eps (rho_p - rho_f) g, N/m^3
};

// Drag minus buoyant weight, per particle volume (N/m^3): increasing in the slip speed w.
double excess_drag(double w, void* data) {
  const auto* b = static_cast<const Balance*>(data);
  return (*b->beta_p_of_slip)(w)*w - b->weight_per_volume;
}

std::string number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}

}  // namespace

double settling_slip_speed(const std::function<double(double)>& beta_p_of_slip, const DragParams& params,
                           double phi, double rho_p, double g) {
  if (!(params.rho_f > 0 && params.mu_f > 0 && params.d > 0))
    throw InputError("settling balance: fluid density, viscosity and diameter must be > 0 (got rho_f = " +
                     number(params.rho_f) + ", mu_f = " + number(params.mu_f) + ", d = " + number(params.d) +
                     ")");
  if (!(phi >= 0.0 && phi < 1.0))
    throw InputError("settling balance: solids fraction " + number(phi) + " is outside [0, 1)");
  if (!(rho_p > params.rho_f))
    throw InputError("settling balance: particle density " + number(rho_p) +
                     " must exceed the fluid density " + number(params.rho_f) +
                     " for the particles to settle");
  if (!(g > 0.0 && std::isfinite(g)))
    throw InputError("settling balance: gravity magnitude " + number(g) + " must be > 0");

  const double eps = 1.0 - phi;
  Balance balance{&beta_p_of_slip, eps * (rho_p - params.rho_f) * g};
  // beta_p(w) >= beta_p(0) for every law, so the Stokes-limit slip bounds the root from above.
  const double upper = balance.weight_per_volume / beta_p_of_slip(0.0);
  gsl_function f{&excess_drag, &balance};
  const double f_upper = excess_drag(upper, &balance);
  // f(upper) <= 0 only when beta_p(upper) == beta_p(0) to round-off (e.g. Stokes): upper is the root.
  if (!(f_upper > 0.0)) return upper;

  std::unique_ptr<gsl_root_fsolver, decltype(&gsl_root_fsolver_free)> solver(
      gsl_root_fsolver_alloc(gsl_root_fsolver_brent), &gsl_root_fsolver_free);
  // f(0) = -weight < 0 < f(upper): a valid bracket, so gsl_root_fsolver_set cannot fail.
  gsl_root_fsolver_set(solver.get(), &f, 0.0, upper);
  double root = 0.5 * upper;
  for (int iter = 0; iter < 200; ++iter) {
    if (gsl_root_fsolver_iterate(solver.get()) != GSL_SUCCESS) break;
    root = gsl_root_fsolver_root(solver.get());
    const double lo = gsl_root_fsolver_x_lower(solver.get());
    const double hi = gsl_root_fsolver_x_upper(solver.get());
    if (gsl_root_test_interval(lo, hi, 0.0, 1e-14) == GSL_SUCCESS) break;
  }
  return root;
}

}  // namespace detail

double homogeneous_slip_speed(DragLaw law, const DragParams& params, double phi, double rho_p, double g) {
  return visit_drag_law(law, params,
                        [&](const auto& drag) { return homogeneous_slip_speed(drag, phi, rho_p, g); });
}

double homogeneous_slip_over_ut(DragLaw law, const DragParams& params, double phi, double rho_p, double g,
                                double u_t) {
  if (!(u_t > 0.0))
    throw InputError("settling balance: terminal velocity u_t = " + detail::number(u_t) + " must be > 0");
  return homogeneous_slip_speed(law, params, phi, rho_p, g) / u_t;
}

double terminal_velocity(DragLaw law, const DragParams& params, double rho_p, double g) {
  return homogeneous_slip_speed(law, params, 0.0, rho_p, g);
}

}  // namespace cgd
