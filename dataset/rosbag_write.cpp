// The ROS 1 bag writer (rosbag.hpp has the topics and frames): Debian's rosbag_storage writes
// the bag; Kalibr's and VINS-Fusion's calibration files are written beside it.
#include <fmt/format.h>
#include <rosbag/bag.h>

#include <charconv>
#include <cmath>
#include <limits>

#include "core/atomic_file.hpp"
#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/trajectory_io.hpp"
#include "core/yaml_io.hpp"
#include "dataset/dataset_detail.hpp"
#include "dataset/ros_messages.hpp"
#include "dataset/rosbag.hpp"

namespace driftlab::dataset::detail {
namespace fs = std::filesystem;
namespace names = rosbag_names;
namespace {

ros::Time ros_time(TimeNs t_ns) {
  ros::Time t;
  t.fromNSec(static_cast<std::uint64_t>(t_ns));
  return t;
}

ros1::Header header(TimeNs t_ns, const char* frame, std::uint32_t seq) {
  ros1::Header h;
  h.seq = seq;
  h.stamp = ros_time(t_ns);
  h.frame_id = frame;
  return h;
}

ros1::Quaternion quaternion_msg(const Quat& q) {
  ros1::Quaternion m;
  m.w = q.w(), m.x = q.x(), m.y = q.y(), m.z = q.z();
  return m;
}

ros1::Vector3 vector3_msg(const Vec3& v) {
  ros1::Vector3 m;
  m.x = v.x(), m.y = v.y(), m.z = v.z();
  return m;
}

ros1::TransformStamped transform_msg(TimeNs t_ns, const char* parent, const char* child,
                                     const SE3& T_parent_child) {
  ros1::TransformStamped m;
  m.header = header(t_ns, parent, 0);
  m.child_frame_id = child;
  m.transform.translation = vector3_msg(T_parent_child.translation());
  m.transform.rotation = quaternion_msg(T_parent_child.quaternion());
  return m;
}

// base_link (REP 103: x forward, y left, z up) in driftlab's body frame (FRD).
const SE3& T_frd_flu() {
  static const SE3 T(Mat3(Vec3(1, -1, -1).asDiagonal()), Vec3::Zero());
  return T;
}

ros1::Image image_msg(const ros1::Header& h, const cv::Mat& gray) {
  if (gray.type() != CV_8UC1) throw InternalError("rosbag writer: expected 8-bit gray images");
  ros1::Image m;
  m.header = h;
  m.height = static_cast<std::uint32_t>(gray.rows);
  m.width = static_cast<std::uint32_t>(gray.cols);
  m.encoding = "mono8";
  m.is_bigendian = 0;
  m.step = m.width;
  m.data.resize(static_cast<std::size_t>(gray.rows) * gray.cols);
  for (int r = 0; r < gray.rows; ++r)
    std::copy_n(gray.ptr<std::uint8_t>(r), gray.cols, m.data.data() + std::size_t(r) * gray.cols);
  return m;
}

// The rectified pair's camera_info: no distortion, R the identity, P = K [I | (-B, 0, 0)].
ros1::CameraInfo camera_info_msg(const ros1::Header& h, const StereoRig& rig, int i) {
  const PinholeCamera& c = rig.camera;
  ros1::CameraInfo m;
  m.header = h;
  m.height = static_cast<std::uint32_t>(c.height);
  m.width = static_cast<std::uint32_t>(c.width);
  m.distortion_model = "plumb_bob";
  m.D.assign(5, 0.0);
  m.K = {c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1};
  m.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  m.P = {c.fx, 0, c.cx, i == 0 ? 0.0 : -c.fx * rig.baseline_m, 0, c.fy, c.cy, 0, 0, 0, 1, 0};
  return m;
}

// A number of a sensor CSV that may be "nan" (a GPS epoch without a fix).
double number_or_nan(std::string_view token, const fs::path& path, int line, const char* field) {
  if (token == "nan") return std::numeric_limits<double>::quiet_NaN();
  return parse_number(token, path, line, field);
}

std::string rosbag_info_yaml(const ExportCalibration& cal, std::size_t frames) {
  return fmt::format(
      "# driftlab export, a ROS 1 bag (format 2.0)\n"
      "format: rosbag\n"
      "source: \"{}\"\n"
      "frames: {}\n"
      "camera_rate_hz: {}\n"
      "frames_and_units: \"REP 103: base_link the vessel (x forward, y left, z up); imu and "
      "compass the sensors' axes; camN_optical x right, y down, z forward; world_ned the "
      "scenario's world (x north, y east, z down); stamps in ns of the sensors' clocks\"\n"
      "files:\n"
      "  {}: /cam0/image_raw, /cam1/image_raw (mono8, rectified, baseline {} m), "
      "/camN/camera_info, /imu0, /gps/fix, /mag, /compass/heading, /groundtruth/pose (imu in "
      "world_ned), /tf_static\n"
      "  {}: Kalibr's camera chain (OpenVINS, Basalt, Kimera; driftlab vo reads it)\n"
      "  {}: Kalibr's IMU noise model\n"
      "  vins_fusion/: VINS-Fusion's stereo + IMU configuration and camera files\n"
      "  scenario.resolved.yaml: the scenario that made this dataset\n",
      cal.source, frames, yaml::format_double(cal.camera_rate_hz), names::kBagFile,
      cal.rig.baseline_m, names::kCamchainFile, names::kImuChainFile);
}

class RosbagWriter final : public DatasetWriter {
 public:
  RosbagWriter(const fs::path& root, const ExportCalibration& cal)
      : root_(root), cal_(cal), T_C0_C1_(Mat3::Identity(), Vec3(cal.rig.baseline_m, 0, 0)) {
    try {
      bag_.open((root / names::kBagFile).string(), rosbag::bagmode::Write);
    } catch (const rosbag::BagException& e) {
      throw UserError(fmt::format("{}: cannot write the bag ({})",
                                  (root / names::kBagFile).string(), e.what()));
    }
  }
  void add_frame(TimeNs t, const cv::Mat& left, const cv::Mat& right, const cv::Mat&) override {
    if (first_ns_ < 0) first_ns_ = t;
    const cv::Mat* images[2] = {&left, &right};
    for (int i = 0; i < 2; ++i) {
      const ros1::Header h = header(t, names::kOpticalFrame[i], frames_);
      write(names::kImage[i], t, image_msg(h, *images[i]));
      write(names::kCameraInfo[i], t, camera_info_msg(h, cal_.rig, i));
    }
    ++frames_;
  }
  bool wants_depth() const override { return false; }
  void finish(const ExportTruth& truth) override;

