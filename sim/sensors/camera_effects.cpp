#include "sim/sensors/camera_effects.hpp"

#include <fmt/format.h>
#include <boost/math/distributions/normal.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "core/error.hpp"
#include "core/rotation.hpp"
#include "sim/physics/vessel/simulator.hpp"

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

// nearbyint(x) clamped to [0, 255], as a byte. Clamping first changes nothing (the bounds are
// whole numbers), and for 0 <= x < 2^51 adding 2^52 rounds x to the nearest whole number, ties
// to even, exactly as nearbyint does in the default rounding mode (a double at 2^52 has no
// fraction bits), and leaves that number in the low bits of the sum. nearbyint is a library
// call on x86-64 without SSE4.1, and std::clamp compiles to branches: together most of apply()'s
// time before.
constexpr double kTwo52 = 4503599627370496.0;

inline std::uint8_t round_to_dn(double x) {
  const double c = x < 0.0 ? 0.0 : (x > 255.0 ? 255.0 : x);
  return static_cast<std::uint8_t>(std::bit_cast<std::uint64_t>(c + kTwo52));
}

// The clamped, rounded pixels of v = m + s z, two at a time.
#if defined(__SSE2__)
inline void store_two(__m128d v, std::uint8_t* out) {
  const __m128i n = _mm_castpd_si128(_mm_add_pd(
      _mm_min_pd(_mm_max_pd(v, _mm_setzero_pd()), _mm_set1_pd(255.0)), _mm_set1_pd(kTwo52)));
  out[0] = static_cast<std::uint8_t>(_mm_cvtsi128_si32(n));
  out[1] = static_cast<std::uint8_t>(_mm_extract_epi16(n, 4));
}
#endif

// One row without vignetting: pixel value v has mean mean_lut[v] and noise sd sd_lut[v] [DN];
// row[x] becomes round_to_dn(mean + sd z[x]).
void write_row(std::uint8_t* row, const double* z, std::size_t cols,
               const std::array<double, 256>& mean_lut, const std::array<double, 256>& sd_lut) {
  std::size_t x = 0;
#if defined(__SSE2__)
  for (; x + 2 <= cols; x += 2) {
    const __m128d m = _mm_set_pd(mean_lut[row[x + 1]], mean_lut[row[x]]);
    const __m128d s = _mm_set_pd(sd_lut[row[x + 1]], sd_lut[row[x]]);
    store_two(_mm_add_pd(m, _mm_mul_pd(s, _mm_loadu_pd(z + x))), row + x);
  }
#endif
  for (; x < cols; ++x) row[x] = round_to_dn(mean_lut[row[x]] + sd_lut[row[x]] * z[x]);
}

// One row with vignetting V (vig[x]): mean mean_lut[v] V, noise sd k sqrt(mean / k + read_var)
// [DN] (k the system gain [DN/e-], read_var the read noise variance [e-^2]).
void write_row_vignetted(std::uint8_t* row, const double* z, std::size_t cols,
                         const std::array<double, 256>& mean_lut, const float* vig, double k,
                         double read_var) {
  std::size_t x = 0;
#if defined(__SSE2__)
  const __m128d kk = _mm_set1_pd(k), r = _mm_set1_pd(read_var);
  for (; x + 2 <= cols; x += 2) {
    const __m128d m = _mm_mul_pd(_mm_set_pd(mean_lut[row[x + 1]], mean_lut[row[x]]),
                                 _mm_set_pd(vig[x + 1], vig[x]));
    const __m128d s = _mm_mul_pd(kk, _mm_sqrt_pd(_mm_add_pd(_mm_div_pd(m, kk), r)));
    store_two(_mm_add_pd(m, _mm_mul_pd(s, _mm_loadu_pd(z + x))), row + x);
  }
#endif
  for (; x < cols; ++x) {
    const double mean = mean_lut[row[x]] * vig[x];
    row[x] = round_to_dn(mean + k * std::sqrt(mean / k + read_var) * z[x]);
  }
}

// Standard normal variates from normal_quantiles(), 16 random bits each, four per 64-bit draw
// of the generator, in the order the pixels take them.
class NormalVariates {
 public:
  explicit NormalVariates(Rng* rng) : rng_(rng), table_(normal_quantiles()) {}
  double next() {
    if (left_ == 0) {
      bits_ = rng_->next_u64();
      left_ = 4;
    }
    const float z = table_[bits_ & 0xFFFFu];
    bits_ >>= 16;
    --left_;
    return z;
  }

 private:
  Rng* rng_;
  const std::array<float, 65536>& table_;
  std::uint64_t bits_ = 0;
  int left_ = 0;  // 16-bit variates left in bits_
};

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
  // Row by row: the variates first (the draws are serial), then the pixels. Shot and read
  // noise are independent Gaussians: one draw of their combined standard deviation
  // K sqrt(mu_e + sigma_r^2). Without noise z is 0 and each pixel its mean.
  const std::size_t cols = static_cast<std::size_t>(image->cols);
  std::vector<double> z(cols, 0.0);
  NormalVariates variates(rng);
  for (int y = 0; y < image->rows; ++y) {
    std::uint8_t* row = image->ptr<std::uint8_t>(y);
    if (noisy)
      for (std::size_t x = 0; x < cols; ++x) z[x] = variates.next();
    if (vignetting_.empty())
      write_row(row, z.data(), cols, mean_lut, sd_lut);
    else
      write_row_vignetted(row, z.data(), cols, mean_lut,
                          vignetting_.data() + static_cast<std::size_t>(y) * cols, k, read_var_e2_);
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
