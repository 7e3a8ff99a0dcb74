// EuRoC/ASL layout (Burri et al., "The EuRoC micro aerial vehicle datasets", IJRR 2016; the
// ASL dataset format): writer and reader.
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <limits>

#include <opencv2/calib3d.hpp>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/file_io.hpp"
#include "core/yaml_io.hpp"
#include "dataset/dataset_detail.hpp"

namespace driftlab::dataset::detail {
namespace fs = std::filesystem;
namespace {

std::string t_bs_yaml(const SE3& T_B_S) {
  return fmt::format("T_BS:\n  cols: 4\n  rows: 4\n  data: [{}]\n",
                     matrix_text(matrix_4x4(T_B_S), ", "));
}

std::string camera_yaml(const ExportCalibration& cal, int index, const SE3& T_S_C) {
  const PinholeCamera& c = cal.rig.camera;
  return fmt::format(
      "# General sensor definitions.\n"
      "sensor_type: camera\n"
      "comment: driftlab cam{} ({} camera of the rectified stereo pair)\n"
      "# Sensor extrinsics wrt. the body-frame.\n{}"
      "# Camera specific definitions.\n"
      "rate_hz: {}\n"
      "resolution: [{}, {}]\n"
      "camera_model: pinhole\n"
      "intrinsics: [{}, {}, {}, {}] #fu, fv, cu, cv\n"
      "distortion_model: radial-tangential\n"
      "distortion_coefficients: [0.0, 0.0, 0.0, 0.0]\n",
      index, index == 0 ? "left" : "right", t_bs_yaml(T_S_C),
      yaml::format_double(cal.camera_rate_hz), c.width, c.height, yaml::format_double(c.fx),
      yaml::format_double(c.fy), yaml::format_double(c.cx), yaml::format_double(c.cy));
}

std::string imu_yaml(const ImuNoiseModel& m) {
  return fmt::format(
      "# General sensor definitions.\n"
      "sensor_type: imu\n"
      "comment: driftlab imu0 (the scenario's sensors.imu)\n"
      "# Sensor extrinsics wrt. the body-frame.\n{}"
      "rate_hz: {}\n"
      "# inertial sensor noise model parameters (static)\n"
      "gyroscope_noise_density: {}     # [ rad / s / sqrt(Hz) ]   ( gyro \"white noise\" )\n"
      "gyroscope_random_walk: {}       # [ rad / s^2 / sqrt(Hz) ] ( gyro bias diffusion )\n"
      "accelerometer_noise_density: {} # [ m / s^2 / sqrt(Hz) ]   ( accel \"white noise\" )\n"
      "accelerometer_random_walk: {}   # [ m / s^3 / sqrt(Hz) ].  ( accel bias diffusion )\n",
      t_bs_yaml(SE3()), yaml::format_double(m.rate_hz),
      yaml::format_double(m.gyroscope_noise_density), yaml::format_double(m.gyroscope_random_walk),
      yaml::format_double(m.accelerometer_noise_density),
      yaml::format_double(m.accelerometer_random_walk));
}

std::string euroc_info_yaml(const ExportCalibration& cal, std::size_t frames) {
  return fmt::format(
      "# driftlab export, EuRoC/ASL layout\n"
      "format: euroc\n"
      "source: \"{}\"\n"
      "frames: {}\n"
      "camera_rate_hz: {}\n"
      "frames_and_units: \"body frame B = the IMU's (imu0 T_BS is the identity); world R = the "
      "scenario's NED frame (x north, y east, z down: gravity is +z); cameras x right, y down, z "
      "forward; time stamps in ns of the sensors' clocks\"\n"
      "files:\n"
      "  mav0/cam0/data/<t_ns>.png: left image, 8-bit gray, rectified (distortion zero)\n"
      "  mav0/cam1/data/<t_ns>.png: right image of the same pair, baseline {} m\n"
      "  mav0/camN/data.csv: '#timestamp [ns],filename'\n"
      "  mav0/camN/sensor.yaml: intrinsics fu fv cu cv, resolution, T_BS = camera in the body "
      "frame (4x4 row-major)\n"
      "  mav0/imu0/data.csv: angular rate [rad/s] and specific force [m/s^2] in the IMU frame\n"
      "  mav0/imu0/sensor.yaml: the IMU's Kalibr noise model\n"
      "  mav0/state_groundtruth_estimate0/data.csv: true body pose in the world (p_RS_R, "
      "q_RS), velocity v_RS_R and the simulated IMU's biases b_w_RS_S, b_a_RS_S, at most "
      "200 Hz\n"
      "  mav0/gps0/data.csv, mav0/compass0/data.csv: driftlab's own GPS and compass CSVs\n"
      "  basalt_calib.json: Basalt's camera calibration (basalt_vio --cam-calib)\n"
      "  orbslam3_stereo.yaml, orbslam3_stereo_inertial.yaml: ORB-SLAM3's settings (the second "
      "with an IMU)\n"
      "  orbslam3_times.txt: ORB-SLAM3's times file, one image stamp [ns] a line\n"
      "  scenario.resolved.yaml: the scenario that made this dataset\n",
      cal.source, frames, yaml::format_double(cal.camera_rate_hz), cal.rig.baseline_m);
}

class EurocWriter final : public DatasetWriter {
 public:
  EurocWriter(const fs::path& root, const ExportCalibration& cal)
      : root_(root), mav_(root / "mav0"), cal_(cal) {
    fs::create_directories(mav_ / "cam0" / "data");
    fs::create_directories(mav_ / "cam1" / "data");
    index_ = "#timestamp [ns],filename\n";
  }
  void add_frame(TimeNs t, const cv::Mat& left, const cv::Mat& right, const cv::Mat&) override {
    const std::string name = fmt::format("{}.png", t);
    write_png(mav_ / "cam0" / "data" / name, left);
    write_png(mav_ / "cam1" / "data" / name, right);
    index_ += fmt::format("{},{}\n", t, name);
    stamps_.push_back(t);
    ++frames_;
  }
  bool wants_depth() const override { return false; }
  void finish(const ExportTruth& truth) override {
    const SE3 T_C0_C1(Mat3::Identity(), Vec3(cal_.rig.baseline_m, 0, 0));
    for (int i = 0; i < 2; ++i) {
      const fs::path cam = mav_ / fmt::format("cam{}", i);
      write_file_atomic(cam / "data.csv", index_);
      write_file_atomic(cam / "sensor.yaml",
                        camera_yaml(cal_, i, i == 0 ? cal_.T_S_C : cal_.T_S_C * T_C0_C1));
    }
    Trajectory body;
    std::vector<Vec3> velocities;
    std::vector<ImuBias> biases;  // only when every state has one
    const bool with_bias = std::all_of(truth.body.begin(), truth.body.end(),
                                       [](const BodyState& b) { return b.bias.has_value(); });
    for (const BodyState& b : truth.body) {
      body.push_back({b.t_ns, b.T_W_S});
      velocities.push_back(b.v_W);
      if (with_bias) biases.push_back(*b.bias);
    }
    fs::create_directories(mav_ / "state_groundtruth_estimate0");
    write_euroc_groundtruth(mav_ / "state_groundtruth_estimate0" / "data.csv", body, velocities,
                            biases);
    for (const auto& csv : truth.sensor_csvs)
      move_file(csv, mav_ / (csv.stem().string() + "0") / "data.csv");
    const bool imu = fs::exists(mav_ / "imu0" / "data.csv");
    if (imu) write_file_atomic(mav_ / "imu0" / "sensor.yaml", imu_yaml(cal_.imu));
    write_peer_settings(imu);
    write_file_atomic(root_ / "info.yaml", euroc_info_yaml(cal_, frames_));
  }

