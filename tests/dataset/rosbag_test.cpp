// ROS 1 bags: the writer against ROS's own Python reader (python3-rosbag, independent of the C++
// library that writes), the reader against the writer and against a bag written by ROS's Python
// writer in EuRoC's layout, whose images are also an EuRoC folder.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fmt/format.h>

#include <cmath>
#include <opencv2/imgcodecs.hpp>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/process.hpp"
#include "core/rotation.hpp"
#include "core/trajectory_io.hpp"
#include "dataset/dataset.hpp"
#include "dataset/rosbag.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::dataset {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using test::slurp;

const fs::path kTests = fs::path(DRIFTLAB_SOURCE_DIR) / "tests" / "dataset";

// Runs one of the tests' Python scripts with Debian's interpreter (the one python3-rosbag is
// installed for); its standard output.
std::string python(const std::string& script, const std::vector<std::string>& args,
                   const fs::path& output) {
  ProcessSpec spec;
  spec.executable = "/usr/bin/python3";
  spec.args = {(kTests / script).string()};
  spec.args.insert(spec.args.end(), args.begin(), args.end());
  spec.output_file = output;
  const ExitStatus status = wait_process(spawn_process(spec));
  EXPECT_TRUE(status.ok()) << script << ": " << status.describe() << "\n" << slurp(output);
  return slurp(output);
}

ExportCalibration bag_calibration() {
  ExportCalibration cal;
  cal.rig.camera = {480, 470, 40.5, 30.25, 80, 60};
  cal.rig.baseline_m = 0.25;
  cal.T_S_C = SE3(quat_from_euler_zyx({0.1, -0.2, 0.3}), Vec3(0.5, -0.1, 0.2));
  cal.T_B_S = SE3(quat_from_euler_zyx({0, 0, 0.05}), Vec3(1, 0, -0.5));  // yaw 0.05 rad
  cal.T_B_M = SE3(Quat::Identity(), Vec3(-2, 0, -1));
  cal.p_B_gps = Vec3(0, 0.5, -3);
  cal.gps_sigma_horizontal_m = 1.5;
  cal.camera_rate_hz = 10;
  cal.imu = {200, 1.7e-4, 2e-5, 2e-3, 3e-3};
  cal.source = "test";
  return cal;
}

// Three frames (the first stamped 0), IMU, GPS (a fix and none), compass and the IMU's truth.
struct BagSequence {
  std::vector<TimeNs> stamps{0, 100'000'123, 200'000'000};
  std::vector<cv::Mat> left, right;
  std::vector<ImuSample> imu;
  ExportTruth truth;
  explicit BagSequence(const fs::path& staging) {
    cv::RNG rng(7);
    for (std::size_t i = 0; i < stamps.size(); ++i) {
      cv::Mat l(60, 80, CV_8UC1), r(60, 80, CV_8UC1);
      rng.fill(l, cv::RNG::UNIFORM, 0, 256);
      rng.fill(r, cv::RNG::UNIFORM, 0, 256);
      left.push_back(l);
      right.push_back(r);
    }
    for (int k = 0; k < 41; ++k) {
      const TimeNs t = k * 5'000'000;
      imu.push_back({t, Vec3(0.01 * k, -0.2, 1.0 / 3), Vec3(0.1, 0.7 * k, -9.81)});
      const SE3 T_W_S(quat_from_euler_zyx({0.01 * k, 0.02, 0.5}), Vec3(3 + 0.1 * k, k, -1));
      truth.body.push_back({t, T_W_S, Vec3(1, 0, 0), {}});
    }
    fs::create_directories(staging);
    write_euroc_imu(staging / "imu.csv", imu);
    write_file_atomic(staging / "gps.csv",
                      "#timestamp [ns],fix [0/1],satellites [],hdop [],north [m],east [m],down "
                      "[m],latitude [deg],longitude [deg],height [m]\n"
                      "0,1,7,1.25,1,2,3,52.5,-0.25,17.5\n"
                      "100000000,0,2,nan,nan,nan,nan,nan,nan,nan\n");
    write_file_atomic(staging / "compass.csv",
                      "#timestamp [ns],heading [deg],m_S_x [nT],m_S_y [nT],m_S_z [nT]\n"
                      "50000000,30,17000,-1500,46000\n"
                      "150000000,350.5,16000,2500,45000\n");
    truth.sensor_csvs = {staging / "imu.csv", staging / "gps.csv", staging / "compass.csv"};
  }
  void write(DatasetWriter& w) const {
    for (std::size_t i = 0; i < stamps.size(); ++i) w.add_frame(stamps[i], left[i], right[i], {});
    w.finish(truth);
  }
};

