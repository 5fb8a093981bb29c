// cgd-coarse's checks and the time average with batch-means error bars (coarse/coarse.hpp,
// core/time_average.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>

#include "coarse/coarse.hpp"
#include "core/error.hpp"
#include "core/filtered_drag.hpp"
#include "core/schema/series.hpp"
#include "core/schema/snapshot.hpp"
#include "core/scene.hpp"
#include "core/time_average.hpp"

namespace cgd {
namespace {

TEST(TimeAverage, ConstantAndLinearSignals) {
  // y = 2: mean 2 and no spread between batches. y = t on uneven rows: the time-weighted mean of a
  // ramp over [0, 1) is 1/2 (rows weighted by the time to the next: the rectangle rule, exact to dt/2).
  std::vector<double> t, c, r;
  double time = 0;
  for (int i = 0; i < 1000; ++i) {
    t.push_back(time);
    c.push_back(2.0);
    r.push_back(time);
    time += (i % 2 ? 0.0005 : 0.0015);
  }
  const WindowAverage a = window_average(t, c, 0.0, 1.0);
  EXPECT_DOUBLE_EQ(a.mean, 2.0);
  EXPECT_NEAR(a.standard_error, 0.0, 1e-15);
  EXPECT_EQ(a.batches, 10);
  const WindowAverage b = window_average(t, r, 0.0, 1.0);
  EXPECT_NEAR(b.mean, 0.5, 0.0015);
  EXPECT_THROW(window_average(t, r, 0.999, 1.0), std::invalid_argument);
}

TEST(TimeAverage, BatchMeansErrorOfWhiteNoise) {
  // Uncorrelated noise of sd 1 on 20000 rows: the standard error of the mean is 1/sqrt(20000) = 0.0071.
  // The batch-means estimate from 10 batches has a relative spread of 1/sqrt(2 * 9) = 24 %: over 20
  // seeds the mean estimate must be within 15 % (24 %/sqrt(20) = 5 %, three of those).
  double sum = 0;
  for (unsigned seed = 0; seed < 20; ++seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> N(0, 1);
    std::vector<double> t, y;
    for (int i = 0; i < 20000; ++i) {
      t.push_back(i);
      y.push_back(N(rng));
    }
    sum += window_average(t, y, 0, 1e9).standard_error;
  }
  EXPECT_NEAR(sum / 20, 1 / std::sqrt(20000.0), 0.15 / std::sqrt(20000.0));
}

std::string coarse_scene(const std::string& extra_particles, const std::string& extra_fluid, const std::string& extra_run) {
  return "[domain]\nsize_dp = [45, 180, 45]\n[particles]\ndiameter = 75e-6\ndensity = 1500.0\nsolids_fraction = 0.05\n" +
         extra_particles + "\n[contact]\ngamma_star = 3e-3\n[fluid]\ndx_over_dp = 7.5\n" + extra_fluid +
         "\n[run]\nend_time_tref = 20\n" + extra_run + "\n";
}

TEST(CoarseChecks, RefusesParcelsWiderThanACellTooFewParcelsThinSlabsAndAnEmptyWindow) {
  const Scene ok = load_scene_from_string(coarse_scene("parcel_size = 4", "", ""), "ok.toml");
  EXPECT_NO_THROW(coarse::check_coarse_scene(ok, 1));
  auto refused = [](const std::string& text, int ranks, const std::string& expected) {
    const Scene s = load_scene_from_string(text, "bad.toml");
    try {
      coarse::check_coarse_scene(s, ranks);
      ADD_FAILURE() << "accepted: " << expected;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  };
  refused(coarse_scene("parcel_size = 8", "", ""), 1, "wider than a fluid cell");  // 8 d_p > 7.5 d_p
  const std::string seven = coarse_scene("parcel_size = 7", "", "");
  refused(std::string(seven).replace(seven.find("solids_fraction = 0.05"), 22, "solids_fraction = 0.02"), 1,
          "at least 100");  // 40 parcels
  refused(coarse_scene("", "", "sampling_start_tref = 25"), 1, "must be before run.end_time");
  // 24 rows of 7.5 d_p over 23 ranks: the particles' slabs are L_y / 23 = 7.83 d_p (balanced later, none
  // thinner), the cutoff of 7 d_p parcels with a fixed skin of 0.15 parcel diameters 8.05 d_p; the adaptive skin
  // (no skin_over_dp) needs only 7 x 1.05 = 7.35 d_p (its largest skin is then bounded by the slab:
  // sim/dem/system.hpp). (The fluid grid refuses fewer than 2 rows per rank on its own, at the run's start.)
  std::string dense = std::string(seven).replace(seven.find("solids_fraction = 0.05"), 22, "solids_fraction = 0.30");
  EXPECT_NO_THROW(coarse::check_coarse_scene(load_scene_from_string(dense, "adaptive.toml"), 23));
  dense.replace(dense.find("gamma_star = 3e-3"), 17, "gamma_star = 3e-3\nskin_over_dp = 0.15");
  refused(dense, 23, "thinner than the contact cutoff");
}

}  // namespace
}  // namespace cgd

namespace cgd {
namespace {

TEST(CoarseChecks, ParcelCorrectionSwitchedOffGivesTheGridModelAlone) {
  // fluid.parcel_correction = false (the parcel fit's runs): beta of alpha = 4 parcels equals the
  // alpha = 1 value; on, it is c_corr(4) = exp(-0.05 x 3) = 0.8607 times that (the paper's a = 0, k = 0.05).
  const std::string base = coarse_scene("parcel_size = 4", "drag = \"radl2014\"", "");
  const Scene on = load_scene_from_string(base, "on.toml");
  const Scene off = load_scene_from_string(base, "off.toml", {"fluid.parcel_correction=false"});
  const Vec3 cell{7.5 * 75e-6, 7.5 * 75e-6, 7.5 * 75e-6};
  const DragParams p{1.3, 1.8e-5, 75e-6};
  FilteredDragSetup s_on = filtered_drag_setup(on, cell), s_off = filtered_drag_setup(off, cell);
  const double b_on = beta_p(DragLaw::Radl2014, p, s_on, 0.1, 0.2), b_off = beta_p(DragLaw::Radl2014, p, s_off, 0.1, 0.2);
  EXPECT_NEAR(b_on / b_off, std::exp(-0.05 * 3), 1e-14);
  s_off.parcel_size = 1;
  EXPECT_DOUBLE_EQ(beta_p(DragLaw::Radl2014, p, s_off, 0.1, 0.2), b_off);
}

TEST(CoarseSummary, FlagsAWindowThatStillHoldsTheTransient) {
  // A coarse run's slip: stationary noise around 0.8 u_t, and the same noise on a climb from 0.8 to 1.1
  // u_t across the window (a clustering instability still growing). The halves of the climbing window
  // differ by 0.15 u_t against a standard error of ~0.003: flagged; the stationary one is not (its
  // drift is noise, within 3 standard errors but for a 0.3 % chance).
  const Scene scene = load_scene_from_string(coarse_scene("parcel_size = 4", "", ""), "ok.toml");
  const double u_t = scene.derived.u_t_m_s;
  auto write = [&](const std::string& dir, bool climbing) {
    std::filesystem::create_directories(dir);
    schema::Series series;
    series.add_column("time", 1, "s");
    series.add_column("slip_velocity", 3, "m/s");
    series.add_column("wall_seconds", 1, "s");
    std::mt19937_64 rng(7);
    std::normal_distribution<double> noise(0.0, 0.02);
    for (int i = 0; i < 4000; ++i) {
      const double t = 1e-3 * i;
      const double trend = climbing && t >= 1.0 ? 0.3 * (t - 1.0) / 3.0 : 0.0;
      series.append({t, 0.0, (0.8 + trend + noise(rng)) * u_t, 0.0, 0.01 * i});
    }
    series.write(dir + "/series.h5", MPI_COMM_SELF, scene);
  };
  const std::string base = ::testing::TempDir() + "cgd_coarse_summary";
  std::filesystem::remove_all(base);
  write(base + "/flat", false);
  write(base + "/climb", true);
  const coarse::SlipSummary flat = coarse::summarise_run(base + "/flat", u_t, 1.0, 1);
  const coarse::SlipSummary climb = coarse::summarise_run(base + "/climb", u_t, 1.0, 1);
  EXPECT_NEAR(flat.slip.mean, 0.8, 0.005);
  EXPECT_TRUE(flat.stationary()) << flat.drift << " +- " << flat.drift_stderr;
  EXPECT_NEAR(climb.drift, 0.15, 0.01);
  EXPECT_FALSE(climb.stationary());
  EXPECT_NE(coarse::describe(climb).find("not stationary"), std::string::npos);
  EXPECT_EQ(coarse::describe(flat).find("not stationary"), std::string::npos);
  std::filesystem::remove_all(base);
}

}  // namespace
}  // namespace cgd
