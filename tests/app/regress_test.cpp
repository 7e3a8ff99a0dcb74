// `driftlab regress`, the CI regression gate, run as CI runs it: a baseline
// file, a results folder (a run or a merged sweep), exit codes, the table,
// JUnit XML and --update.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>
#include "tests/support/test_support.hpp"

namespace fs = std::filesystem;

namespace {

using Result = driftlab::test::CommandResult;
using driftlab::test::run_cli;
using driftlab::test::shell_quote;
using driftlab::test::slurp;

const fs::path kRegressCli = fs::path(DRIFTLAB_BINARY_DIR) / "bin" / "driftlab";

class Regress : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("driftlab_regress_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "run");
    write_results(0.010, 0.50, 7.0);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // A run's metrics.json with the values the gate looks at.
  void write_results(double ape, double r2, double dotted) {
    nlohmann::json m;
    m["algorithms"]["sparse"]["ape"]["trans_m"]["rmse"] = ape;
    m["algorithms"]["sparse"]["regression"]["r2"] = r2;
    m["algorithms"]["sparse"]["regression"]["coefficients"]["mission.yaw_weave.amplitude_deg"]
     ["estimate"] = dotted;
    m["algorithms"]["sparse"]["kitti"] = nlohmann::json::array();
    m["algorithms"]["sparse"]["basin"]["north_m"]["rmse"] = nullptr;
    std::ofstream(dir_ / "run/metrics.json") << m.dump(2);
  }

  // Three metrics: APE lower is better (10% or 0.0005), R^2 higher is better (0.05 absolute),
  // a coefficient under a key with dots (a JSON pointer) that must not move (0.5).
  void write_baseline(const std::string& extra = "") {
    std::ofstream(baseline()) << R"({
  "description": "unit test gate",
  "metrics": [
    {"key": "algorithms.sparse.ape.trans_m.rmse", "baseline": 0.010, "direction": "lower",
     "abs_tol": 0.0005, "rel_tol": 0.1},
    {"key": "algorithms.sparse.regression.r2", "baseline": 0.5, "direction": "higher",
     "abs_tol": 0.05},
    {"key": "/algorithms/sparse/regression/coefficients/mission.yaw_weave.amplitude_deg/estimate",
     "baseline": 7.0, "direction": "both", "abs_tol": 0.5})" +
                                     extra + R"(
  ]
})";
  }

  fs::path baseline() const { return dir_ / "baseline.json"; }
  Result gate(std::vector<std::string> more = {}) {
    std::vector<std::string> args = {"regress", "--baseline", baseline().string(), "--results",
                                     (dir_ / "run").string()};
    args.insert(args.end(), more.begin(), more.end());
    return run_cli(args);
  }

  fs::path dir_;
};

TEST_F(Regress, PassesWithinToleranceAndPrintsTheTable) {
  write_baseline();
  write_results(0.0109, 0.46, 6.6);  // +9% (tolerance 10% = 0.001), -0.04, -0.4
  const Result r = gate();
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("metric"), std::string::npos);
  EXPECT_NE(r.out.find("baseline"), std::string::npos);
  EXPECT_NE(r.out.find("verdict"), std::string::npos);
  EXPECT_NE(r.out.find("+0.0009 (+9.0%)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("regress: 3 metrics: 3 pass"), std::string::npos) << r.out;
}

TEST_F(Regress, ImprovementsPassAndAreNamed) {
  write_baseline();
  write_results(0.005, 0.9, 7.0);
  const Result r = gate();
  EXPECT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("regress: 3 metrics: 1 pass, 2 improved"), std::string::npos) << r.out;
}

