// Verification of the fluid solver (sim/fluid, model A of docs/models.md) against known answers:
// the Taylor–Green vortex and its order of convergence, the exactness of the FFT preconditioner, the
// continuity of a variable-eps step with strong drag, the implicit drag update, momentum conservation
// and free-stream preservation. Single process (the slab decomposition is tested in tests/mpi).
#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <random>

#include "sim/fluid/solver.hpp"
#include "fluid_test_util.hpp"

namespace {

using cgd::fluid::FluidGrid;
using cgd::fluid::FluidSettings;
using cgd::fluid::FluidSolver;
using cgd::fluid::test::fill_cells;
using cgd::fluid::test::fill_faces;
using cgd::fluid::Preconditioner;
using cgd::fluid::PressureSettings;
using cgd::fluid::PressureSolver;
constexpr double kPi = std::numbers::pi;

double max_owned(const FluidGrid& g, const std::vector<double>& f) {
  double m = 0.0;
  for (std::size_t c = g.first_owned(); c < g.first_owned() + g.owned_size(); ++c)
    m = std::max(m, std::abs(f[c]));
  return m;
}

// ---- (1) Taylor–Green vortex -----------------------------------------------------------------------
// u = U sin(kx) cos(ky), v = -U cos(kx) sin(ky) with eps = 1, B = 0 is an exact Navier–Stokes solution
// decaying as exp(-2 nu k^2 t) (the nonlinear term is balanced by the pressure). Unit box, k = 2 pi,
// nu = 0.05 (Re = U/(k nu) = 3.2): viscosity dominated, so the run to t = 1/(2 nu k^2) (decay to 1/e)
// is short. Error: max over all faces at t_end, relative to the exact amplitude.
double taylor_green_error(int n) {
  FluidGrid grid(MPI_COMM_SELF, {n, n, 1}, {1.0, 1.0, 1.0 / n});
  FluidSettings s;
  s.density_kg_m3 = 1.0;
  s.viscosity_Pa_s = 0.05;
  FluidSolver solver(grid, s);
  const double k = 2.0 * kPi, U = 1.0, nu = 0.05;
  auto& st = solver.state();
  fill_faces(grid, 0, st.velocity[0],
             [&](double x, double y, double) { return U * std::sin(k * x) * std::cos(k * y); });
  fill_faces(grid, 1, st.velocity[1],
             [&](double x, double y, double) { return -U * std::cos(k * x) * std::sin(k * y); });
  solver.reset_history();
  const double t_end = 1.0 / (2.0 * nu * k * k);
  const int steps = static_cast<int>(std::ceil(t_end / solver.max_dt(0.3, 1.0)));
  const double dt = t_end / steps;
  for (int s_ = 0; s_ < steps; ++s_) solver.step(dt);
  const double amp = U * std::exp(-2.0 * nu * k * k * t_end);
  std::vector<double> ex = grid.make_field(), ey = grid.make_field();
  fill_faces(grid, 0, ex,
             [&](double x, double y, double) { return amp * std::sin(k * x) * std::cos(k * y); });
  fill_faces(grid, 1, ey,
             [&](double x, double y, double) { return -amp * std::cos(k * x) * std::sin(k * y); });
  double err = 0.0;
  for (std::size_t c = grid.first_owned(); c < grid.first_owned() + grid.owned_size(); ++c)
    err = std::max({err, std::abs(st.velocity[0][c] - ex[c]), std::abs(st.velocity[1][c] - ey[c])});
  return err / amp;
}

TEST(FluidTaylorGreen, DecayRateConvergesAtSecondOrder) {
  const double e16 = taylor_green_error(16), e32 = taylor_green_error(32), e64 = taylor_green_error(64);
  const double p1 = std::log2(e16 / e32), p2 = std::log2(e32 / e64);
  std::printf("[ Taylor-Green ] max rel. error 16^2 %.3e  32^2 %.3e  64^2 %.3e  order %.3f %.3f\n", e16, e32,
              e64, p1, p2);
  // Central differences on the MAC grid and AB2 in time (dt ~ h^2 here, viscous limit): second order.
  EXPECT_GT(p1, 1.8);
  EXPECT_GT(p2, 1.8);
  EXPECT_LT(e64, 1e-2);
}

// ---- (2) The FFT preconditioner is the exact inverse for constant K ---------------------------------
// With constant K the operator is K times the 7-point Laplacian whose eigenvalues the FFT solve uses
// exactly, so PCG from p = 0 converges in one iteration; 1e-12 is round-off of the FFT and the stencil.
TEST(FluidPressure, FftPreconditionerIsExactForConstantCoefficient) {
  FluidGrid grid(MPI_COMM_SELF, {12, 10, 7}, {1.0, 0.7, 0.45});  // odd n_z, anisotropic cells
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  for (Preconditioner pc : {Preconditioner::ArithmeticMean, Preconditioner::HarmonicMean,
                            Preconditioner::DiagonalScaled, Preconditioner::Sandwich}) {
    PressureSettings ps;
    ps.tolerance = 1e-12;
    ps.preconditioner = pc;
    PressureSolver solver(grid, ps);
    std::array<std::vector<double>, 3> K{grid.make_field(3.7), grid.make_field(3.7), grid.make_field(3.7)};
    std::vector<double> b = grid.make_field(), p = grid.make_field();
    fill_cells(grid, b, [&](double, double, double) { return uni(rng); });
    const auto st = solver.solve(K, b, p);
    EXPECT_LE(st.iterations, 1) << "preconditioner " << static_cast<int>(pc);
    EXPECT_LT(st.residual, 1e-12);
    // The constant-coefficient solve on its own: (c L) z = r.
    std::vector<double> z = grid.make_field(), Az = grid.make_field();
    solver.solve_constant_coefficient(b, z, 3.7);
    grid.exchange_ghosts({z.data()}, 1);
    solver.apply_operator(K, z, Az);
    double err = 0.0;
    for (std::size_t c = grid.first_owned(); c < grid.first_owned() + grid.owned_size(); ++c)
      err = std::max(err, std::abs(Az[c] - b[c]));
    EXPECT_LT(err / max_owned(grid, b), 1e-12);
  }
}

// Variable K (a factor 20 between min and max): PCG's iterates are unchanged when the preconditioner is
// scaled by a constant, so the arithmetic and the harmonic mean of K must take the same iterations
// (to round-off: +-1); the diagonally scaled FFT solve is reported beside them.
TEST(FluidPressure, ConstantCoefficientVariantsTakeTheSameIterations) {
  FluidGrid grid(MPI_COMM_SELF, {16, 32, 16}, {1.0, 2.0, 1.0});
  std::array<std::vector<double>, 3> K{grid.make_field(), grid.make_field(), grid.make_field()};
  for (int d = 0; d < 3; ++d)
    fill_faces(grid, d, K[d], [](double x, double y, double z) {
      return 1.0 + 0.9 * std::sin(2 * kPi * x) * std::cos(kPi * y) * std::sin(2 * kPi * z + 0.3);
    });
  std::vector<double> b0 = grid.make_field();
  fill_cells(grid, b0, [](double x, double y, double z) {
    return std::sin(2 * kPi * x + 0.1) * std::sin(kPi * y) +
           0.5 * std::cos(6 * kPi * z) * std::cos(3 * kPi * y);
  });
  int it[4];
  int n = 0;
  for (Preconditioner pc : {Preconditioner::ArithmeticMean, Preconditioner::HarmonicMean,
                            Preconditioner::DiagonalScaled, Preconditioner::Sandwich}) {
    PressureSettings ps;
    ps.preconditioner = pc;
    PressureSolver solver(grid, ps);
    std::vector<double> b = b0, p = grid.make_field();
    const auto st = solver.solve(K, b, p);
    EXPECT_LE(st.residual, 1e-10);
    it[n++] = st.iterations;
  }
  std::printf(
      "[ PCG, K in [0.1, 1.9] ] iterations: arithmetic mean %d, harmonic mean %d, diagonal scaled %d, "
      "sandwich %d\n",
      it[0], it[1], it[2], it[3]);
  EXPECT_LE(std::abs(it[0] - it[1]), 1);
}

// In 1-D (n_x = n_z = 1) the sandwich preconditioner (-L)^-1 (-D K^-1 G) (-L)^-1 is the exact inverse up
// to a rank-one term (the constant flux of D K G p = b), so PCG needs at most two iterations for any K.
TEST(FluidPressure, SandwichPreconditionerIsExactUpToRankOneIn1D) {
  FluidGrid grid(MPI_COMM_SELF, {1, 64, 1}, {0.1, 1.0, 0.1});
  std::array<std::vector<double>, 3> K{grid.make_field(1.0), grid.make_field(), grid.make_field(1.0)};
  fill_faces(grid, 1, K[1], [](double, double y, double) {
    return 1.0 + 0.99 * std::sin(2 * kPi * y) + (y > 0.5 ? 10.0 : 0.0);
  });
  std::vector<double> b = grid.make_field(), p = grid.make_field();
  fill_cells(grid, b,
             [](double, double y, double) { return std::cos(2 * kPi * y) + 0.3 * std::sin(6 * kPi * y); });
  PressureSettings ps;
  ps.preconditioner = Preconditioner::Sandwich;
  PressureSolver solver(grid, ps);
  const auto st = solver.solve(K, b, p);
  EXPECT_LE(st.iterations, 2);
  EXPECT_LT(st.residual, 1e-10);
}

// ---- (3) variable eps with strong drag: continuity holds to the PCG tolerance -----------------------
// A smooth eps in [0.4, 1] moving down one tenth of a cell per step, drag B dt/rho_f up to 30 in the
// dense regions, the sedimentation body force eps (rho_f - rho_mix) g, air at h = 250 um. After each
// step (eps^{n+1} - eps^n)/dt + D(eps_f u^{n+1}) must vanish to the PCG tolerance (1e-10 of max|b|),
// measured against the size of its terms; the mean of eps is conserved exactly by the moving pattern.
struct VariableEpsCase {
  std::array<int, 3> cells{16, 32, 16};
  double h = 250e-6, rho = 1.3, mu = 1.8e-5, dt = 2.9e-4, shift_per_step = 0.1;
  std::array<double, 3> box() const { return {cells[0] * h, cells[1] * h, cells[2] * h}; }
  double eps_at(double x, double y, double z, int level) const {
    const auto L = box();
    const double y_shift = -shift_per_step * h * level;
    return 0.7 + 0.3 * std::sin(2 * kPi * x / L[0]) * std::cos(2 * kPi * (y - y_shift) / L[1]) *
                     std::cos(2 * kPi * z / L[2] + 0.4);
  }
  FluidSettings settings() const {
    FluidSettings s;
    s.density_kg_m3 = rho;
    s.viscosity_Pa_s = mu;
    const double rho_mix = 0.3 * 1500.0 + 0.7 * rho;  // <phi_p> = 0.3 at 1500 kg/m^3
    s.body_force_per_fluid_volume_N_m3 = {0.0, (rho - rho_mix) * -9.81, 0.0};
    return s;
  }
  void set_level(FluidSolver& solver, int level) const {
    const FluidGrid& g = solver.grid();
    auto& st = solver.state();
    fill_cells(g, st.void_fraction, [&](double x, double y, double z) { return eps_at(x, y, z, level); });
    const double B_max = 30.0 * rho / dt;  // B dt / rho_f = 30 where eps = 0.4
    for (std::size_t c = g.first_owned(); c < g.first_owned() + g.owned_size(); ++c)
      st.drag_coefficient[c] = B_max * (1.0 - st.void_fraction[c]) / 0.6;
    fill_cells(g, st.drag_velocity[1],
               [&](double x, double, double) { return -0.25 + 0.05 * std::sin(2 * kPi * x / box()[0]); });
    fill_cells(g, st.drag_velocity[0],
               [&](double, double y, double) { return 0.02 * std::cos(2 * kPi * y / box()[1]); });
  }
  void initialise(FluidSolver& solver) const {
    const auto L = box();
    auto& st = solver.state();
    set_level(solver, 0);
    fill_faces(solver.grid(), 0, st.velocity[0], [&](double x, double y, double z) {
      return 0.1 * std::sin(2 * kPi * y / L[1]) * std::cos(2 * kPi * z / L[2]) +
             0.02 * std::sin(2 * kPi * x / L[0]);
    });
    fill_faces(solver.grid(), 1, st.velocity[1], [&](double x, double, double z) {
      return -0.2 + 0.1 * std::cos(2 * kPi * x / L[0]) * std::sin(2 * kPi * z / L[2]);
    });
    solver.reset_history();
  }
};

TEST(FluidVariableVoidFraction, ContinuityHoldsToPressureTolerance) {
  const VariableEpsCase vc;
  int iterations[4] = {0, 0, 0, 0};
  int n = 0;
  for (Preconditioner pc : {Preconditioner::ArithmeticMean, Preconditioner::HarmonicMean,
                            Preconditioner::DiagonalScaled, Preconditioner::Sandwich}) {
    FluidGrid grid(MPI_COMM_SELF, vc.cells, vc.box());
    FluidSettings s = vc.settings();
    s.pressure.preconditioner = pc;
    s.warm_start = false;  // compare the preconditioners on full solves
    FluidSolver solver(grid, s);
    vc.initialise(solver);
    double worst = 0.0;
    for (int level = 1; level <= 4; ++level) {
      vc.set_level(solver, level);
      const auto rep = solver.step(vc.dt);
      worst = std::max(worst, rep.continuity_relative);
      iterations[n] = std::max(iterations[n], rep.pressure.iterations);
      EXPECT_LE(rep.pressure.residual, s.pressure.tolerance * (1 + 1e-3));
      EXPECT_LT(std::abs(rep.pressure.rhs_mean_removed), 1e-12 * rep.rhs_term_scale_1_s);
    }
    // max|r| <= 1e-10 max|b| and max|b| <= the term size; 2x for the recomputation's round-off.
    EXPECT_LT(worst, 2 * s.pressure.tolerance);
    std::printf("[ variable eps, B dt/rho = 30 ] preconditioner %d: max PCG iterations %d, continuity %.2e\n",
                static_cast<int>(pc), iterations[n], worst);
    ++n;
  }
  EXPECT_LE(std::abs(iterations[0] - iterations[1]), 1);
}

// Stability of the coupled-like regime: the same moving eps with drag up to B dt/rho_f = 30 and the
// sedimentation body force, 300 steps at the largest stable step (Co = 0.3, viscous limit, cap 0.29 ms).
// Drag ties the fluid to V = -0.25 m/s where eps is small; the velocity must stay of that order (a
// blow-up of the explicit terms would grow without bound) and continuity hold at every step.
TEST(FluidStability, StrongDragRunStaysBounded) {
  const VariableEpsCase vc;
  FluidGrid grid(MPI_COMM_SELF, vc.cells, vc.box());
  FluidSolver solver(grid, vc.settings());
  vc.initialise(solver);
  double u_max = 0.0, worst = 0.0;
  int max_iterations = 0;
  for (int level = 1; level <= 300; ++level) {
    vc.set_level(solver, level);
    const auto rep = solver.step(solver.max_dt(0.3, vc.dt));
    worst = std::max(worst, rep.continuity_relative);
    max_iterations = std::max(max_iterations, rep.pressure.iterations);
  }
  for (int d = 0; d < 3; ++d) u_max = std::max(u_max, max_owned(grid, solver.state().velocity[d]));
  const auto avg = solver.averages();
  std::printf(
      "[ stability ] 300 steps: max|u| %.3f m/s, <eps u>_y %.4f m/s, continuity %.1e, PCG <= %d it.\n", u_max,
      avg.eps_velocity[1], worst, max_iterations);
  EXPECT_LT(u_max, 2.0);
  EXPECT_LT(worst, 2e-10);
}

// ---- (4) implicit drag -------------------------------------------------------------------------------
// Uniform eps, u, B, V: advection, viscosity and pressure vanish, and each step is the implicit update
// u^{n+1} = (rho eps u^n/dt + B V)/(rho eps/dt + B) exactly (same operations: to the last bit but we allow
// 1e-15). With B dt/rho = 100 it relaxes toward V monotonically, never past it.
TEST(FluidDrag, ImplicitDragRelaxesWithoutOvershoot) {
  FluidGrid grid(MPI_COMM_SELF, {8, 8, 8}, {1e-3, 1e-3, 1e-3});
  FluidSettings s;
  FluidSolver solver(grid, s);
  const double rho = s.density_kg_m3, eps = 0.6, dt = 1e-4, B = 100.0 * rho / dt;
  const std::array<double, 3> V{0.1, -0.3, 0.05};
  std::array<double, 3> u{0.5, 0.2, 0.0};
  auto& st = solver.state();
  std::fill(st.void_fraction.begin(), st.void_fraction.end(), eps);
  std::fill(st.drag_coefficient.begin(), st.drag_coefficient.end(), B);
  for (int d = 0; d < 3; ++d) {
    std::fill(st.drag_velocity[d].begin(), st.drag_velocity[d].end(), V[d]);
    std::fill(st.velocity[d].begin(), st.velocity[d].end(), u[d]);
  }
  solver.reset_history();
  for (int step = 0; step < 10; ++step) {
    solver.step(dt);
    for (int d = 0; d < 3; ++d) {
      const double expected = (rho * eps * u[d] / dt + B * V[d]) / (rho * eps / dt + B);
      const auto [lo, hi] =
          std::minmax_element(st.velocity[d].begin() + grid.first_owned(),
                              st.velocity[d].begin() + grid.first_owned() + grid.owned_size());
      EXPECT_NEAR(*lo, expected, 1e-15);
      EXPECT_NEAR(*hi, expected, 1e-15);
      // No overshoot: u - V keeps its sign and shrinks.
      EXPECT_GE((expected - V[d]) * (u[d] - V[d]), 0.0);
      EXPECT_LE(std::abs(expected - V[d]), std::abs(u[d] - V[d]));
      u[d] = expected;
    }
  }
  EXPECT_EQ(solver.last_report().pressure.iterations, 0);  // b = 0: nothing to project
}

// ---- (5) momentum conservation -------------------------------------------------------------------------
// B = 0, no body force, uniform eps: every advective and viscous flux is shared by two control volumes
// and sum G p = 0, so sum rho eps_f u V_cell is conserved to round-off, over many steps and through the
// first projection of a non-solenoidal start. Round-off bound: 1e-13 of sum |rho eps u| V_cell.
TEST(FluidConservation, MomentumConservedToRoundOff) {
  FluidGrid grid(MPI_COMM_SELF, {16, 16, 16}, {1e-2, 1e-2, 1e-2});
  FluidSettings s;
  s.viscosity_Pa_s = 1e-4;  // cell Re ~ 1 at u ~ 0.1 m/s
  FluidSolver solver(grid, s);
  auto& st = solver.state();
  std::fill(st.void_fraction.begin(), st.void_fraction.end(), 0.8);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> uni(-0.1, 0.1);
  const std::array<double, 3> mean{0.05, -0.12, 0.02};
  for (int d = 0; d < 3; ++d)
    fill_faces(grid, d, st.velocity[d], [&](double, double, double) { return mean[d] + uni(rng); });
  solver.reset_history();
  const auto before = solver.averages();
  double scale = 0.0;
  for (int d = 0; d < 3; ++d)
    for (std::size_t c = grid.first_owned(); c < grid.first_owned() + grid.owned_size(); ++c)
      scale += s.density_kg_m3 * 0.8 * std::abs(st.velocity[d][c]) * grid.cell_volume();
  for (int step = 0; step < 200; ++step) solver.step(solver.max_dt(0.3, 1.0));
  const auto after = solver.averages();
  double drift = 0.0;
  for (int d = 0; d < 3; ++d) {
    EXPECT_NEAR(after.momentum_kg_m_s[d], before.momentum_kg_m_s[d], 1e-13 * scale) << d;
    drift = std::max(drift, std::abs(after.momentum_kg_m_s[d] - before.momentum_kg_m_s[d]) / scale);
  }
  std::printf("[ momentum ] 200 steps: max |change| / sum|rho eps u V| = %.2e\n", drift);
  EXPECT_LT(after.kinetic_energy_J, before.kinetic_energy_J);  // projection and viscosity remove energy
}

// ---- (6) free-stream preservation ----------------------------------------------------------------------
// A uniform flow through a uniform eps (and no drag) is a solution; it must stay uniform to round-off.
TEST(FluidConservation, UniformFlowStaysUniform) {
  FluidGrid grid(MPI_COMM_SELF, {8, 12, 6}, {2e-3, 3e-3, 1.5e-3});
  FluidSettings s;
  FluidSolver solver(grid, s);
  auto& st = solver.state();
  const std::array<double, 3> u0{0.3, -0.2, 0.1};
  std::fill(st.void_fraction.begin(), st.void_fraction.end(), 0.55);
  for (int d = 0; d < 3; ++d) std::fill(st.velocity[d].begin(), st.velocity[d].end(), u0[d]);
  solver.reset_history();
  for (int step = 0; step < 50; ++step) solver.step(solver.max_dt(0.3, 1.0));
  for (int d = 0; d < 3; ++d)
    for (std::size_t c = grid.first_owned(); c < grid.first_owned() + grid.owned_size(); ++c)
      ASSERT_NEAR(st.velocity[d][c], u0[d], 1e-15);
  EXPECT_EQ(max_owned(grid, st.pressure), 0.0);
}

// The body-force hooks: with uniform eps and no drag a constant eps f accelerates the fluid uniformly,
// du/dt = f/rho_f (eps cancels), and a face field f_field gives du/dt = f_field/(rho_f eps); no pressure.
TEST(FluidBodyForce, UniformForceAcceleratesUniformly) {
  FluidGrid grid(MPI_COMM_SELF, {6, 8, 4}, {6e-3, 8e-3, 4e-3});
  FluidSettings s;
  s.body_force_per_fluid_volume_N_m3 = {0.0, -3.0, 0.0};
  s.body_force_field = true;
  FluidSolver solver(grid, s);
  auto& st = solver.state();
  const double eps = 0.5, dt = 1e-3, rho = s.density_kg_m3;
  std::fill(st.void_fraction.begin(), st.void_fraction.end(), eps);
  std::fill(st.body_force[0].begin(), st.body_force[0].end(), 2.0);
  solver.reset_history();
  for (int step = 0; step < 20; ++step) solver.step(dt);
  const double t = 20 * dt;
  for (std::size_t c = grid.first_owned(); c < grid.first_owned() + grid.owned_size(); ++c) {
    ASSERT_NEAR(st.velocity[0][c], 2.0 / (rho * eps) * t, 1e-14);
    ASSERT_NEAR(st.velocity[1][c], -3.0 / rho * t, 1e-14);
  }
  EXPECT_EQ(max_owned(grid, st.pressure), 0.0);
}

// ---- output layout -------------------------------------------------------------------------------------
// The snapshot schema's order (z, y, x), x fastest; cell-centred velocity is the mean of the two faces.
TEST(FluidOutput, FileOrderIsZYXWithFaceMeans) {
  FluidGrid grid(MPI_COMM_SELF, {5, 4, 3}, {5.0, 4.0, 3.0});
  FluidSolver solver(grid, FluidSettings{});
  auto& st = solver.state();
  fill_cells(grid, st.void_fraction, [](double x, double y, double z) { return 100 * z + 10 * y + x; });
  fill_cells(grid, st.pressure, [](double x, double y, double z) { return -(100 * z + 10 * y + x); });
  // u_x = x on the faces (periodic jump at the wrap is fine: check an interior cell).
  for (int d = 0; d < 3; ++d)
    fill_faces(grid, d, st.velocity[d], [d](double x, double y, double z) {
      return d == 0 ? x : d == 1 ? y : z;
    });
  cgd::fluid::FileOrderFields out;
  solver.fill_file_order(out);
  const int i = 2, j = 1, k = 1;
  const std::size_t o = (static_cast<std::size_t>(k) * 4 + j) * 5 + i;
  EXPECT_DOUBLE_EQ(out.void_fraction[o], 100 * 1.5 + 10 * 1.5 + 2.5);
  EXPECT_DOUBLE_EQ(out.pressure[o], -(100 * 1.5 + 10 * 1.5 + 2.5));
  EXPECT_DOUBLE_EQ(out.velocity[3 * o + 0], 2.5);
  EXPECT_DOUBLE_EQ(out.velocity[3 * o + 1], 1.5);
  EXPECT_DOUBLE_EQ(out.velocity[3 * o + 2], 1.5);
}

}  // namespace
