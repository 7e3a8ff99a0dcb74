// Lens distortion + rectification round trip: images and blob positions
// against expectations computed here from the Brown-Conrady formula written
// out (and inverted by Newton's method), independently of OpenCV's
// projectPoints / undistortPoints that the class uses.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "sim/sensors/lens.hpp"

namespace driftlab::sim {
namespace {

using Coeffs = std::array<double, 5>;  // k1, k2, p1, p2, k3

CameraOptions lens_camera(int w = 640, int h = 480) {
  CameraOptions c;
  c.width_px = w;
  c.height_px = h;
  c.fx_px = 500.0;
  c.fy_px = 480.0;
  c.cx_px = (w - 1) / 2.0;
  c.cy_px = (h - 1) / 2.0;
  c.lens_distortion.enabled = true;  // default coefficients: k1 = -0.30, k2 = 0.10
  return c;
}

Coeffs calibrated(const CameraOptions& c) {
  Coeffs out{};
  for (std::size_t i = 0; i < out.size(); ++i)
    out[i] = c.lens_distortion.coefficients[i] + c.lens_distortion.calibration_error[i];
  return out;
}

// Brown-Conrady on normalised coordinates, OpenCV's order (k1, k2, p1, p2, k3).
cv::Point2d distort_normalised(cv::Point2d p, const Coeffs& k) {
  const double r2 = p.x * p.x + p.y * p.y;
  const double radial = 1 + k[0] * r2 + k[1] * r2 * r2 + k[4] * r2 * r2 * r2;
  return {p.x * radial + 2 * k[2] * p.x * p.y + k[3] * (r2 + 2 * p.x * p.x),
          p.y * radial + k[2] * (r2 + 2 * p.y * p.y) + 2 * k[3] * p.x * p.y};
}

cv::Point2d to_normalised(const CameraOptions& c, cv::Point2d px) {
  return {(px.x - c.cx_px) / c.fx_px, (px.y - c.cy_px) / c.fy_px};
}
cv::Point2d to_pixels(const CameraOptions& c, cv::Point2d n) {
  return {n.x * c.fx_px + c.cx_px, n.y * c.fy_px + c.cy_px};
}

cv::Point2d distort_px(const CameraOptions& c, cv::Point2d px, const Coeffs& k) {
  return to_pixels(c, distort_normalised(to_normalised(c, px), k));
}

// Inverse of distort_px by Newton's method (central-difference Jacobian).
cv::Point2d undistort_px(const CameraOptions& c, cv::Point2d px, const Coeffs& k) {
  const cv::Point2d target = to_normalised(c, px);
  cv::Point2d x = target;
  for (int it = 0; it < 50; ++it) {
    const cv::Point2d r = distort_normalised(x, k) - target;
    if (std::hypot(r.x, r.y) < 1e-15) break;
    const double h = 1e-7;
    const cv::Point2d dx = (distort_normalised(x + cv::Point2d(h, 0), k) -
                            distort_normalised(x - cv::Point2d(h, 0), k)) /
                           (2 * h);
    const cv::Point2d dy = (distort_normalised(x + cv::Point2d(0, h), k) -
                            distort_normalised(x - cv::Point2d(0, h), k)) /
                           (2 * h);
    const double det = dx.x * dy.y - dy.x * dx.y;
    x -= cv::Point2d((dy.y * r.x - dy.x * r.y) / det, (-dx.y * r.x + dx.x * r.y) / det);
  }
  return to_pixels(c, x);
}

// Where ideal pixel p should land in the rectified image, from the formula.
cv::Point2d expected_position(const CameraOptions& c, cv::Point2d p) {
  return undistort_px(c, distort_px(c, p, c.lens_distortion.coefficients), calibrated(c));
}

// The model written out: raw(d) = I(undistort_T(d)), rect(u) = raw(distort_C(u)),
// each an exact bilinear interpolation in double precision (0 outside the
// image), without OpenCV's 1/32-px position and 8-bit intermediate rounding.
class ReferenceRoundTrip {
 public:
  explicit ReferenceRoundTrip(const CameraOptions& c) : c_(c) {
    const int w = c.width_px, h = c.height_px;
    raw_src_.resize(static_cast<std::size_t>(w) * h);
    rect_src_.resize(raw_src_.size());
    for (int y = 0, i = 0; y < h; ++y)
      for (int x = 0; x < w; ++x, ++i) {
        raw_src_[i] = undistort_px(c, {double(x), double(y)}, c.lens_distortion.coefficients);
        rect_src_[i] = distort_px(c, {double(x), double(y)}, calibrated(c));
      }
  }

