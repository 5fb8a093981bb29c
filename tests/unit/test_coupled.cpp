// Verification of the coupled CFD-DEM (sim/run.cpp, sim/coupling, sim/fluid) against known answers:
//   (0) the fluid's viscous term div(eps tau) conserves momentum for any eps;
//   (1) a single particle settles at the terminal velocity u_t (one- and two-way coupling), and the
//       particle's own disturbance of the fluid is what separates the domain slip from u_t;
//   (2) a homogeneous suspension settles at the drag balance of homogeneous_slip_over_ut;
//   (3) the mixture momentum (particles + fluid) is conserved to round-off.
// Single process (MPI_COMM_SELF); the 1-vs-2-rank agreement is in tests/mpi/test_coupled_mpi.cpp and the
// restart in tests/e2e/coupled_restart.sh.
#include <gtest/gtest.h>
#include <mpi.h>
#include <stdlib.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "core/drag.hpp"
#include "core/error.hpp"
#include "core/h5.hpp"
#include "core/schema/series.hpp"
#include "core/schema/snapshot.hpp"
#include "core/scene.hpp"
#include "sim/coupling/coupler.hpp"
#include "sim/dem/placement.hpp"
#include "sim/dem/system.hpp"
#include "sim/fluid/solver.hpp"
#include "sim/run.hpp"
#include "run_quietly.hpp"
#include "temp_dir.hpp"
#include "test_scenes.hpp"

namespace {

namespace fs = std::filesystem;
using cgd::fluid::FluidGrid;
using cgd::fluid::FluidSettings;
using cgd::fluid::FluidSolver;
constexpr double kPi = std::numbers::pi;

/// A fresh directory under the system's temporary directory, removed with its contents at scope exit.
using cgd::testing::run_quietly;
using cgd::testing::TempDir;

/// Base scene of these tests: tests/scenes/unit_suspension.toml (air and 75 um particles, 12^3 d_p box of 4^3
/// cells, two-way coupling, soft contacts); everything else comes as overrides.

cgd::Scene make_scene(const std::vector<std::string>& overrides) {
  return cgd::load_scene_from_string(cgd::testing::test_scene_text("unit_suspension.toml"), "coupled_test.toml",
                                     overrides);
}

std::string num(double v) {
  std::ostringstream o;
  o.precision(17);
  o << v;
  std::string t = o.str();
  if (t.find_first_of(".eE") == std::string::npos) t += ".0";
  return t;
}

/// run_scene into dir/run on MPI_COMM_SELF, its banner and timing table kept out of the test log.
cgd::schema::Series read_series(const fs::path& run) {
  return cgd::schema::Series::read((run / "series.h5").string(), MPI_COMM_SELF);
}

/// The last snapshot of a run directory.
fs::path last_snapshot(const fs::path& run) {
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(run / "snapshots"))
    if (e.path().filename().string().rfind("snap_", 0) == 0) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  if (files.empty()) throw std::runtime_error("no snapshot in " + run.string());
  return files.back();
}

/// Time average of column `name` (component `c` of width `w`) over the series rows with t >= t0. Rows are
/// written at the start of each fluid step; each row's value holds for that step (its dt_fluid).
double time_average(const cgd::schema::Series& s, const std::string& name, int w, int c, double t0) {
  const auto& t = s.column("time");
  const auto& x = s.column(name);
  const auto& dt = s.column("dt_fluid");  // dt of the step that ended at this row
  double sum = 0.0, weight = 0.0;
  for (std::size_t r = 0; r + 1 < t.size(); ++r) {
    if (t[r] < t0) continue;
    const double h = dt[r + 1];  // the step that starts at row r
    sum += x[w * r + c] * h;
    weight += h;
  }
  return sum / weight;
}

