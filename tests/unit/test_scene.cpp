// Scene loading: validation messages (table-driven), derived numbers against docs/models.md and the
// peer benchmark's params.inc, --set overrides, the shipped scenes, and the command-line front.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <numbers>
#include <ostream>
#include <string>
#include <vector>

#include "core/cli.hpp"
#include "core/error.hpp"
#include "core/scales.hpp"
#include "core/scene.hpp"
#include "core/version.hpp"

namespace {

using cgd::InputError;
using cgd::load_scene_from_string;

// A valid scene with a quiescent fluid (so gamma_star and the *_tref keys are allowed).
const std::string kWetScene = R"([domain]
size_dp = [24, 96, 24]
gravity = [0.0, -9.81, 0.0]

[particles]
diameter = 75e-6
density = 1500.0
solids_fraction = 0.05

[contact]
gamma_star = 1e-3
restitution = 0.9
friction = 0.1

[fluid]
density = 1.3
viscosity = 1.8e-5
coupling = "quiescent"
drag = "stokes"

[run]
end_time = 0.05
dump_interval = 0.005
)";

// A valid dry scene (no [fluid]): contacts need an explicit stiffness.
const std::string kDryScene = R"([domain]
size_dp = [32, 32, 32]
gravity = [0.0, 0.0, 0.0]

[particles]
diameter = 75e-6
density = 1500.0
solids_fraction = 0.1
velocity_rms = 0.1

[contact]
stiffness = 1.27

[run]
end_time = 1e-3
)";

/// `text` with `from` replaced by `to`; fails loudly if `from` is not there (a stale test case).
std::string replaced(const std::string& text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  if (at == std::string::npos) throw std::logic_error("test scene has no \"" + from + "\"");
  return text.substr(0, at) + to + text.substr(at + from.size());
}

struct BadInput {
  const char* name;  // the rule the case checks
  std::string toml;  // scene text
  std::vector<std::string> overrides;
  std::vector<std::string> expected;  // substrings of the message: key, value, what is allowed
  cgd::ToolAccepts accepts{};         // what the tool loading the scene accepts (default: every law)
};

