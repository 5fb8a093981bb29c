// The exporter of filtered drag models (see export_model.hpp; docs/export.md).
#include "fit/export_model.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <sstream>

#include "core/error.hpp"
#include "core/version.hpp"

namespace cgd::exporter {

namespace {

/// The shortest of %.15g, %.16g, %.17g that reads back as x (17 digits always do).
std::string shortest(double x) {
  char buf[40];
  for (int digits : {15, 16, 17}) {
    std::snprintf(buf, sizeof buf, "%.*g", digits, x);
    if (std::strtod(buf, nullptr) == x) break;
  }
  return buf;
}

/// The shortest round-trip decimal, always with a '.' or an exponent so that C reads a double.
std::string c_number(double x) {
  if (std::isinf(x)) return x > 0 ? "HUGE_VAL" : "(-HUGE_VAL)";
  std::string s = shortest(x);
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";
  return s;
}

/// A Fortran real(c_double) literal.
std::string f_number(double x) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.17e_c_double", x);
  return buf;
}

std::string csv_number(double x) {
  if (!std::isfinite(x)) return "";
  return shortest(x);
}

std::string short_number(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}

std::string upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

/// Comment text safe inside /* */ and on one line.
std::string comment_safe(std::string s) {
  for (std::size_t p; (p = s.find("*/")) != std::string::npos;) s.replace(p, 2, "* /");
  for (char& c : s)
    if (c == '\n' || c == '\r') c = ' ';
  return s;
}

/// The derivative of a B-spline of order k >= 2: order k - 1, knots t_1 ... t_{n+k-2},
/// d_j = (k - 1) (c_{j+1} - c_j) / (t_{j+k} - t_{j+1}) (0 on an empty span).
BSpline derivative(const BSpline& s) {
  const int k = s.order;
  const std::size_t n = s.coefficients.size();
  BSpline d;
  d.order = k - 1;
  d.knots.assign(s.knots.begin() + 1, s.knots.end() - 1);
  for (std::size_t j = 0; j + 1 < n; ++j) {
    const double dt = s.knots[j + static_cast<std::size_t>(k)] - s.knots[j + 1];
    d.coefficients.push_back(dt > 0 ? (k - 1) * (s.coefficients[j + 1] - s.coefficients[j]) / dt : 0.0);
  }
  return d;
}

LocalCurve from_radl_pieces(const std::vector<Radl2014Curves::Piece>& pieces) {
  LocalCurve c;
  c.x_lo = 0.0;  // Radl2014Curves clamps phi into [0, 1]
  c.x_hi = 1.0;
  for (const auto& p : pieces) c.pieces.push_back({p.phi_lo, p.phi_hi, p.phi0, {p.c0, p.c1, p.c2, p.c3}});
  return c;
}

const char* kind_name(CurveKind k) {
  switch (k) {
    case CurveKind::Splines: return "splines";
    case CurveKind::Table: return "table";
    case CurveKind::Radl2014: return "radl2014";
  }
  return "";
}

/// The piece table as a C array initialiser.
std::string c_table(const std::string& array, const LocalCurve& c) {
  std::ostringstream o;
  o << "static const double " << array << "[" << c.pieces.size() << "][7] = {\n"
    << "    /* phi_lo, phi_hi, phi0, c0, c1, c2, c3 */\n";
  for (const LocalPiece& p : c.pieces) {
    o << "    {" << c_number(p.phi_lo) << ", " << c_number(p.phi_hi) << ", " << c_number(p.phi0);
    for (double x : p.c) o << ", " << c_number(x);
    o << "},\n";
  }
  o << "};\n";
  return o.str();
}

}  // namespace

double LocalCurve::operator()(double x) const {
  x = std::clamp(x, x_lo, x_hi);
  const LocalPiece* p = &pieces.back();
  for (const LocalPiece& q : pieces)
    if (x < q.phi_hi) {
      p = &q;
      break;
    }
  const double t = x - p->phi0;
  return p->c[0] + t * (p->c[1] + t * (p->c[2] + t * p->c[3]));
}

