// The basin paper's tracker and its Eqs. (11)-(20) (sim/sensors/overhead.hpp), against
// drawn markers and closed forms.
#include "sim/sensors/overhead.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <opencv2/imgproc.hpp>

namespace driftlab::sim {
namespace {

using driftlab::test::kPi;

// A gray hall floor, a white hull and two round marks at sub-pixel centres (OpenCV draws with
// 8 fractional bits), red and green as the renderer's materials shade them.
cv::Mat drawn_markers(cv::Point2d red, cv::Point2d green, double radius_px) {
  cv::Mat img(360, 640, CV_8UC3, cv::Scalar(90, 90, 90));
  cv::rectangle(img, cv::Point(100, 150), cv::Point(540, 210), cv::Scalar(215, 215, 215),
                cv::FILLED);
  const auto disc = [&](cv::Point2d c, cv::Scalar bgr) {
    constexpr int kShift = 8;
    cv::circle(img, cv::Point(std::lround(c.x * 256), std::lround(c.y * 256)),
               static_cast<int>(std::lround(radius_px * 256)), bgr, cv::FILLED, cv::LINE_AA,
               kShift);
  };
  disc(red, cv::Scalar(11, 13, 171));
  disc(green, cv::Scalar(21, 117, 13));
  return img;
}

TEST(MarkerTracker, FindsEachMarkersCentreWithinATenthOfAPixel) {
  const MarkerTrackerOptions o;
  for (const auto& [red, green] : std::vector<std::pair<cv::Point2d, cv::Point2d>>{
           {{420.30, 180.70}, {220.55, 179.10}}, {{401.83, 171.25}, {250.12, 190.94}}}) {
    const MarkerFix fix = track_markers(drawn_markers(red, green, 12.0), o);
    ASSERT_TRUE(fix.red && fix.green);
    EXPECT_NEAR(fix.red->x, red.x, 0.1);
    EXPECT_NEAR(fix.red->y, red.y, 0.1);
    EXPECT_NEAR(fix.green->x, green.x, 0.1);
    EXPECT_NEAR(fix.green->y, green.y, 0.1);
  }
}

TEST(MarkerTracker, TheLargestBlobWinsAndGrayIsNoColour) {
  const MarkerTrackerOptions o;
  cv::Mat img = drawn_markers({420, 180}, {220, 180}, 12.0);
  cv::circle(img, cv::Point(500, 300), 5, cv::Scalar(11, 13, 171), cv::FILLED);  // a red speck
  const MarkerFix fix = track_markers(img, o);
  ASSERT_TRUE(fix.red);
  EXPECT_NEAR(fix.red->x, 420, 0.1);
  const cv::Mat gray(360, 640, CV_8UC3, cv::Scalar(128, 128, 128));
  const MarkerFix none = track_markers(gray, o);
  EXPECT_FALSE(none.red);
  EXPECT_FALSE(none.green);
}

// Markers `sep` apart around (n, e) along heading h (clockwise from north).
MarkerPlanePositions markers_at(TimeNs t, double n, double e, double h, double sep = 0.5) {
  MarkerPlanePositions p;
  p.t_ns = t;
  p.red_ne_m = std::array<double, 2>{n + sep / 2 * std::cos(h), e + sep / 2 * std::sin(h)};
  p.green_ne_m = std::array<double, 2>{n - sep / 2 * std::cos(h), e - sep / 2 * std::sin(h)};
  return p;
}

TEST(MarkerReference, EquationsElevenToTwentyGivePositionHeadingAndVelocities) {
  // A model heading 30 deg east of north, moving at 0.15 m/s along a course 40 deg east of
  // north: it crabs 10 deg to starboard, so u = V cos 10 deg and v = V sin 10 deg.
  const double h = 30 * kPi / 180, course = 40 * kPi / 180, V = 0.15;
  std::vector<MarkerPlanePositions> frames;
  for (int k = 0; k < 5; ++k) {
    const double s = V * 0.05 * k;
    frames.push_back(
        markers_at(50'000'000LL * k, 1 + s * std::cos(course), 0.2 + s * std::sin(course), h));
  }
  const MarkerReference r = marker_reference(frames);
  ASSERT_EQ(r.valid.size(), 5u);
  for (int k = 0; k < 5; ++k) {
    EXPECT_TRUE(r.valid[k]);
    const double s = V * 0.05 * k;
    EXPECT_NEAR(r.north_m[k], 1 + s * std::cos(course), 1e-12);
    EXPECT_NEAR(r.east_m[k], 0.2 + s * std::sin(course), 1e-12);
    EXPECT_NEAR(r.heading_rad[k], h, 1e-12);
    EXPECT_NEAR(r.surge_m_s[k], V * std::cos(10 * kPi / 180), 1e-9);
    EXPECT_NEAR(r.sway_m_s[k], V * std::sin(10 * kPi / 180), 1e-9);
  }
}

TEST(MarkerReference, EquationTwentyTurnsTheMathematicalAngleIntoACompassHeading) {
  for (const double deg : {0.0, 90.0, 179.0, 181.0, 270.0, 359.5}) {
    const MarkerReference r = marker_reference({markers_at(0, 0, 0, deg * kPi / 180)});
    EXPECT_NEAR(r.heading_rad[0] * 180 / kPi, deg, 1e-9) << deg;
    EXPECT_GE(r.heading_rad[0], 0.0);
    EXPECT_LT(r.heading_rad[0], 2 * kPi);
  }
}

TEST(MarkerReference, AFrameWithoutAMarkerIsInvalidAndSoIsTheNextVelocity) {
  std::vector<MarkerPlanePositions> frames;
  for (int k = 0; k < 4; ++k) frames.push_back(markers_at(50'000'000LL * k, 0.01 * k, 0, 0));
  frames[1].green_ne_m.reset();
  const MarkerReference r = marker_reference(frames);
  EXPECT_EQ(r.valid, (std::vector<bool>{true, false, true, true}));
  EXPECT_FALSE(std::isfinite(r.north_m[1]));
  EXPECT_FALSE(std::isfinite(r.surge_m_s[0]));  // the first frame's velocity is frame 1's
  EXPECT_FALSE(std::isfinite(r.surge_m_s[2]));
  EXPECT_NEAR(r.surge_m_s[3], 0.2, 1e-12);
}

}  // namespace
}  // namespace driftlab::sim
