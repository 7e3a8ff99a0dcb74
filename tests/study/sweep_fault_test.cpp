// Faults in long work: a sweep whose runner is killed at random
// points, whose jobs crash, hang or are killed, and whose disk fills up must
//  - never leave a result that looks complete and is not (every runs/ID is the
//    byte-for-byte result of an undisturbed run of the same plan),
//  - say in `sweep status` what happened to each job and what to run next,
//  - finish when run again, and merge into the same tables as the undisturbed sweep.
// The faults are real: signals to real processes, a job executable that crashes or
// hangs (a shell wrapper around driftlab), a 2 MB tmpfs.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <thread>

#include <nlohmann/json.hpp>

#include "core/process.hpp"
#include "study/sweep.hpp"
#include "study/sweep_runner.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::study {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using test::CommandResult;
using test::run_cli;
using test::shell_quote;
using test::slurp;

const fs::path kTinyGrid = test::source_dir() / "tests/data/sweeps/tiny_grid.yaml";
const std::vector<std::string> kSummaryFiles = {"sections.csv", "runs.csv", "points.csv",
                                                "metrics.json", "summary.md"};

bool is_temporary(const fs::path& p) {
  const std::string name = p.filename().string();
  return name.find(".tmp.") != std::string::npos || name.find(".old.") != std::string::npos;
}

// The files of a finished run and their bytes, without what differs between two
// undisturbed runs: the completion marker (host, wall time), the timing block of
// metrics.json, its frame cache's state (with DRIFTLAB_FRAME_CACHE set, the first run
// fills the cache and the next ones hit it) and frames.csv's per-frame milliseconds (only
// its row count is kept).
std::map<std::string, std::string> run_contents(const fs::path& run) {
  std::map<std::string, std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(run)) {
    if (!e.is_regular_file()) continue;
    const std::string rel = fs::relative(e.path(), run).string();
    std::string bytes = slurp(e.path());
    if (rel == "job.json") continue;
    if (rel == "frames.csv") bytes = std::to_string(std::count(bytes.begin(), bytes.end(), '\n'));
    if (rel == "metrics.json") {
      auto j = nlohmann::json::parse(bytes);
      j.erase("timing");
      if (j.contains("frame_cache")) j["frame_cache"].erase("state");
      bytes = j.dump();
    }
    out[rel] = bytes;
  }
  return out;
}

CommandResult plan(const fs::path& dir) {
  return run_cli({"sweep", "plan", kTinyGrid.string(), "--out", dir.string()});
}

// One undisturbed sweep of tiny_grid (4 jobs), merged: what every disturbed one must equal.
class SweepFaults : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = test::fresh_temp_dir("sweep_faults");
    reference_ = root_ / "reference";
    ASSERT_EQ(plan(reference_).exit_code, 0);
    const CommandResult r = run_cli({"sweep", "run", reference_.string(), "-j", "2"});
    ASSERT_EQ(r.exit_code, 0) << r.output;
    ASSERT_EQ(run_cli({"sweep", "merge", reference_.string(), "--no-plots"}).exit_code, 0);
    for (const auto& e : fs::directory_iterator(reference_ / "runs"))
      expected_[e.path().filename().string()] = run_contents(e.path());
    ASSERT_EQ(expected_.size(), 4u);
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(root_);
  }

  // Every runs/ID that is not a temporary is complete and equal to the undisturbed run;
  // returns how many there are.
  std::size_t expect_only_complete_results(const fs::path& dir, const std::string& when) {
    std::size_t complete = 0;
    if (!fs::exists(dir / "runs")) return 0;
    for (const auto& e : fs::directory_iterator(dir / "runs")) {
      if (is_temporary(e.path())) continue;
      const std::string id = e.path().filename().string();
      EXPECT_TRUE(fs::exists(e.path() / "job.json")) << when << ": runs/" << id << " has no marker";
      EXPECT_TRUE(run_contents(e.path()) == expected_.at(id))
          << when << ": runs/" << id << " differs from the undisturbed run";
      ++complete;
    }
    return complete;
  }

  // Runs what is left, merges, and checks the summary against the undisturbed sweep.
  void expect_resume_finishes(const fs::path& dir, std::size_t done_before) {
    CommandResult r = run_cli({"sweep", "run", dir.string(), "-j", "2"});
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.out.find(fmt::format("4 jobs: ran {}, 0 failed, {} already done", 4 - done_before,
                                     done_before)),
              std::string::npos)
        << r.out;
    EXPECT_EQ(expect_only_complete_results(dir, "resumed"), 4u);
    r = run_cli({"sweep", "status", dir.string()});
    EXPECT_NE(r.out.find("4 jobs: 4 done, 0 failed, 0 stale, 0 missing"), std::string::npos)
        << r.out;
    ASSERT_EQ(run_cli({"sweep", "merge", dir.string(), "--no-plots"}).exit_code, 0);
    for (const auto& f : kSummaryFiles)
      EXPECT_TRUE(slurp(dir / "summary" / f) == slurp(reference_ / "summary" / f)) << f;
  }

  fs::path root_, reference_;
  std::map<std::string, std::map<std::string, std::string>> expected_;
};

