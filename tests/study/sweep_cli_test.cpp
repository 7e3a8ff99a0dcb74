// Sweeps through the real `driftlab` binary: that a sweep merges to the same bytes whether run
// with -j 2, as shards, or killed and resumed; failing jobs, the runner's lock, regressions in
// the merge, external VOs beside built-in ones and the frame cache shared by jobs.
#include "study/sweep.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "core/csv.hpp"
#include "core/process.hpp"
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

using Result = test::CommandResult;
using test::run_cli;

const std::vector<std::string> kSweepSummaryFiles = {"sections.csv", "runs.csv", "points.csv",
                                                     "metrics.json", "summary.md"};

void expect_same_summary(const fs::path& a, const fs::path& b) {
  for (const auto& f : kSweepSummaryFiles) {
    const std::string x = slurp(a / "summary" / f), y = slurp(b / "summary" / f);
    EXPECT_FALSE(x.empty()) << a / "summary" / f;
    EXPECT_TRUE(x == y) << f << " differs between " << a << " and " << b;
  }
}

std::size_t markers(const fs::path& dir) {
  std::size_t n = 0;
  for (const auto& e : fs::directory_iterator(dir / "runs")) n += fs::exists(e.path() / "job.json");
  return n;
}

TEST(SweepCli, KilledRunResumesOnlyMissingJobsAndEveryWayMergesToTheSameBytes) {
  const fs::path root = temp_dir("resume");
  const fs::path a = root / "a", b = root / "b", c = root / "c";
  const std::string sweep = (kSweeps / "tiny_grid.yaml").string();
  for (const auto& d : {a, b, c}) {
    const Result r = run_cli({"sweep", "plan", sweep, "--out", d.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  EXPECT_EQ(slurp(a / "manifest.jsonl"), slurp(b / "manifest.jsonl"));

  // a: uninterrupted, two at a time.
  Result r = run_cli({"sweep", "run", a.string(), "-j", "2"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("4 jobs: ran 4, 0 failed, 0 already done"), std::string::npos) << r.out;
  EXPECT_EQ(markers(a), 4u);

  // b: as two shards, the way a job array runs it (0-based K).
  for (const char* shard : {"0/2", "1/2"}) {
    r = run_cli({"run", "--manifest", (b / "manifest.jsonl").string(), "--shard", shard});
    ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
    EXPECT_NE(r.out.find("2 jobs: ran 2"), std::string::npos) << r.out;
  }
  // Shard 0/2 holds jobs 0 and 2: the finished jobs are skipped when it runs again.
  r = run_cli({"run", "--manifest", (b / "manifest.jsonl").string(), "--shard", "0/2"});
  EXPECT_NE(r.out.find("2 jobs: ran 0, 0 failed, 2 already done"), std::string::npos) << r.out;

  // c: one at a time, killed (SIGKILL) once the first job is done, then resumed.
  ProcessSpec spec;
  spec.executable = kCli;
  spec.args = {"sweep", "run", c.string(), "-j", "1"};
  spec.output_file = root / "killed.log";
  const pid_t pid = spawn_process(spec);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(5);
  while (!fs::exists(c / "runs/p0000-r00/job.json") && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ::kill(pid, SIGKILL);
  const ExitStatus killed = wait_process(pid);
  EXPECT_FALSE(killed.exited);
  const std::size_t done_before = markers(c);
  ASSERT_GE(done_before, 1u);
  ASSERT_LT(done_before, 4u) << "the run finished before it was killed";
  std::map<std::string, std::pair<std::string, fs::file_time_type>> finished;
  for (const auto& e : fs::directory_iterator(c / "runs"))
    if (fs::exists(e.path() / "job.json"))
      finished[e.path().filename()] = {slurp(e.path() / "job.json"),
                                       fs::last_write_time(e.path() / "job.json")};
  // The interrupted job's child got SIGTERM with its parent; its temporaries go once it is gone.
  const SweepManifest mc = read_manifest(c);
  while (!leftover_temporaries(mc, /*remove=*/true).empty() &&
         std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_TRUE(leftover_temporaries(mc, false).empty());

  r = run_cli({"sweep", "run", c.string(), "-j", "2"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("4 jobs: ran " + std::to_string(4 - done_before) + ", 0 failed, " +
                       std::to_string(done_before) + " already done"),
            std::string::npos)
      << r.out;
  for (const auto& [id, before] : finished) {
    EXPECT_EQ(slurp(c / "runs" / id / "job.json"), before.first) << id << " ran again";
    EXPECT_EQ(fs::last_write_time(c / "runs" / id / "job.json"), before.second) << id;
  }
  r = run_cli({"sweep", "status", c.string()});
  EXPECT_NE(r.out.find("4 jobs: 4 done, 0 failed, 0 stale, 0 missing"), std::string::npos) << r.out;

  for (const auto& d : {a, b, c}) {
    r = run_cli({"sweep", "merge", d.string(), "--no-plots"});
    ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  }
  expect_same_summary(a, b);
  expect_same_summary(a, c);

  // The pooled table: the sweep's columns, then each run's sections.csv rows as they are.
  const std::string pooled = slurp(a / "summary/sections.csv");
  EXPECT_EQ(pooled.rfind("job,point,replicate,seed,yaw_amp_deg,algorithm,index,", 0), 0u)
      << pooled.substr(0, 200);
  std::size_t rows = 0;
  const SweepManifest ma = read_manifest(a);
  for (const auto& job : ma.jobs) {
    std::istringstream in(slurp(ma.run_dir(job.id) / "sections.csv"));
    std::string line;
    std::getline(in, line);  // header
    while (std::getline(in, line)) {
      ++rows;
      const std::string prefix = job.id + "," + std::to_string(job.point) + "," +
                                 std::to_string(job.replicate) + "," + std::to_string(job.seed) +
                                 "," + (job.point == 0 ? "0" : "20") + "," + line;
      EXPECT_NE(pooled.find(prefix + "\n"), std::string::npos) << prefix;
    }
  }
  EXPECT_GT(rows, 0u);
  EXPECT_EQ(static_cast<std::size_t>(std::count(pooled.begin(), pooled.end(), '\n')), rows + 1);

  // Per point: replicates' mean of each run metric, over the runs of that point.
  const auto metrics = nlohmann::json::parse(slurp(a / "summary/metrics.json"));
  for (std::size_t point = 0; point < 2; ++point) {
    double sum = 0;
    int n = 0;
    for (const auto& job : ma.jobs) {
      if (job.point != point) continue;
      const auto run = nlohmann::json::parse(slurp(ma.run_dir(job.id) / "metrics.json"));
      sum += run["algorithms"]["sparse"]["ape"]["trans_m"]["rmse"].get<double>();
      ++n;
    }
    const auto& s = metrics["points"][point == 0 ? "p0000" : "p0001"]["algorithms"]["sparse"]
                           ["ape_trans_rmse_m"];
    EXPECT_EQ(s["n"], n);
    EXPECT_NEAR(s["mean"].get<double>(), sum / n, 1e-12);
  }
  fs::remove_all(root);
}

TEST(SweepCli, AFailingJobIsRecordedAndDoesNotStopTheOthers) {
  const fs::path dir = temp_dir("failing");
  Result r =
      run_cli({"sweep", "plan", (kSweeps / "tiny_grid.yaml").string(), "--out", dir.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // Job p0000-r01 now disagrees with the scenario: it fails when it loads.
  std::string manifest = slurp(dir / "manifest.jsonl");
  const SweepManifest m = read_manifest(dir);
  const auto at = manifest.find(m.jobs[1].hash);
  ASSERT_NE(at, std::string::npos);
  manifest.replace(at, 16, "0123456789abcdef");
  std::ofstream(dir / "manifest.jsonl") << manifest;

  r = run_cli({"sweep", "run", dir.string(), "-j", "2"});
  EXPECT_EQ(r.exit_code, 6) << r.out << r.err;
  EXPECT_NE(r.out.find("4 jobs: ran 4, 1 failed, 0 already done; "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("failed: p0000-r01"), std::string::npos) << r.out;
  const auto rec = nlohmann::json::parse(slurp(dir / "failed/p0000-r01.json"));
  EXPECT_EQ(rec["status"], "exit code 1");
  EXPECT_NE(rec["error"].get<std::string>().find("the scenario hashes to"), std::string::npos)
      << rec.dump(2);
  EXPECT_FALSE(fs::exists(dir / "runs/p0000-r01"));
  EXPECT_TRUE(fs::exists(dir / "logs/p0000-r01.log"));

  r = run_cli({"sweep", "status", dir.string()});
  EXPECT_NE(r.out.find("4 jobs: 3 done, 1 failed, 0 stale, 0 missing"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("p0000-r01  exit code 1: "), std::string::npos) << r.out;
  // The merge refuses an incomplete sweep unless asked, and then writes nothing half-done.
  r = run_cli({"sweep", "merge", dir.string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("1 of 4 jobs are not done (p0000-r01 failed)"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "summary"));
  r = run_cli({"sweep", "merge", dir.string(), "--allow-missing", "--no-plots"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("merged 3 runs"), std::string::npos) << r.out;
  // A covariate that is not a column: an error naming it, the old summary left as it was.
  const std::string before = slurp(dir / "summary/metrics.json");
  r = run_cli({"sweep", "merge", dir.string(), "--allow-missing", "--covariates", "v,wind"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--covariates: got 'wind', expected a column of the pooled sections"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(slurp(dir / "summary/metrics.json"), before);
  fs::remove_all(dir);
}

TEST(SweepCli, OneLocalRunnerAtATime) {
  const fs::path dir = temp_dir("locked");
  Result r =
      run_cli({"sweep", "plan", (kSweeps / "tiny_grid.yaml").string(), "--out", dir.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // Another runner holds the folder's lock (the protocol is flock(2) on .sweep-run.lock).
  const int fd = ::open((dir / ".sweep-run.lock").c_str(), O_RDWR | O_CREAT, 0644);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX | LOCK_NB), 0);
  r = run_cli({"sweep", "run", dir.string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("another `driftlab sweep run` is running the jobs of this folder"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir / "runs"));
  ::close(fd);
  fs::remove_all(dir);
}

TEST(SweepCli, MergeRegressesAnyRunMetricOnTheAxes) {
  const fs::path dir = temp_dir("run_regress");
  Result r =
      run_cli({"sweep", "plan", (kSweeps / "tiny_grid.yaml").string(), "--out", dir.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_cli({"sweep", "run", dir.string(), "-j", "2"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  r = run_cli({"sweep", "merge", dir.string(), "--no-plots", "--regress", "ape_trans_rmse_m"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("expected METRIC~AXIS[+AXIS...]"), std::string::npos) << r.err;
  r = run_cli({"sweep", "merge", dir.string(), "--no-plots", "--regress", "ape_trans_rmse_m~wind"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("got axis 'wind', expected a numeric axis of the sweep: yaw_amp_deg"),
            std::string::npos)
      << r.err;
  r = run_cli(
      {"sweep", "merge", dir.string(), "--no-plots", "--regress", "ape_trans_rmse_m~yaw_amp_deg"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // The slope by hand from runs.csv: cov(x, y) / var(x) over the 4 runs.
  std::istringstream csv(slurp(dir / "summary/runs.csv"));
  std::string line;
  std::getline(csv, line);
  const auto header = split_csv_line(line);
  const auto col = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find(header.begin(), header.end(), name) - header.begin());
  };
  std::vector<double> x, y;
  while (std::getline(csv, line)) {
    const auto cells = split_csv_line(line);
    if (cells[col("algorithm")] != "sparse") continue;
    x.push_back(std::stod(cells[col("yaw_amp_deg")]));
    y.push_back(std::stod(cells[col("ape_trans_rmse_m")]));
  }
  ASSERT_EQ(x.size(), 4u);
  const double mx = (x[0] + x[1] + x[2] + x[3]) / 4, my = (y[0] + y[1] + y[2] + y[3]) / 4;
  double sxy = 0, sxx = 0;
  for (std::size_t i = 0; i < 4; ++i) {
    sxy += (x[i] - mx) * (y[i] - my);
    sxx += (x[i] - mx) * (x[i] - mx);
  }
  const auto m = nlohmann::json::parse(slurp(dir / "summary/metrics.json"));
  const auto& fit = m["algorithms"]["sparse"]["run_regressions"]["ape_trans_rmse_m~yaw_amp_deg"];
  EXPECT_EQ(fit["n"], 4);
  EXPECT_NEAR(fit["coefficients"]["yaw_amp_deg"]["estimate"].get<double>(), sxy / sxx,
              1e-12 * std::max(1.0, std::abs(sxy / sxx)));
  EXPECT_NE(slurp(dir / "summary/summary.md")
                .find("Regression of `ape_trans_rmse_m` on `yaw_amp_deg` over the runs"),
            std::string::npos);
  // The sweep folder's files read back into their typed records and write the same bytes.
  const auto summary =
      read_json_record<SweepSummaryRecord>(dir / "summary/metrics.json", "summary");
  EXPECT_EQ(json_text(summary), slurp(dir / "summary/metrics.json"));
  const auto* typed_fit =
      summary.algorithms.find("sparse")->run_regressions->find("ape_trans_rmse_m~yaw_amp_deg");
  ASSERT_NE(typed_fit, nullptr);
  EXPECT_EQ(typed_fit->coefficients.find("yaw_amp_deg")->estimate,
            fit["coefficients"]["yaw_amp_deg"]["estimate"].get<double>());
  const auto marker = read_json_record<JobMarkerRecord>(dir / "runs/p0000-r00/job.json", "marker");
  EXPECT_EQ(json_text(marker), slurp(dir / "runs/p0000-r00/job.json"));
  const SweepManifest manifest = read_manifest(dir);
  EXPECT_EQ(record_json::to_json(manifest.info).dump(2) + "\n", slurp(dir / "sweep.json"));
  fs::remove_all(dir);
}

TEST(SweepCli, BuiltInAndExternalVoSideBySideMergeIntoOneTable) {
  // An external VO (here driftlab's own sparse VO behind a command) in every job.
  const fs::path root = temp_dir("external");
  fs::create_directories(root);
  const std::string script = (kSource / "tests/data/external_vo/driftlab_sparse.sh").string();
  std::ofstream(root / "sweep.yaml")
      << "name: tiny_external\nbase: " << (kSweeps / "tiny_base.yaml").string()
      << "\nseed: 3\ndesign: grid\nset:\n  pipeline.fusion: []\n  pipeline.external_vo: "
         "[{name: mine, command: 'sh "
      << script
      << " {driftlab} {dir} {root} {out}'}]\naxes:\n  - key: mission.yaw_weave.amplitude_deg\n"
         "    name: yaw_amp_deg\n    values: [0, 20]\n";
  Result r =
      run_cli({"sweep", "plan", (root / "sweep.yaml").string(), "--out", (root / "plan").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_cli({"sweep", "run", (root / "plan").string(), "-j", "1"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  r = run_cli({"sweep", "merge", (root / "plan").string(), "--no-plots"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  const std::string runs = slurp(root / "plan" / "summary" / "runs.csv");
  std::istringstream lines(runs);
  std::string line;
  std::getline(lines, line);
  std::size_t sparse = 0, mine = 0;
  while (std::getline(lines, line)) {
    sparse += line.find(",sparse,") != std::string::npos ? 1 : 0;
    mine += line.find(",mine,") != std::string::npos ? 1 : 0;
  }
  EXPECT_EQ(sparse, 2u) << runs;
  EXPECT_EQ(mine, 2u) << runs;
  fs::remove_all(root);
}

TEST(SweepCli, JobsDifferingOnlyInVoOptionsRenderTheirFramesOnce) {
  // Two VO settings x two replicates, two jobs at once, one frame cache: each
  // replicate's frames (its seed) are rendered by one job and replayed by the other, even when
  // both start together. Then the merge's paired comparisons of the VOs and of the settings.
  const fs::path root = temp_dir("vo_only");
  fs::create_directories(root);
  std::ofstream(root / "sweep.yaml")
      << "name: tiny_vo_only\nbase: " << (kSweeps / "tiny_base.yaml").string()
      << "\nseed: 5\ndesign: grid\nreplicates: 2\naxes:\n"
         "  - key: pipeline.sparse.ransac_iterations\n    name: ransac\n    values: [200, 50]\n";
  Result r =
      run_cli({"sweep", "plan", (root / "sweep.yaml").string(), "--out", (root / "plan").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_cli({"sweep", "run", (root / "plan").string(), "-j", "2", "--frame-cache",
               (root / "frames").string()});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  std::map<std::string, std::multiset<std::string>> states;  // entry -> states of its jobs
  for (const char* job : {"p0000-r00", "p0000-r01", "p0001-r00", "p0001-r01"}) {
    const auto m = nlohmann::json::parse(slurp(root / "plan" / "runs" / job / "metrics.json"));
    states[m["frame_cache"]["entry"].get<std::string>()].insert(
        m["frame_cache"]["state"].get<std::string>());
  }
  ASSERT_EQ(states.size(), 2u);  // one frame sequence per replicate
  for (const auto& [entry, s] : states) {
    EXPECT_EQ(s, (std::multiset<std::string>{"filled", "hit"})) << entry;
    EXPECT_TRUE(fs::exists(fs::path(entry) / "index.csv")) << entry;
  }

  // The merge's paired comparisons against the runs' own metrics.json: sparse_ca against
  // sparse on the four jobs, and the second RANSAC setting against the first on the two
  // replicates.
  r = run_cli({"sweep", "merge", (root / "plan").string(), "--no-plots"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  const auto merged = nlohmann::json::parse(slurp(root / "plan" / "summary" / "metrics.json"));
  auto ape = [&](const char* job, const char* algo) {
    const auto m = nlohmann::json::parse(slurp(root / "plan" / "runs" / job / "metrics.json"));
    return m["algorithms"][algo]["ape"]["trans_m"]["rmse"].get<double>();
  };
  double diff = 0;
  for (const char* job : {"p0000-r00", "p0000-r01", "p0001-r00", "p0001-r01"})
    diff += (ape(job, "sparse_ca") - ape(job, "sparse")) / 4;
  const auto& vo = merged["paired"]["sparse_ca vs sparse"]["ape_trans_rmse_m"];
  EXPECT_EQ(vo["pairs"], 4);
  EXPECT_NEAR(vo["diff"].get<double>(), diff, 1e-12);
  const auto& pt = merged["paired_points"]["sparse"]["p0001 vs p0000"]["ape_trans_rmse_m"];
  EXPECT_EQ(pt["pairs"], 2);
  EXPECT_NEAR(pt["mean_a"].get<double>(),
              (ape("p0000-r00", "sparse") + ape("p0000-r01", "sparse")) / 2, 1e-12);
  EXPECT_NEAR(pt["mean_b"].get<double>(),
              (ape("p0001-r00", "sparse") + ape("p0001-r01", "sparse")) / 2, 1e-12);
  EXPECT_NE(
      slurp(root / "plan" / "summary" / "summary.md").find("## Paired comparisons of the points"),
      std::string::npos);
  fs::remove_all(root);
}

}  // namespace
}  // namespace driftlab::study