LocalCurve local_form(const BSpline& s) {
  if (s.order < 1 || s.order > 4)
    throw InputError("a B-spline of order " + std::to_string(s.order) + " has no cubic local form (order 1..4)");
  std::vector<BSpline> derivatives{s};
  while (derivatives.back().order > 1) derivatives.push_back(derivative(derivatives.back()));
  const double factorial[4] = {1, 1, 2, 6};
  LocalCurve c;
  c.x_lo = s.lower();
  c.x_hi = s.upper();
  const std::size_t k = static_cast<std::size_t>(s.order), n = s.coefficients.size();
  for (std::size_t i = k - 1; i < n; ++i) {
    const double lo = s.knots[i], hi = s.knots[i + 1];
    if (!(hi > lo)) continue;
    LocalPiece p;
    p.phi_lo = lo;
    p.phi_hi = hi;
    p.phi0 = lo;
    for (std::size_t m = 0; m < derivatives.size(); ++m) p.c[m] = derivatives[m](lo) / factorial[m];
    c.pieces.push_back(p);
  }
  return c;
}

ExportedModel from_model(const DragModel& m, const std::string& name, const std::vector<std::string>& provenance) {
  ExportedModel e;
  e.name = name;
  e.kind = m.table ? CurveKind::Table : CurveKind::Splines;
  e.h = local_form(m.h_spline);
  if (!m.table) e.g = local_form(m.log_a_spline);
  e.l_char_m = m.l_char_m;
  e.width_exponent = m.width_exponent;
  e.phi_crit = m.phi_crit;
  e.h_max = m.h_max;
  e.log_a_min = m.log_a_min;
  e.log_a_max = m.log_a_max;
  e.c_corr_a = m.c_corr_a;
  e.c_corr_k = m.c_corr_k;
  e.diameter_m = m.diameter_m;
  e.micro_drag = to_string(m.micro_drag);
  e.calibrated_delta_m = m.calibrated_delta_m;
  std::sort(e.calibrated_delta_m.begin(), e.calibrated_delta_m.end());
  const double d = m.diameter_m;
  e.provenance.push_back("model file: " + m.path + ", FNV-1a 64-bit checksum " + m.checksum);
  e.provenance.push_back("curves: " + std::string(m.table ? "table (cgd-fit --grid-table " +
                                                                std::to_string(m.table_cells_across) + ")"
                                                          : "splines") +
                         ", calibration operator " + to_string(m.calibration_operator) + ", base law " + e.micro_drag +
                         ", c_corr source " + m.c_corr_source);
  if (!e.calibrated_delta_m.empty()) {
    std::string cal = "calibrated Delta:";
    for (double x : e.calibrated_delta_m) cal += " " + short_number(x / d);
    cal += " d_p (" + short_number(e.calibrated_delta_m.front()) + " to " + short_number(e.calibrated_delta_m.back()) +
           " m)";
    e.provenance.push_back(cal);
  }
  if (m.table)
    e.provenance.push_back("phi range: the table's " + short_number(e.h.x_lo) + " to " + short_number(e.h.x_hi) +
                           " (H held constant outside)");
  else
    e.provenance.push_back("phi range: phi_crit = " + short_number(m.phi_crit) + " to phi_max = " +
                           short_number(e.h.x_hi) + " (h linear to 0 below phi_crit, h and a constant above phi_max)");
  e.provenance.push_back("system: d_p = " + short_number(d) + " m, rho_p = " + short_number(m.particle_density_kg_m3) +
                         " kg/m3, rho_f = " + short_number(m.fluid_density_kg_m3) + " kg/m3, mu_f = " +
                         short_number(m.fluid_viscosity_Pa_s) + " Pa s, |g| = " + short_number(m.gravity_m_s2) +
                         " m/s2; u_t = " + short_number(m.u_t_m_s) + " m/s (" + m.u_t_convention +
                         "), L_char = " + short_number(m.l_char_m) + " m");
  for (const std::string& line : provenance) e.provenance.push_back(line);
  return e;
}

