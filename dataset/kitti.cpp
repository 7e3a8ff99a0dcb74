// KITTI odometry layout (devkit readme of the odometry benchmark): writer and reader.
#include <fmt/format.h>

#include <map>
#include <sstream>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/yaml_io.hpp"
#include "dataset/dataset_detail.hpp"

namespace driftlab::dataset::detail {
namespace fs = std::filesystem;
namespace {

// P = K [I | (-fx B, 0, 0)^T / fx] of the rectified camera `baseline_m` to the right of cam 0.
Eigen::Matrix<double, 3, 4> projection(const PinholeCamera& c, double baseline_m) {
  Eigen::Matrix<double, 3, 4> P;
  P << c.fx, 0, c.cx, baseline_m == 0 ? 0.0 : -c.fx * baseline_m, 0, c.fy, c.cy, 0, 0, 0, 1, 0;
  return P;
}

std::string kitti_info_yaml(const ExportCalibration& cal, std::size_t frames) {
  return fmt::format(
      "# driftlab export, KITTI odometry layout\n"
      "format: kitti\n"
      "source: \"{source}\"\n"
      "frames: {frames}\n"
      "camera_rate_hz: {rate}\n"
      "files:\n"
      "  sequences/{seq}/image_0/NNNNNN.png: left image, 8-bit gray, rectified, numbered from 0 "
      "in time order\n"
      "  sequences/{seq}/image_1/NNNNNN.png: right image of the same pair\n"
      "  sequences/{seq}/calib.txt: \"P0..P3: 3x4 row-major projection matrices of the "
      "rectified cameras (P2 = P0, P3 = P1: driftlab has no colour pair); P1 = K [I | (-B, 0, "
      "0)], B = {baseline} m; Tr: the body frame of the IMU (EuRoC's T_BS inverted) in the left "
      "camera frame, in place of KITTI's Velodyne\"\n"
      "  sequences/{seq}/times.txt: time of each image [s], the camera clock's stamp\n"
      "  poses/{seq}.txt: true left-camera pose of each image in the first left camera's frame "
      "(x right, y down, z forward), 3x4 row-major, first line the identity\n"
      "  sensors/: driftlab's own CSVs of the other sensors (imu.csv in EuRoC's IMU layout, "
      "gps.csv, compass.csv), same clocks\n"
      "  scenario.resolved.yaml: the scenario that made this dataset\n",
      fmt::arg("source", cal.source), fmt::arg("frames", frames),
      fmt::arg("rate", yaml::format_double(cal.camera_rate_hz)),
      fmt::arg("baseline", yaml::format_double(cal.rig.baseline_m)), fmt::arg("seq", cal.sequence));
}

class KittiWriter final : public DatasetWriter {
 public:
  KittiWriter(const fs::path& root, const ExportCalibration& cal)
      : root_(root), seq_(root / "sequences" / cal.sequence), cal_(cal) {
    fs::create_directories(seq_ / "image_0");
    fs::create_directories(seq_ / "image_1");
  }
  void add_frame(TimeNs t, const cv::Mat& left, const cv::Mat& right, const cv::Mat&) override {
    const std::string name = fmt::format("{:06d}.png", stamps_.size());
    write_png(seq_ / "image_0" / name, left);
    write_png(seq_ / "image_1" / name, right);
    stamps_.push_back(t);
  }
  bool wants_depth() const override { return false; }
  void finish(const ExportTruth& truth) override {
    DRIFTLAB_DEMAND_MSG(truth.camera.size() == stamps_.size(), "KITTI export: one pose per image");
    const Eigen::Matrix<double, 3, 4> P0 = projection(cal_.rig.camera, 0);
    const Eigen::Matrix<double, 3, 4> P1 = projection(cal_.rig.camera, cal_.rig.baseline_m);
    std::string calib;
    for (const auto& [name, P] : {std::pair{"P0", P0}, {"P1", P1}, {"P2", P0}, {"P3", P1}})
      calib += fmt::format("{}: {}\n", name, matrix_text(P, " "));
    calib += fmt::format("Tr: {}\n", matrix_text(matrix_3x4(cal_.T_S_C.inverse()), " "));
    write_file_atomic(seq_ / "calib.txt", calib);
    Trajectory stamped, relative;
    const SE3 T_C0_W = truth.camera.empty() ? SE3() : truth.camera.front().T_W_C.inverse();
    for (std::size_t i = 0; i < stamps_.size(); ++i) {
      stamped.push_back({stamps_[i], SE3()});
      relative.push_back({stamps_[i], T_C0_W * truth.camera[i].T_W_C});
    }
    write_kitti_times(seq_ / "times.txt", stamped);
    fs::create_directories(root_ / "poses");
    write_kitti(root_ / "poses" / (cal_.sequence + ".txt"), relative);
    for (const auto& csv : truth.sensor_csvs) move_file(csv, root_ / "sensors" / csv.filename());
    write_file_atomic(root_ / "info.yaml", kitti_info_yaml(cal_, stamps_.size()));
  }

