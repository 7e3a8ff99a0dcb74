// The overcast sky's cloud deck (scenes/sky_clouds.hpp) and the river reach's sky.
#include "scenes/sky_clouds.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include <opencv2/core.hpp>

#include "scenes/river_reach.hpp"
#include "scenes/scene_options.hpp"

namespace driftlab::scenes {
namespace {

double texel(const sim::Texture& t, int x, int y) {
  return t.pixels[static_cast<std::size_t>(((y % t.height) + t.height) % t.height) * t.width +
                  static_cast<std::size_t>(((x % t.width) + t.width) % t.width)];
}

TEST(CloudLayer, IsAPureFunctionOfTheSeedWithUnitStatistics) {
  const sim::Texture a = bake_cloud_layer(11), b = bake_cloud_layer(11), c = bake_cloud_layer(12);
  ASSERT_EQ(a.width, 512);
  ASSERT_EQ(a.height, 512);
  EXPECT_EQ(a.pixels, b.pixels);
  EXPECT_NE(a.pixels, c.pixels);
  // Stored as 128 + 32 n with n of zero mean and unit variance.
  double sum = 0, sum2 = 0;
  for (std::uint8_t p : a.pixels) sum += p;
  const double mean = sum / static_cast<double>(a.pixels.size());
  for (std::uint8_t p : a.pixels) sum2 += (p - mean) * (p - mean);
  EXPECT_NEAR(mean, 128, 1);
  EXPECT_NEAR(std::sqrt(sum2 / static_cast<double>(a.pixels.size())), 32, 1);
}

TEST(CloudLayer, TilesWithoutASeam) {
  const sim::Texture t = bake_cloud_layer(5);
  const int n = t.width;
  for (const bool across_x : {true, false}) {
    const auto diff = [&](int i0, int i1) {  // mean |difference| of two columns (rows)
      double d = 0;
      for (int j = 0; j < n; ++j)
        d += across_x ? std::abs(texel(t, i1, j) - texel(t, i0, j))
                      : std::abs(texel(t, j, i1) - texel(t, j, i0));
      return d / n;
    };
    double mean = 0;
    for (int i = 0; i + 1 < n; ++i) mean += diff(i, i + 1) / (n - 1);
    EXPECT_LT(diff(n - 1, 0), 1.5 * mean) << (across_x ? "left/right" : "top/bottom");
  }
}

TEST(CloudLayer, PowerFallsAsStratocumulus) {
  // Radially averaged 2D power spectrum (OpenCV's DFT), fitted in log-log over the octaves
  // the texture has (6 to 48 cycles a tile): f^(-8/3), the 2D form of the k^(-5/3) spectrum of
  // liquid water path (Cahalan and Snider 1989).
  const sim::Texture t = bake_cloud_layer(3);
  const int n = t.width;
  cv::Mat img(n, n, CV_64F);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) img.at<double>(y, x) = texel(t, x, y) - 128.0;
  cv::Mat spectrum;
  cv::dft(img, spectrum, cv::DFT_COMPLEX_OUTPUT);
  std::vector<double> power(n / 2, 0.0), count(n / 2, 0.0);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const int fx = x <= n / 2 ? x : x - n, fy = y <= n / 2 ? y : y - n;
      const auto f = static_cast<std::size_t>(std::lround(std::hypot(fx, fy)));
      if (f >= power.size()) continue;
      const cv::Vec2d c = spectrum.at<cv::Vec2d>(y, x);
      power[f] += c[0] * c[0] + c[1] * c[1];
      count[f] += 1;
    }
  double sx = 0, sy = 0, sxx = 0, sxy = 0, m = 0;
  for (std::size_t f = 6; f <= 48; ++f) {
    const double lx = std::log(static_cast<double>(f)), ly = std::log(power[f] / count[f]);
    sx += lx;
    sy += ly;
    sxx += lx * lx;
    sxy += lx * ly;
    ++m;
  }
  const double slope = (m * sxy - sx * sy) / (m * sxx - sx * sx);
  EXPECT_NEAR(slope, -8.0 / 3.0, 0.5);
}

TEST(CloudLayer, TheRiverReachIsOvercastWithClouds) {
  RiverReachOptions o;
  const sim::SceneGeometry g = build_river_reach(o, Sky::kOvercast, 7, 0, 10);
  EXPECT_EQ(g.lighting.sky_zenith_ratio, 3.f);  // CIE overcast
  EXPECT_EQ(g.lighting.sky_knee, 0.8f);
  EXPECT_EQ(g.lighting.cloud_contrast, 0.08f);
  EXPECT_EQ(g.sky_clouds.pixels, bake_cloud_layer(7).pixels);
  // The knee's inverse gives back the horizon's grey: T(L_h) = sky_brightness.
  const double k = g.lighting.sky_knee, L_h = sim::sky_horizon_luminance(g.lighting);
  EXPECT_NEAR(k + (1 - k) * (1 - std::exp(-(L_h - k) / (1 - k))), g.lighting.sky_brightness, 1e-6);
  o.cloud_contrast = 0;
  EXPECT_TRUE(build_river_reach(o, Sky::kOvercast, 7, 0, 10).sky_clouds.pixels.empty());
  const sim::SceneGeometry sun = build_river_reach(RiverReachOptions{}, Sky::kSun, 7, 0, 10);
  EXPECT_TRUE(sun.sky_clouds.pixels.empty());
  EXPECT_EQ(sun.lighting.cloud_contrast, 0.f);
  EXPECT_EQ(sun.lighting.sky_zenith_ratio, 1.12f);
}

}  // namespace
}  // namespace driftlab::scenes
