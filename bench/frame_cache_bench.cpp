// The frame cache's storage (docs/design.md, "Frame cache"): what a stereo pair of the paper's
// camera (Bumblebee2, 1024x768, river survey with reflections, breeze and sensor noise) costs to
// keep and to read back, per image, in the cache's form (PNG, deflate level 1, OpenCV) against zstd
// (levels 1 and 3, libzstd) and raw bytes. Counters: bytes per image; the time is per image.
//   build/bench/frame_cache_bench
#include <benchmark/benchmark.h>
#include <xxhash.h>
#include <zstd.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "core/hash.hpp"
#include "core/rotation.hpp"
#include "pipeline/frame_source.hpp"
#include "pipeline/scenario.hpp"
#include "scenes/build_scene.hpp"

namespace {

using namespace driftlab;

// Four left images of the river survey, as the camera delivers them (noise included).
const std::vector<cv::Mat>& frames() {
  static const std::vector<cv::Mat> images = [] {
    pipeline::Scenario sc = pipeline::load_scenario(std::filesystem::path(DRIFTLAB_SOURCE_DIR) /
                                                    "scenarios/river_survey.yaml");
    const sim::SceneGeometry scene = scenes::build_scene(sc.scene, sc.seed, -10, 40);
    std::vector<pipeline::FrameTruth> truth;
    std::vector<sim::SampleTime> stamps;
    for (int k = 0; k < 4; ++k) {
      pipeline::FrameTruth f;
      f.t_s = k / 8.2;
      f.T_W_B = SE3(quat_from_euler_zyx({0.0, 0.0, 0.2 * k}), Vec3(2.0 * k, 4, 0));
      truth.push_back(f);
      stamps.push_back(
          {static_cast<TimeNs>(k) * 121'951'220, static_cast<TimeNs>(k) * 121'951'220, false});
    }
    pipeline::FrameSource source(sc, scene, truth, stamps, 1);
    std::vector<cv::Mat> out;
    while (auto f = source.next()) out.push_back(pipeline::cv_view(f->images.left).clone());
    return out;
  }();
  return images;
}

std::vector<std::uint8_t> png(const cv::Mat& m) {
  std::vector<std::uint8_t> b;
  cv::imencode(".png", m, b, {cv::IMWRITE_PNG_COMPRESSION, 1});
  return b;
}

std::vector<char> zstd(const cv::Mat& m, int level) {
  const std::size_t n = m.total();
  std::vector<char> b(ZSTD_compressBound(n));
  b.resize(ZSTD_compress(b.data(), b.size(), m.data, n, level));
  return b;
}

void BM_PngEncode(benchmark::State& state) {
  frames();  // rendered before the clock starts
  std::size_t i = 0, bytes = 0;
  for (auto _ : state) bytes += png(frames()[i++ % frames().size()]).size();
  state.counters["bytes_per_image"] = static_cast<double>(bytes) / static_cast<double>(i);
}
BENCHMARK(BM_PngEncode)->Unit(benchmark::kMillisecond);

void BM_PngDecode(benchmark::State& state) {
  std::vector<std::vector<std::uint8_t>> encoded;
  for (const auto& m : frames()) encoded.push_back(png(m));
  std::size_t i = 0;
  for (auto _ : state)
    benchmark::DoNotOptimize(cv::imdecode(encoded[i++ % encoded.size()], cv::IMREAD_UNCHANGED));
}
BENCHMARK(BM_PngDecode)->Unit(benchmark::kMillisecond);

void BM_ZstdEncode(benchmark::State& state) {
  std::size_t i = 0, bytes = 0;
  for (auto _ : state)
    bytes += zstd(frames()[i++ % frames().size()], static_cast<int>(state.range(0))).size();
  state.counters["bytes_per_image"] = static_cast<double>(bytes) / static_cast<double>(i);
}
BENCHMARK(BM_ZstdEncode)->Arg(1)->Arg(3)->Unit(benchmark::kMillisecond);

void BM_ZstdDecode(benchmark::State& state) {
  std::vector<std::vector<char>> encoded;
  for (const auto& m : frames()) encoded.push_back(zstd(m, static_cast<int>(state.range(0))));
  cv::Mat out(frames()[0].size(), CV_8UC1);
  std::size_t i = 0;
  for (auto _ : state) {
    const auto& e = encoded[i++ % encoded.size()];
    benchmark::DoNotOptimize(ZSTD_decompress(out.data, out.total(), e.data(), e.size()));
  }
}
BENCHMARK(BM_ZstdDecode)->Arg(1)->Arg(3)->Unit(benchmark::kMillisecond);

// The checksum of a cached image file, which the cache computes twice for every file it
// serves: 0 FNV-1a 64 (what it used before), 1 XXH3-64 (what it uses).
void BM_FileChecksum(benchmark::State& state) {
  std::vector<std::vector<char>> encoded;
  for (const auto& m : frames()) encoded.push_back(zstd(m, 1));
  std::size_t i = 0, bytes = 0;
  for (auto _ : state) {
    const auto& e = encoded[i++ % encoded.size()];
    const std::string_view v(e.data(), e.size());
    benchmark::DoNotOptimize(state.range(0) == 0 ? fnv1a64(v) : XXH3_64bits(v.data(), v.size()));
    bytes += e.size();
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(bytes));
}
BENCHMARK(BM_FileChecksum)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