std::vector<BadInput> bad_inputs() {
  const std::string& wet = kWetScene;
  const std::string& dry = kDryScene;
  const auto two_way =
      replaced(wet, "coupling = \"quiescent\"", "coupling = \"two-way\"\ncells = [8, 32, 8]");
  return {
      // --- structure: unknown names, types, arrays
      {"UnknownSectionSuggestsClosest",
       wet + "\n[partcles]\nseed = 2\n",
       {},
       {"unknown section [partcles]", "did you mean [particles]"}},
      {"UnknownKeySuggestsClosest",
       replaced(wet, "diameter = 75e-6", "diamter = 75e-6"),
       {},
       {"particles.diamter", "did you mean particles.diameter?"}},
      {"KeyInWrongSectionSuggestsItsSection",
       replaced(wet, "solids_fraction = 0.05", "solids_fraction = 0.05\nviscosity = 1e-5"),
       {},
       {"unknown key particles.viscosity", "did you mean fluid.viscosity?"}},
      {"TopLevelKeyIsRejected", "seed = 3\n" + wet, {}, {"unknown top-level key seed", "particles.seed"}},
      {"SectionGivenAsValueIsRejected", "fluid = 3\n" + dry, {}, {"must be a section [fluid]"}},
      {"StringWhereNumberExpected",
       replaced(wet, "density = 1500.0", "density = \"heavy\""),
       {},
       {"particles.density = \"heavy\"", "must be a number", "kg/m^3"}},
      {"BooleanWhereNumberExpected",
       replaced(wet, "restitution = 0.9", "restitution = true"),
       {},
       {"contact.restitution = true", "must be a number"}},
      {"NumberWhereStringExpected",
       replaced(wet, "coupling = \"quiescent\"", "coupling = 3"),
       {},
       {"fluid.coupling = 3", "must be a string"}},
      {"NumberWhereBooleanExpected",
       wet + "",
       {"fluid.pressure_gradient_force=1"},
       {"fluid.pressure_gradient_force = 1", "must be true or false"}},
      {"FractionalSeedIsRejected",
       replaced(wet, "solids_fraction = 0.05", "solids_fraction = 0.05\nseed = 1.5"),
       {},
       {"particles.seed = 1.5", "must be an integer"}},
      {"NotANumberIsRejected",
       replaced(wet, "diameter = 75e-6", "diameter = nan"),
       {},
       {"particles.diameter = nan", "must be a finite number"}},
      {"NonNumericArrayElementIsNamed",
       replaced(wet, "gravity = [0.0, -9.81, 0.0]", "gravity = [0.0, \"down\", 0.0]"),
       {},
       {"domain.gravity = [0.0, \"down\", 0.0]", "array of 3 numbers", "element 2 (\"down\")"}},
      {"ArrayOfWrongLengthIsRejected",
       replaced(wet, "size_dp = [24, 96, 24]", "size_dp = [24, 96]"),
       {},
       {"domain.size_dp = [24, 96]", "array of 3 numbers", "got 2 elements"}},
      {"FractionalCellCountIsRejected",
       replaced(two_way, "cells = [8, 32, 8]", "cells = [8.5, 32, 8]"),
       {},
       {"fluid.cells = [8.5, 32, 8]", "array of 3 integers"}},
      {"SyntaxErrorNamesTheLine",
       replaced(wet, "density = 1500.0", "density = = 1500.0"),
       {},
       {"TOML syntax error", "line 7"}},

      // --- required keys
      {"MissingDomainSizeIsReported",
       replaced(wet, "size_dp = [24, 96, 24]\n", ""),
       {},
       {"domain.size_dp is missing", "domain.size"}},
      {"MissingDiameterIsReported",
       replaced(wet, "diameter = 75e-6\n", ""),
       {},
       {"particles.diameter is missing", "(m, "}},
      {"MissingDensityIsReported",
       replaced(wet, "density = 1500.0\n", ""),
       {},
       {"particles.density is missing", "kg/m^3"}},
      {"MissingSolidsFractionIsReported",
       replaced(wet, "solids_fraction = 0.05\n", ""),
       {},
       {"particles.solids_fraction is missing"}},
      {"MissingEndTimeIsReported",
       replaced(wet, "end_time = 0.05\n", ""),
       {},
       {"run.end_time is missing", "end_time_tref"}},
      {"ContactsNeedAStiffness",
       replaced(dry, "stiffness = 1.27\n", "restitution = 0.9\n"),
       {},
       {"contact.stiffness is missing", "contact.gamma_star", "spring-dashpot"}},
      {"NoContactsAndNoFluidNeedAnExplicitTimeStep",
       replaced(dry, "stiffness = 1.27", "model = \"none\""),
       {},
       {"run.dt is missing", "contact.model = \"none\""}},
      {"SolvedFluidNeedsCells",
       replaced(wet, "coupling = \"quiescent\"", "coupling = \"two-way\""),
       {},
       {"fluid.cells is missing", "\"two-way\"", "dx_over_dp"}},
      {"OneWayFluidNeedsCells",
       replaced(wet, "coupling = \"quiescent\"", "coupling = \"one-way\""),
       {},
       {"fluid.cells is missing", "\"one-way\""}},

      // --- ranges
      {"RejectsNegativeDiameter",
       replaced(wet, "diameter = 75e-6", "diameter = -1e-5"),
       {},
       {"particles.diameter = -1e-05: must be > 0 (m"}},
      {"RejectsZeroDiameter",
       replaced(wet, "diameter = 75e-6", "diameter = 0"),
       {},
       {"particles.diameter = 0", "must be > 0"}},
      {"RejectsNonPositiveParticleDensity",
       replaced(wet, "density = 1500.0", "density = -1500.0"),
       {},
       {"particles.density = -1500.0", "must be > 0", "kg/m^3"}},
      {"RejectsZeroSolidsFraction",
       replaced(wet, "solids_fraction = 0.05", "solids_fraction = 0.0"),
       {},
       {"particles.solids_fraction = 0.0", "must be in (0, 0.64)"}},
      {"RejectsSolidsFractionAbovePacking",
       replaced(wet, "solids_fraction = 0.05", "solids_fraction = 0.7"),
       {},
       {"particles.solids_fraction = 0.7", "must be in (0, 0.64)", "random close packing"}},
      {"RejectsParcelSizeBelowOne",
       replaced(wet, "solids_fraction = 0.05", "solids_fraction = 0.05\nparcel_size = 0.5"),
       {},
       {"particles.parcel_size = 0.5", "must be >= 1"}},
      {"RejectsNegativeVelocityRms",
       replaced(wet, "solids_fraction = 0.05", "solids_fraction = 0.05\nvelocity_rms = -0.1"),
       {},
       {"particles.velocity_rms = -0.1", "must be >= 0", "m/s"}},
      {"RejectsNegativeSeed", wet, {"particles.seed=-4"}, {"particles.seed = -4", "integer >= 0"}},
      {"RejectsBoxEdgeBelowFourDiameters",
       replaced(wet, "size_dp = [24, 96, 24]", "size_dp = [3, 96, 24]"),
       {},
       {"domain.size_dp = [3, 96, 24]", ">= 4 parcel diameters", "edge x"}},
      {"RejectsBoxEdgeBelowFourParcelDiameters",
       replaced(wet, "solids_fraction = 0.05", "solids_fraction = 0.05\nparcel_size = 8"),
       {},
       {"domain.size_dp = [24, 96, 24]", "4 alpha d_p = 32 primary diameters"}},
      {"RejectsBoxInMetresBelowFourDiameters",
       replaced(wet, "size_dp = [24, 96, 24]", "size = [1e-3, 1e-4, 1e-3]"),
       {},
       {"domain.size = [0.001, 0.0001, 0.001]", "4 alpha d_p = 0.0003 m", "edge y"}},
      {"RejectsTStarAboveBound",
       replaced(wet, "restitution = 0.9", "restitution = 0.9\nt_star = 0.5"),
       {},
       {"contact.t_star = 0.5", "must be in (0, 0.2]"}},
      {"RejectsZeroTStar",
       replaced(wet, "restitution = 0.9", "restitution = 0.9\nt_star = 0"),
       {},
       {"contact.t_star = 0", "(0, 0.2]"}},
      {"RejectsZeroRestitution",
       replaced(wet, "restitution = 0.9", "restitution = 0.0"),
       {},
       {"contact.restitution = 0.0", "must be in (0, 1]"}},
      {"RejectsRestitutionAboveOne",
       replaced(wet, "restitution = 0.9", "restitution = 1.1"),
       {},
       {"contact.restitution = 1.1", "(0, 1]"}},
      {"RejectsNegativeFriction",
       replaced(wet, "friction = 0.1", "friction = -0.1"),
       {},
       {"contact.friction = -0.1", "must be >= 0"}},
      {"RejectsZeroStiffnessRatio",
       replaced(wet, "friction = 0.1", "friction = 0.1\nkn_over_kt = 0"),
       {},
       {"contact.kn_over_kt = 0", "must be > 0"}},
      {"RejectsZeroDampingRatio",
       replaced(wet, "friction = 0.1", "friction = 0.1\ngamman_over_gammat = 0.0"),
       {},
       {"contact.gamman_over_gammat = 0.0", "must be > 0"}},
      {"RejectsNegativeSkin",
       replaced(wet, "friction = 0.1", "friction = 0.1\nskin_over_dp = -0.1"),
       {},
       {"contact.skin_over_dp = -0.1", "must be >= 0"}},
      {"RejectsZeroSkinTargetSteps",
       wet + "\n[numerics]\nskin_target_steps = 0\n",
       {},
       {"numerics.skin_target_steps = 0", "must be an integer >= 1"}},
      {"RejectsNegativeGammaStar",
       replaced(wet, "gamma_star = 1e-3", "gamma_star = -1e-3"),
       {},
       {"contact.gamma_star = -0.001", "must be > 0"}},
      {"RejectsZeroStiffness",
       replaced(dry, "stiffness = 1.27", "stiffness = 0"),
       {},
       {"contact.stiffness = 0", "must be > 0", "N/m"}},
      {"RejectsCourantAboveTheSchemesLimit",
       replaced(two_way, "drag = \"stokes\"", "drag = \"stokes\"\ncourant = 1.5"),
       {},
       {"fluid.courant = 1.5", "must be in (0, 0.5]", "Adams-Bashforth"}},
      {"RejectsZeroViscosity",
       replaced(wet, "viscosity = 1.8e-5", "viscosity = 0.0"),
       {},
       {"fluid.viscosity = 0.0", "must be > 0 (Pa s"}},
      {"RejectsFluidDenserThanParticles",
       replaced(wet, "density = 1.3", "density = 2000.0"),
       {},
       {"fluid.density = 2000.0", "must be in (0, particles.density = 1500) kg/m^3"}},
      {"RejectsZeroCells",
       replaced(two_way, "cells = [8, 32, 8]", "cells = [0, 32, 8]"),
       {},
       {"fluid.cells = [0, 32, 8]", "[1, 1000000]"}},
      {"RejectsCellLargerThanBox",
       replaced(two_way, "cells = [8, 32, 8]", "dx_over_dp = 100.0"),
       {},
       {"fluid.dx_over_dp = 100.0", "must be > 0 and give between 1 and 1000000 cells along every box edge",
        "it gives 0 cells along x"}},
      {"RejectsZeroEndTime",
       replaced(wet, "end_time = 0.05", "end_time = 0"),
       {},
       {"run.end_time = 0", "must be > 0"}},
      {"RejectsNegativeEndTimeWithTheRuleOfZero",
       replaced(wet, "end_time = 0.05", "end_time = -1.0"),
       {},
       {"run.end_time = -1.0", "must be > 0 (s, simulated time)"}},
      {"RejectsNegativeEndTimeInTref",
       replaced(wet, "end_time = 0.05", "end_time_tref = -2.0"),
       {},
       {"run.end_time_tref = -2.0", "must be > 0 (simulated time in units of t_ref"}},
      {"RejectsNegativeFluidDensityWithTheRuleOfADenseFluid",
       replaced(wet, "density = 1.3", "density = -1.3"),
       {},
       {"fluid.density = -1.3", "must be in (0, particles.density = 1500) kg/m^3"}},
      {"RejectsNegativeCellSizeWithTheRuleOfALargeOne",
       replaced(two_way, "cells = [8, 32, 8]", "dx_over_dp = -3.0"),
       {},
       {"fluid.dx_over_dp = -3.0", "must be > 0 and give between 1 and 1000000 cells along every box edge",
        "24 x 96 x 24 d_p"}},
      {"RejectsNegativeDumpInterval",
       replaced(wet, "dump_interval = 0.005", "dump_interval = -1.0"),
       {},
       {"run.dump_interval = -1.0", "must be >= 0"}},
      {"RejectsZeroCheckpointInterval",
       replaced(wet, "end_time = 0.05", "end_time = 0.05\ncheckpoint_wall_s = 0"),
       {},
       {"run.checkpoint_wall_s = 0", "must be > 0"}},

      // --- enums
      {"RejectsUnknownContactModel",
       wet,
       {"contact.model=hertz"},
       {"contact.model = \"hertz\"", "\"spring-dashpot\", \"none\""}},
      {"RejectsUnknownCouplingWithSuggestion",
       replaced(wet, "coupling = \"quiescent\"", "coupling = \"twoway\""),
       {},
       {"fluid.coupling = \"twoway\"", "\"two-way\", \"one-way\", \"quiescent\"",
        "did you mean \"two-way\"?"}},
      {"RejectsUnknownDragLaw",
       replaced(wet, "drag = \"stokes\"", "drag = \"ergun\""),
       {},
       {"fluid.drag = \"ergun\"", "\"beetstra\", \"wen-yu\", \"stokes\", \"radl2014\", \"model\"",
        "filtered laws of coarse-grid runs"}},

      // --- alternatives and keys that need something else
      {"RejectsGammaStarTogetherWithStiffness",
       replaced(wet, "gamma_star = 1e-3", "gamma_star = 1e-3\nstiffness = 1.27"),
       {},
       {"contact.gamma_star = 0.001 and contact.stiffness = 1.27", "give either contact.gamma_star",
        "not both", "delete one", "--set contact.gamma_star=VALUE replaces contact.stiffness"}},
      {"RejectsGammaStarWithoutFluid",
       replaced(dry, "stiffness = 1.27", "gamma_star = 1e-3"),
       {},
       {"contact.gamma_star = 0.001", "needs a [fluid] section", "give contact.stiffness"}},
      {"RejectsGammaStarWithoutGravity",
       replaced(wet, "gravity = [0.0, -9.81, 0.0]", "gravity = [0.0, 0.0, 0.0]"),
       {},
       {"contact.gamma_star = 0.001", "needs gravity", "contact.stiffness"}},
      {"RejectsEndTimeInTrefWithoutFluid",
       replaced(dry, "end_time = 1e-3", "end_time_tref = 2.0"),
       {},
       {"run.end_time_tref = 2.0", "needs a [fluid] section", "run.end_time"}},
      {"RejectsDumpIntervalInTrefWithoutFluid",
       dry + "dump_interval_tref = 0.5\n",
       {},
       {"run.dump_interval_tref = 0.5", "needs a [fluid] section"}},
      {"RejectsEndTimeGivenTwice",
       replaced(wet, "end_time = 0.05", "end_time = 0.05\nend_time_tref = 2.0"),
       {},
       {"run.end_time = 0.05 and run.end_time_tref = 2.0",
        "run.end_time (s) or run.end_time_tref (units of t_ref", "not both",
        "--set run.end_time=VALUE replaces run.end_time_tref"}},
      {"RejectsBoxSizeGivenTwice",
       replaced(wet, "size_dp = [24, 96, 24]", "size_dp = [24, 96, 24]\nsize = [1e-3, 1e-3, 1e-3]"),
       {},
       {"domain.size_dp = [24, 96, 24] and domain.size = [0.001, 0.001, 0.001]",
        "domain.size_dp (primary diameters) or domain.size (m)", "not both"}},
      {"RejectsCellsTogetherWithCellSize",
       replaced(two_way, "cells = [8, 32, 8]", "cells = [8, 32, 8]\ndx_over_dp = 3.0"),
       {},
       {"fluid.cells = [8, 32, 8] and fluid.dx_over_dp = 3.0", "give either fluid.cells", "not both"}},
      {"RejectsDumpIntervalGivenTwice",
       replaced(wet, "dump_interval = 0.005", "dump_interval = 0.005\ndump_interval_tref = 1.0"),
       {},
       {"run.dump_interval = 0.005 and run.dump_interval_tref = 1.0", "not both"}},
      {"RejectsSeriesIntervalGivenTwice",
       wet + "series_interval = 0.001\nseries_interval_tref = 0.1\n",
       {},
       {"run.series_interval = 0.001 and run.series_interval_tref = 0.1", "not both"}},
      {"RejectsSamplingStartGivenTwice",
       wet + "sampling_start = 0.01\nsampling_start_tref = 1.0\n",
       {},
       {"run.sampling_start = 0.01 and run.sampling_start_tref = 1.0", "not both"}},
      {"ResolvedRunsRefuseAFilteredLawNamingTheToolThatTakesIt",
       replaced(wet, "drag = \"stokes\"", "drag = \"radl2014\""),
       {},
       {"fluid.drag = \"radl2014\"", "coarse-grid runs (cgd-coarse)", "\"beetstra\", \"wen-yu\", \"stokes\""},
       cgd::kResolvedRunAccepts},
      {"ResolvedRunsOfferOnlyMicroscopicLaws",
       replaced(wet, "drag = \"stokes\"", "drag = \"wenyu\""),
       {},
       {"must be one of \"beetstra\", \"wen-yu\", \"stokes\" (microscopic drag law;",
        "did you mean \"wen-yu\"?"},
       cgd::kResolvedRunAccepts},
      {"RejectsExplicitTimeStepWithContacts",
       replaced(wet, "end_time = 0.05", "end_time = 0.05\ndt = 1e-6"),
       {},
       {"run.dt = 1e-06", "contact.t_star"}},

      // --- --set overrides
      {"OverrideWithoutEqualsIsRejected",
       wet,
       {"particles.solids_fraction"},
       {"--set particles.solids_fraction", "SECTION.KEY=VALUE"}},
      {"OverrideWithoutSectionIsRejected", wet, {"diameter=1e-4"}, {"--set diameter=1e-4", "SECTION.KEY"}},
      {"OverrideOfUnknownSectionIsRejected",
       wet,
       {"flud.drag=stokes"},
       {"unknown section [flud]", "did you mean [fluid]"}},
      {"OverrideOfUnknownKeyIsRejected",
       wet,
       {"fluid.drg=stokes"},
       {"unknown key fluid.drg", "did you mean fluid.drag?"}},
      {"OverrideWithoutValueIsRejected", wet, {"run.end_time="}, {"--set run.end_time=", "no value"}},
      {"OverrideWithBrokenArrayIsRejected",
       wet,
       {"domain.size_dp=[10, 20"},
       {"--set domain.size_dp=[10, 20", "not valid TOML"}},
      {"OverrideOutOfRangeSaysItCameFromSet",
       wet,
       {"particles.solids_fraction=0.9"},
       {"particles.solids_fraction = 0.9 (from --set)", "(0, 0.64)"}},
      {"OverrideBareStringIsCheckedAgainstChoices",
       wet,
       {"fluid.drag=wenyu"},
       {"fluid.drag = \"wenyu\"", "did you mean \"wen-yu\"?"}},
      {"OverrideWithTextWhereNumberExpected",
       wet,
       {"particles.diameter=big"},
       {"particles.diameter = \"big\"", "must be a number"}},
  };
}