// ---- (0) the viscous term is in conservative form ----------------------------------------------------
// The fluid's explicit rate is -rho div(M u) + div(eps tau): both are differences of face/edge/cell
// fluxes that are shared by two control volumes, so their sum over a periodic box vanishes to round-off
// for any eps field. With B = 0 and f = 0 the only net force left on the fluid is the pressure term
// -eps_f G p, which does not sum to zero where eps varies (its counterpart is the particles' -V_p grad p,
// docs/models.md eq. 3). So over each step
//     P^{n+1} - P^n = -dt sum_faces eps_f (G p^{n+1}) V_cell,   P = sum rho eps_f u V_cell,
// exactly in exact arithmetic (eps static, so eps_f is the same at both levels). The test integrates
// the defect of this balance over the run. The old form eps_f div(tau) leaves O(mu grad eps . grad u)
// behind: measured 1.3e-11 kg m/s, 1.2e-3 of sum |rho eps u V| and 38 % of the net pressure impulse
// (conservative form: 1.3e-25 kg m/s, 1e-17).
TEST(FluidViscousFlux, MomentumBalanceClosesWithVariableVoidFraction) {
  const int n = 16;
  const double h = 250e-6;
  FluidGrid grid(MPI_COMM_SELF, {n, n, n}, {n * h, n * h, n * h});
  FluidSettings s;  // air: rho 1.3, mu 1.8e-5
  FluidSolver solver(grid, s);
  auto& st = solver.state();
  // eps in [0.4, 1]: a few smooth modes (TSC-like smoothness) plus a rough per-cell part
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  const double L = n * h;
  for (int j = 0; j < n; ++j)
    for (int k = 0; k < n; ++k)
      for (int i = 0; i < n; ++i) {
        const double x = (i + 0.5) * h, y = (j + 0.5) * h, z = (k + 0.5) * h;
        const double smooth = 0.15 * std::sin(2 * kPi * x / L) * std::cos(4 * kPi * y / L + 0.3) +
                              0.1 * std::cos(2 * kPi * z / L) * std::sin(2 * kPi * (x + y) / L);
        st.void_fraction[grid.index(i, j, k)] = 0.7 + smooth + 0.05 * uni(rng);
      }
  // velocity: a shear flow plus random face values, ~0.1 m/s (the suspension's scale)
  for (int d = 0; d < 3; ++d)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k)
        for (int i = 0; i < n; ++i)
          st.velocity[d][grid.index(i, j, k)] =
              (d == 1 ? 0.2 * std::sin(2 * kPi * (i * h) / L) : 0.0) + 0.05 * uni(rng);
  solver.reset_history();
  const double vol = grid.cell_volume(), rho = s.density_kg_m3;
  // sum over the faces of eps_f (G p) V_cell, and of its magnitude
  auto pressure_force = [&](double& mag) {
    std::array<double, 3> f{0, 0, 0};
    const auto& p = st.pressure;
    const auto& e = st.void_fraction;
    const auto& xm = grid.x_minus();
    const auto& zm = grid.z_minus();
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k)
        for (int i = 0; i < n; ++i) {
          const std::size_t c = grid.index(i, j, k);
          const std::size_t cm[3] = {grid.index(xm[i], j, k), grid.index(i, j - 1, k),
                                     grid.index(i, j, zm[k])};
          for (int d = 0; d < 3; ++d) {
            const double t = 0.5 * (e[cm[d]] + e[c]) * (p[c] - p[cm[d]]) / h * vol;
            f[d] += t;
            mag += std::abs(t);
          }
        }
    return f;
  };
  double scale = 0.0;  // sum |rho eps_f u| V at the start
  for (int d = 0; d < 3; ++d)
    for (std::size_t c = grid.first_owned(); c < grid.first_owned() + grid.owned_size(); ++c)
      scale += rho * 0.7 * std::abs(st.velocity[d][c]) * vol;
  const auto P0 = solver.averages().momentum_kg_m_s;
  std::array<double, 3> impulse{0, 0, 0};
  double impulse_mag = 0.0;
  const int steps = 100;
  for (int step = 0; step < steps; ++step) {
    const double dt = solver.max_dt(0.3, 1.0);
    solver.step(dt);
    double mag = 0.0;
    const auto f = pressure_force(mag);
    for (int d = 0; d < 3; ++d) impulse[d] += dt * f[d];
    impulse_mag += dt * mag;
  }
  const auto P1 = solver.averages().momentum_kg_m_s;
  double defect = 0.0, net_pressure = 0.0;
  for (int d = 0; d < 3; ++d) {
    defect = std::max(defect, std::abs(P1[d] - P0[d] + impulse[d]));
    net_pressure = std::max(net_pressure, std::abs(impulse[d]));
  }
  std::printf(
      "[ conservative viscosity ] %d steps, eps in [0.4, 1]: |dP + impulse of -eps G p| = %.2e kg m/s, "
      "relative to sum|rho eps u V| %.2e, to the net pressure impulse %.2e\n",
      steps, defect, defect / scale, defect / net_pressure);
  // Round-off: each step adds ~3 n^3 terms of size <= scale/n^3 and impulse_mag/steps; ~1e-16 each,
  // accumulating like a random walk at worst linearly: 1e-14 of (scale + impulse_mag) covers 100 steps.
  EXPECT_LT(defect, 1e-14 * (scale + impulse_mag));
  // and the balance is not trivially satisfied: the pressure does push on the fluid
  EXPECT_GT(net_pressure, 1e3 * defect);
}

// ---- (1) one particle settles at the terminal velocity ----------------------------------------------
// One particle (solids_fraction = V_p / V_box, so round(phi V/V_p) = 1) in a periodic box with Wen-Yu drag:
// at eps -> 1 it is Schiller-Naumann, so the terminal slip is docs/models.md's u_t = 0.2185 m/s (Re_p 1.18).
// Reported: the domain-average slip of docs/models.md, <eps u>/<eps> - v (series column slip_velocity), and
// the slip the drag law sees, u_p - v (u_p interpolated at the particle, snapshot's fluid_velocity).
//
// What separates them is the particle's own disturbance of the fluid: the fluid gets -F_d spread by the
// TSC kernel over 3 x 3 x 3 cells and is dragged along near the particle, so u_p - <u> points the way the
// particle moves. The drag balance holds for u_p - v = u_t, and the domain slip is larger by this
// self-induced velocity. Measured (two-way, converged: 20-60 t_ref; domain slip / u_t):
//     cell 3.33 d_p: 1.097 (box 60 d_p), 1.104 (box 40 d_p)    cell 6 d_p:  1.052 (60), 1.043 (120)
//     cell 10 d_p:   1.028 (60), 1.0275 (120)                   cell 20 d_p: 1.012 (60)
//     cell 30 d_p:   1.0087 (120)                               cell 40 d_p: 1.0059 / 1.0064 / 1.0066
//                                                                            (120 / 160 / 200)
// while u_p - v stays within 0.2 % of u_t at every cell size. The bias is close to 0.3 d_p/Delta
// (0.32 at Delta = 3.33 d_p down to 0.26 at 30-40 d_p) and depends on the box only weakly: a local
// effect, the velocity a force F spread over a blob of size Delta induces at its centre, ~ F/(mu Delta)
// with F = 3 pi mu d_p u_t (1 + 0.15 Re^0.687). (A Stokeslet smoothed twice by the TSC -- deposit and
// interpolation -- gives 0.66 d_p/Delta in unbounded Stokes flow; the lattice and the inertia of the flow
// past the blob, Re_Delta = 1.18 Delta/d_p, presumably account for the lower measured constant.) So the
// paper's 3.33 d_p cells overestimate a lone particle's slip by ~10 %: the known self-induced velocity
// of unresolved CFD-DEM with a grid-scale kernel (in a suspension the other particles' drag screens it,
// test (2)). A test of the domain slip to 1 % needs the bias below 1 %, i.e. cells of >= 30 d_p: it runs
// at 40 d_p (bias 0.6 %, 4 cells in a 160 d_p box).
//
// One-way coupling (no drag on the fluid): the driving is hydrostatic (sim/run.hpp periodic_driving), so
// the fluid stays at rest and the particle's buoyant weight is exactly (rho_p - rho_f) V_p g. The drag law
// sees the particle's own deposit phi_p = (V_p/V_cell) sum_c w_c^2 ~ 1e-4 at 10 d_p cells (hindrance
// eps^-2.65: slip -2.5e-4), below 1e-3, the tolerance.
struct SettlingResult {
  double domain_slip_over_ut = 0.0;  // time-averaged from t0
  double local_slip_over_ut = 0.0;   // u_p - v at the final snapshot
};

