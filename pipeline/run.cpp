#include "pipeline/run.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <iterator>
#include <nlohmann/json.hpp>
#include <optional>

#include "core/atomic_file.hpp"
#include "core/rng.hpp"
#include "core/rotation.hpp"
#include "core/stopwatch.hpp"
#include "core/trajectory_io.hpp"
#include "core/yaml_io.hpp"
#include "eval/evaluate.hpp"
#include "fusion/ca_smoother.hpp"
#include "pipeline/camera_stage.hpp"
#include "pipeline/external_vo.hpp"
#include "pipeline/filter_stage.hpp"
#include "pipeline/frame_source.hpp"
#include "pipeline/overhead_stage.hpp"
#include "pipeline/progress.hpp"
#include "pipeline/render_stage.hpp"
#include "pipeline/scenario_checks.hpp"
#include "pipeline/sensor_stage.hpp"
#include "pipeline/tracking.hpp"
#include "pipeline/tracks.hpp"
#include "pipeline/vo_pipeline.hpp"
#include "pipeline/vo_stage.hpp"
#include "report/run_report.hpp"
#include "scenes/assets.hpp"
#include "scenes/build_scene.hpp"
#include "sim/physics/waves/wave_field.hpp"
#include "sim/render/renderer.hpp"
#include "sim/sensors/clock.hpp"
#include "vo/sparse/sparse_vo.hpp"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#ifndef DRIFTLAB_VERSION
#define DRIFTLAB_VERSION "unknown"
#endif

namespace driftlab::pipeline {
namespace {

std::string body_csv_header() {
  return "t_ns,north_m,east_m,down_m,qw,qx,qy,qz,roll_deg,pitch_deg,yaw_deg,"
         "u_m_s,v_m_s,w_m_s,p_rad_s,q_rad_s,r_rad_s,"
         "du_m_s2,dv_m_s2,dw_m_s2,dp_rad_s2,dq_rad_s2,dr_rad_s2\n";
}

std::string body_csv_row(const sim::BodySample& b) {
  const auto& s = b.state;
  const EulerZYX e = euler_zyx_from_quat(s.q_W_B);
  auto f = [](double v) { return yaml::format_double(v); };
  return fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
                     b.t_ns, f(s.p_W.x()), f(s.p_W.y()), f(s.p_W.z()), f(s.q_W_B.w()),
                     f(s.q_W_B.x()), f(s.q_W_B.y()), f(s.q_W_B.z()), f(rad2deg(e.roll_rad)),
                     f(rad2deg(e.pitch_rad)), f(rad2deg(e.yaw_rad)), f(s.v_B.x()), f(s.v_B.y()),
                     f(s.v_B.z()), f(s.w_B.x()), f(s.w_B.y()), f(s.w_B.z()), f(b.v_dot_B.x()),
                     f(b.v_dot_B.y()), f(b.v_dot_B.z()), f(b.w_dot_B.x()), f(b.w_dot_B.y()),
                     f(b.w_dot_B.z()));
}

}  // namespace

std::string RunSummary::brief() const {
  std::string s = fmt::format("{}; {} camera frames, camera track {:.2f} m; physics {:.2f} s",
                              motion.brief(), frames, track_length_m, physics_s);
  if (vision && vision->render_pairs_per_s > 0)
    s += fmt::format(", render {:.1f} pairs/s", vision->render_pairs_per_s);
  return s + fmt::format(", total {:.2f} s", total_s);
}

record::RunRecord RunSummary::run_record() const {
  record::RunRecord r;
  r.version = DRIFTLAB_VERSION;
  r.seed = seed;
  r.scenario = scenario;
  r.frames = frames;
  r.track = record::TrackLengthRecord{track_length_m};
  r.motion = record::MotionRecord{motion.mission_completed, motion.duration_s, motion.distance_m,
                                  motion.mean_speed_mps, motion.steps};
  r.stages = stages;
  if (sensors.imu || sensors.ahrs || sensors.gps || sensors.compass) r.sensors = sensors;
  r.timing.sensors_s = sensors_s;
  r.timing.physics_s = physics_s;
  r.timing.total_s = total_s;
  r.timing.physics_steps_per_s =
      physics_s > 0 ? static_cast<double>(motion.steps) / physics_s : 0.0;
  if (vision) vision->add_to(&r);
  return r;
}

