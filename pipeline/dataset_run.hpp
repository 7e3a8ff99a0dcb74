// `driftlab vo`: the built-in VOs on a stereo dataset (KITTI odometry or EuRoC layout, real or
// exported by driftlab), evaluated against its ground truth with the tables of `driftlab eval`.
#pragma once

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "dataset/dataset.hpp"
#include "pipeline/scenario.hpp"

namespace driftlab::pipeline {

struct DatasetRunOptions {
  std::vector<std::string> algorithms;  ///< empty: the settings' pipeline.vo
  std::size_t max_frames = 0;           ///< 0: every frame
  bool replace_existing = false;
  std::FILE* progress = nullptr;
  bool progress_tty = false;
};

struct DatasetRunSummary {
  std::size_t frames = 0;
  double total_s = 0;
  std::vector<std::string> algorithms;  ///< one brief line per VO
  std::string brief() const;
};

/// Runs the VOs on `data` into `out_dir` (written atomically): estimates/NAME.tum,
/// groundtruth.tum (left camera, when the dataset has ground truth), frames.csv,
/// metrics.json, tables.md, sections.csv and scenario.resolved.yaml (the settings).
/// `settings` gives the VO options (pipeline.<algo>), the evaluation (eval) and the seed; the
/// rig and the images come from the dataset. Each estimate starts at the true pose of the
/// first frame with ground truth (frames before it are skipped), as in a scenario run.
DatasetRunSummary run_on_dataset(const dataset::StereoDataset& data, const Scenario& settings,
                                 const std::filesystem::path& out_dir,
                                 const DatasetRunOptions& options);

}  // namespace driftlab::pipeline