std::vector<json> messages_on(const json& bag, const std::string& topic) {
  std::vector<json> out;
  for (const json& m : bag["messages"])
    if (m["topic"] == topic) out.push_back(m);
  return out;
}

std::vector<int> bytes_of(const cv::Mat& image) {
  return std::vector<int>(image.datastart, image.dataend);
}

Quat quat_of(const json& q) { return Quat(q[0], q[1], q[2], q[3]); }

// An export's bag as an independent reader decoded it (read_bag.py's JSON) against the
// sequence written: ROS 1 (`ros2` false) or ROS 2 (types with /msg/, no seq, no record time).
void expect_the_sequence(const json& bag, const BagSequence& seq, bool ros2) {
  const auto type = [&](std::string t) { return ros2 ? t.insert(t.find('/'), "/msg") : t; };
  const std::map<std::string, std::pair<std::string, int>> expected_topics = {
      {"/cam0/image_raw", {"sensor_msgs/Image", 3}},
      {"/cam1/image_raw", {"sensor_msgs/Image", 3}},
      {"/cam0/camera_info", {"sensor_msgs/CameraInfo", 3}},
      {"/cam1/camera_info", {"sensor_msgs/CameraInfo", 3}},
      {"/imu0", {"sensor_msgs/Imu", 41}},
      {"/gps/fix", {"sensor_msgs/NavSatFix", 2}},
      {"/mag", {"sensor_msgs/MagneticField", 2}},
      {"/compass/heading", {"geometry_msgs/QuaternionStamped", 2}},
      {"/groundtruth/pose", {"geometry_msgs/PoseStamped", 41}},
      {"/tf_static", {"tf2_msgs/TFMessage", 1}}};
  EXPECT_EQ(bag["topics"].size(), expected_topics.size());
  for (const auto& [topic, type_count] : expected_topics) {
    ASSERT_TRUE(bag["topics"].contains(topic)) << topic;
    EXPECT_EQ(bag["topics"][topic]["type"], type(type_count.first)) << topic;
    EXPECT_EQ(bag["topics"][topic]["count"], type_count.second) << topic;
    EXPECT_EQ(bag["topics"][topic]["latching"], topic == "/tf_static" ? "1" : "0") << topic;
  }
  // Images: stamps, sizes and every byte; a message stamped 0 is recorded at 1 ns.
  for (int cam = 0; cam < 2; ++cam) {
    const auto images = messages_on(bag, rosbag_names::kImage[cam]);
    const auto infos = messages_on(bag, rosbag_names::kCameraInfo[cam]);
    ASSERT_EQ(images.size(), 3u);
    for (std::size_t i = 0; i < 3; ++i) {
      const json& m = images[i];
      EXPECT_EQ(m["stamp_ns"], seq.stamps[i]);
      EXPECT_EQ(m["record_ns"], ros2 ? seq.stamps[i] : std::max<TimeNs>(seq.stamps[i], 1));
      if (!ros2) {
        EXPECT_EQ(m["seq"], i);
      }
      EXPECT_EQ(m["frame_id"], rosbag_names::kOpticalFrame[cam]);
      EXPECT_EQ(m["encoding"], "mono8");
      EXPECT_EQ(m["width"], 80);
      EXPECT_EQ(m["height"], 60);
      EXPECT_EQ(m["step"], 80);
      EXPECT_EQ(m["data"].get<std::vector<int>>(), bytes_of(cam == 0 ? seq.left[i] : seq.right[i]));
      // camera_info: P = K [I | (-B, 0, 0)] (cam1's Tx = -fx B = -120), no distortion.
      EXPECT_EQ(infos[i]["stamp_ns"], seq.stamps[i]);
      EXPECT_EQ(infos[i]["P"].get<std::vector<double>>(),
                (std::vector<double>{480, 0, 40.5, cam == 0 ? 0.0 : -120.0, 0, 470, 30.25, 0, 0, 0,
                                     1, 0}));
      EXPECT_EQ(infos[i]["D"].get<std::vector<double>>(), std::vector<double>(5, 0.0));
    }
  }
  // IMU: values exactly, covariance density^2 x rate, no orientation.
  const auto imu = messages_on(bag, "/imu0");
  ASSERT_EQ(imu.size(), seq.imu.size());
  for (std::size_t k = 0; k < imu.size(); ++k) {
    EXPECT_EQ(imu[k]["stamp_ns"], seq.imu[k].t_ns);
    for (int a = 0; a < 3; ++a) {
      EXPECT_EQ(imu[k]["w"][a].get<double>(), seq.imu[k].gyro_rad_s[a]);
      EXPECT_EQ(imu[k]["a"][a].get<double>(), seq.imu[k].accel_m_s2[a]);
    }
    EXPECT_EQ(imu[k]["q_cov0"], -1.0);
    EXPECT_DOUBLE_EQ(imu[k]["w_cov"][4].get<double>(), 1.7e-4 * 1.7e-4 * 200);
    EXPECT_DOUBLE_EQ(imu[k]["a_cov"][8].get<double>(), 2e-3 * 2e-3 * 200);
  }
  // GPS: a fix with covariance from HDOP (sigma 1.5 m x HDOP 1.25: 1.875 m horizontal RMS),
  // then no fix.
  const auto gps = messages_on(bag, "/gps/fix");
  ASSERT_EQ(gps.size(), 2u);
  EXPECT_EQ(gps[0]["status"], 0);
  EXPECT_EQ(gps[0]["service"], 1);
  EXPECT_EQ(gps[0]["lla"].get<std::vector<double>>(), (std::vector<double>{52.5, -0.25, 17.5}));
  EXPECT_DOUBLE_EQ(gps[0]["cov"][0].get<double>(), 1.875 * 1.875 / 2);
  EXPECT_DOUBLE_EQ(gps[0]["cov"][4].get<double>(), 1.875 * 1.875 / 2);
  EXPECT_EQ(gps[0]["cov_type"], 1);
  EXPECT_EQ(gps[1]["status"], -1);
  EXPECT_TRUE(gps[1]["lla"][0].is_null());
  EXPECT_EQ(gps[1]["cov_type"], 0);
  // Compass: the field in tesla, the heading a turn about the world's down axis.
  const auto mag = messages_on(bag, "/mag");
  const auto heading = messages_on(bag, "/compass/heading");
  ASSERT_EQ(mag.size(), 2u);
  EXPECT_EQ(mag[0]["stamp_ns"], 50'000'000);
  EXPECT_NEAR(mag[0]["field"][2].get<double>(), 46000e-9, 1e-18);
  const Vec3 north_turned = quat_of(heading[1]["q"]) * Vec3::UnitX();
  EXPECT_NEAR(std::atan2(north_turned.y(), north_turned.x()), deg2rad(350.5 - 360), 1e-12);
  // Ground truth: the IMU's poses, exactly.
  const auto gt = messages_on(bag, "/groundtruth/pose");
  ASSERT_EQ(gt.size(), seq.truth.body.size());
  for (std::size_t k = 0; k < gt.size(); ++k) {
    const SE3& T = seq.truth.body[k].T_W_S;
    EXPECT_EQ(gt[k]["frame_id"], "world_ned");
    for (int a = 0; a < 3; ++a) EXPECT_EQ(gt[k]["p"][a].get<double>(), T.translation()[a]);
    EXPECT_LT(quat_of(gt[k]["q"]).angularDistance(T.quaternion()), 1e-15);
  }
  // tf_static: base_link (x forward, y left, z up) -> imu is FLU <- FRD times the mount, so the
  // IMU's x axis (forward, turned 0.05 rad to starboard) is (cos, -sin, 0) in base_link.
  const json tf = messages_on(bag, "/tf_static").at(0)["transforms"];
  ASSERT_EQ(tf.size(), 5u);
  EXPECT_EQ(tf[0]["parent"], "base_link");
  EXPECT_EQ(tf[0]["child"], "imu");
  const Vec3 imu_x = quat_of(tf[0]["q"]) * Vec3::UnitX();
  EXPECT_LT((imu_x - Vec3(std::cos(0.05), -std::sin(0.05), 0)).norm(), 1e-12);
  EXPECT_EQ(tf[0]["t"].get<std::vector<double>>(), (std::vector<double>{1, 0, 0.5}));
  EXPECT_EQ(tf[1]["child"], "gps");
  EXPECT_EQ(tf[1]["t"].get<std::vector<double>>(), (std::vector<double>{0, -0.5, 3}));
  EXPECT_EQ(tf[4]["parent"], "imu");
  EXPECT_EQ(tf[4]["child"], "cam1_optical");
  const Vec3 cam1 = bag_calibration().T_S_C * Vec3(0.25, 0, 0);
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(tf[4]["t"][a].get<double>(), cam1[a], 1e-15);
}

