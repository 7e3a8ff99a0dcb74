#include "pipeline/dataset_run.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "core/atomic_file.hpp"
#include "core/rng.hpp"
#include "core/rotation.hpp"
#include "core/stopwatch.hpp"
#include "core/yaml_io.hpp"
#include "eval/evaluate.hpp"
#include "pipeline/frame_source.hpp"
#include "pipeline/progress.hpp"
#include "pipeline/sensor_stage.hpp"
#include "pipeline/tracking.hpp"
#include "pipeline/tracks.hpp"
#include "pipeline/vo_stage.hpp"
#include "sim/sensors/clock.hpp"

#ifndef DRIFTLAB_VERSION
#define DRIFTLAB_VERSION "unknown"
#endif

namespace driftlab::pipeline {
namespace fs = std::filesystem;

namespace {

// The first frame with a true pose (all of them start there), and that pose.
std::pair<std::size_t, SE3> first_anchored(const dataset::StereoDataset& d) {
  if (d.camera_gt.empty()) return {0, SE3()};
  for (std::size_t i = 0; i < d.frames.size(); ++i)
    if (const auto T = dataset::pose_at(d.camera_gt, d.frames[i].t_ns)) return {i, *T};
  throw UserError(
      fmt::format("{}: no frame lies within the ground truth's time span", d.root.string()));
}

// Per-frame covariates of a track (its VO's): the features it counts (covariate f of the river
// paper's Table 4), their mean depth and whether it lost track, as frames.csv has them.
eval::FrameTable covariates(const Track& src, const std::vector<dataset::DatasetFrame>& frames) {
  eval::FrameTable ft;
  ft.names = {"inliers", "mean_depth_m", "lost"};
  ft.columns.resize(3);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t k = 0; k < src.results.size(); ++k) {
    const vo::VoResult& r = src.results[k];
    ft.t_ns.push_back(frames[k].t_ns);
    ft.columns[0].push_back(r.valid ? r.feature_count() : nan);
    ft.columns[1].push_back(r.valid ? r.mean_inlier_depth_m : nan);
    ft.columns[2].push_back(lost_track(r) ? 1.0 : 0.0);
  }
  return ft;
}

// The filters' world: the dataset's world W turned so that its axis nearest to gravity is
// down (z of the filters' NED). The IMU's mean specific force over the second around the first
// frame, turned into W by the true attitude there, points up.
struct LevelledWorld {
  Mat3 R_N_W = Mat3::Identity();
  std::string down_axis = "+z";
  double tilt_deg = 0;  // between gravity and that axis
};

LevelledWorld level_world(const std::vector<ImuSample>& imu, const SE3& T_W_S0, TimeNs t0) {
  LevelledWorld w;
  Vec3 f = Vec3::Zero();
  for (const ImuSample& s : imu)
    if (std::abs(static_cast<double>(s.t_ns - t0)) <= 0.5e9) f += s.accel_m_s2;
  if (!(f.norm() > 0)) f = imu.front().accel_m_s2;  // no sample near the first frame
  const Vec3 down_W = -(T_W_S0.rotation() * f).normalized();
  int best = 0;  // the signed world axis nearest to down
  for (int i = 1; i < 3; ++i)
    if (std::abs(down_W[i]) > std::abs(down_W[best])) best = i;
  const double sign = down_W[best] >= 0 ? 1.0 : -1.0;
  w.down_axis = std::string(sign > 0 ? "+" : "-") + "xyz"[best];
  w.tilt_deg = rad2deg(std::acos(std::min(1.0, std::abs(down_W[best]))));
  const Vec3 z = sign * Vec3::Unit(best);
  const Vec3 x = Vec3::Unit(best == 0 ? 1 : 0);  // the first world axis across gravity
  w.R_N_W.row(0) = x.transpose();
  w.R_N_W.row(1) = z.cross(x).transpose();
  w.R_N_W.row(2) = z.transpose();
  return w;
}

// What the filters read from the dataset: its IMU from the last sample at or before the first
// frame `t0` on (the filters start there, at the anchor), and its compass (no GPS: a dataset's
// fixes carry no validity time).
SensorData dataset_sensors(const dataset::StereoDataset& d, TimeNs t0) {
  SensorData s;
  auto from = std::upper_bound(d.imu.begin(), d.imu.end(), t0,
                               [](TimeNs t, const ImuSample& x) { return t < x.t_ns; });
  if (from != d.imu.begin()) --from;
  s.imu.assign(from, d.imu.end());
  for (const dataset::CompassReading& c : d.compass) {
    sim::CompassSample m;
    m.t_ns = c.t_ns;
    m.heading_rad = c.heading_rad;
    s.compass.push_back(m);
  }
  return s;
}

// The body is the dataset's IMU frame S (EuRoC's B): the camera's T_BS from the dataset, the
// compass and GPS antenna from the settings' mounts, taken relative to the settings' IMU; the
// IMU noise from the dataset's imu0/sensor.yaml when it has one, else the settings' sensors.imu.
FilterMounts dataset_mounts(const dataset::StereoDataset& d, const Scenario& settings) {
  const FilterMounts from_settings = filter_mounts(settings);
  const SE3 T_S_B = from_settings.T_B_I.inverse();
  FilterMounts m;
  m.T_B_C = d.T_S_C;
  m.T_B_I = SE3();
  m.R_B_M = T_S_B.rotation() * from_settings.R_B_M;
  m.p_B_antenna_m = T_S_B * from_settings.p_B_antenna_m;
  m.gps_sigma_horizontal_m = from_settings.gps_sigma_horizontal_m;
  m.compass_noise_rad = from_settings.compass_noise_rad;
  m.imu_noise = from_settings.imu_noise;
  if (d.imu_noise)  // the dataset's Kalibr model (imu0/sensor.yaml) over the settings' IMU
    m.imu_noise = {d.imu_noise->gyroscope_noise_density, d.imu_noise->gyroscope_random_walk,
                   d.imu_noise->accelerometer_noise_density,
                   d.imu_noise->accelerometer_random_walk};
  return m;
}

// The filters the dataset can feed: every one of `asked` (explicit: an error for one it
// cannot; from the settings: skipped with a warning).
std::vector<FusionAlgorithm> runnable_filters(const dataset::StereoDataset& d,
                                              const std::vector<FusionAlgorithm>& asked,
                                              bool explicit_request,
                                              std::vector<std::string>* warnings) {
  std::vector<FusionAlgorithm> out;
  for (FusionAlgorithm f : asked) {
    std::string missing;
    const bool imu = f == FusionAlgorithm::kEskf;
    const bool compass = f == FusionAlgorithm::kNedKf || f == FusionAlgorithm::kNedPf;
    if ((imu || compass) && !d.has_extrinsics)
      missing = "the camera's pose on the body (EuRoC's cam0 T_BS)";
    else if (imu && d.imu.empty())
      missing = "an IMU (EuRoC's mav0/imu0/data.csv)";
    else if (compass && d.compass.empty())
      missing = "a compass (mav0/compass0/data.csv, as driftlab's EuRoC exports have)";
    if (missing.empty()) {
      out.push_back(f);
      continue;
    }
    const std::string why =
        fmt::format("{} needs {}; {} has none", yaml::enum_name(f), missing, d.root.string());
    if (explicit_request) throw UserError("driftlab vo: --fusion: " + why);
    warnings->push_back(why + " (skipped)");
  }
  return out;
}

// The VO tracks, then one track per VO for each filter, all starting at the anchor. Filters
// work in the levelled world N; `T_N_W` takes the anchor there.
std::vector<Track> make_dataset_tracks(const dataset::StereoDataset& d, const Scenario& settings,
                                       const std::vector<std::string>& algorithms,
                                       const std::vector<FusionAlgorithm>& fusion,
                                       const SensorData& sensors, const SE3& T_W_C0,
                                       const SE3& T_N_W,
                                       const std::vector<dataset::DatasetFrame>& used) {
  const RngStreams rng(settings.seed);
  std::vector<Track> tracks;
  std::vector<std::unique_ptr<vo::StereoOdometry>> vos =
      make_vos(algorithms, d.rig, settings.pipeline, rng);
  for (std::size_t i = 0; i < vos.size(); ++i) {
    Track t;
    t.name = algorithms[i];
    t.vo = std::move(vos[i]);
    t.results.resize(used.size());
    tracks.push_back(std::move(t));
  }
  if (tracks.empty()) throw UserError("driftlab vo: no VO to run (--algo or pipeline.vo)");
  const PipelineOptions& options = settings.pipeline;
  const FilterMounts mounts = dataset_mounts(d, settings);
  const SE3 T_N_C0 = T_N_W * T_W_C0;
  const SE3 T_N_B0 = T_N_C0 * mounts.T_B_C.inverse();
  add_filter_tracks(
      fusion, tracks.size(),
      [&](FusionAlgorithm f) {
        return std::make_unique<FilterTrack>(f, options, mounts, sensors, T_N_B0, T_N_C0, rng);
      },
      &tracks);
  if (!used.empty())
    for (Track& t : tracks) t.estimate.push_back({used.front().t_ns, T_W_C0});
  return tracks;
}

// Every frame through every track (the VOs, side by side when `threads` >= 2, then the filters
// following them), a frames.csv row each.
void run_frames(const dataset::StereoDataset& d, const std::vector<dataset::DatasetFrame>& used,
                const fs::path& dir, const DatasetRunOptions& options, int threads,
                std::vector<Track>* tracks_io) {
  std::vector<Track>& tracks = *tracks_io;
  AtomicFile frames_csv(dir / "frames.csv");
  std::string header = "t_ns";
  for (const Track& t : tracks)
    if (t.vo) header += vo_csv_header(t.name);
  frames_csv.write(header + "\n");
  Progress progress(options.progress, "vo", used.size(), options.progress_tty);
  for (std::size_t k = 0; k < used.size(); ++k) {
    progress.update(k);
    auto [left, right] = dataset::read_pair(d, used[k]);  // rectified when raw
    const vo::StereoFrame frame{used[k].t_ns, left, right};
    std::string row = std::to_string(frame.t_ns);
    const std::vector<vo::VoResult> vo_results = process_vos(&tracks, frame, threads);
    for (std::size_t i = 0; i < tracks.size(); ++i) {
      Track& t = tracks[i];
      const vo::VoResult& r = t.vo ? vo_results[i] : tracks[t.source].results[k];
      if (t.vo) row += vo_csv_cells(r);
      advance_track(&t, k, k == 0, frame.t_ns, r);
    }
    frames_csv.write(row + "\n");
  }
  progress.update(used.size());
  progress.finish();
  frames_csv.commit();
}

// After the frame loop: the filters' poses back from the levelled world N into the dataset's
// (R_N_W the identity: left as they are, to the bit), then the smoother's backward pass over
// every VO track when pipeline.ca_smoother asks for it.
void finish_tracks(const PipelineOptions& pipeline, const std::vector<dataset::DatasetFrame>& used,
                   const Mat3& R_N_W, std::vector<Track>* tracks_io) {
  std::vector<Track>& tracks = *tracks_io;
  if (R_N_W != Mat3::Identity()) {
    const SE3 T_W_N(Mat3(R_N_W.transpose()), Vec3::Zero());
    for (Track& t : tracks)
      if (t.filter)
        for (std::size_t j = 1; j < t.estimate.size(); ++j)
          t.estimate[j].T_W_C = T_W_N * t.estimate[j].T_W_C;
  }
  if (!runs_backward_pass(pipeline)) return;
  std::vector<std::optional<TimeNs>> delivered;  // a dataset drops no frame
  for (const auto& f : used) delivered.push_back(f.t_ns);
  const std::size_t n_vo = static_cast<std::size_t>(
      std::count_if(tracks.begin(), tracks.end(), [](const Track& t) { return t.vo != nullptr; }));
  for (std::size_t i = 0; i < n_vo; ++i)
    tracks.push_back(rts_smoothed(tracks[i], i, delivered, pipeline.ca_smoother));
}

// Every track against the dataset's ground truth: metrics.json's algorithms, tables.md and
// sections.csv; one brief line per track.
std::vector<std::string> evaluate_tracks(const dataset::StereoDataset& d, const Scenario& settings,
                                         const std::vector<Track>& tracks,
                                         const std::vector<dataset::DatasetFrame>& used,
                                         const fs::path& dir, TrackRecords* records,
                                         std::vector<std::string>* warnings) {
  std::vector<std::string> briefs;
  std::string tables, sections;
  for (const Track& t : tracks) {
    if (t.vo)
      records->vo_timing[t.name] =
          vo_timing(*t.vo, used.empty() ? 0.0 : t.vo_ms / static_cast<double>(used.size()));
    if (d.camera_gt.empty()) {
      briefs.push_back(t.name + ": no ground truth, estimate only");
      continue;
    }
    eval::EvaluationInput in;
    in.gt = d.camera_gt;
    in.est = t.estimate;
    in.gt_label = "groundtruth.tum";
    in.est_label = "estimates/" + t.name + ".tum";
    in.algorithm = t.name;
    in.options = settings.eval;
    in.frames = covariates(t.vo ? t : tracks[t.source], used);
    const eval::Evaluation e = eval::evaluate(in);
    records->algorithms[t.name].evaluation = eval::evaluation_record(e, settings.eval);
    tables += eval::tables_markdown(e, settings.eval) + "\n";
    const std::string csv = eval::sections_csv(e);
    sections += sections.empty() ? csv : csv.substr(csv.find('\n') + 1);
    briefs.push_back(e.brief());
  }
  if (!d.camera_gt.empty()) tables += compare_filters_with_raw_vo(tracks, records, warnings);
  report_filter_counts(tracks, records, warnings);
  if (!sections.empty()) write_file_atomic(dir / "sections.csv", sections);
  write_file_atomic(dir / "tables.md",
                    fmt::format("# driftlab vo: {}\n\n{}", d.root.string(), tables));
  return briefs;
}

record::DatasetRecord dataset_record(const dataset::StereoDataset& d, std::size_t used,
                                     std::size_t first) {
  record::DatasetRecord r;
  r.root = d.root.string();
  r.format = dataset::format_name(d.format);
  r.frames_used = used;
  r.first_frame = first;
  r.ground_truth = !d.camera_gt.empty();
  r.imu_samples = d.imu.size();
  r.compass_samples = d.compass.size();
  r.fx_px = d.rig.camera.fx;
  r.baseline_m = d.rig.baseline_m;
  r.width_px = d.rig.camera.width;
  r.height_px = d.rig.camera.height;
  return r;
}

}  // namespace