ExportedModel from_radl2014(double l_char_m, double diameter_m, const std::string& name,
                            const std::vector<std::string>& provenance) {
  ExportedModel e;
  e.name = name;
  e.kind = CurveKind::Radl2014;
  e.h = from_radl_pieces(Radl2014Curves::h_pieces());
  e.g = from_radl_pieces(Radl2014Curves::a_pieces());
  e.l_char_m = l_char_m;
  e.width_exponent = 1;
  e.phi_crit = Radl2014Curves::kPhiCrit;
  e.c_corr_a = Radl2014Curves::kCcorrA;
  e.c_corr_k = Radl2014Curves::kCcorrK;
  e.diameter_m = diameter_m;
  e.micro_drag = "beetstra";
  e.provenance.push_back(
      "curves: Radl & Sundaresan (2014), Chem. Eng. Sci. 117:416, as cgd's radl2014 law evaluates them "
      "(data/reference/radl2014-filtered-drag.csv: a(phi) on 0.25-0.40 with c1 = -8.82 as in MFiX, h = 0 at phi >= 0.60)");
  e.provenance.push_back("base law beetstra, c_corr a_c = 0, k_c = 0.05 (the paper's), n = 1, L_char = " +
                         short_number(l_char_m) + " m");
  for (const std::string& line : provenance) e.provenance.push_back(line);
  return e;
}

std::string clamp_report(const ExportedModel& e) {
  if (e.kind == CurveKind::Radl2014) return "none (the published curves are used as they are)";
  const double lo_clamp = e.kind == CurveKind::Table ? -1.0 : 0.0;
  const char* lo_name = e.kind == CurveKind::Table ? "-1" : "0";
  std::string out;
  const double a = e.h.x_lo, b = e.h.x_hi;
  const int steps = std::max(1, static_cast<int>(std::ceil((b - a) / 1e-5)));
  int state = 0;  // 0 inside, 1 above h_max, -1 below
  double start = a;
  auto close = [&](double end) {
    if (state == 0) return;
    if (!out.empty()) out += "; ";
    out += std::string(state > 0 ? "S_h > h_max" : std::string("S_h < ") + lo_name) + " on [" + short_number(start) +
           ", " + short_number(end) + "]";
  };
  for (int i = 0; i <= steps; ++i) {
    const double x = i == steps ? b : a + (b - a) * i / steps;
    const double v = e.h(x);
    const int s = v > e.h_max ? 1 : (v < lo_clamp ? -1 : 0);
    if (s != state) {
      close(x);
      state = s;
      start = x;
    }
  }
  close(b);
  return out.empty() ? "none (h_max and the lower clamp are never reached on the spline's interval)" : out;
}