TEST(RosbagExport, PythonsRosbagReadsEveryMessageWithItsStampsAndValues) {
  const fs::path root = test::fresh_temp_dir("rosbag_export");
  const BagSequence seq(root / "staging");
  seq.write(*make_writer(DatasetFormat::kRosbag, root, bag_calibration()));
  const json bag = json::parse(
      python("read_bag.py", {(root / rosbag_names::kBagFile).string()}, root / "bag.json"));
  EXPECT_EQ(bag["version"], 200);
  expect_the_sequence(bag, seq, false);
  // The bag_calibration files: OpenCV's FileStorage reads VINS-Fusion's configuration.
  cv::FileStorage vins((root / "vins_fusion" / "stereo_imu_config.yaml").string(),
                       cv::FileStorage::READ);
  cv::Mat body_T_cam1;
  vins["body_T_cam1"] >> body_T_cam1;
  ASSERT_EQ(body_T_cam1.rows, 4);
  const Vec3 cam1 = bag_calibration().T_S_C * Vec3(0.25, 0, 0);
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(body_T_cam1.at<double>(a, 3), cam1[a], 1e-15);
  EXPECT_EQ(static_cast<std::string>(vins["image1_topic"]), "/cam1/image_raw");
  // VINS-Fusion takes its noises per IMU sample: over one sample period dt its preintegration
  // adds sigma^2 dt^2, which must be the variance a Kalibr density gives, density^2 dt.
  const double dt = 1.0 / bag_calibration().imu.rate_hz;
  const std::pair<const char*, double> densities[] = {
      {"gyr_n", 1.7e-4}, {"gyr_w", 2e-5}, {"acc_n", 2e-3}, {"acc_w", 3e-3}};
  for (const auto& [key, density] : densities) {
    const double sigma = static_cast<double>(vins[key]);
    EXPECT_NEAR(sigma * sigma * dt * dt, density * density * dt, 1e-6 * density * density * dt)
        << key;
  }
  EXPECT_DOUBLE_EQ(static_cast<double>(vins["g_norm"]), 9.80665);
  // With multiple_thread: 1 its estimator takes every second image (estimator.cpp,
  // inputImageCnt % 2): at 10 Hz, one thread and every image.
  ASSERT_LT(bag_calibration().camera_rate_hz, 20);
  EXPECT_EQ(static_cast<int>(vins["multiple_thread"]), 0);
  fs::remove_all(root);
}

