// The drift-velocity (two-marker) closure, fluid.drag = "drift" (issue 28; docs/closure.md "The drift-velocity
// closure"; core/drag.hpp above the law table; sim/coupling/coupler.hpp), against answers known here:
//   (a) the drift table: bilinear between its bin centres, constant outside, clamped to [-1, h_max];
//   (b) the cell-mean particle velocity, its interpolation, the cell slip and the force of two particles in one cell,
//       computed by hand from the TSC weights;
//   (c) a constant table H gives the force of the phi-only table law with that H when every particle moves with its
//       cell's mean (uniform velocities), and differs by H beta V (vbar_i - v_i) when not;
//   (d) H = 0 gives the micro law's run bit for bit (a coupled run of the engine);
//   (e) the mixture momentum is conserved to round-off with the drift law (a varying table, random velocities);
//   (f) the scene refuses a drift table with fluid.drag = "model" and a phi-only model with "drift";
//   (g) cgd-fit --drift-table: a filtered file with drift sums (written and read through its schema) gives the table
//       H = N/S where measured and the filling rule elsewhere; the model file round-trips;
//   (h) a damaged drift table is refused by the model file's reader.
// The filter's drift sums: tests/unit/test_tsc_grid.cpp (DriftSums.*); 1 vs 2 ranks: tests/mpi/test_coupled_mpi.cpp.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <mpi.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <filesystem>
#include <memory>
#include <numbers>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "core/drag.hpp"
#include "core/error.hpp"
#include "core/filtered_drag.hpp"
#include "core/h5.hpp"
#include "core/scene.hpp"
#include "core/schema/drag_model.hpp"
#include "core/schema/filtered.hpp"
#include "fit/filtered_input.hpp"
#include "fit/fitter.hpp"
#include "sim/coupling/coupler.hpp"
#include "sim/dem/placement.hpp"
#include "sim/dem/system.hpp"
#include "sim/fluid/solver.hpp"
#include "sim/run.hpp"
#include "drift_test_util.hpp"
#include "run_quietly.hpp"
#include "temp_dir.hpp"
#include "test_scenes.hpp"

