#include "pipeline/export_stage.hpp"

#include <fmt/format.h>

#include <cmath>

#include <opencv2/imgcodecs.hpp>

#include "core/atomic_file.hpp"
#include "core/stopwatch.hpp"
#include "core/yaml_io.hpp"
#include "pipeline/frame_source.hpp"
#include "pipeline/progress.hpp"
#include "pipeline/render_stage.hpp"
#include "pipeline/run.hpp"
#include "pipeline/sensor_stage.hpp"
#include "sim/sensors/clock.hpp"

namespace driftlab::pipeline {
namespace fs = std::filesystem;

namespace {

// The left image's mask of moving things (mask_0/ in docs/datasets.md), numbered as the export's
// frames.
void write_mask(const fs::path& path, const sim::GrayImage& mask) {
  if (!cv::imwrite(path.string(), cv_view(mask)))
    throw UserError(fmt::format("{}: cannot write the mask", path.string()));
}

}  // namespace

std::string ExportSummary::brief() const {
  return fmt::format(
      "exported {} stereo pairs and {} IMU samples; render {:.1f} pairs/s; total "
      "{:.2f} s",
      frames, imu_samples, render_pairs_per_s, total_s);
}

dataset::ExportCalibration export_calibration(const Scenario& sc) {
  dataset::ExportCalibration cal;
  cal.rig = rig_of(sc.sensors.camera);
  cal.T_S_C = imu_mount_T_B_S(sc).inverse() * camera_mount_T_B_C(sc.sensors.camera.mount);
  cal.T_B_S = imu_mount_T_B_S(sc);
  if (sc.sensors.compass.enabled)
    cal.T_B_M = sim::SensorMount::from_options(sc.sensors.compass.mount).T_B_S();
  if (sc.sensors.gps.enabled) {
    const auto& a = sc.sensors.gps.antenna_frd_m;
    cal.p_B_gps = Vec3(a[0], a[1], a[2]);
    cal.gps_sigma_horizontal_m = sc.sensors.gps.sigma_horizontal_m;
  }
  cal.camera_rate_hz = sc.sensors.camera.rate_hz;
  const auto& imu = sc.sensors.imu;
  if (imu.enabled)
    cal.imu = {imu.rate_hz,
               imu.gyro_noise_density_rad_s_sqrt_hz,
               imu.gyro_random_walk_rad_s2_sqrt_hz,
               imu.accel_noise_density_m_s2_sqrt_hz,
               imu.accel_random_walk_m_s3_sqrt_hz,
               sim::kImuStandardGravity_m_s2};
  cal.source = fmt::format("driftlab scenario '{}', seed {}", sc.name, sc.seed);
  return cal;
}

ExportSummary export_dataset(const Scenario& sc, const fs::path& out_dir,
                             const ExportOptions& options) {
  const auto t0 = SteadyClock::now();
  validate_scenario(sc, "scenario '" + sc.name + "'");
  AtomicDirectory dir(out_dir, options.replace_existing);
  write_file_atomic(dir.path() / "scenario.resolved.yaml", resolved_yaml(sc));
  dataset::ExportCalibration cal = export_calibration(sc);
  cal.sequence = options.sequence;
  const auto writer = dataset::make_writer(options.format, dir.path(), cal);

  // Physics and the other sensors (into a staging folder the writer empties).
  const fs::path staging = dir.path() / ".sensors";
  fs::create_directories(staging);
  SensorStage sensors(sc, staging);
  dataset::ExportTruth truth;
  MissionTruth mission =
      simulate_mission(sc, nullptr, &sensors, dataset::wants_body_truth(options.format));
  truth.body = std::move(mission.imu_states);
  if (mission.camera_gt.empty()) throw UserError("scenario '" + sc.name + "': no camera frames");
  const sim::SceneGeometry scene = scene_for_track(sc, mission.camera_gt);
  const SensorData sensor_data = sensors.finish(&scene);
  for (const char* name : {"imu.csv", "gps.csv", "compass.csv"})
    if (fs::exists(staging / name)) truth.sensor_csvs.push_back(staging / name);

  // The frames, as a run's VOs see them.
  const RngStreams rng(sc.seed);
  const std::vector<sim::SampleTime> stamps =
      sim::camera_frame_times(sc.sensors.camera, rng, motion_end_s(sc));
  // A scene with movers also gets their masks: mask_0/NNNNNN.png (the frames in order) and
  // mask_0/moving_px.csv.
  const bool masks = scene_moves(sc, scene);
  const bool depth = writer->wants_depth();
  FrameSource source(sc, scene, mission.frames, stamps, run_threads(sc.pipeline.threads), 4,
                     depth || masks, options.frame_cache);
  std::string moving_csv = "frame,t_ns,moving_px\n";
  if (masks) fs::create_directories(dir.path() / "mask_0");
  ExportSummary summary;
  double render_s = 0;
  Progress progress(options.progress, "export", mission.camera_gt.size(), options.progress_tty);
  while (std::optional<CapturedFrame> f = source.next()) {
    progress.update(f->k);
    render_s += f->render_ms / 1000;
    const TimeNs t = stamps[f->k].t_stamp_ns;
    writer->add_frame(t, cv_view(f->images.left), cv_view(f->images.right),
                      depth ? cv_view(f->images.depth_left) : cv::Mat());
    if (masks) {
      write_mask(dir.path() / "mask_0" / fmt::format("{:06d}.png", summary.frames),
                 f->images.moving_left);
      moving_csv += fmt::format("{},{},{}\n", summary.frames, t, yaml::format_double(f->moving_px));
    }
    truth.camera.push_back(mission.camera_gt[f->k]);
    ++summary.frames;
  }
  progress.update(mission.camera_gt.size());
  progress.finish();
  writer->finish(truth);
  if (masks) write_file_atomic(dir.path() / "mask_0" / "moving_px.csv", moving_csv);
  fs::remove_all(staging);
  dir.commit();
  summary.imu_samples = sensor_data.imu.size();
  summary.render_pairs_per_s = render_s > 0 ? static_cast<double>(summary.frames) / render_s : 0;
  summary.total_s = seconds_since(t0);
  return summary;
}

}  // namespace driftlab::pipeline