SE3 camera_mount_T_B_C(const sim::MountOptions& mount) {
  const Quat q_mount = quat_from_euler_zyx(
      {deg2rad(mount.rpy_deg[0]), deg2rad(mount.rpy_deg[1]), deg2rad(mount.rpy_deg[2])});
  const Mat3 R_B_C = q_mount.toRotationMatrix() * R_frd_optical();
  const auto& p = mount.position_frd_m;
  return SE3(R_B_C, Vec3(p[0], p[1], p[2]));
}

double motion_end_s(const Scenario& sc) {
  double end_s = sc.mission.duration_s;
  if (sc.pipeline.max_frames > 0) {
    // The last frame's time; for one frame (t = 0) one physics step, as an end of 0 means none.
    const double frames_s = sc.pipeline.max_frames > 1
                                ? (sc.pipeline.max_frames - 1) / sc.sensors.camera.rate_hz
                                : 1.0 / sc.vessel.physics_rate_hz;
    end_s = end_s > 0 ? std::min(end_s, frames_s) : frames_s;
  }
  return end_s > 0 ? end_s : sim::MotionOptions{}.hard_limit_s;
}

sim::MotionSummary simulate_scenario_motion(
    const Scenario& sc, const std::function<void(const sim::BodySample&)>& on_physics,
    const std::function<void(const sim::BodySample&)>& on_frame) {
  return simulate_scenario_motion(sc, on_physics, on_frame, {}, nullptr);
}

sim::MotionSummary simulate_scenario_motion(
    const Scenario& sc, const std::function<void(const sim::BodySample&)>& on_physics,
    const std::function<void(const sim::BodySample&)>& on_frame,
    const std::vector<TimeNs>& extra_times,
    const std::function<void(const sim::BodySample&)>& on_extra) {
  // Waves and vessel from the scenario, the mission planned in the scene's geometry.
  const RngStreams rng(sc.seed);
  const auto waves = sim::make_wave_field(sc.water.waves, rng.stream("waves.phases"));
  sim::Environment env;
  env.waves = waves.get();
  env.current = sc.water.current;
  env.channel_half_width_m = sc.scene.river_reach.river_width_m / 2;
  const sim::VesselModel model(sc.vessel);
  const sim::Vec2 start(sc.vessel.start_ne_m[0], sc.vessel.start_ne_m[1]);
  const double heading = deg2rad(sc.vessel.start_heading_deg);
  sim::MissionContext context;
  context.river_width_m = sc.scene.river_reach.river_width_m;
  context.survey_leg_length_m = 0.8 * sc.scene.river_reach.reach_length_m;  // river_reach.cpp
  sim::Guidance guidance(model, sim::plan_mission(sc.mission, start, heading, context), sc.mission);
  sim::MotionOptions motion;
  motion.physics_rate_hz = sc.vessel.physics_rate_hz;
  motion.max_duration_s = sc.mission.duration_s;
  const double end_s = motion_end_s(sc);
  if (sc.pipeline.max_frames > 0 || sc.mission.duration_s > 0) motion.max_duration_s = end_s;
  const std::vector<TimeNs> frame_times = sim::sample_times(sc.sensors.camera.rate_hz, end_s);
  if (extra_times.empty() || !on_extra)
    return sim::simulate(model, env, &guidance, sim::initial_state(model, start, heading), motion,
                         frame_times, on_physics, on_frame);
  // Camera frames and the other sensors' times in one sorted list; each time goes to whoever
  // asked for it (both, when they coincide).
  std::vector<TimeNs> all;
  all.reserve(frame_times.size() + extra_times.size());
  std::merge(frame_times.begin(), frame_times.end(), extra_times.begin(), extra_times.end(),
             std::back_inserter(all));
  all.erase(std::unique(all.begin(), all.end()), all.end());
  std::size_t next_frame = 0, next_extra = 0;
  return sim::simulate(model, env, &guidance, sim::initial_state(model, start, heading), motion,
                       all, on_physics, [&](const sim::BodySample& b) {
                         if (next_frame < frame_times.size() && frame_times[next_frame] == b.t_ns) {
                           ++next_frame;
                           on_frame(b);
                         }
                         if (next_extra < extra_times.size() && extra_times[next_extra] == b.t_ns) {
                           ++next_extra;
                           on_extra(b);
                         }
                       });
}