namespace {

namespace fs = std::filesystem;
using cgd::DragLaw;
using cgd::testing::TempDir;

constexpr double kD = 75e-6, kRhoP = 1500.0, kRhoF = 1.3, kMu = 1.8e-5, kUt = 0.2185;

/// An in-memory drift model (Beetstra micro law) of table H on (phi, slip).
std::shared_ptr<cgd::DragModel> drift_model(std::vector<double> phi, std::vector<double> slip, std::vector<double> H) {
  auto m = std::make_shared<cgd::DragModel>();
  m->micro_drag = DragLaw::Beetstra;
  m->u_t_m_s = kUt;
  m->l_char_m = 3.02e-4;
  m->diameter_m = kD;
  m->path = "test-drift.h5";
  m->drift = true;
  m->drift_table = cgd::DriftTable{std::move(phi), std::move(slip), std::move(H), 0.99};
  return m;
}

/// An in-memory phi-only table model (the --grid-table kind) of constant H.
std::shared_ptr<cgd::DragModel> constant_table_model(double H) {
  auto m = std::make_shared<cgd::DragModel>();
  m->micro_drag = DragLaw::Beetstra;
  m->u_t_m_s = kUt;
  m->l_char_m = 3.02e-4;
  m->diameter_m = kD;
  m->path = "test-table.h5";
  m->table = true;
  m->h_spline.order = 2;
  m->h_spline.knots = {0.0, 0.0, 0.6, 0.6};
  m->h_spline.coefficients = {H, H};
  m->log_a_spline = m->h_spline;
  m->log_a_spline.coefficients = {-700.0, -700.0};
  m->c_corr_a = 1.0, m->c_corr_k = 0.0;
  return m;
}

// ---- (a) the table ------------------------------------------------------------------------------------------

TEST(DriftTable, BilinearBetweenCentresConstantOutsideClamped) {
  const cgd::DriftTable t{{0.05, 0.15}, {0.25, 0.75, 1.25}, {0.1, 0.3, 0.5, 0.2, 0.6, 1.4}, 0.99};
  EXPECT_DOUBLE_EQ(t(0.05, 0.25), 0.1);
  EXPECT_DOUBLE_EQ(t(0.15, 0.75), 0.6);
  EXPECT_NEAR(t(0.10, 0.50), 0.25 * (0.1 + 0.3 + 0.2 + 0.6), 1e-15);       // the middle of a cell
  EXPECT_NEAR(t(0.075, 1.0), 0.75 * 0.4 + 0.25 * 1.0, 1e-15);              // 1/4 along phi, between slip 2 and 3
  EXPECT_NEAR(t(0.0, 0.0), 0.1, 1e-15);                                    // below both ends: the corner
  EXPECT_NEAR(t(0.10, 5.0), 0.5 * (0.5 + 1.4), 1e-15);                    // beyond the slip end: its last column
  EXPECT_NEAR(t(0.20, 5.0), 0.99, 1e-15);                                  // 1.4 clamped to h_max
  const cgd::DriftTable neg{{0.1, 0.2}, {0.5}, {-3.0, 0.2}, 0.99};
  EXPECT_NEAR(neg(0.0, 1.0), -1.0, 1e-15);  // clamped at -1; one slip column: constant in the slip
  EXPECT_NEAR(neg(0.19, 0.0), 0.1 * -3.0 + 0.9 * 0.2, 1e-15);
  EXPECT_NEAR(neg(0.15, 0.0), -1.0, 1e-15);  // -1.4 clamped
}

// ---- the coupler on hand-made particles ---------------------------------------------------------------------

constexpr double kCell = 4 * kD;  // cells of 4 d_p, a 4^3 box

struct Bench {
  cgd::fluid::FluidGrid grid{MPI_COMM_SELF, {4, 4, 4}, {4 * kCell, 4 * kCell, 4 * kCell}};
  cgd::fluid::FluidSolver fluid{grid, [] {
                                  cgd::fluid::FluidSettings s;
                                  s.density_kg_m3 = kRhoF;
                                  s.viscosity_Pa_s = kMu;
                                  return s;
                                }()};
};

cgd::coupling::CouplerSettings coupler_settings(DragLaw law, std::shared_ptr<const cgd::DragModel> model) {
  cgd::coupling::CouplerSettings cs;
  cs.drag = law;
  cs.drag_params = {kRhoF, kMu, kD};
  cs.particle_volume_m3 = std::numbers::pi / 6 * kD * kD * kD;
  cs.particle_mass_kg = kRhoP * cs.particle_volume_m3;
  cs.filtered.model = std::move(model);
  cs.filtered.filter_width_m = kCell;
  cs.filtered.l_char_m = 3.02e-4;
  return cs;
}

cgd::dem::Particles particles(const std::vector<double>& x, const std::vector<double>& v) {
  cgd::dem::Particles p;
  p.external = true;
  p.resize(x.size() / 3, x.size() / 3);
  for (std::size_t i = 0; i < p.n_owned; ++i) p.id[i] = static_cast<std::int64_t>(i);
  p.x = x;
  p.v = v;
  return p;
}

// (b) Two particles in cell (1, 1, 1) of a fluid at rest: A at its centre, B a quarter cell further along x. Per axis
// the TSC weights on cells 0, 1, 2 are aA = (1/8, 3/4, 1/8) and, along x for B, aB = ((1/2 - 1/4)^2/2, 3/4 - 1/16,
// (1/2 + 1/4)^2/2) = (1/32, 11/16, 9/32); along y and z B has A's. Both deposit on the same 27 cells, and the y, z
// weights (common to both) cancel in the cell mean: vbar(ix) = (aA vA + aB vB)/(aA + aB) for every cell of column
// ix, so vbar_A = sum_ix aA(ix) vbar(ix) and vbar_B = sum_ix aB(ix) vbar(ix). u = 0: the cell slip is -vbar_i; phi_i
// = (V/V_cell) (sum aA^2)^2 sum_ix a_i(ix) (aA + aB)(ix). With the constant table H = 0.4 the acceleration is
// beta_i/rho_p (-v_i + 0.4 vbar_i), beta_i = Beetstra(phi_i, |v_i|); the phi-only table law with H = 0.4 gives
// 0.6 beta_i/rho_p (-v_i): they differ by 0.4 beta_i/rho_p (vbar_i - v_i).
TEST(DriftCoupler, CellMeanVelocityAndForceOfTwoParticlesInOneCellByHand) {
  Bench b;
  const double h0 = 0.4;
  const std::vector<double> x = {1.5 * kCell, 1.5 * kCell, 1.5 * kCell, 1.75 * kCell, 1.5 * kCell, 1.5 * kCell};
  const std::vector<double> v = {0.0, -0.1, 0.0, 0.02, -0.3, 0.01};
  cgd::dem::Particles p = particles(x, v);
  cgd::coupling::Coupler drift(coupler_settings(DragLaw::Drift, drift_model({0.0, 0.5}, {0.0, 3.0}, {h0, h0, h0, h0})),
                               b.grid);
  drift.compute_drag(p, b.fluid.state());
  drift.compute_particle_forces(p, b.fluid.state());
  const std::vector<double> a_drift = std::vector<double>(p.a_ext.begin(), p.a_ext.begin() + 6);
  const cgd::coupling::ParticleCoupling pc = drift.particles();

  const double aA[3] = {1.0 / 8, 3.0 / 4, 1.0 / 8}, aB[3] = {1.0 / 32, 11.0 / 16, 9.0 / 32};
  double vbar_A[3] = {0, 0, 0}, vbar_B[3] = {0, 0, 0}, sA = 0, sB = 0;
  for (int ix = 0; ix < 3; ++ix)
    for (int d = 0; d < 3; ++d) {
      const double cell_mean = (aA[ix] * v[d] + aB[ix] * v[3 + d]) / (aA[ix] + aB[ix]);
      vbar_A[d] += aA[ix] * cell_mean;
      vbar_B[d] += aB[ix] * cell_mean;
    }
  for (int ix = 0; ix < 3; ++ix) sA += aA[ix] * (aA[ix] + aB[ix]), sB += aB[ix] * (aA[ix] + aB[ix]);
  const double yz = std::pow(aA[0] * aA[0] + aA[1] * aA[1] + aA[2] * aA[2], 2);
  const double per_cell = std::numbers::pi / 6 * kD * kD * kD / (kCell * kCell * kCell);
  const double phi[2] = {per_cell * yz * sA, per_cell * yz * sB};
  const double* vbar[2] = {vbar_A, vbar_B};
  const cgd::BeetstraDrag micro(kRhoF, kMu, kD);
  cgd::coupling::Coupler table(coupler_settings(DragLaw::Model, constant_table_model(h0)), b.grid);
  cgd::dem::Particles q = particles(x, v);
  table.compute_drag(q, b.fluid.state());
  table.compute_particle_forces(q, b.fluid.state());
  for (int i = 0; i < 2; ++i) {
    const double speed = std::hypot(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
    const double beta = micro.beta_p(phi[i], speed);
    EXPECT_NEAR(pc.beta[i], beta, 1e-12 * beta) << "particle " << i;
    for (int d = 0; d < 3; ++d) {
      EXPECT_NEAR(pc.cell_slip[3 * i + d], -vbar[i][d], 1e-15) << "particle " << i << " axis " << d;
      EXPECT_NEAR(pc.drift_shift[3 * i + d], -h0 * vbar[i][d], 1e-15);
      const double expect = beta / kRhoP * (-v[3 * i + d] + h0 * vbar[i][d]);
      EXPECT_NEAR(a_drift[3 * i + d], expect, 1e-12 * std::abs(beta / kRhoP * 0.3)) << "particle " << i << " axis " << d;
      // the phi-only law with the same H: (1 - H) beta, and the difference is H beta (vbar - v) / rho_p
      EXPECT_NEAR(q.a_ext[3 * i + d], (1 - h0) * beta / kRhoP * -v[3 * i + d], 1e-12 * std::abs(beta / kRhoP * 0.3));
      EXPECT_NEAR(a_drift[3 * i + d] - q.a_ext[3 * i + d], h0 * beta / kRhoP * (vbar[i][d] - v[3 * i + d]),
                  1e-12 * std::abs(beta / kRhoP * 0.3));
    }
  }
  // the two particles do move differently from their cell's mean: the check above is not the uniform case
  EXPECT_GT(std::abs(vbar_A[1] - v[1]), 0.01);
  EXPECT_GT(std::abs(vbar_B[1] - v[4]), 0.01);
}

// (c) Uniform velocities (every particle with its cells' mean, random positions): the drift law with constant H is
// the phi-only table law with that H, force and cell deposit, to round-off (vbar_c = v to 1 ulp).
TEST(DriftCoupler, ConstantTableIsThePhiOnlyTableLawForUniformVelocities) {
  Bench b;
  const double h0 = 0.35;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(0, 1);
  std::vector<double> x, v;
  for (int i = 0; i < 200; ++i)
    for (int d = 0; d < 3; ++d) {
      x.push_back(U(rng) * 4 * kCell);
      v.push_back(d == 1 ? -0.12 : 0.01 * d);
    }
  cgd::dem::Particles p = particles(x, v), q = particles(x, v);
  // a few fluid velocities, so that the slip is not v alone
  auto& st = b.fluid.state();
  for (int d = 0; d < 3; ++d)
    for (std::size_t c = 0; c < st.velocity[d].size(); ++c) st.velocity[d][c] = 0.02 * std::sin(0.7 * c + d);
  cgd::coupling::Coupler drift(coupler_settings(DragLaw::Drift, drift_model({0.0, 0.5}, {0.0, 3.0}, {h0, h0, h0, h0})),
                               b.grid);
  drift.compute_drag(p, st);
  const std::vector<double> B_drift = st.drag_coefficient;
  drift.compute_particle_forces(p, st);
  cgd::coupling::Coupler table(coupler_settings(DragLaw::Model, constant_table_model(h0)), b.grid);
  table.compute_drag(q, st);
  table.compute_particle_forces(q, st);
  double max_a = 0;
  for (double a : q.a_ext) max_a = std::max(max_a, std::abs(a));
  for (std::size_t k = 0; k < 3 * p.n_owned; ++k) EXPECT_NEAR(p.a_ext[k], q.a_ext[k], 1e-12 * max_a) << k;
  // the fluid's side: B of the drift law is beta_micro, the table's (1 - H) beta_micro
  for (std::size_t c = b.grid.first_owned(); c < b.grid.first_owned() + b.grid.owned_size(); ++c)
    EXPECT_NEAR((1 - h0) * B_drift[c], st.drag_coefficient[c], 1e-12 * st.drag_coefficient[c]);
  // the drift law's force is beta (u - v) - H beta (u - vbar): with vbar = v that is (1 - H) beta (u - v)
  for (std::size_t i = 0; i < p.n_owned; ++i)
    for (int d = 0; d < 3; ++d)
      EXPECT_NEAR(drift.particles().cell_slip[3 * i + d], drift.particles().fluid_velocity[3 * i + d] - v[3 * i + d],
                  1e-15);
}

// ---- the engine ---------------------------------------------------------------------------------------------

cgd::Scene make_scene(const std::vector<std::string>& overrides) {
  return cgd::load_scene_from_string(cgd::testing::test_scene_text("unit_suspension.toml"), "drift_test.toml",
                                     overrides);
}

struct Final {
  std::vector<double> x, v, u, p;
};

Final read_final(const fs::path& run) {
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(run / "snapshots"))
    if (e.path().filename().string().rfind("snap_", 0) == 0) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  cgd::h5::File f = cgd::h5::File::open_read(files.back().string(), MPI_COMM_SELF);
  return {f.read_double("/particles/position"), f.read_double("/particles/velocity"), f.read_double("/fluid/velocity"),
          f.read_double("/fluid/pressure")};
}

// (d) H = 0: the drift law's force is beta_micro (u - v - 0 s~) and its deposit v + 0 s~: the micro law's, bit for
// bit (0 x s~ = 0 and v + 0 = v exactly). A table with H != 0 changes the run (the comparison is not vacuous).
TEST(DriftEngine, ZeroTableGivesTheMicroLawRunBitForBit) {
  TempDir dir;
  const std::vector<std::string> base = {"particles.velocity_rms=0.02", "run.end_time=0.008"};
  const cgd::Scene micro = make_scene(base);
  const std::string zero = (dir / "zero.h5").string(), some = (dir / "some.h5").string();
  cgd::testing::write_drift_model(zero, micro, {0.0, 0.5}, {0.0, 1.0, 2.0}, std::vector<double>(6, 0.0));
  cgd::testing::write_drift_model(some, micro, {0.0, 0.5}, {0.0, 1.0, 2.0}, {0.1, 0.3, 0.5, 0.3, 0.5, 0.7});
  auto with = [&](const std::string& file) {
    std::vector<std::string> o = base;
    o.push_back("fluid.drag=\"drift\"");
    o.push_back("fluid.drag_model=\"" + file + "\"");
    return make_scene(o);
  };
  cgd::testing::run_quietly(micro, dir / "micro", MPI_COMM_SELF);
  cgd::testing::run_quietly(with(zero), dir / "zero", MPI_COMM_SELF);
  cgd::testing::run_quietly(with(some), dir / "some", MPI_COMM_SELF);
  const Final a = read_final(dir / "micro"), z = read_final(dir / "zero"), s = read_final(dir / "some");
  EXPECT_EQ(a.x, z.x);
  EXPECT_EQ(a.v, z.v);
  EXPECT_EQ(a.u, z.u);
  EXPECT_EQ(a.p, z.p);
  double dv = 0;
  for (std::size_t k = 0; k < a.v.size(); ++k) dv = std::max(dv, std::abs(a.v[k] - s.v[k]));
  EXPECT_GT(dv, 1e-6) << "a table with H > 0 changes the run";
}

// (e) The mixture momentum with the drift law: the fluid gets B and B (v + d), the particle beta (u - v - d) with
// the same d = H s~ (frozen at the deposit): its impulse is minus the fluid's, to round-off, as with every law
// (tests/unit/test_coupled.cpp Coupled.MixtureMomentumConserved, the same bound). A table that varies with phi and
// the cell slip, random particle velocities (0.05 m/s rms) so that the cell slips and the shifts differ.
TEST(DriftCoupler, MixtureMomentumConservedWithTheDriftLaw) {
  const cgd::Scene scene = make_scene({"particles.solids_fraction=0.2", "particles.velocity_rms=0.05"});
  MPI_Comm comm = MPI_COMM_SELF;
  const cgd::FluidConfig& fc = *scene.fluid;
  const cgd::Vec3& g = scene.domain.gravity_m_s2;
  cgd::fluid::FluidGrid grid(comm, scene.derived.cells, scene.domain.size_m);
  cgd::dem::DemSystem dem(cgd::dem_settings_from_scene(scene), comm);
  const auto placement =
      cgd::dem::place_particles(scene.domain.size_m, dem.settings().diameter_m, scene.derived.particle_count,
                                scene.particles.velocity_rms_m_s, scene.particles.seed);
  std::vector<std::int64_t> ids(static_cast<std::size_t>(scene.derived.particle_count));
  std::iota(ids.begin(), ids.end(), 0);
  dem.set_particles(ids, placement.position, placement.velocity, {});
  const double volume = scene.domain.size_m[0] * scene.domain.size_m[1] * scene.domain.size_m[2];
  const double phi = static_cast<double>(scene.derived.particle_count) * scene.derived.particle_volume_m3 / volume;
  const double rho_mix = phi * scene.particles.density_kg_m3 + (1.0 - phi) * fc.density_kg_m3;
  cgd::fluid::FluidSettings fs;
  fs.density_kg_m3 = fc.density_kg_m3;
  fs.viscosity_Pa_s = fc.viscosity_Pa_s;
  for (int d = 0; d < 3; ++d) fs.body_force_per_fluid_volume_N_m3[d] = (fc.density_kg_m3 - rho_mix) * g[d];
  cgd::fluid::FluidSolver fluid(grid, fs);
  cgd::coupling::CouplerSettings cs =
      coupler_settings(DragLaw::Drift, drift_model({0.1, 0.3}, {0.0, 0.5, 1.0}, {0.2, 0.5, 0.7, 0.4, 0.6, 0.9}));
  cs.particle_volume_m3 = scene.derived.particle_volume_m3;
  cs.particle_mass_kg = scene.derived.parcel_mass_kg;
  cs.filtered.filter_width_m = std::cbrt(grid.cell_volume());
  for (int d = 0; d < 3; ++d) cs.particle_body_accel[d] = g[d] * (1.0 - rho_mix / scene.particles.density_kg_m3);
  cgd::coupling::Coupler coupler(cs, grid);
  const double dt_cap = 0.5 * scene.particles.density_kg_m3 /
                        cgd::beta_p(DragLaw::Beetstra, cs.drag_params, 1.0 - cs.void_fraction_floor, 0.0);
  const double dt = dem.settings().dt_s, m = dem.settings().mass_kg;
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
        s += fc.density_kg_m3 * std::abs(st.velocity[d][c]) * grid.cell_volume();
    return s;
  };
  const auto P0 = dem.diagnostics(false).momentum;
  double scale = particle_scale(), drift = 0.0, max_fluid = 0.0, max_shift = 0.0;
  const int fluid_steps = 200;
  for (int k = 0; k < fluid_steps; ++k) {
    dem.prepare();
    coupler.compute_drag(dem.particles(), fluid.state());
    for (double s : coupler.particles().drift_shift) max_shift = std::max(max_shift, std::abs(s));
    if (k == 0) fluid.reset_history();
    const std::int64_t n_sub =
        std::max<std::int64_t>(1, static_cast<std::int64_t>(fluid.max_dt(fc.courant, dt_cap) / dt));
    fluid.step(static_cast<double>(n_sub) * dt);
    const auto Pf = fluid.averages().momentum_kg_m_s;
    coupler.compute_particle_forces(dem.particles(), fluid.state());
    for (std::int64_t s_ = 0; s_ < n_sub; ++s_) dem.step();
    const auto Pp = dem.diagnostics(false).momentum;
    scale = std::max(scale, particle_scale() + fluid_scale());
    for (int d = 0; d < 3; ++d) {
      drift = std::max(drift, std::abs(Pf[d] + Pp[d] - P0[d]));
      max_fluid = std::max(max_fluid, std::abs(Pf[d]));
    }
  }
  std::printf("[ drift momentum ] %d fluid steps: max |P - P0| = %.2e kg m/s, %.2e of the scale %.2e; largest fluid "
              "momentum %.2e; largest shift H s~ %.2e m/s\n",
              fluid_steps, drift, drift / scale, scale, max_fluid, max_shift);
  EXPECT_LT(drift, fluid_steps * 10 * 2.2e-16 * scale);
  EXPECT_GT(max_fluid, 1e6 * drift);
  EXPECT_GT(max_shift, 1e-3);  // the shift acts: the test is not the micro law's
}

