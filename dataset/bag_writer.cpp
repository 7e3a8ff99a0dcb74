// The bag writers' shared part (bag_writer.hpp).
#include "dataset/bag_writer.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>

#include "core/atomic_file.hpp"
#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/trajectory_io.hpp"
#include "core/yaml_io.hpp"
#include "dataset/dataset_detail.hpp"
#include "dataset/rosbag.hpp"

namespace driftlab::dataset::detail {
namespace fs = std::filesystem;
namespace names = rosbag_names;
namespace {

// base_link (REP 103: x forward, y left, z up) in driftlab's body frame (FRD).
SE3 T_frd_flu() { return SE3(Mat3(Vec3(1, -1, -1).asDiagonal()), Vec3::Zero()); }

// A number of a sensor CSV that may be "nan" (a GPS epoch without a fix).
double number_or_nan(std::string_view token, const fs::path& path, int line, const char* field) {
  if (token == "nan") return std::numeric_limits<double>::quiet_NaN();
  return parse_number(token, path, line, field);
}

std::string bag_info_yaml(const ExportCalibration& cal, std::size_t frames,
                          const std::string& format, const std::string& bag_files) {
  return fmt::format(
      "# driftlab export, {}\n"
      "format: {}\n"
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
      "  {}: Kalibr's camera chain (OpenVINS, Kimera; driftlab vo reads it)\n"
      "  {}: Kalibr's IMU noise model\n"
      "  estimator_config.yaml: OpenVINS's estimator configuration (with an IMU)\n"
      "  vins_fusion/: VINS-Fusion's stereo + IMU configuration and camera files\n"
      "  scenario.resolved.yaml: the scenario that made this dataset\n",
      format == "rosbag" ? "a ROS 1 bag (format 2.0)" : "a ROS 2 bag (sqlite3, CDR)", format,
      cal.source, frames, yaml::format_double(cal.camera_rate_hz), bag_files, cal.rig.baseline_m,
      names::kCamchainFile, names::kImuChainFile);
}

class BagWriter final : public DatasetWriter {
 public:
  BagWriter(const fs::path& root, const ExportCalibration& cal, std::unique_ptr<BagSink> sink,
            std::string format, std::string bag_files)
      : root_(root),
        cal_(cal),
        sink_(std::move(sink)),
        format_(std::move(format)),
        bag_files_(std::move(bag_files)) {}
  void add_frame(TimeNs t, const cv::Mat& left, const cv::Mat& right, const cv::Mat&) override {
    if (first_ns_ < 0) first_ns_ = t;
    const cv::Mat* images[2] = {&left, &right};
    for (int i = 0; i < 2; ++i) {
      sink_->image(i, t, frames_, *images[i]);
      sink_->camera_info(i, t, frames_, cal_.rig);
    }
    ++frames_;
  }
  bool wants_depth() const override { return false; }
  void finish(const ExportTruth& truth) override;

 private:
  std::vector<TransformRecord> transforms() const;
  void write_imu(const fs::path& csv);
  void write_gps(const fs::path& csv);
  void write_calibration_files() const;