namespace {

// Fig. 3 of the river paper: the current left image above the right one, each match's
// points joined across the pair, its flow from the previous frame drawn in the left image.
cv::Mat draw_matches(const vo::StereoFrame& frame, std::span<const vo::MatchInfo> matches) {
  cv::Mat gray, out;
  cv::vconcat(frame.left, frame.right, gray);
  cv::cvtColor(gray, out, cv::COLOR_GRAY2BGR);
  const int h = frame.left.rows;
  for (const auto& m : matches) {
    const cv::Scalar colour = m.inlier ? cv::Scalar(0, 200, 0) : cv::Scalar(0, 0, 255);
    const cv::Point2d l(m.u_lc, m.v_lc), r(m.u_rc, m.v_lc + h), prev(m.u_lp, m.v_lp);
    cv::line(out, l, r, colour * 0.5, 1, cv::LINE_AA);
    cv::line(out, l, prev, cv::Scalar(0, 160, 255), 1, cv::LINE_AA);
    cv::circle(out, l, 3, colour, 1, cv::LINE_AA);
    cv::circle(out, r, 3, colour, 1, cv::LINE_AA);
  }
  return out;
}

// Where each VO lost track: metrics (algorithms.NAME.tracking), a warning for a stretch of a
// second or more, and the report's table.
std::string report_tracking(const std::vector<Track>& tracks, const Trajectory& camera_gt,
                            TrackRecords* records, std::vector<std::string>* warnings) {
  std::vector<std::string> names;
  std::vector<TrackingSummary> summaries;
  for (const Track& tr : tracks) {
    if (!tr.vo) continue;
    const TrackingSummary s = summarize_tracking(tr.results, camera_gt);
    records->algorithms[tr.name].tracking = s.tracking_record();
    const std::string w = tracking_warning(tr.name, s);
    if (!w.empty()) warnings->push_back(w);
    names.push_back(tr.name);
    summaries.push_back(s);
  }
  return names.empty() ? "" : tracking_table_markdown(names, summaries);
}

// The VO tracks of pipeline.vo (every frame "dropped" until it comes), then for each fusion
// algorithm one track per VO, following it.
// `T_W_C0`: the anchor, the true pose of the first delivered frame.
std::vector<Track> make_tracks(const Scenario& sc, const StereoRig& rig,
                               const SensorData& sensor_data, const Trajectory& camera_gt,
                               const SE3& T_W_C0, const RngStreams& rng) {
  std::vector<Track> tracks;
  std::vector<std::unique_ptr<vo::StereoOdometry>> vos =
      make_vos(sc.pipeline.vo, rig, sc.pipeline, rng);
  for (std::size_t i = 0; i < vos.size(); ++i) {
    Track t;
    t.name = sc.pipeline.vo[i];
    t.vo = std::move(vos[i]);
    t.results.resize(camera_gt.size());
    for (auto& r : t.results) r.reason = kFrameDropped;
    tracks.push_back(std::move(t));
  }
  const SE3 T_W_B0 =
      camera_gt.front().T_W_C * camera_mount_T_B_C(sc.sensors.camera.mount).inverse();
  const FilterMounts mounts = filter_mounts(sc);
  add_filter_tracks(
      sc.pipeline.fusion, tracks.size(),
      [&](FusionAlgorithm f) {
        return std::make_unique<FilterTrack>(f, sc.pipeline, mounts, sensor_data, T_W_B0, T_W_C0,
                                             rng);
      },
      &tracks);
  return tracks;
}

// Every track evaluated against the camera ground truth (with the platform's angles and the
// VO's inliers and depths as the section covariates): metrics.json's algorithms and VO
// timings, and the tables; each track's sections CSV is appended to *sections.
std::string evaluate_tracks(const Scenario& sc, const std::vector<Track>& tracks,
                            const MissionTruth& mission, const std::vector<double>& moving_px,
                            const std::optional<eval::PlanarReference>& overhead,
                            const std::optional<eval::AttitudeReference>& ahrs,
                            TrackRecords* records, std::string* sections_csv) {
  const Trajectory& camera_gt = mission.camera_gt;
  const std::vector<EulerZYX>& platform = mission.platform;
  std::string report;
  std::string& sections = *sections_csv;
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    const Track& tr = tracks[i];
    const Track& src = tr.vo || tr.external ? tr : tracks[tr.source];
    eval::EvaluationInput in;
    in.gt = camera_gt;
    in.est = tr.estimate;
    in.gt_label = "groundtruth.tum";
    in.est_label = "estimates/" + tr.name + ".tum";
    in.algorithm = tr.name;
    in.options = sc.eval;
    in.basin_reference = overhead;
    in.attitude_reference = ahrs;
    eval::FrameTable ft;
    // `lost`: 1 where the VO gave no motion, so each section's mean is its share of such
    // frames (the sections a lost stretch touched). The frames the camera delivered, as in
    // frames.csv, so that `driftlab eval --covariates frames.csv` finds the same covariates.
    ft.names = {"yaw_deg", "pitch_deg", "roll_deg", "inliers", "mean_depth_m", "lost", "moving_px"};
    ft.columns.resize(7);
    for (std::size_t k = 0; k < camera_gt.size(); ++k) {
      if (dropped_frame(src.results[k])) continue;
      ft.t_ns.push_back(camera_gt[k].t_ns);
      ft.columns[0].push_back(rad2deg(platform[k].yaw_rad));
      ft.columns[1].push_back(rad2deg(platform[k].pitch_rad));
      ft.columns[2].push_back(rad2deg(platform[k].roll_rad));
      const vo::VoResult& r = src.results[k];
      // Covariate f as the VO counts its features (river paper Table 4).
      ft.columns[3].push_back(r.valid ? r.feature_count()
                                      : std::numeric_limits<double>::quiet_NaN());
      ft.columns[4].push_back(r.valid ? r.mean_inlier_depth_m
                                      : std::numeric_limits<double>::quiet_NaN());
      ft.columns[5].push_back(lost_track(r) ? 1.0 : 0.0);
      ft.columns[6].push_back(moving_px[k]);
    }
    in.frames = ft;
    const eval::Evaluation e = eval::evaluate(in);
    records->algorithms[tr.name].evaluation = eval::evaluation_record(e, sc.eval);
    report += eval::tables_markdown(e, sc.eval) + "\n";
    const std::string csv = eval::sections_csv(e);
    sections += sections.empty() ? csv : csv.substr(csv.find('\n') + 1);
    if (tr.vo)
      records->vo_timing[tr.name] =
          vo_timing(*tr.vo, tr.vo_ms / static_cast<double>(camera_gt.size()));
  }
  return report;
}

