// The renderer on both backends (OSMesa, EGL), as one typed suite: where a marker and a wall
// land, byte-identical repeats, and the water's reflection of waves and ripples.
#include "sim/render/renderer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "core/rotation.hpp"
#include "sim/physics/waves/wave_field.hpp"
#include "sim/physics/wind/gusts.hpp"
#include "tests/sim/render_disc_fixtures.hpp"
#include "tests/sim/render_fixtures.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::sim {
namespace {

using fixtures::camera_at;
using fixtures::checker_disc_over_water;
using fixtures::dark_scene;
using fixtures::disc;
using fixtures::rig_640;

// Intensity-weighted bright_centroid of an image.
Eigen::Vector2d bright_centroid(const GrayImage& img) {
  double sx = 0, sy = 0, s = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const double w = img.at(x, y);
      sx += w * x;
      sy += w * y;
      s += w;
    }
  EXPECT_GT(s, 0.0);
  return {sx / s, sy / s};
}

// One suite for both backends (OSMesa, EGL): the same geometry, depth and determinism
// expectations hold for each. EGL is Mesa's llvmpipe on a machine without a GPU and the
// vendor's driver on one; a machine with no EGL display at all skips it, saying why. A typed
// suite, so that each backend's tests run together with one renderer, destroyed before the
// other backend's suite starts: OSMesa and EGL cannot share a process (see
// Render.MixingBackendsIsAClearError).
template <RenderBackend B>
struct BackendIs {
  static constexpr RenderBackend value = B;
};
using BackendTypes =
    ::testing::Types<BackendIs<RenderBackend::kOsmesa>, BackendIs<RenderBackend::kEgl>>;
struct BackendName {
  template <class T>
  static std::string GetName(int) {
    return T::value == RenderBackend::kOsmesa ? "osmesa" : "egl";
  }
};

template <class T>
class RenderTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
#if defined(DRIFTLAB_TEST_ASAN)
    // See Render.EglBackendWorksOrSaysWhy.
    if (T::value == RenderBackend::kEgl) {
      skip_reason_ = "EGL under AddressSanitizer: Mesa's unloaded DRI driver leaks its globals";
      return;
    }
#endif
    RenderOptions o;
    o.msaa_samples = 4;
    o.backend = T::value;
    try {
      shared_ = std::make_unique<StereoRenderer>(rig_640(), o);
      std::cout << shared_->context_description() << "\n";
    } catch (const UserError& e) {
      if (T::value != RenderBackend::kEgl) throw;
      skip_reason_ = e.what();
    }
  }
  static void TearDownTestSuite() { shared_.reset(); }
  void SetUp() override {
    if (!shared_) GTEST_SKIP() << skip_reason_;
    renderer_ = shared_.get();
  }
  static inline std::unique_ptr<StereoRenderer> shared_;
  static inline std::string skip_reason_;
  StereoRenderer* renderer_ = nullptr;
};
TYPED_TEST_SUITE(RenderTest, BackendTypes, BackendName);

TYPED_TEST(RenderTest, MarkerLandsOnItsPinholeProjectionInBothImages) {
  SceneGeometry s = dark_scene();
  const Vec3 marker(10.0, 0.7, -0.3);  // north, east, down
  s.meshes.push_back(disc(marker, 0.06));
  this->renderer_->upload(s);
  const SE3 T_W_C = camera_at(Vec3::Zero());
  const StereoImages img = this->renderer_->render(T_W_C, 0.0, false);
  const StereoRig rig = rig_640();
  const Vec3 p_C = T_W_C.inverse() * marker;
  const Eigen::Vector2d uv = rig.camera.project(p_C);
  const Eigen::Vector2d uv_r = rig.project_right(p_C);
  const Eigen::Vector2d cl = bright_centroid(img.left), cr = bright_centroid(img.right);
  EXPECT_NEAR(cl.x(), uv.x(), 0.1);
  EXPECT_NEAR(cl.y(), uv.y(), 0.1);
  EXPECT_NEAR(cr.x(), uv_r.x(), 0.1);
  EXPECT_NEAR(cr.y(), uv_r.y(), 0.1);
  // Disparity = fx B / Z, river paper Eq. (1).
  EXPECT_NEAR(cl.x() - cr.x(), 500 * 0.12 / 10.0, 0.1);
  std::cout << "marker: left (" << cl.x() << ", " << cl.y() << ") vs (" << uv.x() << ", " << uv.y()
            << "), disparity " << cl.x() - cr.x() << " vs " << 6.0 << "\n";
}

