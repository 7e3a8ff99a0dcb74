// The dataset layouts driftlab writes and reads, by name (light: no OpenCV).
#pragma once

#include <array>
#include <string_view>
#include <utility>

namespace driftlab::dataset {

enum class DatasetFormat { kKitti, kEuroc, kTumRgbd };

/// Names for the scenario reader (yaml::enum_name and friends).
constexpr auto enum_table(DatasetFormat) {
  return std::array{std::pair{DatasetFormat::kKitti, "kitti"},
                    std::pair{DatasetFormat::kEuroc, "euroc"},
                    std::pair{DatasetFormat::kTumRgbd, "tum-rgbd"}};
}

/// "kitti", "euroc" or "tum-rgbd" (any case); UserError listing these otherwise.
DatasetFormat format_from_name(std::string_view name);
std::string_view format_name(DatasetFormat format);

}  // namespace driftlab::dataset
