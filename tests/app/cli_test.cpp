// Runs the `driftlab` executable as a user would and checks exit codes,
// messages and files written.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>
#include "tests/support/test_support.hpp"

namespace fs = std::filesystem;

namespace {

using Result = driftlab::test::CommandResult;
using driftlab::test::fresh_temp_dir;
using driftlab::test::run_cli;
using driftlab::test::shell_quote;
using driftlab::test::slurp;

const fs::path kSource = DRIFTLAB_SOURCE_DIR;
const fs::path kCli = fs::path(DRIFTLAB_BINARY_DIR) / "bin" / "driftlab";

std::string read_text(const fs::path& p) { return slurp(p); }

std::vector<fs::path> bad_scenarios() {
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(kSource / "tests/data/bad_scenarios"))
    if (e.path().extension() == ".yaml") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files;
}

TEST(Cli, AtLeastFifteenBadScenarios) { EXPECT_GE(bad_scenarios().size(), 15u); }

class BadScenario : public ::testing::TestWithParam<fs::path> {};

TEST_P(BadScenario, FailsWithItsOwnClearMessage) {
  const fs::path file = GetParam();
  const auto expected = driftlab::test::expected_messages(file);
  ASSERT_FALSE(expected.empty()) << file << " has no '# expect:' line";
  const Result r = run_cli({"scenario", "check", file.string()});
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.err.rfind("error: ", 0), 0u) << r.output;
  EXPECT_TRUE(r.out.empty()) << r.out;
  for (const auto& e : expected) EXPECT_NE(r.output.find(e), std::string::npos) << r.output;
}

INSTANTIATE_TEST_SUITE_P(All, BadScenario, ::testing::ValuesIn(bad_scenarios()),
                         [](const ::testing::TestParamInfo<fs::path>& info) {
                           return info.param.stem().string();
                         });

TEST(Cli, MissingScenarioFile) {
  const Result r = run_cli({"scenario", "check", "no/such/scenario.yaml"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("no/such/scenario.yaml: no such scenario file"), std::string::npos)
      << r.output;
}

TEST(Cli, EveryShippedScenarioIsValid) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(kSource / "scenarios")) {
    if (e.path().extension() != ".yaml") continue;
    ++n;
    const Result r = run_cli({"scenario", "check", "--quiet", e.path().string()});
    EXPECT_EQ(r.exit_code, 0) << e.path() << "\n" << r.output;
  }
  EXPECT_GE(n, 10);  // river_crossing(_mist), river_survey, basin_exp1..7
}

