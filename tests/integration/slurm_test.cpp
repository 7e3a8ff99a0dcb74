// The Slurm path of sweeps on a real, single-node Slurm cluster started by the
// test (Debian's slurm-wlm and munge, set up by the helpers below): munged with its own
// key, slurmctld and slurmd on 127.0.0.1, every file under a temporary folder. A
// 4-job sweep is submitted as a job array of shards; its merged tables must
// equal those of a local `sweep run` of the same plan, and the resubmission
// line of `sweep status` must rerun exactly the shard of a deleted run.
// Skipped when slurmctld is not installed (scripts/setup-deps installs it).
//
// The daemons run in the foreground (munged -F, slurmctld -D, slurmd -D) so
// that they are this test's children: it stops each by its PID (SIGTERM) and
// waits for it to exit, and they get SIGTERM should the test die first.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <thread>

#include "core/process.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::study {
namespace {

using test::shell_quote;
using test::slurp;

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
const fs::path kSource = DRIFTLAB_SOURCE_DIR;
const fs::path kCli = fs::path(DRIFTLAB_BINARY_DIR) / "bin" / "driftlab";

std::optional<fs::path> find_program(const std::string& name) {
  if (auto p = find_on_path(name)) return p;
  for (const char* dir : {"/usr/sbin", "/usr/local/sbin", "/sbin"}) {
    const fs::path p = fs::path(dir) / name;
    if (::access(p.c_str(), X_OK) == 0) return p;
  }
  return std::nullopt;
}

struct Result {
  int exit_code;
  std::string out;
};

// Runs a shell command line; stdout and stderr together.
Result sh(const std::string& command) {
  const std::string log =
      (fs::temp_directory_path() / ("driftlab_slurm_sh_" + std::to_string(::getpid()))).string();
  const int status = std::system((command + " > " + shell_quote(log) + " 2>&1").c_str());
  Result r{WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(log)};
  fs::remove(log);
  return r;
}

class SlurmCluster : public ::testing::Test {
 protected:
  void SetUp() override {
    for (const char* p : {"slurmctld", "slurmd", "munged", "sbatch", "sinfo", "squeue"}) {
      auto found = find_program(p);
      if (!found)
        GTEST_SKIP() << p
                     << " is not installed (scripts/setup-deps installs slurm-wlm "
                        "and munge)";
      programs_[p] = *found;
    }
    root_ = fs::temp_directory_path() / ("driftlab_slurm_" + std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_);
    ::chmod(root_.c_str(), 0755);  // munged checks every folder on the socket's path

    // munge: key in a 700 folder, socket folder 755.
    const fs::path etc = root_ / "munge/etc", run = root_ / "munge/run";
    fs::create_directories(etc);
    fs::create_directories(run);
    fs::create_directories(root_ / "munge/lib");
    fs::create_directories(root_ / "munge/log");
    ::chmod((root_ / "munge").c_str(), 0755);
    ::chmod(etc.c_str(), 0700);
    ::chmod(run.c_str(), 0755);
    {
      std::random_device rd;
      std::string key(1024, '\0');
      for (char& c : key) c = static_cast<char>(rd() & 0xff);
      std::ofstream(etc / "munge.key", std::ios::binary) << key;
      ::chmod((etc / "munge.key").c_str(), 0600);
    }
    socket_ = run / "munge.socket";
    start("munged", {"-F", "--key-file=" + (etc / "munge.key").string(),
                     "--socket=" + socket_.string(), "--pid-file=" + (run / "munged.pid").string(),
                     "--log-file=" + (root_ / "munge/log/munged.log").string(),
                     "--seed-file=" + (root_ / "munge/lib/munged.seed").string()});
    ASSERT_TRUE(wait_for([&] { return fs::exists(socket_); }, std::chrono::seconds(30)))
        << slurp(root_ / "munged.out");

    // slurm.conf: the node and every path under root_, ports of our own.
    for (const char* d : {"state", "spool", "log"}) fs::create_directories(root_ / d);
    const int port = 20000 + static_cast<int>(::getpid() % 10000) * 2;
    conf_ = root_ / "slurm.conf";
    std::ofstream(conf_) << "ClusterName=driftlab\n"
                         << "SlurmctldHost=localhost\n"
                         << "SlurmctldPort=" << port << "\n"
                         << "SlurmdPort=" << port + 1 << "\n"
                         << "AuthType=auth/munge\n"
                         << "AuthInfo=socket=" << socket_.string() << "\n"
                         << "CredType=cred/munge\n"
                         << "ProctrackType=proctrack/linuxproc\n"
                         << "TaskPlugin=task/none\n"
                         << "SelectType=select/cons_tres\n"
                         << "AccountingStorageType=accounting_storage/none\n"
                         << "JobAcctGatherType=jobacct_gather/none\n"
                         << "SlurmUser=root\n"
                         << "StateSaveLocation=" << (root_ / "state").string() << "\n"
                         << "SlurmdSpoolDir=" << (root_ / "spool").string() << "\n"
                         << "SlurmctldPidFile=" << (root_ / "slurmctld.pid").string() << "\n"
                         << "SlurmdPidFile=" << (root_ / "slurmd.pid").string() << "\n"
                         << "SlurmctldLogFile=" << (root_ / "log/slurmctld.log").string() << "\n"
                         << "SlurmdLogFile=" << (root_ / "log/slurmd.log").string() << "\n"
                         << "ReturnToService=2\n"
                         << "NodeName=localhost NodeAddr=127.0.0.1 CPUs=2 State=UNKNOWN\n"
                         << "PartitionName=debug Nodes=localhost Default=YES MaxTime=INFINITE "
                            "State=UP\n";
    start("slurmctld", {"-D", "-f", conf_.string()});
    start("slurmd", {"-D", "-f", conf_.string(), "-N", "localhost"});
    ASSERT_TRUE(
        wait_for([&] { return slurm("sinfo -h -o %t").out == "idle\n"; }, std::chrono::seconds(60)))
        << "the node never became idle: " << slurm("sinfo -h -o %t").out
        << slurp(root_ / "slurmctld.out") << slurp(root_ / "slurmd.out");
  }

