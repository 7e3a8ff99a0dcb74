// The dataset layouts driftlab writes and reads, by name (light: no OpenCV).
#pragma once

#include <array>
#include <string_view>
#include <utility>

namespace driftlab::dataset {

enum class DatasetFormat { kKitti, kEuroc, kTumRgbd, kRosbag, kRosbag2 };

/// Names for the scenario reader (yaml::enum_name and friends).
constexpr auto enum_table(DatasetFormat) {
  return std::array{
      std::pair{DatasetFormat::kKitti, "kitti"}, std::pair{DatasetFormat::kEuroc, "euroc"},
      std::pair{DatasetFormat::kTumRgbd, "tum-rgbd"}, std::pair{DatasetFormat::kRosbag, "rosbag"},
      std::pair{DatasetFormat::kRosbag2, "rosbag2"}};
}

/// "kitti", "euroc", "tum-rgbd", "rosbag" or "rosbag2" (any case); UserError listing these
/// otherwise.
DatasetFormat format_from_name(std::string_view name);
std::string_view format_name(DatasetFormat format);

/// Whether a writer of `format` keeps the IMU's true states (EuRoC's state ground truth, a
/// bag's /groundtruth/pose): the mission is then simulated with them.
constexpr bool wants_body_truth(DatasetFormat format) {
  return format == DatasetFormat::kEuroc || format == DatasetFormat::kRosbag ||
         format == DatasetFormat::kRosbag2;
}

}  // namespace driftlab::dataset