  cv::Mat apply(const cv::Mat& ideal8) const {
    cv::Mat ideal, raw(ideal8.size(), CV_64F), rect(ideal8.size(), CV_64F);
    ideal8.convertTo(ideal, CV_64F);
    for (int y = 0, i = 0; y < raw.rows; ++y)
      for (int x = 0; x < raw.cols; ++x, ++i) raw.at<double>(y, x) = bilinear(ideal, raw_src_[i]);
    for (int y = 0, i = 0; y < rect.rows; ++y)
      for (int x = 0; x < rect.cols; ++x, ++i) rect.at<double>(y, x) = bilinear(raw, rect_src_[i]);
    return rect;
  }

 private:
  static double bilinear(const cv::Mat& m, cv::Point2d p) {
    const int x0 = static_cast<int>(std::floor(p.x)), y0 = static_cast<int>(std::floor(p.y));
    const double a = p.x - x0, b = p.y - y0;
    const auto at = [&](int x, int y) {
      return x < 0 || y < 0 || x >= m.cols || y >= m.rows ? 0.0 : m.at<double>(y, x);
    };
    return (1 - a) * (1 - b) * at(x0, y0) + a * (1 - b) * at(x0 + 1, y0) +
           (1 - a) * b * at(x0, y0 + 1) + a * b * at(x0 + 1, y0 + 1);
  }

  CameraOptions c_;
  std::vector<cv::Point2d> raw_src_, rect_src_;
};

// Smooth texture: a sum of low-frequency sinusoids (periods 29 to 53 px).
cv::Mat textured_image(int w, int h) {
  cv::Mat img(h, w, CV_8UC1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double two_pi = 2 * std::numbers::pi;
      const double v = 128 + 40 * std::sin(two_pi * x / 37.0 + 0.3) +
                       30 * std::sin(two_pi * y / 29.0 + 1.1) +
                       20 * std::sin(two_pi * (x + y) / 53.0);
      img.at<std::uint8_t>(y, x) =
          static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0, 255.0)));
    }
  return img;
}

// Black image with a Gaussian blob (peak 250) centred at sub-pixel `centre`.
cv::Mat blob_image(int w, int h, cv::Point2d centre, double sigma_px = 1.5) {
  cv::Mat img = cv::Mat::zeros(h, w, CV_8UC1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double dx = x - centre.x, dy = y - centre.y;
      const double v = 250 * std::exp(-(dx * dx + dy * dy) / (2 * sigma_px * sigma_px));
      img.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(std::lround(v));
    }
  return img;
}

// Intensity centroid within a (2 r + 1)^2 window around `guess` (any depth).
cv::Point2d centroid(const cv::Mat& image, cv::Point2d guess, int r = 7) {
  cv::Mat img;
  image.convertTo(img, CV_64F);
  const int gx = static_cast<int>(std::lround(guess.x)),
            gy = static_cast<int>(std::lround(guess.y));
  double s = 0, sx = 0, sy = 0;
  for (int y = std::max(0, gy - r); y <= std::min(img.rows - 1, gy + r); ++y)
    for (int x = std::max(0, gx - r); x <= std::min(img.cols - 1, gx + r); ++x) {
      const double v = img.at<double>(y, x);
      s += v;
      sx += v * x;
      sy += v * y;
    }
  EXPECT_GT(s, 0.0);
  return {sx / s, sy / s};
}

