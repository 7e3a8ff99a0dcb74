// The command line of studies: `driftlab sweep ...` and the
// `--manifest/--job/--shard` options of `driftlab run`.
// Kept apart from main.cpp, which only wires these in.
#pragma once

#include <CLI/CLI.hpp>

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace driftlab::app {

class StudyCommands {
 public:
  /// Adds `sweep` (plan, run, status, merge, slurm-script) to `app`.
  explicit StudyCommands(CLI::App& app);

  /// Adds --manifest, --job, --shard and --parallel to the `run` subcommand,
  /// whose SCENARIO and --out are then required only without --manifest.
  /// `force` is the run's --force flag (it also reruns a finished job).
  void add_run_options(CLI::App* run_cmd, CLI::Option* scenario, CLI::Option* out,
                       const bool* force);

  /// Runs the parsed command if it is one of these; nullopt otherwise.
  /// Throws as the library does (UserError: bad input).
  std::optional<int> dispatch();

 private:
  int plan();
  int run_local();
  int status();
  int merge();
  int slurm_script();
  int run_manifest();

  CLI::App* sweep_ = nullptr;
  CLI::App* plan_ = nullptr;
  CLI::App* run_ = nullptr;
  CLI::App* status_ = nullptr;
  CLI::App* merge_ = nullptr;
  CLI::App* slurm_ = nullptr;
  CLI::App* schema_ = nullptr;
  CLI::App* run_cmd_ = nullptr;

  std::string sweep_file_, dir_, out_, schema_out_;
  std::vector<std::string> plan_sets_;  // sweep plan --set
  bool force_ = false;
  std::size_t parallel_ = 1;
  std::vector<std::string> covariates_, run_regressions_;
  std::string response_ = "p_m_per_m";
  bool allow_missing_ = false, no_plots_ = false;
  std::string partition_, time_, driftlab_;
  std::size_t cpus_per_task_ = 1, max_parallel_ = 0, shards_ = 0;
  std::string manifest_, job_, shard_;
  std::size_t run_parallel_ = 1;
  double job_timeout_s_ = 0;  // sweep run --job-timeout, run --shard --job-timeout
  const bool* run_force_ = nullptr;
};

}  // namespace driftlab::app
