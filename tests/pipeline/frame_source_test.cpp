// The frame source: the render thread delivers exactly the frames the serial loop renders, in
// order, skipping dropped ones; a consumer that stops early does not hang it; its errors come
// out of next() as the serial loop's would. With a frame cache: replayed frames are the
// rendered ones byte for byte, a broken entry is rendered again with a warning, two sources
// wanting the same frames at once render them once, and frames with depth are not cached.
#include "pipeline/frame_source.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "core/rotation.hpp"
#include "scenes/build_scene.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::pipeline {
namespace {

namespace fs = std::filesystem;
const fs::path kFrameSourceDir = DRIFTLAB_SOURCE_DIR;

// A short, noisy, auto-exposed look across the river, with its traffic (a moored boat in view):
// every camera effect that keeps state from frame to frame (noise streams, exposure) is on.
struct RiverLook {
  RiverLook() : sc(load_scenario(kFrameSourceDir / "scenarios/river_crossing_traffic.yaml")) {
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
    EXPECT_EQ(a[i].moving_px, b[i].moving_px) << i;
    EXPECT_GT(a[i].moving_px, 0.001) << i;  // the moored boat is in view
  }
  EXPECT_FALSE(a[0].images.left.pixels == a[1].images.left.pixels);  // the frames do move
  EXPECT_EQ(serial.info().triangles, threaded.info().triangles);
  EXPECT_GT(threaded.info().triangles, 0u);
  EXPECT_FALSE(serial.next().has_value());
  EXPECT_FALSE(threaded.next().has_value());
}

// Without depth the moving share comes from the left image's own pass, with depth from
// render_truth's (a second method): the same shares, the same images.
TEST(FrameSource, MovingShareFromTheLeftImagesPassIsTheTruthPasss) {
  const RiverLook s;
  FrameSource plain(s.sc, s.scene, s.truth, s.stamps, 1);
  FrameSource with_depth(s.sc, s.scene, s.truth, s.stamps, 1, 4, /*depth=*/true);
  const auto a = all_frames(plain);
  const auto b = all_frames(with_depth);
  ASSERT_EQ(a.size(), 5u);
  ASSERT_EQ(b.size(), a.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_GT(a[i].moving_px, 0.001) << i;
    EXPECT_EQ(a[i].moving_px, b[i].moving_px) << i;
    EXPECT_TRUE(a[i].images.left.pixels == b[i].images.left.pixels) << i;
    EXPECT_TRUE(a[i].images.moving_left.pixels.empty()) << i;  // kept only when asked for
  }
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

// ---------------------------------------------------------------------------
// With a frame cache

fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() /
                     ("driftlab_frame_source_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  return d;
}

void expect_same_frames(const std::vector<CapturedFrame>& a, const std::vector<CapturedFrame>& b,
                        const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].k, b[i].k) << what << " " << i;
    EXPECT_EQ(a[i].exposure_ms, b[i].exposure_ms) << what << " " << i;
    EXPECT_EQ(a[i].blur_samples, b[i].blur_samples) << what << " " << i;
    EXPECT_EQ(a[i].moving_px, b[i].moving_px) << what << " " << i;
    EXPECT_TRUE(a[i].images.left.pixels == b[i].images.left.pixels) << what << " " << i;
    EXPECT_TRUE(a[i].images.right.pixels == b[i].images.right.pixels) << what << " " << i;
  }
}

TEST(FrameSourceCache, ASecondSourceReplaysTheFirstsFramesByteForByte) {
  const RiverLook s;
  FrameSource plain(s.sc, s.scene, s.truth, s.stamps, 1);
  const auto rendered = all_frames(plain);
  EXPECT_EQ(plain.cache_status().state, "off");
  for (const int threads : {1, 2}) {
    FrameCacheOptions cache;
    cache.dir = fresh_dir("replay");
    FrameSource first(s.sc, s.scene, s.truth, s.stamps, threads, 4, false, cache);
    expect_same_frames(rendered, all_frames(first), "filling");
    EXPECT_EQ(first.cache_status().state, "filled");
    FrameSource second(s.sc, s.scene, s.truth, s.stamps, threads, 4, false, cache);
    expect_same_frames(rendered, all_frames(second), "replayed");
    EXPECT_EQ(second.cache_status().state, "hit");
    EXPECT_EQ(second.cache_status().entry, first.cache_status().entry);
    EXPECT_EQ(second.info().context, plain.info().context);
    EXPECT_EQ(second.info().triangles, plain.info().triangles);
    fs::remove_all(cache.dir);
  }
}