void PrintTo(const BadInput& c, std::ostream* out) {
  *out << c.name;
}

class SceneValidation : public ::testing::TestWithParam<BadInput> {};

TEST_P(SceneValidation, MessageNamesKeyValueAndAllowedRange) {
  const BadInput& c = GetParam();
  try {
    load_scene_from_string(c.toml, "scene.toml", c.overrides, c.accepts);
    FAIL() << "accepted a bad scene (" << c.name << ")";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind("scene.toml", 0), 0u) << "the message must start with the file name: " << message;
    for (const auto& expected : c.expected)
      EXPECT_NE(message.find(expected), std::string::npos)
          << "expected \"" << expected << "\" in: " << message;
  }
}

INSTANTIATE_TEST_SUITE_P(BadInputs, SceneValidation, ::testing::ValuesIn(bad_inputs()),
                         [](const ::testing::TestParamInfo<BadInput>& info) {
                           return std::string(info.param.name);
                         });

TEST(SceneValidationTable, CoversAtLeastThirtyCases) {
  EXPECT_GE(bad_inputs().size(), 30u);
}

TEST(SceneFiles, MissingFileIsAnInputErrorNamingThePath) {
  try {
    cgd::load_scene("/nonexistent/dir/scene.toml");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/scene.toml: cannot read the scene file"),
              std::string::npos)
        << e.what();
  }
}

