#include "sim/sensors/lens.hpp"

#include <fmt/format.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "sim/sensors/clock.hpp"

namespace driftlab::sim {
namespace {

// undistortPoints' fixed-point iteration, run until the re-distorted point is
// within 1e-9 px of the input (or 50 steps; the default is 5, too few near the
// corners of a wide lens).
const cv::TermCriteria kUndistortCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 50,
                                          1e-9);
// Raw pixels whose inverse misses by more than this (beyond the fold of a
// strongly distorting polynomial, where no ideal ray lands) are left black.
constexpr double kMaxInverseResidualPx = 0.01;
// A sampling position outside any image: remap's constant border (0) there.
constexpr float kOutsidePx = -1e4f;

void require_finite(const std::array<double, 5>& c, const char* field) {
  for (double v : c)
    if (!std::isfinite(v))
      throw UserError(fmt::format(
          "sensors.camera.lens_distortion.{}: got [{}, {}, {}, {}, {}], expected 5 finite "
          "numbers (k1, k2, p1, p2, k3)",
          field, c[0], c[1], c[2], c[3], c[4]));
}

const CameraOptions& validated(const CameraOptions& camera) {
  require_finite(camera.lens_distortion.coefficients, "coefficients");
  require_finite(camera.lens_distortion.calibration_error, "calibration_error");
  validate_sensor_options(camera, "sensors.camera");
  return camera;
}

cv::Mat coefficient_row(const std::array<double, 5>& c) {
  return (cv::Mat_<double>(1, 5) << c[0], c[1], c[2], c[3], c[4]);
}

// distort_D(p) for pixels `ideal_px` (N x 1 CV_64FC2): the lens' forward model.
cv::Mat distort_pixels(const cv::Mat& ideal_px, const cv::Mat& K, const cv::Mat& coefficients) {
  const double fx = K.at<double>(0, 0), fy = K.at<double>(1, 1);
  const double cx = K.at<double>(0, 2), cy = K.at<double>(1, 2);
  cv::Mat rays(ideal_px.rows, 1, CV_64FC3);
  for (int i = 0; i < ideal_px.rows; ++i) {
    const auto& p = ideal_px.at<cv::Vec2d>(i);
    rays.at<cv::Vec3d>(i) = cv::Vec3d((p[0] - cx) / fx, (p[1] - cy) / fy, 1.0);
  }
  cv::Mat out;
  cv::projectPoints(rays, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, coefficients, out);
  return out.reshape(2, ideal_px.rows);
}

}  // namespace

LensRoundTrip::LensRoundTrip(const CameraOptions& camera) : options_(validated(camera)) {
  const auto& lens = options_.lens_distortion;
  camera_matrix_ = (cv::Mat_<double>(3, 3) << options_.fx_px, 0, options_.cx_px,  //
                    0, options_.fy_px, options_.cy_px,                            //
                    0, 0, 1);
  true_coefficients_ = coefficient_row(lens.coefficients);
  std::array<double, 5> calibrated{};
  for (std::size_t i = 0; i < calibrated.size(); ++i)
    calibrated[i] = lens.coefficients[i] + lens.calibration_error[i];
  calibrated_coefficients_ = coefficient_row(calibrated);
  if (!lens.enabled) return;

  const int w = options_.width_px, h = options_.height_px;
  const cv::Size size(w, h);

  // raw(d) = ideal(undistort_T(d)) at every raw pixel centre d.
  cv::Mat raw_px(w * h, 1, CV_64FC2);
  for (int y = 0, i = 0; y < h; ++y)
    for (int x = 0; x < w; ++x, ++i) raw_px.at<cv::Vec2d>(i) = cv::Vec2d(x, y);
  cv::Mat ideal_px;
  cv::undistortPoints(raw_px, ideal_px, camera_matrix_, true_coefficients_, cv::noArray(),
                      camera_matrix_, kUndistortCriteria);
  ideal_px = ideal_px.reshape(2, w * h);
  const cv::Mat redistorted = distort_pixels(ideal_px, camera_matrix_, true_coefficients_);
  cv::Mat map(h, w, CV_32FC2);
  for (int y = 0, i = 0; y < h; ++y) {
    auto* row = map.ptr<cv::Vec2f>(y);
    for (int x = 0; x < w; ++x, ++i) {
      const cv::Vec2d p = ideal_px.at<cv::Vec2d>(i);
      const cv::Vec2d back = redistorted.at<cv::Vec2d>(i);
      const bool ok = std::isfinite(p[0]) && std::isfinite(p[1]) &&
                      std::hypot(back[0] - x, back[1] - y) <= kMaxInverseResidualPx;
      row[x] = ok ? cv::Vec2f(static_cast<float>(p[0]), static_cast<float>(p[1]))
                  : cv::Vec2f(kOutsidePx, kOutsidePx);
    }
  }
  // Fixed-point form: what remap would otherwise convert to on every call.
  cv::convertMaps(map, cv::noArray(), distort_map_xy_, distort_map_frac_, CV_16SC2, false);

  // rect(u) = raw(distort_C(u)): OpenCV's standard rectification map.
  cv::initUndistortRectifyMap(camera_matrix_, calibrated_coefficients_, cv::Matx33d::eye(),
                              camera_matrix_, size, CV_16SC2, rectify_map_xy_, rectify_map_frac_);
}