TEST(Cli, CheckPrintsResolvedScenarioThatChecksAgain) {
  const fs::path dir = fresh_temp_dir("resolved");
  const Result r =
      run_cli({"scenario", "check", (kSource / "scenarios/river_crossing.yaml").string(), "--set",
               "sensors.camera.baseline_m=0.2"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.out.find("baseline_m: 0.2  # Stereo baseline B [m]"), std::string::npos);
  EXPECT_NE(r.out.find("section_length_m: 6.5"), std::string::npos);
  EXPECT_NE(r.err.find("OK (scenario 'river_crossing', seed 2013)"), std::string::npos);
  // The printed YAML is itself a valid scenario, and resolving it again is a fixed point.
  std::ofstream(dir / "resolved.yaml") << r.out;
  const Result again = run_cli({"scenario", "check", (dir / "resolved.yaml").string()});
  EXPECT_EQ(again.exit_code, 0) << again.output;
  EXPECT_EQ(again.out, r.out);
  fs::remove_all(dir);
}

TEST(Cli, SetOverridesAreValidatedLikeTheFile) {
  const std::string file = (kSource / "scenarios/river_crossing.yaml").string();
  Result r = run_cli({"scenario", "check", "-q", file, "--set", "sensors.camera.baseline_m=-1"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("--set sensors.camera.baseline_m=-1: sensors.camera.baseline_m: got -1, "
                          "expected a value in (0, 100] (a stereo rig wider than any vessel)"),
            std::string::npos)
      << r.output;
  r = run_cli({"scenario", "check", "-q", file, "--set", "sensors.camera.nope=1"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("sensors.camera.nope: unknown key"), std::string::npos) << r.output;
  r = run_cli({"scenario", "check", "-q", file, "--set", "pipeline.vo=[pnp, dense]"});
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

TEST(Cli, SchemaReferenceInDocsIsUpToDate) {
  const fs::path dir = fresh_temp_dir("schema");
  const Result r = run_cli({"scenario", "schema", "--out", (dir / "ref.md").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(read_text(dir / "ref.md"), read_text(kSource / "docs/scenario-reference.md"))
      << "docs/scenario-reference.md is stale: run `build/bin/driftlab scenario schema --out "
         "docs/scenario-reference.md`";
  fs::remove_all(dir);
}

// The sweep-file, baseline and metrics references come from the same visit() lists as their
// readers.
TEST(Cli, SweepBaselineAndMetricsReferencesInDocsAreUpToDate) {
  const fs::path dir = fresh_temp_dir("schema");
  const std::pair<std::vector<std::string>, std::string> refs[] = {
      {{"sweep", "schema"}, "docs/sweep-reference.md"},
      {{"regress", "schema"}, "docs/baseline-reference.md"},
      {{"metrics", "schema"}, "docs/metrics-reference.md"}};
  for (const auto& [args, doc] : refs) {
    std::vector<std::string> cmd = args;
    cmd.insert(cmd.end(), {"--out", (dir / "ref.md").string()});
    const Result r = run_cli(cmd);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(read_text(dir / "ref.md"), read_text(kSource / doc))
        << doc << " is stale: run `build/bin/driftlab " << args[0] << " schema --out " << doc
        << "`";
  }
  fs::remove_all(dir);
}

TEST(Cli, RunWritesAtomicallyAndRefusesToOverwrite) {
  const fs::path dir = fresh_temp_dir("run");
  const std::string file = (kSource / "scenarios/river_crossing.yaml").string();
  const fs::path out = dir / "out";
  Result r = run_cli(
      {"run", file, "--out", out.string(), "--seed", "99", "--set", "pipeline.max_frames=10"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(out / "scenario.resolved.yaml"));
  EXPECT_NE(read_text(out / "metrics.json").find("\"seed\": 99"), std::string::npos);
  r = run_cli({"run", file, "--out", out.string()});
  EXPECT_EQ(r.exit_code, 1) << r.output;
  r = run_cli({"run", file, "--out", out.string(), "--force", "--set", "pipeline.max_frames=10"});
  EXPECT_EQ(r.exit_code, 0) << r.output;
  // A bad scenario leaves nothing behind.
  const fs::path out2 = dir / "out2";
  r = run_cli({"run", file, "--out", out2.string(), "--set", "seed=-4"});
  EXPECT_EQ(r.exit_code, 1);
  // So does a bad frame cache size: the message names the variable, its value and what was
  // expected, and neither the run nor the cache folder appears.
  r = run_cli({"run", file, "--out", out2.string(), "--frame-cache", (dir / "frames").string()},
              "DRIFTLAB_FRAME_CACHE_GIB=lots");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("DRIFTLAB_FRAME_CACHE_GIB: got 'lots', expected the frame cache's size "
                          "in GiB, a number above 0"),
            std::string::npos)
      << r.output;
  for (const auto& e : fs::directory_iterator(dir))
    EXPECT_EQ(e.path().filename(), "out") << "left behind: " << e.path();
  fs::remove_all(dir);
}

// docs/design.md, "Data contract of a run": an interrupted run leaves nothing that looks
// complete. Kill a run in its frame loop (SIGKILL: no handler can tidy up) and look at what is
// left.
TEST(Cli, KilledRunLeavesNoOutputFolder) {
  const fs::path dir = fresh_temp_dir("killed");
  const fs::path out = dir / "out";
  const fs::path log = dir / "log";
  const std::string cmd = shell_quote(kCli.string()) + " run " +
                          shell_quote((kSource / "scenarios/river_crossing.yaml").string()) +
                          " --out " + shell_quote(out.string()) + " > " +
                          shell_quote(log.string()) + " 2>&1 & pid=$!; " +
                          // wait until the frame loop reports progress, then kill; up to
                          // 300 s, since under AddressSanitizer the physics stage before the
                          // loop alone takes 50 s of an idle CI machine (60 s was too short)
                          "for i in $(seq 1 3000); do grep -q frames " + shell_quote(log.string()) +
                          " && break; sleep 0.1; done; kill -9 $pid; wait $pid";
  const int status = std::system(("bash -c " + shell_quote(cmd)).c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 128 + 9) << read_text(log);  // it was still running
  EXPECT_NE(read_text(log).find("frames"), std::string::npos);
  EXPECT_FALSE(fs::exists(out));
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    EXPECT_TRUE(name == "log" || name.rfind("out.tmp.", 0) == 0) << "unexpected: " << name;
    if (e.is_directory()) {
      EXPECT_FALSE(fs::exists(e.path() / "metrics.json")) << name;
    }
  }
  fs::remove_all(dir);
}

TEST(Cli, HelpForEverySubcommand) {
  for (const auto& sub : {"scenario", "run", "render", "eval", "sweep", "regress", "imagestats"}) {
    const Result r = run_cli({sub, "--help"});
    EXPECT_EQ(r.exit_code, 0) << sub << "\n" << r.output;
    EXPECT_NE(r.output.find("Usage"), std::string::npos) << r.output;
  }
  EXPECT_NE(run_cli({"--bogus"}).exit_code, 0);
  EXPECT_NE(run_cli({}).exit_code, 0);
}

TEST(Cli, ASweepPlanOfAScenarioFileSaysWhatASweepNeeds) {
  // A scenario is not a sweep: its keys are unknown to the sweep file and it has no base.
  const fs::path dir = fresh_temp_dir("sweep_of_scenario");
  const std::string file = (kSource / "scenarios/river_crossing.yaml").string();
  const Result r = run_cli({"sweep", "plan", file, "--out", (dir / "out").string()});
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.err.find(file + ": base: missing, expected the path of the base scenario"),
            std::string::npos)
      << r.err;
  // The line of the scenario's `scene:` key.
  std::ifstream in(file);
  std::string line;
  int scene_line = 0;
  for (int n = 1; std::getline(in, line); ++n)
    if (line.rfind("scene:", 0) == 0) scene_line = n;
  ASSERT_GT(scene_line, 0);
  EXPECT_NE(r.err.find(fmt::format("{}:{}:1: scene: unknown key", file, scene_line)),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir / "out"));
  fs::remove_all(dir);
}

}  // namespace

namespace {

// A straight 30 m track at 0.5 m per 0.5 s, camera level and looking north;
// the estimate over-measures every step by 2%.
void write_tum_pair(const fs::path& dir) {
  std::ofstream gt(dir / "gt.tum"), est(dir / "est.tum");
  // Camera optical z north, x east, y down: q = R_W_C as (x y z w).
  const char* q = "0.5 0.5 0.5 0.5";
  for (int i = 0; i <= 60; ++i) {
    gt << i * 0.5 << " " << i * 0.5 << " 0 0 " << q << "\n";
    est << i * 0.5 << " " << i * 0.5 * 1.02 << " 0 0 " << q << "\n";
  }
}

TEST(CliEval, WritesMetricsSectionsAndTables) {
  const fs::path dir = fresh_temp_dir("eval");
  write_tum_pair(dir);
  const Result r =
      run_cli({"eval", "--gt", (dir / "gt.tum").string(), "--est", (dir / "est.tum").string(),
               "--align", "none", "--out", (dir / "out").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string metrics = read_text(dir / "out/metrics.json");
  EXPECT_NE(metrics.find("\"p_m_per_m\""), std::string::npos);
  EXPECT_NE(read_text(dir / "out/tables.md").find("Table 1"), std::string::npos);
  // 30 m straight: 4 sections of 6.5 m (first pose at or past 6.5 m: 13 steps),
  // each with a 2% scale error.
  const std::string csv = read_text(dir / "out/sections.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 5) << csv;
  const auto j = nlohmann::json::parse(metrics);
  EXPECT_EQ(j["sections"]["count"], 4);
  EXPECT_NEAR(j["sections"]["p_m_per_m"]["mean"].get<double>(), 0.02, 1e-12);
  EXPECT_NEAR(j["algorithms"]["est"]["sections"]["p_m_per_m"]["max"].get<double>(), 0.02, 1e-12);
  // The 2 % scale error is the length error, whether sampled (default) or summed per pose.
  EXPECT_NEAR(j["track"]["length_error_pct"].get<double>(), 2.0, 1e-9);
  const Result every_pose =
      run_cli({"eval", "--gt", (dir / "gt.tum").string(), "--est", (dir / "est.tum").string(),
               "--align", "none", "--length-sample", "0", "--out", (dir / "out0").string()});
  ASSERT_EQ(every_pose.exit_code, 0) << every_pose.output;
  const auto j0 = nlohmann::json::parse(read_text(dir / "out0/metrics.json"));
  EXPECT_NEAR(j0["track"]["length_error_pct"].get<double>(), 2.0, 1e-9);
  const Result negative =
      run_cli({"eval", "--gt", (dir / "gt.tum").string(), "--est", (dir / "est.tum").string(),
               "--length-sample", "-1", "--out", (dir / "out1").string()});
  EXPECT_NE(negative.exit_code, 0);
  EXPECT_NE(negative.err.find("length_sample_m: got -1"), std::string::npos) << negative.err;
  EXPECT_FALSE(fs::exists(dir / "out1"));
  fs::remove_all(dir);
}

// A grey image as binary PGM (P5), which needs no image library to write.
void write_pgm(const fs::path& path, int width, int height,
               const std::function<unsigned char(int, int)>& pixel) {
  std::ofstream out(path, std::ios::binary);
  out << "P5\n" << width << " " << height << "\n255\n";
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) out.put(static_cast<char>(pixel(x, y)));
}

TEST(CliImageStats, CountsTheCornersOfACheckerboardAndNamesABadInput) {
  const fs::path dir = fresh_temp_dir("imagestats");
  fs::create_directories(dir / "frames");
  const auto board = [](int x, int y) -> unsigned char {
    return ((x / 32 + y / 32) % 2 == 0) ? 40 : 200;
  };
  write_pgm(dir / "board.pgm", 1024, 768, board);
  write_pgm(dir / "frames/000000.pgm", 1024, 768, board);
  write_pgm(dir / "frames/000001.pgm", 1024, 768, board);
  const Result r = run_cli(
      {"imagestats", (dir / "board.pgm").string(), "frames=" + (dir / "frames").string(), "--json",
       (dir / "stats.json").string(), "--montage", (dir / "montage.png").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.out.find("| board | 1 |"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("| frames | 2 |"), std::string::npos) << r.out;
  const auto json = nlohmann::json::parse(slurp(dir / "stats.json"));
  // Inner corners every 32 px: 31 x 23 of them inside the 20 x 15 whole 50x50 cells.
  EXPECT_NEAR(json["board"]["mean"]["corners_per_cell"].get<double>(), 31.0 * 23.0 / 300.0, 1e-9);
  EXPECT_EQ(json["frames"]["images"].size(), 2u);
  EXPECT_TRUE(fs::exists(dir / "montage.png"));

  Result bad = run_cli({"imagestats", (dir / "no_such.png").string()});
  EXPECT_EQ(bad.exit_code, 1) << bad.output;
  EXPECT_NE(bad.err.find("no_such.png: no such file or folder"), std::string::npos) << bad.err;
  fs::create_directories(dir / "empty");
  bad = run_cli({"imagestats", (dir / "empty").string(), "--out", (dir / "t.md").string()});
  EXPECT_EQ(bad.exit_code, 1) << bad.output;
  EXPECT_NE(bad.err.find("no images"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(dir / "t.md"));
  bad = run_cli({"imagestats", (dir / "board.pgm").string(), "--size", "100x50"});
  EXPECT_EQ(bad.exit_code, 2) << bad.output;  // a bad command line
  EXPECT_NE(bad.err.find("--size: got 100x50, expected at least 200x150"), std::string::npos)
      << bad.err;
  fs::remove_all(dir);
}

TEST(Cli, OptionValuesAreCheckedBeforeAnyWorkAndExit2) {
  const std::string crossing = (kSource / "scenarios/river_crossing.yaml").string();
  const fs::path dir = fresh_temp_dir("option_values");
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"render", crossing, "--frames", "-3"}, "--frames: Value -3 not in range"},
      {{"export", crossing, "--frames", "-3"}, "--frames: Value -3 not in range"},
      {{"run", crossing, "--seed", "abc"}, "--seed: got 'abc', expected a non-negative integer"},
      {{"vo", dir.string(), "--algo", "sparse,spars"},
       "--algo: got 'spars', expected one of: sparse, sparse_kf, pnp, dense"},
      {{"vo", dir.string(), "--fusion", "foo"},
       "--fusion: got 'foo', expected one of: none, ca_smoother, ned_kf, ned_pf, eskf"}};
  for (const auto& [args, message] : cases) {
    std::vector<std::string> argv = args;
    argv.insert(argv.end(), {"--out", (dir / "out").string()});
    const Result r = run_cli(argv);
    EXPECT_EQ(r.exit_code, 2) << args[0] << ": " << r.output;
    EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "out"));
  }
  fs::remove_all(dir);
}

TEST(CliRender, OneFrameIsOneFrame) {
  // --frames 1 once meant the whole mission: the physics' end at the first frame, t = 0, read
  // as "no end".
  const fs::path dir = fresh_temp_dir("one_frame");
  const Result r = run_cli({"render", (kSource / "scenarios/river_crossing.yaml").string(),
                            "--frames", "1", "--out", (dir / "r").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.out.find("rendered 1 stereo pairs"), std::string::npos) << r.out;
  EXPECT_EQ(std::distance(fs::directory_iterator(dir / "r/left"), fs::directory_iterator{}), 1);
  fs::remove_all(dir);
}

TEST(CliRender, ProfileSaysWhereEachFramesTimeWent) {
  // --profile: the frame's time, the passes' part of it and one line a pass (the crossing has
  // nothing that moves: no truth pass); the same images.
  const fs::path dir = fresh_temp_dir("profile");
  const std::string scenario = (kSource / "scenarios/river_crossing.yaml").string();
  const Result r =
      run_cli({"render", scenario, "--frames", "2", "--profile", "--out", (dir / "p").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* line : {"profile: ", "2 stereo pairs, 0 truth passes", "mirror images", "water",
                           "scene meshes", "sky", "resolve and read back", "truth: "})
    EXPECT_NE(r.out.find(line), std::string::npos) << line << "\n" << r.out;
  const Result plain =
      run_cli({"render", scenario, "--frames", "2", "--out", (dir / "q").string()});
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  EXPECT_EQ(plain.out.find("profile: "), std::string::npos) << plain.out;
  for (const char* f : {"left/000000.png", "left/000001.png", "right/000001.png"})
    EXPECT_EQ(slurp(dir / "p" / f), slurp(dir / "q" / f)) << f;
  fs::remove_all(dir);
}

TEST(CliEval, ReadsARunsFramesCsvAsTheColumnsOfTheEstimatesVo) {
  // A run's frames.csv with two VOs' blocks; the estimate file's name says whose f to read.
  const fs::path dir = fresh_temp_dir("eval_frames");
  write_tum_pair(dir);
  fs::copy_file(dir / "est.tum", dir / "sparse_kf_ca.tum");
  fs::copy_file(dir / "est.tum", dir / "other.tum");
  {
    std::ofstream f(dir / "frames.csv");
    f << "t_ns,yaw_deg,render_ms,sparse_valid,sparse_features,sparse_kf_valid,sparse_kf_features,"
         "sparse_kf_mean_depth_m\n";
    for (int i = 0; i <= 60; ++i) f << i * 500'000'000LL << ",0,10,1,50,1," << 100 + i << ",20\n";
  }
  auto eval = [&](const std::string& est, std::vector<std::string> extra) {
    std::vector<std::string> args = {"eval",
                                     "--gt",
                                     (dir / "gt.tum").string(),
                                     "--est",
                                     (dir / est).string(),
                                     "--covariates",
                                     (dir / "frames.csv").string(),
                                     "--align",
                                     "none",
                                     "--out",
                                     (dir / ("out_" + est)).string()};
    args.insert(args.end(), extra.begin(), extra.end());
    return run_cli(args);
  };
  // sparse_kf's f: 100 + i; the 4 sections span rows 0-13, 13-26, 26-39 and 39-52, with means
  // 106.5, 119.5, 132.5 and 145.5: 126 on average.
  Result r = eval("sparse_kf_ca.tum", {});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto j = nlohmann::json::parse(read_text(dir / "out_sparse_kf_ca.tum/metrics.json"));
  EXPECT_NEAR(j["covariates"]["f"]["mean"].get<double>(), 126.0, 1e-12);
  EXPECT_NEAR(j["covariates"]["d"]["mean"].get<double>(), 20.0, 1e-12);
  EXPECT_FALSE(j["covariates"].contains("render_ms"));  // the run's other columns are left out
  // No VO of that name: say so, and how to choose; --vo chooses.
  r = eval("other.tum", {});
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.err.find("with the columns of sparse, sparse_kf; none of them is 'other'"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir / "out_other.tum"));
  r = eval("other.tum", {"--vo", "sparse"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  j = nlohmann::json::parse(read_text(dir / "out_other.tum/metrics.json"));
  EXPECT_NEAR(j["covariates"]["f"]["mean"].get<double>(), 50.0, 1e-12);
  fs::remove_all(dir);
}

TEST(CliEval, BadInputFailsAndLeavesNothing) {
  const fs::path dir = fresh_temp_dir("eval_bad");
  write_tum_pair(dir);
  std::ofstream(dir / "unsorted.tum") << "1.0 0 0 0 0 0 0 1\n0.5 0 0 0 0 0 0 1\n";
  Result r = run_cli({"eval", "--gt", (dir / "gt.tum").string(), "--est",
                      (dir / "unsorted.tum").string(), "--out", (dir / "out").string()});
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.err.find("unsorted.tum"), std::string::npos) << r.err;
  // A bad option value is a bad command line (exit 2), named by the flag as given.
  r = run_cli({"eval", "--gt", (dir / "gt.tum").string(), "--est", (dir / "est.tum").string(),
               "--align", "procrustes", "--out", (dir / "out").string()});
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.err.find("--align procrustes: align: got 'procrustes', expected one of: horn, se3, "
                       "sim3, posyaw, none"),
            std::string::npos)
      << r.err;
  r = run_cli({"eval", "--gt", (dir / "gt.tum").string(), "--est", (dir / "est.tum").string(),
               "--section-length", "-1", "--out", (dir / "out").string()});
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.err.find("--section-length -1: section_length_m: got -1"), std::string::npos)
      << r.err;
  r = run_cli({"eval", "--gt", (dir / "gt.tum").string(), "--est", (dir / "est.tum").string(),
               "--format", "ply", "--out", (dir / "out").string()});
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.err.find("--format: unknown trajectory format: got 'ply'"), std::string::npos)
      << r.err;
  r = run_cli({"export", (kSource / "scenarios/river_crossing.yaml").string(), "--format", "kiti",
               "--out", (dir / "out").string()});
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.err.find("--format: unknown dataset format: got 'kiti'"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "out"));
  fs::remove_all(dir);
}

}  // namespace