TEST(SceneFiles, DirectoryIsAnInputError) {
  EXPECT_THROW(cgd::load_scene(std::filesystem::temp_directory_path().string()), InputError);
}

// ---- derived numbers ----------------------------------------------------------------------------

double relative(double a, double b) {
  return std::abs(a - b) / std::abs(b);
}

TEST(SceneDerived, PaperParametersGiveTheReferenceScalesOfModelsMd) {
  const auto s = load_scene_from_string(kWetScene, "paper.toml");
  const auto& x = s.derived;
  const double d = 75e-6;
  // docs/models.md quotes these to the digits below; tolerances are half a unit of the last digit quoted.
  EXPECT_NEAR(x.u_t_m_s, 0.2185, 0.00005);
  EXPECT_NEAR(x.re_p, 1.18, 0.005);
  EXPECT_NEAR(x.fr_p, 65.0, 0.5);
  EXPECT_NEAR(x.l_ref_m, 4.86e-3, 0.005e-3);
  EXPECT_NEAR(x.l_char_m / d, 4.02,
              0.005);  // (docs/models.md's "3.02e-4 m" is 4.02 d_p rounded up; 4.018 d_p = 3.013e-4 m)
  EXPECT_NEAR(x.t_ref_s, 0.0223, 0.00005);
  // Contact numbers of docs/models.md (1.27 N/m, 3.59e-5 s, 7.18e-7 s) are rounded from u_t ~= 0.219 m/s
  // (the peer benchmark's value); with u_t = 0.21851 m/s the same gamma* gives k_n = 1.2760 N/m.
  // So: within 0.5 % of the quoted values, and exact against the formulas below.
  EXPECT_LT(relative(x.k_n_N_m, 1.27), 0.005);
  EXPECT_LT(relative(x.t_c_s, 3.59e-5), 0.005);
  EXPECT_LT(relative(x.dt_dem_s, 7.18e-7), 0.005);
  EXPECT_NEAR(x.k_n_N_m, 1.2760, 0.00005);
  EXPECT_NEAR(x.t_c_s, 3.5816e-5, 0.0001e-5);
  EXPECT_NEAR(x.dt_dem_s, 7.1633e-7, 0.0001e-7);
  EXPECT_NEAR(x.dt_dem_s / x.t_c_s, 0.02, 1e-15);
}

TEST(SceneDerived, DerivedNumbersFollowTheFormulasOfModelsMd) {
  const auto s = load_scene_from_string(kWetScene, "paper.toml");
  const auto& x = s.derived;
  const double d = 75e-6, rho_p = 1500.0, rho_f = 1.3, mu = 1.8e-5, g = 9.81;
  const double v_p = std::numbers::pi / 6.0 * d * d * d;
  EXPECT_DOUBLE_EQ(x.particle_volume_m3, v_p);
  EXPECT_DOUBLE_EQ(x.particle_mass_kg, rho_p * v_p);
  EXPECT_DOUBLE_EQ(x.parcel_diameter_m, d);
  EXPECT_DOUBLE_EQ(x.parcel_mass_kg, rho_p * v_p);
  // u_t solves the Schiller-Naumann balance (iteration converged to round-off)
  const double re = rho_f * d * x.u_t_m_s / mu;
  EXPECT_LT(
      relative(x.u_t_m_s, (rho_p - rho_f) * g * d * d / (18.0 * mu * (1.0 + 0.15 * std::pow(re, 0.687)))),
      1e-12);
  EXPECT_DOUBLE_EQ(x.re_p, re);
  EXPECT_DOUBLE_EQ(x.fr_p, x.u_t_m_s * x.u_t_m_s / (g * d));
  EXPECT_LT(relative(x.l_char_m, d * std::cbrt(x.fr_p)), 1e-13);  // L_ref Fr^(-2/3) = d Fr^(1/3)
  EXPECT_DOUBLE_EQ(x.t_ref_s, x.u_t_m_s / g);
  EXPECT_DOUBLE_EQ(x.stokes_relaxation_s, rho_p * d * d / (18.0 * mu));
  // gamma* = (g/u_t) sqrt(rho_p d^3 / k_n) recovered from k_n
  EXPECT_LT(relative((g / x.u_t_m_s) * std::sqrt(rho_p * d * d * d / x.k_n_N_m), 1e-3), 1e-13);
  const auto sd = cgd::spring_dashpot(x.k_n_N_m, 0.9, rho_p * v_p / 2.0, 3.5, 1.0);
  EXPECT_DOUBLE_EQ(x.t_c_s, sd.t_c);
  EXPECT_DOUBLE_EQ(x.gamma_n_kg_s, sd.gamma_n);
  EXPECT_DOUBLE_EQ(x.k_t_N_m, x.k_n_N_m / 3.5);
  EXPECT_DOUBLE_EQ(x.gamma_t_kg_s, x.gamma_n_kg_s);
  // quiescent fluid: no grid, no fluid step
  EXPECT_EQ(x.cells, (std::array<int, 3>{0, 0, 0}));
  EXPECT_EQ(x.dt_fluid_s, 0.0);
  // particle count: round(phi V_box / V_p) = round(0.05 * 24*96*24 / (pi/6)) = 5280
  EXPECT_EQ(x.particle_count, 5280);
  EXPECT_DOUBLE_EQ(x.memory_estimate_bytes, 5280 * 450.0);
}