  void TearDown() override {
    // Reverse order of start; each stopped by its PID and waited for, so that a
    // later cluster does not race an old controller.
    for (auto it = daemons_.rbegin(); it != daemons_.rend(); ++it) {
      ::kill(it->second, SIGTERM);
      const auto deadline = Clock::now() + std::chrono::seconds(30);
      std::optional<ExitStatus> st;
      while (!(st = try_wait_process(it->second)) && Clock::now() < deadline)
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      if (!st) {
        ::kill(it->second, SIGKILL);
        wait_process(it->second);
        ADD_FAILURE() << it->first << " did not stop on SIGTERM";
      }
    }
    daemons_.clear();
    if (!root_.empty() && !HasFailure()) fs::remove_all(root_);
  }

  void start(const std::string& name, const std::vector<std::string>& args) {
    ProcessSpec spec;
    spec.executable = programs_.at(name);
    spec.args = args;
    spec.output_file = root_ / (name + ".out");
    daemons_.emplace_back(name, spawn_process(spec));
  }

  template <class F>
  static bool wait_for(F ready, std::chrono::seconds limit) {
    const auto deadline = Clock::now() + limit;
    while (Clock::now() < deadline) {
      if (ready()) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
    return ready();
  }

  Result slurm(const std::string& command_line) {
    return sh("SLURM_CONF=" + shell_quote(conf_.string()) + " " + command_line);
  }

  Result driftlab(const std::vector<std::string>& args) {
    std::string cmd = shell_quote(kCli.string());
    for (const auto& a : args) cmd += " " + shell_quote(a);
    return sh(cmd);
  }

  // Submits a command line that starts with "sbatch" and waits for every task of the job.
  // (`sbatch --wait` polls with growing intervals; squeue -t all shows finished tasks too.)
  std::string submit_and_wait(const std::string& sbatch_line) {
    const Result sub = slurm(sbatch_line.substr(0, 6) + " --parsable" + sbatch_line.substr(6));
    EXPECT_EQ(sub.exit_code, 0) << sub.out;
    const std::string id = sub.out.substr(0, sub.out.find_first_of(";\n"));
    std::string states;
    const bool done = wait_for(
        [&] {
          states = slurm("squeue -h -j " + id + " -t all -o '%i %T'").out;
          for (const char* busy : {"PENDING", "RUNNING", "CONFIGURING", "COMPLETING"})
            if (states.find(busy) != std::string::npos) return false;
          return !states.empty();
        },
        std::chrono::seconds(600));
    EXPECT_TRUE(done) << states;
    return states;
  }

  std::map<std::string, fs::path> programs_;
  std::vector<std::pair<std::string, pid_t>> daemons_;
  fs::path root_, socket_, conf_;
};

TEST_F(SlurmCluster, ArrayOfShardsMergesLikeALocalRunAndResubmitsOnlyUnfinishedShards) {
  const fs::path on_slurm = root_ / "on_slurm", local = root_ / "local";
  const std::string sweep = (kSource / "tests/data/sweeps/tiny_grid.yaml").string();
  for (const auto& d : {on_slurm, local}) {
    const Result r = driftlab({"sweep", "plan", sweep, "--out", d.string()});
    ASSERT_EQ(r.exit_code, 0) << r.out;
  }
  // 4 jobs in 2 shards: task 0 runs jobs 0 and 2, task 1 jobs 1 and 3.
  Result r =
      driftlab({"sweep", "slurm-script", on_slurm.string(), "--shards", "2", "--cpus-per-task", "1",
                "--max-parallel", "2", "--partition", "debug", "--time", "00:10:00"});
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const std::string states =
      submit_and_wait("sbatch " + (on_slurm / "slurm/sweep.sbatch").string());
  EXPECT_EQ(states.find("FAILED"), std::string::npos) << states;
  EXPECT_NE(states.find("_0 COMPLETED"), std::string::npos) << states;
  EXPECT_NE(states.find("_1 COMPLETED"), std::string::npos) << states;
  r = driftlab({"sweep", "status", on_slurm.string()});
  ASSERT_NE(r.out.find("4 jobs: 4 done, 0 failed, 0 stale, 0 missing"), std::string::npos)
      << r.out << slurp(on_slurm / "slurm/logs");

  r = driftlab({"sweep", "run", local.string(), "-j", "2"});
  ASSERT_EQ(r.exit_code, 0) << r.out;
  for (const auto& d : {on_slurm, local}) {
    r = driftlab({"sweep", "merge", d.string(), "--no-plots"});
    ASSERT_EQ(r.exit_code, 0) << r.out;
  }
  for (const char* f : {"sections.csv", "runs.csv", "points.csv", "metrics.json", "summary.md"}) {
    const std::string a = slurp(on_slurm / "summary" / f);
    EXPECT_FALSE(a.empty()) << f;
    EXPECT_TRUE(a == slurp(local / "summary" / f)) << f << " differs";
  }

  // Lose job 2 (p0001-r00, shard 0): status names shard 0 only; resubmitting it
  // reruns that job and skips shard 0's finished job 0.
  const std::string job0_marker = slurp(on_slurm / "runs/p0000-r00/job.json");
  fs::remove_all(on_slurm / "runs/p0001-r00");
  r = driftlab({"sweep", "status", on_slurm.string()});
  const std::string expected =
      "sbatch --array=0%2 '" + (on_slurm / "slurm/sweep.sbatch").string() + "'";
  ASSERT_NE(r.out.find(expected), std::string::npos) << r.out;
  submit_and_wait(expected);
  r = driftlab({"sweep", "status", on_slurm.string()});
  EXPECT_NE(r.out.find("4 jobs: 4 done"), std::string::npos) << r.out;
  EXPECT_EQ(slurp(on_slurm / "runs/p0000-r00/job.json"), job0_marker);
  r = driftlab({"sweep", "merge", on_slurm.string(), "--no-plots"});
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_TRUE(slurp(on_slurm / "summary/sections.csv") == slurp(local / "summary/sections.csv"));
}

// An array task that dies (SIGKILL once its first job is done, as when a node is lost or
// the task is killed for memory): `sweep status` names the interrupted job and prints the
// sbatch line for that task alone; resubmitting it finishes the sweep and keeps the job
// the dead task had finished.
TEST_F(SlurmCluster, AFailedArrayTaskIsResubmittedAloneAndFinishesTheSweep) {
  const fs::path dir = root_ / "task_fails";
  Result r = driftlab({"sweep", "plan", (kSource / "tests/data/sweeps/tiny_grid.yaml").string(),
                       "--out", dir.string()});
  ASSERT_EQ(r.exit_code, 0) << r.out;
  // Task 1 (jobs p0000-r01 and p0001-r01) runs driftlab and kills it after its first job
  // while the file FAULT exists.
  const fs::path wrapper = root_ / "driftlab-on-a-bad-node", fault = root_ / "FAULT";
  std::ofstream(wrapper) << "#!/bin/sh\n"
                         << "case \"$*\" in *'--shard 1/2'*) if [ -e "
                         << shell_quote(fault.string()) << " ]; then\n"
                         << "  " << shell_quote(kCli.string()) << " \"$@\" & pid=$!\n"
                         << "  while [ ! -e "
                         << shell_quote((dir / "runs/p0000-r01/job.json").string())
                         << " ]; do sleep 0.05; done\n"
                         << "  kill -KILL $pid; exit 137\n"
                         << "fi ;; esac\n"
                         << "exec " << shell_quote(kCli.string()) << " \"$@\"\n";
  fs::permissions(wrapper, fs::perms::owner_all | fs::perms::group_read | fs::perms::others_read);
  std::ofstream(fault) << "1\n";
  r = driftlab({"sweep", "slurm-script", dir.string(), "--shards", "2", "--max-parallel", "2",
                "--partition", "debug", "--driftlab", wrapper.string()});
  ASSERT_EQ(r.exit_code, 0) << r.out;
  std::string states = submit_and_wait("sbatch " + (dir / "slurm/sweep.sbatch").string());
  EXPECT_NE(states.find("_0 COMPLETED"), std::string::npos) << states;
  EXPECT_NE(states.find("_1 FAILED"), std::string::npos) << states;

  r = driftlab({"sweep", "status", dir.string()});
  EXPECT_NE(r.out.find("4 jobs: 3 done, 0 failed, 0 stale, 1 missing"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("missing:\n  p0001-r01"), std::string::npos) << r.out;
  const std::string resubmit = "sbatch --array=1%2 '" + (dir / "slurm/sweep.sbatch").string() + "'";
  ASSERT_NE(r.out.find(resubmit), std::string::npos) << r.out;
  for (const auto& e : fs::directory_iterator(dir / "runs")) {
    const std::string name = e.path().filename().string();
    if (name.find(".tmp.") != std::string::npos) {
      const std::string id = name.substr(0, name.find('.'));
      EXPECT_NE(r.out.find(id + "  interrupted: runs/" + id + ".tmp."), std::string::npos) << r.out;
    } else {
      EXPECT_TRUE(fs::exists(e.path() / "job.json")) << name << " looks finished but is not";
    }
  }

  const std::string finished_by_the_dead_task = slurp(dir / "runs/p0000-r01/job.json");
  fs::remove(fault);
  states = submit_and_wait(resubmit);
  EXPECT_NE(states.find("_1 COMPLETED"), std::string::npos) << states;
  r = driftlab({"sweep", "status", dir.string()});
  EXPECT_NE(r.out.find("4 jobs: 4 done, 0 failed, 0 stale, 0 missing"), std::string::npos) << r.out;
  EXPECT_EQ(slurp(dir / "runs/p0000-r01/job.json"), finished_by_the_dead_task);
}

}  // namespace
}  // namespace driftlab::study
