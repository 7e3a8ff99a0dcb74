// Running the jobs of a sweep folder: one job in this process (the entry point
// for any scheduler: `driftlab run --manifest M --job ID`), many jobs as child
// processes (`driftlab sweep run`, `driftlab run --manifest M --shard K/N`),
// and the Slurm array script with its resubmission line.
#pragma once

#include <cstdio>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "pipeline/run.hpp"
#include "study/sweep.hpp"

namespace driftlab::study {

struct JobRunOptions {
  bool force = false;             // run again even when done
  std::FILE* progress = nullptr;  // the run's frame-loop progress (plain lines); null: none
  pipeline::FrameCacheOptions frame_cache;  // where the run keeps and finds its frames
};

struct JobRunResult {
  std::string id;
  bool skipped = false;  // already done
  pipeline::RunSummary run;
  std::string brief() const;
};

/// Runs job `id` of the manifest in this process: loads scenario.yaml with the
/// job's overrides, checks that it hashes as planned, runs it into a temporary
/// folder, writes the completion marker job.json last and renames the folder to
/// runs/ID (replacing a stale one). A finished job is skipped unless `force`.
/// On failure writes failed/ID.json and rethrows.
JobRunResult run_manifest_job(const SweepManifest& m, const std::string& id,
                              const JobRunOptions& options = {});

/// What a progress report sees.
struct SweepProgress {
  std::size_t total = 0;     // jobs to run this time
  std::size_t finished = 0;  // of those, ended (either way)
  std::size_t failed = 0;
  std::size_t running = 0;
  std::size_t skipped = 0;  // already done before this run
  double elapsed_s = 0;
  std::string last_id;  // the job that just ended ("" for the first report)
  bool last_ok = true;
  double last_s = 0;        // its wall time
  std::string last_detail;  // its failure
  /// "[ 3/8] 2 running, 1 failed | p0002-r00 done in 1.4 s | 5 s elapsed, ~8 s left"
  std::string line() const;
};

struct SweepRunOptions {
  std::filesystem::path executable;  // the driftlab binary that runs each job
  std::size_t parallel = 1;          // jobs at once
  bool force = false;                // run finished jobs again
  std::optional<Shard> shard;        // only this shard's jobs
  /// This machine owns the folder (`sweep run`): hold DIR/.sweep-run.lock so that a
  /// second local runner refuses to start, and remove temporaries of killed jobs.
  /// False for shards, which run side by side on several machines.
  bool local = true;
  /// A job still running after this many seconds is stopped (SIGTERM, SIGKILL 5 s later) and
  /// recorded as `timeout`; 0: no limit. The guard against a job that hangs.
  double job_timeout_s = 0;
  std::function<void(const SweepProgress&)> on_progress;
};

struct SweepRunSummary {
  std::size_t jobs = 0;     // in the manifest (or the shard)
  std::size_t skipped = 0;  // already done
  std::size_t ran = 0;
  std::size_t failed = 0;
  std::vector<std::string> failed_ids;
  double wall_s = 0;
  bool ok() const { return failed == 0; }
  std::string brief() const;
};

/// Runs every job that is not done (all with `force`) as a child process
/// `EXECUTABLE run --manifest M --job ID`, at most `parallel` at once, its
/// output in logs/ID.log. A job that fails, crashes or runs past `job_timeout_s`
/// gets failed/ID.json (what happened, the end of its output) and does not stop
/// the others; a failure record that cannot be written (a full disk) does not
/// stop them either (the job is then `missing` and runs again next time).
SweepRunSummary run_sweep_jobs(const SweepManifest& m, const SweepRunOptions& options);

struct SlurmOptions {
  std::string partition;             // empty: the cluster's default
  std::string time;                  // per array task, e.g. 01:00:00; empty: the default
  std::size_t cpus_per_task = 1;     // also the jobs a task runs at once
  std::size_t max_parallel = 0;      // array tasks at once (%K); 0: no limit
  std::size_t shards = 0;            // array tasks; 0: min(jobs, 1000)
  std::filesystem::path executable;  // the driftlab binary on the compute nodes
};

/// The array script of a sweep folder and how to submit it.
struct SlurmScript {
  std::filesystem::path script;  // DIR/slurm/sweep.sbatch
  std::size_t shards = 0;
  std::size_t max_parallel = 0;
  std::string submit_command;  // sbatch DIR/slurm/sweep.sbatch
  std::string brief() const;
};

/// Writes DIR/slurm/sweep.sbatch (and slurm.json, logs/): array task K runs
/// `driftlab run --manifest DIR/manifest.jsonl --shard K/N`. N is written into
/// the script rather than read from SLURM_ARRAY_TASK_COUNT, which counts only
/// the tasks of the submission: a resubmission of some tasks must keep N.
SlurmScript write_slurm_script(const SweepManifest& m, const SlurmOptions& options);

/// The script of the folder, if `sweep slurm-script` wrote one.
std::optional<SlurmScript> read_slurm_script(const SweepManifest& m);

/// "sbatch --array=1,3-5%K SCRIPT" for the shards holding a job that is not
/// done; "" when every job is done.
std::string resubmit_command(const SweepManifest& m, const SweepStatus& status,
                             const SlurmScript& script);

/// 0-based indices as Slurm array ranges: {0,1,2,5,7,8} -> "0-2,5,7-8".
std::string array_ranges(const std::vector<std::size_t>& sorted_indices);

}  // namespace driftlab::study
