#include "pipeline/scenario.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <set>

#include "core/error.hpp"
#include "pipeline/scenario_checks.hpp"

namespace driftlab::pipeline {
namespace {

namespace fs = std::filesystem;
const fs::path kScenarioSourceDir = DRIFTLAB_SOURCE_DIR;

std::string error_of(const std::string& text, const std::vector<std::string>& sets = {}) {
  try {
    parse_scenario(text, "s.yaml", fs::temp_directory_path(), sets);
  } catch (const UserError& e) {
    return e.what();
  }
  return "";
}

TEST(Scenario, DefaultsAreValid) {
  const Scenario s;
  EXPECT_EQ(yaml::validate(s), "");
  EXPECT_NO_THROW(validate_scenario(s, "defaults"));
}

TEST(Scenario, LoadsTheDemoScenario) {
  const Scenario s = load_scenario(kScenarioSourceDir / "scenarios/river_crossing.yaml");
  EXPECT_EQ(s.name, "river_crossing");
  EXPECT_EQ(s.seed, 2013u);
  EXPECT_EQ(s.mission.type, sim::MissionType::kTransects);
  EXPECT_EQ(s.mission.crossings, 4);
  // 4 crossings of 13.5 m: the river paper's 54 m discharge measurement.
  EXPECT_DOUBLE_EQ(s.mission.crossings * s.mission.crossing_width_m, 54.0);
  EXPECT_DOUBLE_EQ(s.sensors.camera.baseline_m, 0.12);
  // The paper's frame-to-frame method and the keyframe variant.
  EXPECT_EQ(s.pipeline.vo, (std::vector<std::string>{"sparse", "sparse_kf"}));
  EXPECT_FALSE(s.pipeline.sparse.keyframes);
  EXPECT_TRUE(s.pipeline.sparse_kf.keyframes);
  EXPECT_DOUBLE_EQ(s.eval.section_length_m, 6.5);
}

TEST(Scenario, CameraPresetsAreThePapersCamerasAndLaterKeysOverrideThem) {
  // River paper Sec. 2.1: Bumblebee2, 1024x768, 0.12 m, 8.2 Hz; 3.8 mm lens on 4.65 um pixels.
  const Scenario river = load_scenario(kScenarioSourceDir / "scenarios/river_crossing.yaml");
  const sim::CameraOptions& c = river.sensors.camera;
  EXPECT_EQ(c.preset, sim::CameraPreset::kBumblebee2);
  EXPECT_EQ(c.width_px, 1024);
  EXPECT_EQ(c.height_px, 768);
  EXPECT_NEAR(c.fx_px, 3.8e-3 / 4.65e-6, 0.5);
  EXPECT_EQ(c.fy_px, c.fx_px);
  EXPECT_DOUBLE_EQ(c.cx_px, 511.5);
  EXPECT_DOUBLE_EQ(c.cy_px, 383.5);
  EXPECT_DOUBLE_EQ(c.baseline_m, 0.12);
  EXPECT_DOUBLE_EQ(c.rate_hz, 8.2);
  EXPECT_NEAR(2 * std::atan(512 / c.fx_px) * 180 / std::numbers::pi, 64.1, 0.1);
  EXPECT_EQ(load_scenario(kScenarioSourceDir / "scenarios/river_survey.yaml").sensors.camera.preset,
            sim::CameraPreset::kBumblebee2);
  // Basin paper Sec. 2.2: PlayStation Eye pair, 640x480 at 20 Hz; 75 deg diagonal field of view.
  const sim::CameraOptions b =
      load_scenario(kScenarioSourceDir / "scenarios/basin_exp1.yaml").sensors.camera;
  EXPECT_EQ(b.preset, sim::CameraPreset::kPs3Eye);
  EXPECT_EQ(b.width_px, 640);
  EXPECT_NEAR(2 * std::atan(400 / b.fx_px) * 180 / std::numbers::pi, 75.0, 0.1);
  EXPECT_DOUBLE_EQ(b.rate_hz, 20.0);
  // Its OV7720 has a rolling shutter (a VGA line of 784 pixel clocks at 12 MHz), and
  // the two free-running cameras meet within half a 30 fps period; the Bumblebee2's CCDs are
  // global and synchronised.
  EXPECT_EQ(b.shutter, sim::Shutter::kRolling);
  EXPECT_DOUBLE_EQ(b.line_delay_us, 784 / 12.0);
  EXPECT_DOUBLE_EQ(b.right_offset_spread_ms, 1000.0 / 60);
  EXPECT_EQ(c.shutter, sim::Shutter::kGlobal);
  EXPECT_EQ(c.right_offset_spread_ms, 0.0);
  // Keys after the preset override it; custom leaves the defaults.
  const Scenario o = parse_scenario(
      "sensors:\n  camera:\n    preset: bumblebee2\n    rate_hz: 15\n", "o", kScenarioSourceDir);
  EXPECT_EQ(o.sensors.camera.width_px, 1024);
  EXPECT_DOUBLE_EQ(o.sensors.camera.rate_hz, 15.0);
  const Scenario d =
      parse_scenario("sensors:\n  camera:\n    preset: custom\n", "d", kScenarioSourceDir);
  EXPECT_EQ(d.sensors.camera.width_px, sim::CameraOptions{}.width_px);
  EXPECT_EQ(d.sensors.camera.fx_px, sim::CameraOptions{}.fx_px);
}

TEST(Scenario, BasinExperimentsMatchThePaperTable) {
  // Kucic and Valcic (2020), Table 1: (gamma [deg], zeta_a [mm], lambda [mm] as printed, which
  // the scenarios read as centimetres: printed, experiments 4 and 7 would break).
  const double table[7][3] = {{0, 0, 0},   {40, 5, 210},  {40, 7.5, 132}, {40, 11, 59},
                              {0, 5, 210}, {0, 7.5, 132}, {0, 11, 59}};
  for (int i = 0; i < 7; ++i) {
    const Scenario s = load_scenario(kScenarioSourceDir /
                                     ("scenarios/basin_exp" + std::to_string(i + 1) + ".yaml"));
    SCOPED_TRACE(s.name);
    EXPECT_EQ(s.scene.type, scenes::SceneType::kWaveBasin);
    EXPECT_DOUBLE_EQ(s.sensors.camera.rate_hz, 20.0);
    EXPECT_DOUBLE_EQ(s.sensors.imu.rate_hz, 100.0);
    if (i == 0) {
      EXPECT_EQ(s.water.waves.model, sim::WaveModel::kCalm);
      continue;
    }
    EXPECT_EQ(s.water.waves.model, sim::WaveModel::kAiry);
    EXPECT_DOUBLE_EQ(-s.water.waves.airy.direction_deg, table[i][0]);
    EXPECT_DOUBLE_EQ(s.water.waves.airy.amplitude_m * 1000, table[i][1]);
    EXPECT_NEAR(s.water.waves.airy.wavelength_m * 100, table[i][2], 1e-9);
  }
}

TEST(Scenario, OverridesApplyInOrderAfterTheFile) {
  const Scenario s =
      parse_scenario("seed: 5\nsensors: {camera: {rate_hz: 10}}\n", "s.yaml",
                     fs::temp_directory_path(), {"seed=6", "seed=7", "sensors.camera.rate_hz=20"});
  EXPECT_EQ(s.seed, 7u);
  EXPECT_DOUBLE_EQ(s.sensors.camera.rate_hz, 20.0);
}

TEST(Scenario, CrossFieldRulesHoldAfterAllOverrides) {
  // Shrinking the image needs the principal point moved too: each --set alone
  // breaks the rule, both together satisfy it.
  const Scenario s = parse_scenario("name: x\n", "s.yaml", fs::temp_directory_path(),
                                    {"sensors.camera.width_px=160", "sensors.camera.cx_px=79.5"});
  EXPECT_EQ(s.sensors.camera.width_px, 160);
  EXPECT_NE(error_of("name: x\n", {"sensors.camera.width_px=160"})
                .find("sensors.camera.cx_px: expected a principal point inside [0, width_px)"),
            std::string::npos);
}

TEST(Scenario, ResolvedYamlRoundTripsByteForByte) {
  for (const char* name : {"river_crossing", "river_survey", "basin_exp4"}) {
    const Scenario s =
        load_scenario(kScenarioSourceDir / "scenarios" / (std::string(name) + ".yaml"));
    const std::string text = resolved_yaml(s);
    const Scenario back = parse_scenario(text, "resolved", fs::temp_directory_path());
    EXPECT_EQ(resolved_yaml(back), text) << name;
  }
}

TEST(Scenario, WaypointsFileIsReadRelativeToTheScenarioAndInlined) {
  const fs::path dir = fs::temp_directory_path() / ("driftlab_wp_" + std::to_string(::getpid()));
  fs::create_directories(dir / "sub");
  std::ofstream(dir / "sub" / "wp.csv") << "# a comment\nnorth_m,east_m\n0,0\n10.5, -2\n\n20,3\n";
  std::ofstream(dir / "s.yaml") << "mission:\n  type: waypoints\n  waypoints_ne_m: [[-1, -1]]\n"
                                   "  waypoints_file: sub/wp.csv\n";
  const Scenario s = load_scenario(dir / "s.yaml");
  ASSERT_EQ(s.mission.waypoints_ne_m.size(), 4u);
  EXPECT_EQ(s.mission.waypoints_ne_m[0], (std::array<double, 2>{-1, -1}));
  EXPECT_EQ(s.mission.waypoints_ne_m[2], (std::array<double, 2>{10.5, -2}));
  EXPECT_EQ(s.mission.waypoints_ne_m[3], (std::array<double, 2>{20, 3}));
  EXPECT_TRUE(s.mission.waypoints_file.empty());  // inlined: the resolved scenario stands alone
  std::ofstream(dir / "sub" / "wp.csv") << "0,0,1\n";
  try {
    load_scenario(dir / "s.yaml");
    FAIL();
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("wp.csv:1: got 3 columns, expected 2"), std::string::npos)
        << e.what();
  }
  fs::remove_all(dir);
}

TEST(Scenario, CrossSectionRules) {
  EXPECT_NE(error_of("mission: {type: waypoints}\n").find("at least 2"), std::string::npos);
  EXPECT_NE(error_of("mission: {type: tow, speed_mps: 0}\n").find("a speed > 0"),
            std::string::npos);
  EXPECT_EQ(error_of("mission: {type: spin, speed_mps: 0}\n"), "");
  EXPECT_NE(error_of("water: {waves: {model: components}}\n").find("at least one component"),
            std::string::npos);
  EXPECT_NE(error_of("sensors: {camera: {rate_hz: 100, exposure_ms: 20}}\n")
                .find("an exposure no longer than the frame period"),
            std::string::npos);
}

TEST(Scenario, ABadValueIsReportedOnceNotAgainByTheRulesOnIt) {
  const std::string e = error_of("sensors:\n  camera:\n    baseline_m: -0.12\n");
  EXPECT_NE(e.find("s.yaml:3:17: sensors.camera.baseline_m: got -0.12"), std::string::npos) << e;
  EXPECT_EQ(e.find("calibration_error"), std::string::npos) << e;
  EXPECT_NE(error_of("sensors: {camera: {calibration_error: {baseline_error_m: -0.2}}}\n")
                .find("expected a true baseline (baseline_m + baseline_error_m) > 0"),
            std::string::npos);
}

TEST(Scenario, CrossSectionErrorsSayWhereInTheFile) {
  // At the key the message is about, where the file gives it.
  EXPECT_NE(error_of("name: x\npipeline:\n  vo: []\n  fusion: [ca_smoother]\n")
                .find("s.yaml:4:11: pipeline.fusion: got filters but no VO to feed them"),
            std::string::npos)
      << error_of("name: x\npipeline:\n  vo: []\n  fusion: [ca_smoother]\n");
  // A key the file does not give (a default, or a --set): no line, not a parent's.
  EXPECT_NE(error_of("name: x\nmission:\n  type: waypoints\n")
                .find("s.yaml: invalid scenario:\nmission.waypoints_ne_m: got 0 waypoints"),
            std::string::npos);
  EXPECT_NE(error_of("mission: {type: waypoints, waypoints_ne_m: [[0, 0], [5, 30]]}\n")
                .find("s.yaml:1:53: mission.waypoints_ne_m[1]: got (5, 30), expected a point on"),
            std::string::npos)
      << error_of("mission: {type: waypoints, waypoints_ne_m: [[0, 0], [5, 30]]}\n");
  // Nothing of the path in the file (a --set): the message as it was, under the file's name.
  const std::string set = error_of("name: x\n", {"pipeline.vo=[]"});
  EXPECT_NE(set.find("s.yaml: invalid scenario:\npipeline.fusion: got filters"), std::string::npos)
      << set;
}

// Miche's limit H / lambda <= 0.142 tanh(k d), computed here on its own: in 100 m of water a
// 10 m wave is deep-water (tanh(k d) = 1 to 1e-27), so 1.40 m stands and 1.45 m breaks; in
// 0.5 m of water tanh(k d) = tanh(0.1 pi) = 0.3042 lowers the limit to a 0.432 m wave. Such a
// wave still runs (linear theory computes it): a warning, not an error.
TEST(Scenario, WavesSteeperThanBreakingAreFlaggedWithTheMicheLimit) {
  const auto warnings = [](double depth, double height, double length) {
    const std::string text = fmt::format(
        "water: {{waves: {{model: airy, water_depth_m: {}, airy: {{amplitude_m: {}, "
        "wavelength_m: {}}}}}}}\n",
        depth, height / 2, length);
    const auto w = implausible_values(parse_scenario(text, "s.yaml", fs::temp_directory_path()));
    return w.empty() ? std::string() : w.front();
  };
  EXPECT_EQ(warnings(100, 1.40, 10), "");
  EXPECT_NE(warnings(100, 1.45, 10).find("steeper than the 0.142 at which waves break in 100 m"),
            std::string::npos);
  const double shallow_limit_m = 0.142 * std::tanh(2 * std::numbers::pi / 10 * 0.5) * 10;
  EXPECT_NEAR(shallow_limit_m, 0.432, 5e-4);
  EXPECT_EQ(warnings(0.5, shallow_limit_m * 0.99, 10), "");
  EXPECT_NE(warnings(0.5, shallow_limit_m * 1.01, 10).find("(Miche)"), std::string::npos);
  // The basin paper's experiment 4 as its Table 1 prints it (11 mm on a 59 mm wavelength) is
  // such a wave; the shipped scenarios read the wavelengths as centimetres and are not.
  Scenario exp4 = load_scenario(kScenarioSourceDir / "scenarios/basin_exp4.yaml");
  EXPECT_TRUE(implausible_values(exp4).empty());
  exp4.water.waves.airy.wavelength_m = 0.059;
  EXPECT_EQ(implausible_values(exp4).size(), 1u);
  for (int i = 1; i <= 7; ++i)
    EXPECT_TRUE(
        implausible_values(load_scenario(kScenarioSourceDir /
                                         ("scenarios/basin_exp" + std::to_string(i) + ".yaml")))
            .empty())
        << i;
}

// A box hull floats at draft m / (rho L B): 55 kg in 1.95 x 0.73 m draws 38.6 mm, so with
// the centre of gravity 0.15 m above the keel a camera mounted 0.11 m below it is 1.4 mm
// above the water and one 0.112 m below it is 0.6 mm under.
TEST(Scenario, TheCameraMustBeAboveTheWaterLineOfAFloatingHull) {
  const auto mount = [](double z) {
    return fmt::format("sensors: {{camera: {{mount: {{position_frd_m: [0.5, 0, {}]}}}}}}\n", z);
  };
  const Scenario defaults;
  ASSERT_EQ(defaults.vessel.mass_kg, 55.0);
  ASSERT_EQ(defaults.vessel.hull.kg_m, 0.15);
  EXPECT_EQ(error_of(mount(0.11)), "");
  EXPECT_NE(error_of(mount(0.112)).find("the camera sits 0.000637 m below the still water"),
            std::string::npos)
      << error_of(mount(0.112));
  EXPECT_NE(error_of("vessel: {mass_kg: 499}\n").find("(it sinks)"), std::string::npos);
  EXPECT_EQ(error_of("vessel: {mass_kg: 498}\n").find("(it sinks)"), std::string::npos);
}

TEST(Scenario, MissionsMustStartAndStayOnTheWater) {
  EXPECT_EQ(error_of("vessel: {start_ne_m: [0, 9.9]}\n"), "");
  EXPECT_NE(error_of("vessel: {start_ne_m: [0, 10]}\n").find("expected a point on the river"),
            std::string::npos);
  EXPECT_EQ(error_of("mission: {type: transects, crossing_width_m: 19.9}\n"), "");
  EXPECT_NE(error_of("mission: {type: transects, crossing_width_m: 20}\n")
                .find("crossings shorter than the river is wide"),
            std::string::npos);
  const std::string basin =
      "scene: {type: wave_basin}\nvessel: {preset: basin_model, start_ne_m: [0.2, 0]}\n";
  EXPECT_EQ(error_of(basin + "mission: {type: tow, survey_length_m: 2.7}\n"), "");
  EXPECT_NE(error_of(basin + "mission: {type: tow, survey_length_m: 2.8}\n")
                .find("the track ends at (3, 0)"),
            std::string::npos);
}

TEST(Scenario, ReferenceListsEveryKeyOnce) {
  const auto rows = yaml::schema_of(Scenario{});
  std::set<std::string> keys;
  for (const auto& r : rows) EXPECT_TRUE(keys.insert(r.key_path).second) << r.key_path;
  EXPECT_TRUE(keys.count("sensors.camera.baseline_m"));
  EXPECT_TRUE(keys.count("water.waves.airy.wavelength_m"));
  EXPECT_TRUE(keys.count("water.waves.components[].amplitude_m"));
  for (const auto& r : rows) EXPECT_FALSE(r.doc.empty()) << r.key_path << " has no doc";
}

}  // namespace
}  // namespace driftlab::pipeline