std::string c_header(const ExportedModel& e) {
  const std::string p = "cgd_" + e.name + "_", P = "CGD_" + upper(e.name) + "_";
  const std::string api = P + "API";
  std::ostringstream o;
  o << "/* " << e.name << ".h: a filtered drag model of cgd (" << kind_name(e.kind)
    << ") as a self-contained C99 evaluator. Written by cgd-export " << cgd::code_version()
    << "; do not edit, export again (docs/export.md).\n"
    << " *\n"
    << " *   beta_bar / beta_micro = c_corr(alpha) [1 - H(phi, Delta)],   H = h(phi) / (1 + a(phi) F^n),\n"
    << " *   F = L_char / Delta,  L_char = " << c_number(e.l_char_m) << " m,  n = " << c_number(e.width_exponent) << ",\n"
    << " *   c_corr(alpha) = a_c + (1 - a_c) exp(-k_c (alpha - 1)),  a_c = " << c_number(e.c_corr_a)
    << ", k_c = " << c_number(e.c_corr_k) << ",\n"
    << " *   phi = solids fraction at the parcel (1 - the void fraction the code's drag uses), Delta = cube root of the\n"
    << " *   fluid cell volume (m, > 0), alpha = d_parcel / d_primary (>= 1); beta_micro = the base law (" << e.micro_drag
    << ")\n"
    << " *   evaluated with the PRIMARY diameter and the parcel's slip |u - v|, per primary; a parcel carries alpha^3\n"
    << " *   primaries' drag (docs/models.md \"Parcels\"). The base law is not in this header.\n"
    << " *\n"
    << " * Provenance:\n";
  for (const std::string& line : e.provenance) o << " *   " << comment_safe(line) << "\n";
  o << " *\n * Curves (the pieces below: c0 + c1 x + c2 x^2 + c3 x^3, x = phi - phi0, on phi_lo <= phi < phi_hi, the last\n"
    << " * piece also above; the argument is first clamped into the curve's interval):\n";
  switch (e.kind) {
    case CurveKind::Splines:
      o << " *   h(phi) = clamp(S_h(phi), 0, h_max) on [phi_crit, phi_max]; h(phi_crit) max(phi, 0) / phi_crit below;\n"
        << " *            h(phi_max) above;  h_max = " << c_number(e.h_max) << ", phi_crit = " << c_number(e.phi_crit)
        << ", phi_max = " << c_number(e.h.x_hi) << "\n"
        << " *   a(phi) = exp(clamp(S_log_a(clamp(phi, phi_crit, " << c_number(e.g.x_hi) << ")), " << c_number(e.log_a_min)
        << ", " << c_number(e.log_a_max) << "))\n";
      break;
    case CurveKind::Table:
      o << " *   h(phi) = clamp(S_h(phi), -1, h_max) (piecewise linear through the table, constant outside "
        << c_number(e.h.x_lo) << " ... " << c_number(e.h.x_hi) << "), h_max = " << c_number(e.h_max)
        << "; a = 0: H = h at any Delta\n";
      break;
    case CurveKind::Radl2014:
      o << " *   h, a: the published piecewise cubics on [0, 1] (phi clamped into it); a jumps at 0.016\n";
      break;
  }
  o << " *   where a clamp of h is active: " << comment_safe(clamp_report(e)) << "\n"
    << " *\n"
    << " * Use from C or C++: #include \"" << e.name << ".h\" (static inline functions). For Fortran (bind(C), module\n"
    << " * " << e.name << ".f90) or a library: in exactly one C file\n"
    << " *   #define " << P << "IMPLEMENTATION\n"
    << " *   #include \"" << e.name << ".h\"\n"
    << " * which defines the functions with external C linkage.\n"
    << " */\n"
    << "#ifndef " << P << "H\n#define " << P << "H\n\n#include <math.h>\n\n"
    << "#define " << P << "L_CHAR_M " << c_number(e.l_char_m) << " /* m */\n"
    << "#define " << P << "WIDTH_EXPONENT " << c_number(e.width_exponent) << "\n"
    << "#define " << P << "PHI_CRIT " << c_number(e.phi_crit) << "\n"
    << "#define " << P << "PHI_LOW " << c_number(e.h.x_lo) << " /* lower end of the h curve's interval */\n"
    << "#define " << P << "PHI_HIGH " << c_number(e.h.x_hi) << " /* upper end of the h curve's interval */\n"
    << "#define " << P << "H_MAX " << c_number(e.h_max) << "\n"
    << "#define " << P << "CCORR_A " << c_number(e.c_corr_a) << "\n"
    << "#define " << P << "CCORR_K " << c_number(e.c_corr_k) << "\n";
  if (e.diameter_m > 0) o << "#define " << P << "DIAMETER_M " << c_number(e.diameter_m) << " /* primary d_p, m */\n";
  for (std::size_t i = 0; i < e.calibrated_delta_m.size(); ++i)
    o << (i == 0 ? "/* calibrated Delta (m): " : ", ") << c_number(e.calibrated_delta_m[i])
      << (i + 1 == e.calibrated_delta_m.size() ? " */\n" : "");
  o << "\n#ifdef " << P << "IMPLEMENTATION\n#define " << api << "\n#else\n#define " << api
    << " static inline\n#endif\n\n#ifdef __cplusplus\nextern \"C\" {\n#endif\n\n";
  const std::string h_name = e.kind == CurveKind::Radl2014 ? "h" : "S_h";
  const std::string g_name = e.kind == CurveKind::Radl2014 ? "a" : "S_log_a";
  o << "/* " << h_name << ": interval [" << c_number(e.h.x_lo) << ", " << c_number(e.h.x_hi) << "] */\n"
    << c_table(p + "h_pieces", e.h);
  if (e.kind != CurveKind::Table)
    o << "/* " << g_name << ": interval [" << c_number(e.g.x_lo) << ", " << c_number(e.g.x_hi) << "] */\n"
      << c_table(p + "a_pieces", e.g);
  o << "\n/* the master curves h(phi), a(phi); H(phi, Delta) = h/(1 + a F^n); c_corr(alpha); beta_bar/beta_micro */\n";
  for (const char* proto : {"master_h(double phi)", "master_a(double phi)", "F_to_n(double delta_m)",
                            "H(double phi, double delta_m)", "c_corr(double alpha)",
                            "correction(double phi, double delta_m, double alpha)"})
    o << api << " double " << p << proto << ";\n";
  // the piece evaluator: as core/filtered_drag.cpp (clamp, first piece with x < phi_hi, Horner)
  o << "\nstatic inline double " << p << "local_(const double (*pieces)[7], int n, double lo, double hi, double x) {\n"
    << "  int i = 0;\n  double t;\n"
    << "  x = x < lo ? lo : (hi < x ? hi : x);\n"
    << "  while (i < n - 1 && !(x < pieces[i][1])) ++i;\n"
    << "  t = x - pieces[i][2];\n"
    << "  return pieces[i][3] + t * (pieces[i][4] + t * (pieces[i][5] + t * pieces[i][6]));\n}\n\n";
  const std::string H_call = p + "local_(" + p + "h_pieces, " + std::to_string(e.h.pieces.size()) + ", " +
                             c_number(e.h.x_lo) + ", " + c_number(e.h.x_hi) + ", ";
  const std::string G_call = e.kind == CurveKind::Table ? ""
                                                        : p + "local_(" + p + "a_pieces, " +
                                                              std::to_string(e.g.pieces.size()) + ", " +
                                                              c_number(e.g.x_lo) + ", " + c_number(e.g.x_hi) + ", ";
  o << api << " double " << p << "master_h(double phi) {\n";
  switch (e.kind) {
    case CurveKind::Splines:
      o << "  double s;\n"
        << "  if (phi < " << P << "PHI_CRIT) {\n"
        << "    s = " << H_call << P << "PHI_CRIT);\n"
        << "    s = s < 0.0 ? 0.0 : (" << P << "H_MAX < s ? " << P << "H_MAX : s);\n"
        << "    return s * (phi < 0.0 ? 0.0 : phi) / " << P << "PHI_CRIT;\n  }\n"
        << "  s = " << H_call << "(" << c_number(e.h.x_hi) << " < phi ? " << c_number(e.h.x_hi) << " : phi));\n"
        << "  return s < 0.0 ? 0.0 : (" << P << "H_MAX < s ? " << P << "H_MAX : s);\n";
      break;
    case CurveKind::Table:
      o << "  const double s = " << H_call << "phi);\n"
        << "  return s < -1.0 ? -1.0 : (" << P << "H_MAX < s ? " << P << "H_MAX : s);\n";
      break;
    case CurveKind::Radl2014:
      o << "  return " << H_call << "phi);\n";
      break;
  }
  o << "}\n\n" << api << " double " << p << "master_a(double phi) {\n";
  switch (e.kind) {
    case CurveKind::Splines:
      o << "  double s;\n"
        << "  phi = phi < " << P << "PHI_CRIT ? " << P << "PHI_CRIT : (" << c_number(e.g.x_hi) << " < phi ? "
        << c_number(e.g.x_hi) << " : phi);\n"
        << "  s = " << G_call << "phi);\n"
        << "  s = s < " << c_number(e.log_a_min) << " ? " << c_number(e.log_a_min) << " : (" << c_number(e.log_a_max)
        << " < s ? " << c_number(e.log_a_max) << " : s);\n"
        << "  return exp(s);\n";
      break;
    case CurveKind::Table:
      o << "  (void)phi;\n  return 0.0;\n";
      break;
    case CurveKind::Radl2014:
      o << "  return " << G_call << "phi);\n";
      break;
  }
  o << "}\n\n" << api << " double " << p << "F_to_n(double delta_m) {\n";
  if (e.kind == CurveKind::Radl2014)
    o << "  return " << P << "L_CHAR_M / delta_m;\n";
  else
    o << "  return pow(" << P << "L_CHAR_M / delta_m, " << P << "WIDTH_EXPONENT);\n";
  o << "}\n\n"
    << api << " double " << p << "H(double phi, double delta_m) {\n"
    << "  return " << p << "master_h(phi) / (1.0 + " << p << "master_a(phi) * " << p << "F_to_n(delta_m));\n}\n\n"
    << api << " double " << p << "c_corr(double alpha) {\n"
    << "  return " << P << "CCORR_A + (1.0 - " << P << "CCORR_A) * exp(-" << P << "CCORR_K * (alpha - 1.0));\n}\n\n"
    << api << " double " << p << "correction(double phi, double delta_m, double alpha) {\n"
    << "  return " << p << "c_corr(alpha) * (1.0 - " << p << "master_h(phi) / (1.0 + " << p << "master_a(phi) * " << p
    << "F_to_n(delta_m)));\n}\n\n"
    << "#ifdef __cplusplus\n}\n#endif\n\n#endif /* " << P << "H */\n";
  return o.str();
}

