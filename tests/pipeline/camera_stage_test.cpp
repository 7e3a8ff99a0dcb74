// The camera stage on rendered river frames: shot and read noise with the
// model's variance, motion blur as the mean of renders at independently
// computed sub-frame poses, the miscalibrated right camera, and (through a
// whole run) the camera clock's offset and dropped frames.
#include "pipeline/camera_stage.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "core/rotation.hpp"
#include "core/trajectory_io.hpp"
#include "pipeline/render_stage.hpp"
#include "pipeline/run.hpp"
#include "scenes/build_scene.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::pipeline {
namespace {

using test::slurp;

namespace fs = std::filesystem;
const fs::path kSource = DRIFTLAB_SOURCE_DIR;

Scenario river() {
  Scenario sc = load_scenario(kSource / "scenarios/river_crossing.yaml");
  sc.sensors.camera.noise.enabled = false;
  return sc;
}

// A frame mid-river looking at the east bank, the body moving and turning.
FrameTruth frame(double yaw_rate_rad_s = 0.0) {
  FrameTruth f;
  f.t_s = 3.0;
  f.T_W_B = SE3(quat_from_euler_zyx({0.0, 0.0, 0.3}), Vec3(5, 0, 0));
  f.twist_B << 0.0, 0.0, 0.0, 0.0, 0.0, yaw_rate_rad_s;
  return f;
}

struct Rendering {
  explicit Rendering(const Scenario& sc)
      : scene(scenes::build_scene(sc.scene, sc.seed, -10, 30)),
        renderer(rig_of(sc.sensors.camera), sc.render) {
    renderer.upload(scene);
  }
  sim::SceneGeometry scene;
  sim::StereoRenderer renderer;
};

TEST(CameraStage, NoiseVarianceOnARenderedFrameMatchesTheModel) {
  Scenario clean_sc = river();
  Scenario noisy_sc = clean_sc;
  noisy_sc.sensors.camera.noise.enabled = true;
  noisy_sc.sensors.camera.noise.full_well_e = 4000;  // strong shot noise: about 2.5 DN at mid grey
  Rendering r(clean_sc);
  CameraStage clean(clean_sc, &r.renderer, RngStreams(1));
  CameraStage noisy(noisy_sc, &r.renderer, RngStreams(1));
  const sim::StereoImages a = clean.capture(frame());
  const sim::StereoImages b = noisy.capture(frame());
  // The model's variance per pixel, from the clean value (pixels away from
  // clipping): K * mean + K^2 read^2 + 1/12, K = gain * 255 / full well.
  const auto& n = noisy_sc.sensors.camera.noise;
  const double K = n.analog_gain * 255.0 / n.full_well_e;
  double expected = 0, measured = 0, mean_diff = 0;
  int count = 0;
  for (std::size_t i = 0; i < a.left.pixels.size(); ++i) {
    const double v = a.left.pixels[i];
    if (v < 20 || v > 235) continue;
    const double d = static_cast<double>(b.left.pixels[i]) - v;
    expected += K * v + K * K * n.read_noise_e * n.read_noise_e + 1.0 / 12.0;
    measured += d * d;
    mean_diff += d;
    ++count;
  }
  ASSERT_GT(count, 100000);
  // The clean image is itself rounded: the noisy one rounds v + noise, so the
  // difference carries the noise plus the rounding term, as in the model.
  EXPECT_NEAR(measured / count, expected / count, 0.05 * expected / count);
  EXPECT_NEAR(mean_diff / count, 0.0, 0.05);
  // Left and right draw from separate streams: their noise is uncorrelated.
  double cross = 0;
  for (std::size_t i = 0; i < a.left.pixels.size(); ++i)
    cross += (static_cast<double>(b.left.pixels[i]) - a.left.pixels[i]) *
             (static_cast<double>(b.right.pixels[i]) - a.right.pixels[i]);
  EXPECT_LT(std::abs(cross / a.left.pixels.size()), 0.05 * expected / count);
}

// The largest image motion over the exposure of a turn about body down, found by brute force:
// every 8th pixel's ray turned by the sub-frame poses' relative rotation and projected again.
double largest_turn_motion_px(const Scenario& sc, double yaw_rate, double exposure_s) {
  const PinholeCamera cam = rig_of(sc.sensors.camera).camera;
  const SE3 T_B_C = camera_mount_T_B_C(sc.sensors.camera.mount);
  const SE3 start = frame(yaw_rate).T_W_B * T_B_C;
  const SE3 turn(quat_from_euler_zyx({0.0, 0.0, yaw_rate * exposure_s}), Vec3::Zero());
  const SE3 end = frame(yaw_rate).T_W_B * turn * T_B_C;
  const Mat3 R_end_start = (end.inverse() * start).quaternion().toRotationMatrix();
  double largest = 0;
  for (int v = 0; v < cam.height; v += 8)
    for (int u = 0; u < cam.width; u += 8) {
      const Eigen::Vector2d px(u, v);
      const Vec3 ray = R_end_start * cam.unproject(px, 1.0);
      largest = std::max(largest, (cam.project(ray) - px).norm());
    }
  return largest;
}

TEST(CameraStage, AdaptiveMotionBlurTakesTheSamplesTheTurnNeeds) {
  Scenario sc = river();
  sc.render.motion_blur_samples = 16;
  sc.render.motion_blur_step_px = 0.5;
  sc.sensors.camera.exposure_ms = 40;
  sc.sensors.camera.noise.reference_exposure_ms = 40;
  Rendering r(sc);
  CameraStage adaptive(sc, &r.renderer, RngStreams(1));
  // Still: one render. A slow turn: as many as keep 0.5 px between two. A fast one: the most.
  EXPECT_EQ(adaptive.blur_samples(frame(0.0)), 1);
  const double slow = 0.05;  // rad/s: about 2 px over 40 ms at f = 817 px
  const double motion_px = largest_turn_motion_px(sc, slow, 0.040);
  ASSERT_GT(motion_px, 1.0);
  ASSERT_LT(motion_px, 16 * 0.5);
  const int expected = static_cast<int>(std::ceil(motion_px / 0.5));
  EXPECT_EQ(adaptive.blur_samples(frame(slow)), expected);
  EXPECT_EQ(adaptive.blur_samples(frame(1.0)), 16);
  // The images are those of that many samples always.
  const sim::StereoImages got = adaptive.capture(frame(slow));
  EXPECT_EQ(adaptive.last_blur_samples(), expected);
  Scenario fixed_sc = sc;
  fixed_sc.render.motion_blur_samples = expected;
  fixed_sc.render.motion_blur_step_px = 0;
  CameraStage fixed(fixed_sc, &r.renderer, RngStreams(1));
  EXPECT_EQ(fixed.blur_samples(frame(0.0)), expected);  // step 0: every frame, moving or not
  EXPECT_EQ(got.left.pixels, fixed.capture(frame(slow)).left.pixels);
}

TEST(CameraStage, MotionBlurIsTheMeanOfRendersOverTheExposure) {
  Scenario sc = river();
  sc.render.motion_blur_samples = 4;
  sc.sensors.camera.exposure_ms = 40;
  sc.sensors.camera.noise.reference_exposure_ms = 40;  // same brightness as the sharp render
  Rendering r(sc);
  const double yaw_rate = 0.5;  // rad/s about body down: 20 mrad over the exposure, ~10 px
  CameraStage blur(sc, &r.renderer, RngStreams(1));
  const sim::StereoImages got = blur.capture(frame(yaw_rate));
  // The sub-frame poses written out here: a pure turn about body z by
  // yaw_rate * d at d = (s + 1/2) / 4 - 1/2 of the exposure.
  const SE3 T_B_C = camera_mount_T_B_C(sc.sensors.camera.mount);
  const FrameTruth f = frame(yaw_rate);
  std::vector<int> sum(got.left.pixels.size(), 0);
  for (int s = 0; s < 4; ++s) {
    const double d = ((s + 0.5) / 4 - 0.5) * 0.040;
    const SE3 turn(quat_from_euler_zyx({0.0, 0.0, yaw_rate * d}), Vec3::Zero());
    const sim::StereoImages img = r.renderer.render(f.T_W_B * turn * T_B_C, f.t_s + d, false);
    for (std::size_t i = 0; i < sum.size(); ++i) sum[i] += img.left.pixels[i];
  }
  // Equal up to the float rounding of the two ways of writing the pose (an
  // edge pixel may flip in one sub-render).
  int off_by_more = 0;
  for (std::size_t i = 0; i < sum.size(); ++i)
    off_by_more += std::abs(got.left.pixels[i] - (sum[i] + 2) / 4) > 1;
  EXPECT_LT(off_by_more, static_cast<int>(sum.size() / 1000));
  // And it is blurred: different from the single render at the frame time.
  CameraStage sharp(river(), &r.renderer, RngStreams(1));
  const sim::StereoImages one = sharp.capture(frame(yaw_rate));
  int differ = 0;
  for (std::size_t i = 0; i < sum.size(); ++i) differ += got.left.pixels[i] != one.left.pixels[i];
  EXPECT_GT(differ, static_cast<int>(sum.size() / 10));
  // Without motion the blurred image is the sharp one.
  CameraStage still(sc, &r.renderer, RngStreams(1));
  EXPECT_EQ(still.capture(frame(0.0)).left.pixels, sharp.capture(frame(0.0)).left.pixels);
}

TEST(CameraStage, TheRightCameraIsRenderedWhereTheMiscalibratedRigPutsIt) {
  Scenario sc = river();
  Rendering r(sc);
  const sim::StereoImages nominal = CameraStage(sc, &r.renderer, RngStreams(1)).capture(frame());
  sc.sensors.camera.calibration_error.baseline_error_m = 0.01;
  CameraStage off(sc, &r.renderer, RngStreams(1));
  const sim::StereoImages got = off.capture(frame());
  EXPECT_EQ(got.left.pixels, nominal.left.pixels);
  EXPECT_NE(got.right.pixels, nominal.right.pixels);
  // The right image is the render from the left pose + 13 cm along optical x.
  const SE3 T_W_C = off.T_W_C(frame());
  const sim::StereoImages direct =
      r.renderer.render(T_W_C * SE3::from_translation(Vec3(0.13, 0, 0)), 3.0, false);
  EXPECT_EQ(got.right.pixels, direct.left.pixels);
}

// Auto exposure: starting 8x too long (a saturated frame), the loop brings the
// left image's mean to the target; the image mean scales with the exposure,
// so the settled exposure is the one that scales the reference render's mean
// to the target (computed here from the render at the reference exposure).
TEST(CameraStage, AutoExposureSettlesOnTheTargetMean) {
  Scenario sc = river();
  Rendering r(sc);
  auto mean_of = [](const sim::GrayImage& g) {
    double m = 0;
    for (std::uint8_t v : g.pixels) m += v;
    return m / static_cast<double>(g.pixels.size());
  };
  const double reference_mean =
      mean_of(CameraStage(sc, &r.renderer, RngStreams(1)).capture(frame()).left);
  sc.sensors.camera.auto_exposure.enabled = true;
  sc.sensors.camera.auto_exposure.target_mean_dn = 80;
  sc.sensors.camera.exposure_ms = 40;  // 8x the reference exposure of 5 ms
  CameraStage stage(sc, &r.renderer, RngStreams(1));
  EXPECT_EQ(stage.exposure_ms(), 20.0);  // clamped to max_exposure_ms
  double mean = 0;
  for (int k = 0; k < 15; ++k) mean = mean_of(stage.capture(frame()).left);
  EXPECT_NEAR(mean, 80.0, 1.5);
  // Linear camera: exposure = reference exposure * target / reference mean
  // (a little off where pixels clip).
  EXPECT_NEAR(stage.exposure_ms(), 5.0 * 80.0 / reference_mean, 0.05 * 5.0 * 80.0 / reference_mean);
  // Bad options name the field.
  sc.sensors.camera.auto_exposure.max_exposure_ms = 1.5e3 / sc.sensors.camera.rate_hz;  // > 1 frame
  EXPECT_THROW(validate_scenario(sc, "test"), UserError);
}

TEST(CameraStage, RunStampsFramesWithTheCameraClockAndSkipsDroppedOnes) {
  Scenario sc = river();
  sc.pipeline.max_frames = 60;
  sc.pipeline.vo = {"sparse"};
  sc.pipeline.fusion = {};
  sc.sensors.camera.clock.offset_ms = 30;  // the river paper's mean camera offset
  sc.sensors.camera.clock.drop_probability = 0.2;
  EXPECT_THROW(validate_scenario(sc, "test"), UserError);  // 30 ms > the 20 ms tolerance
  sc.eval.association_tolerance_s = 0.035;
  const fs::path out =
      fs::temp_directory_path() / ("driftlab_camera_clock_" + std::to_string(::getpid()));
  fs::remove_all(out);
  run_scenario(sc, out, {});
  const Trajectory gt = read_tum(out / "groundtruth.tum");
  const Trajectory est = read_tum(out / "estimates/sparse.tum");
  ASSERT_EQ(gt.size(), 60u);
  // Every estimate is stamped 30 ms after a ground-truth frame time (no jitter).
  int matched = 0;
  for (const auto& e : est)
    for (const auto& g : gt) matched += e.t_ns == g.t_ns + 30'000'000;
  EXPECT_EQ(matched, static_cast<int>(est.size()));
  const auto m = nlohmann::json::parse(slurp(out / "metrics.json"));
  const int dropped = m["camera"]["frames_dropped"].get<int>();
  EXPECT_EQ(static_cast<int>(est.size()), 60 - dropped);
  // 60 frames, p = 0.2: 12 expected; a binomial's 4-sigma range.
  EXPECT_GT(dropped, 0);
  EXPECT_LT(dropped, 25);
  fs::remove_all(out);
}

}  // namespace
}  // namespace driftlab::pipeline