// ---- (f) the scene ------------------------------------------------------------------------------------------

TEST(DriftScene, ModelAndDriftRefuseEachOthersFiles) {
  TempDir dir;
  const cgd::Scene micro = make_scene({});
  const std::string drift_file = (dir / "drift.h5").string();
  cgd::testing::write_drift_model(drift_file, micro, {0.0, 0.5}, {0.0, 1.0}, {0.1, 0.2, 0.3, 0.4});
  const cgd::Scene ok = make_scene({"fluid.drag=\"drift\"", "fluid.drag_model=\"" + drift_file + "\""});
  ASSERT_TRUE(ok.fluid->drag_model);
  EXPECT_TRUE(ok.fluid->drag_model->drift);
  EXPECT_EQ(ok.fluid->drag, DragLaw::Drift);
  try {
    make_scene({"fluid.drag=\"model\"", "fluid.drag_model=\"" + drift_file + "\""});
    ADD_FAILURE() << "fluid.drag = \"model\" took a drift table";
  } catch (const cgd::InputError& e) {
    const std::string what = e.what();
    for (const std::string& part : {std::string("drift_test.toml"), std::string("fluid.drag_model"), drift_file,
                                   std::string("drift_table"), std::string("fluid.drag = \"drift\"")})
      EXPECT_NE(what.find(part), std::string::npos) << part << " not in: " << what;
  }
  const char* src = std::getenv("CGD_SOURCE_DIR");
  const std::string shipped = std::string(src ? src : CGD_SOURCE_DIR_DEFAULT) + "/data/models/half_box.h5";
  try {
    make_scene({"fluid.drag=\"drift\"", "fluid.drag_model=\"" + shipped + "\""});
    ADD_FAILURE() << "fluid.drag = \"drift\" took a phi-only model";
  } catch (const cgd::InputError& e) {
    const std::string what = e.what();
    for (const std::string& part : {std::string("fluid.drag_model"), shipped, std::string("drift_table"),
                                   std::string("fluid.drag = \"model\"")})
      EXPECT_NE(what.find(part), std::string::npos) << part << " not in: " << what;
  }
  try {
    make_scene({"fluid.drag=\"drift\""});
    ADD_FAILURE() << "drift without a table";
  } catch (const cgd::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("fluid.drag_model is missing"), std::string::npos) << e.what();
  }
  // resolved runs refuse it as every filtered law
  EXPECT_THROW(cgd::load_scene_from_string(cgd::testing::test_scene_text("unit_suspension.toml"), "x.toml",
                                           {"fluid.drag=\"drift\"", "fluid.drag_model=\"" + drift_file + "\""},
                                           cgd::kResolvedRunAccepts),
               cgd::InputError);
  // the evaluator's own check, for code that sets the law up by hand
  cgd::FilteredDragSetup setup;
  setup.model = ok.fluid->drag_model;
  setup.filter_width_m = 1e-3;
  setup.l_char_m = 3e-4;
  EXPECT_THROW(cgd::check_filtered_setup(DragLaw::Model, setup), cgd::InputError);
  EXPECT_NO_THROW(cgd::check_filtered_setup(DragLaw::Drift, setup));
  setup.model = constant_table_model(0.2);
  EXPECT_THROW(cgd::check_filtered_setup(DragLaw::Drift, setup), cgd::InputError);
}

