// `driftlab export`: a scenario's stereo sequence as a dataset in the layout of KITTI
// odometry, EuRoC/ASL or TUM RGB-D (dataset/), so that any VO or VIO can read it. The
// images are the ones a run's VOs see (camera effects, the camera clock's stamps, dropped
// frames left out), byte for byte: a built-in VO on the export gives a run's estimate.
#pragma once

#include <cstdio>
#include <filesystem>
#include <string>

#include "dataset/dataset.hpp"
#include "pipeline/frame_cache.hpp"
#include "pipeline/scenario.hpp"

namespace driftlab::pipeline {

struct ExportOptions {
  dataset::DatasetFormat format = dataset::DatasetFormat::kKitti;
  std::string sequence = "00";  ///< KITTI sequence number
  bool replace_existing = false;
  std::FILE* progress = nullptr;  ///< progress of the frame loop; null: none
  bool progress_tty = false;
  FrameCacheOptions frame_cache;  ///< where frames are kept and replayed (no folder: nowhere)
};

struct ExportSummary {
  std::size_t frames = 0;  ///< stereo pairs written
  std::size_t imu_samples = 0;
  double render_pairs_per_s = 0;
  double total_s = 0;
  std::string brief() const;
};

/// Simulates, renders and writes `scenario` as a dataset into `out_dir` (appears complete or
/// not at all), with scenario.resolved.yaml and info.yaml.
ExportSummary export_dataset(const Scenario& scenario, const std::filesystem::path& out_dir,
                             const ExportOptions& options);

/// The calibration a dataset of `scenario` carries (rig, camera in the IMU frame, IMU noise).
dataset::ExportCalibration export_calibration(const Scenario& scenario);

}  // namespace driftlab::pipeline
