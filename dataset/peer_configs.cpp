// The settings files stereo(-inertial) systems read beside an export, written from the export's
// calibration: Basalt's camera calibration (a cereal JSON archive, basalt-headers'
// serialization/headers_serialization.h) and ORB-SLAM3's settings (an OpenCV FileStorage YAML
// in its v1.0 format, src/Settings.cc) with the times file its EuRoC examples read, beside a
// EuRoC folder; OpenVINS's estimator configuration (OpenCV FileStorage YAML, ov_msckf's
// VioManagerOptions) beside a ROS 1 bag and its Kalibr files. Their keys
// and conventions: ../shared/research/peers-inputs.md; docs/datasets.md, "Peers on the twin".
#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "core/yaml_io.hpp"
#include "dataset/dataset_detail.hpp"
#include "dataset/rosbag.hpp"

namespace driftlab::dataset::detail {

namespace {

SE3 right_in_left(const ExportCalibration& cal) {
  return SE3(Mat3::Identity(), Vec3(cal.rig.baseline_m, 0, 0));
}

// A Sophus pose as cereal writes it: translation px, py, pz, then the quaternion qx, qy, qz, qw.
nlohmann::ordered_json basalt_pose(const SE3& T) {
  const Quat& q = T.quaternion();
  const Vec3& t = T.translation();
  return {{"px", t.x()}, {"py", t.y()}, {"pz", t.z()}, {"qx", q.x()},
          {"qy", q.y()}, {"qz", q.z()}, {"qw", q.w()}};
}

// ORB-SLAM3 reads its real-valued keys only from YAML reals (Settings::readParameter<float>
// aborts on an integer literal): a number always with a point or an exponent.
std::string real(double x) {
  std::string s = yaml::format_double(x);
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";
  return s;
}

// A 4x4 matrix as ORB-SLAM3 reads it: Converter::toSophus takes its elements as floats, so the
// matrix is written with dt: f.
std::string orbslam3_matrix(const SE3& T) {
  const Mat4 m = T.matrix();
  std::string data;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) data += (data.empty() ? "" : ", ") + real(m(r, c));
  return fmt::format("!!opencv-matrix\n  rows: 4\n  cols: 4\n  dt: f\n  data: [{}]\n", data);
}

}  // namespace

std::string basalt_calibration_json(const ExportCalibration& cal) {
  nlohmann::ordered_json v;
  v["T_imu_cam"] = {basalt_pose(cal.T_S_C), basalt_pose(cal.T_S_C * right_in_left(cal))};
  const PinholeCamera& c = cal.rig.camera;
  const nlohmann::ordered_json pinhole = {
      {"camera_type", "pinhole"},
      {"intrinsics", {{"fx", c.fx}, {"fy", c.fy}, {"cx", c.cx}, {"cy", c.cy}}}};
  v["intrinsics"] = {pinhole, pinhole};  // the rectified pair: one pinhole, no distortion
  v["resolution"] = {{c.width, c.height}, {c.width, c.height}};
  v["vignette"] = nlohmann::ordered_json::array();
  v["calib_accel_bias"] = std::vector<double>(9, 0.0);  // bias and scale: none
  v["calib_gyro_bias"] = std::vector<double>(12, 0.0);
  // Kalibr's continuous densities and random walks are Basalt's *_noise_std and *_bias_std
  // (basalt calibration.hpp; doc/Calibration.md). Without an IMU (a VO run), Basalt's defaults.
  const ImuNoiseModel& m = cal.imu;
  const bool imu = m.rate_hz > 0;
  auto three = [](double x) { return std::vector<double>(3, x); };
  v["imu_update_rate"] = imu ? m.rate_hz : 200.0;
  v["accel_noise_std"] = three(imu ? m.accelerometer_noise_density : 0.016);
  v["gyro_noise_std"] = three(imu ? m.gyroscope_noise_density : 0.000282);
  v["accel_bias_std"] = three(imu ? m.accelerometer_random_walk : 0.001);
  v["gyro_bias_std"] = three(imu ? m.gyroscope_random_walk : 0.0001);
  v["cam_time_offset_ns"] = 0;
  return nlohmann::ordered_json{{"value0", v}}.dump(4) + "\n";
}