// ---- (g) the fitter -----------------------------------------------------------------------------------------

/// A filtered file with one grid (4 across, 7.5 d_p) and its drift sums, 4 phi bins of 0.05 and 4 slip bins of 0.25
/// u_t, two snapshots (the second empty), designed for the filling rule:
///   phi bin 0: phi-only H_grid 0.2 (N = 40 + 40 per snapshot... of M = 50 + 50), no drift bin with >= 100 samples;
///   phi bin 1: slip 0 has 200 samples but |S| = 10 < 0.25 x 100 (misaligned), slip 1 H = 30/100, slip 2 H = 50/100,
///              slip 3 empty;
///   phi bin 2: slip 0 H = 10/100, slip 3 H = 70/100, slips 1, 2 below min_count;
///   phi bin 3: 50 samples: not a row.
cgd::schema::Filtered drift_filtered(const cgd::Scene& scene) {
  namespace s = cgd::schema;
  s::Filtered f;
  f.scene_toml = scene.effective_toml;
  f.system = cgd::physical_system(scene);
  f.parcel_size = 1;
  f.cell_size_m = {2.5e-4, 2.5e-4, 2.5e-4};
  f.pressure_terms = true;
  f.bootstrap_replicates = 20, f.bootstrap_seed = 1, f.confidence = 0.95, f.bootstrap = "test";
  f.run_paths = {"synthetic/run"};
  f.run_mean_solids_fraction = {0.1};
  f.run_snapshot_count = {2};
  f.run_block_length = {1};
  f.run_tau_int = {0.5};
  f.run_n_eff = {2};
  f.snapshot_files = {"a.h5", "b.h5"};
  f.snapshot_checksums = {"0", "0"};
  f.snapshot_run_index = {0, 0};
  f.snapshot_step = {1, 2};
  f.snapshot_block = {0, 1};
  f.snapshot_time_s = {0.0, 0.1};
  f.phi_edges = {0.0, 0.05, 0.10, 0.15, 0.20};
  f.slip_edges = {0.0, 0.25, 0.5, 0.75, 1.0};
  s::FilteredGroup g;
  g.kind = s::FilterKind::Grid;
  const double cell = 7.5 * kD;
  g.width_m = cell, g.width_over_dp = 7.5, g.width_over_cell = 2.25, g.F = f.system.l_char_m / cell;
  s::FilteredGroup::Grid ga;
  ga.cells_across = 4;
  ga.cells = {4, 16, 4};
  ga.dx_over_dp = 7.5;
  ga.cell_spacing_m = {cell, cell, cell};
  ga.cell_size_m = cell;
  ga.cell_size_over_dp = 7.5;
  ga.void_fraction_floor = 0.3;
  g.grid = ga;
  const std::vector<std::int64_t> count = {500, 600, 700, 50};
  g.count = count;
  g.H = {0.2, 0.3, 0.3, 0.3};
  g.H_low = g.H, g.H_high = g.H, g.phi_mean = {0.025, 0.075, 0.125, 0.175};
  s::FilteredGroup::PerSnapshot ps;
  ps.count = {500, 600, 700, 50, 0, 0, 0, 0};
  ps.numerator = {80, 70, 70, 70, 0, 0, 0, 0};
  ps.micro = {100, 100, 100, 100, 0, 0, 0, 0};
  ps.slip = std::vector<double>(8, 0.0);
  ps.phi = std::vector<double>(8, 0.0);
  g.per_snapshot = ps;
  s::FilteredGroup::Drift d;
  const std::size_t n = 16;
  d.count.assign(n, 0);
  d.numerator.assign(n, 0.0), d.denominator.assign(n, 0.0), d.magnitude.assign(n, 0.0);
  auto set = [&](int b, int m, std::int64_t c, double num, double den, double mag) {
    const std::size_t k = static_cast<std::size_t>(4 * b + m);
    d.count[k] = c, d.numerator[k] = num, d.denominator[k] = den, d.magnitude[k] = mag;
  };
  for (int m = 0; m < 4; ++m) set(0, m, 10, 1.0, 5.0, 5.0);
  set(1, 0, 200, 3.0, 10.0, 100.0);
  set(1, 1, 200, 30.0, 100.0, 120.0);
  set(1, 2, 200, 50.0, 100.0, 110.0);
  set(2, 0, 300, 10.0, 100.0, 100.0);
  set(2, 1, 50, 9.0, 10.0, 10.0);
  set(2, 2, 99, 9.0, 10.0, 10.0);
  set(2, 3, 250, 70.0, 100.0, 100.0);
  set(3, 0, 50, 1.0, 1.0, 1.0);
  d.phi_mean.assign(n, NAN), d.slip_mean.assign(n, NAN), d.H.assign(n, NAN), d.H_stderr.assign(n, NAN);
  for (std::size_t k = 0; k < n; ++k)
    if (d.count[k] > 0) d.H[k] = d.numerator[k] / d.denominator[k], d.phi_mean[k] = 0.1, d.slip_mean[k] = 0.5;
  s::FilteredGroup::Drift::PerSnapshot dps;
  dps.count = d.count, dps.numerator = d.numerator, dps.denominator = d.denominator;
  dps.count.resize(2 * n, 0), dps.numerator.resize(2 * n, 0.0), dps.denominator.resize(2 * n, 0.0);
  d.per_snapshot = dps;
  d.out_of_range = 7;
  g.drift = d;
  f.groups.push_back(g);
  return f;
}