TEST_F(Regress, ARegressionExitsFiveAndWritesJUnit) {
  write_baseline();
  write_results(0.0112, 0.44, 7.6);  // +12% > 10%; -0.06 < -0.05; +0.6 > 0.5
  const fs::path junit = dir_ / "out/junit.xml";
  fs::create_directories(junit.parent_path());
  const Result r = gate({"--junit", junit.string()});
  EXPECT_EQ(r.exit_code, 5) << r.out << r.err;
  EXPECT_NE(r.out.find("regress: 3 metrics: 0 pass, 3 REGRESSED"), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("3 of 3 metrics regressed or are missing"), std::string::npos) << r.err;
  const std::string xml = slurp(junit);
  EXPECT_EQ(xml.rfind("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuites", 0), 0u) << xml;
  EXPECT_NE(xml.find("tests=\"3\" failures=\"3\""), std::string::npos) << xml;
  EXPECT_NE(xml.find("<testcase classname=\"driftlab.regress.baseline\" "
                     "name=\"algorithms.sparse.ape.trans_m.rmse\""),
            std::string::npos)
      << xml;
  EXPECT_NE(xml.find("<failure type=\"REGRESSED\" message=\"regressed: baseline 0.01, new "
                     "0.0112, change +0.0012 (+12.0%), tolerance +0.001 (lower is better)\""),
            std::string::npos)
      << xml;
  EXPECT_EQ(std::count(xml.begin(), xml.end(), '<') - std::count(xml.begin(), xml.end(), '>'), 0);
}

TEST_F(Regress, OnlyTheWorseDirectionRegresses) {
  write_baseline();
  write_results(0.0112, 0.9, 7.0);  // only the APE is worse
  const Result r = gate();
  EXPECT_EQ(r.exit_code, 5);
  EXPECT_NE(r.out.find("regress: 3 metrics: 1 pass, 1 improved, 1 REGRESSED"), std::string::npos)
      << r.out;
}

TEST_F(Regress, MissingAndNullMetricsFail) {
  write_baseline(R"(,
    {"key": "algorithms.pnp.ape.trans_m.rmse", "baseline": 0.01},
    {"key": "algorithms.sparse.basin.north_m.rmse", "baseline": 0.01})");
  const Result r = gate();
  EXPECT_EQ(r.exit_code, 5);
  EXPECT_NE(r.out.find("MISSING: no 'pnp' under algorithms"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("MISSING: null (not computed for these results)"), std::string::npos)
      << r.out;
}

TEST_F(Regress, OnlyComparesTheMetricsUnderItsPrefixes) {
  write_baseline(R"(,
    {"key": "algorithms.pnp.ape.trans_m.rmse", "baseline": 0.01})");
  write_results(0.0112, 0.50, 7.0);  // the APE +12 %: regressed; no pnp in the results
  EXPECT_EQ(gate().exit_code, 5);
  Result r = gate({"--only", "algorithms.sparse.regression"});
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("regress: 1 metrics: 1 pass"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("pnp"), std::string::npos) << r.out;
  // A JSON-pointer key is matched as written, and the prefixes are comma-separated.
  r = gate({"--only", "algorithms.sparse.ape,/algorithms/sparse/"});
  EXPECT_EQ(r.exit_code, 5) << r.out << r.err;
  EXPECT_NE(r.out.find("regress: 2 metrics: 1 pass, 1 REGRESSED"), std::string::npos) << r.out;

  r = gate({"--only", "algorithms.dense.", "--junit", (dir_ / "junit.xml").string()});
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_NE(r.err.find("baseline.json: no metric's key starts with algorithms.dense. (--only); "
                       "expected the start of one of its keys, such as "
                       "algorithms.sparse.ape.trans_m.rmse"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "junit.xml"));            // nothing written
  r = gate({"--only", "algorithms.sparse.", "--update"});  // would drop the others from the file
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.err.find("--update"), std::string::npos) << r.err;
}

TEST_F(Regress, UpdateWritesTheNewValuesAndKeepsTolerances) {
  write_baseline();
  write_results(0.02, 0.3, 9.0);
  Result r = gate({"--update"});
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("updated with the new values"), std::string::npos) << r.out;
  const auto b = nlohmann::json::parse(slurp(baseline()));
  EXPECT_EQ(b["description"], "unit test gate");
  EXPECT_EQ(b["metrics"][0]["baseline"].get<double>(), 0.02);
  EXPECT_EQ(b["metrics"][0]["rel_tol"].get<double>(), 0.1);
  EXPECT_EQ(b["metrics"][1]["baseline"].get<double>(), 0.3);
  EXPECT_EQ(b["metrics"][1]["direction"], "higher");
  EXPECT_EQ(b["metrics"][2]["baseline"].get<double>(), 9.0);
  r = gate();
  EXPECT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("3 pass"), std::string::npos) << r.out;
}