std::string orbslam3_settings_yaml(const ExportCalibration& cal, bool inertial) {
  const PinholeCamera& c = cal.rig.camera;
  std::string y = fmt::format(
      "%YAML:1.0\n"
      "# ORB-SLAM3 v1.0 settings for this export (driftlab export --format euroc): the rectified\n"
      "# pair as Camera.type Rectified; reals with a point, matrices dt: f, as src/Settings.cc\n"
      "# reads them.\n"
      "File.version: \"1.0\"\n"
      "Camera.type: \"Rectified\"\n"
      "Camera1.fx: {}\nCamera1.fy: {}\nCamera1.cx: {}\nCamera1.cy: {}\n"
      "Stereo.b: {}\n"
      "Camera.width: {}\nCamera.height: {}\n"
      "# frames per second, rounded (ORB-SLAM3 takes an integer; it sets keyframe spacing)\n"
      "Camera.fps: {}\n"
      "Camera.RGB: 0\n"
      "# close points within 40 baselines (ORB-SLAM3's EuRoC and D435i examples)\n"
      "Stereo.ThDepth: 40.0\n",
      real(c.fx), real(c.fy), real(c.cx), real(c.cy), real(cal.rig.baseline_m), c.width, c.height,
      std::max(1, static_cast<int>(std::lround(cal.camera_rate_hz))));
  if (inertial) {
    const ImuNoiseModel& m = cal.imu;
    y += "# the left camera in the IMU frame (EuRoC cam0 T_BS, Kalibr T_imu_cam)\n";
    y += "IMU.T_b_c1: " + orbslam3_matrix(cal.T_S_C);
    y += fmt::format(
        "# Kalibr's continuous noise densities and random walks, as ORB-SLAM3 takes them\n"
        "IMU.NoiseGyro: {}\nIMU.NoiseAcc: {}\nIMU.GyroWalk: {}\nIMU.AccWalk: {}\n"
        "IMU.Frequency: {}\n",
        real(m.gyroscope_noise_density), real(m.accelerometer_noise_density),
        real(m.gyroscope_random_walk), real(m.accelerometer_random_walk), real(m.rate_hz));
  }
  y +=
      "# ORB features and the viewer's keys (required even without a viewer): the EuRoC examples'\n"
      "ORBextractor.nFeatures: 1200\nORBextractor.scaleFactor: 1.2\nORBextractor.nLevels: 8\n"
      "ORBextractor.iniThFAST: 20\nORBextractor.minThFAST: 7\n"
      "Viewer.KeyFrameSize: 0.05\nViewer.KeyFrameLineWidth: 1.0\nViewer.GraphLineWidth: 0.9\n"
      "Viewer.PointSize: 2.0\nViewer.CameraSize: 0.08\nViewer.CameraLineWidth: 3.0\n"
      "Viewer.ViewpointX: 0.0\nViewer.ViewpointY: -0.7\nViewer.ViewpointZ: -1.8\n"
      "Viewer.ViewpointF: 500.0\n";
  return y;
}

namespace {

const char* const kOpenVinsHead =
    "%YAML 1.0\n---\n"
    "# OpenVINS's estimator configuration for this export (ov_msckf: every key below is read, a\n"
    "# missing one stops the serial node), beside the Kalibr files it names.\n";

// OpenVINS triangulates a feature only within fi_max_dist, fi_max_baseline (its distance over the
// largest baseline that saw it) and fi_max_cond_number (of the triangulation's 3x3 system, which
// grows as the square of that ratio). Its defaults, 60 m, 40 and 1e4, are a room's or a drone's:
// on a river the bank lies 20-100 m from a 0.12 m pair and every feature fails them, so the
// filter never updates (tried on the crossing: no MSCKF or SLAM feature in 170 frames, then pure
// IMU drift). Here they reach as far as the pair can see: the depth at half a pixel of disparity.
std::string openvins_triangulation_yaml(const ExportCalibration& cal) {
  const double max_depth = cal.rig.camera.fx * cal.rig.baseline_m / 0.5;
  const double ratio = max_depth / cal.rig.baseline_m;
  return fmt::format(
      "# features as far as the pair sees them: the depth at half a pixel of disparity, f B / 0.5 "
      "px\n# (OpenVINS's defaults, 60 m, 40 and 1e4, reject a river's every feature)\n"
      "fi_max_dist: {}\nfi_max_baseline: {}\nfi_max_cond_number: {}\n",
      real(max_depth), real(ratio), real(ratio * ratio));
}

}  // namespace

