// TUM RGB-D layout (Sturm et al., "A benchmark for the evaluation of RGB-D SLAM systems",
// IROS 2012; the dataset's file formats page): writer. Left image and true depth.
#include <fmt/format.h>

#include <cmath>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/yaml_io.hpp"
#include "dataset/dataset_detail.hpp"

namespace driftlab::dataset::detail {
namespace fs = std::filesystem;
namespace {

// Seconds with all nine decimals, so that a stamp reads back to the nanosecond.
std::string seconds_text(TimeNs t) {
  return fmt::format("{}.{:09d}", t / 1'000'000'000, t % 1'000'000'000);
}

cv::Mat tum_depth(const cv::Mat& depth_m, std::size_t* beyond) {
  DRIFTLAB_DEMAND_MSG(depth_m.type() == CV_32FC1, "TUM RGB-D export: depth must be CV_32F");
  cv::Mat out(depth_m.rows, depth_m.cols, CV_16UC1);
  for (int r = 0; r < depth_m.rows; ++r)
    for (int c = 0; c < depth_m.cols; ++c) {
      const double z = depth_m.at<float>(r, c) * kTumDepthScale;
      const bool ok = std::isfinite(z) && z > 0 && z <= 65535.0;
      if (!ok && std::isfinite(z) && z > 0) ++*beyond;
      out.at<std::uint16_t>(r, c) = ok ? static_cast<std::uint16_t>(std::lround(z)) : 0;
    }
  return out;
}

std::string tum_info_yaml(const ExportCalibration& cal, std::size_t frames, double beyond_share) {
  const PinholeCamera& c = cal.rig.camera;
  return fmt::format(
      "# driftlab export, TUM RGB-D layout (left camera only)\n"
      "format: tum-rgbd\n"
      "source: \"{}\"\n"
      "frames: {}\n"
      "camera_rate_hz: {}\n"
      "camera: {{fx: {}, fy: {}, cx: {}, cy: {}, width: {}, height: {}, distortion: none}}\n"
      "depth_scale: {}  # 16-bit value per metre; 0 = no depth\n"
      "depth_beyond_range_share: {}  # pixels deeper than 65535 / depth_scale = {} m, written "
      "as 0\n"
      "files:\n"
      "  rgb/<t>.png: left image, 8-bit gray, rectified; t = the camera clock's stamp [s]\n"
      "  depth/<t>.png: true depth along the optical axis of the same image, 16 bit\n"
      "  rgb.txt, depth.txt: '# timestamp filename'\n"
      "  groundtruth.txt: true left-camera pose in the scenario's NED world at the true frame "
      "times, '# timestamp tx ty tz qx qy qz qw' (camera x right, y down, z forward)\n"
      "  sensors/: driftlab's own CSVs of the other sensors (imu.csv in EuRoC's IMU layout, "
      "gps.csv, compass.csv)\n"
      "  scenario.resolved.yaml: the scenario that made this dataset\n",
      cal.source, frames, yaml::format_double(cal.camera_rate_hz), yaml::format_double(c.fx),
      yaml::format_double(c.fy), yaml::format_double(c.cx), yaml::format_double(c.cy), c.width,
      c.height, kTumDepthScale, yaml::format_double(beyond_share), 65535.0 / kTumDepthScale);
}

class TumRgbdWriter final : public DatasetWriter {
 public:
  TumRgbdWriter(const fs::path& root, const ExportCalibration& cal) : root_(root), cal_(cal) {
    fs::create_directories(root_ / "rgb");
    fs::create_directories(root_ / "depth");
    rgb_ = "# color images\n# file: 'driftlab export'\n# timestamp filename\n";
    depth_ = "# depth maps\n# file: 'driftlab export'\n# timestamp filename\n";
  }
  void add_frame(TimeNs t, const cv::Mat& left, const cv::Mat&, const cv::Mat& depth_m) override {
    DRIFTLAB_DEMAND_MSG(!depth_m.empty(), "TUM RGB-D export needs the depth image");
    const std::string s = seconds_text(t);
    write_png(root_ / "rgb" / (s + ".png"), left);
    write_png(root_ / "depth" / (s + ".png"), tum_depth(depth_m, &beyond_));
    rgb_ += fmt::format("{0} rgb/{0}.png\n", s);
    depth_ += fmt::format("{0} depth/{0}.png\n", s);
    pixels_ += depth_m.total();
    ++frames_;
  }
  bool wants_depth() const override { return true; }
  void finish(const ExportTruth& truth) override {
    write_file_atomic(root_ / "rgb.txt", rgb_);
    write_file_atomic(root_ / "depth.txt", depth_);
    write_tum(root_ / "groundtruth.txt", truth.camera);
    for (const auto& csv : truth.sensor_csvs) move_file(csv, root_ / "sensors" / csv.filename());
    const double share = pixels_ ? static_cast<double>(beyond_) / static_cast<double>(pixels_) : 0;
    write_file_atomic(root_ / "info.yaml", tum_info_yaml(cal_, frames_, share));
  }

 private:
  fs::path root_;
  ExportCalibration cal_;
  std::string rgb_, depth_;
  std::size_t frames_ = 0, pixels_ = 0, beyond_ = 0;
};

}  // namespace

std::unique_ptr<DatasetWriter> make_tum_rgbd_writer(const fs::path& root,
                                                    const ExportCalibration& calibration) {
  return std::make_unique<TumRgbdWriter>(root, calibration);
}

}  // namespace driftlab::dataset::detail
