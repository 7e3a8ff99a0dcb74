#include "app/gate_command.hpp"

#include "app/cli_main.hpp"

#include <fmt/format.h>

#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "gate/gate.hpp"

namespace driftlab::app {

namespace fs = std::filesystem;

GateCommand::GateCommand(CLI::App* cmd) : cmd_(cmd) {
  cmd_->add_option("--baseline", baseline_, "Baseline JSON (see docs/sweeps.md); required");
  cmd_->add_option("--results", results_,
                   "Run folder, merged sweep folder, or a metrics.json; required");
  cmd_->add_option("--junit", junit_, "Also write the verdicts as JUnit XML here");
  CLI::Option* update =
      cmd_->add_flag("--update", update_,
                     "Write the new values into the baseline (accept them) instead of failing");
  cmd_->add_option("--only", only_,
                   "Check only the baseline's metrics whose key starts with one of these "
                   "(comma-separated, e.g. algorithms.sparse.); the others are not compared")
      ->delimiter(',')
      ->excludes(update);
  init_ = cmd_->add_subcommand("init", "Write a new baseline from a run or a merged sweep");
  init_->add_option("--results", init_results_, "Run folder, merged sweep folder, or metrics.json")
      ->required();
  init_->add_option("--baseline", init_baseline_, "The baseline file to write")->required();
  init_
      ->add_option("--keys", keys_,
                   "Metrics to gate, dotted key paths (default: each algorithm's APE, track, "
                   "section and basin errors)")
      ->delimiter(',');
  init_->add_option("--rel-tol", rel_tol_, "Relative tolerance of each value")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  init_->add_option("--description", description_, "What the baseline protects");
  init_->add_flag("--force", force_, "Replace an existing baseline file");
  schema_ =
      cmd_->add_subcommand("schema", "Print the reference of every baseline-file key (Markdown)");
  schema_->add_option("--out", schema_out_, "Write to this file instead of standard output");
  cmd_->require_subcommand(0, 1);
}

int GateCommand::init() {
  const fs::path file = gate::find_results_metrics(init_results_);
  const nlohmann::json results = gate::read_results_metrics(file);
  if (fs::exists(init_baseline_) && !force_)
    throw UserError(
        fmt::format("{}: already exists; --force replaces it, or accept new values "
                    "into it with `regress --update`",
                    init_baseline_));
  gate::InitOptions o;
  o.rel_tol = rel_tol_;
  o.description = description_.empty() ? "baseline of " + file.string() : description_;
  const std::vector<std::string> keys = keys_.empty() ? gate::default_gate_keys(results) : keys_;
  gate::Baseline b = gate::baseline_from_results(results, keys, o);
  b.file = init_baseline_;
  write_file_atomic(init_baseline_, gate::baseline_json(b));
  std::cout << fmt::format("regress init: {} metrics from {} into {}\n", b.metrics.size(),
                           file.string(), init_baseline_);
  return 0;
}

std::optional<int> GateCommand::dispatch() {
  if (!cmd_->parsed()) return std::nullopt;
  return run();
}

int GateCommand::run() {
  if (init_->parsed()) return init();
  if (schema_->parsed())
    return print_reference("Baseline file reference", "driftlab regress schema",
                           "A baseline is JSON (or YAML). A key whose\nconstraint says "
                           "required must be given; the others take the default shown. Unknown "
                           "keys are errors.",
                           gate::baseline_reference_markdown(), schema_out_);
  if (baseline_.empty() || results_.empty())
    throw UsageError("regress: --baseline and --results are required (or `regress init`)");
  if (update_ && !fs::exists(baseline_))
    throw UserError(
        fmt::format("{}: no such baseline; create one from results with `driftlab "
                    "regress init --results DIR --baseline {}`",
                    baseline_, baseline_));
  gate::Baseline baseline = gate::load_baseline(baseline_);
  if (!only_.empty()) baseline = gate::only_metrics(std::move(baseline), only_);
  const fs::path file = gate::find_results_metrics(results_);
  const nlohmann::json results = gate::read_results_metrics(file);
  const gate::GateResult r = gate::check_baseline(baseline, results, file);
  std::cout << r.table();
  if (!junit_.empty()) write_file_atomic(junit_, r.junit_xml());
  if (update_) {
    write_file_atomic(baseline_, gate::baseline_json(gate::updated_baseline(baseline, r)));
    std::cout << fmt::format("regress: {}; baseline {} updated with the new values\n", r.brief(),
                             baseline_);
    return 0;
  }
  std::cout << "regress: " << r.brief() << "\n";
  if (r.failures() > 0) {
    std::cerr << fmt::format(
        "error: {} of {} metrics regressed or are missing (compared {} with "
        "{}); if the change is intended, accept it with --update\n",
        r.failures(), r.checks.size(), file.string(), baseline_);
    return kExitRegressed;
  }
  return 0;
}

}  // namespace driftlab::app
