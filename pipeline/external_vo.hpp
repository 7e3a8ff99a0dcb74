// External VOs (pipeline.external_vo): a VO of the user's, run as a shell command on an export
// of the run's own frames (dataset/), its trajectory read back and evaluated with the
// built-in VOs. A command that fails, hangs past its timeout or writes a trajectory that
// cannot be read is recorded (metrics.json "external_vo", the report, warnings) and never
// stops the run: the other algorithms' results are kept.
//
// Per external VO NAME the run folder gets external/NAME/: log.txt (the command's standard
// output and error), the trajectory the command wrote, and the exported dataset (dataset/,
// removed after the command unless keep_dataset).
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/trajectory_io.hpp"
#include "dataset/dataset.hpp"
#include "pipeline/scenario.hpp"
#include "record/run_record.hpp"
#include "sim/render/renderer.hpp"

namespace driftlab::pipeline {

/// What one external VO gave.
struct ExternalVoResult {
  std::string name;
  bool ok = false;
  Trajectory estimate;  ///< left camera, anchored at the true first pose; empty unless ok
  record::ExternalVoRecord record;  ///< status, command, exit, seconds, message, log_tail
  std::string warning;  ///< why it failed, or why the estimate looks wrong; empty if neither
};

class ExternalVoStage {
 public:
  /// One export per sc.pipeline.external_vo entry, under run_dir/external/NAME/dataset.
  /// `reported_dir`: the folder the run becomes (run_dir is its temporary name until the end),
  /// as the commands, messages and logs in the record name it; empty: run_dir.
  ExternalVoStage(const Scenario& sc, const std::filesystem::path& run_dir,
                  const std::filesystem::path& reported_dir = {});
  ~ExternalVoStage();
  bool empty() const;
  /// Whether any export wants the true depth with each frame (TUM RGB-D).
  bool wants_depth() const;
  /// One delivered frame: its stamp, images and the left camera's true pose.
  void add_frame(TimeNs stamp_ns, const sim::StereoImages& images, const StampedPose& truth);
  /// Finishes the exports (with copies of the run's sensor CSVs and `imu_states` for EuRoC),
  /// runs each command and reads its trajectory back.
  std::vector<ExternalVoResult> finish(const std::vector<dataset::BodyState>& imu_states);

 private:
  struct Export;
  std::filesystem::path run_dir_, reported_dir_;
  std::vector<std::unique_ptr<Export>> exports_;
};

/// The command with its placeholders ({dir}, {root}, {out}, {driftlab}) replaced by these
/// values, each quoted for /bin/sh; UserError naming an unknown {placeholder}. Other text in
/// braces ("${HOME}", "{ print $1 }") is the shell's and stays as written.
std::string expand_command(const std::string& command, const std::filesystem::path& dir,
                           const std::filesystem::path& root, const std::filesystem::path& out,
                           const std::filesystem::path& driftlab);

}  // namespace driftlab::pipeline
