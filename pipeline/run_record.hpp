// What a run measured, as typed records the stages fill (after Ceres'
// Solver::Summary): each turned into metrics.json's JSON in one place, here.
// `driftlab run` (pipeline/run.hpp: RunSummary) and `driftlab vo`
// (pipeline/dataset_run.hpp: DatasetRunSummary) share TrackRecords.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "pipeline/frame_source.hpp"

namespace driftlab::pipeline {

/// A filter against the VO it follows (algorithms.NAME.vs_raw_vo).
struct VsRawVo {
  std::string raw_vo;   ///< the VO's track
  double filtered = 0;  ///< the filter's APE translation RMSE [m]
  double raw = 0;       ///< the VO's [m]
  bool better() const { return filtered < raw; }
  double ratio() const { return raw > 0 ? filtered / raw : 0.0; }
};

/// One track's results (metrics.json algorithms.NAME).
struct AlgorithmRecord {
  nlohmann::json evaluation;               ///< eval::to_json: the error statistics
  std::optional<nlohmann::json> tracking;  ///< where a VO lost track (TrackingSummary)
  std::optional<nlohmann::json> filter;    ///< a filter's counters (FilterCounts)
  std::optional<VsRawVo> vs_raw_vo;
  /// The evaluation's APE translation RMSE [m], when it has one.
  std::optional<double> ape_trans_rmse_m() const;
};

/// A VO's cost (metrics.json timing.vo_ms_per_frame.NAME, timing.sparse_pairs.NAME).
struct VoTiming {
  double ms_per_frame = 0;
  struct SparsePairs {
    std::int64_t detected = 0, shared = 0;
  };
  std::optional<SparsePairs> sparse_pairs;  ///< the sparse VOs' detections
};

/// Every track's results and every VO's cost: what both kinds of run report.
struct TrackRecords {
  std::map<std::string, AlgorithmRecord> algorithms;
  std::map<std::string, VoTiming> vo_timing;
  /// Writes algorithms, timing.vo_ms_per_frame and timing.sparse_pairs into `metrics`.
  void add_to(nlohmann::json* metrics) const;
};

/// What each stage of a scenario run did, or why it did not run (metrics.json stages).
struct StageRecord {
  std::string scenario, physics, sensors, render, vo, external_vo, fusion, eval;
};

/// The camera as the run saw it (metrics.json camera).
struct CameraRecord {
  std::size_t frames_delivered = 0, frames_dropped = 0;
  bool noise = false, lens_distortion = false;
  double vignetting_strength = 0, motion_blur_step_px = 0, clock_offset_ms = 0;
  int motion_blur_samples = 0;
  std::string shutter = "global";
  double line_delay_us = 0;
  double right_offset_ms = 0;  ///< the right image's offset in this run (its spread drawn)
  double right_offset_jitter_ms = 0;
};

/// What the overhead stage did (metrics.json overhead).
struct OverheadRecord {
  std::size_t frames = 0;
  std::size_t tracked = 0;  ///< frames where both markers were found
  double render_s = 0, track_s = 0;
  double plane_z_m = 0;  ///< the height the pixels are mapped onto (the markers' at rest)
  std::string reference_file = "overhead_reference.csv";
  std::string frame_file = "overhead_frame.png";
  void add_to(nlohmann::json* metrics) const;  ///< metrics.json overhead and its timing
};

/// The render, VO, fusion and evaluation stages of a scenario run, when they ran.
struct VisionRecord {
  /// Writes its blocks (timing's render and VO entries, camera, frame_cache, render,
  /// algorithms, external_vo, warnings) into `metrics`.
  void add_to(nlohmann::json* metrics) const;

  int threads = 0;
  double render_s = 0;
  double render_pairs_per_s = 0;
  CameraRecord camera;
  FrameCacheStatus frame_cache;
  std::string render_context, assets;
  std::size_t triangles = 0;
  TrackRecords tracks;
  std::map<std::string, nlohmann::json> external_vo;  ///< each external VO's fate
  std::optional<OverheadRecord> overhead;             ///< the basin's overhead camera
  std::vector<std::string> warnings;
};

}  // namespace driftlab::pipeline