TEST(SceneDerived, PeerBenchmarkStiffnessReproducesParamsInc) {
  // shared/peers/params.inc, printed to 11 significant digits: compare to 1e-9.
  const auto s =
      load_scene_from_string(replaced(kWetScene, "gamma_star = 1e-3", "stiffness = 1.27"), "peer.toml");
  EXPECT_LT(relative(s.derived.t_c_s, 3.5901612019e-05), 1e-9);
  EXPECT_LT(relative(s.derived.dt_dem_s, 7.1803224038e-07), 1e-9);
  EXPECT_LT(relative(s.derived.gamma_n_kg_s, 9.7238356470e-07), 1e-9);
  EXPECT_LT(relative(s.derived.k_t_N_m, 3.6285714286e-01), 1e-9);
}

TEST(SceneDerived, ParcelsScaleStiffnessAndContactTimeWithParcelSize) {
  // docs/models.md "Parcels": mass alpha^3 m, k_n,parcel = alpha k_n, so t_c,parcel = alpha t_c.
  const std::string base = replaced(kDryScene, "size_dp = [32, 32, 32]", "size_dp = [64, 64, 64]");
  const auto one = load_scene_from_string(base, "a.toml");
  const auto two = load_scene_from_string(base, "b.toml", {"particles.parcel_size=2"});
  EXPECT_DOUBLE_EQ(two.derived.parcel_diameter_m, 2.0 * 75e-6);
  EXPECT_DOUBLE_EQ(two.derived.parcel_mass_kg, 8.0 * one.derived.particle_mass_kg);
  EXPECT_DOUBLE_EQ(two.derived.k_n_N_m, 2.0 * 1.27);
  EXPECT_LT(relative(two.derived.t_c_s, 2.0 * one.derived.t_c_s), 1e-13);
  // one parcel stands for alpha^3 primaries: the count falls by 8 (both rounded from the same volume)
  EXPECT_NEAR(static_cast<double>(two.derived.particle_count), one.derived.particle_count / 8.0, 1.0);
}

TEST(SceneDerived, SolvedFluidDerivesCellsAndCourantTimeStep) {
  const auto s = load_scene_from_string(replaced(kWetScene, "coupling = \"quiescent\"",
                                                 "coupling = \"two-way\"\ncells = [8, 32, 8]\ncourant = 0.3"),
                                        "w.toml");
  const auto& x = s.derived;
  EXPECT_EQ(x.cells, (std::array<int, 3>{8, 32, 8}));
  const double cell = 3.0 * 75e-6;  // 24 d_p / 8 cells
  EXPECT_LT(relative(x.dt_fluid_s, 0.3 * cell / x.u_t_m_s), 1e-13);
  EXPECT_DOUBLE_EQ(x.memory_estimate_bytes, 5280 * 450.0 + 16.0 * 8.0 * (8 * 32 * 8));

  // dx_over_dp: cells = round(box / (dx d))
  const auto t = load_scene_from_string(
      replaced(kWetScene, "coupling = \"quiescent\"", "coupling = \"one-way\"\ndx_over_dp = 3.33"), "w.toml");
  EXPECT_EQ(t.derived.cells, (std::array<int, 3>{7, 29, 7}));  // 24/3.33 = 7.2, 96/3.33 = 28.8
  EXPECT_EQ(t.fluid->cells, t.derived.cells);
}

TEST(SceneDerived, QuiescentFluidIgnoresCellsForTheGrid) {
  const auto s = load_scene_from_string(
      replaced(kWetScene, "drag = \"stokes\"", "drag = \"stokes\"\ncells = [8, 32, 8]"), "q.toml");
  EXPECT_FALSE(s.solves_fluid());
  EXPECT_EQ(s.derived.cells, (std::array<int, 3>{0, 0, 0}));
  EXPECT_EQ(s.derived.dt_fluid_s, 0.0);
}

TEST(SceneDerived, TimesInUnitsOfTrefAreConvertedToSeconds) {
  const auto s = load_scene_from_string(
      replaced(replaced(kWetScene, "end_time = 0.05", "end_time_tref = 20.0"), "dump_interval = 0.005",
               "dump_interval_tref = 0.5\nseries_interval_tref = 0.1"),
      "t.toml");
  EXPECT_DOUBLE_EQ(s.run.end_time_s, 20.0 * s.derived.t_ref_s);
  EXPECT_DOUBLE_EQ(s.run.dump_interval_s, 0.5 * s.derived.t_ref_s);
  EXPECT_DOUBLE_EQ(s.run.series_interval_s, 0.1 * s.derived.t_ref_s);
}

TEST(SceneDerived, WithoutContactsTheStepResolvesDragRelaxationOrIsGiven) {
  const auto wet =
      load_scene_from_string(replaced(kWetScene, "gamma_star = 1e-3", "model = \"none\""), "n.toml");
  EXPECT_FALSE(wet.has_contacts());
  EXPECT_DOUBLE_EQ(wet.derived.dt_dem_s, 0.02 * wet.derived.stokes_relaxation_s);
  EXPECT_EQ(wet.derived.k_n_N_m, 0.0);
  const auto dry = load_scene_from_string(replaced(kDryScene, "stiffness = 1.27", "model = \"none\""),
                                          "n.toml", {"run.dt=1e-6"});
  EXPECT_DOUBLE_EQ(dry.derived.dt_dem_s, 1e-6);
  const auto wet_dt = load_scene_from_string(replaced(kWetScene, "gamma_star = 1e-3", "model = \"none\""),
                                             "n.toml", {"run.dt=2e-6"});
  EXPECT_DOUBLE_EQ(wet_dt.derived.dt_dem_s, 2e-6);
}

TEST(SceneDerived, DryGasHasNoFluidScalesAndFrictionSwitchesRotation) {
  const auto s = load_scene_from_string(kDryScene, "gas.toml");
  EXPECT_FALSE(s.fluid.has_value());
  EXPECT_EQ(s.derived.u_t_m_s, 0.0);
  EXPECT_TRUE(s.has_friction());  // default friction 0.1
  const auto frictionless = load_scene_from_string(kDryScene, "gas.toml", {"contact.friction=0"});
  EXPECT_FALSE(frictionless.has_friction());
}