void LensRoundTrip::check_image(const cv::Mat* image) const {
  DRIFTLAB_DEMAND(image != nullptr);
  if (image->type() != CV_8UC1 || image->cols != options_.width_px ||
      image->rows != options_.height_px)
    throw UserError(fmt::format(
        "lens distortion: got a {}x{} image of OpenCV type {} ({} channel(s)), expected an "
        "8-bit grayscale (CV_8UC1) image of sensors.camera width_px x height_px = {}x{}",
        image->cols, image->rows, image->type(), image->channels(), options_.width_px,
        options_.height_px));
}

namespace {

// dst = src sampled at map (bilinear, black outside). dst has src's size and
// type, so remap writes into its existing pixels; src and dst must differ.
void remap_into(const cv::Mat& src, cv::Mat* dst, const cv::Mat& map_xy, const cv::Mat& map_frac) {
  cv::remap(src, *dst, map_xy, map_frac, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0));
}

}  // namespace

void LensRoundTrip::apply(cv::Mat* image) const {
  check_image(image);
  if (!options_.lens_distortion.enabled) return;
  cv::Mat raw(image->size(), CV_8UC1);
  remap_into(*image, &raw, distort_map_xy_, distort_map_frac_);
  remap_into(raw, image, rectify_map_xy_, rectify_map_frac_);
}

void LensRoundTrip::distort(cv::Mat* image) const {
  check_image(image);
  if (!options_.lens_distortion.enabled) return;
  cv::Mat raw(image->size(), CV_8UC1);
  remap_into(*image, &raw, distort_map_xy_, distort_map_frac_);
  raw.copyTo(*image);  // same size and type: into the caller's pixels
}

void LensRoundTrip::rectify(cv::Mat* image) const {
  check_image(image);
  if (!options_.lens_distortion.enabled) return;
  const cv::Mat raw = image->clone();
  remap_into(raw, image, rectify_map_xy_, rectify_map_frac_);
}

cv::Point2d LensRoundTrip::rectified_position(cv::Point2d ideal_px) const {
  if (!options_.lens_distortion.enabled) return ideal_px;
  const cv::Mat p = (cv::Mat_<cv::Vec2d>(1, 1) << cv::Vec2d(ideal_px.x, ideal_px.y));
  const cv::Mat d = distort_pixels(p, camera_matrix_, true_coefficients_);
  cv::Mat u;
  cv::undistortPoints(d, u, camera_matrix_, calibrated_coefficients_, cv::noArray(), camera_matrix_,
                      kUndistortCriteria);
  const auto& v = u.at<cv::Vec2d>(0);
  return {v[0], v[1]};
}

}  // namespace driftlab::sim