double distance(cv::Point2d a, cv::Point2d b) { return std::hypot(a.x - b.x, a.y - b.y); }

// Blob positions: centre, mid-field and near each corner (largest distortion).
const std::vector<cv::Point2d>& blob_positions() {
  static const std::vector<cv::Point2d> positions{{319.5, 239.5}, {400.3, 180.7}, {150.25, 300.6},
                                                  {40.4, 35.3},   {600.7, 45.2},  {30.6, 440.1},
                                                  {610.2, 445.8}, {520.5, 120.35}};
  return positions;
}

TEST(Lens, ExactCalibrationReturnsASmoothImage) {
  const CameraOptions c = lens_camera();
  const LensRoundTrip lens(c);
  const cv::Mat in = textured_image(c.width_px, c.height_px);
  cv::Mat out = in.clone();
  lens.apply(&out);
  ASSERT_EQ(out.type(), CV_8UC1);
  ASSERT_EQ(out.size(), in.size());
  const int margin = 8;
  const cv::Rect interior(margin, margin, c.width_px - 2 * margin, c.height_px - 2 * margin);
  cv::Mat diff;
  cv::absdiff(in(interior), out(interior), diff);
  const double mae = cv::mean(diff)[0];
  double max_err = 0;
  cv::minMaxLoc(diff, nullptr, &max_err);
  std::printf("smooth texture, exact calibration: interior MAE %.3f DN, max %.0f DN\n", mae,
              max_err);
  EXPECT_LT(mae, 1.0);
  EXPECT_LE(max_err, 4.0);
  // Distortion alone (no rectification) would move the corners by tens of pixels.
  const cv::Point2d corner_raw = distort_px(c, {20.0, 20.0}, c.lens_distortion.coefficients);
  EXPECT_GT(std::hypot(corner_raw.x - 20.0, corner_raw.y - 20.0), 30.0);
}

// Bilinear resampling of a blob that the lens compresses (barrel: by up to 40 %
// in the corners, a raw sigma near 0.9 px) locks its centroid towards the
// pixel grid by a few hundredths of a pixel, a real effect of a rectified
// stream that the exact double-precision model shows too. Hence: 0.05 px for a
// sigma 1.5 px blob in the central field and for a sigma 2 px blob anywhere;
// in the outer field the sigma 1.5 px blob is held to the written-out model.
TEST(Lens, ExactCalibrationKeepsBlobCentroids) {
  const CameraOptions c = lens_camera();
  const LensRoundTrip lens(c);
  const ReferenceRoundTrip reference(c);
  double worst_central = 0, worst_wide = 0, worst_outer = 0, worst_vs_model = 0;
  for (double sigma : {1.5, 2.0})
    for (const cv::Point2d& p : blob_positions()) {
      const cv::Mat in = blob_image(c.width_px, c.height_px, p, sigma);
      cv::Mat out = in.clone();
      lens.apply(&out);
      const cv::Point2d before = centroid(in, p);
      const cv::Point2d after = centroid(out, p);
      EXPECT_LT(distance(before, p), 0.02) << p;  // the blob itself
      const double err = distance(after, before);
      // With C = T the predicted position is the ideal one.
      EXPECT_LT(distance(lens.rectified_position(p), p), 1e-6) << p;
      const bool central = distance(p, {c.cx_px, c.cy_px}) < 120.0;
      if (sigma == 2.0) {
        EXPECT_LT(err, 0.05) << "sigma 2 blob at " << p << " came back at " << after;
        worst_wide = std::max(worst_wide, err);
      } else if (central) {
        EXPECT_LT(err, 0.05) << "blob at " << p << " came back at " << after;
        worst_central = std::max(worst_central, err);
      } else {
        EXPECT_LT(err, 0.1) << "blob at " << p << " came back at " << after;
        const double vs_model = distance(after, centroid(reference.apply(in), p));
        EXPECT_LT(vs_model, 0.02) << "blob at " << p << ": OpenCV vs the written-out model";
        worst_outer = std::max(worst_outer, err);
        worst_vs_model = std::max(worst_vs_model, vs_model);
      }
    }
  std::printf(
      "exact calibration, worst blob centroid error: sigma 1.5 central %.4f px, outer %.4f px "
      "(%.4f px from the double-precision model); sigma 2 anywhere %.4f px\n",
      worst_central, worst_outer, worst_vs_model, worst_wide);
}