TEST(SceneDerived, BoxInMetresIsTakenAsIs) {
  const auto s = load_scene_from_string(
      replaced(kWetScene, "size_dp = [24, 96, 24]", "size = [1.8e-3, 7.2e-3, 1.8e-3]"), "m.toml");
  EXPECT_DOUBLE_EQ(s.domain.size_m[1], 7.2e-3);
  EXPECT_EQ(s.derived.particle_count, 5280);
}

// ---- overrides and the effective scene ------------------------------------------------------------

TEST(SceneOverrides, ValuesAreReadAsTomlOrAsBareStrings) {
  const auto s = load_scene_from_string(
      kWetScene, "dry_settling.toml",
      {"particles.solids_fraction=0.2", "fluid.drag=wen-yu", "domain.size_dp=[10,20,10]",
       "fluid.pressure_gradient_force=false", "particles.seed=7", "contact.restitution = 0.8",
       "fluid.coupling=\"quiescent\""});
  EXPECT_DOUBLE_EQ(s.particles.solids_fraction, 0.2);
  EXPECT_EQ(s.fluid->drag, cgd::DragLaw::WenYu);
  EXPECT_DOUBLE_EQ(s.domain.size_m[1], 20 * 75e-6);
  EXPECT_FALSE(s.fluid->pressure_gradient_force);
  EXPECT_EQ(s.particles.seed, 7u);
  EXPECT_DOUBLE_EQ(s.contact.restitution, 0.8);
  EXPECT_EQ(s.name, "dry_settling");
}

TEST(SceneOverrides, LaterOverrideWinsAndCanAddASection) {
  const auto s = load_scene_from_string(kDryScene, "gas.toml",
                                        {"particles.solids_fraction=0.2", "particles.solids_fraction=0.3",
                                         "fluid.coupling=quiescent", "fluid.drag=stokes"});
  EXPECT_DOUBLE_EQ(s.particles.solids_fraction, 0.3);
  ASSERT_TRUE(s.fluid.has_value());
  EXPECT_EQ(s.fluid->coupling, cgd::Coupling::Quiescent);
  EXPECT_EQ(s.fluid->drag, cgd::DragLaw::Stokes);
  EXPECT_DOUBLE_EQ(s.fluid->viscosity_Pa_s, 1.8e-5) << "fluid keys not given keep their defaults";
  EXPECT_GT(s.derived.stokes_relaxation_s, 0.0);
}

TEST(SceneOverrides, EffectiveTomlHoldsTheOverridesAndReloadsToTheSameScene) {
  const auto s =
      load_scene_from_string(kWetScene, "w.toml", {"particles.solids_fraction=0.2", "fluid.drag=wen-yu"});
  EXPECT_NE(s.effective_toml.find("solids_fraction = 0.2\n"), std::string::npos) << s.effective_toml;
  EXPECT_NE(s.effective_toml.find("drag = \"wen-yu\""), std::string::npos) << s.effective_toml;
  EXPECT_NE(s.effective_toml.find("diameter = 7.5e-05\n"), std::string::npos) << "shortest round-trip floats";
  const auto again = load_scene_from_string(s.effective_toml, "w.toml");
  EXPECT_EQ(again.effective_toml, s.effective_toml);
  EXPECT_EQ(again.derived.particle_count, s.derived.particle_count);
  EXPECT_EQ(again.derived.dt_dem_s, s.derived.dt_dem_s);
  EXPECT_EQ(again.derived.u_t_m_s, s.derived.u_t_m_s);
}

// Issue 11, item 3: each pair of keys that gives one quantity two ways can be switched from the command
// line: a --set of one key replaces the other in the file, and the effective scene holds only the new one.
TEST(SceneOverrides, SetSwitchesEveryAlternative) {
  const std::string two_way =
      replaced(kWetScene, "coupling = \"quiescent\"", "coupling = \"two-way\"\ncells = [8, 32, 8]");
  struct Switch {
    std::string scene, set, replaced_line;
  };
  const std::vector<Switch> switches = {
      {two_way, "run.end_time_tref=2", "end_time = "},
      {replaced(two_way, "end_time = 0.05", "end_time_tref = 2.0"), "run.end_time=0.01", "end_time_tref = "},
      {two_way, "run.dump_interval_tref=0.5", "dump_interval = "},
      {two_way + "series_interval = 0.001\n", "run.series_interval_tref=0.1", "series_interval = "},
      {two_way + "sampling_start_tref = 1.0\n", "run.sampling_start=0.002", "sampling_start_tref = "},
      {two_way, "fluid.dx_over_dp=4", "cells = "},
      {replaced(two_way, "cells = [8, 32, 8]", "dx_over_dp = 3.0"), "fluid.cells=[6, 24, 6]",
       "dx_over_dp = "},
      {two_way, "domain.size=[2e-3, 8e-3, 2e-3]", "size_dp = "},
      {two_way, "contact.stiffness=1.27", "gamma_star = "},
      {replaced(two_way, "gamma_star = 1e-3", "stiffness = 1.27"), "contact.gamma_star=1e-3", "stiffness = "},
  };
  for (const Switch& sw : switches) {
    SCOPED_TRACE("--set " + sw.set);
    ASSERT_NE(sw.scene.find(sw.replaced_line), std::string::npos) << "stale case: the scene lacks the key";
    cgd::Scene s;
    ASSERT_NO_THROW(s = load_scene_from_string(sw.scene, "scene.toml", {sw.set}));
    EXPECT_EQ(s.effective_toml.find("\n" + sw.replaced_line), std::string::npos) << s.effective_toml;
    const std::string set_key = sw.set.substr(sw.set.find('.') + 1, sw.set.find('=') - sw.set.find('.') - 1);
    EXPECT_NE(s.effective_toml.find("\n" + set_key + " = "), std::string::npos) << s.effective_toml;
  }
  // the values are the new ones
  const auto end_in_s = load_scene_from_string(replaced(two_way, "end_time = 0.05", "end_time_tref = 2.0"),
                                               "scene.toml", {"run.end_time=0.01"});
  EXPECT_DOUBLE_EQ(end_in_s.run.end_time_s, 0.01);
  const auto end_in_tref = load_scene_from_string(two_way, "scene.toml", {"run.end_time_tref=2"});
  EXPECT_DOUBLE_EQ(end_in_tref.run.end_time_s, 2.0 * end_in_tref.derived.t_ref_s);
  const auto cells = load_scene_from_string(two_way, "scene.toml", {"fluid.dx_over_dp=4"});
  EXPECT_EQ(cells.fluid->cells, (std::array<int, 3>{6, 24, 6}));
  // two --set of one pair: the later wins, as for one key given twice
  const auto later =
      load_scene_from_string(two_way, "scene.toml", {"run.end_time_tref=2", "run.end_time=0.02"});
  EXPECT_DOUBLE_EQ(later.run.end_time_s, 0.02);
}

