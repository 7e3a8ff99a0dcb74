#include "study/sweep_runner.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <signal.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <thread>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/file_io.hpp"
#include "core/process.hpp"
#include "core/yaml_io.hpp"
#include "pipeline/scenario.hpp"

#ifndef DRIFTLAB_VERSION
#define DRIFTLAB_VERSION "unknown"
#endif

namespace driftlab::study {

using pipeline::parse_scenario;
using pipeline::run_scenario;
using pipeline::RunOptions;
using pipeline::Scenario;
namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

std::string host_name() {
  char buf[256] = {};
  if (::gethostname(buf, sizeof buf - 1) != 0) return "unknown";
  return buf;
}

// The last lines of a log (at most ~4 KB), for failure records.
std::string tail_of(const std::string& text, std::size_t max_lines = 20) {
  std::string t = text.size() > 4096 ? text.substr(text.size() - 4096) : text;
  while (!t.empty() && t.back() == '\n') t.pop_back();
  std::size_t pos = t.size(), lines = 0;
  while (pos > 0 && lines < max_lines) {
    pos = t.rfind('\n', pos - 1);
    if (pos == std::string::npos) {
      pos = 0;
      break;
    }
    ++lines;
  }
  return pos == 0 ? t : t.substr(pos + 1);
}

void write_failure(const SweepManifest& m, const SweepJob& job, const std::string& status,
                   const std::string& error, const std::string& log_tail = "") {
  FailureRecord r;
  r.id = job.id;
  r.status = status;
  r.error = error;
  if (!log_tail.empty()) r.log_tail = log_tail;
  r.hash = job.hash;
  r.host = host_name();
  r.log = fs::relative(m.log_file(job.id), m.dir).string();
  fs::create_directories(m.failed_record(job.id).parent_path());
  write_file_atomic(m.failed_record(job.id), json_text(r));
}

void clear_failure(const SweepManifest& m, const SweepJob& job) {
  std::error_code ec;
  fs::remove(m.failed_record(job.id), ec);
}

// What went wrong, for the record the runner writes when a job ends badly: the error
// the job recorded itself (run_manifest_job), else the last line of its output.
std::string job_error(const SweepManifest& m, const SweepJob& job, const std::string& log_tail) {
  std::error_code ec;
  if (fs::exists(m.failed_record(job.id), ec)) {
    try {
      const std::string error = read_json_record<FailureRecord>(m.failed_record(job.id), "record",
                                                                record_json::UnknownKeys::kIgnore)
                                    .error;
      if (!error.empty()) return error;
    } catch (const std::exception&) {
      // Cut short (the job was killed while writing it): fall back to the log.
    }
  }
  const auto nl = log_tail.rfind('\n');
  return nl == std::string::npos ? log_tail : log_tail.substr(nl + 1);
}

// Past the timeout a job gets SIGTERM (driftlab exits; its children get SIGTERM with it),
// and SIGKILL if it is still there kKillGrace_s later.
void stop_if_past_timeout(pid_t pid, double elapsed_s, double timeout_s, int& signals_sent) {
  constexpr double kKillGrace_s = 5;
  if (timeout_s <= 0 || elapsed_s < timeout_s) return;
  if (signals_sent == 0) {
    ::kill(pid, SIGTERM);
    signals_sent = 1;
  } else if (signals_sent == 1 && elapsed_s >= timeout_s + kKillGrace_s) {
    ::kill(pid, SIGKILL);
    signals_sent = 2;
  }
}

const SweepJob& job_or_throw(const SweepManifest& m, const std::string& id) {
  const SweepJob* job = m.find(id);
  if (!job) {
    std::string some;
    for (std::size_t i = 0; i < m.jobs.size() && i < 3; ++i) some += (i ? ", " : "") + m.jobs[i].id;
    throw UserError(
        fmt::format("{}: --job: got '{}', expected the id of one of its {} jobs "
                    "(e.g. {})",
                    m.manifest.string(), id, m.jobs.size(), some));
  }
  return *job;
}

// An exclusive flock(2) on a file, released when the holder exits (even when killed).
class FileLock {
 public:
  FileLock() = default;
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;
  ~FileLock() {
    if (fd_ >= 0) ::close(fd_);
  }
  void acquire(const fs::path& path) {
    fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0)
      throw UserError(fmt::format("{}: cannot write: {}", path.string(), std::strerror(errno)));
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0)
      throw UserError(
          fmt::format("{}: another `driftlab sweep run` is running the jobs of this "
                      "folder, expected one local runner at a time (wait for it, or "
                      "stop it and run again: finished jobs are kept)",
                      path.parent_path().string()));
  }

 private:
  int fd_ = -1;
};

