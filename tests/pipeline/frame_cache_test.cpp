// The frame cache's store: what goes in comes out byte for byte; an entry is found only under
// its own key text; a corrupt, truncated, half-written or foreign entry is detected, removed
// and never served; two fills of one key both finish; eviction drops the least recently used
// entries first and never one being read. The key (frame_cache_key) changes with everything
// that decides a frame's bytes and with nothing else.
#include "pipeline/frame_cache.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "pipeline/frame_cache_key.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::pipeline {
namespace {

namespace fs = std::filesystem;

// A frame of noise (incompressible, so that sizes are predictable) with its metadata.
CacheFrame noise_frame(std::size_t k, unsigned seed, int width = 64, int height = 48) {
  std::mt19937 gen(seed);
  CacheFrame f;
  f.k = k;
  f.exposure_ms = 0.1 * static_cast<double>(seed) + 1.0 / 3.0;  // not a short decimal
  f.blur_samples = 1 + static_cast<int>(seed % 4);
  for (sim::GrayImage* img : {&f.left, &f.right}) {
    img->width = width;
    img->height = height;
    img->pixels.resize(static_cast<std::size_t>(width) * height);
    for (auto& p : img->pixels) p = static_cast<std::uint8_t>(gen());
  }
  return f;
}

void fill(const FrameCache& cache, const std::string& key, const std::vector<CacheFrame>& frames) {
  auto w = cache.fill(key);
  for (const auto& f : frames) w->add(f);
  ASSERT_TRUE(w->commit());
}

void expect_same(const CacheFrame& a, const CacheFrame& b) {
  EXPECT_EQ(a.k, b.k);
  EXPECT_EQ(a.exposure_ms, b.exposure_ms);  // exact: the index keeps every bit
  EXPECT_EQ(a.blur_samples, b.blur_samples);
  EXPECT_EQ(a.left.width, b.left.width);
  EXPECT_EQ(a.left.height, b.left.height);
  EXPECT_EQ(a.left.pixels, b.left.pixels);
  EXPECT_EQ(a.right.pixels, b.right.pixels);
}

std::vector<CacheFrame> three_frames(unsigned seed) {
  return {noise_frame(1, seed), noise_frame(2, seed + 1), noise_frame(5, seed + 2)};
}

TEST(FrameCache, WhatGoesInComesOutByteForByte) {
  const FrameCache cache(test::fresh_temp_dir("fc_roundtrip"), 1u << 30);
  const auto frames = three_frames(7);
  std::string warning;
  EXPECT_EQ(cache.find("scene: a", &warning), nullptr);
  EXPECT_EQ(warning, "");  // a plain miss says nothing
  fill(cache, "scene: a", frames);
  const auto r = cache.find("scene: a", &warning);
  ASSERT_NE(r, nullptr) << warning;
  ASSERT_EQ(r->size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) expect_same(r->frame(i), frames[i]);
  EXPECT_EQ(cache.find("scene: b", &warning), nullptr);
  EXPECT_EQ(warning, "");
}

// Each way an entry can be broken: found, refused with a warning that says what is wrong, and
// removed, so that the next run renders and fills it again.
TEST(FrameCache, BrokenEntriesAreRefusedAndRemoved) {
  struct Case {
    const char* name;
    std::function<void(const fs::path&)> damage;
    const char* warning;
  };
  const auto overwrite = [](const fs::path& p, const std::string& bytes) {
    std::ofstream(p, std::ios::binary | std::ios::trunc) << bytes;
  };
  const auto truncate = [](const fs::path& p, std::uintmax_t n) { fs::resize_file(p, n); };
  const std::vector<Case> cases = {
      {"flipped byte",
       [](const fs::path& d) {
         std::fstream f(d / "000001_r.zst", std::ios::binary | std::ios::in | std::ios::out);
         f.seekg(100);
         const char c = static_cast<char>(f.get());
         f.seekp(100);
         f.put(static_cast<char>(c ^ 0x10));
       },
       "000001_r.zst does not hold the bytes the index names"},
      {"truncated image", [&](const fs::path& d) { truncate(d / "000002_l.zst", 50); },
       "000002_l.zst has 50 bytes"},
      {"missing image", [](const fs::path& d) { fs::remove(d / "000000_l.zst"); },
       "000000_l.zst is missing"},
      {"truncated index",
       [&](const fs::path& d) { truncate(d / "index.csv", fs::file_size(d / "index.csv") - 6); },
       "index.csv is truncated"},
      {"missing index", [](const fs::path& d) { fs::remove(d / "index.csv"); },
       "index.csv is missing"},
      {"another key", [&](const fs::path& d) { overwrite(d / "key.txt", "scene: other"); },
       "key.txt holds another key"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const FrameCache cache(test::fresh_temp_dir("fc_broken"), 1u << 30);
    fill(cache, "scene: a", three_frames(3));
    c.damage(cache.entry_dir("scene: a"));
    std::string warning;
    EXPECT_EQ(cache.find("scene: a", &warning), nullptr);
    EXPECT_NE(warning.find(c.warning), std::string::npos) << warning;
    EXPECT_FALSE(fs::exists(cache.entry_dir("scene: a")));
  }
}

TEST(FrameCache, AFrameChangedWhileInUseIsAnErrorNotServed) {
  const FrameCache cache(test::fresh_temp_dir("fc_in_use"), 1u << 30);
  fill(cache, "k", three_frames(5));
  std::string warning;
  const auto r = cache.find("k", &warning);
  ASSERT_NE(r, nullptr) << warning;
  fs::resize_file(cache.entry_dir("k") / "000001_l.zst", 10);
  EXPECT_NO_THROW(r->frame(0));
  EXPECT_NE(test::user_error_of([&] { r->frame(1); }).find("000001_l.zst has 10 bytes"),
            std::string::npos);
}

// A fill that never commits (a failed or killed run) leaves no entry and, once its process is
// gone, no folder either; of two fills of one key the first to commit wins.
TEST(FrameCache, UncommittedFillsLeaveNothingAndTheFirstCommitWins) {
  const fs::path dir = test::fresh_temp_dir("fc_fills");
  const FrameCache cache(dir, 1u << 30);
  {
    auto w = cache.fill("k");
    w->add(noise_frame(0, 1));
  }
  std::string warning;
  EXPECT_EQ(cache.find("k", &warning), nullptr);
  EXPECT_TRUE(fs::is_empty(dir));

  auto first = cache.fill("k"), second = cache.fill("k");
  const auto a = three_frames(10), b = three_frames(20);
  for (std::size_t i = 0; i < 3; ++i) {
    first->add(a[i]);
    second->add(b[i]);
  }
  EXPECT_TRUE(first->commit());
  EXPECT_FALSE(second->commit());
  second.reset();
  const auto r = cache.find("k", &warning);
  ASSERT_NE(r, nullptr) << warning;
  expect_same(r->frame(2), a[2]);

  // A fill folder of a process that is gone (a child that exited) is cleared by evict().
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  ::waitpid(child, nullptr, 0);
  const fs::path orphan = dir / (".fill-0123456789abcdef-" + std::to_string(child) + "-0");
  fs::create_directory(orphan);
  const fs::path alive = dir / (".fill-0123456789abcdef-" + std::to_string(::getpid()) + "-99");
  fs::create_directory(alive);
  cache.evict();
  EXPECT_FALSE(fs::exists(orphan));
  EXPECT_TRUE(fs::exists(alive));  // another thread of this process may still be filling it
}

TEST(FrameCache, EvictionDropsTheLeastRecentlyUsedButNeverOneInUse) {
  const fs::path dir = test::fresh_temp_dir("fc_evict");
  std::uint64_t entry_bytes = 0;
  {
    const FrameCache probe(test::fresh_temp_dir("fc_evict_probe"), 1u << 30);
    fill(probe, "probe", three_frames(1));
    for (const auto& e : fs::directory_iterator(probe.entry_dir("probe")))
      entry_bytes += e.file_size();
  }
  // Room for two entries of this size (noise images: every entry's files are the same size
  // within a few bytes).
  const FrameCache cache(dir, entry_bytes * 2 + entry_bytes / 2);
  const auto used_at = [&](const std::string& key, int seconds_ago) {
    fs::last_write_time(cache.entry_dir(key),
                        fs::file_time_type::clock::now() - std::chrono::seconds(seconds_ago));
  };
  fill(cache, "a", three_frames(1));
  fill(cache, "b", three_frames(2));
  fill(cache, "c", three_frames(3));
  used_at("a", 300);
  used_at("b", 200);
  used_at("c", 100);
  std::string warning;
  const auto reading_a = cache.find("a", &warning);  // a is now the most recently used
  ASSERT_NE(reading_a, nullptr) << warning;
  EXPECT_EQ(cache.evict(), 1u);
  EXPECT_TRUE(fs::exists(cache.entry_dir("a")));
  EXPECT_FALSE(fs::exists(cache.entry_dir("b")));
  EXPECT_TRUE(fs::exists(cache.entry_dir("c")));

  // With room for none, everything goes but the entry being read.
  const FrameCache tiny(dir, 0);
  EXPECT_EQ(tiny.evict(), 1u);
  EXPECT_TRUE(fs::exists(cache.entry_dir("a")));
  EXPECT_FALSE(fs::exists(cache.entry_dir("c")));
  expect_same(reading_a->frame(0), three_frames(1)[0]);
}

// ---------------------------------------------------------------------------
// The key

// What a run hands frame_cache_key(): a scenario, a small scene, frame truths and stamps.
struct KeyInputs {
  KeyInputs() : sc(load_scenario(fs::path(DRIFTLAB_SOURCE_DIR) / "scenarios/river_crossing.yaml")) {
    sim::Mesh m;
    m.name = "quad";
    m.vertices = {{0, 0, 0, 0, 0, -1, 0, 0}, {1, 0, 0, 0, 0, -1, 1, 0}, {0, 1, 0, 0, 0, -1, 0, 1}};
    m.indices = {0, 1, 2};
    m.material.texture = 0;
    scene.meshes.push_back(m);
    scene.textures.push_back({"bark", 2, 2, {10, 20, 30, 40}, {}});
    for (int k = 0; k < 3; ++k) {
      FrameTruth f;
      f.t_s = k / 13.0;
      f.T_W_B = SE3(Quat::Identity(), Vec3(0.1 * k, 0, 0));
      truth.push_back(f);
      stamps.push_back({k * 76'923'077LL, k * 76'923'077LL, false});
    }
  }
  std::string key() const {
    return frame_cache_key(renderer_identity(gl), sc, scene, truth, stamps);
  }
  Scenario sc;
  sim::SceneGeometry scene;
  std::vector<FrameTruth> truth;
  std::vector<sim::SampleTime> stamps;
  std::string gl = "OpenGL 4.5 (Core Profile) Mesa 22.3.6 / llvmpipe (LLVM 15.0.6, 256 bits)";
};

TEST(FrameCacheKey, NamesEverythingThatDecidesTheFrames) {
  const std::string base = KeyInputs().key();
  EXPECT_EQ(KeyInputs().key(), base);
  EXPECT_NE(base.find(renderer_code_identity()), std::string::npos);
  const std::vector<std::pair<std::string, std::function<void(KeyInputs&)>>> changes = {
      {"the GL driver", [](KeyInputs& k) { k.gl = "OpenGL 4.5 (Core Profile) Mesa 23.0.0"; }},
      {"the seed", [](KeyInputs& k) { k.sc.seed += 1; }},
      {"a render option", [](KeyInputs& k) { k.sc.render.reflections = false; }},
      {"a camera option", [](KeyInputs& k) { k.sc.sensors.camera.vignetting_strength += 0.01; }},
      {"the wind", [](KeyInputs& k) { k.sc.water.wind.speed_mps += 0.5; }},
      {"the frames asked for", [](KeyInputs& k) { k.sc.pipeline.max_frames = 7; }},
      {"a texture pixel", [](KeyInputs& k) { k.scene.textures[0].pixels[3] ^= 1; }},
      {"a texture's alpha (drawn alpha-tested)",
       [](KeyInputs& k) {
         k.scene.textures[0].alpha = {255, 255, 0, 255};
       }},
      {"a vertex", [](KeyInputs& k) { k.scene.meshes[0].vertices[1].x = 1.0001f; }},
      {"the lighting", [](KeyInputs& k) { k.scene.lighting.sun = true; }},
      {"the sky's gradient", [](KeyInputs& k) { k.scene.lighting.sky_zenith_ratio = 3.f; }},
      {"the sky's shoulder", [](KeyInputs& k) { k.scene.lighting.sky_knee = 0.8f; }},
      {"the clouds' contrast", [](KeyInputs& k) { k.scene.lighting.cloud_contrast = 0.1f; }},
      {"a cloud pixel",
       [](KeyInputs& k) {
         k.scene.sky_clouds = {"sky_clouds", 1, 1, {128}, {}};
       }},
      {"a pose by 1e-12 m",
       [](KeyInputs& k) { k.truth[1].T_W_B = SE3(Quat::Identity(), Vec3(0.1 + 1e-12, 0, 0)); }},
      {"a dropped frame", [](KeyInputs& k) { k.stamps[2].dropped = true; }},
      {"a stamp", [](KeyInputs& k) { k.stamps[2].t_stamp_ns += 1; }},
  };
  for (const auto& [what, change] : changes) {
    KeyInputs k;
    change(k);
    EXPECT_NE(k.key(), base) << what;
  }
}

TEST(FrameCacheKey, LeavesOutWhatOnlyTheVosFiltersAndEvaluationSee) {
  const std::string base = KeyInputs().key();
  const std::vector<std::pair<std::string, std::function<void(KeyInputs&)>>> changes = {
      {"the VOs", [](KeyInputs& k) { k.sc.pipeline.vo = {"dense"}; }},
      {"a VO option", [](KeyInputs& k) { k.sc.pipeline.sparse.ransac_iterations = 8; }},
      {"the filters", [](KeyInputs& k) { k.sc.pipeline.fusion = {}; }},
      {"the threads", [](KeyInputs& k) { k.sc.pipeline.threads = 1; }},
      {"the evaluation", [](KeyInputs& k) { k.sc.eval.section_length_m = 3; }},
      {"the name", [](KeyInputs& k) { k.sc.name = "another"; }},
  };
  for (const auto& [what, change] : changes) {
    KeyInputs k;
    change(k);
    EXPECT_EQ(k.key(), base) << what;
  }
  // Nor are the VOs' and the evaluation's option names (not even at their defaults), so that a
  // VO option added or a VO default changed, code outside the renderer's identity, keeps the
  // cached frames; max_frames is the one pipeline line.
  for (const char* name : {"ransac_iterations", "sgbm_mode", "fusion", "section_length_m"})
    EXPECT_EQ(base.find(name), std::string::npos) << name;
  EXPECT_NE(base.find("\npipeline:\n  max_frames: 0\n"), std::string::npos) << base;
  EXPECT_NE(base.find("\nseed: "), std::string::npos);
  EXPECT_NE(base.find("\nsensors:\n"), std::string::npos);
}

}  // namespace
}  // namespace driftlab::pipeline
