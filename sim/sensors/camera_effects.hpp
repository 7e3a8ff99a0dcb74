// Camera effects applied after rendering: photometric noise and vignetting on
// 8-bit grayscale images, the stereo miscalibration the renderer should place
// the right camera with, and frame timing (clock offset, jitter, dropped frames).
//
// Photometric model (EMVA Standard 1288, linear camera): the input image is
// the scene as recorded at reference_exposure_ms and unit gain. A pixel of
// input value v at (x, y) collects on average
//   mu_e = v / 255 * full_well_e * (exposure_ms / reference_exposure_ms) * V(x, y)
// electrons, Poisson distributed (shot noise, approximated by a Gaussian of
// variance mu_e, accurate for the tens of electrons and more of a lit scene),
// plus Gaussian read noise of read_noise_e. The output is
//   DN = clip(round(K (mu_e + noise)), 0, 255),  K = analog_gain * 255 / full_well_e,
// so the mean is v * analog_gain * exposure_ms / reference_exposure_ms * V and,
// away from clipping, the variance is K^2 (mu_e + read_noise_e^2) + 1/12 DN^2
// (the last term: rounding to integers, Sheppard's correction).
// Vignetting: V = 1 - s (1 - cos^4 theta), theta the pixel's field angle in the
// pinhole model, s = vignetting_strength (the cos^4 law of natural illumination
// fall-off, e.g. Hecht, "Optics").
//
// Elsewhere: motion blur (sub-frame renders, pipeline/camera_stage.hpp) and
// lens distortion with rectification (sim/sensors/lens.hpp). Not modelled:
// rolling shutter.
#pragma once

#include <opencv2/core.hpp>

#include <string>
#include <vector>

#include "core/rng.hpp"
#include "core/se3.hpp"
#include "sim/sensors/clock.hpp"
#include "sim/sensors/sensor_options.hpp"

namespace driftlab::sim {

/// The photometric model of one camera (see the file comment).
class PhotometricModel {
 public:
  /// Validates `camera` (UserError naming sensors.camera.FIELD).
  explicit PhotometricModel(const CameraOptions& camera);

  /// K: digital numbers per electron.
  double system_gain_dn_per_e() const { return gain_dn_per_e_; }
  /// analog_gain * exposure_ms / reference_exposure_ms: brightness scale of the output.
  double signal_scale() const { return signal_scale_; }
  /// V(x, y) in (0, 1] at pixel (x, y) (OpenCV pixel-centre coordinates).
  double vignetting(double x_px, double y_px) const;
  /// Mean output [DN] (before clipping) of input value `input_dn` at (x, y).
  double mean_dn(double input_dn, double x_px, double y_px) const {
    return input_dn * signal_scale_ * vignetting(x_px, y_px);
  }
  /// Variance [DN^2] of the output around a mean of `mean_dn`, away from
  /// clipping: K mean + K^2 read_noise^2 + 1/12; 0 with noise disabled.
  double noise_variance_dn2(double mean_dn) const;

  /// Applies gain, exposure, vignetting and (when enabled) noise to `image` in
  /// place, one normal variate per pixel in row-major order, four per 64-bit
  /// draw from `rng` (a 2^16-cell quantised normal, see
  /// image_noise_normal_variance). The image must be CV_8UC1 of width_px x
  /// height_px (UserError otherwise).
  void apply(cv::Mat* image, Rng* rng) const { apply(image, rng, options_.exposure_ms); }
  /// The same at another exposure (auto exposure) [ms].
  void apply(cv::Mat* image, Rng* rng, double exposure_ms) const;

  const CameraOptions& options() const { return options_; }

 private:
  CameraOptions options_;
  double gain_dn_per_e_;
  double signal_scale_;
  double read_var_e2_;
  std::vector<float> vignetting_;  // row-major V(x, y); empty when strength is 0
};

/// Variance of the quantised standard normal the image noise draws from
/// (0.9996: 2^16 equally probable cells at their centre quantiles).
double image_noise_normal_variance();

/// The auto-exposure loop of sensors.camera.auto_exposure: next exposure from
/// the current one and the mean of the image it gave (see AutoExposureOptions).
double next_auto_exposure_ms(const AutoExposureOptions& options, double exposure_ms,
                             double image_mean_dn);

/// One camera's photometric effects with its own stream (NAME.noise, e.g.
/// "camera.left.noise"), so that left and right noise are independent and
/// neither depends on the other sensors.
class CameraImageNoise {
 public:
  CameraImageNoise(const CameraOptions& camera, const RngStreams& rng, const std::string& name);
  void apply(cv::Mat* image) { model_.apply(image, &rng_); }
  void apply(cv::Mat* image, double exposure_ms) { model_.apply(image, &rng_, exposure_ms); }
  const PhotometricModel& model() const { return model_; }

 private:
  PhotometricModel model_;
  Rng rng_;
};

/// Pose of the right camera in the left one as the VO is told: baseline_m
/// along the left optical x, parallel axes.
SE3 nominal_T_left_right(const CameraOptions& camera);
/// Pose of the right camera in the left one as the renderer should place it:
/// baseline_m + baseline_error_m along x, turned by right_rotation_error_deg
/// (a rotation vector in the left optical frame).
SE3 true_T_left_right(const CameraOptions& camera);

/// Frame times from 0 to `end_s` at rate_hz, stamped by the camera's clock
/// (stream prefix "camera": both images of a stereo pair share one trigger,
/// one stamp and one drop). Dropped frames are included with dropped = true.
std::vector<SampleTime> camera_frame_times(const CameraOptions& camera, const RngStreams& rng,
                                           double end_s);

}  // namespace driftlab::sim