// Row r, column c of a matrix written as a block list of rows, read through OpenCV's FileNode
// as OpenVINS's YAML parser reads it.
double kalibr_entry(const cv::FileNode& rows, int r, int c) {
  return static_cast<double>(rows[r][c]);
}

TEST(RosbagExport, OpenVinsReaderOpenCvFileStorageReadsTheKalibrChains) {
  // OpenVINS opens both chains with cv::FileStorage, which takes a file for YAML only when it
  // starts with a %YAML directive, and reads cam0/cam1 T_imu_cam (the camera in the IMU frame)
  // and the IMU's Tw, R_IMUtoGYRO, Ta, R_IMUtoACC and Tg, every one required.
  const fs::path root = test::fresh_temp_dir("kalibr_opencv");
  const BagSequence seq(root / "staging");
  seq.write(*make_writer(DatasetFormat::kRosbag, root, bag_calibration()));
  cv::FileStorage cams((root / "kalibr_imucam_chain.yaml").string(), cv::FileStorage::READ);
  ASSERT_TRUE(cams.isOpened());
  for (int i = 0; i < 2; ++i) {
    const cv::FileNode T = cams[fmt::format("cam{}", i)]["T_imu_cam"];
    ASSERT_EQ(T.size(), 4u);
    const SE3 T_S_Ci = bag_calibration().T_S_C * SE3(Mat3::Identity(), Vec3(0.25 * i, 0, 0));
    const Eigen::Matrix4d expected = T_S_Ci.matrix();
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) EXPECT_NEAR(kalibr_entry(T, r, c), expected(r, c), 1e-15);
    EXPECT_EQ(static_cast<std::string>(cams[fmt::format("cam{}", i)]["camera_model"]), "pinhole");
  }
  cv::FileStorage imu((root / "kalibr_imu_chain.yaml").string(), cv::FileStorage::READ);
  ASSERT_TRUE(imu.isOpened());
  const cv::FileNode imu0 = imu["imu0"];
  EXPECT_DOUBLE_EQ(static_cast<double>(imu0["gyroscope_random_walk"]), 2e-5);
  for (const char* key : {"Tw", "R_IMUtoGYRO", "Ta", "R_IMUtoACC", "Tg"}) {
    const cv::FileNode m = imu0[key];
    ASSERT_EQ(m.size(), 3u) << key;
    const bool identity = std::string(key) != "Tg";
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        EXPECT_EQ(kalibr_entry(m, r, c), identity && r == c ? 1.0 : 0.0) << key;
  }
  fs::remove_all(root);
}

