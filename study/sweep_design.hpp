// The names a sweep file uses for its design and its axes' value lists.
#pragma once

#include <array>
#include <utility>

namespace driftlab::study {

enum class SweepDesign { kGrid, kZip, kRandom };
constexpr auto enum_table(SweepDesign) {
  return std::array{std::pair{SweepDesign::kGrid, "grid"}, std::pair{SweepDesign::kZip, "zip"},
                    std::pair{SweepDesign::kRandom, "random"}};
}

/// How an axis lists its values in the sweep file.
enum class AxisSpec { kValues, kRange, kLinspace, kLogspace };
constexpr auto enum_table(AxisSpec) {
  return std::array{std::pair{AxisSpec::kValues, "values"}, std::pair{AxisSpec::kRange, "range"},
                    std::pair{AxisSpec::kLinspace, "linspace"},
                    std::pair{AxisSpec::kLogspace, "logspace"}};
}

}  // namespace driftlab::study
