// The dataset writers against each format's published description (KITTI odometry devkit,
// EuRoC/ASL, TUM RGB-D file formats) and a round trip through our readers.
#include "dataset/dataset.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <fmt/format.h>

#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <numbers>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/persistence.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>
#include <sstream>

#include "core/error.hpp"
#include "core/rotation.hpp"
#include "dataset/dataset_detail.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::dataset {
namespace {

namespace fs = std::filesystem;
using test::slurp;

ExportCalibration calibration() {
  ExportCalibration cal;
  cal.rig.camera.fx = 480;
  cal.rig.camera.fy = 470;
  cal.rig.camera.cx = 40.5;
  cal.rig.camera.cy = 30.25;
  cal.rig.camera.width = 80;
  cal.rig.camera.height = 60;
  cal.rig.baseline_m = 0.25;
  cal.T_S_C = SE3(quat_from_euler_zyx({0.1, -0.2, 0.3}), Vec3(0.5, -0.1, 0.2));
  cal.camera_rate_hz = 10;
  cal.imu = {200, 1.7e-4, 2e-5, 2e-3, 3e-3};
  cal.source = "test";
  return cal;
}

// Three frames of random 8-bit images, a true trajectory and body states.
struct Sequence {
  std::vector<TimeNs> stamps{1'000'000'000, 1'100'000'123, 1'200'000'000};
  std::vector<cv::Mat> left, right, depth;
  ExportTruth truth;
  Sequence() {
    cv::RNG rng(7);
    for (std::size_t i = 0; i < stamps.size(); ++i) {
      cv::Mat l(60, 80, CV_8UC1), r(60, 80, CV_8UC1), d(60, 80, CV_32FC1);
      rng.fill(l, cv::RNG::UNIFORM, 0, 256);
      rng.fill(r, cv::RNG::UNIFORM, 0, 256);
      rng.fill(d, cv::RNG::UNIFORM, 0.5, 20.0);
      d.at<float>(0, 0) = std::numeric_limits<float>::infinity();  // sky: no depth
      left.push_back(l);
      right.push_back(r);
      depth.push_back(d);
      const SE3 T(quat_from_euler_zyx({0.01 * i, 0.02, 0.5 + 0.1 * i}), Vec3(3 + i, 2 * i, -1));
      truth.camera.push_back({stamps[i], T});
      truth.body.push_back({stamps[i], T * calibration().T_S_C.inverse(), Vec3(1, 0, 0), {}});
    }
  }
  void write(DatasetWriter& w) const {
    for (std::size_t i = 0; i < stamps.size(); ++i)
      w.add_frame(stamps[i], left[i], right[i], w.wants_depth() ? depth[i] : cv::Mat());
    w.finish(truth);
  }
};

bool same_image(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

double pose_difference(const SE3& a, const SE3& b) { return (a.inverse() * b).log().norm(); }

std::vector<double> numbers_after(const std::string& text, const std::string& key) {
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);)
    if (line.rfind(key + ":", 0) == 0) {
      std::istringstream in(line.substr(key.size() + 1));
      std::vector<double> out;
      for (double v; in >> v;) out.push_back(v);
      return out;
    }
  return {};
}

TEST(KittiExport, FollowsTheOdometryDevkitAndReadsBack) {
  const fs::path root = test::fresh_temp_dir("kitti_export");
  const Sequence seq;
  seq.write(*make_writer(DatasetFormat::kKitti, root, calibration()));
  const fs::path s = root / "sequences" / "00";
  for (const char* f : {"000000.png", "000001.png", "000002.png"}) {
    EXPECT_TRUE(fs::exists(s / "image_0" / f)) << f;
    EXPECT_TRUE(fs::exists(s / "image_1" / f)) << f;
  }
  // calib.txt: P0 = K [I | 0], P1 = K [I | (-B, 0, 0)], i.e. P1(0,3) = -fx B (devkit readme).
  const std::string calib = slurp(s / "calib.txt");
  const std::vector<double> P0 = numbers_after(calib, "P0"), P1 = numbers_after(calib, "P1");
  EXPECT_EQ(P0, (std::vector<double>{480, 0, 40.5, 0, 0, 470, 30.25, 0, 0, 0, 1, 0}));
  EXPECT_EQ(P1, (std::vector<double>{480, 0, 40.5, -120, 0, 470, 30.25, 0, 0, 0, 1, 0}));
  EXPECT_EQ(numbers_after(calib, "P2"), P0);
  EXPECT_EQ(numbers_after(calib, "P3"), P1);
  EXPECT_EQ(slurp(s / "times.txt"), "1.000000000\n1.100000123\n1.200000000\n");
  // poses/00.txt: the first line the identity, then T_C0_Ci.
  std::istringstream poses(slurp(root / "poses" / "00.txt"));
  std::string first;
  std::getline(poses, first);
  EXPECT_EQ(first, "1 0 0 0 0 1 0 0 0 0 1 0");

  const StereoDataset d = read_dataset(root, DatasetFormat::kKitti);
  EXPECT_EQ(d.rig.camera.fx, 480);
  EXPECT_EQ(d.rig.camera.fy, 470);
  EXPECT_EQ(d.rig.camera.cx, 40.5);
  EXPECT_EQ(d.rig.camera.cy, 30.25);
  EXPECT_EQ(d.rig.camera.width, 80);
  EXPECT_EQ(d.rig.camera.height, 60);
  EXPECT_DOUBLE_EQ(d.rig.baseline_m, 0.25);
  ASSERT_EQ(d.frames.size(), 3u);
  ASSERT_EQ(d.camera_gt.size(), 3u);
  const SE3 T_C0_W = seq.truth.camera[0].T_W_C.inverse();
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(d.frames[i].t_ns, seq.stamps[i]);
    EXPECT_EQ(d.camera_gt[i].t_ns, seq.stamps[i]);
    EXPECT_LT(pose_difference(d.camera_gt[i].T_W_C, T_C0_W * seq.truth.camera[i].T_W_C), 1e-12);
    EXPECT_TRUE(same_image(read_gray(d.frames[i].left), seq.left[i]));
    EXPECT_TRUE(same_image(read_gray(d.frames[i].right), seq.right[i]));
  }
  // The sequence folder itself reads too.
  EXPECT_EQ(read_dataset(s, DatasetFormat::kKitti).frames.size(), 3u);
  fs::remove_all(root);
}

