// `driftlab imagestats`: the image statistics a VO depends on (eval/image_stats.hpp), for
// photographs and rendered frames side by side.
#pragma once

#include <CLI/CLI.hpp>

#include <optional>
#include <string>
#include <vector>

namespace driftlab::app {

class ImageStatsCommand {
 public:
  /// Adds `imagestats` to `app`.
  explicit ImageStatsCommand(CLI::App& app);
  ImageStatsCommand(const ImageStatsCommand&) = delete;
  ImageStatsCommand& operator=(const ImageStatsCommand&) = delete;
  /// Runs the parsed command if it is this one; nullopt otherwise.
  std::optional<int> dispatch() const;

 private:
  int run() const;

  CLI::App* cmd_ = nullptr;
  std::vector<std::string> inputs_;
  std::string size_ = "1024x768", out_, json_, montage_;
  int per_folder_ = 0;
};

}  // namespace driftlab::app