// Issue 11, item 4: a scene with several unknown or misplaced keys is refused with all of them listed, so
// the user fixes the file in one go; each section's key list is given once.
TEST(SceneValidation, ListsEveryUnknownAndMisplacedKeyAtOnce) {
  std::string text = replaced(kWetScene, "diameter = 75e-6", "diamter = 75e-6\nend_time_tref = 2");
  text = replaced(text, "viscosity = 1.8e-5", "viscosity = 1.8e-5\nseed = 3");
  text = replaced(text, "friction = 0.1", "friction = \"high\"");
  try {
    load_scene_from_string(text, "scene.toml");
    FAIL() << "accepted a scene with four bad keys";
  } catch (const InputError& e) {
    const std::string message = e.what();
    for (const char* expected :
         {"scene.toml: 4 problems:", "unknown key particles.diamter; did you mean particles.diameter?",
          "unknown key particles.end_time_tref; did you mean run.end_time_tref?",
          "unknown key fluid.seed; did you mean particles.seed?",
          "contact.friction = \"high\": must be a number", "(keys of [particles]: diameter,",
          "(keys of [fluid]: density,"})
      EXPECT_NE(message.find(expected), std::string::npos)
          << "expected \"" << expected << "\" in: " << message;
    const auto first = message.find("keys of [particles]");
    EXPECT_EQ(message.find("keys of [particles]", first + 1), std::string::npos)
        << "each key list once: " << message;
  }
}

// Issue 11, item 4: one rule per key. A value on either side of the allowed range gets the same rule.
TEST(SceneValidation, BothSidesOfARangeStateTheSameRule) {
  const std::string two_way =
      replaced(kWetScene, "coupling = \"quiescent\"", "coupling = \"two-way\"\ncells = [8, 32, 8]");
  struct Sides {
    std::string key;
    std::string low, high;  // overrides below and above the allowed range
    std::string scene;
  };
  const std::vector<Sides> cases = {
      {"run.end_time", "run.end_time=-1", "run.end_time=0", kWetScene},
      {"fluid.density", "fluid.density=-1", "fluid.density=2000", kWetScene},
      {"fluid.dx_over_dp", "fluid.dx_over_dp=-1", "fluid.dx_over_dp=1000", two_way},
  };
  const auto rule = [](const std::string& scene, const std::string& set) {
    try {
      load_scene_from_string(scene, "scene.toml", {set});
    } catch (const InputError& e) {
      const std::string message = e.what();
      const auto start = message.find(": ", message.find(" = ")) + 2;
      return message.substr(start, message.find(';', start) - start);  // up to what the value gives
    }
    return std::string("(accepted)");
  };
  for (const Sides& c : cases) {
    SCOPED_TRACE(c.key);
    const std::string low = rule(c.scene, c.low), high = rule(c.scene, c.high);
    EXPECT_NE(low, "(accepted)");
    EXPECT_EQ(low, high);
  }
}

TEST(SceneFiles, FilteredLawsLoadForCoarseRunsOnly) {
  const std::string radl = replaced(kWetScene, "drag = \"stokes\"", "drag = \"radl2014\"");
  EXPECT_EQ(load_scene_from_string(radl, "scene.toml").fluid->drag, cgd::DragLaw::Radl2014);
  EXPECT_THROW(load_scene_from_string(radl, "scene.toml", {}, cgd::kResolvedRunAccepts), InputError);
  EXPECT_EQ(load_scene_from_string(kWetScene, "scene.toml", {}, cgd::kResolvedRunAccepts).fluid->drag,
            cgd::DragLaw::Stokes);
}

// ---- names and description --------------------------------------------------------------------

TEST(SceneNames, EnumNamesAreTheSceneNames) {
  EXPECT_STREQ(cgd::to_string(cgd::ContactModel::SpringDashpot), "spring-dashpot");
  EXPECT_STREQ(cgd::to_string(cgd::ContactModel::None), "none");
  EXPECT_STREQ(cgd::to_string(cgd::Coupling::TwoWay), "two-way");
  EXPECT_STREQ(cgd::to_string(cgd::Coupling::OneWay), "one-way");
  EXPECT_STREQ(cgd::to_string(cgd::Coupling::Quiescent), "quiescent");
  EXPECT_STREQ(cgd::to_string(cgd::DragLaw::Beetstra), "beetstra");
  EXPECT_STREQ(cgd::to_string(cgd::DragLaw::WenYu), "wen-yu");
  EXPECT_STREQ(cgd::to_string(cgd::DragLaw::Stokes), "stokes");
  EXPECT_STREQ(cgd::to_string(cgd::DragLaw::Radl2014), "radl2014");
  EXPECT_STREQ(cgd::to_string(cgd::DragLaw::Model), "model");
}

TEST(SceneDescription, ListsEffectsAndDerivedNumbersWithUnits) {
  const auto text = cgd::describe_scene(load_scene_from_string(kWetScene, "dry_settling.toml"));
  for (const char* expected : {"spring-dashpot",
                               "quiescent",
                               "\"stokes\"",
                               "no grid",
                               "friction and rotation",
                               "gravity",
                               "u_t",
                               "m/s",
                               "Re_p",
                               "Fr_p",
                               "L_char",
                               "t_ref",
                               "k_n",
                               "N/m",
                               "t_c",
                               "dt_DEM",
                               "cells",
                               "particle count",
                               "5280",
                               "memory estimate"})
    EXPECT_NE(text.find(expected), std::string::npos) << "missing \"" << expected << "\" in:\n" << text;
  const auto dry = cgd::describe_scene(load_scene_from_string(kDryScene, "gas.toml", {"contact.friction=0"}));
  EXPECT_NE(dry.find("none (dry granular run"), std::string::npos) << dry;
  EXPECT_NE(dry.find("friction and rotation     off"), std::string::npos) << dry;
}

// ---- the shipped scenes ---------------------------------------------------------------------------

/// data/scenes of the source tree: $CGD_SOURCE_DIR (set by CTest), else relative to this file.
std::filesystem::path scene_dir() {
  const char* source = std::getenv("CGD_SOURCE_DIR");
  const std::filesystem::path root =
      source ? std::filesystem::path(source)
             : std::filesystem::path(__FILE__).parent_path().parent_path().parent_path();
  return root / "data" / "scenes";
}

TEST(SceneFiles, EveryShippedSceneLoads) {
  const std::filesystem::path dir = scene_dir();
  ASSERT_TRUE(std::filesystem::is_directory(dir)) << dir;
  std::vector<std::string> loaded;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() != ".toml") continue;
    SCOPED_TRACE(entry.path().string());
    cgd::Scene scene;
    EXPECT_NO_THROW(scene = cgd::load_scene(entry.path().string())) << entry.path();
    EXPECT_EQ(scene.name, entry.path().stem().string());
    loaded.push_back(scene.name);
  }
  for (const char* name :
       {"dry_settling", "granular_gas", "bench_s10", "bench_s30", "bench_l10", "bench_l30"})
    EXPECT_NE(std::find(loaded.begin(), loaded.end(), name), loaded.end()) << name << ".toml missing";
}