// A job the local runner started.
struct RunningJob {
  pid_t pid;
  const SweepJob* job;
  Clock::time_point start;
  int signals_sent = 0;  // past the timeout: 1 after SIGTERM, 2 after SIGKILL
};

// failed/ID.json for a job that ended without its completion marker; returns what happened.
// A record that cannot be written (a full disk) leaves the job `missing`, to run again.
std::string record_failure(const SweepManifest& m, const RunningJob& r, const ExitStatus& status,
                           const SweepRunOptions& options) {
  std::error_code log_ec;
  const std::string log = fs::exists(m.log_file(r.job->id), log_ec)
                              ? read_text_file(m.log_file(r.job->id), "job log")
                              : std::string();
  std::string why = r.signals_sent > 0 ? fmt::format(
                                             "timeout: still running after --job-timeout {} s, "
                                             "stopped ({})",
                                             options.job_timeout_s, status.describe())
                    : status.ok() ? "exit code 0 but no completion marker"
                                  : status.describe();
  if (options.local && r.signals_sent > 0) leftover_temporaries(m, /*remove=*/true);
  try {
    const std::string log_tail = tail_of(log);
    write_failure(m, *r.job, why, job_error(m, *r.job, log_tail), log_tail);
  } catch (const std::exception& e) {
    const std::string what = e.what();
    why += fmt::format(" (and no failure record: {})", what.substr(0, what.find('\n')));
  }
  return why;
}

}  // namespace

std::string JobRunResult::brief() const {
  if (skipped) return fmt::format("{}: already done, skipped (--force runs it again)", id);
  return fmt::format("{}: {}", id, run.brief());
}

JobRunResult run_manifest_job(const SweepManifest& m, const std::string& id,
                              const JobRunOptions& options) {
  const SweepJob& job = job_or_throw(m, id);
  JobRunResult result;
  result.id = id;
  if (!options.force && job_status(m, job).state == JobState::kDone) {
    result.skipped = true;
    return result;
  }
  const auto t0 = Clock::now();
  try {
    const fs::path scenario_file = m.scenario_file();
    std::error_code ec;
    if (!fs::is_regular_file(scenario_file, ec))
      throw UserError(
          fmt::format("{}: no such file, expected the base scenario that `driftlab "
                      "sweep plan` wrote beside the manifest",
                      scenario_file.string()));
    const Scenario sc = parse_scenario(read_text_file(scenario_file, "scenario file"),
                                       scenario_file.string(), m.base_dir(), job.overrides);
    const std::string hash = fnv1a64_hex(yaml::to_yaml(sc, false));
    if (hash != job.hash)
      throw UserError(fmt::format(
          "{}: job {}: the scenario hashes to {}, the manifest says {}: scenario.yaml or "
          "driftlab's scenario defaults changed since `driftlab sweep plan`; plan again",
          m.manifest.string(), id, hash, job.hash));
    // The run goes into runs/ID.tmp.PID (built there atomically by run_scenario),
    // gets its marker last, and is renamed onto runs/ID.
    AtomicDirectory out(m.run_dir(id), /*replace=*/true);
    RunOptions ro;
    ro.replace_existing = true;  // out.path() exists, empty
    ro.progress = options.progress;
    ro.frame_cache = options.frame_cache;
    result.run = run_scenario(sc, out.path(), ro);
    JobMarkerRecord marker;
    marker.id = job.id;
    marker.hash = job.hash;
    marker.seed = job.seed;
    for (const auto& [name, value] : job.params) marker.params[name] = yaml_text_to_json(value);
    marker.host = host_name();
    marker.wall_s = seconds_since(t0);
    marker.driftlab_version = DRIFTLAB_VERSION;
    write_file_atomic(out.path() / "job.json", json_text(marker));
    out.commit();
    clear_failure(m, job);
  } catch (const std::exception& e) {
    try {
      write_failure(m, job, "failed", e.what());
    } catch (const std::exception&) {
      // The original error is the one to report.
    }
    throw;
  }
  return result;
}

