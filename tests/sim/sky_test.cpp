// The renderer's sky (sim::Lighting's sky fields): the CIE overcast gradient, the camera's
// highlight shoulder, the cloud deck at infinity, and the calm water's mirror image of it.
// Every expectation is computed here from the camera's pose and the published formulas, not
// read from the renderer.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include <Eigen/Geometry>

#include "core/rotation.hpp"
#include "sim/render/renderer.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::sim {
namespace {

using driftlab::test::kDeg;

StereoRig sky_rig() {
  StereoRig rig;
  rig.camera = PinholeCamera{};  // 640x480, fx = fy = 500, cx = 319.5, cy = 239.5
  rig.baseline_m = 0.12;
  return rig;
}

// A camera at p looking north, its nose pitched up by `pitch` and turned east by `yaw`.
SE3 sky_camera(const Vec3& p, double pitch = 0, double yaw = 0) {
  const Mat3 R_W_B =
      (Eigen::AngleAxisd(yaw, Vec3::UnitZ()) * Eigen::AngleAxisd(pitch, Vec3::UnitY()))
          .toRotationMatrix();
  return SE3(Quat(R_W_B * R_frd_optical()), p);
}

// sin(elevation) of the ray through pixel (u, v) (NED: up is -z).
double sin_elevation(const SE3& T_W_C, double u, double v) {
  const Vec3 d = T_W_C.rotation() * sky_rig().camera.unproject({u, v}, 1.0);
  return -d.z() / d.norm();
}

// An empty outdoor scene: nothing but the sky (and the water when asked).
SceneGeometry empty_sky(float brightness, float zenith_ratio, float knee) {
  SceneGeometry s;
  s.lighting.sky_brightness = brightness;
  s.lighting.sky_zenith_ratio = zenith_ratio;
  s.lighting.sky_knee = knee;
  s.lighting.fog_distance_m = 1e9f;
  s.water.enabled = false;
  return s;
}

// A smooth cloud texture, 128 + 32 n: three tiling waves (periods 21 to 64 texels), so that
// bilinear resampling of the rendered sky is exact to well under a grey level.
Texture smooth_clouds(int size) {
  Texture t{"sky_clouds", size, size, {}, {}};
  const double w = 2 * std::numbers::pi / size;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const double n =
          (std::sin(w * 2 * x + 0.6) + std::sin(w * 3 * y + 1.9) + std::sin(w * (x + y))) /
          std::sqrt(1.5);
      t.pixels.push_back(
          static_cast<std::uint8_t>(std::clamp(std::lround(128 + 32 * n), 0L, 255L)));
    }
  return t;
}

// The CIE sky (r = 3) with a cloud deck of `contrast` on a smooth texture of `size` texels.
SceneGeometry clouded_sky(float brightness, float knee, float contrast, int size) {
  SceneGeometry s = empty_sky(brightness, 3.f, knee);
  s.lighting.cloud_contrast = contrast;
  s.sky_clouds = smooth_clouds(size);
  return s;
}

// The camera's shoulder (Lighting::sky_knee), as the scene documents it.
double shoulder(double x, double k) {
  if (k >= 1 || x <= k) return std::min(x, 1.0);
  return k + (1 - k) * (1 - std::exp(-(x - k) / (1 - k)));
}

double bilinear(const GrayImage& img, double u, double v) {
  const int x = static_cast<int>(std::floor(u)), y = static_cast<int>(std::floor(v));
  const double a = u - x, b = v - y;
  return (1 - a) * (1 - b) * img.at(x, y) + a * (1 - b) * img.at(x + 1, y) +
         (1 - a) * b * img.at(x, y + 1) + a * b * img.at(x + 1, y + 1);
}

TEST(OvercastSky, FollowsTheCieGradient) {
  StereoRenderer renderer(sky_rig(), RenderOptions{});
  renderer.upload(empty_sky(0.2f, 3.f, 1.f));
  // Pitched up 45 deg: the rows see elevations from about 20 to 70 deg.
  const SE3 T = sky_camera(Vec3(0, 0, -1), 45 * kDeg);
  const GrayImage img = renderer.render(T, 0.0, false).left;
  double worst = 0;
  for (int v = 0; v < 480; v += 7) {
    const double expected = 255 * 0.2 * (1 + 2 * sin_elevation(T, 320, v));
    worst = std::max(worst, std::abs(img.at(320, v) - expected));
  }
  EXPECT_LE(worst, 1.0);
  // The zenith is three times the horizon (Moon and Spencer 1942): 3 x 51 DN.
  const SE3 up = sky_camera(Vec3(0, 0, -1), 90 * kDeg);
  EXPECT_NEAR(renderer.render(up, 0.0, false).left.at(320, 240), 153, 1);
  const GrayImage level = renderer.render(sky_camera(Vec3(0, 0, -1)), 0.0, false).left;
  EXPECT_NEAR(0.5 * (level.at(100, 239) + level.at(100, 240)), 51, 1);
}