TEST(SceneFiles, PeerBenchmarkScenesMatchThePeerCounts) {
  const std::filesystem::path dir = scene_dir();
  // bench/README.md: N per case (gen_init rounds phi V / V_p the same way)
  const std::vector<std::pair<const char*, std::int64_t>> cases = {
      {"bench_s10", 25033}, {"bench_s30", 75099}, {"bench_l10", 200263}, {"bench_l30", 600790}};
  for (const auto& [name, count] : cases) {
    const auto s = cgd::load_scene((dir / (std::string(name) + ".toml")).string());
    EXPECT_EQ(s.derived.particle_count, count) << name;
    EXPECT_LT(relative(s.derived.dt_dem_s, 7.1803224038e-07), 1e-9) << name;
    EXPECT_NEAR(s.run.end_time_s / s.derived.dt_dem_s, 2200.0, 1e-6) << name;
    // Stokes drag 3 pi mu d equals LAMMPS's fix viscous gamma
    EXPECT_LT(relative(3.0 * std::numbers::pi * s.fluid->viscosity_Pa_s * 75e-6, 1.4842209727e-08), 1e-9)
        << name;
  }
}

// ---- command line ------------------------------------------------------------------------------

struct Argv {
  explicit Argv(std::vector<std::string> args) : storage(std::move(args)) {
    for (auto& a : storage) pointers.push_back(a.data());
    pointers.push_back(nullptr);
  }
  int argc() const { return static_cast<int>(storage.size()); }
  char** argv() { return pointers.data(); }
  std::vector<std::string> storage;
  std::vector<char*> pointers;
};

cgd::RunOptions parse(std::vector<std::string> args) {
  Argv a(std::move(args));
  return cgd::parse_run_command_line(a.argc(), a.argv(), "cgd-generate", "test");
}

TEST(CommandLine, ParsesSceneRepeatedSetOutputAndFlags) {
  const auto o = parse({"cgd-generate", "scene.toml", "--set", "particles.solids_fraction=0.2",
                        "--set=fluid.drag=wen-yu", "-o", "out/x", "--restart", "--quiet"});
  EXPECT_EQ(o.scene_path, "scene.toml");
  EXPECT_EQ(o.overrides, (std::vector<std::string>{"particles.solids_fraction=0.2", "fluid.drag=wen-yu"}));
  EXPECT_EQ(o.output_dir, "out/x");
  EXPECT_TRUE(o.restart);
  EXPECT_TRUE(o.quiet);
}

TEST(CommandLine, SetTakesOneValueSoTheSceneCanFollow) {
  const auto o = parse({"cgd-generate", "--set", "run.end_time=0.1", "scene.toml"});
  EXPECT_EQ(o.scene_path, "scene.toml");
  EXPECT_EQ(o.overrides, (std::vector<std::string>{"run.end_time=0.1"}));
  EXPECT_EQ(o.output_dir, "") << "the caller defaults the run directory";
  EXPECT_FALSE(o.restart);
}

TEST(CommandLine, HelpAndVersionExitWithZeroBadOptionsWithTwo) {
  const auto status_of = [](std::vector<std::string> args) {
    try {
      parse(std::move(args));
    } catch (const cgd::CommandLineExit& e) {
      return e.status();
    }
    return -1;
  };
  EXPECT_EQ(status_of({"cgd-generate", "--help"}), 0);
  EXPECT_EQ(status_of({"cgd-generate", "--version"}), 0);
  EXPECT_EQ(status_of({"cgd-generate"}), 2);                       // no scene
  EXPECT_EQ(status_of({"cgd-generate", "a.toml", "--bogus"}), 2);  // unknown option
  EXPECT_EQ(status_of({"cgd-generate", "a.toml", "b.toml"}), 2);   // two scenes
  EXPECT_EQ(status_of({"cgd-generate", "a.toml", "--set"}), 2);    // --set without a value
}

TEST(CommandLine, VersionPrintsToolNameAndVersion) {
  try {
    parse({"cgd-generate", "--version"});
    FAIL();
  } catch (const cgd::CommandLineExit& e) {
    EXPECT_NE(e.out_text().find(std::string("cgd-generate ") + cgd::code_version()), std::string::npos)
        << e.out_text();
  }
}

TEST(CommandLine, RunToolMapsErrorsToExitStatuses) {
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(cgd::run_tool([] { return 0; }), cgd::kExitOk);
  EXPECT_EQ(cgd::run_tool(
                []() -> int { throw cgd::InputError("scene.toml: particles.diameter = -1: must be > 0"); }),
            cgd::kExitBadInput);
  EXPECT_EQ(cgd::run_tool([]() -> int { throw cgd::RunError("NaN in particle velocity at step 12"); }),
            cgd::kExitRunFailed);
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("error: scene.toml: particles.diameter = -1: must be > 0\n"), std::string::npos) << err;
  EXPECT_NE(err.find("run failed: NaN in particle velocity at step 12\n"), std::string::npos) << err;
}

TEST(CommandLine, RunToolReportsABadSceneFromInsideTheBody) {
  ::testing::internal::CaptureStderr();
  const int status = cgd::run_tool([] {
    Argv a({"cgd-generate", "/nonexistent/scene.toml"});
    const auto options = cgd::parse_run_command_line(a.argc(), a.argv(), "cgd-generate", "test");
    cgd::load_scene(options.scene_path, options.overrides);
    return 0;
  });
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(status, cgd::kExitBadInput);
  EXPECT_NE(err.find("error: /nonexistent/scene.toml"), std::string::npos) << err;
}

TEST(CommandLine, DefaultRunDirectoryIsStageAndSceneStem) {
  EXPECT_EQ(cgd::default_run_directory("generate", "data/scenes/dry_settling.toml"),
            "out/generate/dry_settling");
}

// Issue 10, item 5: what validates key by key but cannot be run is refused (the messages are checked in
// tests/e2e/bad_input.sh); what a user may mean is accepted with a warning that says what is odd.
TEST(SceneNonsense, RefusedOrWarned) {
  const auto refused = [](const std::vector<std::string>& overrides, const std::string& want) {
    try {
      load_scene_from_string(kWetScene, "w.toml", overrides);
      ADD_FAILURE() << "accepted: " << overrides.front();
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(want), std::string::npos) << e.what();
    }
  };
  refused({"particles.diameter=75"}, "Re_p");             // the diameter in the wrong unit
  refused({"run.end_time=1e-9"}, "shorter than one DEM step");
  refused({"fluid.coupling=\"two-way\"", "fluid.dx_over_dp=3.33", "fluid.courant=0.05", "contact.gamma_star=0.1"},
          "longer than the fluid step");
  // the paper's scene: nothing odd
  EXPECT_TRUE(load_scene_from_string(kWetScene, "w.toml").warnings.empty());
  // Stokes drag at Re_p ~ 40 (300 um particles): accepted, with a warning naming the law and Re_p
  const auto big = load_scene_from_string(kWetScene, "w.toml", {"particles.diameter=300e-6"});
  ASSERT_EQ(big.warnings.size(), 1u);
  EXPECT_NE(big.warnings[0].find("stokes"), std::string::npos);
  EXPECT_NE(cgd::describe_scene(big).find("warning: "), std::string::npos);
}

}  // namespace
