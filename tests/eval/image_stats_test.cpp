// The image statistics against images whose statistics are known analytically: fractal noise of
// a chosen spectrum, white noise, a checkerboard, a texture and its mirror image.
#include "eval/image_stats.hpp"

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <random>

#include <gtest/gtest.h>

namespace driftlab::eval {
namespace {

// Noise whose power falls as f^-beta: random complex amplitudes scaled by f^(-beta/2), the real
// part of their inverse DFT.
cv::Mat fractal_noise(int width, int height, double beta, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> normal;
  cv::Mat spectrum(height, width, CV_32FC2);
  for (int ky = 0; ky < height; ++ky)
    for (int kx = 0; kx < width; ++kx) {
      const double fx = (kx <= width / 2 ? kx : kx - width) / static_cast<double>(width);
      const double fy = (ky <= height / 2 ? ky : ky - height) / static_cast<double>(height);
      const double f = std::hypot(fx, fy);
      const float gain = f > 0 ? static_cast<float>(std::pow(f, -beta / 2)) : 0.0f;
      spectrum.at<cv::Vec2f>(ky, kx) = {gain * normal(rng), gain * normal(rng)};
    }
  cv::Mat image;
  cv::dft(spectrum, image, cv::DFT_INVERSE | cv::DFT_REAL_OUTPUT | cv::DFT_SCALE);
  return image;
}

cv::Mat white_noise(int width, int height, double sigma, unsigned seed) {
  cv::Mat image(height, width, CV_32F);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::NORMAL, 100.0, sigma);
  return image;
}

TEST(ImageStats, SpectrumSlopeOfFractalNoiseIsItsExponent) {
  const ImageStatsOptions options;
  for (const double beta : {1.5, 2.0, 2.5}) {
    const cv::Mat image = fractal_noise(options.width_px, options.height_px, beta, 7);
    const SpectrumFit fit = power_spectrum_slope(image, options);
    EXPECT_NEAR(fit.slope, -beta, 0.03) << "beta " << beta;
    EXPECT_GT(fit.r2, 0.98) << "beta " << beta;
  }
}

// Sobel / 8 of white noise of SD sigma: each component has SD sigma sqrt(12/64), the two are
// independent, so the magnitude is Rayleigh: median s sqrt(2 ln 2), 90th percentile
// s sqrt(2 ln 10). A plain difference of Gaussian noise has kurtosis 3.
TEST(ImageStats, GradientsOfWhiteNoiseFollowTheRayleighLaw) {
  const ImageStatsOptions options;
  const double sigma = 20.0;
  const ImageStats s =
      image_stats(white_noise(options.width_px, options.height_px, sigma, 3), options);
  const double scale = sigma * std::sqrt(12.0 / 64.0);
  EXPECT_NEAR(s.gradient_median, scale * std::sqrt(2 * std::log(2.0)), 0.01 * scale);
  EXPECT_NEAR(s.gradient_p90, scale * std::sqrt(2 * std::log(10.0)), 0.01 * scale);
  EXPECT_NEAR(s.derivative_kurtosis, 3.0, 0.05);
  // White noise has a flat spectrum.
  EXPECT_NEAR(s.spectrum_slope, 0.0, 0.05);
}

TEST(ImageStats, CornersOfACheckerboardAreItsInnerCornersOnce) {
  ImageStatsOptions options;
  options.width_px = 1000;
  options.height_px = 750;
  const int square = 25;
  cv::Mat board(options.height_px, options.width_px, CV_32F);
  for (int y = 0; y < board.rows; ++y)
    for (int x = 0; x < board.cols; ++x)
      board.at<float>(y, x) = ((x / square + y / square) % 2 == 0) ? 40.0f : 200.0f;
  cv::GaussianBlur(board, board, cv::Size(0, 0), 1.0);
  const ImageStats s = image_stats(board, options);
  // Inner corners: (1000/25 - 1) x (750/25 - 1) = 39 x 29, over 20 x 15 cells.
  EXPECT_NEAR(s.corners_per_cell, 39.0 * 29.0 / 300.0, 1e-9);
  EXPECT_EQ(s.empty_cell_fraction, 0.0);

  const cv::Mat flat(options.height_px, options.width_px, CV_32F, cv::Scalar(90));
  const ImageStats f = image_stats(flat, options);
  EXPECT_EQ(f.corners_per_cell, 0.0);
  EXPECT_EQ(f.empty_cell_fraction, 1.0);
  EXPECT_EQ(f.mirror_fraction, 0.0);
}

// Above row 400 a texture; below, its mirror image, darker, offset, blurred and noisy as a
// reflection on water. The 10 rows next to the waterline are left out (the 6 of the step from
// bank to water and half a 9x9 patch), so the expected share is (768 - 410) / 768.
TEST(ImageStats, MirrorFractionIsTheReflectedPartOfTheImage) {
  const ImageStatsOptions options;
  const int waterline = 400;
  cv::Mat texture = white_noise(options.width_px, options.height_px, 40.0, 11);
  cv::GaussianBlur(texture, texture, cv::Size(0, 0), 1.5);
  cv::Mat scene = texture.clone();
  for (int y = waterline; y < scene.rows; ++y)
    for (int x = 0; x < scene.cols; ++x)
      scene.at<float>(y, x) = 20.0f + 0.6f * texture.at<float>(2 * waterline - 1 - y, x);
  cv::Mat lower = scene.rowRange(waterline, scene.rows);
  cv::GaussianBlur(lower, lower, cv::Size(0, 0), 0.8);
  lower += white_noise(lower.cols, lower.rows, 1.0, 12) - 100.0;
  const double expected = (768.0 - 410.0) / 768.0;
  EXPECT_NEAR(image_stats(scene, options).mirror_fraction, expected, 0.015);

  // The same texture with an unrelated one below: nothing is a mirror image.
  cv::Mat unrelated = texture.clone();
  white_noise(options.width_px, options.height_px - waterline, 40.0, 13)
      .copyTo(unrelated.rowRange(waterline, unrelated.rows));
  cv::GaussianBlur(unrelated, unrelated, cv::Size(0, 0), 1.5);
  EXPECT_LT(image_stats(unrelated, options).mirror_fraction, 0.005);

  // Structure that does not change down the image (trunks, poles, vertical edges) is its own
  // mirror image about every row in intensity; on the vertical gradient it is not a mirror.
  cv::Mat stripes(options.height_px, options.width_px, CV_32F);
  const cv::Mat columns = white_noise(options.width_px, 1, 40.0, 14);
  for (int y = 0; y < stripes.rows; ++y) columns.copyTo(stripes.row(y));
  stripes += white_noise(options.width_px, options.height_px, 3.0, 15);
  EXPECT_LT(image_stats(stripes, options).mirror_fraction, 0.005);
}

TEST(ImageStats, AnalysedImageIsTheCentreCropAtTheAnalysedSize) {
  const ImageStatsOptions options;
  // 2560x1600 is 16:10; its 4:3 centre is 2133 px wide, starting at x = 213.
  cv::Mat wide(1600, 2560, CV_8U, cv::Scalar(0));
  wide.colRange(213, 213 + 2133).setTo(255);
  const cv::Mat out = analysed_image(wide, options);
  ASSERT_EQ(out.cols, 1024);
  ASSERT_EQ(out.rows, 768);
  double lo = 0, hi = 0;
  cv::minMaxLoc(out, &lo, &hi);
  EXPECT_EQ(lo, 255.0);
  // A tall image is cropped top and bottom.
  cv::Mat tall(2000, 600, CV_8U, cv::Scalar(0));
  tall.rowRange(775, 775 + 450).setTo(255);
  cv::minMaxLoc(analysed_image(tall, options), &lo, &hi);
  EXPECT_EQ(lo, 255.0);
}

}  // namespace
}  // namespace driftlab::eval