// ---------------------------------------------------------------------------
// Local runner

std::string SweepProgress::line() const {
  const int width = static_cast<int>(std::to_string(total).size());
  std::string s = fmt::format("[{:>{}}/{}] {} running", finished, width, total, running);
  if (failed) s += fmt::format(", {} failed", failed);
  if (skipped) s += fmt::format(", {} already done", skipped);
  if (!last_id.empty())
    s += last_ok ? fmt::format(" | {} done in {:.1f} s", last_id, last_s)
                 : fmt::format(" | {} FAILED ({})", last_id, last_detail);
  s += fmt::format(" | {:.0f} s elapsed", elapsed_s);
  if (finished > 0 && finished < total)
    s += fmt::format(", ~{:.0f} s left", elapsed_s / static_cast<double>(finished) *
                                             static_cast<double>(total - finished));
  return s;
}

std::string SweepRunSummary::brief() const {
  std::string s = fmt::format("{} jobs: ran {}, {} failed, {} already done; {:.1f} s", jobs, ran,
                              failed, skipped, wall_s);
  if (!failed_ids.empty()) {
    s += "; failed:";
    for (const auto& id : failed_ids) s += " " + id;
  }
  return s;
}

SweepRunSummary run_sweep_jobs(const SweepManifest& m, const SweepRunOptions& options) {
  if (options.parallel < 1)
    throw UserError(fmt::format("--parallel: got {}, expected at least 1", options.parallel));
  if (!(options.job_timeout_s >= 0) || !std::isfinite(options.job_timeout_s))
    throw UserError(fmt::format("--job-timeout: got {}, expected seconds >= 0 (0: no limit)",
                                options.job_timeout_s));
  std::error_code ec;
  if (!fs::is_regular_file(options.executable, ec))
    throw UserError(fmt::format("{}: no such executable, expected the driftlab binary",
                                options.executable.string()));
  const auto t0 = Clock::now();
  SweepRunSummary summary;
  FileLock lock;
  if (options.local) {
    lock.acquire(m.dir / ".sweep-run.lock");
    leftover_temporaries(m, /*remove=*/true);
  }
  std::vector<const SweepJob*> pending;
  for (const auto& job : m.jobs) {
    if (options.shard && !in_shard(job, *options.shard)) continue;
    ++summary.jobs;
    if (!options.force && job_status(m, job).state == JobState::kDone) {
      ++summary.skipped;
      continue;
    }
    pending.push_back(&job);
  }
  fs::create_directories(m.dir / "logs");

  std::vector<RunningJob> running;
  SweepProgress progress;
  progress.total = pending.size();
  progress.skipped = summary.skipped;
  auto report = [&] {
    progress.running = running.size();
    progress.elapsed_s = seconds_since(t0);
    if (options.on_progress) options.on_progress(progress);
  };
  auto start = [&](const SweepJob* job) {
    ProcessSpec spec;
    spec.executable = options.executable;
    spec.args = {"run", "--manifest", m.manifest.string(), "--job", job->id};
    if (options.force) spec.args.push_back("--force");
    spec.output_file = m.log_file(job->id);
    clear_failure(m, *job);  // a record left when it ends is this attempt's
    running.push_back({spawn_process(spec), job, Clock::now()});
  };
  std::size_t next = 0;
  bool first_report = true;
  try {
    while (next < pending.size() || !running.empty()) {
      while (running.size() < options.parallel && next < pending.size()) start(pending[next++]);
      if (first_report) {
        report();
        first_report = false;
      }
      bool any = false;
      for (std::size_t i = 0; i < running.size();) {
        const auto status = try_wait_process(running[i].pid);
        if (!status) {
          stop_if_past_timeout(running[i].pid, seconds_since(running[i].start),
                               options.job_timeout_s, running[i].signals_sent);
          ++i;
          continue;
        }
        any = true;
        const RunningJob r = running[i];
        running.erase(running.begin() + static_cast<std::ptrdiff_t>(i));
        ++summary.ran;
        ++progress.finished;
        progress.last_id = r.job->id;
        progress.last_s = seconds_since(r.start);
        const JobStatus st = job_status(m, *r.job);
        progress.last_ok = status->ok() && st.state == JobState::kDone;
        if (progress.last_ok) {
          clear_failure(m, *r.job);
        } else {
          ++summary.failed;
          ++progress.failed;
          summary.failed_ids.push_back(r.job->id);
          const std::string why = record_failure(m, r, *status, options);
          progress.last_detail = why;
        }
        // The next job starts before the report, so that "running" counts it.
        while (running.size() < options.parallel && next < pending.size()) start(pending[next++]);
        report();
      }
      if (!any) std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    if (pending.empty()) report();
  } catch (...) {
    for (const auto& r : running) ::kill(r.pid, SIGTERM);
    for (const auto& r : running) wait_process(r.pid);
    throw;
  }
  // Manifest order, not the order in which they happened to end.
  std::sort(summary.failed_ids.begin(), summary.failed_ids.end(),
            [&](const std::string& x, const std::string& y) {
              return m.find(x)->index < m.find(y)->index;
            });
  summary.wall_s = seconds_since(t0);
  return summary;
}

// ---------------------------------------------------------------------------
// Slurm

namespace {

std::string shell_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

bool slurm_token_ok(const std::string& s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == ':' ||
           c == '.' || c == ',';
  });
}

}  // namespace