TEST(OvercastSky, ShoulderKeepsTheHorizonAtTheFogGrey) {
  StereoRenderer renderer(sky_rig(), RenderOptions{});
  renderer.upload(empty_sky(0.85f, 3.f, 0.8f));
  const SE3 T = sky_camera(Vec3(0, 0, -1), 10 * kDeg);
  const GrayImage img = renderer.render(T, 0.0, false).left;
  // L_h from the shoulder's inverse at the horizon's grey 0.85.
  const double L_h = 0.8 - 0.2 * std::log(1 - 0.05 / 0.2);
  double worst = 0;
  for (int v = 0; v < 480; v += 5) {
    const double s = sin_elevation(T, 320, v);
    if (s < 0) continue;
    worst = std::max(worst, std::abs(img.at(320, v) - 255 * shoulder(L_h * (1 + 2 * s), 0.8)));
    if (s < std::sin(20 * kDeg)) {
      EXPECT_LT(img.at(320, v), 255) << "row " << v;
    }
  }
  EXPECT_LE(worst, 1.0);
  const GrayImage level = renderer.render(sky_camera(Vec3(0, 0, -1)), 0.0, false).left;
  EXPECT_NEAR(0.5 * (level.at(100, 239) + level.at(100, 240)), 217, 1);
}

TEST(OvercastSky, CloudsLieAtInfinityFixedInTheWorld) {
  StereoRenderer renderer(sky_rig(), RenderOptions{});
  SceneGeometry s = clouded_sky(0.3f, 1.f, 0.3f, 64);
  renderer.upload(s);
  const SE3 T = sky_camera(Vec3(0, 0, -1), 20 * kDeg);
  const StereoImages a = renderer.render(T, 0.0, false);
  const auto max_diff = [](const GrayImage& x, const GrayImage& y) {
    int m = 0;
    for (std::size_t i = 0; i < x.pixels.size(); ++i)
      m = std::max(m, std::abs(x.pixels[i] - y.pixels[i]));
    return m;
  };
  // Both eyes, and a camera 985 m away, see the same sky (float rounding of the rays aside).
  EXPECT_LE(max_diff(a.left, a.right), 1);
  const GrayImage far = renderer.render(sky_camera(Vec3(900, 400, -1), 20 * kDeg), 0, false).left;
  EXPECT_LE(max_diff(a.left, far), 1);
  // The clouds have contrast, and turn with the world, not with the screen: a camera turned
  // 5 deg east sees each direction where K R^T d puts it.
  const SE3 T2 = sky_camera(Vec3(0, 0, -1), 20 * kDeg, 5 * kDeg);
  const GrayImage b = renderer.render(T2, 0.0, false).left;
  EXPECT_GT(max_diff(a.left, b), 10);
  const PinholeCamera& K = sky_rig().camera;
  double worst = 0;
  int compared = 0;
  for (int v = 20; v < 460; v += 20)
    for (int u = 20; u < 620; u += 20) {
      const Vec3 d_W = T.rotation() * K.unproject({u, v}, 1.0);
      const Vec3 p_C2 = T2.rotation().transpose() * d_W;
      const Eigen::Vector2d px = K.project(p_C2);
      if (px.x() < 1 || px.y() < 1 || px.x() > 638 || px.y() > 478) continue;
      worst = std::max(worst, std::abs(a.left.at(u, v) - bilinear(b, px.x(), px.y())));
      ++compared;
    }
  EXPECT_GT(compared, 300);
  EXPECT_LE(worst, 3.0);
}