// The keys OpenVINS's serial node reads from estimator_config.yaml, each required (a missing
// one stops it), with the type its parser reads: s string, b bool (true/false as a string),
// i integer, r real (an integer node reads as a real too), v three reals.
struct OpenVinsKey {
  const char* key;
  char type;
};
constexpr OpenVinsKey kOpenVinsKeys[] = {{"verbosity", 's'},
                                         {"use_fej", 'b'},
                                         {"integration", 's'},
                                         {"use_stereo", 'b'},
                                         {"max_cameras", 'i'},
                                         {"calib_cam_extrinsics", 'b'},
                                         {"calib_cam_intrinsics", 'b'},
                                         {"calib_cam_timeoffset", 'b'},
                                         {"calib_imu_intrinsics", 'b'},
                                         {"calib_imu_g_sensitivity", 'b'},
                                         {"max_clones", 'i'},
                                         {"max_slam", 'i'},
                                         {"max_slam_in_update", 'i'},
                                         {"max_msckf_in_update", 'i'},
                                         {"dt_slam_delay", 'r'},
                                         {"gravity_mag", 'r'},
                                         {"feat_rep_msckf", 's'},
                                         {"feat_rep_slam", 's'},
                                         {"feat_rep_aruco", 's'},
                                         {"try_zupt", 'b'},
                                         {"zupt_chi2_multipler", 'r'},
                                         {"zupt_max_velocity", 'r'},
                                         {"zupt_noise_multiplier", 'r'},
                                         {"zupt_max_disparity", 'r'},
                                         {"zupt_only_at_beginning", 'b'},
                                         {"init_window_time", 'r'},
                                         {"init_imu_thresh", 'r'},
                                         {"init_max_disparity", 'r'},
                                         {"init_max_features", 'i'},
                                         {"init_dyn_use", 'b'},
                                         {"init_dyn_mle_opt_calib", 'b'},
                                         {"init_dyn_mle_max_iter", 'i'},
                                         {"init_dyn_mle_max_threads", 'i'},
                                         {"init_dyn_mle_max_time", 'r'},
                                         {"init_dyn_min_deg", 'r'},
                                         {"init_dyn_num_pose", 'i'},
                                         {"init_dyn_inflation_ori", 'r'},
                                         {"init_dyn_inflation_vel", 'r'},
                                         {"init_dyn_inflation_bg", 'r'},
                                         {"init_dyn_inflation_ba", 'r'},
                                         {"init_dyn_min_rec_cond", 'r'},
                                         {"init_dyn_bias_g", 'v'},
                                         {"init_dyn_bias_a", 'v'},
                                         {"record_timing_information", 'b'},
                                         {"record_timing_filepath", 's'},
                                         {"use_klt", 'b'},
                                         {"num_pts", 'i'},
                                         {"fast_threshold", 'i'},
                                         {"grid_x", 'i'},
                                         {"grid_y", 'i'},
                                         {"min_px_dist", 'i'},
                                         {"knn_ratio", 'r'},
                                         {"track_frequency", 'r'},
                                         {"downsample_cameras", 'b'},
                                         {"num_opencv_threads", 'i'},
                                         {"histogram_method", 's'},
                                         {"use_aruco", 'b'},
                                         {"num_aruco", 'i'},
                                         {"downsize_aruco", 'b'},
                                         {"up_msckf_sigma_px", 'r'},
                                         {"up_msckf_chi2_multipler", 'r'},
                                         {"up_slam_sigma_px", 'r'},
                                         {"up_slam_chi2_multipler", 'r'},
                                         {"up_aruco_sigma_px", 'r'},
                                         {"up_aruco_chi2_multipler", 'r'},
                                         {"use_mask", 'b'},
                                         {"relative_config_imu", 's'},
                                         {"relative_config_imucam", 's'}};

