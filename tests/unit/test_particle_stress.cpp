// The particle-phase pressure of coarse-grid runs ([particle_stress]; core/particle_stress.hpp; the coupler's
// particle_stress_accelerations, sim/coupling/coupler.hpp), against answers known here:
//   (a) tau of the Harris-Crighton form by hand, below and beyond close packing;
//   (b) the potential mu(phi) = tau/phi + integral_0^phi tau/s^2 ds against its closed form for beta = 2,
//       mu = P_s phi/(phi_cp - phi) + P_s ln(phi_cp/(phi_cp - phi)), and mu' = tau'/phi for beta = 3;
//   (c) one particle per cell at the cell centres (phi uniform): no force;
//   (d) a suspension whose solids fraction varies as phi0 (1 + A sin(2 pi y/L)): each particle's acceleration is
//       the continuum -(1/rho_p) tau'(phi) phi'(y) / phi (from tau alone, not from mu), to the grid's truncation;
//       none across y; the sum over the particles zero;
//   (e) the force on each particle is minus the gradient of the cells' energy sum_c V_c psi(phi_c), psi' = mu (by
//       central differences of that energy, computed here from mu alone): what makes it damp the grid's odd-even mode;
//   (f) without [particle_stress] nothing is allocated and the forces are those of the drag alone;
//   (g) the scene's refusals: beta < 2, keys without a model, a resolved run, no fluid.
#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "core/particle_stress.hpp"
#include "core/scene.hpp"
#include "expect_input_error.hpp"
#include "sim/coupling/coupler.hpp"
#include "sim/dem/particles.hpp"
#include "sim/fluid/solver.hpp"
#include "test_scenes.hpp"