std::string fortran_module(const ExportedModel& e) {
  const std::string p = "cgd_" + e.name + "_";
  std::ostringstream o;
  o << "! " << e.name << ".f90: Fortran 2003 interfaces (bind(C)) to the functions of " << e.name
    << ".h, written by cgd-export " << cgd::code_version() << ".\n"
    << "! Compile the C functions once, from a C file holding\n"
    << "!   #define CGD_" << upper(e.name) << "_IMPLEMENTATION\n"
    << "!   #include \"" << e.name << ".h\"\n"
    << "! then: use cgd_" << e.name << "; corr = " << p << "correction(phi, delta_m, alpha)  (docs/export.md)\n"
    << "module cgd_" << e.name << "\n"
    << "  use, intrinsic :: iso_c_binding, only: c_double\n  implicit none\n"
    << "  real(c_double), parameter :: " << p << "l_char_m = " << f_number(e.l_char_m) << "\n"
    << "  real(c_double), parameter :: " << p << "width_exponent = " << f_number(e.width_exponent) << "\n";
  if (e.diameter_m > 0) o << "  real(c_double), parameter :: " << p << "diameter_m = " << f_number(e.diameter_m) << "\n";
  o << "  interface\n";
  struct Fn {
    const char* name;
    const char* args;
  };
  for (const Fn f : {Fn{"master_h", "phi"}, Fn{"master_a", "phi"}, Fn{"F_to_n", "delta_m"}, Fn{"H", "phi, delta_m"},
                     Fn{"c_corr", "alpha"}, Fn{"correction", "phi, delta_m, alpha"}}) {
    o << "    function " << p << f.name << "(" << f.args << ") bind(C, name=\"" << p << f.name << "\") result(r)\n"
      << "      import :: c_double\n"
      << "      real(c_double), value, intent(in) :: " << f.args << "\n"
      << "      real(c_double) :: r\n"
      << "    end function " << p << f.name << "\n";
  }
  o << "  end interface\nend module cgd_" << e.name << "\n";
  return o.str();
}