TEST(Lens, MatchesTheWrittenOutModelImage) {
  CameraOptions c = lens_camera();
  c.lens_distortion.calibration_error = {0.02, -0.01, 0.001, -0.0005, 0.0};
  const LensRoundTrip lens(c);
  const cv::Mat in = textured_image(c.width_px, c.height_px);
  cv::Mat out = in.clone();
  lens.apply(&out);
  cv::Mat out64, diff;
  out.convertTo(out64, CV_64F);
  cv::absdiff(out64, ReferenceRoundTrip(c).apply(in), diff);
  // Away from the edge, where black from outside the frame meets the texture
  // and OpenCV's 1/32-px positions matter most.
  const int margin = 8;
  const cv::Mat interior =
      diff(cv::Rect(margin, margin, c.width_px - 2 * margin, c.height_px - 2 * margin));
  double max_err = 0;
  cv::minMaxLoc(interior, nullptr, &max_err);
  const double mae = cv::mean(interior)[0];
  std::printf("textured image vs the written-out model: interior MAE %.3f DN, max %.2f DN\n", mae,
              max_err);
  EXPECT_LT(mae, 0.5);
  EXPECT_LT(max_err, 2.0);
}

TEST(Lens, CalibrationErrorMovesBlobsToThePredictedPosition) {
  CameraOptions c = lens_camera();
  c.lens_distortion.calibration_error = {0.02, 0.0, 0.0, 0.0, 0.0};
  const LensRoundTrip lens(c);
  double worst_model = 0, worst_blob = 0, largest_shift = 0;
  for (const cv::Point2d& p : blob_positions()) {
    const cv::Point2d predicted = lens.rectified_position(p);
    // The class' prediction against the formula written out here.
    const cv::Point2d expected = expected_position(c, p);
    const double model_err = distance(predicted, expected);
    EXPECT_LT(model_err, 1e-3) << p;
    const cv::Mat in = blob_image(c.width_px, c.height_px, p);
    cv::Mat out = in.clone();
    lens.apply(&out);
    const cv::Point2d after = centroid(out, expected);
    const double blob_err = distance(after, expected);
    EXPECT_LT(blob_err, 0.1) << "blob at " << p << ": expected at " << expected << ", found at "
                             << after;
    worst_model = std::max(worst_model, model_err);
    worst_blob = std::max(worst_blob, blob_err);
    largest_shift = std::max(largest_shift, distance(expected, p));
  }
  // The error is visible: corners move by pixels, so the test above is not trivial.
  EXPECT_GT(largest_shift, 1.0);
  std::printf(
      "k1 error 0.02: largest residual shift %.3f px, prediction vs formula %.2e px, worst "
      "blob centroid vs prediction %.4f px\n",
      largest_shift, worst_model, worst_blob);
}

TEST(Lens, TangentialCalibrationErrorIsPredictedToo) {
  CameraOptions c = lens_camera();
  c.lens_distortion.coefficients = {-0.25, 0.08, 0.001, -0.002, 0.01};
  c.lens_distortion.calibration_error = {-0.01, 0.005, 0.002, 0.001, 0.0};
  const LensRoundTrip lens(c);
  for (const cv::Point2d& p : blob_positions()) {
    const cv::Point2d predicted = lens.rectified_position(p);
    const cv::Point2d expected = expected_position(c, p);
    EXPECT_LT(std::hypot(predicted.x - expected.x, predicted.y - expected.y), 1e-3) << p;
    const cv::Mat in = blob_image(c.width_px, c.height_px, p);
    cv::Mat out = in.clone();
    lens.apply(&out);
    const cv::Point2d after = centroid(out, expected);
    EXPECT_LT(std::hypot(after.x - expected.x, after.y - expected.y), 0.1) << p;
  }
}