namespace {

TEST(CliRender, SameBytesWithOneOrTwoRasterThreads) {
  // llvmpipe rasterises on LP_NUM_THREADS threads: the images must not depend on it.
  const fs::path dir = fresh_temp_dir("render_threads");
  const std::string file = (kSource / "scenarios/river_crossing.yaml").string();
  for (const char* n : {"1", "2"}) {
    const Result r =
        run_cli({"render", file, "--frames", "3", "--depth", "--out", (dir / n).string()},
                std::string("LP_NUM_THREADS=") + n);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.out.find("rendered 3 stereo pairs"), std::string::npos) << r.out;
  }
  for (const char* f : {"left/000002.png", "right/000002.png", "depth/000002.pfm", "times.csv"})
    EXPECT_EQ(read_text(dir / "1" / f), read_text(dir / "2" / f)) << f;
  EXPECT_GT(read_text(dir / "1/left/000002.png").size(), 10000u);
  fs::remove_all(dir);
}

}  // namespace

namespace {

TEST(Cli, PaperPutsTheRiverPaperBesideARunAndAsksForTheTrackOfOtherScenarios) {
  const fs::path dir = fresh_temp_dir("paper");
  const fs::path metrics = dir / "metrics.json";
  nlohmann::json m;
  m["scenario"] = "my_reach";
  m["algorithms"]["sparse"]["sections"]["p_m_per_m"]["mean"] = 0.0123;
  std::ofstream(metrics) << m.dump();
  Result r = run_cli({"paper", metrics.string()});
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.err.find("scenario 'my_reach' is not a twin of the river paper"), std::string::npos)
      << r.err;
  r = run_cli({"paper", dir.string(), "--track", "sideways"});
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.err.find("--track: got 'sideways', expected discharge or total"), std::string::npos)
      << r.err;
  r = run_cli({"paper", dir.string(), "--track", "total", "--out", (dir / "paper.md").string()});
  EXPECT_EQ(r.exit_code, 0) << r.output;
  const std::string text = slurp(dir / "paper.md");
  EXPECT_NE(text.find("| Mean | 0.067 | 0.012 | 0.177 |"), std::string::npos) << text;
  EXPECT_NE(text.find("13.36 (2.01)"), std::string::npos);
  // A metrics.json without its run's files: the camera's columns, and a warning for the prism's.
  EXPECT_NE(r.err.find("warning: no columns at the prism: " + dir.string() +
                       " lacks scenario.resolved.yaml, groundtruth.tum, frames.csv"),
            std::string::npos)
      << r.err;
  r = run_cli({"paper", dir.string(), "--track", "total", "--prism", "none"});
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;
  r = run_cli({"paper", dir.string(), "--track", "total", "--prism", "0,0"});
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.err.find("--prism 0,0"), std::string::npos) << r.err;
  r = run_cli({"paper", (dir / "missing").string()});
  EXPECT_EQ(r.exit_code, 1) << r.output;
  fs::remove_all(dir);
}

