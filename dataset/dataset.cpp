#include "dataset/dataset.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/file_io.hpp"
#include "core/number.hpp"
#include "core/rotation.hpp"
#include "core/yaml_io.hpp"
#include "dataset/dataset_detail.hpp"

namespace driftlab::dataset {
namespace fs = std::filesystem;

DatasetFormat format_from_name(std::string_view name) {
  if (const auto f = yaml::enum_from_name_any_case<DatasetFormat>(name)) return *f;
  throw UserError(fmt::format("unknown dataset format: got '{}', expected one of: {}", name,
                              yaml::enum_choices<DatasetFormat>()));
}

std::string_view format_name(DatasetFormat format) { return yaml::enum_name(format); }

std::unique_ptr<DatasetWriter> make_writer(DatasetFormat format, const fs::path& root,
                                           const ExportCalibration& calibration) {
  switch (format) {
    case DatasetFormat::kKitti:
      return detail::make_kitti_writer(root, calibration);
    case DatasetFormat::kEuroc:
      return detail::make_euroc_writer(root, calibration);
    case DatasetFormat::kTumRgbd:
      return detail::make_tum_rgbd_writer(root, calibration);
    case DatasetFormat::kRosbag:
      return detail::make_rosbag_writer(root, calibration);
    case DatasetFormat::kRosbag2:
      return detail::make_rosbag2_writer(root, calibration);
  }
  return nullptr;
}

StereoDataset read_dataset(const fs::path& root, DatasetFormat format, const ReadOptions& options) {
  if (format == DatasetFormat::kRosbag) return detail::read_rosbag(root, options);
  if (!fs::is_directory(root))
    throw UserError(fmt::format("{}: no such dataset folder", root.string()));
  switch (format) {
    case DatasetFormat::kKitti:
      return detail::read_kitti(root, options);
    case DatasetFormat::kEuroc:
      return detail::read_euroc(root);
    case DatasetFormat::kTumRgbd:
      throw UserError(
          fmt::format("{}: a TUM RGB-D dataset has one camera; the stereo VOs read kitti, euroc "
                      "or rosbag",
                      root.string()));
    case DatasetFormat::kRosbag:
      break;
    case DatasetFormat::kRosbag2:
      throw UserError(fmt::format(
          "{}: driftlab vo reads ROS 1 bags (--format rosbag), not ROS 2 ones; `ros2 bag convert` "
          "or the rosbags Python package turns one into the other",
          root.string()));
  }
  return {};
}

cv::Mat read_gray(const fs::path& path) {
  if (!fs::is_regular_file(path)) throw UserError(path.string() + ": no such image");
  const cv::Mat image = cv::imread(path.string(), cv::IMREAD_UNCHANGED);
  if (image.empty()) throw UserError(path.string() + ": cannot read the image");
  if (image.depth() != CV_8U)
    throw UserError(path.string() + ": expected an 8-bit image, got another depth");
  if (image.channels() == 1) return image;
  cv::Mat gray;
  cv::cvtColor(image, gray, image.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
  return gray;
}

std::pair<cv::Mat, cv::Mat> read_pair(const StereoDataset& data, const DatasetFrame& frame) {
  cv::Mat left, right;
  if (data.images)
    std::tie(left, right) = data.images->read(frame);
  else
    left = read_gray(frame.left), right = read_gray(frame.right);
  if (!data.rectification) return {left, right};
  const Rectification& r = *data.rectification;
  cv::Mat left_rect, right_rect;
  cv::remap(left, left_rect, r.left_map1, r.left_map2, cv::INTER_LINEAR);
  cv::remap(right, right_rect, r.right_map1, r.right_map2, cv::INTER_LINEAR);
  return {left_rect, right_rect};
}

std::optional<SE3> pose_at(const Trajectory& trajectory, TimeNs t_ns) {
  if (trajectory.empty() || t_ns < trajectory.front().t_ns || t_ns > trajectory.back().t_ns)
    return std::nullopt;
  const auto after = std::lower_bound(trajectory.begin(), trajectory.end(), t_ns,
                                      [](const StampedPose& p, TimeNs t) { return p.t_ns < t; });
  if (after->t_ns == t_ns) return after->T_W_C;
  const auto before = after - 1;
  const double s =
      static_cast<double>(t_ns - before->t_ns) / static_cast<double>(after->t_ns - before->t_ns);
  return SE3::interpolate_decoupled(before->T_W_C, after->T_W_C, s);
}

std::vector<CompassReading> read_compass_csv(const fs::path& path) {
  std::vector<CompassReading> out;
  for (const detail::TextLine& line : detail::data_lines(path, "compass CSV")) {
    const std::vector<std::string> cells = split_csv_line(line.text);
    if (cells.size() != 5)
      throw UserError(fmt::format(
          "{}:{}: got {} columns, expected 5 (timestamp [ns], heading [deg], m_S_x, m_S_y, m_S_z "
          "[nT])",
          path.string(), line.number, cells.size()));
    CompassReading r;
    r.t_ns = detail::parse_stamp_ns(cells[0], path, line.number);
    const double deg = detail::parse_number(cells[1], path, line.number, "heading");
    if (!(deg >= 0 && deg < 360))
      throw UserError(fmt::format("{}:{}: heading: got {}, expected degrees in [0, 360)",
                                  path.string(), line.number, cells[1]));
    r.heading_rad = wrap_angle_rad(deg2rad(deg));
    for (int i = 0; i < 3; ++i)
      r.field_S_nt[i] =
          detail::parse_number(cells[2 + i], path, line.number, fmt::format("m_S_{}", "xyz"[i]));
    if (!out.empty() && r.t_ns <= out.back().t_ns)
      throw UserError(
          fmt::format("{}:{}: timestamp: got {}, expected more than the line before's {}",
                      path.string(), line.number, r.t_ns, out.back().t_ns));
    out.push_back(r);
  }
  return out;
}

namespace detail {

std::vector<TextLine> data_lines(const fs::path& path, std::string_view what) {
  const std::string text = read_text_file(path, what);
  std::vector<TextLine> lines;
  std::size_t pos = 0;
  for (int number = 1; pos < text.size(); ++number) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    std::string line = text.substr(pos, end - pos);
    pos = end + 1;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const auto first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') continue;
    lines.push_back({number, std::move(line)});
  }
  return lines;
}

double parse_number(std::string_view token, const fs::path& path, int line,
                    std::string_view field) {
  while (!token.empty() && (token.front() == ' ' || token.front() == '\t')) token.remove_prefix(1);
  while (!token.empty() && (token.back() == ' ' || token.back() == '\t')) token.remove_suffix(1);
  double value = 0;
  if (read_number(token, &value) != NumberStatus::kOk)
    throw UserError(fmt::format("{}:{}: {}: got '{}', expected a finite number", path.string(),
                                line, field, token.substr(0, 80)));
  return value;
}

TimeNs parse_stamp_ns(std::string_view token, const fs::path& path, int line) {
  while (!token.empty() && (token.front() == ' ' || token.front() == '\t')) token.remove_prefix(1);
  while (!token.empty() && (token.back() == ' ' || token.back() == '\t')) token.remove_suffix(1);
  TimeNs value = 0;
  if (read_number(token, &value) != NumberStatus::kOk || value < 0)
    throw UserError(
        fmt::format("{}:{}: timestamp: got '{}', expected a non-negative integer in nanoseconds",
                    path.string(), line, token.substr(0, 80)));
  return value;
}

void write_png(const fs::path& path, const cv::Mat& image) {
  if (!cv::imwrite(path.string(), image))
    throw UserError(fmt::format("{}: cannot write the image", path.string()));
}

std::string matrix_text(const Eigen::MatrixXd& m, std::string_view sep) {
  std::string out;
  for (Eigen::Index r = 0; r < m.rows(); ++r)
    for (Eigen::Index c = 0; c < m.cols(); ++c) {
      if (!out.empty()) out += sep;
      out += yaml::format_double(m(r, c));
    }
  return out;
}

Eigen::Matrix<double, 3, 4> matrix_3x4(const SE3& T) {
  Eigen::Matrix<double, 3, 4> m;
  m << T.rotation(), T.translation();
  return m;
}

Eigen::Matrix4d matrix_4x4(const SE3& T) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topRows<3>() = matrix_3x4(T);
  return m;
}

void move_file(const fs::path& from, const fs::path& to) {
  fs::create_directories(to.parent_path());
  fs::rename(from, to);
}

}  // namespace detail
}  // namespace driftlab::dataset