 private:
  // What Basalt and ORB-SLAM3 read beside the folder (docs/datasets.md, "Peers on the twin").
  void write_peer_settings(bool imu) const {
    ExportCalibration cal = cal_;
    if (!imu) cal.imu = {};
    write_file_atomic(root_ / "basalt_calib.json", basalt_calibration_json(cal));
    write_file_atomic(root_ / "orbslam3_stereo.yaml", orbslam3_settings_yaml(cal, false));
    if (imu)
      write_file_atomic(root_ / "orbslam3_stereo_inertial.yaml", orbslam3_settings_yaml(cal, true));
    write_file_atomic(root_ / "orbslam3_times.txt", orbslam3_times(stamps_));
  }

  fs::path root_, mav_;
  ExportCalibration cal_;
  std::string index_;
  std::vector<TimeNs> stamps_;
  std::size_t frames_ = 0;
};

// --- Reading.

using CameraYaml = CameraCalibration;

}  // namespace

std::vector<double> yaml_numbers(const YAML::Node& root, const char* key, std::size_t count,
                                 const fs::path& path, std::string_view prefix) {
  const YAML::Node node = root.IsMap() ? root[key] : YAML::Node();
  if (!node || !node.IsSequence() || (count && node.size() != count))
    throw UserError(fmt::format("{}: {}{}: expected a list of {} numbers", path.string(), prefix,
                                key, count ? std::to_string(count) : "some"));
  std::vector<double> out;
  for (const auto& v : node) {
    double x = std::numeric_limits<double>::quiet_NaN();
    if (v.IsScalar()) yaml::parse_double(v.Scalar(), &x);
    if (!std::isfinite(x))
      throw UserError(fmt::format("{}:{}: {}{}: got '{}', expected a finite number", path.string(),
                                  v.Mark().line + 1, prefix, key,
                                  v.IsScalar() ? v.Scalar() : "a list"));
    out.push_back(x);
  }
  return out;
}

CameraCalibration camera_from_keys(const YAML::Node& root, const fs::path& path,
                                   std::string_view prefix) {
  CameraCalibration c;
  const auto k = yaml_numbers(root, "intrinsics", 4, path, prefix);
  const auto res = yaml_numbers(root, "resolution", 2, path, prefix);
  if (!(k[0] > 0 && k[1] > 0))
    throw UserError(fmt::format("{}: {}intrinsics: got fu {} and fv {}, expected both > 0",
                                path.string(), prefix, k[0], k[1]));
  for (double r : res)
    if (!(r >= 1 && r <= 16384 && r == std::floor(r)))
      throw UserError(fmt::format(
          "{}: {}resolution: got {} x {}, expected whole numbers of pixels in [1, 16384]",
          path.string(), prefix, res[0], res[1]));
  c.camera = {k[0], k[1], k[2], k[3], static_cast<int>(res[0]), static_cast<int>(res[1])};
  if (root["distortion_coefficients"])
    c.distortion = yaml_numbers(root, "distortion_coefficients", 0, path, prefix);
  if (root["distortion_model"])
    c.distortion_model =
        root["distortion_model"].IsScalar() ? root["distortion_model"].Scalar() : "(not a name)";
  const bool radtan = c.distortion_model.empty() || c.distortion_model == "radial-tangential" ||
                      c.distortion_model == "radtan" || c.distortion_model == "plumb_bob";
  const std::size_t n = c.distortion.size();
  if (c.distortion_model == "equidistant" && n == 4) return c;  // Kannala-Brandt k1..k4
  if (!radtan || (n != 0 && n != 4 && n != 5))
    throw UserError(fmt::format(
        "{}: {}distortion_model: got '{}' with {} coefficients, expected radial-tangential with 4 "
        "(k1, k2, p1, p2) or 5, or equidistant with 4 (k1..k4)",
        path.string(), prefix, c.distortion_model, n));
  return c;
}

ImuNoiseModel imu_noise_from_keys(const YAML::Node& root, const fs::path& path,
                                  std::string_view prefix) {
  const auto number = [&](const char* key) {
    const YAML::Node n = root.IsMap() ? root[key] : YAML::Node();
    double x = std::numeric_limits<double>::quiet_NaN();
    if (n && n.IsScalar()) yaml::parse_double(n.Scalar(), &x);
    if (!(std::isfinite(x) && x > 0))
      throw UserError(fmt::format("{}{}: {}{}: got '{}', expected a number > 0", path.string(),
                                  n ? fmt::format(":{}", n.Mark().line + 1) : "", prefix, key,
                                  n && n.IsScalar() ? n.Scalar() : "nothing"));
    return x;
  };
  return {number("rate_hz"), number("gyroscope_noise_density"), number("gyroscope_random_walk"),
          number("accelerometer_noise_density"), number("accelerometer_random_walk")};
}

namespace {

// EuRoC's camera keys (Kalibr's names): intrinsics (fu, fv, cu, cv), resolution, distortion,
// T_BS.
CameraYaml camera_from_yaml(const YAML::Node& root, const fs::path& path) {
  if (!root.IsMap())
    throw UserError(path.string() + ": expected a mapping of keys (intrinsics, resolution, T_BS)");
  CameraYaml c = camera_from_keys(root, path, "");
  const auto t = yaml_numbers(root["T_BS"] ? root["T_BS"] : YAML::Node(), "data", 16, path);
  Mat3 R;
  R << t[0], t[1], t[2], t[4], t[5], t[6], t[8], t[9], t[10];
  const Eigen::JacobiSVD<Mat3> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  if ((R.transpose() * R - Mat3::Identity()).cwiseAbs().maxCoeff() > 1e-3 || R.determinant() < 0)
    throw UserError(path.string() + ": T_BS: the rotation part is not a rotation");
  c.T_B_C = SE3(Quat(Mat3(svd.matrixU() * svd.matrixV().transpose())), Vec3(t[3], t[7], t[11]));
  return c;
}

// Kalibr's IMU keys (imu0/sensor.yaml): rate_hz and the four noise parameters.
ImuNoiseModel read_imu_yaml(const fs::path& path) {
  const std::string text = read_text_file(path, "EuRoC sensor.yaml");
  try {
    return imu_noise_from_keys(YAML::Load(text), path, "");
  } catch (const YAML::Exception& e) {
    throw UserError(fmt::format("{}:{}: {}", path.string(), e.mark.line + 1, e.msg));
  }
}

CameraYaml read_camera_yaml(const fs::path& path) {
  const std::string text = read_text_file(path, "EuRoC sensor.yaml");
  try {
    return camera_from_yaml(YAML::Load(text), path);
  } catch (const YAML::Exception& e) {
    throw UserError(fmt::format("{}:{}: {}", path.string(), e.mark.line + 1, e.msg));
  }
}

std::vector<std::pair<TimeNs, std::string>> read_camera_index(const fs::path& path) {
  std::vector<std::pair<TimeNs, std::string>> out;
  for (const TextLine& line : data_lines(path, "EuRoC camera data.csv")) {
    const auto comma = line.text.find(',');
    if (comma == std::string::npos)
      throw UserError(fmt::format("{}:{}: got '{}', expected 'timestamp,filename'", path.string(),
                                  line.number, line.text.substr(0, 80)));
    std::string file = line.text.substr(comma + 1);
    while (!file.empty() && file.front() == ' ') file.erase(0, 1);
    out.emplace_back(parse_stamp_ns(line.text.substr(0, comma), path, line.number), file);
    if (out.size() > 1 && out.back().first <= out[out.size() - 2].first)
      throw UserError(
          fmt::format("{}:{}: timestamp: got {}, expected more than the line "
                      "before's {}",
                      path.string(), line.number, out.back().first, out[out.size() - 2].first));
  }
  return out;
}

bool is_fisheye(const CameraYaml& c) { return c.distortion_model == "equidistant"; }

// Whether the pair is already what the VOs take: equal pinholes, no distortion, the right
// camera moved along the left one's x axis only.
bool already_rectified(const CameraYaml& c0, const CameraYaml& c1) {
  const SE3 T_C0_C1 = c0.T_B_C.inverse() * c1.T_B_C;
  const double baseline = T_C0_C1.translation().x();
  bool rectified = baseline > 0 && std::abs(T_C0_C1.translation().y()) < 1e-6 * baseline &&
                   std::abs(T_C0_C1.translation().z()) < 1e-6 * baseline &&
                   (T_C0_C1.rotation() - Mat3::Identity()).cwiseAbs().maxCoeff() < 1e-9;
  for (const auto* c : {&c0, &c1}) {
    rectified = rectified && !is_fisheye(*c);  // r = f theta, not f tan theta, even at k = 0
    for (double d : c->distortion) rectified = rectified && d == 0;
  }
  const PinholeCamera &a = c0.camera, &b = c1.camera;
  return rectified && a.fx == b.fx && a.fy == b.fy && a.cx == b.cx && a.cy == b.cy &&
         a.width == b.width && a.height == b.height;
}

cv::Matx33d camera_matrix(const PinholeCamera& c) {
  return {c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1};
}

}  // namespace

RectifiedPair rectify_pair(const CameraYaml& c0, const CameraYaml& c1, const fs::path& cam1_yaml) {
  RectifiedPair out;
  if (!((c0.T_B_C.inverse() * c1.T_B_C).translation().norm() > 0))
    throw UserError(
        fmt::format("{}: T_BS: cam1 sits where cam0 does, expected a stereo pair with a baseline",
                    cam1_yaml.string()));
  if (already_rectified(c0, c1)) {
    out.rig.camera = c0.camera;
    out.rig.baseline_m = (c0.T_B_C.inverse() * c1.T_B_C).translation().x();
    return out;
  }
  const cv::Size size(c0.camera.width, c0.camera.height);
  if (c1.camera.width != size.width || c1.camera.height != size.height)
    throw UserError(fmt::format("{}: resolution: got {}x{}, expected cam0's {}x{}",
                                cam1_yaml.string(), c1.camera.width, c1.camera.height, size.width,
                                size.height));
  // x_c1 = R x_c0 + T, OpenCV's convention for the pair.
  const SE3 T_C1_C0 = c1.T_B_C.inverse() * c0.T_B_C;
  cv::Matx33d R;
  const Mat3 Re = T_C1_C0.rotation();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) R(i, j) = Re(i, j);
  const Vec3 te = T_C1_C0.translation();
  const cv::Vec3d T(te.x(), te.y(), te.z());
  if (is_fisheye(c0) != is_fisheye(c1))
    throw UserError(
        fmt::format("{}: distortion_model: got '{}' and cam0's '{}', expected one "
                    "model for both cameras",
                    cam1_yaml.string(), c1.distortion_model, c0.distortion_model));
  const bool fisheye = is_fisheye(c0);
  cv::Mat R1, R2, P1, P2, Q;
  if (fisheye)  // equidistant lenses: OpenCV's fisheye model (Kannala-Brandt), balance 0
    cv::fisheye::stereoRectify(camera_matrix(c0.camera), c0.distortion, camera_matrix(c1.camera),
                               c1.distortion, size, R, T, R1, R2, P1, P2, Q,
                               cv::CALIB_ZERO_DISPARITY, size, 0.0, 1.0);
  else
    cv::stereoRectify(camera_matrix(c0.camera), c0.distortion, camera_matrix(c1.camera),
                      c1.distortion, size, R, T, R1, R2, P1, P2, Q, cv::CALIB_ZERO_DISPARITY, 0,
                      size);
  const double baseline = -P2.at<double>(0, 3) / P2.at<double>(0, 0);
  if (!(baseline > 0))
    throw UserError(
        fmt::format("{}: T_BS: cam1 is not to the right of cam0 (rectified "
                    "baseline {} m), expected the right camera as cam1",
                    cam1_yaml.string(), baseline));
  auto maps = std::make_shared<Rectification>();
  const auto map = [&](const CameraYaml& c, const cv::Mat& Ri, const cv::Mat& Pi, cv::Mat* m1,
                       cv::Mat* m2) {
    if (fisheye)
      cv::fisheye::initUndistortRectifyMap(camera_matrix(c.camera), c.distortion, Ri, Pi, size,
                                           CV_16SC2, *m1, *m2);
    else
      cv::initUndistortRectifyMap(camera_matrix(c.camera), c.distortion, Ri, Pi, size, CV_16SC2,
                                  *m1, *m2);
  };
  map(c0, R1, P1, &maps->left_map1, &maps->left_map2);
  map(c1, R2, P2, &maps->right_map1, &maps->right_map2);
  out.rectification = maps;
  out.rig.camera = {P1.at<double>(0, 0), P1.at<double>(1, 1), P1.at<double>(0, 2),
                    P1.at<double>(1, 2), size.width,          size.height};
  out.rig.baseline_m = baseline;
  Mat3 R1e;  // x_rect = R1 x_c0
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) R1e(i, j) = R1.at<double>(i, j);
  out.T_C0_Crect = SE3(Mat3(R1e.transpose()), Vec3::Zero());
  return out;
}