TEST(Lens, BarrelDefaultKeepsAConstantImageExceptAtTheBorder) {
  const CameraOptions c = lens_camera();
  ASSERT_LT(c.lens_distortion.coefficients[0], 0.0);
  const LensRoundTrip lens(c);
  cv::Mat img(c.height_px, c.width_px, CV_8UC1, cv::Scalar(200));
  lens.apply(&img);
  EXPECT_EQ(img.at<std::uint8_t>(240, 320), 200);
  // Rectification with P = K looks inside the distorted frame everywhere:
  // only the outermost pixels may mix in the black outside the ideal image.
  const int margin = 2;
  int changed = 0;
  for (int y = margin; y < c.height_px - margin; ++y)
    for (int x = margin; x < c.width_px - margin; ++x) changed += img.at<std::uint8_t>(y, x) != 200;
  EXPECT_EQ(changed, 0);
}

TEST(Lens, PincushionLeavesBlackOnlyOutsideTheValidRegion) {
  CameraOptions c = lens_camera();
  c.lens_distortion.coefficients = {0.20, 0.0, 0.0, 0.0, 0.0};
  const LensRoundTrip lens(c);
  cv::Mat img(c.height_px, c.width_px, CV_8UC1, cv::Scalar(200));
  lens.apply(&img);
  EXPECT_EQ(img.at<std::uint8_t>(240, 320), 200);
  // A rectified pixel u reads the raw image at distort_C(u); the raw image is
  // valid everywhere (pincushion: undistort_T pulls inwards). Outside the raw
  // frame by more than a pixel: black; inside by two: unchanged.
  int black = 0, checked_black = 0, checked_valid = 0;
  for (int y = 0; y < c.height_px; ++y)
    for (int x = 0; x < c.width_px; ++x) {
      const cv::Point2d d = distort_px(c, {double(x), double(y)}, calibrated(c));
      const double inside = std::min({d.x, d.y, c.width_px - 1 - d.x, c.height_px - 1 - d.y});
      const int v = img.at<std::uint8_t>(y, x);
      black += v == 0;
      if (inside < -1.0) {
        ++checked_black;
        EXPECT_EQ(v, 0) << x << "," << y;
      } else if (inside > 2.0) {
        ++checked_valid;
        EXPECT_EQ(v, 200) << x << "," << y;
      }
    }
  EXPECT_GT(checked_black, 1000);  // the corners do go black
  EXPECT_GT(checked_valid, c.width_px * c.height_px / 2);
  EXPECT_EQ(img.at<std::uint8_t>(0, 0), 0);
  std::printf("pincushion k1 = 0.2: %d black pixels of %d\n", black, c.width_px * c.height_px);
}

TEST(Lens, SameBytesOnRepeatedApplication) {
  CameraOptions c = lens_camera();
  c.lens_distortion.calibration_error = {0.02, -0.01, 0.001, 0.0, 0.0};
  const LensRoundTrip lens(c);
  const LensRoundTrip lens2(c);
  const cv::Mat in = textured_image(c.width_px, c.height_px);
  cv::Mat a = in.clone(), b = in.clone(), d = in.clone();
  lens.apply(&a);
  lens.apply(&b);
  lens2.apply(&d);
  ASSERT_TRUE(a.isContinuous() && b.isContinuous() && d.isContinuous());
  EXPECT_EQ(std::memcmp(a.data, b.data, a.total()), 0);
  EXPECT_EQ(std::memcmp(a.data, d.data, a.total()), 0);
  // Nor does the number of OpenCV threads change a byte.
  const int threads = cv::getNumThreads();
  cv::setNumThreads(1);
  cv::Mat e = in.clone();
  lens.apply(&e);
  cv::setNumThreads(threads);
  EXPECT_EQ(std::memcmp(a.data, e.data, a.total()), 0);
  EXPECT_GT(cv::norm(a, in, cv::NORM_L1), 0.0);  // it did something
}