TEST(OvercastSky, CalmWaterMirrorsTheSkyWithFresnelsReflectance) {
  StereoRenderer renderer(sky_rig(), RenderOptions{});
  SceneGeometry s = clouded_sky(0.3f, 1.f, 0.3f, 64);
  s.water.enabled = true;
  s.water.body_gray = 0.f;
  s.water.turbidity = 0.f;
  s.water.reflectivity = 1.f;
  renderer.upload(s);
  const SE3 T = sky_camera(Vec3(0, 0, -0.5));
  const GrayImage img = renderer.render(T, 0.0, false).left;
  // A level camera: water pixel (u, r) shows the sky of pixel (u, 479 - r), times Schlick's
  // reflectance at the pixel's incidence (the renderer interpolates it between the vertices
  // of its water grid: 2 DN and 3 % allowed).
  double worst_excess = 0;
  double min_correlation = 1;
  int rows_with_clouds = 0;
  for (int r = 250; r <= 400; r += 10) {
    std::vector<double> water, sky;
    for (int u = 0; u < 640; u += 4) {
      const Vec3 d = (T.rotation() * sky_rig().camera.unproject({u, r}, 1.0)).normalized();
      const double F = 0.02 + 0.98 * std::pow(1 - d.z(), 5);  // cos(incidence) = d.z
      water.push_back(img.at(u, r));
      sky.push_back(F * img.at(u, 479 - r));
      worst_excess =
          std::max(worst_excess, std::abs(water.back() - sky.back()) - (2 + 0.03 * sky.back()));
    }
    const auto mean = [](const std::vector<double>& x) {
      double s = 0;
      for (double v : x) s += v;
      return s / static_cast<double>(x.size());
    };
    const double mw = mean(water), ms = mean(sky);
    double sww = 0, sss = 0, sws = 0;
    for (std::size_t i = 0; i < water.size(); ++i) {
      sww += (water[i] - mw) * (water[i] - mw);
      sss += (sky[i] - ms) * (sky[i] - ms);
      sws += (water[i] - mw) * (sky[i] - ms);
    }
    // The clouds along the row (not faded out by the haze near the horizon) are mirrored.
    if (std::sqrt(sss / static_cast<double>(sky.size())) > 2) {
      ++rows_with_clouds;
      // A flat mirror (the sky's clear colour) has no variance: correlation 0.
      min_correlation = std::min(min_correlation, sww > 0 ? sws / std::sqrt(sww * sss) : 0.0);
    }
  }
  EXPECT_LE(worst_excess, 0.0);
  EXPECT_GE(rows_with_clouds, 10);
  EXPECT_GT(min_correlation, 0.95);
}

TEST(OvercastSky, SunnySkyKeepsItsFormula) {
  StereoRenderer renderer(sky_rig(), RenderOptions{});
  SceneGeometry s = empty_sky(0.5f, 1.12f, 1.f);
  s.lighting.sun = true;
  const Vec3 sun = Vec3(std::cos(10 * kDeg), 0.05, -std::sin(10 * kDeg)).normalized();
  s.lighting.sun_direction_W = sun.cast<float>();
  renderer.upload(s);
  const SE3 T = sky_camera(Vec3(0, 0, -1), 5 * kDeg);
  const GrayImage img = renderer.render(T, 0.0, false).left;
  double worst = 0;
  int brightest = 0;
  for (int v = 0; v < 240; v += 3)
    for (int u = 0; u < 640; u += 3) {
      const Vec3 d = (T.rotation() * sky_rig().camera.unproject({u, v}, 1.0)).normalized();
      const double se = std::max(0.0, -d.z());
      const double g = 0.5 * (1 + 0.12 * se) + 0.35 * std::pow(std::max(d.dot(sun), 0.0), 200);
      worst = std::max(worst, std::abs(img.at(u, v) - 255 * std::min(g, 1.0)));
      brightest = std::max<int>(brightest, img.at(u, v));
    }
  EXPECT_LE(worst, 1.0);
  EXPECT_GT(brightest, 200);  // the halo is in view
}

TEST(OvercastSky, CloudedRendersAreByteIdentical) {
  StereoRenderer renderer(sky_rig(), RenderOptions{});
  SceneGeometry s = clouded_sky(0.85f, 0.8f, 0.08f, 128);
  s.water.enabled = true;
  renderer.upload(s);
  const SE3 T = sky_camera(Vec3(0, 0, -0.5), 3 * kDeg);
  const StereoImages a = renderer.render(T, 0.5, false);
  const StereoImages b = renderer.render(T, 0.5, false);
  EXPECT_EQ(a.left.pixels, b.left.pixels);
  EXPECT_EQ(a.right.pixels, b.right.pixels);
}

}  // namespace
}  // namespace driftlab::sim