// The report: plots (gnuplot), the external VOs' fates, and report.md and report.html with
// the tables so far (`report`).
void write_report(const Scenario& sc, const std::vector<Track>& tracks, const Trajectory& camera_gt,
                  const std::filesystem::path& dir, std::size_t sample_frame,
                  const std::string& sections, std::string report,
                  const std::map<std::string, ExternalVoRecord>& external_vo,
                  std::vector<std::string>* warnings) {
  std::vector<report::NamedTrajectory> named;
  for (const auto& tr : tracks) named.push_back({tr.name, tr.estimate});
  report::PlotSet made = report::make_plots(dir, camera_gt, named, sections);
  if (!made.warning.empty()) warnings->push_back(made.warning);
  std::vector<report::PlotFile>& plots = made.files;
  for (const auto& tr : tracks)
    if (std::filesystem::exists(dir / "plots" / (tr.name + "_matches.png")))
      plots.push_back({fmt::format("Stereo pair at frame {} with the {} matches: current left "
                                   "(top) and right (bottom), inliers green, outliers red, flow "
                                   "from the previous frame in orange (Fig. 3)",
                                   sample_frame, tr.name),
                       "plots/" + tr.name + "_matches.png"});
  if (!external_vo.empty()) {  // every external VO's fate, failures included
    report +=
        "## External VOs\n\n| name | status | exit | seconds | message |\n|---|---|---|---|---|\n";
    for (const auto& [name, r] : external_vo)
      report += fmt::format("| {} | {} | {} | {:.2f} | {} |\n", name, r.status, r.exit, r.seconds,
                            r.message);
    report += "\nEach command's output is in external/NAME/log.txt.\n\n";
  }
  const std::string tables = report;
  if (!plots.empty()) report += "## Plots\n\n";
  for (const auto& p : plots) report += fmt::format("![{}]({})\n\n", p.title, p.file);
  write_file_atomic(dir / "report.md", report);
  write_file_atomic(dir / "report.html",
                    report::report_html("driftlab run: " + sc.name, tables, plots));
}

}  // namespace

sim::SceneGeometry scene_for_track(const Scenario& sc, const Trajectory& camera_gt) {
  double north_min = camera_gt.front().T_W_C.translation().x(), north_max = north_min;
  for (const auto& p : camera_gt) {
    north_min = std::min(north_min, p.T_W_C.translation().x());
    north_max = std::max(north_max, p.T_W_C.translation().x());
  }
  return scenes::build_scene(sc.scene, sc.seed, north_min, north_max);
}