namespace {

using cgd::ParticleStressModel;
using cgd::ParticleStressParams;
constexpr double kPi = std::numbers::pi;
constexpr double kDp = 75e-6, kRhoP = 1500.0;

ParticleStressParams hc(double p_s, double beta, double phi_cp = 0.6) {
  ParticleStressParams s;
  s.model = ParticleStressModel::HarrisCrighton;
  s.p_s_Pa = p_s;
  s.beta = beta;
  s.phi_packed = phi_cp;
  return s;
}

TEST(ParticleStress, HarrisCrightonByHand) {
  const ParticleStressParams s = hc(2.0, 3.0);
  EXPECT_NEAR(cgd::harris_crighton_stress(s, 0.3), 2.0 * 0.027 / 0.3, 1e-15);
  EXPECT_EQ(cgd::harris_crighton_stress(s, 0.0), 0.0);
  // at and beyond phi_cp the denominator is eps (1 - phi): finite, and large
  EXPECT_NEAR(cgd::harris_crighton_stress(s, 0.6), 2.0 * 0.216 / (1e-7 * 0.4), 1e-6 * 2.0 * 0.216 / (1e-7 * 0.4));
  EXPECT_NEAR(cgd::harris_crighton_stress(s, 0.7), 2.0 * 0.343 / (1e-7 * 0.3), 1e-6 * 2.0 * 0.343 / (1e-7 * 0.3));
}

TEST(ParticleStress, PotentialMatchesItsClosedFormAndDerivative) {
  const double P = 3.0, cp = 0.6;
  const cgd::StressPotential mu2(hc(P, 2.0, cp));
  for (double phi : {0.01, 0.1, 0.25, 0.4, 0.55}) {
    const double exact = P * phi / (cp - phi) + P * std::log(cp / (cp - phi));
    // the table's linear interpolation of a smooth integral on 8192 intervals: relative 1e-6 is ample below phi_cp
    EXPECT_NEAR(mu2(phi), exact, 1e-6 * exact) << "phi " << phi;
  }
  EXPECT_EQ(mu2(0.0), 0.0);
  // beta = 3: mu' = tau'/phi, both by central differences of step 1e-4 (truncation ~1e-8 relative; the table's
  // interpolation error in a difference of two values 2e-4 apart: relative ~1e-5)
  const ParticleStressParams s3 = hc(P, 3.0, cp);
  const cgd::StressPotential mu3(s3);
  for (double phi : {0.05, 0.2, 0.35, 0.5}) {
    const double h = 1e-4;
    const double dmu = (mu3(phi + h) - mu3(phi - h)) / (2 * h);
    const double dtau = (cgd::harris_crighton_stress(s3, phi + h) - cgd::harris_crighton_stress(s3, phi - h)) / (2 * h);
    EXPECT_NEAR(dmu, dtau / phi, 1e-4 * dtau / phi) << "phi " << phi;
  }
}

TEST(ParticleStress, StiffnessCapHoldsTauPrimeBeyondItsPhi) {
  // tau' by hand (beta = 3): P_s (3 phi^2 / (phi_cp - phi) + phi^3 / (phi_cp - phi)^2)
  ParticleStressParams s = hc(30.0, 3.0);
  EXPECT_NEAR(cgd::harris_crighton_stiffness(s, 0.3), 30.0 * (3 * 0.09 / 0.3 + 0.027 / 0.09), 1e-12);
  const cgd::StressPotential free(s);
  EXPECT_EQ(free.stiffness_limit_phi(), 1.0);
  s.max_stiffness_Pa = 5000.0;
  const cgd::StressPotential capped(s);
  const double lim = capped.stiffness_limit_phi();
  ASSERT_GT(lim, 0.3);
  ASSERT_LT(lim, 0.6);
  EXPECT_NEAR(cgd::harris_crighton_stiffness(s, lim), 5000.0, 1e-6 * 5000.0);
  // below phi_lim the law itself; above, mu continues with slope tau'(phi_lim)/phi_lim, continuous at phi_lim
  EXPECT_EQ(capped(0.9 * lim), free(0.9 * lim));
  EXPECT_NEAR(capped(lim + 1e-9), free(lim), 1e-6 * free(lim));
  for (double phi : {lim + 0.01, 0.6, 0.7})
    EXPECT_NEAR(capped(phi), free(lim) + 5000.0 / lim * (phi - lim), 1e-6 * capped(phi)) << phi;
}

/// A coupler on a periodic grid of `cells` cells of edge h = 10 d_p, one rank, Beetstra drag, fluid at rest, and
/// parcels of alpha^3 = `factor` primaries (so that a few particles per cell reach a dense phi).
struct Bench {
  std::array<int, 3> cells;
  double h = 10 * kDp;
  cgd::fluid::FluidGrid grid;
  cgd::fluid::FluidSolver fluid;
  cgd::coupling::CouplerSettings cs;
  Bench(std::array<int, 3> n, double factor, ParticleStressParams stress)
      : cells(n),
        grid(MPI_COMM_SELF, n, {n[0] * 10 * kDp, n[1] * 10 * kDp, n[2] * 10 * kDp}),
        fluid(grid, cgd::fluid::FluidSettings{}) {
    cs.drag = cgd::DragLaw::Beetstra;
    cs.drag_params = {1.3, 1.8e-5, kDp};
    cs.particle_volume_m3 = kPi / 6 * kDp * kDp * kDp;
    cs.parcel_volume_factor = factor;
    cs.particle_mass_kg = kRhoP * cs.particle_volume_m3 * factor;
    cs.particle_stress = stress;
  }
};

cgd::dem::Particles particles(const std::vector<double>& x) {
  cgd::dem::Particles p;
  p.external = true;
  p.resize(x.size() / 3, x.size() / 3);
  for (std::size_t i = 0; i < p.n_owned; ++i) p.id[i] = static_cast<std::int64_t>(i);
  p.x = x;
  std::fill(p.v.begin(), p.v.end(), 0.0);
  return p;
}

TEST(ParticleStress, UniformSuspensionFeelsNoForce) {
  Bench b({4, 8, 4}, 200.0, hc(10.0, 3.0));
  std::vector<double> x;
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 8; ++j)
      for (int i = 0; i < 4; ++i)
        for (double c : {(i + 0.5) * b.h, (j + 0.5) * b.h, (k + 0.5) * b.h}) x.push_back(c);
  cgd::dem::Particles p = particles(x);
  cgd::coupling::Coupler coupler(b.cs, b.grid);
  coupler.compute_drag(p, b.fluid.state());
  const auto& a = coupler.particles().stress_accel;
  ASSERT_EQ(a.size(), 3 * p.n_owned);
  // phi = 200 V_p / h^3 = 0.105 in every cell; the force is a sum of 27 terms of size mu grad w ~ mu / (rho_p h):
  // round-off only
  const double phi = 200 * b.cs.particle_volume_m3 / (b.h * b.h * b.h);
  const double scale = cgd::StressPotential(b.cs.particle_stress)(phi) / (kRhoP * b.h);
  for (double v : a) EXPECT_LT(std::abs(v), 1e-13 * scale);
}

