// `driftlab regress` (also the standalone `driftlab-gate`): the CI baseline
// gate's command line. Needs only the gate module (core), so a CI machine
// that only gates can build `driftlab-gate` without the renderer.
#pragma once

#include <CLI/CLI.hpp>

#include <optional>
#include <string>

namespace driftlab::app {

class GateCommand {
 public:
  /// Adds the gate's options to `cmd` (the `regress` subcommand, or the whole driftlab-gate).
  explicit GateCommand(CLI::App* cmd);

  /// Runs the gate if `cmd` was parsed; nullopt otherwise. Exit 0: passed; 1: regressed.
  std::optional<int> dispatch();
  /// Runs the gate with the parsed options.
  int run();

 private:
  CLI::App* cmd_;
  std::string baseline_, results_, junit_;
  bool update_ = false;
};

}  // namespace driftlab::app