record::RunRecord DatasetRunSummary::run_record() const {
  record::RunRecord r;
  r.version = DRIFTLAB_VERSION;
  r.seed = seed;
  r.dataset = dataset;
  r.filters_world = filters_world;
  tracks.add_to(&r);
  r.timing.total_s = total_s;
  r.warnings = warnings;
  return r;
}

std::string DatasetRunSummary::brief() const {
  std::string s = fmt::format("{} stereo frames in {:.2f} s", frames, total_s);
  for (const auto& a : algorithms) s += "\n  " + a;
  for (const auto& w : warnings) s += "\n  warning: " + w;
  return s;
}

DatasetRunSummary run_on_dataset(const dataset::StereoDataset& d, const Scenario& settings,
                                 const fs::path& out_dir, const DatasetRunOptions& options) {
  const auto t0 = SteadyClock::now();
  AtomicDirectory dir(out_dir, options.replace_existing);
  write_file_atomic(dir.path() / "scenario.resolved.yaml", resolved_yaml(settings));
  DatasetRunSummary summary;
  const auto [first, T_W_C0] = first_anchored(d);
  std::size_t end = d.frames.size();
  if (options.max_frames > 0) end = std::min(end, first + options.max_frames);
  const std::vector<dataset::DatasetFrame> used(d.frames.begin() + first, d.frames.begin() + end);
  const std::vector<FusionAlgorithm> fusion = runnable_filters(
      d, settings.pipeline.fusion, options.fusion_on_command_line, &summary.warnings);
  LevelledWorld world;
  const bool gravity = std::any_of(fusion.begin(), fusion.end(), [](FusionAlgorithm f) {
    return f != FusionAlgorithm::kCaSmoother;
  });
  if (gravity && !d.imu.empty() && !used.empty()) {
    world = level_world(d.imu, T_W_C0 * d.T_S_C.inverse(), used.front().t_ns);
    summary.filters_world = record::FiltersWorldRecord{world.down_axis, world.tilt_deg};
    if (world.tilt_deg > 2.0)
      summary.warnings.push_back(fmt::format(
          "the dataset's world is tilted {:.1f} deg from gravity; the filters take {} as down",
          world.tilt_deg, world.down_axis));
  }
  const bool levelled = world.R_N_W != Mat3::Identity();
  const SensorData sensors = dataset_sensors(d, used.empty() ? 0 : used.front().t_ns);
  std::vector<Track> tracks = make_dataset_tracks(
      d, settings, options.algorithms.empty() ? settings.pipeline.vo : options.algorithms, fusion,
      sensors, T_W_C0, levelled ? SE3(world.R_N_W, Vec3::Zero()) : SE3(), used);
  run_frames(d, used, dir.path(), options, run_threads(settings.pipeline.threads), &tracks);
  finish_tracks(settings.pipeline, used, levelled ? world.R_N_W : Mat3::Identity(), &tracks);
  write_estimates(tracks, dir.path());
  if (!d.camera_gt.empty()) write_tum(dir.path() / "groundtruth.tum", d.camera_gt);
  summary.seed = settings.seed;
  summary.dataset = dataset_record(d, used.size(), first);
  summary.frames = used.size();
  summary.algorithms =
      evaluate_tracks(d, settings, tracks, used, dir.path(), &summary.tracks, &summary.warnings);
  summary.total_s = seconds_since(t0);
  write_file_atomic(dir.path() / "metrics.json", record::metrics_text(summary.run_record()));
  dir.commit();
  return summary;
}

}  // namespace driftlab::pipeline