// The prism's default: 1 m above the centre of gravity on the centre line, seen from the run's
// camera through its mount (lever arm, pitch and yaw), here a mount other than the shipped one.
TEST(Cli, PaperPlacesTheDefaultPrismThroughTheRunsCameraMount) {
  const fs::path dir = fresh_temp_dir("paper_prism");
  const double pitch = -20 * M_PI / 180, yaw = 45 * M_PI / 180;
  Result r = run_cli({"run", (kSource / "scenarios/river_crossing.yaml").string(), "--out",
                      (dir / "run").string(), "--set", "pipeline.max_frames=12", "--set",
                      "pipeline.vo=[sparse]", "--set", "pipeline.fusion=[]", "--set",
                      "sensors.camera.mount.rpy_deg=[0,-20,45]", "--set",
                      "sensors.camera.mount.position_frd_m=[-0.5,0.2,-0.4]"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = run_cli({"paper", (dir / "run").string(), "--out", (dir / "paper.md").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // The prism from the camera, body FRD: (0, 0, -1) - (-0.5, 0.2, -0.4). The optical axes in
  // the body: z forward along the mount's yaw and pitch (negative: down), x to its right, level
  // (no roll), y = z x x down.
  const double d[3] = {0.5, -0.2, -0.6};
  const double z[3] = {std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw),
                       -std::sin(pitch)};
  const double x[3] = {-std::sin(yaw), std::cos(yaw), 0};
  const double y[3] = {z[1] * x[2] - z[2] * x[1], z[2] * x[0] - z[0] * x[2],
                       z[0] * x[1] - z[1] * x[0]};
  auto dot = [&](const double* a) { return a[0] * d[0] + a[1] * d[1] + a[2] * d[2]; };
  const std::string expected =
      fmt::format("at [{:.3g}, {:.3g}, {:.3g}] m in the camera's frame", dot(x), dot(y), dot(z));
  EXPECT_NE(slurp(dir / "paper.md").find(expected), std::string::npos) << expected;
  fs::remove_all(dir);
}

}  // namespace