TEST_F(Regress, UpdateRefusesResultsThatLackAMetric) {
  write_baseline(R"(,
    {"key": "algorithms.pnp.ape.trans_m.rmse", "baseline": 0.01})");
  const std::string before = slurp(baseline());
  const Result r = gate({"--update"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("nothing was updated"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(baseline()), before);
}

TEST_F(Regress, BadBaselineNamesFileLineFieldAndValue) {
  std::ofstream(baseline()) << R"({
  "metrics": [
    {"key": "algorithms.sparse.ape.trans_m.rmse", "baseline": 0.01,
     "direction": "smaller", "tolerance": 0.1, "abs_tol": -1}
  ]
})";
  const Result r = gate();
  EXPECT_EQ(r.exit_code, 1);
  const std::string b = baseline().string();
  EXPECT_NE(r.err.find(b + ":4:30: metrics[0].tolerance: unknown key; expected one of: key, "
                           "baseline, direction, abs_tol, rel_tol"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find(b + ":4:19: metrics[0].direction: got 'smaller', expected one of: lower"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find(b + ":4:59: metrics[0].abs_tol: got '-1', expected a number >= 0"),
            std::string::npos)
      << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

// What the fuzzer found (fuzz/regressions/gate): a number past double's range in
// metrics.json, and a baseline that is not UTF-8, each a clear error, not a crash.
TEST_F(Regress, ANumberPastDoubleOrTextThatIsNotUtf8IsABadInputNotACrash) {
  write_baseline();
  std::ofstream(dir_ / "run/metrics.json") << R"({"algorithms": {"sparse": {"x": 1e999}}})";
  Result r = gate();
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.err.find("metrics.json: not valid JSON ("), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("number overflow"), std::string::npos) << r.err;
  write_results(0.010, 0.50, 7.0);
  std::ofstream(baseline(), std::ios::binary)
      << "{\"description\": \"gate \xE9\", \"metrics\": []}";
  r = gate();
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.err.find(baseline().string() + ":1:23: got byte 0xE9, expected UTF-8 text"),
            std::string::npos)
      << r.err;
}

TEST_F(Regress, ReadsAMergedSweepAndExplainsAnUnmergedOne) {
  const fs::path sweep = dir_ / "sweep";
  fs::create_directories(sweep);
  std::ofstream(sweep / "manifest.jsonl") << "{}\n";
  std::ofstream(baseline()) << R"({"metrics": [
    {"key": "algorithms.sparse.runs.ape_trans_rmse_m.mean", "baseline": 0.01, "rel_tol": 0.1}]})";
  Result r = run_cli({"regress", "--baseline", baseline().string(), "--results", sweep.string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("a sweep folder that is not merged yet"), std::string::npos) << r.err;
  fs::create_directories(sweep / "summary");
  std::ofstream(sweep / "summary/metrics.json")
      << R"({"algorithms": {"sparse": {"runs": {"ape_trans_rmse_m": {"mean": 0.0101}}}}})";
  r = run_cli({"regress", "--baseline", baseline().string(), "--results", sweep.string()});
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("1 metrics: 1 pass"), std::string::npos) << r.out;
}

}  // namespace

