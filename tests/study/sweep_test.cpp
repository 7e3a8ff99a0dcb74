// Sweeps: the sweep file, its expansion into jobs (grid, zip, Latin hypercube),
// seeds and parameter hashes, bad sweep files, job states and Slurm shards, the
// merge's run metrics and regressions. (Through the real `driftlab` binary:
// sweep_cli_test.cpp.)
#include "study/sweep.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "core/yaml_io.hpp"
#include "gate/gate.hpp"
#include "pipeline/scenario.hpp"
#include "study/run_regressions.hpp"
#include "study/sweep_merge.hpp"
#include "study/sweep_runner.hpp"
#include "tests/study/sweep_fixtures.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::study {
namespace {

using fixtures::kCli;
using fixtures::kSource;
using fixtures::kSweeps;
using fixtures::temp_dir;
using test::slurp;

namespace fs = std::filesystem;

// A sweep from text, in the folder of the test sweeps (so that `base: tiny_base.yaml` resolves).
Sweep sweep_from(const std::string& text) {
  return parse_sweep(text, (kSweeps / "inline.yaml").string(), kSweeps);
}

std::string param(const SweepJob& j, const std::string& name) {
  for (const auto& [n, v] : j.params)
    if (n == name) return v;
  return "(none)";
}

double number(const std::string& s) {
  double v = 0;
  EXPECT_TRUE(yaml::parse_double(s, &v)) << s;
  return v;
}

// ---------------------------------------------------------------------------
// Expansion

TEST(SweepPlan, GridIsRowMajorWithReplicatesInnermost) {
  const SweepPlan plan = plan_sweep(sweep_from(R"(
base: tiny_base.yaml
replicates: 2
axes:
  - key: mission.yaw_weave.amplitude_deg
    name: amp
    values: [0, 10]
  - key: mission.yaw_weave.period_s
    range: {start: 5, stop: 8, step: 1}
)"));
  ASSERT_EQ(plan.points, 6u);
  ASSERT_EQ(plan.jobs.size(), 12u);
  const std::vector<std::pair<std::string, std::string>> expected = {
      {"0", "5"}, {"0", "6"}, {"0", "7"}, {"10", "5"}, {"10", "6"}, {"10", "7"}};
  for (std::size_t k = 0; k < plan.jobs.size(); ++k) {
    const SweepJob& j = plan.jobs[k];
    EXPECT_EQ(j.index, k);
    EXPECT_EQ(j.point, k / 2);
    EXPECT_EQ(j.replicate, k % 2);
    EXPECT_EQ(j.id, (k / 2 < 10 ? "p000" : "p00") + std::to_string(k / 2) + "-r0" +
                        std::to_string(k % 2));
    EXPECT_EQ(param(j, "amp"), expected[k / 2].first);
    EXPECT_EQ(param(j, "mission.yaw_weave.period_s"), expected[k / 2].second);
    ASSERT_EQ(j.overrides.size(), 3u);
    EXPECT_EQ(j.overrides[0], "mission.yaw_weave.amplitude_deg=" + expected[k / 2].first);
    EXPECT_EQ(j.overrides[1], "mission.yaw_weave.period_s=" + expected[k / 2].second);
    EXPECT_EQ(j.overrides[2], "seed=" + std::to_string(j.seed));
  }
}

TEST(SweepPlan, ZipPairsTheKthValues) {
  const SweepPlan plan = plan_sweep(sweep_from(R"(
base: tiny_base.yaml
design: zip
set:
  water.waves.model: airy
  water.waves.water_depth_m: 0.6
axes:
  - key: water.waves.airy.amplitude_m
    values: [0.005, 0.0075, 0.011]
  - key: water.waves.airy.wavelength_m
    values: [0.21, 0.132, 0.059]
)"));
  ASSERT_EQ(plan.jobs.size(), 3u);
  EXPECT_EQ(param(plan.jobs[1], "water.waves.airy.amplitude_m"), "0.0075");
  EXPECT_EQ(param(plan.jobs[1], "water.waves.airy.wavelength_m"), "0.132");
  EXPECT_EQ(param(plan.jobs[2], "water.waves.airy.wavelength_m"), "0.059");
  // The fixed overrides are part of the base scenario of every job.
  const pipeline::Scenario sc =
      pipeline::parse_scenario(plan.scenario_yaml, "scenario.yaml", kSweeps);
  EXPECT_EQ(sc.water.waves.model, sim::WaveModel::kAiry);
  EXPECT_EQ(sc.water.waves.water_depth_m, 0.6);
}

// A value that the base scenario rejects alone but a point of the design makes valid: a rolling
// shutter needs a line delay, so a zip of shutter and line delay plans, and so do fixed
// overrides that are valid together; a grid of the same axes holds the point (rolling, 0),
// which is refused by name.
TEST(SweepPlan, ValuesValidOnlyTogetherAreCheckedAsPoints) {
  const auto shutter_sweep = [](const std::string& design) {
    return sweep_from("base: tiny_base.yaml\ndesign: " + design + R"(
axes:
  - key: sensors.camera.shutter
    values: [rolling, global]
  - key: sensors.camera.line_delay_us
    values: [50, 0]
)");
  };
  const SweepPlan zip = plan_sweep(shutter_sweep("zip"));
  ASSERT_EQ(zip.jobs.size(), 2u);
  EXPECT_EQ(param(zip.jobs[0], "sensors.camera.shutter"), "rolling");
  const SweepPlan fixed = plan_sweep(sweep_from(R"(
base: tiny_base.yaml
set:
  sensors.camera.shutter: rolling
  sensors.camera.line_delay_us: 50
axes:
  - key: sensors.camera.right_offset_ms
    values: [0, 5]
)"));
  EXPECT_EQ(fixed.jobs.size(), 2u);
  try {
    plan_sweep(shutter_sweep("grid"));
    FAIL() << "the grid's point (rolling, 0) was accepted";
  } catch (const UserError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("(sensors.camera.shutter=rolling, sensors.camera.line_delay_us=0): the "
                        "combination is rejected"),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("line_delay_us > 0 with shutter: rolling"), std::string::npos) << what;
  }
}

// `sweep plan --set` (the gate's GATE_SET): the command line's value replaces the file's fixed
// one or joins them, reaches every job's scenario, and may not fix a swept key or the seed.
TEST(SweepPlan, CommandLineSetsReplaceOrJoinTheFixedOverrides) {
  Sweep s = sweep_from(R"(
base: tiny_base.yaml
set:
  water.waves.model: airy
  water.waves.water_depth_m: 0.6
axes:
  - key: water.waves.airy.amplitude_m
    values: [0.005, 0.0075]
)");
  apply_sets(&s, {"water.waves.water_depth_m=0.9", "water.waves.airy.wavelength_m=0.3"});
  const SweepPlan plan = plan_sweep(s);
  ASSERT_EQ(plan.jobs.size(), 2u);
  const pipeline::Scenario sc =
      pipeline::parse_scenario(plan.scenario_yaml, "scenario.yaml", kSweeps);
  EXPECT_EQ(sc.water.waves.model, sim::WaveModel::kAiry);
  EXPECT_EQ(sc.water.waves.water_depth_m, 0.9);
  EXPECT_EQ(sc.water.waves.airy.wavelength_m, 0.3);
  EXPECT_EQ(plan.info().set.at("water.waves.water_depth_m"), 0.9);

  const auto error_of = test::user_error_of;
  const auto has = [](const std::string& text, const std::string& part) {
    return text.find(part) != std::string::npos;
  };
  Sweep swept = s;
  EXPECT_PRED2(has, error_of([&] { apply_sets(&swept, {"water.waves.airy.amplitude_m=0.1"}); }),
               "--set water.waves.airy.amplitude_m=0.1: set.water.waves.airy."
               "amplitude_m: also swept by axes[0]");
  Sweep seeded = s;
  EXPECT_PRED2(has, error_of([&] { apply_sets(&seeded, {"seed=3"}); }),
               "--set seed=3: set.seed: got a fixed seed");
  Sweep bad_key = s;
  apply_sets(&bad_key, {"water.waves.no_such_key=1"});
  EXPECT_PRED2(has, error_of([&] { plan_sweep(bad_key); }),
               "--set water.waves.no_such_key=1: set.water.waves.no_such_key");
  EXPECT_PRED2(has, error_of([&] { apply_sets(&bad_key, {"=1"}); }), "expected KEY.PATH=VALUE");
}

TEST(SweepPlan, RangeLinspaceAndLogspaceValues) {
  const Sweep s = sweep_from(R"(
base: tiny_base.yaml
axes:
  - key: mission.yaw_weave.period_s
    range: {start: 0.1, stop: 0.4, step: 0.1}
  - key: mission.yaw_weave.amplitude_deg
    linspace: {start: 0, stop: 1, num: 5}
  - key: water.waves.airy.amplitude_m
    logspace: {start: 0.001, stop: 0.1, num: 3}
  - key: scene.river_reach.buildings
    range: {start: 6, stop: 0, step: -2}
)");
  // Python's range: stop excluded; generated values rounded to 12 significant digits.
  EXPECT_EQ(s.axes[0].levels, (std::vector<std::string>{"0.1", "0.2", "0.3"}));
  EXPECT_EQ(s.axes[1].levels, (std::vector<std::string>{"0", "0.25", "0.5", "0.75", "1"}));
  // logspace: start and stop are the values themselves (as numpy.geomspace).
  EXPECT_EQ(s.axes[2].levels, (std::vector<std::string>{"0.001", "0.01", "0.1"}));
  EXPECT_EQ(s.axes[3].levels, (std::vector<std::string>{"6", "4", "2"}));
  for (const auto& a : s.axes) EXPECT_TRUE(a.numeric);
}

TEST(SweepPlan, LatinHypercubeUsesEveryStratumOnce) {
  const std::string text = R"(
base: tiny_base.yaml
design: random
samples: 8
seed: 3
axes:
  - key: mission.yaw_weave.amplitude_deg
    linspace: {start: 0, stop: 40}
  - key: water.waves.airy.amplitude_m
    logspace: {start: 0.001, stop: 0.256}
  - key: scene.river_reach.buildings
    values: [1, 2, 3, 4]
)";
  const SweepPlan plan = plan_sweep(sweep_from(text));
  ASSERT_EQ(plan.jobs.size(), 8u);
  std::set<int> lin_strata, log_strata;
  std::map<std::string, int> level_count;
  for (const auto& j : plan.jobs) {
    const double a = number(param(j, "mission.yaw_weave.amplitude_deg"));
    const double w = number(param(j, "water.waves.airy.amplitude_m"));
    ASSERT_GE(a, 0);
    ASSERT_LE(a, 40);
    ASSERT_GE(w, 0.001);
    ASSERT_LE(w, 0.256);
    lin_strata.insert(static_cast<int>(std::floor(a / 5.0)));  // 40 / 8 = 5 per stratum
    // log2(0.256 / 0.001) = 8: one octave per stratum.
    log_strata.insert(static_cast<int>(std::floor(std::log2(w / 0.001) + 1e-9)));
    ++level_count[param(j, "scene.river_reach.buildings")];
  }
  EXPECT_EQ(lin_strata, (std::set<int>{0, 1, 2, 3, 4, 5, 6, 7}));
  EXPECT_EQ(log_strata, (std::set<int>{0, 1, 2, 3, 4, 5, 6, 7}));
  // 8 strata over 4 levels: each level twice.
  EXPECT_EQ(level_count, (std::map<std::string, int>{{"1", 2}, {"2", 2}, {"3", 2}, {"4", 2}}));

  // Seeded: the same file gives the same points, another seed others.
  const SweepPlan again = plan_sweep(sweep_from(text));
  EXPECT_EQ(again.manifest_jsonl(), plan.manifest_jsonl());
  std::string other = text;
  other.replace(other.find("seed: 3"), 7, "seed: 4");
  EXPECT_NE(plan_sweep(sweep_from(other)).manifest_jsonl(), plan.manifest_jsonl());
}

// ---------------------------------------------------------------------------
// Seeds and hashes

TEST(SweepPlan, ReplicateSeedsAreDistinctCommonToPointsAndDerivedFromTheSweepSeed) {
  const SweepPlan plan = plan_sweep(sweep_from(R"(
base: tiny_base.yaml
replicates: 3
seed: 42
axes:
  - key: mission.yaw_weave.amplitude_deg
    values: [0, 10]
)"));
  ASSERT_EQ(plan.jobs.size(), 6u);
  std::set<std::uint64_t> seeds;
  for (const auto& j : plan.jobs) {
    // The documented derivation: the low 53 bits of derive_seed(seed, "sweep.replicate.<r>").
    const std::uint64_t expected =
        derive_seed(42, "sweep.replicate." + std::to_string(j.replicate)) & ((1ULL << 53) - 1);
    EXPECT_EQ(j.seed, expected) << j.id;
    EXPECT_LT(j.seed, 1ULL << 53);
    seeds.insert(j.seed);
  }
  EXPECT_EQ(seeds.size(), 3u);  // distinct per replicate, the same at both points
  EXPECT_EQ(plan.jobs[0].seed, plan.jobs[3].seed);

  // Without a seed key, the sweep seed is the base scenario's (tiny_base.yaml: seed 7).
  const SweepPlan defaulted = plan_sweep(sweep_from(R"(
base: tiny_base.yaml
axes:
  - key: mission.yaw_weave.amplitude_deg
    values: [0]
)"));
  EXPECT_EQ(defaulted.seed, 7u);
  EXPECT_EQ(defaulted.jobs[0].seed, derive_seed(7, "sweep.replicate.0") & ((1ULL << 53) - 1));
}

TEST(SweepPlan, HashIsThatOfTheResolvedScenarioAndStable) {
  const std::string text = R"(
base: tiny_base.yaml
replicates: 2
axes:
  - key: mission.yaw_weave.amplitude_deg
    values: [0, 10]
)";
  const SweepPlan a = plan_sweep(sweep_from(text));
  const SweepPlan b = plan_sweep(sweep_from(text));
  std::set<std::string> hashes;
  for (std::size_t k = 0; k < a.jobs.size(); ++k) {
    EXPECT_EQ(a.jobs[k].hash, b.jobs[k].hash);
    EXPECT_EQ(a.jobs[k].hash.size(), 16u);
    hashes.insert(a.jobs[k].hash);
    // What the hash covers: every parameter of the job's resolved scenario.
    const pipeline::Scenario sc =
        pipeline::parse_scenario(a.scenario_yaml, "x", kSweeps, a.jobs[k].overrides);
    EXPECT_EQ(a.jobs[k].hash, fnv1a64_hex(yaml::to_yaml(sc, false)));
  }
  EXPECT_EQ(hashes.size(), 4u);  // parameters or seed differ in every pair of jobs
  // A change to the base (here a fixed override) changes every hash.
  std::string with_set = text;
  with_set += "set:\n  pipeline.max_frames: 9\n";
  const SweepPlan c = plan_sweep(sweep_from(with_set));
  for (std::size_t k = 0; k < a.jobs.size(); ++k) EXPECT_NE(c.jobs[k].hash, a.jobs[k].hash);
}

// ---------------------------------------------------------------------------
// Bad sweep files: each states, in "# expect:" lines, what its message must contain.

std::vector<fs::path> bad_sweeps() {
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(kSource / "tests/data/bad_sweeps"))
    if (e.path().extension() == ".yaml") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files;
}

TEST(BadSweeps, CoverTheIssuesCases) {
  std::set<std::string> names;
  for (const auto& f : bad_sweeps()) names.insert(f.stem().string());
  for (const char* n : {"unknown_key_path", "empty_axis", "replicates_zero", "samples_with_grid",
                        "random_without_samples", "zip_lengths_differ", "two_value_specs"})
    EXPECT_TRUE(names.count(n)) << n;
}

class BadSweep : public ::testing::TestWithParam<fs::path> {};

TEST_P(BadSweep, FailsWithItsOwnClearMessage) {
  const fs::path file = GetParam();
  const auto expected = test::expected_messages(file);
  ASSERT_FALSE(expected.empty()) << file << " has no '# expect:' line";
  try {
    plan_sweep(load_sweep(file));
    FAIL() << file << " was accepted";
  } catch (const UserError& e) {
    const std::string what = e.what();
    for (const auto& x : expected) EXPECT_NE(what.find(x), std::string::npos) << what;
  }
}

INSTANTIATE_TEST_SUITE_P(All, BadSweep, ::testing::ValuesIn(bad_sweeps()),
                         [](const ::testing::TestParamInfo<fs::path>& info) {
                           return info.param.stem().string();
                         });

TEST(BadSweeps, EveryProblemIsReportedAtOnce) {
  try {
    sweep_from(R"(
base: tiny_base.yaml
replicates: 0
axes:
  - key: a.b
    values: []
)");
    FAIL();
  } catch (const UserError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("inline.yaml:3:13: replicates: got '0', expected an integer >= 1"),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("inline.yaml:6:13: axes[0].values: got an empty list, expected at least "
                        "one value"),
              std::string::npos)
        << what;
  }
}

// ---------------------------------------------------------------------------
// The sweep folder: manifest, states, shards, Slurm

TEST(SweepFolder, ManifestReadsBackAsPlanned) {
  const fs::path dir = temp_dir("manifest");
  const SweepPlan plan = plan_sweep(load_sweep(kSweeps / "tiny_grid.yaml"));
  const auto w = write_plan(plan, dir, false);
  EXPECT_FALSE(w.unchanged);
  const SweepManifest m = read_manifest(dir / "manifest.jsonl");
  ASSERT_EQ(m.jobs.size(), plan.jobs.size());
  for (std::size_t k = 0; k < m.jobs.size(); ++k) {
    EXPECT_EQ(m.jobs[k].id, plan.jobs[k].id);
    EXPECT_EQ(m.jobs[k].seed, plan.jobs[k].seed);
    EXPECT_EQ(m.jobs[k].overrides, plan.jobs[k].overrides);
    EXPECT_EQ(m.jobs[k].params, plan.jobs[k].params);
    EXPECT_EQ(m.jobs[k].hash, plan.jobs[k].hash);
  }
  ASSERT_EQ(m.axes.size(), 1u);
  EXPECT_EQ(m.axes[0].name, "yaw_amp_deg");
  EXPECT_EQ(slurp(dir / "scenario.yaml"), plan.scenario_yaml);
  // One job per line, as JSON.
  const std::string first =
      slurp(dir / "manifest.jsonl").substr(0, slurp(dir / "manifest.jsonl").find('\n'));
  const auto j = nlohmann::json::parse(first);
  EXPECT_EQ(j["id"], "p0000-r00");
  EXPECT_EQ(j["params"]["yaw_amp_deg"], 0);
  // Planning again: the same plan is left alone; a different one needs --force.
  EXPECT_TRUE(write_plan(plan, dir, false).unchanged);
  SweepPlan other = plan;
  other.jobs.pop_back();
  EXPECT_THROW(write_plan(other, dir, false), UserError);
  EXPECT_TRUE(write_plan(other, dir, true).replaced);
  EXPECT_EQ(read_manifest(dir).jobs.size(), plan.jobs.size() - 1);
  fs::remove_all(dir);
}

TEST(SweepFolder, JobStatesAndTheResubmissionLine) {
  const fs::path dir = temp_dir("states");
  const SweepPlan plan = plan_sweep(load_sweep(kSweeps / "tiny_grid.yaml"));
  write_plan(plan, dir, false);
  const SweepManifest m = read_manifest(dir);
  // p0000-r00 done, p0000-r01 stale (another hash), p0001-r00 failed, p0001-r01 missing.
  fs::create_directories(m.run_dir("p0000-r00"));
  std::ofstream(m.marker("p0000-r00")) << nlohmann::json{{"hash", m.jobs[0].hash}}.dump();
  fs::create_directories(m.run_dir("p0000-r01"));
  std::ofstream(m.marker("p0000-r01")) << nlohmann::json{{"hash", "0000000000000000"}}.dump();
  fs::create_directories(dir / "failed");
  std::ofstream(m.failed_record("p0001-r00"))
      << nlohmann::json{{"status", "exit code 1"}, {"error", "boom\nmore"}}.dump();
  const SweepStatus st = sweep_status(m);
  ASSERT_EQ(st.jobs.size(), 4u);
  EXPECT_EQ(st.jobs[0].state, JobState::kDone);
  EXPECT_EQ(st.jobs[1].state, JobState::kStale);
  EXPECT_EQ(st.jobs[2].state, JobState::kFailed);
  EXPECT_EQ(st.jobs[2].detail, "exit code 1: boom");
  EXPECT_EQ(st.jobs[3].state, JobState::kMissing);
  EXPECT_EQ(st.brief(), "4 jobs: 1 done, 1 failed, 1 stale, 1 missing");
  EXPECT_FALSE(st.complete());

  // Shards of 3: job k in shard k % 3; jobs 1, 2 and 3 are unfinished: shards 1, 2, 0.
  SlurmOptions so;
  so.executable = kCli;
  so.shards = 3;
  so.max_parallel = 2;
  const SlurmScript script = write_slurm_script(m, so);
  EXPECT_EQ(resubmit_command(m, st, script),
            "sbatch --array=0-2%2 '" + (dir / "slurm/sweep.sbatch").string() + "'");
  const std::string text = slurp(script.script);
  EXPECT_NE(text.find("#SBATCH --array=0-2%2\n"), std::string::npos) << text;
  EXPECT_NE(text.find("--shard \"${SLURM_ARRAY_TASK_ID}/3\""), std::string::npos) << text;
  EXPECT_NE(text.find("--manifest '" + (dir / "manifest.jsonl").string() + "'"), std::string::npos)
      << text;
  ASSERT_TRUE(read_slurm_script(m));
  EXPECT_EQ(read_slurm_script(m)->shards, 3u);
  // With only p0001-r01 (index 3) unfinished, only shard 0 goes again.
  SweepStatus one = st;
  for (auto& j : one.jobs) j.state = j.index == 3 ? JobState::kMissing : JobState::kDone;
  EXPECT_EQ(resubmit_command(m, one, script),
            "sbatch --array=0%2 '" + (dir / "slurm/sweep.sbatch").string() + "'");
  for (auto& j : one.jobs) j.state = JobState::kDone;
  EXPECT_EQ(resubmit_command(m, one, script), "");
  fs::remove_all(dir);
}

TEST(SweepFolder, ShardsPartitionTheJobs) {
  EXPECT_EQ(parse_shard("0/1").count, 1u);
  EXPECT_EQ(parse_shard("3/4").index, 3u);
  for (const char* bad : {"4/4", "1", "-1/3", "a/b", "1/0", "1/2/3"})
    EXPECT_THROW(parse_shard(bad), UserError) << bad;
  std::vector<SweepJob> jobs(10);
  for (std::size_t k = 0; k < jobs.size(); ++k) jobs[k].index = k;
  std::vector<int> owners(jobs.size(), 0);
  for (std::size_t s = 0; s < 4; ++s)
    for (const auto& j : jobs) owners[j.index] += in_shard(j, {s, 4});
  for (int o : owners) EXPECT_EQ(o, 1);
  EXPECT_EQ(array_ranges({0, 1, 2, 5, 7, 8}), "0-2,5,7-8");
  EXPECT_EQ(array_ranges({3}), "3");
  EXPECT_EQ(array_ranges({}), "");
}

TEST(SweepFiles, ShippedSweepsAndTheCiBaselineAreValid) {
  std::vector<fs::path> files = {kSource / "examples/ci/gate_sweep.yaml"};
  for (const auto& e : fs::directory_iterator(kSource / "scenarios/sweeps"))
    if (e.path().extension() == ".yaml") files.push_back(e.path());
  EXPECT_GE(files.size(), 4u);  // yaw_variability, feature_depth, wave_amplitude, the CI one
  for (const auto& f : files) {
    SCOPED_TRACE(f.string());
    const SweepPlan plan = plan_sweep(load_sweep(f));
    EXPECT_GE(plan.jobs.size(), 4u);
  }
  const gate::Baseline b = gate::load_baseline(kSource / "examples/ci/baseline.json");
  EXPECT_GE(b.metrics.size(), 5u);
  for (const auto& m : b.metrics) EXPECT_TRUE(m.baseline.has_value()) << m.key;
}

TEST(SweepMerge, RunMetricsIncludeTheBasinTableAndFilterStatisticsAndMissingIsMissing) {
  const auto metric = [](const std::string& name) {
    for (const auto& rm : run_metrics())
      if (rm.name == name) return rm;
    ADD_FAILURE() << name << " is not a run metric";
    return run_metrics().front();
  };
  nlohmann::json run;  // a 2.5 m basin tow: no 6.5 m section, a basin table
  // The value in the run's record, read as the merge reads metrics.json.
  const auto value = [&](const std::string& algo, const std::string& name) {
    return run_metric_value(record::run_record_from_json(run, "metrics.json"), algo, metric(name));
  };
  run["algorithms"]["pnp"]["sections"] = {{"count", 0}, {"p_m_per_m", {{"mean", 0.0}}}};
  run["algorithms"]["pnp"]["basin"]["north_m"]["rmse"] = 0.062;
  run["algorithms"]["pnp"]["ape"]["trans_m"]["rmse"] = 0.01;
  EXPECT_TRUE(std::isnan(value("pnp", "p_m_per_m_mean")));
  EXPECT_EQ(value("pnp", "basin_north_rmse_m"), 0.062);
  EXPECT_EQ(value("pnp", "ape_trans_rmse_m"), 0.01);
  EXPECT_TRUE(std::isnan(value("pnp", "basin_east_rmse_m")));
  run["algorithms"]["pnp"]["sections"]["count"] = 3;
  EXPECT_EQ(value("pnp", "p_m_per_m_mean"), 0.0);
  // The filter statistics: a filter's ratio to its raw VO and its guards; missing for a VO.
  run["algorithms"]["pnp_ned_kf"]["vs_raw_vo"]["ratio"] = 1.19;
  run["algorithms"]["pnp_ned_kf"]["filter"]["nonfinite_guards"] = 0;
  run["algorithms"]["pnp"]["tracking"]["lost_fraction"] = 0.25;
  EXPECT_EQ(value("pnp_ned_kf", "filter_vs_raw_ratio"), 1.19);
  EXPECT_EQ(value("pnp_ned_kf", "filter_nonfinite_guards"), 0.0);
  EXPECT_TRUE(std::isnan(value("pnp", "filter_vs_raw_ratio")));
  EXPECT_EQ(value("pnp", "lost_fraction"), 0.25);
  EXPECT_TRUE(std::isnan(value("pnp_ned_kf", "lost_fraction")));
}

TEST(RunRegressions, AConditionFitsOnlyTheRunsWithThatValue) {
  // Six hand-made runs on a zip of amplitude and direction: north RMSE = 2 a + 0.01 from
  // -40 deg, 0.5 a + 0.02 from 0 deg (exact lines), so each direction's slope is known.
  SweepManifest m;
  m.axes = {{"water.waves.airy.amplitude_m", "amplitude_m", AxisSpec::kValues, true, {}, {}},
            {"water.waves.airy.direction_deg", "direction_deg", AxisSpec::kValues, true, {}, {}}};
  const double amplitude[] = {0.005, 0.0075, 0.011, 0.005, 0.0075, 0.011};
  const char* amplitude_text[] = {"0.005", "0.0075", "0.011", "0.005", "0.0075", "0.011"};
  for (int k = 0; k < 6; ++k) {
    SweepJob job;
    job.id = "p000" + std::to_string(k) + "-r00";
    job.params = {{"amplitude_m", amplitude_text[k]}, {"direction_deg", k < 3 ? "-40" : "0"}};
    m.jobs.push_back(job);
  }
  std::vector<RunData> runs;
  for (int k = 0; k < 6; ++k) {
    const double north = k < 3 ? 2.0 * amplitude[k] + 0.01 : 0.5 * amplitude[k] + 0.02;
    record::RunRecord metrics;
    metrics.algorithms["pnp"].evaluation.basin.north_m.rmse = north;
    runs.push_back({&m.jobs[static_cast<std::size_t>(k)], metrics});
  }
  const auto specs =
      parse_run_regressions({"basin_north_rmse_m~amplitude_m@direction_deg=-40.0",
                             "basin_north_rmse_m~amplitude_m@direction_deg=0,amplitude_m=0.005",
                             "basin_north_rmse_m~amplitude_m"},
                            m);
  ASSERT_EQ(specs.size(), 3u);
  ASSERT_EQ(specs[0].where.size(), 1u);
  std::string md;
  std::vector<std::string> warnings;
  const auto fits = run_regressions(specs, runs, "pnp", &md, &warnings);
  ASSERT_EQ(fits.size(), 3u);
  const OlsFitRecord* within = fits.find("basin_north_rmse_m~amplitude_m@direction_deg=-40.0");
  ASSERT_NE(within, nullptr);
  EXPECT_EQ(within->n, 3u);
  EXPECT_NEAR(within->coefficients.find("amplitude_m")->estimate, 2.0, 1e-9);
  EXPECT_NEAR(within->coefficients.find("Intercept")->estimate, 0.01, 1e-11);
  EXPECT_NE(md.find("over the runs with direction_deg = -40.0:"), std::string::npos) << md;
  // One run meets both conditions: too few to fit, recorded and warned, not thrown.
  EXPECT_TRUE(fits.find("basin_north_rmse_m~amplitude_m@direction_deg=0,amplitude_m=0.005")
                  ->skipped.has_value());
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("got 1 runs with a value"), std::string::npos) << warnings[0];
  EXPECT_EQ(fits.find("basin_north_rmse_m~amplitude_m")->n, 6u);
  // Written, a skipped fit is its reason alone, a fit its statistics alone.
  const auto written = record_json::OrderedWriter::value_json(fits, "", nullptr);
  EXPECT_EQ(written["basin_north_rmse_m~amplitude_m@direction_deg=0,amplitude_m=0.005"].dump(),
            R"({"skipped":")" + *fits.items[1].second.skipped + R"("})");
  EXPECT_EQ(written["basin_north_rmse_m~amplitude_m"].begin().key(), "n");
  EXPECT_FALSE(written["basin_north_rmse_m~amplitude_m"].contains("skipped"));

  auto refused = [&](const std::string& spec, const std::string& expected) {
    try {
      parse_run_regressions({spec}, m);
      ADD_FAILURE() << spec << " was accepted";
    } catch (const UserError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  };
  refused("basin_north_rmse_m~amplitude_m@direction_deg=40",
          "got direction_deg = 40, expected one of the axis's values: -40, 0");
  refused("basin_north_rmse_m~amplitude_m@heading_deg=0",
          "got condition axis 'heading_deg', expected an axis of the sweep: amplitude_m, "
          "direction_deg");
  refused("basin_north_rmse_m~amplitude_m@direction_deg", "expected AXIS=VALUE");
  refused("basin_north_rmse_m@direction_deg=0", "expected METRIC~AXIS[+AXIS...]");
}

}  // namespace
}  // namespace driftlab::study