std::unique_ptr<DatasetWriter> make_euroc_writer(const fs::path& root,
                                                 const ExportCalibration& calibration) {
  return std::make_unique<EurocWriter>(root, calibration);
}

StereoDataset read_euroc(const fs::path& root) {
  const fs::path mav = fs::is_directory(root / "mav0") ? root / "mav0" : root;
  StereoDataset d;
  d.format = DatasetFormat::kEuroc;
  d.root = root;
  const CameraYaml c0 = read_camera_yaml(mav / "cam0" / "sensor.yaml");
  const CameraYaml c1 = read_camera_yaml(mav / "cam1" / "sensor.yaml");
  RectifiedPair pair;
  try {
    pair = rectify_pair(c0, c1, mav / "cam1" / "sensor.yaml");
  } catch (const cv::Exception& e) {  // a calibration OpenCV cannot rectify
    throw UserError(fmt::format("{}: the pair cannot be rectified ({}), expected a stereo pair",
                                (mav / "cam1" / "sensor.yaml").string(), e.err));
  }
  d.rig = pair.rig;
  d.rectification = pair.rectification;
  d.T_S_C = c0.T_B_C * pair.T_C0_Crect;
  const auto left = read_camera_index(mav / "cam0" / "data.csv");
  const auto right = read_camera_index(mav / "cam1" / "data.csv");
  std::size_t j = 0;  // pairs: the stamps both cameras have
  for (const auto& [t, file] : left) {
    while (j < right.size() && right[j].first < t) ++j;
    if (j < right.size() && right[j].first == t)
      d.frames.push_back(
          {t, mav / "cam0" / "data" / file, mav / "cam1" / "data" / right[j].second});
  }
  if (d.frames.empty())
    throw UserError(
        fmt::format("{}: no time stamp in both cam0/data.csv and cam1/data.csv", mav.string()));
  const fs::path gt = mav / "state_groundtruth_estimate0" / "data.csv";
  if (fs::exists(gt))
    for (const StampedPose& p : read_euroc_groundtruth(gt))
      d.camera_gt.push_back({p.t_ns, p.T_W_C * d.T_S_C});
  d.has_extrinsics = true;
  if (fs::exists(mav / "imu0" / "data.csv")) {
    d.imu = read_euroc_imu(mav / "imu0" / "data.csv");
    if (fs::exists(mav / "imu0" / "sensor.yaml"))
      d.imu_noise = read_imu_yaml(mav / "imu0" / "sensor.yaml");
  }
  if (fs::exists(mav / "compass0" / "data.csv"))
    d.compass = read_compass_csv(mav / "compass0" / "data.csv");
  return d;
}

}  // namespace driftlab::dataset::detail