TEST(RosbagExport, OpenVinsFindsEveryRequiredKeyOfItsEstimatorConfigWithItsType) {
  const fs::path root = test::fresh_temp_dir("openvins_config");
  const BagSequence seq(root / "staging");
  seq.write(*make_writer(DatasetFormat::kRosbag, root, bag_calibration()));
  cv::FileStorage config((root / "estimator_config.yaml").string(), cv::FileStorage::READ);
  ASSERT_TRUE(config.isOpened());
  ASSERT_EQ(std::size(kOpenVinsKeys), 68u);
  for (const auto& [key, type] : kOpenVinsKeys) {
    const cv::FileNode n = config[key];
    ASSERT_FALSE(n.empty()) << key;
    switch (type) {
      case 's':
        EXPECT_TRUE(n.isString()) << key;
        break;
      case 'b': {
        const std::string b = n.isString() ? static_cast<std::string>(n) : "";
        EXPECT_TRUE(b == "true" || b == "false") << key << ": " << b;
        break;
      }
      case 'i':
        EXPECT_TRUE(n.isInt()) << key;
        break;
      case 'r':
        EXPECT_TRUE(n.isReal() || n.isInt()) << key;
        break;
      case 'v':
        ASSERT_TRUE(n.isSeq() && n.size() == 3) << key;
        for (int a = 0; a < 3; ++a) EXPECT_TRUE(n[a].isReal() || n[a].isInt()) << key;
        break;
    }
  }
  // Its own checks: an IMU model 'calibrated' with neither IMU calibration on, a stereo pair,
  // the dynamic initialiser's limits, and the Kalibr files it names, beside it.
  cv::FileStorage imu((root / static_cast<std::string>(config["relative_config_imu"])).string(),
                      cv::FileStorage::READ);
  ASSERT_TRUE(imu.isOpened());
  EXPECT_EQ(static_cast<std::string>(imu["imu0"]["model"]), "calibrated");
  EXPECT_EQ(static_cast<std::string>(config["calib_imu_intrinsics"]), "false");
  EXPECT_EQ(static_cast<std::string>(config["calib_imu_g_sensitivity"]), "false");
  cv::FileStorage cams((root / static_cast<std::string>(config["relative_config_imucam"])).string(),
                       cv::FileStorage::READ);
  ASSERT_TRUE(cams.isOpened());
  EXPECT_EQ(static_cast<int>(config["max_cameras"]), 2);
  EXPECT_FALSE(cams["cam1"].empty());
  EXPECT_GE(static_cast<int>(config["init_max_features"]), 15);
  EXPECT_GE(static_cast<int>(config["init_dyn_num_pose"]), 4);
  EXPECT_EQ(static_cast<std::string>(config["integration"]), "rk4");
  EXPECT_EQ(static_cast<std::string>(config["histogram_method"]), "HISTOGRAM");
  // No frame is dropped: each comes 1 / rate after the last, later than 1 / track_frequency.
  EXPECT_GT(static_cast<double>(config["track_frequency"]), bag_calibration().camera_rate_hz);
  EXPECT_DOUBLE_EQ(static_cast<double>(config["gravity_mag"]), 9.80665);
  // Its feature triangulation reaches the depth at half a pixel of stereo disparity, f B / 0.5:
  // a feature at that depth seen by the pair alone passes the distance, the distance over
  // baseline and (growing as its square) the condition number gates.
  const auto& cal = bag_calibration();
  const double depth = cal.rig.camera.fx * cal.rig.baseline_m / 0.5;
  EXPECT_NEAR(static_cast<double>(config["fi_max_dist"]), depth, 1e-9 * depth);
  EXPECT_NEAR(static_cast<double>(config["fi_max_baseline"]), depth / cal.rig.baseline_m, 1e-6);
  EXPECT_NEAR(static_cast<double>(config["fi_max_cond_number"]),
              std::pow(depth / cal.rig.baseline_m, 2), 1e-3);
  fs::remove_all(root);
}

TEST(Rosbag2Export, ADecoderOfItsOwnFindsEveryMessageInTheDatabase) {
  const fs::path root = test::fresh_temp_dir("rosbag2_export");
  const BagSequence seq(root / "staging");
  seq.write(*make_writer(DatasetFormat::kRosbag2, root, bag_calibration()));
  const json bag = json::parse(
      python("read_rosbag2.py", {(root / rosbag_names::kBag2Folder).string()}, root / "bag.json"));
  EXPECT_EQ(bag["version"], 5);
  EXPECT_EQ(bag["storage"], "sqlite3");
  EXPECT_EQ(bag["metadata_count"], bag["messages"].size());
  for (const auto& [topic, info] : bag["topics"].items()) {
    EXPECT_EQ(info["format"], "cdr") << topic;
    EXPECT_EQ(bag["metadata_topics"][topic], info["count"]) << topic;
  }
  expect_the_sequence(bag, seq, true);
  fs::remove_all(root);
}