std::string openvins_estimator_config_yaml(const ExportCalibration& cal) {
  const std::string r = real(cal.imu.gravity_m_s2);
  return kOpenVinsHead + openvins_triangulation_yaml(cal) +
         fmt::format(
             "verbosity: \"WARNING\"\n"
             "use_fej: true\nintegration: \"rk4\"\nuse_stereo: true\nmax_cameras: 2\n"
             "# the export's calibration is exact: nothing to refine online; the IMU is "
             "'calibrated'\n"
             "# (kalibr_imu_chain.yaml), so its intrinsics and g-sensitivity stay fixed\n"
             "calib_cam_extrinsics: false\ncalib_cam_intrinsics: false\ncalib_cam_timeoffset: "
             "false\n"
             "calib_imu_intrinsics: false\ncalib_imu_g_sensitivity: false\n"
             "max_clones: 11\nmax_slam: 50\nmax_slam_in_update: 25\nmax_msckf_in_update: 40\n"
             "dt_slam_delay: 1.0\n"
             "# the twin's gravity\ngravity_mag: {}\n"
             "feat_rep_msckf: \"GLOBAL_3D\"\nfeat_rep_slam: \"ANCHORED_MSCKF_INVERSE_DEPTH\"\n"
             "feat_rep_aruco: \"ANCHORED_MSCKF_INVERSE_DEPTH\"\n"
             "try_zupt: false\nzupt_chi2_multipler: 0.0\nzupt_max_velocity: 0.1\n"
             "zupt_noise_multiplier: 10.0\nzupt_max_disparity: 0.5\nzupt_only_at_beginning: false\n"
             "# a vessel under way never gives the static initialiser its standstill and jerk: "
             "the\n"
             "# dynamic initialiser instead, which needs some rotation in its window\n"
             "init_window_time: 2.0\ninit_imu_thresh: 1.5\ninit_max_disparity: 10.0\n"
             "init_max_features: 50\ninit_dyn_use: true\ninit_dyn_mle_opt_calib: false\n"
             "init_dyn_mle_max_iter: 50\ninit_dyn_mle_max_threads: 1\ninit_dyn_mle_max_time: 0.05\n"
             "init_dyn_num_pose: 6\ninit_dyn_min_deg: 10.0\ninit_dyn_inflation_ori: 10.0\n"
             "init_dyn_inflation_vel: 100.0\ninit_dyn_inflation_bg: 10.0\ninit_dyn_inflation_ba: "
             "100.0\n"
             "init_dyn_min_rec_cond: 1.0e-12\ninit_dyn_bias_g: [0.0, 0.0, 0.0]\n"
             "init_dyn_bias_a: [0.0, 0.0, 0.0]\n"
             "record_timing_information: false\nrecord_timing_filepath: "
             "\"/tmp/openvins_timing.txt\"\n"
             "use_klt: true\nnum_pts: 200\nfast_threshold: 20\ngrid_x: 5\ngrid_y: 5\nmin_px_dist: "
             "10\n"
             "knn_ratio: 0.7\n"
             "# a frame earlier than the last tracked one plus 1 / track_frequency is dropped: "
             "above the\n"
             "# camera's {} Hz, so that none is\ntrack_frequency: {}\n"
             "downsample_cameras: false\n"
             "# OpenCV on one thread, for runs that repeat\nnum_opencv_threads: 0\n"
             "multi_threading_pubs: false\n"
             "histogram_method: \"HISTOGRAM\"\n"
             "use_aruco: false\nnum_aruco: 1024\ndownsize_aruco: true\n"
             "up_msckf_sigma_px: 1.0\nup_msckf_chi2_multipler: 1.0\nup_slam_sigma_px: 1.0\n"
             "up_slam_chi2_multipler: 1.0\nup_aruco_sigma_px: 1.0\nup_aruco_chi2_multipler: 1.0\n"
             "use_mask: false\n"
             "relative_config_imu: \"{}\"\nrelative_config_imucam: \"{}\"\n",
             r, real(cal.camera_rate_hz), real(cal.camera_rate_hz + 1), rosbag_names::kImuChainFile,
             rosbag_names::kCamchainFile);
}

std::string orbslam3_times(const std::vector<TimeNs>& stamps) {
  std::string out;
  for (const TimeNs t : stamps) out += fmt::format("{}\n", t);
  return out;
}

}  // namespace driftlab::dataset::detail