TEST(DriftFit, TableIsNOverSWhereMeasuredAndFilledByTheRuleElsewhere) {
  TempDir dir;
  const cgd::Scene scene = cgd::load_scene_from_string(cgd::testing::test_scene_text("demo_box.toml"), "demo.toml");
  const std::string filtered = (dir / "filtered.h5").string(), model = (dir / "drift.h5").string();
  cgd::schema::write_filtered(filtered, &scene, drift_filtered(scene));
  // the filtered file's round trip: the drift sums and the slip bins come back
  const cgd::schema::Filtered back = cgd::schema::read_filtered(filtered);
  ASSERT_EQ(back.slip_edges.size(), 5u);
  ASSERT_TRUE(back.groups.at(0).drift.has_value());
  EXPECT_EQ(back.groups[0].drift->count[4 * 2 + 3], 250);
  EXPECT_EQ(back.groups[0].drift->out_of_range, 7);
  EXPECT_DOUBLE_EQ(back.groups[0].drift->H[4 * 1 + 1], 0.3);
  ASSERT_TRUE(back.groups[0].drift->per_snapshot.has_value());
  const cgd::fit::FilteredFile f = cgd::fit::read_filtered_file(filtered);
  ASSERT_TRUE(f.grids.at(0).drift.has_value());
  const std::string report = cgd::fit::write_drift_table_model(model, {f}, 4, 100, 0.25, scene);
  EXPECT_NE(report.find("3 phi rows x 4 slip columns"), std::string::npos) << report;

  const cgd::DragModel m = cgd::load_drag_model(model);
  ASSERT_TRUE(m.drift);
  EXPECT_FALSE(m.table);
  EXPECT_EQ(m.table_cells_across, 4);
  EXPECT_EQ(m.calibration_operator, cgd::CalibrationOperator::Grid);
  const cgd::DriftTable& t = m.drift_table;
  ASSERT_EQ(t.phi.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) EXPECT_NEAR(t.phi[k], 0.025 + 0.05 * k, 1e-15);
  ASSERT_EQ(t.slip.size(), 4u);
  EXPECT_NEAR(t.slip[0], 0.125, 1e-15);
  EXPECT_NEAR(t.slip[3], 0.875, 1e-15);
  const std::vector<double> expect = {0.2, 0.2, 0.2, 0.2,   // row 0: its phi-only H_grid 1 - 80/100
                                      0.3, 0.3, 0.5, 0.3,   // row 1: misaligned slip 0 -> slip 1; empty slip 3, beyond
                                                            // the last measured: min(0.5, its phi-only 0.3)
                                      0.1, 0.1, 0.7, 0.7};  // row 2: slip 1 -> 0 (the lower on a tie... nearest), 2 -> 3
  ASSERT_EQ(t.H.size(), expect.size());
  for (std::size_t k = 0; k < expect.size(); ++k) EXPECT_NEAR(t.H[k], expect[k], 1e-14) << "entry " << k;
  const cgd::schema::DragModelFile raw = cgd::schema::read_drag_model(model);
  ASSERT_TRUE(raw.drift_table.has_value());
  EXPECT_EQ(raw.curves, cgd::schema::ModelCurves::DriftTable);
  EXPECT_EQ(raw.drift_table->filled, (std::vector<std::int64_t>{2, 2, 2, 2, 1, 0, 0, 3, 0, 1, 1, 0}));
  EXPECT_EQ(raw.drift_table->count[4 * 2 + 3], 250);
  EXPECT_NEAR(raw.drift_table->phi_only_H[1], 0.3, 1e-14);
  // the law reads the table: at a bin centre its value, in between bilinear
  EXPECT_NEAR(t(0.075, 0.375), 0.3, 1e-14);
  EXPECT_NEAR(t(0.1, 0.5), 0.25 * (0.3 + 0.5 + 0.1 + 0.7), 1e-14);
  // a run at the table's grid gets no warning; another cell one
  EXPECT_TRUE(cgd::model_calibration_warnings(m, 7.5 * kD).empty());
  EXPECT_EQ(cgd::model_calibration_warnings(m, 10 * kD).size(), 1u);
  // refusals: another grid, a file without drift sums, no measured bin
  EXPECT_THROW(cgd::fit::write_drift_table_model((dir / "x.h5").string(), {f}, 5, 100, 0.25, scene), cgd::InputError);
  EXPECT_THROW(cgd::fit::write_drift_table_model((dir / "x.h5").string(), {f}, 4, 1000, 0.25, scene), cgd::InputError);
  cgd::fit::FilteredFile bare = f;
  bare.grids[0].drift.reset();
  EXPECT_THROW(cgd::fit::write_drift_table_model((dir / "x.h5").string(), {bare}, 4, 100, 0.25, scene), cgd::InputError);
  // pooling two copies with twice the min count: the same table (sums and counts double, ratios unchanged)
  const std::string pooled = (dir / "pooled.h5").string();
  cgd::fit::write_drift_table_model(pooled, {f, f}, 4, 200, 0.25, scene);
  EXPECT_EQ(cgd::load_drag_model(pooled).drift_table.H.size(), expect.size());
  for (std::size_t k = 0; k < expect.size(); ++k)
    EXPECT_NEAR(cgd::load_drag_model(pooled).drift_table.H[k], expect[k], 1e-14);
}

