// `driftlab vo`: the built-in VOs on a stereo dataset (KITTI odometry or EuRoC layout, real or
// exported by driftlab), evaluated against its ground truth with the tables of `driftlab eval`.
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "dataset/dataset.hpp"
#include "pipeline/run_record.hpp"
#include "pipeline/scenario.hpp"

namespace driftlab::pipeline {

struct DatasetRunOptions {
  std::vector<std::string> algorithms;  ///< empty: the settings' pipeline.vo
  /// Whether the settings' pipeline.fusion was asked for on the command line (--fusion): then a
  /// filter the dataset cannot feed is an error; otherwise it is skipped with a warning.
  bool fusion_on_command_line = false;
  std::size_t max_frames = 0;  ///< 0: every frame
  bool replace_existing = false;
  std::FILE* progress = nullptr;
  bool progress_tty = false;
};

/// What `driftlab vo` measured, turned into metrics.json's record by run_record().
struct DatasetRunSummary {
  std::uint64_t seed = 0;
  std::size_t frames = 0;
  double total_s = 0;
  record::DatasetRecord dataset;  ///< the dataset: root, format, frames, rig
  std::optional<record::FiltersWorldRecord> filters_world;  ///< the filters' levelled world
  TrackRecords tracks;
  std::vector<std::string> algorithms;  ///< one brief line per estimate (VO or filter)
  std::vector<std::string> warnings;
  std::string brief() const;
  record::RunRecord run_record() const;
};

/// Runs the VOs on `data` into `out_dir` (written atomically): estimates/NAME.tum,
/// groundtruth.tum (left camera, when the dataset has ground truth), frames.csv,
/// metrics.json, tables.md, sections.csv and scenario.resolved.yaml (the settings).
/// `settings` gives the VO and filter options (pipeline.<algo>), the evaluation (eval) and the
/// seed; the rig and the images come from the dataset. Each estimate starts at the true pose of
/// the first frame with ground truth (frames before it are skipped), as in a scenario run.
///
/// The filters of the settings' pipeline.fusion follow each VO, as in a scenario run
/// (estimates/NAME_ca.tum, NAME_eskf.tum, ...): the smoother on any dataset; the ESKF where the
/// dataset has an IMU and the camera's pose on it (EuRoC's imu0 and cam0 T_BS), with the IMU
/// noise of its imu0/sensor.yaml; the NED filters where it also has a compass (a driftlab
/// export's compass0). Those filters work in the dataset's world turned so that the axis
/// nearest to gravity (measured by the IMU at the first frame) is down, and start from the
/// anchor's position and heading (or the compass's) and the IMU's roll and pitch.
DatasetRunSummary run_on_dataset(const dataset::StereoDataset& data, const Scenario& settings,
                                 const std::filesystem::path& out_dir,
                                 const DatasetRunOptions& options);

}  // namespace driftlab::pipeline
