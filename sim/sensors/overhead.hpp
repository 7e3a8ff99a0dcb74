// The basin paper's truth system (Kucic and Valcic 2020, Section 3.2): an overhead camera
// looking straight down on the ship model, which carries a red and a green marker, and the
// paper's colour tracker (BGR to HSV, Gaussian blur, colour thresholds, erosion and dilation,
// the largest contour's centroid), whose marker positions give the model's position, heading
// and velocities by the paper's Eqs. (11)-(20). The pipeline renders the camera's frames
// (pipeline/overhead_stage.hpp); this file holds the options, the tracker and the equations.
#pragma once

#include <array>
#include <optional>
#include <vector>

#include <opencv2/core.hpp>

#include "core/time.hpp"
#include "sim/sensors/overhead_options.hpp"

namespace driftlab::sim {

/// One frame's markers: the centroid [px] of each colour's largest contour, when found.
struct MarkerFix {
  std::optional<cv::Point2d> red, green;
};

/// The paper's tracker on one BGR frame.
MarkerFix track_markers(const cv::Mat& bgr, const MarkerTrackerOptions& options);

/// The model's planar state from its markers' positions in the basin plane (north, east [m])
/// at times t_ns (Eqs. (11)-(20)); a frame without both markers is invalid, and so is the
/// velocity of the frame after it. Heading [rad] clockwise from north, in [0, 2 pi); surge and
/// sway [m/s] along and across (starboard positive) the heading.
struct MarkerReference {
  std::vector<TimeNs> t_ns;
  std::vector<double> north_m, east_m, heading_rad, surge_m_s, sway_m_s;
  std::vector<bool> valid;
};
struct MarkerPlanePositions {
  TimeNs t_ns = 0;
  std::optional<std::array<double, 2>> red_ne_m, green_ne_m;
};
MarkerReference marker_reference(const std::vector<MarkerPlanePositions>& frames);

}  // namespace driftlab::sim
