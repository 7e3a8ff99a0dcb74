// Lens distortion followed by rectification of the rendered 8-bit grayscale
// images: what a real rectified camera stream carries. The lens bends the
// rays (the sensor records a distorted "raw" image), and the driver removes
// the distortion again with the coefficients found by calibration, resampling
// the image a second time. With a perfect calibration the VO gets the pinhole
// image back, softened by the two bilinear resamplings; with a calibration
// error it also gets residual distortion, which bends straight lines and
// biases the geometry.
//
// Distortion model: Brown-Conrady (A. E. Conrady, "Decentred lens-systems",
// Monthly Notices of the Royal Astronomical Society 79, 1919; D. C. Brown,
// "Decentering distortion of lenses", Photogrammetric Engineering 32(3), 1966)
// in OpenCV's parameterisation (OpenCV calib3d documentation, "Camera
// Calibration and 3D Reconstruction", https://docs.opencv.org/4.x/d9/d0c/group__calib3d.html).
// On normalised coordinates x = (u - cx) / fx, y = (v - cy) / fy, r^2 = x^2 + y^2,
// the lens moves the ideal point (x, y) to
//   x_d = x (1 + k1 r^2 + k2 r^4 + k3 r^6) + 2 p1 x y + p2 (r^2 + 2 x^2)
//   y_d = y (1 + k1 r^2 + k2 r^4 + k3 r^6) + p1 (r^2 + 2 y^2) + 2 p2 x y
// (distort_D), in pixels again through the same fx, fy, cx, cy (OpenCV's
// pixel-centre convention, as the renderer's). The inverse (undistort_D) has no
// closed form; cv::undistortPoints iterates it (here to < 1e-9 px or 50 steps).
//
// Images: the rendered image I is the ideal pinhole image. With the true
// coefficients T and the calibrated ones C = T + calibration_error,
//   raw(d)  = I(undistort_T(d))        the image on the sensor,
//   rect(u) = raw(distort_C(u))        the rectified image the VO sees
//                                      (cv::initUndistortRectifyMap, R = I, P = K),
// each a cv::remap with bilinear interpolation and black (0) outside the
// source image. Both sampling maps are computed once. The two resamplings are
// kept separate on purpose: composing them into one map,
// I(undistort_T(distort_C(u))), would sample once and lose the double
// interpolation blur of a real stream. OpenCV's remap quantises sample
// positions to 1/32 px (INTER_BITS) and bilinear weights to 15 bits, as every
// OpenCV-based rectifying driver does; the remap is deterministic (each output
// pixel depends on its map entry only), so equal inputs give equal bytes.
//
// The double resampling also locks the centroid of small features towards the
// pixel grid where the lens compresses them: for a Gaussian blob of sigma
// 1.5 px, up to ~0.07 px in the corners of the default lens (fx 500, 640 x 480;
// < 0.02 px near the centre, < 0.04 px at sigma 2), as exact bilinear
// interpolation in double precision gives too (tests/sim/lens_test.cpp).
//
// An ideal pixel p thus appears in the rectified image at
//   undistort_C(distort_T(p))  (= p when C = T),
// rectified_position(). With the default barrel lens (k1 < 0) the distorted
// image of the whole frame covers the raw corners only partly (they turn
// black), but rectification with P = K looks back inside, so the rectified
// frame is valid up to the outermost pixel; a pincushion lens (k1 > 0) or a
// calibration error can leave black corners.
//
// Not modelled: the rectifying rotation of a stereo pair (stereoRectify's R1,
// R2; the renderer already places parallel cameras), chromatic and
// higher-order (k4..k6, thin-prism, tilt) terms.
#pragma once

#include <opencv2/core.hpp>

#include "sim/sensors/sensor_options.hpp"

namespace driftlab::sim {

/// Distortion then rectification of one camera's images (see file comment).
/// With lens_distortion.enabled false, apply() only checks the image and
/// leaves it unchanged, and rectified_position() is the identity.
class LensRoundTrip {
 public:
  /// Validates `camera` (UserError naming sensors.camera.FIELD) and builds the
  /// two sampling maps (about 0.15 s for 640 x 480 on one core).
  explicit LensRoundTrip(const CameraOptions& camera);

  /// image: CV_8UC1 width_px x height_px (UserError otherwise); replaced in place by the
  /// rectified image the VO sees. Same bytes as distort() then rectify().
  void apply(cv::Mat* image) const;

  /// The two halves of apply(), for effects that happen on the sensor in
  /// between (noise, vignetting): ideal -> raw and raw -> rectified. Same
  /// image requirements; both write into the caller's pixels (views included).
  void distort(cv::Mat* image) const;
  void rectify(cv::Mat* image) const;

  /// Where ideal (pinhole) pixel p appears in the rectified output (for tests and docs):
  /// u = undistort_calibrated(distort_true(p)).
  cv::Point2d rectified_position(cv::Point2d ideal_px) const;

  const CameraOptions& options() const { return options_; }

 private:
  void check_image(const cv::Mat* image) const;

  CameraOptions options_;
  cv::Mat camera_matrix_;      // K, 3x3 CV_64F
  cv::Mat true_coefficients_;  // k1, k2, p1, p2, k3, 1x5 CV_64F
  cv::Mat calibrated_coefficients_;
  // raw(d) = ideal(map(d)) and rect(u) = raw(map(u)), each as OpenCV's
  // fixed-point pair: CV_16SC2 integer positions + CV_16UC1 1/32-px fractions.
  cv::Mat distort_map_xy_, distort_map_frac_;
  cv::Mat rectify_map_xy_, rectify_map_frac_;
};

}  // namespace driftlab::sim