TYPED_TEST(RenderTest, GroundTruthDepthOfAWallIsItsDistance) {
  SceneGeometry s = dark_scene();
  Mesh wall;
  wall.name = "wall";
  const float x = 20.f;
  wall.vertices = {{x, -50, -30, -1, 0, 0, 0, 0},
                   {x, 50, -30, -1, 0, 0, 1, 0},
                   {x, 50, 30, -1, 0, 0, 1, 1},
                   {x, -50, 30, -1, 0, 0, 0, 1}};
  wall.indices = {0, 1, 2, 0, 2, 3};
  s.meshes.push_back(wall);
  this->renderer_->upload(s);
  const StereoImages img = this->renderer_->render(camera_at(Vec3(0, 0, 0)), 0.0, true);
  ASSERT_EQ(img.depth_left.width, 640);
  double worst = 0;
  for (float d : img.depth_left.depth_m) worst = std::max(worst, std::abs(d - 20.0));
  EXPECT_LT(worst, 1e-3);
}

TYPED_TEST(RenderTest, RepeatedRendersAreByteIdentical) {
  this->renderer_->upload(checker_disc_over_water(Vec3(8, 1, -1), 1.5, 40, 200));
  WaveComponent w{0.02, 2 * std::numbers::pi / 1.5, 3.0, 0.3, 0.1};
  this->renderer_->set_waves({w});
  const StereoImages a = this->renderer_->render(camera_at(Vec3(0, 0, -0.5)), 1.25, true);
  const StereoImages b = this->renderer_->render(camera_at(Vec3(0, 0, -0.5)), 1.25, true);
  EXPECT_EQ(a.left.pixels, b.left.pixels);
  EXPECT_EQ(a.right.pixels, b.right.pixels);
  EXPECT_EQ(a.depth_left.depth_m, b.depth_left.depth_m);
  // The water is visible below the horizon and has texture from the waves.
  int lower_nonzero = 0;
  for (int x = 0; x < 640; ++x) lower_nonzero += a.left.at(x, 470) > 0;
  EXPECT_GT(lower_nonzero, 600);
  this->renderer_->set_waves({});
}

// Water alone under a uniform bright sky, seen from 0.5 m up by a camera pitched 5 deg down:
// its grey is the Fresnel reflectance of the sky, so where the water is rippled it is brighter
// than the calm water's where the surface faces away from the camera. One wave travelling
// north, of slope amplitude 0.1, frozen (omega 0).
struct WaterColumn {
  std::vector<double> grey;       // the centre column's rows [kFirstRow, 480), less the calm grey
  std::vector<double> predicted;  // the same from Schlick's Fresnel reflectance at the slope
};

// Schlick's approximation of water's Fresnel reflectance (n = 1.33) of a surface of slope s
// (grad eta, z down) seen from direction `to_eye`.
double schlick(const Vec2& s, const Vec3& to_eye) {
  const double m = 1 - std::clamp(Vec3(-s.x(), -s.y(), -1).normalized().dot(to_eye), 0.0, 1.0);
  return 0.02 + 0.98 * std::pow(m, 5);
}
constexpr int kFirstRow = 350;
constexpr double kWaterHeightM = 0.5, kWaterPitchRad = -5 * std::numbers::pi / 180;

WaterColumn water_column(StereoRenderer& renderer, double wavelength_m) {
  SceneGeometry s = dark_scene();
  s.water.enabled = true;
  s.water.body_gray = 0;
  s.water.turbidity = 0;
  s.lighting.sky_brightness = 1;
  renderer.upload(s);
  const Mat3 R_W_B = quat_from_euler_zyx({0, kWaterPitchRad, 0}).toRotationMatrix();
  const SE3 T_W_C(R_W_B * R_frd_optical(), Vec3(0, 0, -kWaterHeightM));
  renderer.set_waves({});
  const StereoImages calm = renderer.render(T_W_C, 0.0, false);
  const double k = 2 * std::numbers::pi / wavelength_m;
  renderer.set_waves({WaveComponent{0.1 / k, k, 0.0, 0.0, 0.3}});
  const StereoImages wavy = renderer.render(T_W_C, 0.0, false);
  renderer.set_waves({});
  WaterColumn c;
  for (int v = kFirstRow; v < 480; ++v) {
    const Vec3 ray = T_W_C.rotation() * Vec3(0, (v - 239.5) / 500.0, 1);
    const double x = ray.x() * kWaterHeightM / ray.z();
    const Vec3 to_eye = -ray.normalized();
    c.grey.push_back(wavy.left.at(320, v) - calm.left.at(320, v));
    const Vec2 slope(-0.1 * std::sin(k * x + 0.3), 0);
    c.predicted.push_back(255 * (schlick(slope, to_eye) - schlick(Vec2::Zero(), to_eye)));
  }
  return c;
}

double grey_sd(const std::vector<double>& x) {
  double m = 0, q = 0;
  for (double v : x) m += v / x.size();
  for (double v : x) q += (v - m) * (v - m) / x.size();
  return std::sqrt(q);
}