TEST(FrameSourceCache, ABrokenEntryIsRenderedAgainWithAWarning) {
  const RiverLook s;
  FrameCacheOptions cache;
  cache.dir = fresh_dir("broken");
  FrameSource first(s.sc, s.scene, s.truth, s.stamps, 1, 4, false, cache);
  const auto rendered = all_frames(first);
  const fs::path image = fs::path(first.cache_status().entry) / "000002_r.zst";
  std::string bytes = test::slurp(image);
  bytes[bytes.size() / 2] = static_cast<char>(bytes[bytes.size() / 2] ^ 0x10);
  std::ofstream(image, std::ios::binary) << bytes;
  FrameSource second(s.sc, s.scene, s.truth, s.stamps, 2, 4, false, cache);
  expect_same_frames(rendered, all_frames(second), "after the damage");
  const FrameCacheStatus st = second.cache_status();
  EXPECT_EQ(st.state, "filled");
  EXPECT_TRUE(st.warn);
  EXPECT_NE(st.note.find("000002_r.zst does not hold the bytes the index names"), std::string::npos)
      << st.note;
  FrameSource third(s.sc, s.scene, s.truth, s.stamps, 1, 4, false, cache);
  expect_same_frames(rendered, all_frames(third), "refilled");
  EXPECT_EQ(third.cache_status().state, "hit");
  fs::remove_all(cache.dir);
}

TEST(FrameSourceCache, SourcesWantingTheSameFramesAtOnceRenderThemOnce) {
  const RiverLook s;
  FrameCacheOptions cache;
  cache.dir = fresh_dir("together");
  std::vector<CapturedFrame> frames[2];
  FrameCacheStatus status[2];
  auto take = [&](int i) {
    FrameSource source(s.sc, s.scene, s.truth, s.stamps, 1, 4, false, cache);
    frames[i] = all_frames(source);
    status[i] = source.cache_status();
  };
  std::thread a(take, 0), b(take, 1);
  a.join();
  b.join();
  std::multiset<std::string> states{status[0].state, status[1].state};
  EXPECT_EQ(states, (std::multiset<std::string>{"filled", "hit"}));
  expect_same_frames(frames[0], frames[1], "side by side");
  std::size_t entries = 0;
  for (const auto& e : fs::directory_iterator(cache.dir))
    entries += e.path().filename().string().front() != '.' ? 1 : 0;
  EXPECT_EQ(entries, 1u);
  fs::remove_all(cache.dir);
}

TEST(FrameSourceCache, FramesWithDepthAreRenderedNotCached) {
  const RiverLook s;
  FrameCacheOptions cache;
  cache.dir = fresh_dir("depth");
  FrameSource source(s.sc, s.scene, s.truth, s.stamps, 1, 4, /*depth=*/true, cache);
  const auto frames = all_frames(source);
  ASSERT_FALSE(frames.empty());
  EXPECT_FALSE(frames[0].images.depth_left.depth_m.empty());
  for (const CapturedFrame& f : frames)  // the mask whose share frames.csv's moving_px gives
    EXPECT_EQ(moving_share(f.images.moving_left), f.moving_px);
  EXPECT_GT(frames[0].moving_px, 0.0);
  EXPECT_EQ(source.cache_status().state, "off");
  EXPECT_NE(source.cache_status().note.find("no ground-truth depth or masks"), std::string::npos);
  fs::remove_all(cache.dir);
}

}  // namespace
}  // namespace driftlab::pipeline
