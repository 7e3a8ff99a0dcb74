#include "sim/sensors/overhead.hpp"

#include <cmath>
#include <limits>
#include <numbers>

#include <opencv2/imgproc.hpp>

#include "core/error.hpp"

namespace driftlab::sim {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

cv::Scalar scalar(const std::array<double, 3>& v) { return {v[0], v[1], v[2]}; }

// The pixels within an HSV box; a hue range whose low end is above its high end wraps
// through 0, as red's does.
cv::Mat in_range(const cv::Mat& hsv, const HsvRange& r) {
  cv::Mat mask;
  if (r.lo[0] <= r.hi[0]) {
    cv::inRange(hsv, scalar(r.lo), scalar(r.hi), mask);
    return mask;
  }
  cv::Mat upper, lower;
  cv::inRange(hsv, scalar(r.lo), cv::Scalar(180, r.hi[1], r.hi[2]), upper);
  cv::inRange(hsv, cv::Scalar(0, r.lo[1], r.lo[2]), scalar(r.hi), lower);
  cv::bitwise_or(upper, lower, mask);
  return mask;
}

// The centroid of the largest contour of a mask (by its area, OpenCV's contour moments).
std::optional<cv::Point2d> largest_contour_centroid(const cv::Mat& mask) {
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(mask, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
  double best_area = 0;
  std::optional<cv::Point2d> best;
  for (const auto& c : contours) {
    const cv::Moments m = cv::moments(c);
    if (m.m00 <= best_area) continue;
    best_area = m.m00;
    best = cv::Point2d(m.m10 / m.m00, m.m01 / m.m00);
  }
  return best;
}

}  // namespace

MarkerFix track_markers(const cv::Mat& bgr, const MarkerTrackerOptions& o) {
  DRIFTLAB_DEMAND(bgr.type() == CV_8UC3);
  // As the paper's Section 3.2 lists the steps: blur, to HSV, thresholds, erode, dilate,
  // the largest contour.
  cv::Mat blurred, hsv;
  cv::GaussianBlur(bgr, blurred, cv::Size(o.blur_kernel_px, o.blur_kernel_px), 0);
  cv::cvtColor(blurred, hsv, cv::COLOR_BGR2HSV);
  const auto find = [&](const HsvRange& range) {
    cv::Mat mask = in_range(hsv, range);
    cv::erode(mask, mask, cv::Mat(), cv::Point(-1, -1), o.erode_iterations);
    cv::dilate(mask, mask, cv::Mat(), cv::Point(-1, -1), o.dilate_iterations);
    return largest_contour_centroid(mask);
  };
  return {find(o.red), find(o.green)};
}

MarkerReference marker_reference(const std::vector<MarkerPlanePositions>& frames) {
  MarkerReference r;
  const std::size_t n = frames.size();
  // The paper's x and y: east and north (a mathematical angle from east, counter-clockwise).
  std::vector<double> x(n, kNaN), y(n, kNaN), psi(n, kNaN);
  for (std::size_t k = 0; k < n; ++k) {
    const MarkerPlanePositions& f = frames[k];
    r.t_ns.push_back(f.t_ns);
    const bool valid = f.red_ne_m && f.green_ne_m;
    r.valid.push_back(valid);
    if (!valid) continue;
    const double xr = (*f.red_ne_m)[1], yr = (*f.red_ne_m)[0];
    const double xg = (*f.green_ne_m)[1], yg = (*f.green_ne_m)[0];
    psi[k] = std::atan2(yr - yg, xr - xg);  // Eq. (11), as atan2
    x[k] = xg + 0.5 * (xr - xg);            // Eq. (12)
    y[k] = yg + 0.5 * (yr - yg);            // Eq. (13)
  }
  // Eq. (20): from the mathematical angle to the navigational heading, clockwise from north.
  const auto nautical = [](double xi) {
    return std::fmod(
        std::fmod(5 * std::numbers::pi / 2 - xi, 2 * std::numbers::pi) + 2 * std::numbers::pi,
        2 * std::numbers::pi);
  };
  for (std::size_t k = 0; k < n; ++k) {
    r.north_m.push_back(y[k]);
    r.east_m.push_back(x[k]);
    r.heading_rad.push_back(std::isfinite(psi[k]) ? nautical(psi[k]) : kNaN);
    // Eqs. (14)-(15) between a frame and the one before it (the first frame: the next one).
    const std::size_t a = k == 0 ? 0 : k - 1, b = k == 0 ? std::min<std::size_t>(1, n - 1) : k;
    const double dt = ns_to_seconds(frames[b].t_ns - frames[a].t_ns);
    const double dx = x[b] - x[a], dy = y[b] - y[a];
    if (!(dt > 0) || !std::isfinite(dx + dy + psi[k])) {
      r.surge_m_s.push_back(kNaN);
      r.sway_m_s.push_back(kNaN);
      continue;
    }
    const double U = std::hypot(dx, dy) / dt;         // Eq. (18), per second
    const double beta = psi[k] - std::atan2(dy, dx);  // Eq. (19), as atan2
    r.surge_m_s.push_back(U * std::cos(beta));        // Eq. (16)
    r.sway_m_s.push_back(U * std::sin(beta));         // Eq. (17)
  }
  return r;
}

}  // namespace driftlab::sim