TEST(ParticleStress, SinusoidalSuspensionFeelsMinusGradTauOverPhi) {
  // 4 x 32 x 4 cells; phi(y) = phi0 (1 + A sin(2 pi y / L)) made of 8 x 8 columns per cell face and layers whose
  // spacing follows 1/phi: layer k at y_k with Y(y_k) = (k + 1/2) L / N, Y(y) = y + A L/(2 pi) (1 - cos(2 pi y/L))
  const int ny = 32, nlayers = 512, cols = 8;
  const double phi0 = 0.3, A = 0.3;
  const ParticleStressParams s = hc(10.0, 3.0);
  Bench probe({4, ny, 4}, 1.0, s);
  const double L = ny * probe.h, area = (4 * probe.h) * (4 * probe.h);
  // alpha^3 such that the mean is phi0: N V alpha^3 = phi0 L area
  const double n_particles = static_cast<double>(nlayers) * (4 * cols) * (4 * cols);
  const double factor = phi0 * L * area / (n_particles * probe.cs.particle_volume_m3);
  Bench b({4, ny, 4}, factor, s);
  std::vector<double> x, y_of;
  for (int k = 0; k < nlayers; ++k) {
    const double target = (k + 0.5) * L / nlayers;
    double y = target;
    for (int it = 0; it < 50; ++it) {  // Newton on Y(y) = target, Y' = 1 + A sin
      const double Y = y + A * L / (2 * kPi) * (1 - std::cos(2 * kPi * y / L));
      y -= (Y - target) / (1 + A * std::sin(2 * kPi * y / L));
    }
    for (int cz = 0; cz < 4 * cols; ++cz)
      for (int cx = 0; cx < 4 * cols; ++cx) {
        x.push_back((cx + 0.5) * b.h / cols);
        x.push_back(y);
        x.push_back((cz + 0.5) * b.h / cols);
      }
  }
  cgd::dem::Particles p = particles(x);
  cgd::coupling::Coupler coupler(b.cs, b.grid);
  coupler.compute_drag(p, b.fluid.state());
  const auto& a = coupler.particles().stress_accel;
  double worst = 0, amplitude = 0, sum[3] = {0, 0, 0}, across = 0;
  for (std::size_t i = 0; i < p.n_owned; ++i) {
    const double y = p.x[3 * i + 1];
    const double phi = phi0 * (1 + A * std::sin(2 * kPi * y / L));
    const double dphi = phi0 * A * 2 * kPi / L * std::cos(2 * kPi * y / L);
    const double e = 1e-6;
    const double dtau = (cgd::harris_crighton_stress(s, phi + e) - cgd::harris_crighton_stress(s, phi - e)) / (2 * e);
    const double expected = -dtau * dphi / (kRhoP * phi);
    worst = std::max(worst, std::abs(a[3 * i + 1] - expected));
    amplitude = std::max(amplitude, std::abs(expected));
    across = std::max({across, std::abs(a[3 * i]), std::abs(a[3 * i + 2])});
    for (int d = 0; d < 3; ++d) sum[d] += a[3 * i + d];
  }
  std::printf("[ particle stress, sinusoid ] phi0 %.2f A %.2f, %d cells per wavelength: largest |a_y| %.4g m/s^2, "
              "largest error %.4g (%.2f %%), largest |a_x|, |a_z| %.2g\n",
              phi0, A, ny, amplitude, worst, 100 * worst / amplitude, across);
  // truncation: TSC smooths the deposit by exp(-(kh)^2/8)-like factors and the kernel gradient of mu adds about
  // as much, (kh)^2 = (2 pi/32)^2 = 0.039, a few per cent of the amplitude at most: 3 %
  EXPECT_LT(worst, 0.03 * amplitude);
  EXPECT_GT(amplitude, 0.1);  // m/s^2: the test is not vacuous (about 0.6 m/s^2 here)
  EXPECT_LT(across, 1e-9 * amplitude);  // uniform across y: nothing but round-off
  for (int d = 0; d < 3; ++d) EXPECT_LT(std::abs(sum[d]), 1e-9 * amplitude * static_cast<double>(p.n_owned));
}

