// What a run measured, as the typed records of metrics.json (record/run_record.hpp) that the
// stages fill: `driftlab run` (pipeline/run.hpp: RunSummary) and `driftlab vo`
// (pipeline/dataset_run.hpp: DatasetRunSummary) share TrackRecords; each adds its blocks to
// one record::RunRecord, written in one place.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "pipeline/frame_source.hpp"
#include "record/run_record.hpp"

namespace driftlab::pipeline {

using record::AlgorithmRecord;
using record::CameraRecord;
using record::ExternalVoRecord;
using record::StagesRecord;

/// The evaluation's APE translation RMSE [m], when it paired poses and the value is finite.
std::optional<double> ape_trans_rmse_m(const AlgorithmRecord& a);

/// A filter against the VO it follows (algorithms.NAME.vs_raw_vo).
record::VsRawVoRecord vs_raw_vo(const std::string& raw_vo, double filtered, double raw);

/// A VO's cost (metrics.json timing.vo_ms_per_frame.NAME, timing.sparse_pairs.NAME).
struct VoTiming {
  double ms_per_frame = 0;
  std::optional<record::SparsePairsRecord> sparse_pairs;  ///< the sparse VOs' detections
};

/// Every track's results and every VO's cost: what both kinds of run report.
struct TrackRecords {
  std::map<std::string, AlgorithmRecord> algorithms;
  std::map<std::string, VoTiming> vo_timing;
  /// Sets algorithms, timing.vo_ms_per_frame and timing.sparse_pairs of `out`.
  void add_to(record::RunRecord* out) const;
};

/// What the overhead stage did (metrics.json overhead).
struct OverheadRecord {
  std::size_t frames = 0;
  std::size_t tracked = 0;  ///< frames where both markers were found
  double render_s = 0, track_s = 0;
  double plane_z_m = 0;  ///< the height the pixels are mapped onto (the markers' at rest)
  std::string reference_file = "overhead_reference.csv";
  std::string frame_file = "overhead_frame.png";
  void add_to(record::RunRecord* out) const;  ///< overhead and its timing
};

/// The render, VO, fusion and evaluation stages of a scenario run, when they ran.
struct VisionRecord {
  /// Sets its blocks (timing's render and VO entries, camera, frame_cache, render,
  /// algorithms, external_vo, overhead, warnings) of `out`.
  void add_to(record::RunRecord* out) const;

  int threads = 0;
  double render_s = 0;
  double render_pairs_per_s = 0;
  CameraRecord camera;
  FrameCacheStatus frame_cache;
  std::string render_context, assets;
  std::size_t triangles = 0;
  TrackRecords tracks;
  std::map<std::string, ExternalVoRecord> external_vo;  ///< each external VO's fate
  std::optional<OverheadRecord> overhead;               ///< the basin's overhead camera
  std::vector<std::string> warnings;
};

}  // namespace driftlab::pipeline