namespace {

// What the frame loop reads and where it writes.
struct FrameLoop {
  FrameSource& source;                         // the frames, rendered or replayed
  const std::vector<sim::SampleTime>& stamps;  // the camera clock's stamps and drops
  const MissionTruth& mission;
  std::size_t first;                 // the first frame the camera delivers
  const std::filesystem::path& dir;  // the run's folder: frames.csv, plots/
  const RunOptions& options;
  int threads;
  ExternalVoStage& external;  // the exports for the external VOs
  std::vector<Track>& tracks;
  std::vector<double>& moving_px;  // per frame (camera_gt's indices): CapturedFrame::moving_px
};

// Frames the VOs may be apart (pipeline/vo_pipeline.hpp): enough for the fast ones to run on
// while the slow one takes a long frame; each is a stereo pair held in memory.
constexpr std::size_t kVoLookahead = 4;

// The frame loop: every delivered frame through every VO (each along its own frames, side by
// side when `threads` >= 2), then, frame by frame in order, the filters following them, a
// frames.csv row each, the exports for the external VOs. Returns the render seconds.
double run_frame_loop(const FrameLoop& loop) {
  std::vector<Track>& tracks = loop.tracks;
  const std::filesystem::path& dir = loop.dir;
  const Trajectory& camera_gt = loop.mission.camera_gt;
  const std::vector<EulerZYX>& platform = loop.mission.platform;
  AtomicFile frames_csv(dir / "frames.csv");
  std::string header =
      "t_ns,yaw_deg,pitch_deg,roll_deg,render_ms,exposure_ms,blur_samples,moving_px";
  for (const Track& tr : tracks)
    if (tr.vo) header += vo_csv_header(tr.name);
  frames_csv.write(header + "\n");
  double render_s = 0;
  Progress progress(loop.options.progress, "render+vo", camera_gt.size(),
                    loop.options.progress_tty);
  const std::size_t sample_frame = camera_gt.size() / 2;  // drawn with its matches (Fig. 3)
  std::filesystem::create_directories(dir / "plots");
  // One frame whose VOs are done: its row, the tracks' steps, its export.
  auto finish_frame = [&](const VoJobDone& done) {
    const std::size_t k = done.job.k;
    const auto captured = std::static_pointer_cast<const CapturedFrame>(done.job.keep_alive);
    const TimeNs t = done.job.frame.t_ns;
    std::string row = fmt::format("{},{},{},{},{:.3f},{},{},{}", t, rad2deg(platform[k].yaw_rad),
                                  rad2deg(platform[k].pitch_rad), rad2deg(platform[k].roll_rad),
                                  captured->render_ms, yaml::format_double(captured->exposure_ms),
                                  captured->blur_samples, yaml::format_double(captured->moving_px));
    for (std::size_t i = 0; i < tracks.size(); ++i) {
      Track& tr = tracks[i];
      const vo::VoResult& r = tr.vo ? done.results[i] : tracks[tr.source].results[k];
      if (k == sample_frame && tr.vo && r.valid && !done.matches[i].empty())
        cv::imwrite((dir / "plots" / (tr.name + "_matches.png")).string(),
                    draw_matches(done.job.frame, done.matches[i]));
      if (tr.vo) row += vo_csv_cells(r);
      advance_track(&tr, k, k == loop.first, t, r);
    }
    frames_csv.write(row + "\n");
    loop.external.add_frame(t, captured->images, camera_gt[k]);
  };
  VoPipeline vos(&tracks, loop.threads, kVoLookahead);
  while (std::optional<CapturedFrame> captured = loop.source.next()) {
    const std::size_t k = captured->k;  // dropped frames never come: nothing rendered or seen
    progress.update(k);
    loop.moving_px[k] = captured->moving_px;
    render_s += captured->render_ms / 1000;
    auto held = std::make_shared<const CapturedFrame>(std::move(*captured));
    VoJob job;
    job.k = k;
    job.frame.t_ns = loop.stamps[k].t_stamp_ns;  // what the camera's clock wrote
    job.frame.left = cv_view(held->images.left);
    job.frame.right = cv_view(held->images.right);
    job.keep_alive = held;
    job.keep_matches = k == sample_frame;
    while (vos.full()) finish_frame(*vos.next_done(true));
    vos.submit(std::move(job));
    while (const std::optional<VoJobDone> done = vos.next_done(false)) finish_frame(*done);
  }
  while (const std::optional<VoJobDone> done = vos.next_done(true)) finish_frame(*done);
  progress.update(camera_gt.size());
  progress.finish();
  frames_csv.commit();
  return render_s;
}

// The tracks that follow the frame loop: the smoother's Rauch-Tung-Striebel pass over the
// whole run (NAME_ca_rts) and the external VOs, run on the exports of the same frames.
void add_whole_run_tracks(const Scenario& sc, const std::vector<sim::SampleTime>& stamps,
                          std::size_t first, const MissionTruth& mission, ExternalVoStage* external,
                          std::vector<Track>* tracks,
                          std::map<std::string, ExternalVoRecord>* external_vo,
                          std::vector<std::string>* warnings) {
  if (runs_backward_pass(sc.pipeline)) {
    std::vector<std::optional<TimeNs>> delivered(stamps.size());
    for (std::size_t k = first; k < stamps.size(); ++k)
      if (!stamps[k].dropped) delivered[k] = stamps[k].t_stamp_ns;
    for (std::size_t i = 0; i < sc.pipeline.vo.size(); ++i)
      tracks->push_back(rts_smoothed((*tracks)[i], i, delivered, sc.pipeline.ca_smoother));
  }
  for (ExternalVoResult& r : external->finish(mission.imu_states)) {
    (*external_vo)[r.name] = r.record;
    if (!r.warning.empty()) warnings->push_back(r.warning);
    if (!r.ok) continue;
    Track t;
    t.name = r.name;
    t.external = true;
    t.estimate = std::move(r.estimate);
    t.results.resize(mission.camera_gt.size());
    for (auto& v : t.results) v.reason = "external VO: no per-frame statistics";
    tracks->push_back(std::move(t));
  }
}

// The camera as the run saw it: frames delivered and dropped, and the effects that were on.
CameraRecord camera_record(const Scenario& sc, std::size_t frames, std::size_t dropped) {
  const auto& cam = sc.sensors.camera;
  CameraRecord c;
  c.frames_delivered = frames - dropped;
  c.frames_dropped = dropped;
  c.noise = cam.noise.enabled;
  c.vignetting_strength = cam.vignetting_strength;
  c.motion_blur_samples = sc.render.motion_blur_samples;
  c.motion_blur_step_px = sc.render.motion_blur_step_px;
  c.lens_distortion = cam.lens_distortion.enabled;
  c.clock_offset_ms = cam.clock.offset_ms;
  c.shutter = std::string(yaml::enum_name(cam.shutter));
  c.line_delay_us = cam.shutter == sim::Shutter::kRolling ? cam.line_delay_us : 0.0;
  c.right_offset_ms = 1e3 * run_right_offset_s(cam, RngStreams(sc.seed));
  c.right_offset_jitter_ms = cam.right_offset_jitter_ms;
  return c;
}

}  // namespace