SettlingResult settle_one_particle(double box_dp, double cell_dp, const std::string& coupling,
                                   double end_tref, double average_from_tref) {
  const double phi = kPi / 6.0 / (box_dp * box_dp * box_dp);
  const double t_ref = make_scene({}).derived.t_ref_s;
  const cgd::Scene scene =
      make_scene({"domain.size_dp=[" + num(box_dp) + ", " + num(box_dp) + ", " + num(box_dp) + "]",
                  "particles.solids_fraction=" + num(phi), "fluid.dx_over_dp=" + num(cell_dp),
                  "fluid.coupling=\"" + coupling + "\"", "fluid.drag=\"wen-yu\"",
                  // a lone particle never touches another: soft contacts, dt_DEM 0.29 ms
                  "contact.stiffness=8e-6", "run.end_time=" + num(end_tref * t_ref)});
  EXPECT_EQ(scene.derived.particle_count, 1);
  const double u_t = scene.derived.u_t_m_s;
  TempDir dir;
  const fs::path run = run_quietly(scene, dir);
  const auto series = read_series(run);
  SettlingResult r;
  // slip_velocity = <eps u>/<eps> - <v>; the particle falls (-y), the slip points up
  r.domain_slip_over_ut =
      time_average(series, "slip_velocity", 3, 1, average_from_tref * scene.derived.t_ref_s) / u_t;
  cgd::h5::File snap = cgd::h5::File::open_read(last_snapshot(run).string(), MPI_COMM_SELF);
  const auto v = snap.read_double("/particles/velocity");
  const auto u = snap.read_double("/particles/fluid_velocity");
  r.local_slip_over_ut = (u[1] - v[1]) / u_t;
  return r;
}

TEST(Coupled, SingleParticleReachesTerminalVelocity) {
  // docs/models.md's u_t is what the scene derives and what Wen-Yu gives at phi = 0
  const cgd::Scene base = make_scene({});
  const double u_t = cgd::terminal_velocity(cgd::DragLaw::WenYu, {1.3, 1.8e-5, 75e-6}, 1500.0, 9.81);
  EXPECT_NEAR(base.derived.u_t_m_s, u_t, 1e-12 * u_t);
  EXPECT_NEAR(u_t, 0.2185, 5e-5);

  // One-way: the particle relaxes with tau ~ t_ref (e^-10 after 10 t_ref); average over 10-15 t_ref.
  const SettlingResult one = settle_one_particle(120, 10, "one-way", 15, 10);
  // Two-way, 40 d_p cells: self-induced bias ~0.6 % (see above). The far field builds up over the box's
  // viscous time L^2/(4 pi^2 nu) = 0.26 s ~ 12 t_ref: slip/u_t = 0.997 at 5 t_ref, 1.003 at 10 t_ref,
  // 1.005 at 20 t_ref, 1.006 at 40-60 t_ref; average over 10-20 t_ref.
  const SettlingResult two = settle_one_particle(160, 40, "two-way", 20, 10);
  // Two-way at the paper's 3.33 d_p cells (box 40 d_p, 10 t_ref): the drag balance the law sees holds,
  // the domain slip carries the ~10 % self-induced velocity.
  const SettlingResult fine = settle_one_particle(40, 3.33, "two-way", 10, 7);
  std::printf(
      "[ single particle, Wen-Yu ] slip/u_t: one-way 10 d_p cells %.6f;  two-way 40 d_p cells %.5f "
      "(u_p - v: %.5f);  two-way 3.33 d_p cells %.4f (u_p - v: %.5f)\n",
      one.domain_slip_over_ut, two.domain_slip_over_ut, two.local_slip_over_ut, fine.domain_slip_over_ut,
      fine.local_slip_over_ut);
  EXPECT_NEAR(one.domain_slip_over_ut, 1.0, 1e-3);
  EXPECT_NEAR(one.local_slip_over_ut, 1.0, 1e-3);
  EXPECT_NEAR(two.domain_slip_over_ut, 1.0, 1e-2);
  EXPECT_NEAR(two.local_slip_over_ut, 1.0, 3e-3);
  // 3.33 d_p: the law's balance within 0.5 % (own deposit in the hindrance, -0.6 %; measured -0.1 %),
  // the domain slip biased by the self-induced velocity (measured +10.4 %: 0.3 d_p / Delta = 9 %).
  EXPECT_NEAR(fine.local_slip_over_ut, 1.0, 5e-3);
  EXPECT_GT(fine.domain_slip_over_ut, 1.05);
  EXPECT_LT(fine.domain_slip_over_ut, 1.15);
}