  fs::path root_;
  ExportCalibration cal_;
  std::unique_ptr<BagSink> sink_;
  std::string format_, bag_files_;
  std::uint32_t frames_ = 0;
  TimeNs first_ns_ = -1;
};

std::vector<TransformRecord> BagWriter::transforms() const {
  const SE3 T_flu_frd = T_frd_flu().inverse();
  std::vector<TransformRecord> out;
  out.push_back({names::kBaseFrame, names::kImuFrame, T_flu_frd * cal_.T_B_S});
  if (cal_.p_B_gps)
    out.push_back({names::kBaseFrame, "gps", T_flu_frd * SE3(Mat3::Identity(), *cal_.p_B_gps)});
  if (cal_.T_B_M) out.push_back({names::kBaseFrame, "compass", T_flu_frd * *cal_.T_B_M});
  const SE3 T_C0_C1(Mat3::Identity(), Vec3(cal_.rig.baseline_m, 0, 0));
  out.push_back({names::kImuFrame, names::kOpticalFrame[0], cal_.T_S_C});
  out.push_back({names::kImuFrame, names::kOpticalFrame[1], cal_.T_S_C * T_C0_C1});
  return out;
}

void BagWriter::write_imu(const fs::path& csv) {
  // Discrete noise of one sample: density^2 times the rate (Kalibr's model).
  const double gyro_var = std::pow(cal_.imu.gyroscope_noise_density, 2) * cal_.imu.rate_hz;
  const double accel_var = std::pow(cal_.imu.accelerometer_noise_density, 2) * cal_.imu.rate_hz;
  std::uint32_t seq = 0;
  for (const ImuSample& s : read_euroc_imu(csv)) sink_->imu(s, seq++, gyro_var, accel_var);
}

// gps.csv (sim/sensors/gps.hpp): timestamp, fix, satellites, hdop, north, east, down, latitude,
// longitude, height. The covariance is approximated from HDOP: each horizontal axis
// (sigma HDOP)^2 / 2, the vertical (1.5 sigma HDOP)^2 (VDOP is typically 1.5 HDOP).
void BagWriter::write_gps(const fs::path& csv) {
  std::uint32_t seq = 0;
  for (const TextLine& line : data_lines(csv, "GPS CSV")) {
    const std::vector<std::string> c = split_csv_line(line.text);
    if (c.size() != 10)
      throw UserError(
          fmt::format("{}:{}: got {} columns, expected 10", csv.string(), line.number, c.size()));
    GpsRecord g;
    g.t_ns = parse_stamp_ns(c[0], csv, line.number);
    g.fix = parse_number(c[1], csv, line.number, "fix") == 1;
    g.latitude_deg = number_or_nan(c[7], csv, line.number, "latitude");
    g.longitude_deg = number_or_nan(c[8], csv, line.number, "longitude");
    g.height_m = number_or_nan(c[9], csv, line.number, "height");
    const double h = cal_.gps_sigma_horizontal_m * number_or_nan(c[3], csv, line.number, "hdop");
    if (g.fix && std::isfinite(h)) g.covariance_enu_m2 = Vec3(h * h / 2, h * h / 2, 2.25 * h * h);
    sink_->gps(g, seq++);
  }
}

void BagWriter::finish(const ExportTruth& truth) {
  sink_->tf_static(first_ns_ < 0 ? 0 : first_ns_, transforms());
  for (const fs::path& csv : truth.sensor_csvs) {
    const std::string stem = csv.stem().string();
    if (stem == "imu") write_imu(csv);
    if (stem == "gps") write_gps(csv);
    if (stem == "compass") {
      std::uint32_t seq = 0;
      for (const CompassReading& r : read_compass_csv(csv)) sink_->compass(r, seq++);
    }
    fs::remove(csv);
  }
  std::uint32_t seq = 0;
  for (const BodyState& b : truth.body) sink_->pose(b.t_ns, b.T_W_S, seq++);
  sink_->close();
  write_calibration_files();
}

void BagWriter::write_calibration_files() const {
  write_file_atomic(root_ / names::kCamchainFile, kalibr_imucam_chain_yaml(cal_));
  if (cal_.imu.rate_hz > 0) {
    write_file_atomic(root_ / names::kImuChainFile, kalibr_imu_chain_yaml(cal_.imu));
    write_file_atomic(root_ / "estimator_config.yaml", openvins_estimator_config_yaml(cal_));
    fs::create_directories(root_ / "vins_fusion");
    for (const auto& [name, text] : vins_fusion_files(cal_))
      write_file_atomic(root_ / "vins_fusion" / name, text);
  }
  write_file_atomic(root_ / "info.yaml", bag_info_yaml(cal_, frames_, format_, bag_files_));
}

}  // namespace

std::unique_ptr<DatasetWriter> make_bag_writer(const fs::path& root,
                                               const ExportCalibration& calibration,
                                               std::unique_ptr<BagSink> sink, std::string format,
                                               std::string bag_files) {
  return std::make_unique<BagWriter>(root, calibration, std::move(sink), std::move(format),
                                     std::move(bag_files));
}

Quat heading_quaternion(double heading_rad) {
  return Quat(Eigen::AngleAxisd(heading_rad, Vec3::UnitZ()));
}

}  // namespace driftlab::dataset::detail