// The render, VO, fusion and evaluation stages: their estimates, frames.csv, sections.csv
// and the report in `dir`, their record returned.
static VisionRecord run_vision_stages(const Scenario& sc, const sim::SceneGeometry& scene,
                                      const SensorData& sensor_data, const MissionTruth& mission,
                                      const std::filesystem::path& dir,
                                      const std::filesystem::path& final_dir,
                                      const RunOptions& options) {
  const Trajectory& camera_gt = mission.camera_gt;
  const RngStreams rng(sc.seed);
  VisionRecord record;
  // The camera's clock: stamps (offset, jitter) and dropped frames.
  const std::vector<sim::SampleTime> stamps =
      sim::camera_frame_times(sc.sensors.camera, rng, motion_end_s(sc));
  DRIFTLAB_DEMAND_MSG(stamps.size() >= camera_gt.size(), "camera clock: fewer stamps than frames");
  // Stage: render and camera effects (the scene built once, uploaded once), on a thread of
  // their own when the run has more than one.
  record.threads = run_threads(sc.pipeline.threads);
  ExternalVoStage external(sc, dir, final_dir);  // exports of the frames for the external VOs
  FrameSource source(sc, scene, mission.frames, stamps, record.threads, 4, external.wants_depth(),
                     options.frame_cache);

  // Stages: VO and fusion. VO sees images and the rig only; the pipeline
  // anchors every estimate at the true first pose so that tracks overlay.
  std::size_t first = 0;  // the first frame the camera delivers
  while (first < stamps.size() && first < camera_gt.size() && stamps[first].dropped) ++first;
  const SE3 T_W_C0 = first < camera_gt.size() ? camera_gt[first].T_W_C : SE3();
  std::vector<Track> tracks =
      make_tracks(sc, rig_of(sc.sensors.camera), sensor_data, camera_gt, T_W_C0, rng);
  std::vector<std::string>& warnings = record.warnings;
  warnings = implausible_values(sc);
  if (first < camera_gt.size())
    for (auto& t : tracks) t.estimate.push_back({stamps[first].t_stamp_ns, camera_gt[first].T_W_C});
  std::size_t dropped = 0;
  for (std::size_t k = 0; k < camera_gt.size(); ++k) dropped += stamps[k].dropped ? 1 : 0;
  std::vector<double> moving_px(camera_gt.size(), 0.0);
  record.render_s = run_frame_loop(
      {source, stamps, mission, first, dir, options, record.threads, external, tracks, moving_px});
  add_whole_run_tracks(sc, stamps, first, mission, &external, &tracks, &record.external_vo,
                       &warnings);
  write_estimates(tracks, dir);

  // Stage: the basin paper's reference, when the overhead camera is on.
  std::optional<eval::PlanarReference> overhead;
  if (sc.sensors.overhead.enabled) {
    OverheadResult o = run_overhead_camera(sc, scene, mission, dir);
    record.overhead = o.record;
    overhead = planar_reference(o.reference);
  }

  // Stage: evaluation of every estimate against the camera ground truth (and the overhead
  // camera's reference).
  std::string report = fmt::format("# driftlab run: {}\n\n{}\n\n", sc.name, sc.description);
  std::string sections;
  std::optional<eval::AttitudeReference> ahrs;
  if (!sensor_data.ahrs.empty()) {
    ahrs.emplace();
    for (const sim::AhrsSample& a : sensor_data.ahrs) {
      ahrs->t_ns.push_back(a.t_ns);
      ahrs->euler.push_back(a.euler);
    }
  }
  report +=
      evaluate_tracks(sc, tracks, mission, moving_px, overhead, ahrs, &record.tracks, &sections);
  write_file_atomic(dir / "sections.csv", sections);
  report += report_tracking(tracks, camera_gt, &record.tracks, &warnings);
  report += compare_filters_with_raw_vo(tracks, &record.tracks, &warnings);
  report_filter_counts(tracks, &record.tracks, &warnings);

  write_report(sc, tracks, camera_gt, dir, camera_gt.size() / 2, sections, report,
               record.external_vo, &warnings);
  record.render_pairs_per_s =
      record.render_s > 0 ? static_cast<double>(camera_gt.size() - dropped) / record.render_s : 0.0;
  record.camera = camera_record(sc, camera_gt.size(), dropped);
  record.frame_cache = source.cache_status();
  if (record.frame_cache.warn) {
    warnings.push_back(record.frame_cache.note);
    if (options.progress) fmt::print(options.progress, "warning: {}\n", record.frame_cache.note);
  }
  record.render_context = source.info().context;
  record.assets = scenes::shipped_asset_dir();
  record.triangles = source.info().triangles;
  return record;
}

