// The command line of datasets: `driftlab export` (a scenario as a KITTI, EuRoC or TUM RGB-D
// dataset) and `driftlab vo` (the built-in VOs on a KITTI or EuRoC dataset).
#pragma once

#include <CLI/CLI.hpp>

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace driftlab::app {

class DatasetCommands {
 public:
  /// Adds `export` and `vo` to `app`.
  explicit DatasetCommands(CLI::App& app);
  /// Runs the parsed command if it is one of these; nullopt otherwise.
  std::optional<int> dispatch();

 private:
  int export_dataset();
  int run_vo();

  CLI::App* export_ = nullptr;
  CLI::App* vo_ = nullptr;
  std::string scenario_, out_, format_ = "kitti", sequence_ = "00", seed_;
  std::vector<std::string> sets_;
  int frames_ = 0;
  bool force_ = false;
  std::string dataset_, settings_, gt_topic_, calibration_;
  std::vector<std::string> algos_;
  std::vector<std::string> fusion_;
};

}  // namespace driftlab::app
