// The frame source: the render thread delivers exactly the frames the serial loop renders, in
// order, skipping dropped ones; a consumer that stops early does not hang it; its errors come
// out of next() as the serial loop's would.
#include "pipeline/frame_source.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "core/rotation.hpp"
#include "scenes/build_scene.hpp"

namespace driftlab::pipeline {
namespace {

namespace fs = std::filesystem;
const fs::path kSource = DRIFTLAB_SOURCE_DIR;

// A short, noisy, auto-exposed look across the river: every camera effect that keeps state
// from frame to frame (noise streams, exposure) is on.
struct RiverLook {
  RiverLook() : sc(load_scenario(kSource / "scenarios/river_crossing.yaml")) {
    sc.sensors.camera.auto_exposure.enabled = true;
    scene = scenes::build_scene(sc.scene, sc.seed, -10, 30);
    for (int k = 0; k < 8; ++k) {
      FrameTruth f;
      f.t_s = k / 13.0;
      f.T_W_B = SE3(quat_from_euler_zyx({0.0, 0.0, 0.3 + 0.01 * k}), Vec3(5 + 0.05 * k, 0, 0));
      truth.push_back(f);
      sim::SampleTime s;
      s.t_true_ns = s.t_stamp_ns = static_cast<TimeNs>(k) * 76'923'077;
      s.dropped = k == 0 || k == 3 || k == 4;
      stamps.push_back(s);
    }
  }
  Scenario sc;
  sim::SceneGeometry scene;
  std::vector<FrameTruth> truth;
  std::vector<sim::SampleTime> stamps;
};

std::vector<CapturedFrame> all_frames(FrameSource& source) {
  std::vector<CapturedFrame> frames;
  while (auto f = source.next()) frames.push_back(std::move(*f));
  return frames;
}

TEST(FrameSource, RenderThreadDeliversTheSerialFramesInOrderSkippingDropped) {
  const RiverLook s;
  FrameSource serial(s.sc, s.scene, s.truth, s.stamps, 1);
  FrameSource threaded(s.sc, s.scene, s.truth, s.stamps, 2, /*queue_frames=*/2);
  const auto a = all_frames(serial);
  const auto b = all_frames(threaded);
  ASSERT_EQ(a.size(), 5u);
  ASSERT_EQ(b.size(), a.size());
  const std::vector<std::size_t> delivered{1, 2, 5, 6, 7};
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].k, delivered[i]);
    EXPECT_EQ(b[i].k, delivered[i]);
    EXPECT_EQ(a[i].exposure_ms, b[i].exposure_ms) << i;
    EXPECT_TRUE(a[i].images.left.pixels == b[i].images.left.pixels) << i;
    EXPECT_TRUE(a[i].images.right.pixels == b[i].images.right.pixels) << i;
  }
  EXPECT_FALSE(a[0].images.left.pixels == a[1].images.left.pixels);  // the frames do move
  EXPECT_EQ(serial.info().triangles, threaded.info().triangles);
  EXPECT_GT(threaded.info().triangles, 0u);
  EXPECT_FALSE(serial.next().has_value());
  EXPECT_FALSE(threaded.next().has_value());
}

TEST(FrameSource, ConsumerThatStopsEarlyDoesNotHangTheRenderThread) {
  const RiverLook s;
  for (const std::size_t taken : {0, 1}) {
    FrameSource source(s.sc, s.scene, s.truth, s.stamps, 2, /*queue_frames=*/1);
    for (std::size_t i = 0; i < taken; ++i) ASSERT_TRUE(source.next().has_value());
  }  // the destructor stops and joins the thread blocked on the full queue
  SUCCEED();
}

TEST(FrameSource, RenderErrorsComeOutOfNextAsInTheSerialLoop) {
  // More samples than any GL implementation offers: the framebuffer is refused where the
  // renderer is made, on the render thread.
  RiverLook s;
  s.sc.render.msaa_samples = 16;
  auto outcome = [&](int threads) {
    try {
      FrameSource source(s.sc, s.scene, s.truth, s.stamps, threads);
      return "frames: " + std::to_string(all_frames(source).size());
    } catch (const std::exception& e) {
      return std::string("error: ") + e.what();
    }
  };
  EXPECT_EQ(outcome(1), outcome(2));
}

TEST(FrameSource, ZeroThreadsMeansEveryCore) {
  EXPECT_GE(run_threads(0), 1);
  EXPECT_EQ(run_threads(1), 1);
  EXPECT_EQ(run_threads(3), 3);
}

}  // namespace
}  // namespace driftlab::pipeline