// ---- (h) damaged drift tables -------------------------------------------------------------------------------

/// A copy of `source` at `target` changed by `body` (the HDF5 file id).
void damaged_copy(const std::string& source, const std::string& target, const std::function<void(hid_t)>& body) {
  fs::copy_file(source, target, fs::copy_options::overwrite_existing);
  const hid_t f = H5Fopen(target.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  body(f);
  H5Fclose(f);
}

void write_dataset(hid_t f, const char* name, const std::vector<double>& values, std::vector<hsize_t> dims) {
  H5Ldelete(f, name, H5P_DEFAULT);
  const hid_t space = H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr);
  const hid_t set = H5Dcreate2(f, name, H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  H5Dwrite(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data());
  H5Dclose(set);
  H5Sclose(space);
}

TEST(DriftModelFile, DamagedTablesAreRefusedNamingTheDataset) {
  TempDir dir;
  const cgd::Scene micro = make_scene({});
  const std::string good = (dir / "good.h5").string();
  cgd::testing::write_drift_model(good, micro, {0.0, 0.5}, {0.0, 1.0, 2.0}, {0.1, 0.2, 0.3, 0.4, 0.5, 0.6});
  EXPECT_TRUE(cgd::load_drag_model(good).drift);
  auto refused = [&](const std::string& name, const std::function<void(hid_t)>& body, const std::string& says) {
    const std::string path = (dir / (name + ".h5")).string();
    damaged_copy(good, path, body);
    try {
      cgd::load_drag_model(path);
      ADD_FAILURE() << name << ": not refused";
    } catch (const cgd::InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(path), std::string::npos) << what;
      EXPECT_NE(what.find(says), std::string::npos) << name << ": " << what;
    }
  };
  refused("no_H", [](hid_t f) { H5Ldelete(f, "/drift_table/H", H5P_DEFAULT); }, "/drift_table/H");
  refused("no_group", [](hid_t f) { H5Ldelete(f, "/drift_table", H5P_DEFAULT); }, "/drift_table");
  refused("nan_H", [](hid_t f) { write_dataset(f, "/drift_table/H", {0.1, NAN, 0.3, 0.4, 0.5, 0.6}, {2, 3}); },
          "/drift_table/H");
  refused("shape_H", [](hid_t f) { write_dataset(f, "/drift_table/H", {0.1, 0.2, 0.3, 0.4, 0.5, 0.6}, {3, 2}); },
          "/drift_table/H");
  refused("slip_order", [](hid_t f) { write_dataset(f, "/drift_table/slip", {0.0, 2.0, 1.0}, {3}); },
          "strictly increasing");
  refused("count_float", [](hid_t f) { write_dataset(f, "/drift_table/count", std::vector<double>(6, 1.0), {2, 3}); },
          "/drift_table/count");
}

}  // namespace