std::string pieces_csv(const ExportedModel& e) {
  std::ostringstream o;
  o << "# " << e.name << "_pieces.csv: the curves of " << e.name << ".h in local form (cgd-export " << cgd::code_version()
    << "; docs/export.md)\n";
  for (const std::string& line : e.provenance) o << "# " << line << "\n";
  o << "# value = c0 + c1*x + c2*x^2 + c3*x^3, x = phi - phi0, on phi_lo <= phi < phi_hi (the last row of a curve also above);\n"
    << "# the argument is first clamped into the curve's interval (its first phi_lo and last phi_hi).\n";
  const std::string g = e.kind == CurveKind::Radl2014 ? "a" : "log_a";
  switch (e.kind) {
    case CurveKind::Splines:
      o << "# h(phi) = clamp(S_h(phi), 0, " << csv_number(e.h_max) << ") for phi_crit = " << csv_number(e.phi_crit)
        << " <= phi; h(phi_crit) * max(phi, 0) / phi_crit below; a(phi) = exp(clamp(log_a(clamp(phi, phi_crit, "
        << csv_number(e.g.x_hi) << ")), " << csv_number(e.log_a_min) << ", " << csv_number(e.log_a_max) << "))\n";
      break;
    case CurveKind::Table:
      o << "# h(phi) = clamp(S_h(phi), -1, " << csv_number(e.h_max) << "); a = 0 (H = h at any Delta)\n";
      break;
    case CurveKind::Radl2014:
      o << "# h and a as they are (the published pieces)\n";
      break;
  }
  o << "# H = h / (1 + a F^n), F = L_char / Delta, L_char = " << csv_number(e.l_char_m) << " m, n = "
    << csv_number(e.width_exponent) << "; where a clamp of h is active: " << clamp_report(e) << "\n"
    << "function,phi_lo,phi_hi,phi0,c0,c1,c2,c3\n";
  auto rows = [&](const std::string& f, const LocalCurve& c) {
    for (const LocalPiece& p : c.pieces) {
      o << f << "," << csv_number(p.phi_lo) << "," << csv_number(p.phi_hi) << "," << csv_number(p.phi0);
      for (double x : p.c) o << "," << csv_number(x);
      o << "\n";
    }
  };
  rows(e.kind == CurveKind::Radl2014 ? "h" : "S_h", e.h);
  if (e.kind != CurveKind::Table) rows(e.kind == CurveKind::Radl2014 ? "a" : "S_log_a", e.g);
  return o.str();
}