TEST(Lens, WritesIntoTheCallersPixels) {
  const CameraOptions c = lens_camera();
  const LensRoundTrip lens(c);
  cv::Mat big(c.height_px + 10, c.width_px + 10, CV_8UC1, cv::Scalar(7));
  cv::Mat view = big(cv::Rect(5, 5, c.width_px, c.height_px));
  textured_image(c.width_px, c.height_px).copyTo(view);
  cv::Mat expected = view.clone();
  lens.apply(&expected);
  const std::uint8_t* data = view.data;
  lens.apply(&view);
  EXPECT_EQ(view.data, data);
  EXPECT_EQ(cv::norm(big(cv::Rect(5, 5, c.width_px, c.height_px)), expected, cv::NORM_INF), 0.0);
  EXPECT_EQ(big.at<std::uint8_t>(0, 0), 7);  // nothing outside the view
}

TEST(Lens, DistortThenRectifyIsApply) {
  CameraOptions c = lens_camera();
  c.lens_distortion.calibration_error = {0.02, 0.0, 0.0, 0.0, 0.0};
  const LensRoundTrip lens(c);
  const cv::Mat in = textured_image(c.width_px, c.height_px);
  cv::Mat whole = in.clone();
  lens.apply(&whole);
  cv::Mat big(c.height_px + 4, c.width_px + 4, CV_8UC1, cv::Scalar(7));
  cv::Mat view = big(cv::Rect(2, 2, c.width_px, c.height_px));
  in.copyTo(view);
  const std::uint8_t* data = view.data;
  lens.distort(&view);
  lens.rectify(&view);
  EXPECT_EQ(view.data, data);
  EXPECT_EQ(cv::norm(big(cv::Rect(2, 2, c.width_px, c.height_px)), whole, cv::NORM_INF), 0.0);
  EXPECT_EQ(big.at<std::uint8_t>(0, 0), 7);
}

TEST(Lens, DistortMovesBlobsWhereTheLensPutsThem) {
  const CameraOptions c = lens_camera();
  const LensRoundTrip lens(c);
  double worst = 0, largest_shift = 0;
  for (const cv::Point2d& p : blob_positions()) {
    // The raw image of a blob centred at p is centred at distort_T(p) (up to
    // O(sigma^2) terms of the lens' curvature, small at sigma 2 px).
    const cv::Point2d expected = distort_px(c, p, c.lens_distortion.coefficients);
    cv::Mat img = blob_image(c.width_px, c.height_px, p, 2.0);
    lens.distort(&img);
    const double err = distance(centroid(img, expected), expected);
    EXPECT_LT(err, 0.1) << p << " expected at " << expected;
    worst = std::max(worst, err);
    largest_shift = std::max(largest_shift, distance(expected, p));
  }
  EXPECT_GT(largest_shift, 30.0);
  std::printf("raw image: blobs moved by up to %.1f px, centroid vs distort_T(p) within %.3f px\n",
              largest_shift, worst);
}

TEST(Lens, DisabledLeavesTheImageAlone) {
  CameraOptions c = lens_camera();
  c.lens_distortion.enabled = false;
  c.lens_distortion.calibration_error = {0.05, 0, 0, 0, 0};
  const LensRoundTrip lens(c);
  const cv::Mat in = textured_image(c.width_px, c.height_px);
  cv::Mat out = in.clone();
  lens.apply(&out);
  EXPECT_EQ(cv::norm(in, out, cv::NORM_INF), 0.0);
  const cv::Point2d u = lens.rectified_position({10.25, 20.5});
  EXPECT_EQ(u, cv::Point2d(10.25, 20.5));
}