TYPED_TEST(RenderTest, WaterShowsTheWavesPixelByPixelAndFiltersWhatAPixelCannotHold) {
  // A 0.15 m wave is longer than a pixel's footprint on these rows (4-11 mm) and shorter than
  // two steps of the water's mesh there (8-15 cm): the water's grey must follow the slope of
  // the wave itself where each row's ray meets the water, the brighter the more the surface
  // faces away from the camera: Schlick's reflectance at the wave's slope, to the rounding.
  const WaterColumn resolved = water_column(*this->renderer_, 0.15);
  double worst = 0;
  for (std::size_t i = 0; i < resolved.grey.size(); ++i)
    worst = std::max(worst, std::abs(resolved.grey[i] - resolved.predicted[i]));
  EXPECT_LT(worst, 2.5);  // two 8-bit roundings
  // A 3 mm wave of the same slope is below the footprint (k d = 8-23 rad a row): the Gaussian
  // of sd d / 2 keeps exp(-(k d)^2 / 8) < 0.0003 of it, so the water is as calm, where a
  // surface sampled by its mesh would alias it into a pattern as strong as the resolved one.
  const WaterColumn unresolved = water_column(*this->renderer_, 0.003);
  EXPECT_GT(grey_sd(resolved.grey), 5.0);
  EXPECT_LT(grey_sd(unresolved.grey), 0.05 * grey_sd(resolved.grey));
  std::cout << "water: worst " << worst << " DN from Schlick, grey sd resolved "
            << grey_sd(resolved.grey) << ", unresolved " << grey_sd(unresolved.grey) << "\n";
}

TYPED_TEST(RenderTest, WindRipplesBreakTheMirrorImageOnlyOnTheWater) {
  // A bright textured disc above dark water: its mirror image lies below the
  // horizon. Ripples move and blur the mirror image; the disc itself, above
  // the horizon, keeps every byte; with the ripples gone again the frame is
  // the calm frame byte for byte.
  this->renderer_->upload(checker_disc_over_water(Vec3(8, 0, -1.5), 1.2, 30, 220));
  this->renderer_->set_waves({});
  const SE3 T_W_C = camera_at(Vec3(0, 0, -0.5));
  const StereoImages calm = this->renderer_->render(T_W_C, 2.0, false);
  WindOptions w;
  w.speed_mps = 3.0;
  this->renderer_->set_ripples(
      std::make_shared<RippleMaps>(w, CurrentOptions{}, RngStreams(3).stream("water.ripples")));
  const StereoImages rippled = this->renderer_->render(T_W_C, 2.0, false);
  const StereoImages later = this->renderer_->render(T_W_C, 2.5, false);
  const StereoImages rippled_again = this->renderer_->render(T_W_C, 2.0, false);
  this->renderer_->set_ripples(nullptr);
  const StereoImages calm_again = this->renderer_->render(T_W_C, 2.0, false);
  EXPECT_EQ(calm.left.pixels, calm_again.left.pixels);
  EXPECT_EQ(rippled.left.pixels, rippled_again.left.pixels);
  // Rows 0..239 look above the horizon (row 239.5 is level with the camera):
  // not a byte changes there.
  const int W = 640;
  int above_diff = 0;
  for (int y = 0; y < 236; ++y)
    for (int x = 0; x < W; ++x) above_diff += calm.left.at(x, y) != rippled.left.at(x, y);
  EXPECT_EQ(above_diff, 0);
  // The disc's mirror image (columns 260-380, rows 300-420) against open
  // water beside it (columns 40-160): the ripples break it up (it differs
  // from the calm mirror image) and move (it differs from frame to frame),
  // but a darker image of the disc is still there.
  double changed = 0, moving = 0, n = 0;
  double calm_in = 0, calm_out = 0, rippled_in = 0, rippled_out = 0;
  for (int y = 300; y < 420; ++y)
    for (int x = 260; x < 380; ++x) {
      changed += std::abs(calm.left.at(x, y) - rippled.left.at(x, y));
      moving += rippled.left.at(x, y) != later.left.at(x, y);
      calm_in += calm.left.at(x, y);
      rippled_in += rippled.left.at(x, y);
      calm_out += calm.left.at(x - 220, y);
      rippled_out += rippled.left.at(x - 220, y);
      n += 1;
    }
  EXPECT_GT(changed / n, 4.0);
  EXPECT_GT(moving / n, 0.5);
  const double calm_contrast = (calm_out - calm_in) / n,
               rippled_contrast = (rippled_out - rippled_in) / n;
  EXPECT_GT(calm_contrast, 10.0);
  EXPECT_GT(rippled_contrast, calm_contrast / 3);
}

}  // namespace
}  // namespace driftlab::sim