std::string h_table_csv(const ExportedModel& e, const std::function<double(double, double)>& H_of,
                        const std::vector<double>& phis, const std::vector<double>& deltas_m, const Bands* bands) {
  std::ostringstream o;
  o << "# " << e.name << "_H.csv: H(phi, Delta) = h/(1 + a F^n) of " << e.name << ".h, as cgd's engine evaluates it (cgd-export "
    << cgd::code_version() << "; docs/export.md)\n";
  for (const std::string& line : e.provenance) o << "# " << line << "\n";
  o << "# beta_bar / beta_micro = c_corr(alpha) (1 - H), c_corr(alpha) = " << csv_number(e.c_corr_a) << " + (1 - "
    << csv_number(e.c_corr_a) << ") exp(-" << csv_number(e.c_corr_k) << " (alpha - 1)); F = L_char / Delta, L_char = "
    << csv_number(e.l_char_m) << " m, n = " << csv_number(e.width_exponent) << "\n"
    << "# H_low, H_high: the model file's 95 % band at that (phi, F) (/bands), empty where it has none\n"
    << "phi,delta_m,delta_over_dp,F,H,H_low,H_high\n";
  for (double delta : deltas_m) {
    const double F = e.l_char_m / delta;
    long f_index = -1;
    if (bands)
      for (std::size_t j = 0; j < bands->F.size(); ++j)
        if (std::abs(bands->F[j] - F) <= 1e-9 * F) f_index = static_cast<long>(j);
    for (double phi : phis) {
      double lo = NAN, hi = NAN;
      if (f_index >= 0) {
        const auto it = std::find(bands->phi.begin(), bands->phi.end(), phi);
        if (it != bands->phi.end()) {
          const std::size_t k = static_cast<std::size_t>(f_index) * bands->phi.size() +
                                static_cast<std::size_t>(it - bands->phi.begin());
          lo = bands->H_low[k];
          hi = bands->H_high[k];
        }
      }
      o << csv_number(phi) << "," << csv_number(delta) << ","
        << (e.diameter_m > 0 ? csv_number(delta / e.diameter_m) : "") << "," << csv_number(F) << ","
        << csv_number(H_of(phi, delta)) << "," << csv_number(lo) << "," << csv_number(hi) << "\n";
    }
  }
  return o.str();
}

double engine_H(const DragModel* model, double l_char_m, double phi, double delta_m) {
  FilteredDragSetup setup;
  setup.filter_width_m = delta_m;
  setup.l_char_m = l_char_m;
  setup.parcel_size = 1;
  DragParams params{1.3, 1.8e-5, 75e-6};  // the base law's parameters do not enter H
  DragLaw law = DragLaw::Radl2014;
  if (model) {
    setup.model = std::shared_ptr<const DragModel>(std::shared_ptr<const DragModel>{}, model);  // not owned
    params = model->drag_params();
    law = DragLaw::Model;
  }
  return visit_any_drag_law(law, params, setup, [&](const auto& drag) -> double {
    if constexpr (requires { drag.curves; drag.filter_term; })
      return drag.curves.h(phi) / (1.0 + drag.curves.a(phi) * drag.filter_term);
    else
      return NAN;  // a micro law: not reached
  });
}

}  // namespace cgd::exporter
