#include "app/study_commands.hpp"

#include "app/cli_main.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <sstream>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/yaml_io.hpp"
#include "study/sweep.hpp"
#include "study/sweep_merge.hpp"
#include "study/sweep_runner.hpp"

namespace driftlab::app {
namespace fs = std::filesystem;
namespace pl = driftlab::study;

namespace {

// The running driftlab binary: each job runs in a child process of the same program.
fs::path self_executable() {
  std::error_code ec;
  const fs::path p = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw UserError("cannot find the driftlab executable (/proc/self/exe): " + ec.message());
  return p;
}

std::string quote(const std::string& s) {
  if (s.find_first_of(" '\"\\$`!*?[]{}()<>|&;#~") == std::string::npos && !s.empty()) return s;
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// Progress on stderr: redrawn in place on a terminal, a line per finished job otherwise.
std::function<void(const pl::SweepProgress&)> progress_printer() {
  const bool tty = ::isatty(STDERR_FILENO) != 0;
  return [tty](const pl::SweepProgress& p) {
    if (tty) {
      std::cerr << "\r\033[K" << p.line() << std::flush;
      if (p.finished == p.total) std::cerr << "\n";
    } else {
      std::cerr << p.line() << "\n";
    }
  };
}

}  // namespace

StudyCommands::StudyCommands(CLI::App& app) {
  sweep_ = app.add_subcommand("sweep", "Plan, run and merge scenario sweeps");
  sweep_->require_subcommand(1);

  plan_ = sweep_->add_subcommand("plan",
                                 "Expand a sweep file into DIR/manifest.jsonl (one job per line)");
  plan_->add_option("SWEEP", sweep_file_, "Sweep YAML file (see docs/sweeps.md)")->required();
  plan_->add_option("--out", out_, "Sweep folder to create")->required();
  plan_->add_option("--set", plan_sets_,
                    "Override a key of every job: KEY.PATH=VALUE (repeatable; replaces the "
                    "sweep file's set entry for that key)");
  plan_->add_flag("--force", force_,
                  "Replace a different plan in --out (finished runs with unchanged parameters "
                  "are kept)");

  run_ = sweep_->add_subcommand(
      "run", "Run the jobs of a sweep folder that are not done, each as a child process");
  run_->add_option("DIR", dir_, "Sweep folder (from `sweep plan`)")->required();
  run_->add_option("-j,--parallel", parallel_, "Jobs at once")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  run_->add_flag("--force", force_, "Run finished jobs again too");
  add_frame_cache_option(run_);
  run_->add_option("--job-timeout", job_timeout_s_,
                   "Stop a job still running after this many seconds and record it as "
                   "timed out (0: no limit)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);

  status_ = sweep_->add_subcommand(
      "status", "List done, failed and missing jobs and how to finish them (locally or Slurm)");
  status_->add_option("DIR", dir_, "Sweep folder")->required();

  merge_ = sweep_->add_subcommand(
      "merge", "Pool all runs' sections, regress, summarise points and plot into DIR/summary");
  merge_->add_option("DIR", dir_, "Sweep folder")->required();
  merge_
      ->add_option("--covariates", covariates_,
                   "Regression covariates (comma-separated columns of the pooled sections; "
                   "default: the scenario's eval.regression_covariates and every numeric "
                   "swept parameter that varies)")
      ->delimiter(',');
  merge_->add_option("--response", response_, "Regression response column")->capture_default_str();
  merge_->add_flag("--allow-missing", allow_missing_,
                   "Merge the finished jobs even when some are not done");
  merge_->add_flag("--no-plots", no_plots_, "Do not run gnuplot");
  merge_->add_option("--regress", run_regressions_,
                     "Run-level regression METRIC~AXIS[+AXIS...][@AXIS=VALUE,...] "
                     "(repeatable), e.g. basin_north_rmse_m~amplitude_m+wavelength_m; after @ "
                     "only the runs with those parameter values, e.g. "
                     "basin_north_rmse_m~amplitude_m@direction_deg=-40");

  schema_ =
      sweep_->add_subcommand("schema", "Print the reference of every sweep-file key (Markdown)");
  schema_->add_option("--out", schema_out_, "Write to this file instead of standard output");

  slurm_ = sweep_->add_subcommand(
      "slurm-script", "Write DIR/slurm/sweep.sbatch: a Slurm job array over shards of the jobs");
  slurm_->add_option("DIR", dir_, "Sweep folder")->required();
  slurm_->add_option("--partition", partition_, "Slurm partition (default: the cluster's)");
  slurm_->add_option("--time", time_, "Time limit per array task, e.g. 02:00:00");
  slurm_
      ->add_option("--cpus-per-task", cpus_per_task_,
                   "CPUs per array task; also the jobs a task runs at once")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  slurm_->add_option("--max-parallel", max_parallel_, "Array tasks running at once (0: no limit)")
      ->capture_default_str();
  slurm_->add_option("--shards", shards_,
                     "Array tasks (default: the number of jobs, at most 1000: Slurm's default "
                     "MaxArraySize is 1001)");
  slurm_->add_option("--driftlab", driftlab_,
                     "driftlab binary on the compute nodes (default: this one)");
}

void StudyCommands::add_run_options(CLI::App* run_cmd, CLI::Option* scenario, CLI::Option* out,
                                    const bool* force) {
  run_cmd_ = run_cmd;
  run_force_ = force;
  scenario->required(false);
  out->required(false);
  auto* manifest = run_cmd->add_option(
      "--manifest", manifest_,
      "Run jobs of a sweep instead: DIR/manifest.jsonl of `driftlab sweep plan` (with --job or "
      "--shard)");
  auto* job = run_cmd->add_option("--job", job_, "The id of the one job to run (with --manifest)");
  auto* shard = run_cmd->add_option(
      "--shard", shard_,
      "K/N: run the jobs whose index % N == K, K 0-based (with --manifest; for job arrays)");
  run_cmd->add_option("--parallel", run_parallel_, "Jobs at once with --shard")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  auto* timeout = run_cmd
                      ->add_option("--job-timeout", job_timeout_s_,
                                   "With --shard: stop a job still running after this many "
                                   "seconds and record it as timed out (0: no limit)")
                      ->capture_default_str()
                      ->check(CLI::NonNegativeNumber);
  timeout->needs(shard);
  job->needs(manifest);
  shard->needs(manifest);
  job->excludes(shard);
  manifest->excludes(scenario);
  manifest->excludes(out);
  for (const char* name : {"--set", "--seed", "--only-motion"})
    if (CLI::Option* o = run_cmd->get_option_no_throw(name)) manifest->excludes(o);
  run_cmd->callback([this, scenario, out] {
    if (manifest_.empty()) {
      if (scenario->count() == 0) throw CLI::RequiredError("SCENARIO");
      if (out->count() == 0) throw CLI::RequiredError("--out");
    } else if (job_.empty() && shard_.empty()) {
      throw CLI::ValidationError("--manifest", "needs --job ID or --shard K/N");
    }
  });
}

std::optional<int> StudyCommands::dispatch() {
  if (plan_->parsed()) return plan();
  if (run_->parsed()) return run_local();
  if (status_->parsed()) return status();
  if (merge_->parsed()) return merge();
  if (slurm_->parsed()) return slurm_script();
  if (schema_->parsed())
    return print_reference("Sweep file reference", "driftlab sweep schema",
                           "A key whose constraint says required must be given; the others\n"
                           "take the default shown. Unknown keys are errors. See docs/sweeps.md.",
                           pl::sweep_reference_markdown(), schema_out_);
  if (run_cmd_ && run_cmd_->parsed() && !manifest_.empty()) return run_manifest();
  return std::nullopt;
}

int StudyCommands::plan() {
  pl::Sweep sweep = pl::load_sweep(sweep_file_);
  pl::apply_sets(&sweep, plan_sets_);
  const pl::SweepPlan plan = pl::plan_sweep(sweep);
  const pl::PlanWriteSummary s = pl::write_plan(plan, out_, force_);
  std::cout << "planned " << s.brief() << "\n";
  std::cerr << fmt::format(
      "next: driftlab sweep run {} -j N   (or: driftlab sweep slurm-script "
      "{})\n",
      quote(out_), quote(out_));
  return 0;
}

int StudyCommands::run_local() {
  const pl::SweepManifest m = pl::read_manifest(dir_);
  pl::SweepRunOptions o;
  o.executable = self_executable();
  o.parallel = parallel_;
  o.force = force_;
  o.job_timeout_s = job_timeout_s_;
  o.on_progress = progress_printer();
  const pl::SweepRunSummary s = pl::run_sweep_jobs(m, o);
  std::cout << "sweep run: " << s.brief() << "\n";
  if (!s.ok()) {
    std::cerr << fmt::format(
        "error: {} job(s) failed; see `driftlab sweep status {}` and "
        "{}/failed/\n",
        s.failed, quote(dir_), dir_);
    return kExitJobsFailed;
  }
  return 0;
}

int StudyCommands::status() {
  const pl::SweepManifest m = pl::read_manifest(dir_);
  const pl::SweepStatus st = pl::sweep_status(m);
  std::cout << fmt::format("sweep {} in {}\n{}\n", m.info.name, m.dir.string(), st.brief());
  constexpr std::size_t kShow = 20;
  for (const auto state : {pl::JobState::kFailed, pl::JobState::kStale, pl::JobState::kMissing}) {
    std::size_t n = 0;
    for (const auto& j : st.jobs) {
      if (j.state != state) continue;
      if (n == 0) std::cout << yaml::enum_name(state) << ":\n";
      if (n++ < kShow) {
        std::cout << "  " << j.id;
        if (!j.detail.empty()) std::cout << "  " << j.detail;
        if (state == pl::JobState::kFailed)
          std::cout << fmt::format("  (failed/{}.json, logs/{}.log)", j.id, j.id);
        std::cout << "\n";
      }
    }
    if (n > kShow) std::cout << fmt::format("  ... and {} more\n", n - kShow);
  }
  if (!st.leftovers.empty())
    std::cout << fmt::format(
        "{} temporaries of interrupted jobs under runs/ (the next `driftlab "
        "sweep run` removes those whose process is gone)\n",
        st.leftovers.size());
  if (st.complete()) {
    std::cout << fmt::format("all jobs done: driftlab sweep merge {}\n", quote(m.dir.string()));
    return 0;
  }
  std::cout << fmt::format("finish locally:   driftlab sweep run {} -j N\n", quote(m.dir.string()));
  if (const auto script = pl::read_slurm_script(m)) {
    std::cout << "resubmit on Slurm (only the shards with unfinished jobs):\n  "
              << pl::resubmit_command(m, st, *script) << "\n";
  } else {
    std::cout << fmt::format(
        "on Slurm:         driftlab sweep slurm-script {} (then this status "
        "prints the sbatch line)\n",
        quote(m.dir.string()));
  }
  return 0;
}

int StudyCommands::merge() {
  const pl::SweepManifest m = pl::read_manifest(dir_);
  pl::MergeOptions o;
  o.covariates = covariates_;
  o.response = response_;
  o.run_regressions = run_regressions_;
  o.allow_missing = allow_missing_;
  o.plots = !no_plots_;
  const pl::MergeSummary s = pl::merge_sweep(m, o);
  for (const auto& w : s.warnings) std::cerr << "warning: " << w << "\n";
  std::cout << s.brief() << "\n";
  return 0;
}

int StudyCommands::slurm_script() {
  const pl::SweepManifest m = pl::read_manifest(dir_);
  pl::SlurmOptions o;
  o.partition = partition_;
  o.time = time_;
  o.cpus_per_task = cpus_per_task_;
  o.max_parallel = max_parallel_;
  o.shards = shards_;
  o.executable = driftlab_.empty() ? self_executable() : fs::path(driftlab_);
  const pl::SlurmScript s = pl::write_slurm_script(m, o);
  std::cout << s.brief() << "\n";
  return 0;
}

int StudyCommands::run_manifest() {
  const pl::SweepManifest m = pl::read_manifest(manifest_);
  const bool force = run_force_ && *run_force_;
  if (!job_.empty()) {
    pl::JobRunOptions o;
    o.force = force;
    o.progress = stderr;
    o.frame_cache = driftlab::pipeline::FrameCacheOptions::from_environment();
    const pl::JobRunResult r = pl::run_manifest_job(m, job_, o);
    std::cout << r.brief() << "\n";
    return 0;
  }
  pl::SweepRunOptions o;
  o.executable = self_executable();
  o.parallel = run_parallel_;
  o.force = force;
  o.shard = pl::parse_shard(shard_);
  o.local = false;  // other machines may be running jobs of this sweep
  o.job_timeout_s = job_timeout_s_;
  o.on_progress = progress_printer();
  const pl::SweepRunSummary s = pl::run_sweep_jobs(m, o);
  std::cout << fmt::format("shard {}: {}\n", shard_, s.brief());
  if (!s.ok()) {
    std::cerr << fmt::format("error: {} job(s) of shard {} failed; see {}/failed/\n", s.failed,
                             shard_, m.dir.string());
    return kExitJobsFailed;
  }
  return 0;
}

}  // namespace driftlab::app