// ---- (1b) one-way suspension and the pressure-gradient force in coupled runs ------------------------------
// One-way coupling (sim/run.hpp periodic_driving, coupler.hpp): the particles do not act on the fluid (no
// drag on it, eps = 1 in its equations) and the fluid carries no particle weight (hydrostatic driving,
// G = rho_f g), so a fluid at rest stays at rest, exactly; each particle sees the fluid's buoyancy and
// settles at its single-particle drag balance
//     beta_p w = (rho_p - rho_f) g        (pressure_gradient_force = true)
//     beta_p w = rho_p g                  (pressure_gradient_force = false: no buoyancy either),
// exactly what a quiescent fluid gives (sim/run.cpp dem_settings_from_scene). Before the fix the driving
// used rho_mix whatever the coupling: at <phi> = 0.05 the fluid got eps (rho_f - rho_mix) g = -565 m/s^2
// with nothing to balance it (measured with this scene: 10.9 m/s upward after 19 ms, then the run failed
// on the Courant limit), and the particles (rho_p - rho_mix) V_p g, 5 % short. (With the right driving but
// eps in the fluid's equations, the fluid had to get out of the particles' way without being pushed: a
// displacement flow that grew, doubling every ~40 ms, to 0.025 m/s by 0.3 s and pulled the slip 1.6 % off.)
//
// Stokes drag (beta_p independent of phi and slip) makes the balance one number, u_St = weight d^2/(18 mu):
// every particle relaxes to it in tau_p = 26 ms; after 0.3 s (11.5 tau_p, e^-11.5 = 1e-5) the mean slip
// <u_p - v>_y of the one-way run and the quiescent run's -<v>_y must equal u_St. Tolerance 2e-4 relative
// (measured 1e-5: the transient); it is below rho_f/rho_p = 8.7e-4, so the test tells buoyancy on from off.
// Beetstra (the scenes' law) at <phi> = 0.05: each particle's balance is beta_p(phi_p, w) w = weight at its
// own phi_p; the phi_p-dependence (hindrance) lets concentration waves grow, and the particles' mean
// acceleration rho_p d<v>/dt moves <beta_p (u_p - v)> off the weight (measured 0.997-1.013 over 0.075-0.2 s):
// tolerance 3 % at 0.1 s. The fluid velocity must stay 0 there (bound 1e-3 u_t; before the fix: 10.9 m/s).
TEST(Coupled, OneWaySuspensionSettlesAtSingleParticleBalance) {
  const double u_stokes_no_buoyancy = 1500.0 * 9.81 * 75e-6 * 75e-6 / (18.0 * 1.8e-5);
  for (const bool pressure_force : {true, false}) {
    const std::string pgf = std::string("fluid.pressure_gradient_force=") + (pressure_force ? "true" : "false");
    const double u_st = u_stokes_no_buoyancy * (pressure_force ? 1.0 - 1.3 / 1500.0 : 1.0);
    double slip[2] = {0.0, 0.0};  // quiescent, one-way
    for (int k = 0; k < 2; ++k) {
      const cgd::Scene scene =
          make_scene({"particles.solids_fraction=0.05", std::string("fluid.coupling=") + (k ? "\"one-way\"" : "\"quiescent\""),
                      "fluid.drag=\"stokes\"", pgf, "run.end_time=0.3"});
      TempDir dir;
      const fs::path run = run_quietly(scene, dir);
      cgd::h5::File snap = cgd::h5::File::open_read(last_snapshot(run).string(), MPI_COMM_SELF);
      const auto v = snap.read_double("/particles/velocity");
      const auto u = k ? snap.read_double("/particles/fluid_velocity") : std::vector<double>(v.size(), 0.0);
      for (std::size_t i = 1; i < v.size(); i += 3) slip[k] += u[i] - v[i];
      slip[k] /= static_cast<double>(v.size() / 3);
    }
    std::printf(
        "[ one-way vs quiescent, Stokes drag ] phi 0.05, pressure-gradient force %s: mean slip quiescent %.7f, "
        "one-way %.7f m/s, balance %.7f m/s (rel. dev. %+.2e, %+.2e)\n",
        pressure_force ? "on" : "off", slip[0], slip[1], u_st, slip[0] / u_st - 1.0, slip[1] / u_st - 1.0);
    EXPECT_NEAR(slip[0] / u_st, 1.0, 2e-4) << pgf;
    EXPECT_NEAR(slip[1] / u_st, 1.0, 2e-4) << pgf;
  }

  const cgd::Scene scene = make_scene({"particles.solids_fraction=0.05", "fluid.coupling=\"one-way\"",
                                       "run.end_time=0.1", "run.dump_interval=0.05"});
  const double u_t = scene.derived.u_t_m_s, weight = (1500.0 - 1.3) * 9.81;  // N/m^3 of particle
  TempDir dir;
  const fs::path run = run_quietly(scene, dir);
  cgd::h5::File snap = cgd::h5::File::open_read(last_snapshot(run).string(), MPI_COMM_SELF);
  const auto v = snap.read_double("/particles/velocity");
  const auto u = snap.read_double("/particles/fluid_velocity");
  const auto beta = snap.read_double("/particles/drag_coefficient");
  const auto uf = snap.read_double("/fluid/velocity");
  double drag = 0.0, uf_max = 0.0;
  for (std::size_t i = 0; i < beta.size(); ++i) drag += beta[i] * (u[3 * i + 1] - v[3 * i + 1]);
  drag /= static_cast<double>(beta.size());
  for (double x : uf) uf_max = std::max(uf_max, std::abs(x));
  const auto series = read_series(run);
  double mean_u_max = 0.0;
  for (double x : series.column("fluid_velocity_mean")) mean_u_max = std::max(mean_u_max, std::abs(x));
  std::printf(
      "[ one-way suspension, Beetstra ] phi 0.05, %lld particles, t = 0.1 s: <beta (u_p - v)_y> / weight %.4f; "
      "fluid max |u| %.3g m/s (%.3g u_t), max |<u>| %.3g m/s\n",
      static_cast<long long>(scene.derived.particle_count), drag / weight, uf_max, uf_max / u_t, mean_u_max);
  EXPECT_NEAR(drag / weight, 1.0, 0.03);
  EXPECT_LT(uf_max, 1e-3 * u_t);
  EXPECT_LT(mean_u_max, 1e-3 * u_t);
}