TEST(RosbagExport, ReadsBackThroughItsKalibrChain) {
  const fs::path root = test::fresh_temp_dir("rosbag_reader");
  const BagSequence seq(root / "staging");
  seq.write(*make_writer(DatasetFormat::kRosbag, root, bag_calibration()));
  const StereoDataset d = read_dataset(root, DatasetFormat::kRosbag);
  EXPECT_EQ(d.format, DatasetFormat::kRosbag);
  EXPECT_EQ(d.rig.camera.fx, 480);
  EXPECT_EQ(d.rig.camera.cy, 30.25);
  EXPECT_NEAR(d.rig.baseline_m, 0.25, 1e-15);
  EXPECT_FALSE(d.rectification);
  EXPECT_TRUE(d.has_extrinsics);
  EXPECT_LT((d.T_S_C.inverse() * bag_calibration().T_S_C).log().norm(), 1e-12);
  ASSERT_EQ(d.frames.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(d.frames[i].t_ns, seq.stamps[i]);
    const auto [left, right] = read_pair(d, d.frames[i]);
    EXPECT_EQ(bytes_of(left), bytes_of(seq.left[i]));
    EXPECT_EQ(bytes_of(right), bytes_of(seq.right[i]));
  }
  ASSERT_EQ(d.imu.size(), seq.imu.size());
  EXPECT_EQ(d.imu[7].gyro_rad_s, seq.imu[7].gyro_rad_s);
  EXPECT_EQ(d.imu[7].accel_m_s2, seq.imu[7].accel_m_s2);
  ASSERT_TRUE(d.imu_noise.has_value());
  EXPECT_EQ(d.imu_noise->gyroscope_random_walk, 2e-5);
  ASSERT_EQ(d.compass.size(), 2u);
  EXPECT_NEAR(d.compass[1].heading_rad, deg2rad(350.5 - 360), 1e-12);
  EXPECT_NEAR(d.compass[0].field_S_nt.x(), 17000, 1e-9);
  ASSERT_EQ(d.camera_gt.size(), seq.truth.body.size());
  const SE3 expected = seq.truth.body[5].T_W_S * bag_calibration().T_S_C;
  EXPECT_LT((d.camera_gt[5].T_W_C.inverse() * expected).log().norm(), 1e-12);
  fs::remove_all(root);
}

// A Kalibr chain for the EuRoC-like bag, as OpenVINS ships them (T_imu_cam), with distortion and
// a right camera turned a little, and the same cameras as an EuRoC folder's sensor.yaml files.
void write_distorted_calibration(const fs::path& root) {
  const std::string T0 = "[1, 0, 0, 0.1, 0, 1, 0, -0.02, 0, 0, 1, 0.01, 0, 0, 0, 1]";
  const std::string T1 =
      "[0.9998, -0.0199987, 0, 0.21, 0.0199987, 0.9998, 0, -0.02, 0, 0, 1, 0.01, 0, 0, 0, 1]";
  const auto rows = [](const std::string& flat) {
    std::string out, inner = flat.substr(1, flat.size() - 2);
    std::istringstream in(inner);
    std::vector<std::string> v;
    for (std::string x; std::getline(in, x, ',');) v.push_back(x);
    for (int r = 0; r < 4; ++r)
      out +=
          fmt::format("    - [{},{},{},{}]\n", v[4 * r], v[4 * r + 1], v[4 * r + 2], v[4 * r + 3]);
    return out;
  };
  // OpenVINS's files start with OpenCV's directive, which is not YAML 1.2's.
  std::string chain = "%YAML:1.0 # need to specify the file type at the top!\n\n";
  for (int i = 0; i < 2; ++i) {
    const std::string k = i == 0 ? "[100, 101, 47.5, 35.5]" : "[102, 103, 48.5, 36]";
    const std::string dist = i == 0 ? "[-0.28, 0.07, 0.0002, 0.00002]" : "[-0.27, 0.06, 0, 0.0001]";
    chain += fmt::format(
        "cam{}:\n  T_imu_cam:\n{}  camera_model: pinhole\n  distortion_coeffs: {}\n"
        "  distortion_model: radtan\n  intrinsics: {}\n  resolution: [96, 72]\n"
        "  rostopic: /cam{}/image_raw\n",
        i, rows(i == 0 ? T0 : T1), dist, k, i);
    write_file_atomic(root / "mav0" / fmt::format("cam{}", i) / "sensor.yaml",
                      fmt::format("sensor_type: camera\nT_BS:\n  cols: 4\n  rows: 4\n  data: {}\n"
                                  "rate_hz: 20\nresolution: [96, 72]\ncamera_model: pinhole\n"
                                  "intrinsics: {}\ndistortion_model: radial-tangential\n"
                                  "distortion_coefficients: {}\n",
                                  i == 0 ? T0 : T1, k, dist));
  }
  write_file_atomic(root / "openvins_euroc_chain.yaml", chain);
}