TEST(ParticleStress, ForceIsMinusTheGradientOfTheCellsEnergy) {
  // E = sum_c V_c psi(phi_c), psi(phi) = integral_0^phi mu (Simpson here, from the potential's values), phi_c the
  // deposit (read back as 1 - eps: no cell reaches the floor). Moving one particle by +-delta along each axis,
  // -(E(+) - E(-)) / (2 delta) is its force; the coupler takes the mean over the particles off every particle, so
  // the differences between particles are compared: (F_p - F_q)/m against a_p - a_q
  Bench b({4, 8, 4}, 120.0, hc(10.0, 3.0));
  const cgd::StressPotential mu(b.cs.particle_stress);
  const auto psi = [&](double phi) {
    const int n = 20000;  // Simpson: mu is a table with a kink every 1/8192 in phi, so steps finer than that
    const double h = phi / n;
    double sum = mu(0.0) + mu(phi);
    for (int k = 1; k < n; ++k) sum += (k % 2 ? 4.0 : 2.0) * mu(k * h);
    return sum * h / 3.0;
  };
  std::vector<double> x;
  std::uint64_t state = 12345;
  const auto uniform = [&] {  // a small LCG: the test's own numbers, the same on every platform
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(state >> 11) / 9007199254740992.0;
  };
  for (int i = 0; i < 300; ++i) {
    x.push_back(uniform() * 4 * b.h);
    x.push_back(uniform() * 8 * b.h * (i < 150 ? 0.4 : 1.0));  // half of them crowded in the lower 40 %
    x.push_back(uniform() * 4 * b.h);
  }
  const auto energy = [&](const std::vector<double>& xs) {
    cgd::dem::Particles p = particles(xs);
    cgd::coupling::Coupler c(b.cs, b.grid);
    c.compute_drag(p, b.fluid.state());
    double e = 0;
    const auto& eps = b.fluid.state().void_fraction;
    for (std::size_t k = b.grid.first_owned(); k < b.grid.first_owned() + b.grid.owned_size(); ++k)
      e += b.grid.cell_volume() * psi(1.0 - eps[k]);
    return e;
  };
  cgd::dem::Particles p = particles(x);
  cgd::coupling::Coupler coupler(b.cs, b.grid);
  coupler.compute_drag(p, b.fluid.state());
  const std::vector<double> a = coupler.particles().stress_accel;
  double phi_max = 0;
  for (double e : b.fluid.state().void_fraction) phi_max = std::max(phi_max, 1.0 - e);
  const double delta = 1e-4 * b.h;
  double worst = 0, scale = 0;
  const std::size_t q = 7;  // the reference particle
  std::vector<double> fq(3);
  for (std::size_t pi : {q, std::size_t{0}, std::size_t{42}, std::size_t{151}, std::size_t{299}})
    for (int d = 0; d < 3; ++d) {
      std::vector<double> up = x, down = x;
      up[3 * pi + d] += delta;
      down[3 * pi + d] -= delta;
      const double f = -(energy(up) - energy(down)) / (2 * delta) / b.cs.particle_mass_kg;
      if (pi == q) {
        fq[d] = f;
        continue;
      }
      worst = std::max(worst, std::abs((f - fq[d]) - (a[3 * pi + d] - a[3 * q + d])));
      scale = std::max(scale, std::abs(a[3 * pi + d] - a[3 * q + d]));
    }
  std::printf("[ particle stress, energy ] densest cell phi %.3f; largest |a_p - a_q| %.4g m/s^2, largest difference "
              "from -grad E/m %.3g (relative %.2g)\n",
              phi_max, scale, worst, worst / scale);
  // central differences of E with delta = 1e-4 h: truncation ~(delta/h)^2 = 1e-8 of the force; psi's Simpson over
  // the table's kinks about as much (measured 2e-8 in all; 4e-7 with 2000 Simpson steps): 1e-6
  EXPECT_LT(worst, 1e-6 * scale);
  EXPECT_GT(scale, 0.01);  // m/s^2: the particles do feel the stress
}

