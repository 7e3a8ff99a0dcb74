#include "sim/sensors/camera_effects.hpp"

#include <fmt/format.h>
#include <boost/math/distributions/normal.hpp>

#include <algorithm>
#include <array>
#include <cmath>

#include "core/error.hpp"
#include "core/rotation.hpp"
#include "sim/vessel/simulator.hpp"

namespace driftlab::sim {
namespace {

// Image noise needs about 600 000 normal variates per stereo pair, and the
// polar method (Rng::normal) costs ~30 ns each. Here a normal variate comes
// from 16 random bits instead (four per 64-bit draw): the index of one of 2^16
// equally probable cells, whose value is the standard normal quantile at the
// cell's centre (i + 1/2) / 2^16 (Boost.Math). This is the standard normal
// quantised to 2^16 cells: variance 0.9996, tails cut at 4.3 sigma, far finer
// than the rounding to whole DN that follows.
const std::array<float, 65536>& normal_quantiles() {
  static const std::array<float, 65536> table = [] {
    std::array<float, 65536> t{};
    const boost::math::normal_distribution<double> n(0.0, 1.0);
    for (std::size_t i = 0; i < t.size(); ++i)
      t[i] = static_cast<float>(boost::math::quantile(n, (static_cast<double>(i) + 0.5) / 65536.0));
    return t;
  }();
  return table;
}

}  // namespace

double image_noise_normal_variance() {
  double v = 0;
  for (float z : normal_quantiles()) v += static_cast<double>(z) * z;
  return v / 65536.0;
}

PhotometricModel::PhotometricModel(const CameraOptions& camera)
    // Validated before any member uses a field (members initialise in order).
    : options_((validate_sensor_options(camera, "sensors.camera"), camera)),
      gain_dn_per_e_(camera.noise.analog_gain * 255.0 / camera.noise.full_well_e),
      signal_scale_(camera.noise.analog_gain * camera.exposure_ms /
                    camera.noise.reference_exposure_ms),
      read_var_e2_(camera.noise.read_noise_e * camera.noise.read_noise_e) {
  if (camera.vignetting_strength > 0) {
    vignetting_.resize(static_cast<std::size_t>(camera.width_px) *
                       static_cast<std::size_t>(camera.height_px));
    std::size_t i = 0;
    for (int y = 0; y < camera.height_px; ++y)
      for (int x = 0; x < camera.width_px; ++x)
        vignetting_[i++] = static_cast<float>(vignetting(x, y));
  }
}

double PhotometricModel::vignetting(double x_px, double y_px) const {
  const double s = options_.vignetting_strength;
  if (s <= 0) return 1.0;
  // cos^2 theta = 1 / (1 + tan^2 theta), tan theta from the normalised image point.
  const double u = (x_px - options_.cx_px) / options_.fx_px;
  const double v = (y_px - options_.cy_px) / options_.fy_px;
  const double cos2 = 1.0 / (1.0 + u * u + v * v);
  return 1.0 - s * (1.0 - cos2 * cos2);
}

double PhotometricModel::noise_variance_dn2(double mean_dn) const {
  if (!options_.noise.enabled) return 0.0;
  const double k = gain_dn_per_e_;
  return k * mean_dn + k * k * read_var_e2_ + 1.0 / 12.0;
}

double next_auto_exposure_ms(const AutoExposureOptions& o, double exposure_ms,
                             double image_mean_dn) {
  // The image mean is proportional to the exposure away from clipping: the
  // exposure that hits the target is exposure * target / mean. A saturated or
  // black image gives a mean that understates the step; the loop still moves
  // the right way and gets there over frames.
  const double mean = std::max(image_mean_dn, 0.5);
  const double wanted = exposure_ms * o.target_mean_dn / mean;
  const double next =
      std::exp(std::log(exposure_ms) + o.response * (std::log(wanted) - std::log(exposure_ms)));
  return std::clamp(next, o.min_exposure_ms, o.max_exposure_ms);
}

void PhotometricModel::apply(cv::Mat* image, Rng* rng, double exposure_ms) const {
  DRIFTLAB_DEMAND(image != nullptr && rng != nullptr);
  if (image->type() != CV_8UC1 || image->cols != options_.width_px ||
      image->rows != options_.height_px)
    throw UserError(fmt::format(
        "camera image: got a {}x{} image of OpenCV type {}, expected an 8-bit grayscale "
        "(CV_8UC1) image of sensors.camera width_px x height_px = {}x{}",
        image->cols, image->rows, image->type(), options_.width_px, options_.height_px));
  const bool noisy = options_.noise.enabled;
  const double k = gain_dn_per_e_;
  // Without vignetting the mean and noise depend on the input value only.
  const double scale =
      options_.noise.analog_gain * exposure_ms / options_.noise.reference_exposure_ms;
  std::array<double, 256> mean_lut{}, sd_lut{};
  for (int v = 0; v < 256; ++v) {
    mean_lut[v] = v * scale;
    sd_lut[v] = k * std::sqrt(mean_lut[v] / k + read_var_e2_);
  }
  const auto& z = normal_quantiles();
  std::uint64_t bits = 0;
  int left_in_bits = 0;  // 16-bit variates left in `bits`
  std::size_t i = 0;
  for (int y = 0; y < image->rows; ++y) {
    auto* row = image->ptr<std::uint8_t>(y);
    for (int x = 0; x < image->cols; ++x, ++i) {
      const int v = row[x];
      double mean, sd;
      if (vignetting_.empty()) {
        mean = mean_lut[v];
        sd = sd_lut[v];
      } else {
        mean = mean_lut[v] * vignetting_[i];
        sd = k * std::sqrt(mean / k + read_var_e2_);
      }
      // Shot and read noise are independent Gaussians: one draw of their
      // combined standard deviation K sqrt(mu_e + sigma_r^2).
      double out = mean;
      if (noisy) {
        if (left_in_bits == 0) {
          bits = rng->next_u64();
          left_in_bits = 4;
        }
        out += sd * z[bits & 0xFFFFu];
        bits >>= 16;
        --left_in_bits;
      }
      row[x] = static_cast<std::uint8_t>(std::clamp(std::nearbyint(out), 0.0, 255.0));
    }
  }
}

CameraImageNoise::CameraImageNoise(const CameraOptions& camera, const RngStreams& rng,
                                   const std::string& name)
    : model_(camera), rng_(rng.stream(name + ".noise")) {}

SE3 nominal_T_left_right(const CameraOptions& camera) {
  return SE3::from_translation(Vec3(camera.baseline_m, 0, 0));
}

SE3 true_T_left_right(const CameraOptions& camera) {
  const auto& e = camera.calibration_error;
  const Vec3 rotvec(deg2rad(e.right_rotation_error_deg[0]), deg2rad(e.right_rotation_error_deg[1]),
                    deg2rad(e.right_rotation_error_deg[2]));
  return SE3(so3_exp(rotvec), Vec3(camera.baseline_m + e.baseline_error_m, 0, 0));
}

std::vector<SampleTime> camera_frame_times(const CameraOptions& camera, const RngStreams& rng,
                                           double end_s) {
  validate_sensor_options(camera, "sensors.camera");
  return stamp_times(sample_times(camera.rate_hz, end_s), camera.clock, rng, "camera");
}

}  // namespace driftlab::sim