std::string array_ranges(const std::vector<std::size_t>& v) {
  std::string out;
  for (std::size_t i = 0; i < v.size();) {
    std::size_t j = i;
    while (j + 1 < v.size() && v[j + 1] == v[j] + 1) ++j;
    out += (out.empty() ? "" : ",") +
           (j == i ? std::to_string(v[i]) : fmt::format("{}-{}", v[i], v[j]));
    i = j + 1;
  }
  return out;
}

std::string SlurmScript::brief() const {
  return fmt::format("{}: a Slurm array of {} tasks{}; submit with: {}", script.string(), shards,
                     max_parallel ? fmt::format(" ({} at once)", max_parallel) : "",
                     submit_command);
}

SlurmScript write_slurm_script(const SweepManifest& m, const SlurmOptions& o) {
  if (!o.partition.empty() && !slurm_token_ok(o.partition))
    throw UserError(
        fmt::format("--partition: got '{}', expected a Slurm partition name "
                    "(letters, digits, - _ . ,)",
                    o.partition));
  if (!o.time.empty() && !slurm_token_ok(o.time))
    throw UserError(
        fmt::format("--time: got '{}', expected a Slurm time such as 30, 01:00:00 "
                    "or 1-00:00:00",
                    o.time));
  if (o.cpus_per_task < 1)
    throw UserError(fmt::format("--cpus-per-task: got {}, expected at least 1", o.cpus_per_task));
  constexpr std::size_t kMaxArray = 1000;  // Slurm's default MaxArraySize is 1001 (0..1000)
  std::size_t shards = o.shards ? o.shards : std::min(m.jobs.size(), kMaxArray);
  if (shards < 1 || shards > kMaxArray)
    throw UserError(
        fmt::format("--shards: got {}, expected 1 to {} (Slurm's default "
                    "MaxArraySize is 1001)",
                    shards, kMaxArray));
  shards = std::min(shards, m.jobs.size());
  SlurmScript s;
  s.script = m.dir / "slurm" / "sweep.sbatch";
  s.shards = shards;
  s.max_parallel = o.max_parallel;
  fs::create_directories(m.dir / "slurm" / "logs");
  const std::string name = m.info.name.empty() ? "sweep" : m.info.name;
  std::string job_name;
  for (char c : name) job_name += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  std::string text = fmt::format(
      "#!/bin/bash\n"
      "# Generated by `driftlab sweep slurm-script` for the sweep folder\n"
      "#   {dir}\n"
      "# Array task K runs shard K/{n} of the manifest: the jobs whose index % {n} == K.\n"
      "# The shard count is written here, not read from SLURM_ARRAY_TASK_COUNT (which\n"
      "# counts only the tasks of one submission), so that resubmitting some tasks,\n"
      "#   sbatch --array=1,3 {script}\n"
      "# (the line `driftlab sweep status` prints) keeps the mapping. Finished jobs are\n"
      "# skipped, so resubmitting a task reruns only its missing or failed jobs.\n"
      "#SBATCH --job-name=driftlab-{job_name}\n"
      "#SBATCH --array=0-{last}{throttle}\n"
      "#SBATCH --cpus-per-task={cpus}\n"
      "#SBATCH --output={dir}/slurm/logs/%A_%a.out\n",
      fmt::arg("dir", m.dir.string()), fmt::arg("n", shards), fmt::arg("script", s.script.string()),
      fmt::arg("job_name", job_name), fmt::arg("last", shards - 1),
      fmt::arg("throttle", o.max_parallel ? fmt::format("%{}", o.max_parallel) : ""),
      fmt::arg("cpus", o.cpus_per_task));
  if (!o.partition.empty()) text += "#SBATCH --partition=" + o.partition + "\n";
  if (!o.time.empty()) text += "#SBATCH --time=" + o.time + "\n";
  text += fmt::format(
      "set -euo pipefail\n"
      "exec {exe} run --manifest {manifest} \\\n"
      "  --shard \"${{SLURM_ARRAY_TASK_ID}}/{n}\" --parallel "
      "\"${{SLURM_CPUS_PER_TASK:-{cpus}}}\"\n",
      fmt::arg("exe", shell_quote(fs::absolute(o.executable).string())),
      fmt::arg("manifest", shell_quote(m.manifest.string())), fmt::arg("n", shards),
      fmt::arg("cpus", o.cpus_per_task));
  {
    AtomicFile f(s.script);
    f.write(text);
    f.commit();
  }
  fs::permissions(s.script, fs::perms::owner_exec | fs::perms::group_exec | fs::perms::others_exec,
                  fs::perm_options::add);
  s.submit_command = "sbatch " + shell_quote(s.script.string());
  const SlurmRecord r{s.script.string(), shards,      o.max_parallel,
                      o.cpus_per_task,   o.partition, o.time};
  write_file_atomic(m.dir / "slurm" / "slurm.json", json_text(r));
  return s;
}