// Waits until no process of the group is left (the runner and its jobs).
bool group_gone(pid_t pgid, std::chrono::seconds limit) {
  const auto deadline = Clock::now() + limit;
  while (Clock::now() < deadline) {
    if (::kill(-pgid, 0) != 0 && errno == ESRCH) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

TEST_F(SweepFaults, RunnerKilledAtRandomPointsLeavesOnlyCompleteResultsAndResumes) {
  const fs::path dir = root_ / "killed";
  ASSERT_EQ(plan(dir).exit_code, 0);
  // Five interruptions at random points of a 2-at-a-time run (~1 s a job), each
  // one of: SIGKILL to the runner alone (its jobs get SIGTERM as it dies), SIGKILL to the
  // runner and its jobs at once (the OOM killer, a lost node), SIGTERM to the runner (scancel).
  std::mt19937 rng(20261124);
  std::uniform_int_distribution<int> delay_ms(200, 1600), how(0, 2);
  int mid_job = 0;  // rounds that interrupted a job (it left a temporary)
  for (int round = 0; round < 5; ++round) {
    const int wait = delay_ms(rng), mode = how(rng);
    const std::string when = fmt::format("round {} (mode {} after {} ms)", round, mode, wait);
    ProcessSpec spec;  // setsid: the runner leads a process group of its own and its jobs
    spec.executable = "/usr/bin/setsid";
    spec.args = {test::cli_path().string(), "sweep", "run", dir.string(), "-j", "2"};
    spec.output_file = root_ / fmt::format("round{}.log", round);
    const pid_t pid = spawn_process(spec);
    std::this_thread::sleep_for(std::chrono::milliseconds(wait));
    if (mode == 0) ::kill(pid, SIGKILL);
    if (mode == 1) ::kill(-pid, SIGKILL);
    if (mode == 2) ::kill(pid, SIGTERM);
    wait_process(pid);
    ASSERT_TRUE(group_gone(pid, std::chrono::seconds(30))) << when << ": jobs outlived the runner";

    const std::size_t complete = expect_only_complete_results(dir, when);
    const CommandResult st = run_cli({"sweep", "status", dir.string()});
    ASSERT_EQ(st.exit_code, 0) << st.output;
    EXPECT_NE(st.out.find(fmt::format("4 jobs: {} done, 0 failed, 0 stale, {} missing", complete,
                                      4 - complete)),
              std::string::npos)
        << when << "\n"
        << st.out;
    // Each job that left a temporary is named as interrupted, with what to run next.
    const auto leftovers = leftover_temporaries(read_manifest(dir), false);
    mid_job += !leftovers.empty();
    for (const auto& p : leftovers) {
      const std::string name = p.filename().string(), id = name.substr(0, name.find('.'));
      EXPECT_NE(st.out.find(id + "  interrupted: runs/" + id + ".tmp."), std::string::npos)
          << when << "\n"
          << st.out;
    }
    if (complete < 4) {
      EXPECT_NE(st.out.find("finish locally:   driftlab sweep run " + dir.string() + " -j N"),
                std::string::npos)
          << st.out;
    }
  }
  EXPECT_GT(mid_job, 0) << "no kill landed while a job ran: the test tested nothing";
  expect_resume_finishes(dir, expect_only_complete_results(dir, "before resuming"));
}

// A job executable with faults: job p0000-r01 crashes before it starts, p0001-r00 hangs,
// p0001-r01 is killed (SIGKILL, as by the OOM killer) while driftlab runs it.
fs::path write_faulty_driftlab(const fs::path& dir) {
  const fs::path wrapper = dir / "faulty-driftlab";
  std::ofstream(wrapper) << "#!/bin/sh\n"
                         << "case \"$*\" in\n"
                         << "  *'--job p0000-r01'*) kill -SEGV $$ ;;\n"
                         << "  *'--job p0001-r00'*) exec sleep 600 ;;\n"
                         << "  *'--job p0001-r01'*)\n"
                         << "    " << shell_quote(test::cli_path().string()) << " \"$@\" &\n"
                         << "    sleep 0.3; kill -KILL $!; wait $!; kill -KILL $$ ;;\n"
                         << "esac\n"
                         << "exec " << shell_quote(test::cli_path().string()) << " \"$@\"\n";
  fs::permissions(wrapper, fs::perms::owner_all);
  return wrapper;
}

TEST_F(SweepFaults, CrashingHangingAndKilledJobsAreRecordedAndRunAgain) {
  const fs::path dir = root_ / "faulty";
  ASSERT_EQ(plan(dir).exit_code, 0);
  const SweepManifest m = read_manifest(dir);
  SweepRunOptions o;
  o.executable = write_faulty_driftlab(root_);
  o.parallel = 2;
  o.job_timeout_s = 3;
  const auto t0 = Clock::now();
  const SweepRunSummary s = run_sweep_jobs(m, o);
  EXPECT_LT(std::chrono::duration<double>(Clock::now() - t0).count(), 60.0)
      << "the hanging job was not stopped";
  EXPECT_EQ(s.ran, 4u);
  EXPECT_EQ(s.failed, 3u);
  EXPECT_EQ(s.failed_ids, (std::vector<std::string>{"p0000-r01", "p0001-r00", "p0001-r01"}));
  EXPECT_EQ(expect_only_complete_results(dir, "after the faults"), 1u);

  const CommandResult st = run_cli({"sweep", "status", dir.string()});
  EXPECT_NE(st.out.find("4 jobs: 1 done, 3 failed, 0 stale, 0 missing"), std::string::npos)
      << st.out;
  for (const char* what :
       {"p0000-r01  killed by signal 11 (Segmentation fault)",
        "p0001-r00  timeout: still running after --job-timeout 3 s, stopped (killed by signal 15",
        "p0001-r01  killed by signal 9 (Killed)", "(failed/p0001-r01.json, logs/p0001-r01.log)"})
    EXPECT_NE(st.out.find(what), std::string::npos) << what << "\n" << st.out;
  expect_resume_finishes(dir, 1);
}

// A tmpfs mounted over a folder for the life of the object; unmounted (lazily) after.
class SmallDisk {
 public:
  SmallDisk(const fs::path& at, const std::string& size) : at_(at) {
    fs::create_directories(at);
    mounted_ = ::mount("tmpfs", at.c_str(), "tmpfs", 0, ("size=" + size).c_str()) == 0;
    error_ = mounted_ ? "" : std::strerror(errno);
  }
  ~SmallDisk() {
    if (mounted_) ::umount2(at_.c_str(), MNT_DETACH);
  }
  bool grow(const std::string& size) {
    return ::mount("tmpfs", at_.c_str(), "tmpfs", MS_REMOUNT, ("size=" + size).c_str()) == 0;
  }
  bool mounted() const { return mounted_; }
  const std::string& error() const { return error_; }

 private:
  fs::path at_;
  bool mounted_ = false;
  std::string error_;
};

TEST_F(SweepFaults, FullDiskFailsJobsCleanlyAndTheSweepFinishesOnceThereIsRoom) {
  const fs::path disk = root_ / "disk";
  SmallDisk small(disk, "2m");  // a finished tiny run takes ~0.75 MB
  if (!small.mounted())
    GTEST_SKIP() << "cannot mount a tmpfs here (" << small.error()
                 << "); the test needs root or CAP_SYS_ADMIN";
  const fs::path dir = disk / "sweep";
  ASSERT_EQ(plan(dir).exit_code, 0);
  CommandResult r = run_cli({"sweep", "run", dir.string(), "-j", "1"});
  EXPECT_NE(r.exit_code, 0) << r.output;
  const std::size_t complete = expect_only_complete_results(dir, "disk full");
  EXPECT_GE(complete, 1u);
  EXPECT_LT(complete, 4u) << "2 MB held the whole sweep; the test no longer fills the disk";

  r = run_cli({"sweep", "status", dir.string()});
  EXPECT_NE(r.out.find(fmt::format("4 jobs: {} done, {} failed", complete, 4 - complete)),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("No space left on device"), std::string::npos) << r.out;
  EXPECT_TRUE(leftover_temporaries(read_manifest(dir), false).empty()) << "failed jobs left files";

  ASSERT_TRUE(small.grow("64m"));
  expect_resume_finishes(dir, complete);
}

}  // namespace
}  // namespace driftlab::study