namespace {

// driftlab-gate is the same command as `driftlab regress`, built from the gate module alone: it
// gives the same verdicts and table, and links none of the renderer's, Ceres' or assimp's
// libraries (nor OpenCV's), so a CI machine that only gates need not build them.
TEST_F(Regress, StandaloneGateBinaryMatchesRegressAndLinksNoRendererCeresOrAssimp) {
  const fs::path gate_bin = fs::path(DRIFTLAB_BINARY_DIR) / "bin" / "driftlab-gate";
  ASSERT_TRUE(fs::exists(gate_bin)) << gate_bin;
  write_baseline();
  write_results(0.0112, 0.44, 7.6);
  const Result via_driftlab = gate();
  const Result alone = driftlab::test::run_shell(shell_quote(gate_bin.string()) + " --baseline " +
                                                 shell_quote(baseline().string()) + " --results " +
                                                 shell_quote((dir_ / "run").string()));
  EXPECT_EQ(alone.exit_code, 5) << alone.output;
  EXPECT_EQ(alone.exit_code, via_driftlab.exit_code);
  EXPECT_EQ(alone.out, via_driftlab.out);

  const Result ldd = driftlab::test::run_shell("ldd " + shell_quote(gate_bin.string()));
  ASSERT_EQ(ldd.exit_code, 0) << ldd.output;
  EXPECT_NE(ldd.out.find("libyaml-cpp"), std::string::npos) << ldd.out;  // ldd does list libs
  for (const char* lib : {"OSMesa", "libEGL", "libceres", "libassimp", "libopencv"})
    EXPECT_EQ(ldd.out.find(lib), std::string::npos) << lib << " in\n" << ldd.out;
  // The full CLI does link them: the check above can fail.
  const Result full = driftlab::test::run_shell("ldd " + shell_quote(kRegressCli.string()));
  EXPECT_NE(full.out.find("OSMesa"), std::string::npos) << full.out;
}

}  // namespace

namespace {

TEST_F(Regress, InitWritesABaselineThatPassesTheSameResultsAndFailsDoubledErrors) {
  Result r = run_cli(
      {"regress", "init", "--results", (dir_ / "run").string(), "--baseline", baseline().string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto b = nlohmann::json::parse(slurp(baseline()));
  ASSERT_EQ(b["metrics"].size(), 1u);  // the APE; the null basin value is not gated
  EXPECT_EQ(b["metrics"][0]["key"], "algorithms.sparse.ape.trans_m.rmse");
  EXPECT_EQ(b["metrics"][0]["baseline"], 0.010);
  EXPECT_EQ(b["metrics"][0]["rel_tol"], 0.1);
  EXPECT_EQ(gate().exit_code, 0);
  write_results(0.020, 0.50, 7.0);  // the error doubled
  r = gate();
  EXPECT_EQ(r.exit_code, 5) << r.output;
  EXPECT_NE(r.out.find("1 REGRESSED"), std::string::npos) << r.out;
  // An existing baseline is not overwritten without --force; named keys must exist.
  r = run_cli(
      {"regress", "init", "--results", (dir_ / "run").string(), "--baseline", baseline().string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("already exists"), std::string::npos) << r.err;
  r = run_cli({"regress", "init", "--results", (dir_ / "run").string(), "--baseline",
               baseline().string(), "--force", "--keys",
               "algorithms.sparse.regression.r2,algorithms.pnp.ape.trans_m.rmse"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("no number at: algorithms.pnp.ape.trans_m.rmse"), std::string::npos)
      << r.err;
}

TEST_F(Regress, InitTakesTheToleranceOfASweepMeanFromItsReplicateSpread) {
  nlohmann::json m;  // a merged sweep's summary/metrics.json, pooled over 4 runs
  m["sweep"]["name"] = "unit";
  m["algorithms"]["sparse"]["runs"]["ape_trans_rmse_m"] = {{"n", 4}, {"mean", 1.0}, {"sd", 0.2}};
  std::ofstream(dir_ / "run/metrics.json") << m.dump(2);
  const Result r = run_cli({"regress", "init", "--results", (dir_ / "run").string(), "--baseline",
                            baseline().string(), "--rel-tol", "0"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto b = nlohmann::json::parse(slurp(baseline()));
  ASSERT_EQ(b["metrics"].size(), 1u);
  EXPECT_EQ(b["metrics"][0]["key"], "algorithms.sparse.runs.ape_trans_rmse_m.mean");
  EXPECT_DOUBLE_EQ(b["metrics"][0]["abs_tol"].get<double>(), 2 * 0.2 / 2);  // 2 sd / sqrt(n)
}

TEST_F(Regress, WithoutBaselineOrResultsIsABadCommandLine) {
  const Result r = run_cli({"regress", "--results", (dir_ / "run").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--baseline and --results are required"), std::string::npos) << r.err;
  const Result u = run_cli({"regress", "--baseline", (dir_ / "none.json").string(), "--results",
                            (dir_ / "run").string(), "--update"});
  EXPECT_EQ(u.exit_code, 1);
  EXPECT_NE(u.err.find("regress init"), std::string::npos) << u.err;
}

}  // namespace
