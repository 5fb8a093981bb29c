// The engine's side of the export tests (tests/export/export_test.sh; docs/export.md "Tests"):
//   export_check points (--model MODEL.h5 | --radl2014) OUT.txt
//       the (phi, Delta, alpha) points every consumer evaluates: phi from -0.05 to 1.5 (dense on 0 ... 0.7, and
//       around every breakpoint of the model's curves: knots, phi_crit, the table's ends, Radl's intervals),
//       Delta from 0.5 to 200 d_p (and the calibrated Delta), alpha 1, 3, 8;
//   export_check compare (--model MODEL.h5 | --radl2014 L_CHAR_M) POINTS [--csv H.csv] LABEL=OUT...
//       each consumer's "h a H correction" per point against the engine's evaluator (visit_any_drag_law, as a
//       coarse run sets it up); the CSV's H against the engine; fails (exit 1) beyond the tolerance below or when
//       the comparison would be vacuous (too few points, H not varying, no point below phi_crit);
//   export_check make-table OUT.h5
//       a --grid-table model (cgd::fit::write_grid_table_model, what cgd-fit --grid-table runs) of synthetic
//       filtered data with coarse grids (tests/unit/fit_test_util.hpp);
//   export_check make-shifted MODEL.h5 OUT.h5
//       MODEL's spline model with 0.1 added to every h coefficient (S_h + 0.1: a B-spline's basis sums to 1), so
//       that h(phi_crit) > 0 and the linear ramp below phi_crit is exercised whatever the shipped model's
//       h(phi_crit) is (the six-run model's S_h(phi_crit) = -0.007 is clamped to 0: its ramp is 0); fails (exit 1)
//       when the shifted h(phi_crit) is not > 0.05.
// Tolerance: |consumer - engine| <= 1e-12 max(1, |engine|) for h, a, H and beta_bar/beta_micro. The local form is
// the B-spline's own polynomial on each span (exact in exact arithmetic); the header evaluates it by Horner's
// rule where the engine runs de Boor's recursion, so the two differ by rounding only (a few ulp, times the
// cancellation among a piece's terms): measured 1.9e-15 on data/models/half_box.h5, 1.1e-16 on a table model, 0 on
// Radl 2014, whose pieces are the engine's own (docs/export.md). 1e-12 leaves a margin of > 500 and still catches a
// change in the 10th significant digit of one coefficient (export_test.sh perturbs one: 5.5e-10, caught).
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "core/mpi_init.hpp"
#include "core/filtered_drag.hpp"
#include "core/schema/drag_model.hpp"
#include "core/scene.hpp"
#include "fit/fitter.hpp"
#include "tests/unit/fit_test_util.hpp"