 private:
  template <class Message>
  void write(const std::string& topic, TimeNs t_ns, const Message& m) {
    bag_.write(topic, ros_time(names::record_ns(t_ns)), m);
  }
  void write_tf_static(TimeNs t_ns);
  void write_imu(const fs::path& csv);
  void write_gps(const fs::path& csv);
  void write_compass(const fs::path& csv);
  void write_groundtruth(const std::vector<BodyState>& body);
  void write_calibration_files() const;

  fs::path root_;
  ExportCalibration cal_;
  SE3 T_C0_C1_;
  rosbag::Bag bag_;
  std::uint32_t frames_ = 0;
  TimeNs first_ns_ = -1;
};

void RosbagWriter::write_tf_static(TimeNs t_ns) {
  ros1::TFMessage m;
  const SE3 T_base_imu = T_frd_flu().inverse() * cal_.T_B_S;
  m.transforms.push_back(transform_msg(t_ns, names::kBaseFrame, names::kImuFrame, T_base_imu));
  if (cal_.p_B_gps)
    m.transforms.push_back(
        transform_msg(t_ns, names::kBaseFrame, "gps",
                      T_frd_flu().inverse() * SE3(Mat3::Identity(), *cal_.p_B_gps)));
  if (cal_.T_B_M)
    m.transforms.push_back(
        transform_msg(t_ns, names::kBaseFrame, "compass", T_frd_flu().inverse() * *cal_.T_B_M));
  m.transforms.push_back(
      transform_msg(t_ns, names::kImuFrame, names::kOpticalFrame[0], cal_.T_S_C));
  m.transforms.push_back(
      transform_msg(t_ns, names::kImuFrame, names::kOpticalFrame[1], cal_.T_S_C * T_C0_C1_));
  const auto connection = boost::make_shared<ros::M_string>();
  // With a connection header of its own, rosbag_storage writes it as given: the type fields
  // go in by hand.
  (*connection)["type"] = ros::message_traits::datatype(m);
  (*connection)["md5sum"] = ros::message_traits::md5sum(m);
  (*connection)["message_definition"] = ros::message_traits::definition(m);
  (*connection)["latching"] = "1";
  bag_.write(names::kTfStatic, ros_time(names::record_ns(t_ns)), m, connection);
}

void RosbagWriter::write_imu(const fs::path& csv) {
  // Discrete noise of one sample: density^2 times the rate (Kalibr's model).
  const double gyro_var = std::pow(cal_.imu.gyroscope_noise_density, 2) * cal_.imu.rate_hz;
  const double accel_var = std::pow(cal_.imu.accelerometer_noise_density, 2) * cal_.imu.rate_hz;
  std::uint32_t seq = 0;
  for (const ImuSample& s : read_euroc_imu(csv)) {
    ros1::Imu m;
    m.header = header(s.t_ns, names::kImuFrame, seq++);
    m.orientation_covariance[0] = -1;  // no orientation estimate
    m.angular_velocity = vector3_msg(s.gyro_rad_s);
    m.linear_acceleration = vector3_msg(s.accel_m_s2);
    for (int i = 0; i < 3; ++i) {
      m.angular_velocity_covariance[4 * i] = gyro_var;
      m.linear_acceleration_covariance[4 * i] = accel_var;
    }
    write(names::kImu, s.t_ns, m);
  }
}

// gps.csv (sim/sensors/gps.hpp): timestamp, fix, satellites, hdop, north, east, down, latitude,
// longitude, height. The covariance is approximated from HDOP: each horizontal axis
// (sigma HDOP)^2 / 2, the vertical (1.5 sigma HDOP)^2 (VDOP is typically 1.5 HDOP).
void RosbagWriter::write_gps(const fs::path& csv) {
  std::uint32_t seq = 0;
  for (const TextLine& line : data_lines(csv, "GPS CSV")) {
    const std::vector<std::string> c = split_csv_line(line.text);
    if (c.size() != 10)
      throw UserError(
          fmt::format("{}:{}: got {} columns, expected 10", csv.string(), line.number, c.size()));
    const TimeNs t = parse_stamp_ns(c[0], csv, line.number);
    ros1::NavSatFix m;
    m.header = header(t, "gps", seq++);
    const bool fix = parse_number(c[1], csv, line.number, "fix") == 1;
    m.status.status = fix ? ros1::NavSatStatus::STATUS_FIX : ros1::NavSatStatus::STATUS_NO_FIX;
    m.status.service = ros1::NavSatStatus::SERVICE_GPS;
    m.latitude = number_or_nan(c[7], csv, line.number, "latitude");
    m.longitude = number_or_nan(c[8], csv, line.number, "longitude");
    m.altitude = number_or_nan(c[9], csv, line.number, "height");
    const double h = cal_.gps_sigma_horizontal_m * number_or_nan(c[3], csv, line.number, "hdop");
    if (fix && std::isfinite(h)) {
      m.position_covariance[0] = m.position_covariance[4] = h * h / 2;
      m.position_covariance[8] = 2.25 * h * h;
      m.position_covariance_type = ros1::NavSatFix::COVARIANCE_TYPE_APPROXIMATED;
    } else {
      m.position_covariance_type = ros1::NavSatFix::COVARIANCE_TYPE_UNKNOWN;
    }
    write(names::kGps, t, m);
  }
}

void RosbagWriter::write_compass(const fs::path& csv) {
  std::uint32_t seq = 0;
  for (const CompassReading& r : read_compass_csv(csv)) {
    ros1::MagneticField field;
    field.header = header(r.t_ns, "compass", seq);
    field.magnetic_field = vector3_msg(r.field_S_nt * 1e-9);  // nT -> T
    write(names::kMag, r.t_ns, field);
    ros1::QuaternionStamped heading;
    heading.header = header(r.t_ns, names::kWorldFrame, seq++);
    heading.quaternion = quaternion_msg(Quat(Eigen::AngleAxisd(r.heading_rad, Vec3::UnitZ())));
    write(names::kHeading, r.t_ns, heading);
  }
}

void RosbagWriter::write_groundtruth(const std::vector<BodyState>& body) {
  std::uint32_t seq = 0;
  for (const BodyState& b : body) {
    ros1::PoseStamped m;
    m.header = header(b.t_ns, names::kWorldFrame, seq++);
    m.pose.position.x = b.T_W_S.translation().x();
    m.pose.position.y = b.T_W_S.translation().y();
    m.pose.position.z = b.T_W_S.translation().z();
    m.pose.orientation = quaternion_msg(b.T_W_S.quaternion());
    write(names::kGroundTruth, b.t_ns, m);
  }
}

void RosbagWriter::finish(const ExportTruth& truth) {
  try {
    write_tf_static(first_ns_ < 0 ? 0 : first_ns_);
    for (const fs::path& csv : truth.sensor_csvs) {
      const std::string stem = csv.stem().string();
      if (stem == "imu") write_imu(csv);
      if (stem == "gps") write_gps(csv);
      if (stem == "compass") write_compass(csv);
      fs::remove(csv);
    }
    write_groundtruth(truth.body);
    bag_.close();
  } catch (const rosbag::BagException& e) {
    throw UserError(
        fmt::format("{}: cannot write the bag ({})", (root_ / names::kBagFile).string(), e.what()));
  }
  write_calibration_files();
}

void RosbagWriter::write_calibration_files() const {
  write_file_atomic(root_ / names::kCamchainFile, kalibr_imucam_chain_yaml(cal_));
  if (cal_.imu.rate_hz > 0) {
    write_file_atomic(root_ / names::kImuChainFile, kalibr_imu_chain_yaml(cal_.imu));
    fs::create_directories(root_ / "vins_fusion");
    for (const auto& [name, text] : vins_fusion_files(cal_))
      write_file_atomic(root_ / "vins_fusion" / name, text);
  }
  write_file_atomic(root_ / "info.yaml", rosbag_info_yaml(cal_, frames_));
}

}  // namespace

std::unique_ptr<DatasetWriter> make_rosbag_writer(const fs::path& root,
                                                  const ExportCalibration& calibration) {
  return std::make_unique<RosbagWriter>(root, calibration);
}

}  // namespace driftlab::dataset::detail