template <class F>
std::string user_error_message(F&& f) {
  try {
    f();
  } catch (const UserError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no UserError";
  return {};
}

TEST(Lens, RejectsWrongImages) {
  const CameraOptions c = lens_camera();
  const LensRoundTrip lens(c);
  cv::Mat small(240, 320, CV_8UC1, cv::Scalar(0));
  std::string msg = user_error_message([&] { lens.apply(&small); });
  EXPECT_NE(msg.find("320x240"), std::string::npos) << msg;
  EXPECT_NE(msg.find("640x480"), std::string::npos) << msg;
  cv::Mat colour(480, 640, CV_8UC3, cv::Scalar(0, 0, 0));
  msg = user_error_message([&] { lens.apply(&colour); });
  EXPECT_NE(msg.find("3 channel"), std::string::npos) << msg;
  EXPECT_NE(msg.find("CV_8UC1"), std::string::npos) << msg;
  cv::Mat wide(480, 640, CV_16UC1, cv::Scalar(0));
  msg = user_error_message([&] { lens.apply(&wide); });
  EXPECT_NE(msg.find("640x480"), std::string::npos) << msg;
  msg = user_error_message([&] { lens.distort(&small); });
  EXPECT_NE(msg.find("320x240"), std::string::npos) << msg;
  msg = user_error_message([&] { lens.rectify(&colour); });
  EXPECT_NE(msg.find("3 channel"), std::string::npos) << msg;
}

TEST(Lens, RejectsNonFiniteCoefficients) {
  CameraOptions c = lens_camera();
  c.lens_distortion.coefficients[1] = std::numeric_limits<double>::quiet_NaN();
  std::string msg = user_error_message([&] { LensRoundTrip lens(c); });
  EXPECT_NE(msg.find("sensors.camera.lens_distortion.coefficients"), std::string::npos) << msg;
  c = lens_camera();
  c.lens_distortion.calibration_error[0] = std::numeric_limits<double>::infinity();
  msg = user_error_message([&] { LensRoundTrip lens(c); });
  EXPECT_NE(msg.find("sensors.camera.lens_distortion.calibration_error"), std::string::npos) << msg;
  // Other option problems go through the options' own validation.
  c = lens_camera();
  c.lens_distortion.coefficients[0] = 3.0;
  msg = user_error_message([&] { LensRoundTrip lens(c); });
  EXPECT_NE(msg.find("sensors.camera"), std::string::npos) << msg;
  EXPECT_NE(msg.find("coefficients"), std::string::npos) << msg;
}

TEST(Lens, TimingOf640x480) {
  CameraOptions c = lens_camera();
  c.lens_distortion.calibration_error = {0.02, 0, 0, 0, 0};
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  const LensRoundTrip lens(c);
  const double build_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  const cv::Mat in = textured_image(c.width_px, c.height_px);
  const auto median_ms = [&] {
    std::vector<double> ms;
    for (int i = 0; i < 50; ++i) {
      cv::Mat img = in.clone();
      const auto t = Clock::now();
      lens.apply(&img);
      ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t).count());
    }
    std::sort(ms.begin(), ms.end());
    return ms[ms.size() / 2];
  };
  const int threads = cv::getNumThreads();
  const double parallel_ms = median_ms();
  cv::setNumThreads(1);
  const double serial_ms = median_ms();
  cv::setNumThreads(threads);
  std::printf(
      "640x480: maps built in %.1f ms; apply() (both remaps) median %.3f ms on %d OpenCV "
      "threads, %.3f ms on 1\n",
      build_ms, parallel_ms, threads, serial_ms);
  EXPECT_LT(serial_ms, 100.0);  // loose: a few ms expected, machines vary
}

}  // namespace
}  // namespace driftlab::sim