// ---- (2) homogeneous suspension: the drag balance ---------------------------------------------------
// A 12 d_p box (3 L_char; 4 cells of 3 d_p, dx_over_dp = 3.33) at phi = 0.1 and 0.3 with Beetstra and
// Wen-Yu, from rest. The mean particle momentum balance in a homogeneous state is
//     <beta_p (u_p - v)> = (rho_p - rho_mix) g = eps (rho_p - rho_f) g,
// (the mean of the perturbation pressure gradient vanishes), i.e. docs/models.md's balance, whose root is
// homogeneous_slip_over_ut. Time scales: the mean slip settles within ~2 ms (the light fluid follows in
// rho_f eps/(phi beta) ~ 0.1 ms; the particles relax in tau = slip/(eps g') = 5-18 ms, but start from rest
// with the fluid, so the slip itself is set by the fast fluid response).
//
// The homogeneous state is unstable even in this box: grid-scale concentration waves grow from the
// random placement (max cell phi 0.32 -> 0.34 by 20 ms at phi = 0.3, -> 0.43-0.50 after 50-100 ms;
// the same in 10 d_p and 8 d_p boxes of 3 cells), after which the slip leaves the homogeneous value
// (measured over 0.1-0.2 s: Beetstra phi = 0.1 +6 %, 0.3 -21 %; Wen-Yu 0.1 +1.6 %, 0.3 between -7 and
// +10 %). So the test averages over 5-25 ms, after the slip transient and before the structure grows,
// and checks that the suspension is still homogeneous then (max cell phi within 0.08 of <phi>).
//
// What biases the domain slip of a homogeneous state (measured at 5-25 ms, seed 1, in % of the slip;
// Beetstra 0.1 / Wen-Yu 0.1 / Beetstra 0.3 / Wen-Yu 0.3):
//   * the fluid velocity the law sees: each particle drags its own neighbourhood along (the self-induced
//     velocity of test (1), screened by the other particles' drag): domain slip - <u_p - v> = +1.7 /
//     +1.5 / +0.06 / +0.1 %;
//   * the solids fraction the law sees: <phi_p> = <phi_c^2>/<phi_c> > <phi> (own deposit plus placement
//     fluctuations, TSC-smoothed; the denser random packing fluctuates less): 0.1021 / 0.1020 / 0.3003 /
//     0.3005, which lowers the balance slip by -1.2 / -0.7 / -0.1 / -0.3 %;
//   * the rest (<u_p - v> against the balance at <phi_p>: +0.4 / +0.2 / +0.06 / +0.03 %): the particles'
//     mean pressure gradient (-0.01..-0.05 % of the buoyant weight), velocity fluctuations (horizontal
//     slip rms <= 0.45 % of u_t: |u_p - v| and beta change by ~1e-5), the coupling's time lag.
// Net: +0.9 / +1.0 / -0.05 / -0.2 %; seeds 2 and 3 within [-0.2, +0.8] %. Tolerance 2 %.
TEST(Coupled, HomogeneousSuspensionMatchesDragBalance) {
  struct Case {
    const char* law;
    cgd::DragLaw drag;
    double phi;
  };
  const Case cases[] = {{"beetstra", cgd::DragLaw::Beetstra, 0.1},
                        {"beetstra", cgd::DragLaw::Beetstra, 0.3},
                        {"wen-yu", cgd::DragLaw::WenYu, 0.1},
                        {"wen-yu", cgd::DragLaw::WenYu, 0.3}};
  for (const Case& c : cases) {
    const cgd::Scene scene = make_scene({"particles.solids_fraction=" + num(c.phi),
                                         "fluid.drag=\"" + std::string(c.law) + "\"", "run.end_time=0.025"});
    ASSERT_EQ(scene.derived.cells, (std::array<int, 3>{4, 4, 4}));
    const double u_t = scene.derived.u_t_m_s;
    const double phi = static_cast<double>(scene.derived.particle_count) * scene.derived.particle_volume_m3 /
                       (scene.domain.size_m[0] * scene.domain.size_m[1] * scene.domain.size_m[2]);
    const double expected =
        cgd::homogeneous_slip_over_ut(c.drag, {1.3, 1.8e-5, 75e-6}, phi, 1500.0, 9.81, u_t);
    TempDir dir;
    const fs::path run = run_quietly(scene, dir);
    const auto series = read_series(run);
    const double slip = time_average(series, "slip_velocity", 3, 1, 0.005) / u_t;
    const auto& max_phi = series.column("max_solids_fraction");
    const auto& floored = series.column("floored_cells");
    const double phi_max = *std::max_element(max_phi.begin(), max_phi.end());
    cgd::h5::File snap = cgd::h5::File::open_read(last_snapshot(run).string(), MPI_COMM_SELF);
    const auto v = snap.read_double("/particles/velocity");
    const auto u = snap.read_double("/particles/fluid_velocity");
    double local = 0.0;
    for (std::size_t i = 1; i < v.size(); i += 3) local += u[i] - v[i];
    local /= static_cast<double>(v.size() / 3) * u_t;
    std::printf(
        "[ homogeneous suspension ] %-8s phi %.3f (%lld particles): <slip_y>/u_t %.4f, drag balance %.4f, "
        "deviation %+.2f %%; <u_p - v>_y/u_t %.4f at t_end; max cell phi %.3f\n",
        c.law, phi, static_cast<long long>(scene.derived.particle_count), slip, expected,
        100.0 * (slip / expected - 1.0), local, phi_max);
    EXPECT_NEAR(slip / expected, 1.0, 0.02) << c.law << " phi " << c.phi;
    EXPECT_LT(phi_max, c.phi + 0.08) << "the suspension is no longer homogeneous in the averaging window";
    EXPECT_EQ(*std::max_element(floored.begin(), floored.end()), 0.0);
  }
}