SE3 imu_mount_T_B_S(const Scenario& sc) {
  return sc.sensors.imu.enabled ? sim::SensorMount::from_options(sc.sensors.imu.mount).T_B_S()
                                : SE3();
}

MissionTruth simulate_mission(const Scenario& sc,
                              const std::function<void(const sim::BodySample&)>& on_physics,
                              SensorStage* sensors, bool imu_states) {
  const SE3 T_B_C = camera_mount_T_B_C(sc.sensors.camera.mount);
  MissionTruth truth;
  const auto on_frame = [&](const sim::BodySample& b) {
    truth.camera_gt.push_back({b.t_ns, b.state.T_W_B() * T_B_C});
    Vec6 twist;
    twist << b.state.v_B, b.state.w_B;
    truth.frames.push_back({ns_to_seconds(b.t_ns), b.state.T_W_B(), twist});
    truth.platform.push_back(euler_zyx_from_quat(b.state.q_W_B));
  };
  // EuRoC's ground truth rate is 200 Hz: every n-th physics step, at most that often.
  const std::size_t every = std::max<std::size_t>(
      1, static_cast<std::size_t>(std::lround(sc.vessel.physics_rate_hz / 200.0)));
  const SE3 T_B_S = imu_mount_T_B_S(sc);
  std::size_t step = 0;
  const auto physics = [&](const sim::BodySample& b) {
    if (on_physics) on_physics(b);
    if (!imu_states || step++ % every) return;
    const Vec3 v_S_B = b.state.v_B + b.state.w_B.cross(T_B_S.translation());
    truth.imu_states.push_back(
        {b.t_ns, b.state.T_W_B() * T_B_S, b.state.q_W_B.toRotationMatrix() * v_S_B, {}});
  };
  truth.motion = sensors ? simulate_scenario_motion(
                               sc, physics, on_frame, sensors->sample_times(motion_end_s(sc)),
                               [&](const sim::BodySample& b) { sensors->on_sample(b); })
                         : simulate_scenario_motion(sc, physics, on_frame);
  if (sensors)
    for (dataset::BodyState& s : truth.imu_states) s.bias = sensors->imu_bias_at(s.t_ns);
  return truth;
}