 private:
  fs::path root_, seq_;
  ExportCalibration cal_;
  std::vector<TimeNs> stamps_;
};

// "P0: 12 numbers" lines of calib.txt.
std::map<std::string, Eigen::Matrix<double, 3, 4>> read_calib(const fs::path& path) {
  std::map<std::string, Eigen::Matrix<double, 3, 4>> out;
  for (const TextLine& line : data_lines(path, "KITTI calib.txt")) {
    const auto colon = line.text.find(':');
    if (colon == std::string::npos)
      throw UserError(fmt::format("{}:{}: got '{}', expected 'NAME: 12 numbers'", path.string(),
                                  line.number, line.text.substr(0, 80)));
    const std::string name = line.text.substr(0, colon);
    std::istringstream in(line.text.substr(colon + 1));
    std::vector<std::string> tokens;
    for (std::string token; in >> token;) tokens.push_back(token);
    if (tokens.size() != 12) {
      if (name == "P0" || name == "P1")
        throw UserError(fmt::format("{}:{}: {}: got {} numbers, expected 12 (a 3x4 matrix)",
                                    path.string(), line.number, name, tokens.size()));
      continue;  // other entries (e.g. a 4x4 Tr of KITTI raw) are not needed
    }
    Eigen::Matrix<double, 3, 4> m;
    for (int i = 0; i < 12; ++i) m(i / 4, i % 4) = parse_number(tokens[i], path, line.number, name);
    out[name] = m;
  }
  return out;
}

StereoRig rig_from_calib(const fs::path& path, const cv::Mat& first_image) {
  const auto calib = read_calib(path);
  for (const char* name : {"P0", "P1"})
    if (!calib.count(name))
      throw UserError(
          fmt::format("{}: no {} line, expected 'P0: ...' and 'P1: ...'", path.string(), name));
  const auto& P0 = calib.at("P0");
  const auto& P1 = calib.at("P1");
  if ((P0.leftCols<3>() - P1.leftCols<3>()).cwiseAbs().maxCoeff() > 1e-9 * P0(0, 0) ||
      P0(0, 3) != 0 || P1(1, 3) != 0 || P1(2, 3) != 0 || P0(0, 0) <= 0 || P1(0, 3) >= 0)
    throw UserError(fmt::format(
        "{}: P0 and P1 are not a rectified pair with the right camera to the right (expected "
        "equal K, P0 = K [I | 0], P1 = K [I | (-B, 0, 0)] with B > 0)",
        path.string()));
  StereoRig rig;
  rig.camera.fx = P0(0, 0);
  rig.camera.fy = P0(1, 1);
  rig.camera.cx = P0(0, 2);
  rig.camera.cy = P0(1, 2);
  rig.camera.width = first_image.cols;
  rig.camera.height = first_image.rows;
  rig.baseline_m = -P1(0, 3) / P1(0, 0);
  return rig;
}

}  // namespace

std::unique_ptr<DatasetWriter> make_kitti_writer(const fs::path& root,
                                                 const ExportCalibration& calibration) {
  return std::make_unique<KittiWriter>(root, calibration);
}

StereoDataset read_kitti(const fs::path& root_in, const ReadOptions& options) {
  // The root of the odometry set (sequences/NN, poses/NN.txt) or a sequence folder itself.
  fs::path root = root_in, seq = root_in / "sequences" / options.sequence;
  if (!fs::is_directory(seq)) {
    if (!fs::exists(root_in / "calib.txt"))
      throw UserError(fmt::format(
          "{}: not a KITTI odometry folder: expected sequences/{}/ (or calib.txt, times.txt, "
          "image_0/, image_1/ in the folder itself)",
          root_in.string(), options.sequence));
    seq = root_in;
    root = root_in.parent_path().parent_path();
  }
  StereoDataset d;
  d.format = DatasetFormat::kKitti;
  d.root = root_in;
  const std::vector<TimeNs> times = read_kitti_times(seq / "times.txt");
  for (std::size_t i = 0; i < times.size(); ++i) {
    const std::string name = fmt::format("{:06d}.png", i);
    d.frames.push_back({times[i], seq / "image_0" / name, seq / "image_1" / name});
  }
  if (d.frames.empty()) throw UserError((seq / "times.txt").string() + ": no frames");
  d.rig = rig_from_calib(seq / "calib.txt", read_gray(d.frames.front().left));
  const fs::path poses = root / "poses" / (options.sequence + ".txt");
  if (fs::exists(poses)) {
    KittiTiming timing;
    timing.times_ns = times;
    d.camera_gt = driftlab::read_kitti(poses, timing);
  }
  return d;
}

}  // namespace driftlab::dataset::detail
