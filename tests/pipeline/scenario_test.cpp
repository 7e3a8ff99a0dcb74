#include "pipeline/scenario.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>

#include "core/error.hpp"

namespace driftlab::pipeline {
namespace {

namespace fs = std::filesystem;
const fs::path kSource = DRIFTLAB_SOURCE_DIR;

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
  const Scenario s = load_scenario(kSource / "scenarios/river_crossing.yaml");
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

TEST(Scenario, BasinExperimentsMatchThePaperTable) {
  // Kucic and Valcic (2020), Table 1: (gamma [deg], zeta_a [mm], lambda [mm]).
  const double table[7][3] = {{0, 0, 0},   {40, 5, 210},  {40, 7.5, 132}, {40, 11, 59},
                              {0, 5, 210}, {0, 7.5, 132}, {0, 11, 59}};
  for (int i = 0; i < 7; ++i) {
    const Scenario s =
        load_scenario(kSource / ("scenarios/basin_exp" + std::to_string(i + 1) + ".yaml"));
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
    EXPECT_NEAR(s.water.waves.airy.wavelength_m * 1000, table[i][2], 1e-9);
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
    const Scenario s = load_scenario(kSource / "scenarios" / (std::string(name) + ".yaml"));
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