TEST(RosbagRead, AnEurocLayoutBagFromRosPythonGivesWhatItsEurocFolderGives) {
  const fs::path root = test::fresh_temp_dir("rosbag_euroc_like");
  python("write_euroc_bag.py", {root.string()}, root / "writer.log");
  write_distorted_calibration(root);
  ReadOptions options;
  options.calibration = root / "openvins_euroc_chain.yaml";
  const StereoDataset bag = read_dataset(root / "euroc_like.bag", DatasetFormat::kRosbag, options);
  const StereoDataset folder = read_dataset(root, DatasetFormat::kEuroc);
  ASSERT_TRUE(bag.rectification);
  EXPECT_EQ(bag.rig.camera.fx, folder.rig.camera.fx);
  EXPECT_EQ(bag.rig.baseline_m, folder.rig.baseline_m);
  EXPECT_LT((bag.T_S_C.inverse() * folder.T_S_C).log().norm(), 1e-12);
  ASSERT_EQ(bag.frames.size(), 4u);
  ASSERT_EQ(folder.frames.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(bag.frames[i].t_ns, folder.frames[i].t_ns);  // header stamps, not record times
    EXPECT_EQ(bag.frames[i].left_record_ns, bag.frames[i].t_ns + 3'000'000);
    const auto [bl, br] = read_pair(bag, bag.frames[i]);
    const auto [fl, fr] = read_pair(folder, folder.frames[i]);
    EXPECT_EQ(bytes_of(bl), bytes_of(fl)) << i;
    EXPECT_EQ(bytes_of(br), bytes_of(fr)) << i;
  }
  // EuRoC's Vicon topic is found without --gt-topic: the IMU's pose times T_S_C.
  ASSERT_EQ(bag.camera_gt.size(), 40u);
  const SE3 T_W_S(Quat(std::cos(0.005), 0, 0, std::sin(0.005)), Vec3(0.05, 1, 0.8));
  EXPECT_LT((bag.camera_gt[5].T_W_C.inverse() * (T_W_S * bag.T_S_C)).log().norm(), 1e-12);
  EXPECT_EQ(bag.imu.size(), 40u);
  EXPECT_FALSE(bag.imu_noise.has_value());  // no Kalibr IMU chain beside the camera chain
  // Position-only truth is a clear error naming the topic and why.
  options.gt_topic = "/leica/position";
  const std::string leica = driftlab::test::user_error_of(
      [&] { read_dataset(root / "euroc_like.bag", DatasetFormat::kRosbag, options); });
  EXPECT_NE(leica.find("/leica/position: got ground truth of type geometry_msgs/PointStamped"),
            std::string::npos)
      << leica;
  fs::remove_all(root);
}

TEST(RosbagRead, BadInputIsAClearError) {
  const fs::path root = test::fresh_temp_dir("rosbag_errors");
  const BagSequence seq(root / "export" / "staging");
  seq.write(*make_writer(DatasetFormat::kRosbag, root / "export", bag_calibration()));
  const fs::path bag = root / "export" / rosbag_names::kBagFile;
  const auto read = [&](const fs::path& path, const ReadOptions& o) {
    return driftlab::test::user_error_of([&] { read_dataset(path, DatasetFormat::kRosbag, o); });
  };
  // No bag_calibration beside the bag.
  fs::create_directories(root / "alone");
  fs::copy_file(bag, root / "alone" / "x.bag");
  EXPECT_NE(read(root / "alone" / "x.bag", {})
                .find("no camera calibration: expected "
                      "kalibr_imucam_chain.yaml beside the bag"),
            std::string::npos);
  // Not a bag.
  write_file_atomic(root / "export" / "text.bag", "#ROSBAG V2.0\nnot really\n");
  ReadOptions o;
  o.calibration = root / "export" / rosbag_names::kCamchainFile;
  EXPECT_NE(read(root / "export" / "text.bag", o).find("text.bag: record at byte 13: "),
            std::string::npos)
      << read(root / "export" / "text.bag", o);
  // Two bags in a folder, neither driftlab.bag: which one?
  fs::copy_file(bag, root / "alone" / "y.bag");
  EXPECT_NE(read(root / "alone", {}).find("found 2 .bag files"), std::string::npos);
  // A ground-truth topic that is not there.
  o.gt_topic = "/nothing";
  EXPECT_NE(read(bag, o).find("--gt-topic: no messages on '/nothing'"), std::string::npos);
  // A camera topic with messages of another type.
  o.gt_topic.clear();
  std::string chain = slurp(o.calibration);
  chain.replace(chain.find("rostopic: /cam1/image_raw"), 25, "rostopic: /imu0");
  write_file_atomic(root / "chain.yaml", chain);
  o.calibration = root / "chain.yaml";
  EXPECT_NE(read(bag, o).find("/imu0: got messages of type sensor_msgs/Imu, expected "
                              "sensor_msgs/Image"),
            std::string::npos)
      << read(bag, o);
  fs::remove_all(root);
}

}  // namespace
}  // namespace driftlab::dataset
