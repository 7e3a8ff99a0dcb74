// `driftlab regress` (also the standalone `driftlab-gate`): the CI baseline
// gate's command line. Needs only the gate module (core), so a CI machine
// that only gates can build `driftlab-gate` without the renderer.
#pragma once

#include <CLI/CLI.hpp>

#include <optional>
#include <string>
#include <vector>

namespace driftlab::app {

class GateCommand {
 public:
  /// Adds the gate's options to `cmd` (the `regress` subcommand, or the whole driftlab-gate).
  explicit GateCommand(CLI::App* cmd);

  /// Runs the gate (or `init`) if `cmd` was parsed; nullopt otherwise. Exit 0: passed;
  /// kExitRegressed: a metric regressed or is missing.
  std::optional<int> dispatch();
  /// Runs the gate (or `init`) with the parsed options.
  int run();

 private:
  int init();

  CLI::App* cmd_;
  CLI::App* init_ = nullptr;
  CLI::App* schema_ = nullptr;
  std::string schema_out_;
  std::string baseline_, results_, junit_;
  bool update_ = false;
  std::vector<std::string> only_;  // --only: key prefixes
  std::string init_results_, init_baseline_, description_;
  std::vector<std::string> keys_;
  double rel_tol_ = 0.1;
  bool force_ = false;
};

}  // namespace driftlab::app