TEST(ParticleStress, OffAllocatesNothingAndChangesNothing) {
  std::vector<double> x = {1.3 * 10 * kDp, 2.2 * 10 * kDp, 0.7 * 10 * kDp, 2.9 * 10 * kDp, 5.1 * 10 * kDp, 3.3 * 10 * kDp};
  Bench off({4, 8, 4}, 27.0, ParticleStressParams{});
  cgd::dem::Particles p = particles(x), q = particles(x);
  for (std::size_t k = 0; k < 6; ++k) p.v[k] = q.v[k] = 0.01 * (k + 1);
  cgd::coupling::Coupler plain(off.cs, off.grid);
  plain.compute_drag(p, off.fluid.state());
  plain.compute_particle_forces(p, off.fluid.state());
  EXPECT_TRUE(plain.particles().stress_accel.empty());
  Bench on({4, 8, 4}, 27.0, hc(10.0, 3.0));
  cgd::coupling::Coupler stressed(on.cs, on.grid);
  stressed.compute_drag(q, on.fluid.state());
  stressed.compute_particle_forces(q, on.fluid.state());
  const auto& s = stressed.particles().stress_accel;
  ASSERT_EQ(s.size(), 6u);
  for (std::size_t k = 0; k < 6; ++k) EXPECT_EQ(q.a_ext[k], p.a_ext[k] + s[k]) << k;  // the drag part bit for bit
  // two particles: their accelerations are equal and opposite after the mean is taken off
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(s[d] + s[3 + d], 0.0, 1e-15 * (std::abs(s[d]) + 1e-30));
}

cgd::Scene scene_with(const std::vector<std::string>& overrides, const cgd::ToolAccepts& accepts = {}) {
  return cgd::load_scene_from_string(cgd::testing::test_scene_text("unit_suspension.toml"), "stress_test.toml",
                                     overrides, accepts);
}

TEST(ParticleStress, SceneRefusesWhatCannotRun) {
  const cgd::Scene ok = scene_with({"particle_stress.model=\"harris-crighton\"", "particle_stress.p_s=30"});
  EXPECT_EQ(ok.fluid->particle_stress.model, ParticleStressModel::HarrisCrighton);
  EXPECT_EQ(ok.fluid->particle_stress.p_s_Pa, 30.0);
  EXPECT_NE(cgd::describe_scene(ok).find("Harris-Crighton"), std::string::npos);
  EXPECT_EQ(scene_with({}).fluid->particle_stress.model, ParticleStressModel::None);
  cgd::testing::expect_input_error(
      [] { scene_with({"particle_stress.model=\"harris-crighton\"", "particle_stress.beta=1.5"}); },
      {"stress_test.toml", "particle_stress.beta", "1.5", "[2, 10]"});
  cgd::testing::expect_input_error([] { scene_with({"particle_stress.p_s=3"}); },
                                   {"particle_stress.p_s", "harris-crighton", "none"});
  cgd::testing::expect_input_error([] { scene_with({"particle_stress.model=\"harris\""}); },
                                   {"particle_stress.model", "harris-crighton"});
  cgd::testing::expect_input_error(
      [] { scene_with({"particle_stress.model=\"harris-crighton\""}, cgd::kResolvedRunAccepts); },
      {"particle_stress.model", "cgd-coarse", "cgd-generate"});
}

}  // namespace