std::optional<SlurmScript> read_slurm_script(const SweepManifest& m) {
  const fs::path info = m.dir / "slurm" / "slurm.json";
  std::error_code ec;
  if (!fs::exists(info, ec)) return std::nullopt;
  const char* expected = "the slurm.json of `driftlab sweep slurm-script`";
  const auto j =
      record_json::parse_json(read_text_file(info, "Slurm record"), info.string(), expected);
  if (const auto missing = record_json::missing_keys<SlurmRecord>(j); !missing.empty())
    throw UserError(
        fmt::format("{}: no {}, expected {}", info.string(), fmt::join(missing, ", "), expected));
  const auto r = record_json::from_json<SlurmRecord>(j, info.string());
  if (r.shards < 1) return std::nullopt;
  return SlurmScript{r.script, r.shards, r.max_parallel, "sbatch " + shell_quote(r.script)};
}

std::string resubmit_command(const SweepManifest& m, const SweepStatus& status,
                             const SlurmScript& script) {
  std::vector<bool> needed(script.shards, false);
  for (const auto& st : status.jobs)
    if (st.state != JobState::kDone) needed[m.jobs[st.index].index % script.shards] = true;
  std::vector<std::size_t> shards;
  for (std::size_t k = 0; k < needed.size(); ++k)
    if (needed[k]) shards.push_back(k);
  if (shards.empty()) return "";
  return fmt::format("sbatch --array={}{} {}", array_ranges(shards),
                     script.max_parallel ? fmt::format("%{}", script.max_parallel) : "",
                     shell_quote(script.script.string()));
}

}  // namespace driftlab::study