// ---- (3) mixture momentum -------------------------------------------------------------------------------
// Every force in the coupled system has its counterpart, so the total momentum
//     P = sum_p m v_p + sum_faces rho_f eps_f u V_cell
// is conserved to round-off (docs/models.md's periodic driving makes the net external force zero):
//   * drag: the fluid gets dt sum B_f (V_f - u_f^{n+1}) V_cell, the particles dt sum beta V_p
//     (u_p^{n+1} - v): equal and opposite because face values are means of the two cells, cell-centred u
//     the mean of the two faces, and deposition and interpolation are transposes (coupler.hpp);
//   * pressure: the fluid's -sum_faces eps_f (G p) V and the particles' -sum V_p (grad p)_p, whose TSC
//     interpolation of the central-difference gradient sums to -sum_faces phi_f (G p) V (the central
//     difference is the mean of the two face gradients): together -sum_faces (G p) V = 0, periodic --
//     exactly only where eps + phi = 1 in every cell, i.e. where the void-fraction floor (coupler.hpp:
//     eps_min = 0.3, which moves volume between cells) is not active: the test checks floored_cells = 0;
//   * the driving: eps (rho_f - rho_mix) g on the fluid, (rho_p - rho_mix) V_p g on the particles, summing
//     to (<eps> rho_f + <phi> rho_p - rho_mix) g V_box = 0;
//   * advection and viscosity are differences of shared fluxes (test (0)), contacts are pairwise.
// With docs/models.md's eps div(tau) instead of div(eps tau) this case drifts by 2.6e-12 kg m/s over the 300
// steps, 5.6 % of the largest fluid momentum (1.7e-4 of the scale below); with div(eps tau), 6e-24.
// The particles' momentum is taken from the leapfrog velocities v_{n-1/2} at fluid-step boundaries
// (DemSystem::diagnostics(false)), the velocities the drag used; the fluid's right after its step, with
// the eps of that step. The loop is RunDriver::time_loop_coupled's, assembled here to see the fluid's
// momentum at that point (the series has only the particles').
// The one combination that would not conserve it, two-way coupling without the pressure-gradient force
// (the fluid's -eps grad p' has no counterpart on the particles; the fluid drifted at 0.6 m/s^2 at
// phi = 0.1), is refused by scene validation, naming the key and what is allowed.
TEST(Coupled, MixtureMomentumConserved) {
  try {
    make_scene({"particles.solids_fraction=0.1", "fluid.pressure_gradient_force=false"});
    ADD_FAILURE() << "a two-way scene without the pressure-gradient force was accepted";
  } catch (const cgd::InputError& e) {
    const std::string what = e.what();
    for (const char* part : {"fluid.pressure_gradient_force = false", "two-way", "one-way", "quiescent"})
      EXPECT_NE(what.find(part), std::string::npos) << part << " not in: " << what;
  }
  EXPECT_NO_THROW(make_scene({"fluid.coupling=\"one-way\"", "fluid.pressure_gradient_force=false"}));

  const cgd::Scene scene = make_scene({"particles.solids_fraction=0.2", "particles.velocity_rms=0.05",
                                       "contact.friction=0.1", "fluid.drag=\"beetstra\""});
  MPI_Comm comm = MPI_COMM_SELF;
  const cgd::FluidConfig& fc = *scene.fluid;
  const cgd::Vec3& g = scene.domain.gravity_m_s2;
  FluidGrid grid(comm, scene.derived.cells, scene.domain.size_m);
  cgd::dem::DemSystem dem(cgd::dem_settings_from_scene(scene), comm);
  const auto placement =
      cgd::dem::place_particles(scene.domain.size_m, dem.settings().diameter_m, scene.derived.particle_count,
                                scene.particles.velocity_rms_m_s, scene.particles.seed);
  std::vector<std::int64_t> ids(static_cast<std::size_t>(scene.derived.particle_count));
  for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = static_cast<std::int64_t>(i);
  dem.set_particles(ids, placement.position, placement.velocity, {});
  const double volume = scene.domain.size_m[0] * scene.domain.size_m[1] * scene.domain.size_m[2];
  const double phi =
      static_cast<double>(scene.derived.particle_count) * scene.derived.particle_volume_m3 / volume;
  const double rho_mix = phi * scene.particles.density_kg_m3 + (1.0 - phi) * fc.density_kg_m3;
  FluidSettings fs;
  fs.density_kg_m3 = fc.density_kg_m3;
  fs.viscosity_Pa_s = fc.viscosity_Pa_s;
  for (int d = 0; d < 3; ++d) fs.body_force_per_fluid_volume_N_m3[d] = (fc.density_kg_m3 - rho_mix) * g[d];
  FluidSolver fluid(grid, fs);
  cgd::coupling::CouplerSettings cs;
  cs.drag = fc.drag;
  cs.drag_params = {fc.density_kg_m3, fc.viscosity_Pa_s, scene.particles.diameter_m};
  cs.particle_volume_m3 = scene.derived.particle_volume_m3;
  cs.parcel_volume_factor = 1.0;
  cs.particle_mass_kg = scene.derived.parcel_mass_kg;
  cs.two_way = true;
  cs.pressure_gradient_force = true;
  for (int d = 0; d < 3; ++d)
    cs.particle_body_accel[d] = g[d] * (1.0 - rho_mix / scene.particles.density_kg_m3);
  cgd::coupling::Coupler coupler(cs, grid);
  const double dt_cap = 0.5 * scene.particles.density_kg_m3 /
                        cgd::beta_p(fc.drag, cs.drag_params, 1.0 - cs.void_fraction_floor, 0.0);
  const double dt = dem.settings().dt_s, m = dem.settings().mass_kg;

  // magnitude scale of the momentum: sum m |v| + sum rho_f eps_f |u| V (its largest value over the run)
  auto particle_scale = [&] {
    const auto& p = dem.particles();
    double s = 0.0;
    for (std::size_t i = 0; i < 3 * p.n_owned; ++i) s += m * std::abs(p.v[i]);
    return s;
  };
  auto fluid_scale = [&] {
    const auto& st = fluid.state();
    double s = 0.0;
    for (int d = 0; d < 3; ++d)
      for (std::size_t c = grid.first_owned(); c < grid.first_owned() + grid.owned_size(); ++c)
        s += fc.density_kg_m3 * std::abs(st.velocity[d][c]) * grid.cell_volume();  // eps_f <= 1
    return s;
  };
  const auto P0 = dem.diagnostics(false).momentum;  // the fluid starts at rest
  double scale = particle_scale(), drift = 0.0, max_fluid = 0.0;
  long long floored = 0;
  const int fluid_steps = 300;
  for (int k = 0; k < fluid_steps; ++k) {
    dem.prepare();  // a due rebuild (wrap, migrate) before the deposit, as RunDriver does
    coupler.compute_drag(dem.particles(), fluid.state());
    floored = std::max(floored, coupler.floored_cells());
    if (k == 0) fluid.reset_history();
    const std::int64_t n_sub =
        std::max<std::int64_t>(1, static_cast<std::int64_t>(fluid.max_dt(fc.courant, dt_cap) / dt));
    fluid.step(static_cast<double>(n_sub) * dt);
    const auto Pf = fluid.averages().momentum_kg_m_s;  // with eps^{n+1}, the level of u^{n+1}
    coupler.compute_particle_forces(dem.particles(), fluid.state());
    for (std::int64_t s_ = 0; s_ < n_sub; ++s_) dem.step();
    const auto Pp = dem.diagnostics(false).momentum;
    scale = std::max(scale, particle_scale() + fluid_scale());
    for (int d = 0; d < 3; ++d) {
      drift = std::max(drift, std::abs(Pf[d] + Pp[d] - P0[d]));
      max_fluid = std::max(max_fluid, std::abs(Pf[d]));
    }
  }
  std::printf(
      "[ mixture momentum ] %d fluid steps (%lld DEM steps), phi 0.2, %lld particles: "
      "max |P - P0| = %.2e kg m/s, %.2e of sum |m v| + |rho eps u V| (%.2e); largest fluid momentum %.2e; "
      "floored cells %lld\n",
      fluid_steps, static_cast<long long>(dem.step_index()),
      static_cast<long long>(scene.derived.particle_count), drift, drift / scale, scale, max_fluid, floored);
  ASSERT_EQ(floored, 0);
  // Round-off: each fluid step adds O(eps_mach) of the momentum magnitudes to the sums (3 n_cells face
  // terms, N particles, n_sub leapfrog kicks): bound 10 ulp of the scale per fluid step.
  EXPECT_LT(drift, fluid_steps * 10 * 2.2e-16 * scale);
  EXPECT_GT(max_fluid, 1e6 * drift);  // the fluid does carry momentum: the test is not vacuous
}

}  // namespace

