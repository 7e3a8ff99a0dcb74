#include "app/gate_command.hpp"

#include "app/cli_main.hpp"

#include <fmt/format.h>

#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/file_io.hpp"
#include "gate/gate.hpp"

namespace driftlab::app {

namespace fs = std::filesystem;

GateCommand::GateCommand(CLI::App* cmd) : cmd_(cmd) {
  cmd_->add_option("--baseline", baseline_, "Baseline JSON (see docs/sweeps.md)")->required();
  cmd_->add_option("--results", results_, "Run folder, merged sweep folder, or a metrics.json")
      ->required();
  cmd_->add_option("--junit", junit_, "Also write the verdicts as JUnit XML here");
  cmd_->add_flag("--update", update_,
                 "Write the new values into the baseline (accept them) instead of failing");
}

std::optional<int> GateCommand::dispatch() {
  if (!cmd_->parsed()) return std::nullopt;
  return run();
}

int GateCommand::run() {
  const gate::Baseline baseline = gate::load_baseline(baseline_);
  const fs::path file = gate::find_results_metrics(results_);
  nlohmann::json results;
  try {
    results = nlohmann::json::parse(read_text_file(file, "metrics.json"));
  } catch (const nlohmann::json::parse_error& e) {
    throw UserError(
        fmt::format("{}: not valid JSON ({}), expected metrics.json", file.string(), e.what()));
  }
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