// What each stage did, with the reason when it did not run.
static StagesRecord stages_record(const Scenario& sc, const RunOptions& options, bool ran_vision) {
  const auto& s = sc.sensors;
  const std::string vision = ran_vision            ? "done"
                             : options.only_motion ? "skipped (--only-motion)"
                                                   : "skipped (no VO in pipeline.vo or "
                                                     "pipeline.external_vo)";
  const auto unless = [&](bool empty, const char* why) {
    return vision != "done" ? vision : empty ? std::string("skipped (") + why + ")" : vision;
  };
  StagesRecord r;
  r.scenario = "done";
  r.physics = "done";
  r.sensors = s.imu.enabled || s.gps.enabled || s.compass.enabled
                  ? "done"
                  : "skipped (no IMU, GPS or compass enabled)";
  r.render = vision;
  r.vo = unless(sc.pipeline.vo.empty(), "pipeline.vo is empty");
  r.external_vo = unless(sc.pipeline.external_vo.empty(), "pipeline.external_vo is empty");
  r.fusion = unless(sc.pipeline.fusion.empty(), "pipeline.fusion is empty");
  r.eval = vision;
  return r;
}

RunSummary run_scenario(const Scenario& sc, const std::filesystem::path& out_dir,
                        const RunOptions& options) {
  const auto t0 = SteadyClock::now();
  validate_scenario(sc, "scenario '" + sc.name + "'");
  RunSummary summary;
  AtomicDirectory dir(out_dir, options.replace_existing);
  write_file_atomic(dir.path() / "scenario.resolved.yaml", resolved_yaml(sc));

  // Stage: physics: ground truth at the physics rate and at each frame.
  AtomicFile body(dir.path() / "body_groundtruth.csv");
  body.write(body_csv_header());
  const auto t_physics = SteadyClock::now();
  SensorStage sensors(sc, dir.path());
  bool euroc_export = false;  // an external VO reads EuRoC or a bag: keep the IMU's true states
  for (const auto& e : sc.pipeline.external_vo)
    euroc_export = euroc_export || dataset::wants_body_truth(e.format);
  MissionTruth truth = simulate_mission(
      sc, [&](const sim::BodySample& b) { body.write(body_csv_row(b)); }, &sensors, euroc_export);
  summary.motion = truth.motion;
  const Trajectory& camera_gt = truth.camera_gt;
  summary.physics_s = seconds_since(t_physics);
  body.commit();
  write_tum(dir.path() / "groundtruth.tum", camera_gt);
  summary.frames = camera_gt.size();
  for (std::size_t i = 1; i < camera_gt.size(); ++i)
    summary.track_length_m +=
        (camera_gt[i].T_W_C.translation() - camera_gt[i - 1].T_W_C.translation()).norm();

  // Stage: sensors. GPS and compass need the scene (sky obstruction, steel structures).
  const auto t_sensors = SteadyClock::now();
  std::optional<sim::SceneGeometry> scene;
  if (!camera_gt.empty()) scene = scene_for_track(sc, camera_gt);
  const SensorData sensor_data = sensors.finish(scene ? &*scene : nullptr);
  summary.sensors = sensor_data.stats;
  summary.sensors_s = seconds_since(t_sensors);

  const bool run_vo = !options.only_motion &&
                      (!sc.pipeline.vo.empty() || !sc.pipeline.external_vo.empty()) &&
                      !camera_gt.empty();
  if (run_vo)
    summary.vision =
        run_vision_stages(sc, *scene, sensor_data, truth, dir.path(), dir.final_path(), options);

  summary.scenario = sc.name;
  summary.seed = sc.seed;
  summary.stages = stages_record(sc, options, run_vo);
  summary.total_s = seconds_since(t0);
  write_file_atomic(dir.path() / "metrics.json", record::metrics_text(summary.run_record()));
  dir.commit();
  return summary;
}

}  // namespace driftlab::pipeline
