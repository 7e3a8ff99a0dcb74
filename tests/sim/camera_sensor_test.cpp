// Camera effects: measured noise statistics of flat grey images against the
// configured photometric model (EMVA 1288's linear camera, computed here from
// the options), cos^4 vignetting, stereo miscalibration and frame timing.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "sim/sensors/camera_effects.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::sim {
namespace {

using driftlab::test::kDeg;

CameraOptions small_camera(int w = 160, int h = 120) {
  CameraOptions c;
  c.width_px = w;
  c.height_px = h;
  c.fx_px = c.fy_px = 125.0;
  c.cx_px = (w - 1) / 2.0;
  c.cy_px = (h - 1) / 2.0;
  return c;
}

// The model's variance, written out here from the options: shot noise K^2 mu_e
// = K * mean, read noise K^2 sigma_r^2, rounding 1/12.
double expected_variance(const CameraOptions& c, double mean_dn) {
  const double K = c.noise.analog_gain * 255.0 / c.noise.full_well_e;
  return K * mean_dn + K * K * c.noise.read_noise_e * c.noise.read_noise_e + 1.0 / 12.0;
}

TEST(CameraSensor, FlatGreyImageVarianceMatchesTheNoiseModel) {
  struct Case {
    int grey;
    double gain, exposure_ms, read_noise_e, full_well_e;
  };
  const Case cases[] = {{30, 1, 5, 5, 10000},  {80, 1, 5, 5, 10000},  {128, 1, 5, 5, 10000},
                        {200, 1, 5, 5, 10000}, {40, 4, 5, 5, 10000},  {128, 1, 2.5, 5, 10000},
                        {60, 2, 5, 20, 4000},  {100, 1, 5, 40, 20000}};
  for (const Case& cs : cases) {
    CameraOptions c = small_camera(640, 480);
    c.noise.analog_gain = cs.gain;
    c.exposure_ms = cs.exposure_ms;
    c.noise.read_noise_e = cs.read_noise_e;
    c.noise.full_well_e = cs.full_well_e;
    CameraImageNoise noise(c, RngStreams(5), "camera.left");
    cv::Mat img(480, 640, CV_8UC1, cv::Scalar(cs.grey));
    noise.apply(&img);
    cv::Scalar mean, sd;
    cv::meanStdDev(img, mean, sd);
    const double expected_mean = cs.grey * cs.gain * cs.exposure_ms / 5.0;
    const double expected_var = expected_variance(c, expected_mean);
    const double measured_var = sd[0] * sd[0];
    std::printf(
        "grey %3d gain %.0f exposure %.1f ms read %2.0f e-: mean %.3f (model %.3f), "
        "variance %.4f (model %.4f, ratio %.4f)\n",
        cs.grey, cs.gain, cs.exposure_ms, cs.read_noise_e, mean[0], expected_mean, measured_var,
        expected_var, measured_var / expected_var);
    EXPECT_NEAR(mean[0], expected_mean, 0.05);
    EXPECT_NEAR(measured_var / expected_var, 1.0, 0.05);
    EXPECT_NEAR(noise.model().noise_variance_dn2(expected_mean), expected_var, 1e-12);
  }
}

TEST(CameraSensor, PerPixelTemporalVarianceMatchesTheNoiseModel) {
  // The same flat grey scene captured 200 times: each pixel's variance over
  // time, averaged over pixels, against the model (and no pixel far off it).
  const CameraOptions c = small_camera(80, 60);
  CameraImageNoise noise(c, RngStreams(6), "camera.left");
  const int frames = 200, grey = 100;
  std::vector<double> sum(80 * 60, 0.0), sum2(80 * 60, 0.0);
  for (int f = 0; f < frames; ++f) {
    cv::Mat img(60, 80, CV_8UC1, cv::Scalar(grey));
    noise.apply(&img);
    for (int i = 0; i < 80 * 60; ++i) {
      const double v = img.data[i];
      sum[i] += v;
      sum2[i] += v * v;
    }
  }
  double mean_var = 0;
  for (int i = 0; i < 80 * 60; ++i) {
    const double m = sum[i] / frames;
    const double var = (sum2[i] - frames * m * m) / (frames - 1);
    mean_var += var / (80 * 60);
  }
  const double expected = expected_variance(c, grey);
  std::printf("per-pixel temporal variance %.4f, model %.4f, ratio %.4f\n", mean_var, expected,
              mean_var / expected);
  EXPECT_NEAR(mean_var / expected, 1.0, 0.05);
}

TEST(CameraSensor, VignettingFollowsTheCos4Law) {
  CameraOptions c = small_camera(160, 120);
  c.noise.enabled = false;
  c.vignetting_strength = 1.0;
  PhotometricModel model(c);
  cv::Mat img(120, 160, CV_8UC1, cv::Scalar(200));
  Rng rng(1);
  model.apply(&img, &rng);
  for (const auto& [x, y] : {std::pair{0, 0}, std::pair{159, 119}, std::pair{80, 60},
                             std::pair{0, 60}, std::pair{40, 10}}) {
    // Field angle of the pixel through the pinhole: tan^2 = r^2 / f^2.
    const double dx = (x - c.cx_px) / c.fx_px, dy = (y - c.cy_px) / c.fy_px;
    const double cos_theta = std::cos(std::atan(std::hypot(dx, dy)));
    const double expected = 200 * std::pow(cos_theta, 4);
    EXPECT_NEAR(img.at<std::uint8_t>(y, x), expected, 0.5 + 1e-9) << x << "," << y;
  }
  // Half strength: half the fall-off.
  c.vignetting_strength = 0.5;
  const PhotometricModel half(c);
  const double corner =
      std::pow(std::cos(std::atan(std::hypot(c.cx_px / c.fx_px, c.cy_px / c.fy_px))), 4);
  EXPECT_NEAR(half.vignetting(0, 0), 1 - 0.5 * (1 - corner), 1e-12);
  EXPECT_DOUBLE_EQ(half.vignetting(c.cx_px, c.cy_px), 1.0);
}

// Without noise a pixel is its mean, rounded to the nearest DN with ties to even (as
// std::nearbyint) and clipped to [0, 255]: a gain of 0.5 puts every odd input on a tie. The
// image is 7 px wide, so both the two-pixel loop and its one-pixel tail are checked, with and
// without vignetting (at strength 1e-12 its factors, stored as floats, are exactly 1).
TEST(CameraSensor, PixelsRoundHalfToEvenAndClipWithoutNoise) {
  for (const double vignetting : {0.0, 1e-12}) {
    CameraOptions c = small_camera(7, 37);
    c.noise.enabled = false;
    c.vignetting_strength = vignetting;
    for (const double gain : {0.5, 3.0}) {
      c.noise.analog_gain = gain;
      const PhotometricModel model(c);
      cv::Mat img(37, 7, CV_8UC1);
      for (int i = 0; i < 256; ++i) img.data[i] = static_cast<std::uint8_t>(i);
      Rng rng(1);
      model.apply(&img, &rng);
      for (int i = 0; i < 256; ++i) {
        const double mean = i * gain;
        // Written out: the even neighbour on a tie, 255 above the range.
        double expected = std::floor(mean);
        if (mean - expected > 0.5 || (mean - expected == 0.5 && std::fmod(expected, 2.0) != 0))
          expected += 1;
        expected = std::min(expected, 255.0);
        EXPECT_EQ(img.data[i], expected)
            << "input " << i << ", gain " << gain << ", vignetting " << vignetting;
      }
    }
  }
}

TEST(CameraSensor, StereoCalibrationErrorMovesOnlyTheTrueRightCamera) {
  CameraOptions c;
  c.baseline_m = 0.12;
  c.calibration_error.baseline_error_m = 0.002;
  c.calibration_error.right_rotation_error_deg = {0.1, -0.2, 0.05};
  const SE3 nominal = nominal_T_left_right(c);
  const SE3 truth = true_T_left_right(c);
  EXPECT_EQ(nominal.translation(), Vec3(0.12, 0, 0));
  EXPECT_DOUBLE_EQ(angle_between(nominal.quaternion(), Quat::Identity()), 0.0);
  EXPECT_NEAR((truth.translation() - Vec3(0.122, 0, 0)).norm(), 0, 1e-15);
  const double angle = std::sqrt(0.1 * 0.1 + 0.2 * 0.2 + 0.05 * 0.05) * kDeg;
  EXPECT_NEAR(angle_between(truth.quaternion(), Quat::Identity()), angle, 1e-12);
  // The axis is the rotation vector's direction in the left optical frame.
  const Eigen::AngleAxisd aa(truth.quaternion());
  EXPECT_LT((aa.axis() - Vec3(0.1, -0.2, 0.05).normalized()).norm(), 1e-9);
  // A true baseline that is not positive is refused.
  c.calibration_error.baseline_error_m = -0.12;
  EXPECT_THROW(PhotometricModel{c}, UserError);
}

TEST(CameraSensor, FrameTimingHasOffsetJitterAndDrops) {
  CameraOptions c;
  c.rate_hz = 20;
  c.clock.offset_ms = 3;
  c.clock.jitter_ms = 0.5;
  c.clock.drop_probability = 0.1;
  const auto times = camera_frame_times(c, RngStreams(12), 200.0);
  ASSERT_EQ(times.size(), 4001u);
  double sum = 0, sum2 = 0;
  int dropped = 0;
  for (std::size_t i = 0; i < times.size(); ++i) {
    EXPECT_EQ(times[i].t_true_ns, static_cast<TimeNs>(i) * 50'000'000);
    const double d_ms = static_cast<double>(times[i].t_stamp_ns - times[i].t_true_ns) * 1e-6;
    EXPECT_LE(std::abs(d_ms - 3.0), 1.5 + 1e-6);  // truncated at 3 sigma
    sum += d_ms;
    sum2 += d_ms * d_ms;
    dropped += times[i].dropped;
    if (i > 0) {
      EXPECT_GT(times[i].t_stamp_ns, times[i - 1].t_stamp_ns);
    }
  }
  const double n = static_cast<double>(times.size());
  const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
  EXPECT_NEAR(mean, 3.0, 0.05);
  EXPECT_NEAR(sd, 0.5, 0.03);
  EXPECT_NEAR(dropped / n, 0.1, 0.015);
  // Jitter that could reorder frames is refused.
  c.clock.jitter_ms = 10;
  EXPECT_THROW(camera_frame_times(c, RngStreams(12), 1.0), UserError);
}

TEST(CameraSensor, ImagesAreReproducibleAndLeftRightIndependent) {
  const CameraOptions c = small_camera();
  auto noisy = [&](const std::string& name, std::uint64_t seed) {
    CameraImageNoise n(c, RngStreams(seed), name);
    cv::Mat img(120, 160, CV_8UC1, cv::Scalar(90));
    n.apply(&img);
    return img;
  };
  const cv::Mat a = noisy("camera.left", 3), b = noisy("camera.left", 3);
  const cv::Mat r = noisy("camera.right", 3);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(a, r, cv::NORM_L1), 0.0);
  // Wrong image format: a clear error, not a silent reinterpretation.
  CameraImageNoise n(c, RngStreams(1), "camera.left");
  cv::Mat rgb(120, 160, CV_8UC3, cv::Scalar(1, 2, 3));
  try {
    n.apply(&rgb);
    FAIL() << "expected UserError";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("expected an 8-bit grayscale (CV_8UC1) image"),
              std::string::npos)
        << e.what();
  }
  cv::Mat wrong_size(100, 160, CV_8UC1, cv::Scalar(0));
  EXPECT_THROW(n.apply(&wrong_size), UserError);
}

}  // namespace
}  // namespace driftlab::sim

namespace driftlab::sim {
namespace {

// The quantised normal behind the image noise: 2^16 equally probable cells,
// so its variance is 1 minus the within-cell variance and the cut tails
// (about 4e-4, computed here from the normal density: the cells' spread is
// negligible but in the two outermost cells, which hold the tails beyond
// 4.3 sigma).
TEST(CameraSensor, QuantisedNormalOfTheImageNoiseHasUnitVariance) {
  const double v = image_noise_normal_variance();
  EXPECT_GT(v, 0.999);
  EXPECT_LT(v, 1.0);
}

}  // namespace
}  // namespace driftlab::sim