// ---- (6) parcels (docs/models.md "Parcels"; docs/coarse.md) ---------------------------------------------------
namespace {

// A lone parcel of size alpha: drag alpha^3 V_p beta_p(phi, w) w with beta_p evaluated with the primary
// diameter, weight alpha^3 V_p (rho_p - rho_f) g: both scale with alpha^3, so it settles at the primary's
// u_t -- up to its own volume, which the drag law sees as a local solids fraction (the void fraction is
// deposited with alpha^3 V_p): phi_self = alpha^3 V_p / V_cell x sum_c w_c^2 <= alpha^3 V_p / V_cell x
// 0.594^3 (TSC, at a cell centre), and Wen-Yu's eps^-2.65 lowers the slip by at most ~2.65 phi_self (at
// 10 d_p cells and alpha = 6 that is 4.4 %: measured 4.4 %). One-way coupling on 30 d_p cells (4 across
// the 120 d_p box), averaged over 10-15 t_ref as the single-particle test: tolerance 1e-3 (as there) plus
// 2.65 phi_self,max (0.04 % at alpha = 3, 0.2 % at alpha = 6).
TEST(Parcels, LoneParcelSettlesAtThePrimaryTerminalVelocity) {
  for (double alpha : {3.0, 6.0}) {
    const double box = 120, cell = 30;
    const double phi = std::pow(alpha, 3) * kPi / 6.0 / (box * box * box);  // one parcel
    const double t_ref = make_scene({}).derived.t_ref_s;
    const cgd::Scene scene = make_scene({"domain.size_dp=[120, 120, 120]", "particles.solids_fraction=" + num(phi),
                                         "particles.parcel_size=" + num(alpha), "fluid.dx_over_dp=" + num(cell),
                                         "fluid.coupling=\"one-way\"", "fluid.drag=\"wen-yu\"",
                                         // the primary's soft contacts, scaled so that the parcel's t_c
                                         // (hence dt_DEM) is the primary's: k alpha / (m alpha^3) fixed
                                         "contact.stiffness=" + num(8e-6 * alpha * alpha),
                                         "run.end_time=" + num(15 * t_ref)});
    ASSERT_EQ(scene.derived.particle_count, 1);
    TempDir dir;
    const fs::path run = run_quietly(scene, dir);
    const double slip = time_average(read_series(run), "slip_velocity", 3, 1, 10 * t_ref) / scene.derived.u_t_m_s;
    const double phi_self_max = std::pow(alpha, 3) * kPi / 6.0 / (cell * cell * cell) * std::pow(0.59375, 3);
    std::printf("[ lone parcel ] alpha %.0f: slip/u_t %.6f (own-volume bound %.4f)\n", alpha, slip, 2.65 * phi_self_max);
    EXPECT_NEAR(slip, 1.0, 1e-3 + 2.65 * phi_self_max) << "alpha " << alpha;
  }
}

// fluid.drag_own_deposit = false (issue 28): the drag's phi at a parcel leaves out the parcel's own deposit
// alpha^3 V_p sum_c w_c^2 / V_cell, so a lone parcel sees phi = 0 and settles at u_t exactly as a lone
// primary does, even where its own deposit is large: alpha = 6 on 10 d_p cells, where with its own deposit
// (the default) Wen-Yu's eps^-2.65 lowers the slip by ~2.65 phi_self = 4.4 % (the test above's note). Both
// runs: one-way coupling, 10-15 t_ref averaged; without: 1 within 1e-3 (the single-particle tolerance);
// with: below 1 by more than half the own-volume estimate (so the key is seen to act).
TEST(Parcels, LoneParcelWithoutItsOwnDepositSettlesAtTheTerminalVelocity) {
  const double alpha = 6, box = 120, cell = 10;
  const double phi = std::pow(alpha, 3) * kPi / 6.0 / (box * box * box);
  const double t_ref = make_scene({}).derived.t_ref_s;
  const double phi_self_max = std::pow(alpha, 3) * kPi / 6.0 / (cell * cell * cell) * std::pow(0.59375, 3);
  double slips[2] = {0, 0};
  for (int own = 0; own < 2; ++own) {
    const cgd::Scene scene = make_scene({"domain.size_dp=[120, 120, 120]", "particles.solids_fraction=" + num(phi),
                                         "particles.parcel_size=" + num(alpha), "fluid.dx_over_dp=" + num(cell),
                                         "fluid.coupling=\"one-way\"", "fluid.drag=\"wen-yu\"",
                                         std::string("fluid.drag_own_deposit=") + (own ? "true" : "false"),
                                         "contact.stiffness=" + num(8e-6 * alpha * alpha),
                                         "run.end_time=" + num(15 * t_ref)});
    ASSERT_EQ(scene.derived.particle_count, 1);
    ASSERT_EQ(scene.fluid->drag_own_deposit, own == 1);
    TempDir dir;
    const fs::path run = run_quietly(scene, dir);
    slips[own] = time_average(read_series(run), "slip_velocity", 3, 1, 10 * t_ref) / scene.derived.u_t_m_s;
  }
  std::printf("[ lone parcel, alpha 6, 10 d_p cells ] slip/u_t without its own deposit %.6f, with %.6f (estimate %.4f)\n",
              slips[0], slips[1], 1.0 - 2.65 * phi_self_max);
  EXPECT_NEAR(slips[0], 1.0, 1e-3);
  EXPECT_LT(slips[1], 1.0 - 0.5 * 2.65 * phi_self_max);
}

// A homogeneous suspension of parcels: per primary volume the balance is the primaries' (docs/models.md),
// beta_p(phi, w) w = eps (rho_p - rho_f) g, so the slip is the drag-law balance at <phi> whatever alpha.
// The same setting and tolerance (2 %) as HomogeneousSuspensionMatchesDragBalance, alpha = 2 in a
// 30 d_p box on 5 d_p cells (6 x 6 x 6, 645 parcels at phi = 0.1: ~3 parcels per cell, so the void
// fraction's parcel noise stays near the primaries' on 3.33 d_p cells).
TEST(Parcels, HomogeneousParcelSuspensionMatchesDragBalance) {
  const cgd::Scene scene = make_scene({"domain.size_dp=[30, 30, 30]", "particles.parcel_size=2", "fluid.dx_over_dp=5",
                                       "particles.solids_fraction=0.1", "run.end_time=0.025"});
  const double u_t = scene.derived.u_t_m_s;
  const double phi = static_cast<double>(scene.derived.particle_count) * 8.0 * scene.derived.particle_volume_m3 /
                     (scene.domain.size_m[0] * scene.domain.size_m[1] * scene.domain.size_m[2]);
  const double expected = cgd::homogeneous_slip_over_ut(cgd::DragLaw::Beetstra, {1.3, 1.8e-5, 75e-6}, phi, 1500.0, 9.81, u_t);
  TempDir dir;
  const fs::path run = run_quietly(scene, dir);
  const double slip = time_average(read_series(run), "slip_velocity", 3, 1, 0.005) / u_t;
  std::printf("[ parcel suspension ] alpha 2, phi %.3f (%lld parcels): slip/u_t %.4f, balance %.4f (%+.2f %%)\n", phi,
              static_cast<long long>(scene.derived.particle_count), slip, expected, 100 * (slip / expected - 1));
  EXPECT_NEAR(slip / expected, 1.0, 0.02);
}

// Parcel contacts (docs/models.md "Parcels"): k_n,parcel = alpha k_n with the parcel mass alpha^3 m, gamma_n
// from the same restitution, so for any alpha
//   e = exp(-beta pi / omega) is the scene's restitution,       beta = gamma_n/(2 m_eff), omega the damped frequency;
//   t_c / (d / v) and the relative overlap v / (omega d) are alpha-independent (t_c, d both ~ alpha).
// Computed here from the scene's derived k_n, gamma_n, t_c independently of core/scales.hpp; the DEM
// realises a contact of given (k_n, gamma_n, m) to 0.5 % (DemBinaryCollision.HeadOnRestitutionAndContactTime).
TEST(Parcels, ContactScalingKeepsRestitutionRelativeContactTimeAndOverlap) {
  const cgd::Scene one = make_scene({"domain.size_dp=[40, 40, 40]"});
  for (double alpha : {2.0, 4.0, 8.0}) {
    const cgd::Scene s = make_scene({"domain.size_dp=[40, 40, 40]", "particles.parcel_size=" + num(alpha)});
    const auto& x = s.derived;
    const double m_eff = 0.5 * x.parcel_mass_kg;
    const double beta = x.gamma_n_kg_s / (2 * m_eff), omega = std::sqrt(x.k_n_N_m / m_eff - beta * beta);
    EXPECT_NEAR(std::exp(-beta * kPi / omega), 0.9, 1e-12) << "alpha " << alpha;
    EXPECT_NEAR(kPi / omega, x.t_c_s, 1e-12 * x.t_c_s);
    EXPECT_NEAR(x.k_n_N_m / one.derived.k_n_N_m, alpha, 1e-12 * alpha);
    EXPECT_NEAR(x.gamma_n_kg_s / one.derived.gamma_n_kg_s, alpha * alpha, 1e-10 * alpha * alpha);
    const double v = 0.1;  // impact speed, m/s
    EXPECT_NEAR(x.t_c_s / (x.parcel_diameter_m / v), one.derived.t_c_s / (one.derived.parcel_diameter_m / v), 1e-12);
    const double omega1 = std::sqrt(one.derived.k_n_N_m / (0.5 * one.derived.parcel_mass_kg));
    const double omega_undamped = std::sqrt(x.k_n_N_m / m_eff);
    EXPECT_NEAR(v / (omega_undamped * x.parcel_diameter_m), v / (omega1 * one.derived.parcel_diameter_m), 1e-14);
    EXPECT_NEAR(x.dt_dem_s / one.derived.dt_dem_s, alpha, 1e-12 * alpha);
  }
}

}  // namespace