namespace {

struct Point {
  double phi, delta_m, alpha;
};

struct Engine {
  std::shared_ptr<const cgd::DragModel> model;  // null: Radl 2014
  double l_char_m = 0;
  struct Values {
    double h, a, H, correction;
  };
  Values at(const Point& p) const {
    cgd::FilteredDragSetup setup;
    setup.model = model;
    setup.filter_width_m = p.delta_m;
    setup.l_char_m = l_char_m;
    setup.parcel_size = p.alpha;
    const cgd::DragParams params = model ? model->drag_params() : cgd::DragParams{1.3, 1.8e-5, 75e-6};
    return cgd::visit_any_drag_law(model ? cgd::DragLaw::Model : cgd::DragLaw::Radl2014, params, setup,
                                   [&](const auto& d) -> Values {
                                     if constexpr (requires { d.curves; }) {
                                       const double h = d.curves.h(p.phi), a = d.curves.a(p.phi);
                                       return {h, a, h / (1.0 + a * d.filter_term), d.correction(p.phi)};
                                     } else {
                                       return {NAN, NAN, NAN, NAN};
                                     }
                                   });
  }
};

int usage() {
  std::cerr << "usage: export_check points (--model MODEL.h5 | --radl2014) OUT.txt\n"
               "       export_check compare (--model MODEL.h5 | --radl2014 L_CHAR_M) POINTS [--csv H.csv] LABEL=OUT...\n"
               "       export_check make-table OUT.h5\n"
               "       export_check make-shifted MODEL.h5 OUT.h5\n";
  return 2;
}

std::vector<double> breakpoints(const cgd::DragModel* m) {
  std::vector<double> b;
  if (m) {
    b = m->h_spline.knots;
    b.insert(b.end(), m->log_a_spline.knots.begin(), m->log_a_spline.knots.end());
    b.push_back(m->phi_crit);
  } else {
    for (const auto& p : cgd::Radl2014Curves::h_pieces()) b.push_back(p.phi_lo);
    for (const auto& p : cgd::Radl2014Curves::a_pieces()) b.push_back(p.phi_lo);
  }
  return b;
}

int points(const cgd::DragModel* m, const std::string& out_path) {
  std::vector<double> phis{-0.05, -1e-3, 0.0, 1e-6, 1e-4, 1e-3, 0.004, 0.008, 0.012, 0.015, 0.7, 0.8, 0.95, 1.0, 1.5};
  for (int i = 1; i < 280; ++i) phis.push_back(0.0025 * i);
  for (double b : breakpoints(m))
    for (double eps : {-1e-9, 0.0, 1e-9}) phis.push_back(b + eps);
  std::sort(phis.begin(), phis.end());
  phis.erase(std::unique(phis.begin(), phis.end()), phis.end());
  const double d = m ? m->diameter_m : 75e-6;
  std::vector<double> deltas;
  for (double x : {0.5, 1.0, 3.33, 6.67, 10.0, 13.3, 17.7, 26.7, 50.0, 200.0}) deltas.push_back(x * d);
  if (m) deltas.insert(deltas.end(), m->calibrated_delta_m.begin(), m->calibrated_delta_m.end());
  std::ofstream out(out_path);
  out.precision(17);
  std::size_t n = 0;
  for (double phi : phis)
    for (double delta : deltas)
      for (double alpha : {1.0, 3.0, 8.0}) {
        out << phi << " " << delta << " " << alpha << "\n";
        ++n;
      }
  out.close();
  if (!out) {
    std::cerr << out_path << ": cannot write\n";
    return 1;
  }
  std::cout << "wrote " << n << " points (" << phis.size() << " phi x " << deltas.size() << " Delta x 3 alpha) to "
            << out_path << "\n";
  return 0;
}

std::vector<Point> read_points(const std::string& path) {
  std::ifstream in(path);
  std::vector<Point> p;
  Point q;
  while (in >> q.phi >> q.delta_m >> q.alpha) p.push_back(q);
  return p;
}

double scaled_diff(double x, double ref) {
  if (std::isnan(x) || std::isnan(ref)) return (std::isnan(x) && std::isnan(ref)) ? 0.0 : HUGE_VAL;
  return std::abs(x - ref) / std::max(1.0, std::abs(ref));
}

int compare(const Engine& engine, const std::string& points_path, const std::string& csv,
            const std::vector<std::string>& outputs) {
  constexpr double kTolerance = 1e-12;
  const std::vector<Point> pts = read_points(points_path);
  int failures = 0;
  auto fail = [&](const std::string& what) {
    std::cout << "FAIL " << what << "\n";
    ++failures;
  };
  std::vector<Engine::Values> ref;
  double H_min = HUGE_VAL, H_max = -HUGE_VAL;
  int low_phi_nonzero = 0;
  const double phi_crit = engine.model ? engine.model->phi_crit : cgd::Radl2014Curves::kPhiCrit;
  for (const Point& p : pts) {
    ref.push_back(engine.at(p));
    H_min = std::min(H_min, ref.back().H);
    H_max = std::max(H_max, ref.back().H);
    if (p.phi > 0 && p.phi < phi_crit && ref.back().H != 0) ++low_phi_nonzero;
  }
  // not vacuous: many points, H varies, the low-phi end carries a correction (splines, Radl) or is the table's;
  // a spline model whose h(phi_crit) is 0 (clamped) has a ramp of 0 below phi_crit: make-shifted's model covers it
  if (pts.size() < 5000) fail("only " + std::to_string(pts.size()) + " points in " + points_path);
  if (!(H_max - H_min > 0.1)) fail("H varies by less than 0.1 over the points: a comparison of nothing");
  const bool zero_ramp = engine.model && !engine.model->table && !engine.model->drift &&
                         cgd::SplineCurves{engine.model.get()}.h(phi_crit) == 0.0;
  if (zero_ramp)
    std::cout << "note h(phi_crit) = 0: the ramp below phi_crit is 0 here (exercised by the shifted model)\n";
  else if (low_phi_nonzero < 10)
    fail("fewer than 10 points with 0 < phi < phi_crit and H != 0");
  for (const std::string& spec : outputs) {
    const auto eq = spec.find('=');
    const std::string label = spec.substr(0, eq), path = spec.substr(eq + 1);
    std::ifstream in(path);
    double worst[4] = {0, 0, 0, 0}, worst_abs[4] = {0, 0, 0, 0};
    std::size_t worst_at[4] = {0, 0, 0, 0}, n = 0;
    std::string line;
    while (n < pts.size() && std::getline(in, line)) {
      std::istringstream s(line);
      double v[4];
      std::string tok;
      for (double& x : v) {
        s >> tok;
        x = std::strtod(tok.c_str(), nullptr);  // also reads Fortran's 1.0E+000 and nan/NaN
      }
      const double r[4] = {ref[n].h, ref[n].a, ref[n].H, ref[n].correction};
      for (int k = 0; k < 4; ++k) {
        const double d = scaled_diff(v[k], r[k]);
        if (d > worst[k]) worst[k] = d, worst_at[k] = n;
        if (std::isfinite(v[k]) && std::isfinite(r[k])) worst_abs[k] = std::max(worst_abs[k], std::abs(v[k] - r[k]));
      }
      ++n;
    }
    if (n != pts.size()) {
      fail(label + ": " + path + " has " + std::to_string(n) + " values, expected " + std::to_string(pts.size()));
      continue;
    }
    const char* names[4] = {"h", "a", "H", "beta_bar/beta_micro"};
    std::ostringstream msg;
    msg.precision(2);
    msg << std::scientific << label << ": " << n << " points, max |diff|/max(1,|engine|):";
    for (int k = 0; k < 4; ++k) msg << " " << names[k] << " " << worst[k];
    msg << "; max |diff|:";
    for (int k = 0; k < 4; ++k) msg << " " << names[k] << " " << worst_abs[k];
    bool ok = true;
    for (int k = 0; k < 4; ++k)
      if (!(worst[k] <= kTolerance)) {
        ok = false;
        const Point& p = pts[worst_at[k]];
        msg << "\n     worst " << names[k] << " at phi = " << p.phi << ", Delta = " << p.delta_m << " m, alpha = " << p.alpha;
      }
    if (ok)
      std::cout << "ok   " << msg.str() << " (tolerance 1e-12)\n";
    else
      fail(msg.str() + " (tolerance 1e-12)");
  }
  if (!csv.empty()) {
    std::ifstream in(csv);
    std::string line;
    std::size_t n = 0, banded = 0;
    double worst = 0;
    while (std::getline(in, line)) {
      if (line.empty() || line[0] == '#' || line.rfind("phi,", 0) == 0) continue;
      std::vector<std::string> cells;
      std::stringstream s(line);
      for (std::string c; std::getline(s, c, ',');) cells.push_back(c);
      if (cells.size() < 5) {
        fail(csv + ": a row with " + std::to_string(cells.size()) + " cells: " + line);
        break;
      }
      const Point p{std::stod(cells[0]), std::stod(cells[1]), 1.0};
      worst = std::max(worst, scaled_diff(std::stod(cells[4]), engine.at(p).H));
      if (cells.size() >= 7 && !cells[5].empty() && !cells[6].empty()) {
        ++banded;
        if (!(std::stod(cells[5]) <= std::stod(cells[6]))) fail(csv + ": H_low > H_high in " + line);
      }
      ++n;
    }
    if (n < 100) fail(csv + ": only " + std::to_string(n) + " rows");
    else if (!(worst <= kTolerance)) fail(csv + ": H differs from the engine by " + std::to_string(worst));
    else
      std::cout << "ok   " << csv << ": " << n << " rows (" << banded << " with bands), H = the engine's, max diff "
                << worst << "\n";
  }
  return failures ? 1 : 0;
}

/// The scene a written model's common attributes come from (the models here are compared, not run).
cgd::Scene test_scene() {
  const char* src = std::getenv("CGD_SOURCE_DIR");
  return cgd::load_scene(std::string(src ? src : ".") + "/tests/scenes/demo_box.toml");
}

int make_table(const std::string& out_path) {
  using namespace cgd::fit::testing;
  SyntheticSpec s;
  s.noise = 0.02;
  cgd::fit::FilteredFile f = make_synthetic(s);
  int k = 0;
  for (const cgd::fit::WidthSeries& w : f.widths) {  // the box widths become coarse grids (test_closure_fit.cpp)
    if (w.whole_box) continue;
    cgd::fit::WidthSeries g = w;
    g.grid = true;
    g.cells_across = 10 - k;
    g.group = "/grids/" + std::to_string(g.cells_across);
    g.cell_size_over_dp = w.width_m / f.physics.diameter_m;
    g.width_over_cell = 2.0 + k;
    f.grids.push_back(g);
    ++k;
  }
  std::cout << cgd::fit::write_grid_table_model(out_path, {f}, static_cast<int>(f.grids[2].cells_across), 100,
                                                test_scene());
  return 0;
}

int make_shifted(const std::string& in_path, const std::string& out_path) {
  cgd::schema::DragModelFile m = cgd::schema::read_drag_model(in_path);
  for (double& c : m.h.coefficients) c += 0.1;
  cgd::schema::write_drag_model(out_path, test_scene(), m);
  const cgd::DragModel shifted = cgd::load_drag_model(out_path);
  const double h = cgd::SplineCurves{&shifted}.h(shifted.phi_crit);
  std::cout << "shifted model: h(phi_crit) = " << h << "\n";
  return h > 0.05 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  cgd::init_mpi(&argc, &argv);
  int status = 2;
  try {
    std::vector<std::string> a(argv + 1, argv + argc);
    if (a.size() >= 2 && a[0] == "make-table") {
      status = make_table(a[1]);
    } else if (a.size() >= 3 && a[0] == "make-shifted") {
      status = make_shifted(a[1], a[2]);
    } else if (a.size() >= 3 && (a[0] == "points" || a[0] == "compare")) {
      std::size_t i = 1;
      Engine engine;
      if (a[i] == "--model" && i + 1 < a.size()) {
        auto m = std::make_shared<cgd::DragModel>(cgd::load_drag_model(a[i + 1]));
        engine.l_char_m = m->l_char_m;
        engine.model = m;
        i += 2;
      } else if (a[i] == "--radl2014") {
        ++i;
        if (a[0] == "compare" && i < a.size()) engine.l_char_m = std::stod(a[i++]);
      } else {
        status = usage();
        MPI_Finalize();
        return status;
      }
      if (a[0] == "points") {
        status = i < a.size() ? points(engine.model.get(), a[i]) : usage();
      } else {
        if (i >= a.size()) return usage();
        const std::string pts = a[i++];
        std::string csv;
        std::vector<std::string> outs;
        for (; i < a.size(); ++i) {
          if (a[i] == "--csv" && i + 1 < a.size()) csv = a[++i];
          else if (a[i].find('=') != std::string::npos) outs.push_back(a[i]);
          else return usage();
        }
        status = compare(engine, pts, csv, outs);
      }
    } else {
      status = usage();
    }
  } catch (const std::exception& e) {
    std::cerr << "export_check: " << e.what() << "\n";
    status = 1;
  }
  MPI_Finalize();
  return status;
}