TEST(EurocExport, FollowsTheAslLayoutAndReadsBack) {
  const fs::path root = test::fresh_temp_dir("euroc_export");
  const Sequence seq;
  // The IMU CSV is handed over as a file (the sensor stage wrote it) and moved, bytes as they are.
  const fs::path staging = root / "staging";
  fs::create_directories(staging);
  const std::vector<ImuSample> imu = {{1'000'000'000, Vec3(0.1, 0.2, 0.3), Vec3(0, 0, -9.8)},
                                      {1'005'000'000, Vec3(0.1, 0.2, 0.4), Vec3(0, 0.1, -9.8)}};
  write_euroc_imu(staging / "imu.csv", imu);
  const std::string imu_bytes = slurp(staging / "imu.csv");
  Sequence with_imu = seq;
  with_imu.truth.sensor_csvs = {staging / "imu.csv"};
  const auto writer = make_writer(DatasetFormat::kEuroc, root, calibration());
  with_imu.write(*writer);
  const fs::path mav = root / "mav0";
  EXPECT_EQ(slurp(mav / "imu0" / "data.csv"), imu_bytes);
  const std::string index = slurp(mav / "cam0" / "data.csv");
  EXPECT_EQ(index.rfind("#timestamp [ns],filename\n1000000000,1000000000.png\n", 0), 0u);
  EXPECT_TRUE(fs::exists(mav / "cam1" / "data" / "1100000123.png"));
  // sensor.yaml as the ASL format describes it.
  const YAML::Node cam0 = YAML::LoadFile((mav / "cam0" / "sensor.yaml").string());
  EXPECT_EQ(cam0["sensor_type"].as<std::string>(), "camera");
  EXPECT_EQ(cam0["intrinsics"].as<std::vector<double>>(),
            (std::vector<double>{480, 470, 40.5, 30.25}));
  EXPECT_EQ(cam0["resolution"].as<std::vector<int>>(), (std::vector<int>{80, 60}));
  EXPECT_EQ(cam0["T_BS"]["rows"].as<int>(), 4);
  const YAML::Node imu_yaml = YAML::LoadFile((mav / "imu0" / "sensor.yaml").string());
  EXPECT_EQ(imu_yaml["gyroscope_noise_density"].as<double>(), 1.7e-4);
  EXPECT_EQ(imu_yaml["accelerometer_random_walk"].as<double>(), 3e-3);
  EXPECT_EQ(imu_yaml["rate_hz"].as<double>(), 200);

  const StereoDataset d = read_dataset(root, DatasetFormat::kEuroc);
  EXPECT_DOUBLE_EQ(d.rig.baseline_m, 0.25);  // from cam1's T_BS: cam0's moved along its x
  EXPECT_EQ(d.rig.camera.fx, 480);
  EXPECT_LT(pose_difference(d.T_S_C, calibration().T_S_C), 1e-12);
  ASSERT_EQ(d.frames.size(), 3u);
  ASSERT_EQ(d.camera_gt.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(d.frames[i].t_ns, seq.stamps[i]);
    EXPECT_LT(pose_difference(d.camera_gt[i].T_W_C, seq.truth.camera[i].T_W_C), 1e-12);
    EXPECT_TRUE(same_image(read_gray(d.frames[i].right), seq.right[i]));
  }
  ASSERT_EQ(d.imu.size(), 2u);
  EXPECT_EQ(d.imu[1].gyro_rad_s, imu[1].gyro_rad_s);
  EXPECT_EQ(d.imu[1].accel_m_s2, imu[1].accel_m_s2);
  ASSERT_TRUE(d.imu_noise.has_value());  // imu0/sensor.yaml's Kalibr model, as written
  EXPECT_EQ(d.imu_noise->gyroscope_noise_density, 1.7e-4);
  EXPECT_EQ(d.imu_noise->accelerometer_random_walk, 3e-3);
  EXPECT_TRUE(d.has_extrinsics);
  EXPECT_TRUE(d.compass.empty());  // no compass0
  fs::remove_all(root);
}

// Stand-ins for Basalt and ORB-SLAM3: each reads its settings beside the EuRoC folder as that
// system does (Basalt: cereal's names and JSON types; ORB-SLAM3 v1.0: OpenCV's FileStorage,
// reals where Settings.cc reads floats, ints where it reads ints, matrices of floats), and the
// values must be the ones the folder's own sensor.yaml files hold.
SE3 basalt_pose(const nlohmann::json& p) {
  for (const char* k : {"px", "py", "pz", "qx", "qy", "qz", "qw"})
    EXPECT_TRUE(p.at(k).is_number_float()) << k;
  return SE3(Quat(p["qw"].get<double>(), p["qx"].get<double>(), p["qy"].get<double>(),
                  p["qz"].get<double>()),
             Vec3(p["px"].get<double>(), p["py"].get<double>(), p["pz"].get<double>()));
}

SE3 t_bs_of(const fs::path& sensor_yaml) {
  const auto d = YAML::LoadFile(sensor_yaml.string())["T_BS"]["data"].as<std::vector<double>>();
  Mat4 m;
  for (int i = 0; i < 16; ++i) m(i / 4, i % 4) = d[static_cast<std::size_t>(i)];
  return SE3(m);
}

void expect_basalt_reads(const fs::path& root, const ExportCalibration& cal, bool imu) {
  const auto j = nlohmann::json::parse(slurp(root / "basalt_calib.json")).at("value0");
  std::set<std::string> keys;
  for (const auto& [k, _] : j.items()) keys.insert(k);
  EXPECT_EQ(keys, (std::set<std::string>{"T_imu_cam", "intrinsics", "resolution", "vignette",
                                         "calib_accel_bias", "calib_gyro_bias", "imu_update_rate",
                                         "accel_noise_std", "gyro_noise_std", "accel_bias_std",
                                         "gyro_bias_std", "cam_time_offset_ns"}));
  for (int i = 0; i < 2; ++i) {
    const fs::path cam = root / "mav0" / fmt::format("cam{}", i) / "sensor.yaml";
    EXPECT_LT(pose_difference(basalt_pose(j["T_imu_cam"][i]), t_bs_of(cam)), 1e-9) << i;
    EXPECT_EQ(j["intrinsics"][i]["camera_type"], "pinhole");
    EXPECT_EQ(j["intrinsics"][i]["intrinsics"]["fx"].get<double>(), cal.rig.camera.fx);
    EXPECT_EQ(j["intrinsics"][i]["intrinsics"]["cy"].get<double>(), cal.rig.camera.cy);
    EXPECT_TRUE(j["resolution"][i][0].is_number_integer());
    EXPECT_EQ(j["resolution"][i],
              nlohmann::json::array({cal.rig.camera.width, cal.rig.camera.height}));
  }
  EXPECT_EQ(j["calib_accel_bias"].size(), 9u);
  EXPECT_EQ(j["calib_gyro_bias"].size(), 12u);
  EXPECT_TRUE(j["cam_time_offset_ns"].is_number_integer());
  if (!imu) {
    EXPECT_EQ(j["imu_update_rate"].get<double>(), 200);  // Basalt's default: a VO run
    return;
  }
  const YAML::Node m = YAML::LoadFile((root / "mav0" / "imu0" / "sensor.yaml").string());
  EXPECT_EQ(j["imu_update_rate"].get<double>(), m["rate_hz"].as<double>());
  EXPECT_EQ(j["gyro_noise_std"][2].get<double>(), m["gyroscope_noise_density"].as<double>());
  EXPECT_EQ(j["accel_noise_std"][0].get<double>(), m["accelerometer_noise_density"].as<double>());
  EXPECT_EQ(j["gyro_bias_std"][1].get<double>(), m["gyroscope_random_walk"].as<double>());
  EXPECT_EQ(j["accel_bias_std"][0].get<double>(), m["accelerometer_random_walk"].as<double>());
}

void expect_orbslam3_reads(const fs::path& file, const ExportCalibration& cal, bool inertial) {
  const cv::FileStorage fs(file.string(), cv::FileStorage::READ);
  ASSERT_TRUE(fs.isOpened()) << file;
  EXPECT_TRUE(fs["File.version"].isString());
  EXPECT_EQ(static_cast<std::string>(fs["File.version"]), "1.0");
  EXPECT_EQ(static_cast<std::string>(fs["Camera.type"]), "Rectified");
  std::vector<std::string> reals = {"Camera1.fx",
                                    "Camera1.fy",
                                    "Camera1.cx",
                                    "Camera1.cy",
                                    "Stereo.b",
                                    "Stereo.ThDepth",
                                    "ORBextractor.scaleFactor"};
  for (const char* v :
       {"KeyFrameSize", "KeyFrameLineWidth", "GraphLineWidth", "PointSize", "CameraSize",
        "CameraLineWidth", "ViewpointX", "ViewpointY", "ViewpointZ", "ViewpointF"})
    reals.push_back(std::string("Viewer.") + v);
  std::vector<std::string> ints = {"Camera.width",
                                   "Camera.height",
                                   "Camera.fps",
                                   "Camera.RGB",
                                   "ORBextractor.nFeatures",
                                   "ORBextractor.nLevels",
                                   "ORBextractor.iniThFAST",
                                   "ORBextractor.minThFAST"};
  if (inertial)
    for (const char* k :
         {"IMU.NoiseGyro", "IMU.NoiseAcc", "IMU.GyroWalk", "IMU.AccWalk", "IMU.Frequency"})
      reals.push_back(k);
  for (const auto& k : reals) EXPECT_TRUE(fs[k].isReal()) << file << ": " << k;
  for (const auto& k : ints) EXPECT_TRUE(fs[k].isInt()) << file << ": " << k;
  EXPECT_EQ(static_cast<double>(fs["Camera1.fx"]), cal.rig.camera.fx);
  EXPECT_EQ(static_cast<double>(fs["Stereo.b"]), cal.rig.baseline_m);
  EXPECT_EQ(static_cast<int>(fs["Camera.fps"]), 10);
  EXPECT_EQ(fs["IMU.T_b_c1"].empty(), !inertial);
  if (!inertial) return;
  EXPECT_EQ(static_cast<double>(fs["IMU.NoiseAcc"]), cal.imu.accelerometer_noise_density);
  cv::Mat T;
  fs["IMU.T_b_c1"] >> T;
  ASSERT_EQ(T.type(), CV_32F);  // Converter::toSophus reads floats
  ASSERT_EQ(T.rows * T.cols, 16);
  const Mat4 expected = cal.T_S_C.matrix();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(T.at<float>(r, c), expected(r, c), 1e-6);
}

TEST(EurocExport, BasaltAndOrbSlam3FindTheirSettingsAndTimesBesideTheFolder) {
  for (const bool imu : {true, false}) {
    const fs::path root = test::fresh_temp_dir(imu ? "euroc_peers_imu" : "euroc_peers_vo");
    const fs::path staging = root / "staging";
    fs::create_directories(staging);
    Sequence seq;
    if (imu) {
      write_euroc_imu(staging / "imu.csv", {{900'000'000, Vec3(0, 0, 0), Vec3(0, 0, -9.8)},
                                            {1'300'000'000, Vec3(0, 0, 0), Vec3(0, 0, -9.8)}});
      seq.truth.sensor_csvs = {staging / "imu.csv"};
    }
    const auto writer = make_writer(DatasetFormat::kEuroc, root, calibration());
    seq.write(*writer);
    expect_basalt_reads(root, calibration(), imu);
    expect_orbslam3_reads(root / "orbslam3_stereo.yaml", calibration(), false);
    EXPECT_EQ(fs::exists(root / "orbslam3_stereo_inertial.yaml"), imu);
    if (imu) expect_orbslam3_reads(root / "orbslam3_stereo_inertial.yaml", calibration(), true);
    // The times file: each line a PNG's name in cam0 and cam1 (the examples read no data.csv).
    std::istringstream times(slurp(root / "orbslam3_times.txt"));
    std::vector<TimeNs> stamps;
    for (std::string line; std::getline(times, line);) {
      stamps.push_back(std::stoll(line));
      EXPECT_TRUE(fs::exists(root / "mav0/cam0/data" / (line + ".png"))) << line;
      EXPECT_TRUE(fs::exists(root / "mav0/cam1/data" / (line + ".png"))) << line;
    }
    EXPECT_EQ(stamps, seq.stamps);
    fs::remove_all(root);
  }
}

TEST(TumRgbdExport, DepthIsSixteenBitAtFiveThousandPerMetre) {
  const fs::path root = test::fresh_temp_dir("tum_export");
  const Sequence seq;
  const auto writer = make_writer(DatasetFormat::kTumRgbd, root, calibration());
  ASSERT_TRUE(writer->wants_depth());
  seq.write(*writer);
  const std::string rgb = slurp(root / "rgb.txt");
  EXPECT_NE(rgb.find("# timestamp filename\n1.000000000 rgb/1.000000000.png\n"), std::string::npos);
  EXPECT_NE(slurp(root / "depth.txt").find("1.100000123 depth/1.100000123.png\n"),
            std::string::npos);
  const cv::Mat depth =
      cv::imread((root / "depth" / "1.100000123.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(depth.type(), CV_16UC1);
  std::size_t checked = 0;
  for (int r = 0; r < 60; ++r)
    for (int c = 0; c < 80; ++c) {
      const double z = seq.depth[1].at<float>(r, c);
      const int expected = z * 5000 <= 65535 ? static_cast<int>(std::lround(z * 5000)) : 0;
      if (!std::isfinite(z)) continue;
      ASSERT_EQ(depth.at<std::uint16_t>(r, c), expected) << r << "," << c;
      ++checked;
    }
  EXPECT_EQ(checked, 60u * 80u - 1);
  EXPECT_EQ(depth.at<std::uint16_t>(0, 0), 0);  // infinite: no depth
  const Trajectory gt = read_tum(root / "groundtruth.txt");
  ASSERT_EQ(gt.size(), 3u);
  EXPECT_LT(pose_difference(gt[2].T_W_C, seq.truth.camera[2].T_W_C), 1e-12);
  EXPECT_TRUE(same_image(
      cv::imread((root / "rgb" / "1.200000000.png").string(), cv::IMREAD_UNCHANGED), seq.left[2]));
  fs::remove_all(root);
}

TEST(DatasetReaders, NameTheFileLineAndExpectation) {
  const fs::path root = test::fresh_temp_dir("dataset_errors");
  Sequence{}.write(*make_writer(DatasetFormat::kKitti, root, calibration()));
  const fs::path calib = root / "sequences" / "00" / "calib.txt";
  std::ofstream(calib) << "P0: 1 2 3\nP1: 1 0 0 0 0 1 0 0 0 0 1 0\n";
  std::string e = driftlab::test::user_error_of([&] { read_dataset(root, DatasetFormat::kKitti); });
  EXPECT_NE(e.find(calib.string() + ":1: P0: got 3 numbers, expected 12"), std::string::npos) << e;
  std::ofstream(calib) << "P0: 1 0 0 0 0 1 0 0 0 0 1 0\nP1: 1 0 0 0 0 1 0 0 0 0 1 0\n";
  e = driftlab::test::user_error_of([&] { read_dataset(root, DatasetFormat::kKitti); });
  EXPECT_NE(e.find("not a rectified pair"), std::string::npos) << e;
  // A leading '+' reads as in a KITTI pose (the one number rule, core/number.hpp); "+-" does not.
  std::ofstream(calib) << "P0: +1 0 0 0 0 1 0 0 0 0 1 0\nP1: 1 0 0 -0.5 0 1 0 0 0 0 1 0\n";
  EXPECT_EQ(read_dataset(root, DatasetFormat::kKitti).rig.baseline_m, 0.5);
  std::ofstream(calib) << "P0: +-1 0 0 0 0 1 0 0 0 0 1 0\nP1: 1 0 0 -0.5 0 1 0 0 0 0 1 0\n";
  e = driftlab::test::user_error_of([&] { read_dataset(root, DatasetFormat::kKitti); });
  EXPECT_NE(e.find(":1: P0: got '+-1', expected a finite number"), std::string::npos) << e;
  e = driftlab::test::user_error_of([&] {
    read_dataset(root, DatasetFormat::kKitti,
                 {.sequence = "07", .gt_topic = {}, .calibration = {}});
  });
  EXPECT_NE(e.find("expected sequences/07/"), std::string::npos) << e;
  e = driftlab::test::user_error_of([&] { read_dataset(root / "nowhere", DatasetFormat::kEuroc); });
  EXPECT_NE(e.find("no such dataset folder"), std::string::npos) << e;
  e = driftlab::test::user_error_of([] { format_from_name("mcap"); });
  EXPECT_NE(e.find("got 'mcap', expected one of: kitti, euroc, tum-rgbd, rosbag, rosbag2"),
            std::string::npos);

  // EuRoC: a lens model other than radial-tangential or equidistant is refused, and so is a
  // pair with one of each; a bad stamp names its line.
  const fs::path eu = test::fresh_temp_dir("dataset_errors_euroc");
  Sequence{}.write(*make_writer(DatasetFormat::kEuroc, eu, calibration()));
  const fs::path cam1 = eu / "mav0" / "cam1" / "sensor.yaml";
  const std::string good_yaml = slurp(cam1);
  std::string yaml = good_yaml;
  yaml.replace(yaml.find("radial-tangential"), 17, "omni");
  std::ofstream(cam1) << yaml;
  e = driftlab::test::user_error_of([&] { read_dataset(eu, DatasetFormat::kEuroc); });
  EXPECT_NE(e.find("distortion_model: got 'omni' with 4 coefficients, expected "
                   "radial-tangential"),
            std::string::npos)
      << e;
  yaml = good_yaml;
  yaml.replace(yaml.find("radial-tangential"), 17, "equidistant");
  std::ofstream(cam1) << yaml;
  e = driftlab::test::user_error_of([&] { read_dataset(eu, DatasetFormat::kEuroc); });
  EXPECT_NE(e.find("distortion_model: got 'equidistant' and cam0's 'radial-tangential', expected "
                   "one model for both cameras"),
            std::string::npos)
      << e;
  // What the fuzzer found (fuzz/regressions/dataset): each a UserError naming the file.
  std::ofstream(cam1) << "just a scalar\n";
  e = driftlab::test::user_error_of([&] { read_dataset(eu, DatasetFormat::kEuroc); });
  EXPECT_NE(e.find(cam1.string() + ": expected a mapping of keys (intrinsics, resolution, T_BS)"),
            std::string::npos)
      << e;
  yaml = good_yaml;
  const std::size_t res = yaml.find("resolution: [");
  yaml.replace(res, yaml.find(']', res) - res, "resolution: [1e20, 60");
  std::ofstream(cam1) << yaml;
  e = driftlab::test::user_error_of([&] { read_dataset(eu, DatasetFormat::kEuroc); });
  EXPECT_NE(e.find("resolution: got 1e+20 x "), std::string::npos) << e;
  EXPECT_NE(e.find("expected whole numbers of pixels in [1, 16384]"), std::string::npos) << e;
  yaml = good_yaml;
  const std::size_t fu = yaml.find("intrinsics: [");
  yaml.replace(fu, yaml.find(',', fu) - fu, "intrinsics: [.nan");
  std::ofstream(cam1) << yaml;
  e = driftlab::test::user_error_of([&] { read_dataset(eu, DatasetFormat::kEuroc); });
  EXPECT_NE(e.find("intrinsics: got '.nan', expected a finite number"), std::string::npos) << e;
  std::ofstream(cam1) << slurp(eu / "mav0" / "cam0" / "sensor.yaml");  // cam1 where cam0 is
  e = driftlab::test::user_error_of([&] { read_dataset(eu, DatasetFormat::kEuroc); });
  EXPECT_NE(e.find("T_BS: cam1 sits where cam0 does, expected a stereo pair with a baseline"),
            std::string::npos)
      << e;
  std::ofstream(cam1) << good_yaml;
  // An IMU model without one of Kalibr's four noise parameters.
  const std::vector<ImuSample> imu = {{1'000'000'000, Vec3(0, 0, 0), Vec3(0, 0, -9.8)}};
  fs::create_directories(eu / "mav0" / "imu0");
  write_euroc_imu(eu / "mav0" / "imu0" / "data.csv", imu);
  std::ofstream(eu / "mav0" / "imu0" / "sensor.yaml") << "rate_hz: 200\n"
                                                         "gyroscope_noise_density: 1e-4\n"
                                                         "gyroscope_random_walk: -1\n";
  e = driftlab::test::user_error_of([&] { read_dataset(eu, DatasetFormat::kEuroc); });
  EXPECT_NE(e.find("sensor.yaml:3: gyroscope_random_walk: got '-1', expected a number > 0"),
            std::string::npos)
      << e;
  fs::remove_all(eu / "mav0" / "imu0");
  std::ofstream(eu / "mav0" / "cam0" / "data.csv") << "#timestamp [ns],filename\n12x,a.png\n";
  e = driftlab::test::user_error_of([&] { read_dataset(eu, DatasetFormat::kEuroc); });
  EXPECT_NE(e.find("data.csv:2: timestamp: got '12x'"), std::string::npos) << e;
  fs::remove_all(root);
  fs::remove_all(eu);
}

TEST(CompassCsv, ReadsHeadingsInDegreesAndNamesTheLineOfABadOne) {
  const fs::path dir = test::fresh_temp_dir("compass_csv");
  const fs::path csv = dir / "compass.csv";
  std::ofstream(csv) << "#timestamp [ns],heading [deg],m_S_x [nT],m_S_y [nT],m_S_z [nT]\n"
                        "100,90,1,2,3\n200,270,1,2,3\n";
  const auto r = read_compass_csv(csv);
  ASSERT_EQ(r.size(), 2u);
  EXPECT_EQ(r[0].t_ns, 100);
  EXPECT_NEAR(r[0].heading_rad, std::numbers::pi / 2, 1e-15);
  EXPECT_NEAR(r[1].heading_rad, -std::numbers::pi / 2, 1e-15);  // wrapped to (-pi, pi]
  std::ofstream(csv) << "100,90,1,2,3\n200,360,1,2,3\n";
  std::string e = driftlab::test::user_error_of([&] { read_compass_csv(csv); });
  EXPECT_NE(e.find(csv.string() + ":2: heading: got 360, expected degrees in [0, 360)"),
            std::string::npos)
      << e;
  std::ofstream(csv) << "100,90,1,2,3\n100,91,1,2,3\n";
  e = driftlab::test::user_error_of([&] { read_compass_csv(csv); });
  EXPECT_NE(e.find(":2: timestamp: got 100, expected more than the line before's 100"),
            std::string::npos)
      << e;
  std::ofstream(csv) << "100,90\n";
  e = driftlab::test::user_error_of([&] { read_compass_csv(csv); });
  EXPECT_NE(e.find(":1: got 2 columns, expected 5"), std::string::npos) << e;
  fs::remove_all(dir);
}

TEST(PoseAt, InterpolatesBetweenNeighboursAndNothingOutside) {
  const Trajectory t = {{0, SE3(Quat::Identity(), Vec3(0, 0, 0))},
                        {10, SE3(Quat::Identity(), Vec3(1, 2, 0))}};
  EXPECT_LT((pose_at(t, 5)->translation() - Vec3(0.5, 1, 0)).norm(), 1e-15);
  EXPECT_EQ(pose_at(t, 10)->translation(), Vec3(1, 2, 0));
  EXPECT_FALSE(pose_at(t, 11).has_value());
  EXPECT_FALSE(pose_at(t, -1).has_value());
}

}  // namespace
}  // namespace driftlab::dataset

namespace driftlab::dataset {
namespace {

// A raw EuRoC pair (lens distortion, the right camera turned by 1 deg): rectified as it is
// read. Each point's rectified pixels, followed through the maps back into the raw images,
// land where OpenCV's own distorted projection puts it, and the rectified rows agree.
using LensProjection =
    std::function<cv::Point2d(const Vec3&, const cv::Matx33d&, const std::vector<double>&)>;
void expect_the_maps_follow_the_lenses(const PinholeCamera& camera, const std::string& model,
                                       const std::vector<double>& D0, const std::vector<double>& D1,
                                       const LensProjection& project) {
  const fs::path root = test::fresh_temp_dir("euroc_raw");
  ExportCalibration cal = calibration();
  cal.rig.camera = camera;
  cal.rig.baseline_m = 0.11;
  Sequence seq;
  seq.left.assign(3, cv::Mat(camera.height, camera.width, CV_8UC1, cv::Scalar(0)));
  seq.right = seq.left;
  seq.write(*make_writer(DatasetFormat::kEuroc, root, cal));
  const SE3 T_B_C0 = cal.T_S_C;
  const SE3 T_C0_C1(quat_from_euler_zyx({0.0, 0.0, deg2rad(1.0)}), Vec3(0.11, 0.001, -0.002));
  const SE3 T_B_C1 = T_B_C0 * T_C0_C1;
  auto write_yaml = [&](int i, const SE3& T, const std::vector<double>& D) {
    const fs::path p = root / "mav0" / fmt::format("cam{}", i) / "sensor.yaml";
    std::string y = slurp(p);
    const auto data = y.find("  data: [");
    y.replace(data, y.find(']', data) - data + 1,
              "  data: [" + detail::matrix_text(detail::matrix_4x4(T), ", ") + "]");
    const auto dist = y.find("[0.0, 0.0, 0.0, 0.0]");
    y.replace(dist, 20, fmt::format("[{}, {}, {}, {}]", D[0], D[1], D[2], D[3]));
    y.replace(y.find("radial-tangential"), 17, model);
    std::ofstream(p) << y;
  };
  write_yaml(0, T_B_C0, D0);
  write_yaml(1, T_B_C1, D1);
  const StereoDataset d = read_dataset(root, DatasetFormat::kEuroc);
  ASSERT_TRUE(d.rectification);
  EXPECT_NEAR(d.rig.baseline_m, T_C0_C1.translation().norm(), 1e-9);
  cv::Mat lx, ly, rx, ry;
  cv::convertMaps(d.rectification->left_map1, d.rectification->left_map2, lx, ly, CV_32FC1);
  cv::convertMaps(d.rectification->right_map1, d.rectification->right_map2, rx, ry, CV_32FC1);
  const cv::Matx33d K(camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
  const double W = camera.width, H = camera.height;
  const SE3 T_Crect_C0 = d.T_S_C.inverse() * T_B_C0;
  std::size_t checked = 0;
  for (double x : {-2.0, -0.5, 0.0, 1.0, 2.5})
    for (double y : {-1.5, 0.0, 1.2})
      for (double z : {4.0, 9.0}) {
        const Vec3 X_c0(x, y, z);
        const Vec3 X_rect = T_Crect_C0 * X_c0;
        const Eigen::Vector2d l = d.rig.camera.project(X_rect);
        const Eigen::Vector2d r = d.rig.project_right(X_rect);
        if (l.x() < 5 || l.x() > W - 7 || l.y() < 5 || l.y() > H - 7 || r.x() < 5 || r.x() > W - 7)
          continue;
        // The maps take a rectified pixel to the raw one, interpolated bilinearly.
        const auto raw_of = [](const cv::Mat& mx, const cv::Mat& my, const Eigen::Vector2d& p) {
          cv::Mat sx, sy;
          const cv::Mat at(1, 1, CV_32FC2, cv::Scalar(p.x(), p.y()));
          cv::remap(mx, sx, at, cv::noArray(), cv::INTER_LINEAR);
          cv::remap(my, sy, at, cv::noArray(), cv::INTER_LINEAR);
          return cv::Point2d(sx.at<float>(0, 0), sy.at<float>(0, 0));
        };
        const cv::Point2d expected_l = project(X_c0, K, D0);
        const cv::Point2d expected_r = project(T_C0_C1.inverse() * X_c0, K, D1);
        EXPECT_LT(cv::norm(raw_of(lx, ly, l) - expected_l), 0.3) << model << " " << x << " " << y;
        EXPECT_LT(cv::norm(raw_of(rx, ry, r) - expected_r), 0.3) << model << " " << x << " " << y;
        EXPECT_NEAR(l.y(), r.y(), 1e-9);  // rectified: the same row
        ++checked;
      }
  EXPECT_GE(checked, 12u) << model;
  const auto [left, right] = read_pair(d, d.frames[0]);
  EXPECT_EQ(left.size(), cv::Size(camera.width, camera.height));
  EXPECT_EQ(right.type(), CV_8UC1);
  fs::remove_all(root);
}

TEST(EurocRaw, IsRectifiedWhenReadWithTheRigAndPosesOfTheRectifiedPair) {
  expect_the_maps_follow_the_lenses(
      {458.7, 457.3, 367.2, 248.4, 752, 480}, "radial-tangential",  // EuRoC-like
      {-0.28, 0.074, 0.0002, 0.00002}, {-0.283, 0.074, -0.0001, 0.0},
      [](const Vec3& X, const cv::Matx33d& K, const std::vector<double>& D) {
        std::vector<cv::Point2d> p;
        cv::projectPoints(std::vector<cv::Point3d>{{X.x(), X.y(), X.z()}}, cv::Vec3d(0, 0, 0),
                          cv::Vec3d(0, 0, 0), K, D, p);
        return p[0];
      });
}

// TUM-VI's cameras: equidistant (Kannala-Brandt) lenses of about 195 deg, rectified with
// OpenCV's fisheye model; the same check against cv::fisheye::projectPoints.
TEST(EurocRaw, EquidistantLensesAreRectifiedWithTheFisheyeModel) {
  expect_the_maps_follow_the_lenses(
      {190.98, 190.99, 254.93, 256.90, 512, 512}, "equidistant",  // TUM-VI-like
      {0.00348, 0.000715, -0.00205, 0.000203}, {0.00341, 0.00171, -0.00283, 0.000382},
      [](const Vec3& X, const cv::Matx33d& K, const std::vector<double>& D) {
        std::vector<cv::Point2d> p;
        cv::fisheye::projectPoints(std::vector<cv::Point3d>{{X.x(), X.y(), X.z()}}, p,
                                   cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, D);
        return p[0];
      });
}

}  // namespace
}  // namespace driftlab::dataset
