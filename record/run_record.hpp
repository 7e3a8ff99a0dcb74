// metrics.json of a run (`driftlab run`, `driftlab vo`) as one typed record, after Ceres'
// Solver::Summary: every block a struct whose visit() lists its fields once. That list writes
// metrics.json (write_run_record), reads it back (read_run_record: the one reader report/,
// study/, `driftlab paper` and the tests use) and documents it (docs/metrics-reference.md).
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/record_json.hpp"
#include "eval/evaluation_record.hpp"

namespace driftlab::record {

/// The shape of metrics.json this driftlab writes. A file without the key is version 1, the
/// same shape without it; a newer version is refused.
inline constexpr int kMetricsVersion = 2;

/// A stretch of frames without a VO motion.
struct LostStretchRecord {
  std::size_t first_frame = 0, frames = 0;
  double t_start_s = 0, t_end_s = 0, track_m = 0;
  std::string reason;
  template <class A>
  void visit(A& a) {
    a("first_frame", first_frame, "its first frame's index");
    a("frames", frames, "its length in frames");
    a("t_start_s", t_start_s, "time of its first frame [s]");
    a("t_end_s", t_end_s, "time of its last frame [s]");
    a("track_m", track_m, "distance along the true track where it starts [m]");
    a("reason", reason, "why the first frame had no motion");
  }
};

/// Where a VO lost track.
struct TrackingRecord {
  std::size_t frames = 0, lost_frames = 0, dropped_frames = 0, longest_stretch_frames = 0;
  double lost_fraction = 0;
  std::map<std::string, std::size_t> reasons;
  std::vector<LostStretchRecord> stretches;
  template <class A>
  void visit(A& a) {
    a("frames", frames, "frames the camera delivered after the VO's first");
    a("lost_frames", lost_frames, "of those, frames without a motion estimate");
    a("lost_fraction", lost_fraction, "lost_frames / frames");
    a("dropped_frames", dropped_frames, "frames the camera dropped (no image)");
    a("reasons", reasons, "lost frames by reason");
    a("stretches", stretches, "each run of lost frames");
    a("longest_stretch_frames", longest_stretch_frames, "the longest stretch's frames");
  }
};

/// A filter against the VO it follows.
struct VsRawVoRecord {
  std::string raw_vo, metric = "ape.trans_m.rmse";
  double filtered = 0, raw = 0, ratio = 0;
  bool better = false;
  template <class A>
  void visit(A& a) {
    a("raw_vo", raw_vo, "the VO's track");
    a("metric", metric, "the error compared");
    a("filtered", filtered, "the filter's [m]");
    a("raw", raw, "the VO's [m]");
    a("ratio", ratio, "filtered / raw (< 1: the filter helps)");
    a("better", better, "filtered < raw");
  }
};

/// One track's results (algorithms.NAME): its evaluation, and what its VO or filter reported.
struct AlgorithmRecord {
  eval::EvaluationRecord evaluation;
  std::optional<TrackingRecord> tracking;
  std::optional<std::map<std::string, std::int64_t>> filter;
  std::optional<VsRawVoRecord> vs_raw_vo;
  template <class A>
  void visit(A& a) {
    // A track never evaluated (a filter on a dataset without ground truth) is written without
    // the evaluation's keys; the reader and the reference see them all.
    if (!record_json::is_writer<A> || !evaluation.algorithm.empty()) evaluation.visit(a);
    a("tracking", tracking,
      "where a VO lost track: its frames without a motion estimate, by reason, and each stretch "
      "of them (a stretch of a second or more is a warning)");
    a("filter", filter,
      "a filter's counters: ned_kf and ned_pf steps, vo_fused, heading_fused, resampled; eskf "
      "imu_samples and each measurement's fused, skipped and gated; for every filter "
      "nonfinite_guards (non-finite inputs skipped or states restarted: each one a warning)");
    a("vs_raw_vo", vs_raw_vo, "a filter against the VO it follows");
  }
};

struct SparsePairsRecord {
  std::int64_t detected = 0, shared = 0;
  template <class A>
  void visit(A& a) {
    a("detected", detected, "stereo pairs this VO detected itself");
    a("shared", shared,
      "stereo pairs it took from the VO it shares detection with (which of the two detects a "
      "pair depends on the threads; the two add up to its frames)");
  }
};

/// Wall-clock figures: the one block that differs between two runs of the same scenario.
struct TimingRecord {
  std::optional<double> physics_s, physics_steps_per_s, sensors_s;
  double total_s = 0;
  std::optional<int> threads;
  std::optional<double> render_s, render_pairs_per_s, overhead_render_s, overhead_track_s;
  std::optional<std::map<std::string, double>> vo_ms_per_frame;
  std::optional<std::map<std::string, SparsePairsRecord>> sparse_pairs;
  template <class A>
  void visit(A& a) {
    a("physics_s", physics_s, "the physics stage [s]");
    a("physics_steps_per_s", physics_steps_per_s, "physics steps a second");
    a("sensors_s", sensors_s, "the sensor stage [s]");
    a("total_s", total_s, "the whole run [s]");
    a("threads", threads, "worker threads");
    a("render_s", render_s, "rendering [s]");
    a("render_pairs_per_s", render_pairs_per_s, "stereo pairs rendered a second");
    a("overhead_render_s", overhead_render_s, "the overhead camera's rendering [s]");
    a("overhead_track_s", overhead_track_s, "its marker tracking [s]");
    a("vo_ms_per_frame", vo_ms_per_frame, "each VO's time a frame [ms]");
    a("sparse_pairs", sparse_pairs, "the sparse VOs' detections, summed over the run");
  }
};

struct MotionRecord {
  bool mission_completed = false;
  double duration_s = 0, distance_m = 0, mean_speed_m_s = 0;
  std::size_t physics_steps = 0;
  template <class A>
  void visit(A& a) {
    a("mission_completed", mission_completed, "the vessel reached the mission's end");
    a("duration_s", duration_s, "simulated time [s]");
    a("distance_m", distance_m, "path length of the centre of gravity [m]");
    a("mean_speed_m_s", mean_speed_m_s, "distance_m / duration_s [m/s]");
    a("physics_steps", physics_steps, "physics steps");
  }
};

/// What each stage did, or why it did not run.
struct StagesRecord {
  std::string scenario, physics, sensors, render, vo, external_vo, fusion, eval;
  template <class A>
  void visit(A& a) {
    a("scenario", scenario, "the scenario stage");
    a("physics", physics, "the physics stage");
    a("sensors", sensors, "the sensor stage");
    a("render", render, "the render stage");
    a("vo", vo, "the VO stage");
    a("external_vo", external_vo, "the external VOs");
    a("fusion", fusion, "the filters");
    a("eval", eval, "the evaluation");
  }
};

struct ImuRecord {
  std::size_t samples = 0;
  double rate_hz = 0;
  template <class A>
  void visit(A& a) {
    a("samples", samples, "samples written to imu.csv");
    a("rate_hz", rate_hz, "sample rate [Hz]");
  }
};

struct AhrsRecord {
  std::size_t samples = 0;
  double rate_hz = 0, roll_rmse_deg = 0, pitch_rmse_deg = 0, yaw_rmse_deg = 0;
  template <class A>
  void visit(A& a) {
    a("samples", samples, "samples written to ahrs.csv");
    a("rate_hz", rate_hz, "sample rate [Hz]");
    a("roll_rmse_deg", roll_rmse_deg, "its roll error, RMS [deg]");
    a("pitch_rmse_deg", pitch_rmse_deg, "its pitch error, RMS [deg]");
    a("yaw_rmse_deg", yaw_rmse_deg, "its yaw error, RMS [deg]");
  }
};

struct GpsRecord {
  std::size_t epochs = 0;
  double fix_fraction = 0, below_min_satellites_fraction = 0, median_satellites = 0;
  double mean_hdop_with_fix = eval::kUnmeasured;
  std::string sky;
  template <class A>
  void visit(A& a) {
    a("epochs", epochs, "epochs written to gps.csv");
    a("fix_fraction", fix_fraction, "share of epochs with a fix");
    a("below_min_satellites_fraction", below_min_satellites_fraction,
      "share of epochs with fewer satellites than the fix needs");
    a("median_satellites", median_satellites, "satellites in view, median");
    a("mean_hdop_with_fix", mean_hdop_with_fix, "HDOP over the epochs with a fix (null: none)");
    a("sky", sky,
      "what hides satellites: scene meshes, or open (the river paper: 46 % of the time below "
      "4 satellites, median 4, mean HDOP 2.8)");
  }
};

struct CompassRecord {
  std::size_t samples = 0, anomalies = 0;
  double heading_rmse_deg = 0, heading_max_error_deg = 0;
  template <class A>
  void visit(A& a) {
    a("samples", samples, "samples written to compass.csv");
    a("anomalies", anomalies, "magnetic anomalies along the track");
    a("heading_rmse_deg", heading_rmse_deg, "heading error, RMS [deg]");
    a("heading_max_error_deg", heading_max_error_deg, "heading error, largest [deg]");
  }
};

/// The sensors that ran, each with its samples and errors.
struct SensorsRecord {
  std::optional<ImuRecord> imu;
  std::optional<AhrsRecord> ahrs;
  std::optional<GpsRecord> gps;
  std::optional<CompassRecord> compass;
  template <class A>
  void visit(A& a) {
    a("imu", imu, "the IMU");
    a("ahrs", ahrs, "the AHRS (the river paper's x-IMU)");
    a("gps", gps, "the GPS receiver");
    a("compass", compass, "the compass");
  }
};

/// The camera as the run saw it.
struct CameraRecord {
  std::size_t frames_delivered = 0, frames_dropped = 0;
  bool noise = false, lens_distortion = false;
  double vignetting_strength = 0, motion_blur_step_px = 0, clock_offset_ms = 0;
  int motion_blur_samples = 0;
  std::string shutter = "global";
  double line_delay_us = 0, right_offset_ms = 0, right_offset_jitter_ms = 0;
  template <class A>
  void visit(A& a) {
    a("frames_delivered", frames_delivered, "stereo pairs delivered");
    a("frames_dropped", frames_dropped, "stereo pairs dropped");
    a("noise", noise, "sensor noise on");
    a("vignetting_strength", vignetting_strength, "vignetting at the corners (0: none)");
    a("motion_blur_samples", motion_blur_samples, "sub-frames averaged for motion blur");
    a("motion_blur_step_px", motion_blur_step_px, "largest image motion between sub-frames [px]");
    a("lens_distortion", lens_distortion, "lens distortion on");
    a("clock_offset_ms", clock_offset_ms, "camera clock's offset [ms]");
    a("shutter", shutter, "global or rolling");
    a("line_delay_us", line_delay_us, "rolling shutter's line delay [us]");
    a("right_offset_ms", right_offset_ms, "the right image's time offset in this run [ms]");
    a("right_offset_jitter_ms", right_offset_jitter_ms, "its jitter [ms]");
  }
};

struct FrameCacheRecord {
  std::string state, entry, note;
  template <class A>
  void visit(A& a) {
    a("state", state, "off, hit (replayed), filled (rendered and kept) or miss");
    a("entry", entry, "the entry's folder");
    a("note", note, "why off or not kept");
  }
};

struct RenderRecord {
  std::string context, assets;
  std::size_t triangles = 0;
  template <class A>
  void visit(A& a) {
    a("context", context, "the GL context (osmesa or egl) and its renderer");
    a("assets", assets, "the scene's assets");
    a("triangles", triangles, "triangles in the scene");
  }
};

/// The basin's overhead camera.
struct OverheadRecord {
  std::size_t frames = 0, tracked = 0;
  double plane_z_m = 0;
  std::string reference, frame;
  template <class A>
  void visit(A& a) {
    a("frames", frames, "overhead frames");
    a("tracked", tracked, "frames where both markers were found");
    a("plane_z_m", plane_z_m, "height the pixels are mapped onto (the markers' at rest) [m]");
    a("reference", reference, "its reference trajectory's file");
    a("frame", frame, "its first frame's file");
  }
};

/// An external VO's fate.
struct ExternalVoRecord {
  std::string status, command, format, output, exit, message, log_tail;
  double seconds = 0;
  std::size_t frames = 0;
  template <class A>
  void visit(A& a) {
    a("status", status, "ok, failed, timeout or bad output");
    a("command", command, "the command as run (its paths name the run's folder)");
    a("format", format, "the dataset format it was given");
    a("output", output, "the trajectory format it wrote");
    a("exit", exit, "how the command ended (exit code 0, killed by signal 9 (Killed))");
    a("seconds", seconds, "its wall-clock time [s]");
    a("frames", frames, "frames it was given");
    a("message", message, "the warning, if any");
    a("log_tail", log_tail, "the end of its log");
  }
};

struct TrackLengthRecord {
  double length_m = 0;
  template <class A>
  void visit(A& a) {
    a("length_m", length_m, "the left camera's true path length [m]");
  }
};

/// The dataset a `driftlab vo` run read.
struct DatasetRecord {
  std::string root, format;
  std::size_t frames_used = 0, first_frame = 0, imu_samples = 0, compass_samples = 0;
  bool ground_truth = false;
  double fx_px = 0, baseline_m = 0;
  int width_px = 0, height_px = 0;
  template <class A>
  void visit(A& a) {
    a("root", root, "its folder");
    a("format", format, "its format");
    a("frames_used", frames_used, "stereo pairs the VOs ran on");
    a("first_frame", first_frame, "the first of them (the first with ground truth)");
    a("ground_truth", ground_truth, "it has ground truth");
    a("imu_samples", imu_samples, "IMU samples");
    a("compass_samples", compass_samples, "compass samples");
    a("fx_px", fx_px, "the left camera's focal length [px]");
    a("baseline_m", baseline_m, "the stereo baseline [m]");
    a("width_px", width_px, "image width [px]");
    a("height_px", height_px, "image height [px]");
  }
};

struct FiltersWorldRecord {
  std::string down_axis;
  double tilt_deg = 0;
  template <class A>
  void visit(A& a) {
    a("down_axis", down_axis, "the dataset's axis taken as down");
    a("tilt_deg", tilt_deg, "between gravity and that axis [deg]");
  }
};

/// metrics.json of a scenario run (`driftlab run`) or of a run on a dataset (`driftlab vo`).
struct RunRecord {
  int metrics_version = kMetricsVersion;
  std::string version;
  std::uint64_t seed = 0;
  std::optional<std::string> scenario;
  std::optional<std::size_t> frames;
  std::optional<TrackLengthRecord> track;
  std::optional<MotionRecord> motion;
  std::optional<StagesRecord> stages;
  std::optional<SensorsRecord> sensors;
  std::optional<DatasetRecord> dataset;
  std::optional<FiltersWorldRecord> filters_world;
  TimingRecord timing;
  std::optional<CameraRecord> camera;
  std::optional<FrameCacheRecord> frame_cache;
  std::optional<RenderRecord> render;
  std::map<std::string, AlgorithmRecord> algorithms;
  std::optional<std::map<std::string, ExternalVoRecord>> external_vo;
  std::optional<OverheadRecord> overhead;
  std::vector<std::string> warnings;
  template <class A>
  void visit(A& a) {
    a("metrics_version", metrics_version, "this file's shape (absent: 1)");
    a("version", version, "the driftlab that wrote it");
    a("seed", seed, "the scenario's seed");
    a("scenario", scenario, "the scenario's name (driftlab run)");
    a("frames", frames, "camera frames with ground truth (driftlab run)");
    a("track", track, "the true track (driftlab run)");
    a("motion", motion, "the vessel's motion (driftlab run)");
    a("stages", stages, "each stage: done, or skipped (why) (driftlab run)");
    a("sensors", sensors, "the sensors that ran (driftlab run)");
    a("dataset", dataset, "the dataset read (driftlab vo)");
    a("filters_world", filters_world, "the filters' levelled world (driftlab vo)");
    a("timing", timing,
      "wall-clock figures: the only keys that differ between two runs of the same seed, or of "
      "different thread counts");
    a("camera", camera, "the camera as the run saw it (when it rendered)");
    a("frame_cache", frame_cache, "the frame cache (when it rendered)");
    a("render", render, "the renderer (when it rendered)");
    a("algorithms", algorithms, "each track's results, by the track's name");
    a("external_vo", external_vo, "each external VO's fate");
    a("overhead", overhead, "the basin's overhead camera");
    a("warnings", warnings, "stages skipped, plots not drawn, results in doubt");
  }
};

/// metrics.json's text: 2-space indent, keys sorted, a final newline.
std::string metrics_text(const RunRecord& record);

/// Reads a run's metrics.json (a file, or the run's folder). Throws UserError naming the file
/// and the key when it is not a run's metrics, or written by a newer driftlab.
RunRecord read_run_record(const std::filesystem::path& path);

/// The same, from JSON already parsed; `source` names it in errors.
RunRecord run_record_from_json(const nlohmann::json& j, const std::string& source);

/// docs/metrics-reference.md's table: every key, its type and its meaning.
std::string metrics_reference_markdown();

}  // namespace driftlab::record
