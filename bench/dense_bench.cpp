// Dense VO (vo/dense): wall time per stereo frame at the river paper's 640x480, single-threaded
// (cv::setNumThreads(1)), with SGBM and the alignment timed separately; and a side-by-side with
// OpenCV's cv::rgbd::RgbdOdometry (Steinbruecker et al. 2011, the river paper's reference [27],
// from Debian's OpenCV contrib) on the same frames and the same depth. Targets: alignment under
// 15 ms per frame and more accurate than RgbdOdometry (the dense VO issue); the whole VO at most
// 20 ms per frame (the speed issue).
//
// Sequence: tests/vo's exactly rendered river bank, 0.5 m and 1 deg of yaw per frame. Frames are
// fed back and forth (0 1 2 ... 7 6 ... 1 0 1 ...), so every call tracks a real motion, whose
// ground truth gives the error counters (t_err_mm, r_err_deg: mean per frame; *_max: worst).
// Rendering, and for the side-by-side the depth maps, are computed once, outside the timing.
//
// Benchmarks:
//   BM_DenseVo           the whole VO (extended method, the defaults): stage counters
//                        sgbm_ms (SGBM + disparity refinement), alignment_ms (pyramid +
//                        reference points and Jacobians + Levenberg-Marquardt), and their parts
//   BM_DenseVoPaper      the same, river paper's plain method
//   BM_DenseVo1024/threads:N/sgbm:M
//                        BM_DenseVo through the river scenarios' Bumblebee2 (1024x768) with N
//                        threads in OpenCV's pool, M = 1: sgbm_mode sgbm (the default before
//                        3way); one_core_ms adds the
//                        stages (the wall overlaps two of them: with N = 1 it is the work of a
//                        frame on one core)
//   BM_Sgbm              cv::StereoSGBM alone on the full pair (the paper's method)
//   BM_SgbmShrunk        cv::StereoSGBM alone on the pair shrunk by sgbm_downsample (default 2)
//   BM_SgbmRefined       the default: SGBM on the shrunk pair + our Lucas-Kanade refinement
//   BM_DenseAlignment    the alignment alone, on precomputed depth (the same depth maps as below)
//   BM_RgbdOdometry      cv::rgbd::RgbdOdometry on the same frames and depth: per new frame,
//                        its frame cache (pyramids, gradients, clouds) and compute() against the
//                        previous frame's cache; arg 0: its defaults except the depth range and
//                        the largest motion it accepts (its 4 m / 0.15 m defaults reject this
//                        scene), arg 1: also a depth tolerance for SGBM depths (maxDepthDiff)
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/rgbd.hpp>

#include "core/rng.hpp"
#include "core/stopwatch.hpp"
#include "tests/vo/vo_test_sequences.hpp"
#include "vo/dense/dense_vo.hpp"
#include "vo/dense/disparity.hpp"
#include "vo/dense/photometric.hpp"

namespace {

using namespace driftlab;
using namespace driftlab::vo;
constexpr std::size_t kFrames = 8;
constexpr double kDeg = std::numbers::pi / 180.0;

const test::Sequence& sequence() {
  static const test::Sequence s =
      test::make_sequence(test::river_bank_scene_640(), test::rig_640x480(),
                          test::turning_poses(static_cast<int>(kFrames), 0.5, 1.0));
  return s;
}

// The same bank and motion through the river paper's Bumblebee2 (1024x768, 817 px).
const test::Sequence& sequence_1024() {
  static const test::Sequence s =
      test::make_sequence(test::river_bank_scene_640(), test::bumblebee2_rig(),
                          test::turning_poses(static_cast<int>(kFrames), 0.5, 1.0));
  return s;
}

// 0 1 2 ... 7 6 5 ... 1 0 1 ...
std::size_t ping_pong(std::size_t i) {
  const std::size_t period = 2 * (kFrames - 1);
  const std::size_t k = i % period;
  return k < kFrames ? k : period - k;
}

SE3 true_motion(const test::Sequence& s, std::size_t from, std::size_t to) {
  return s.T_scene_cam[from].inverse() * s.T_scene_cam[to];
}

// Accumulates per-frame errors against the ground truth into counters.
struct ErrorCounters {
  double t_sum = 0, r_sum = 0, t_max = 0, r_max = 0;
  int n = 0, invalid = 0;
  const test::Sequence& seq;
  void add(bool valid, const SE3& T_prev_curr, std::size_t from, std::size_t to) {
    if (!valid) {
      ++invalid;
      return;
    }
    const auto e = test::motion_error(T_prev_curr, true_motion(seq, from, to));
    t_sum += e.translation_m;
    r_sum += e.rotation_rad;
    t_max = std::max(t_max, e.translation_m);
    r_max = std::max(r_max, e.rotation_rad);
    ++n;
  }
  void report(benchmark::State& state) const {
    state.counters["t_err_mm"] = n > 0 ? 1e3 * t_sum / n : 0.0;
    state.counters["r_err_deg"] = n > 0 ? r_sum / n / kDeg : 0.0;
    state.counters["t_err_max_mm"] = 1e3 * t_max;
    state.counters["r_err_max_deg"] = r_max / kDeg;
    state.counters["invalid"] = invalid;
  }
};

void run_vo(benchmark::State& state, const DenseVoOptions& options,
            const test::Sequence& seq = sequence(), int threads = 1) {
  cv::setNumThreads(threads);
  DenseStereoOdometry vo(seq.rig, options, RngStreams(1).stream("vo.dense"));
  vo.process(seq.frames[0]);
  std::size_t i = 1;
  double pyramid = 0, sgbm = 0, reference = 0, lm = 0, points = 0;
  ErrorCounters errors{.seq = seq};
  for (auto _ : state) {
    const std::size_t from = ping_pong(i - 1), to = ping_pong(i);
    ++i;
    const VoResult r = vo.process(seq.frames[to]);
    benchmark::DoNotOptimize(r);
    const DenseFrameStats& s = vo.last_stats();
    pyramid += s.pyramid_ms;
    sgbm += s.sgbm_ms;
    reference += s.reference_ms;
    lm += s.align_ms;
    points += s.reference_points;
    errors.add(r.valid, r.T_prev_curr, from, to);
  }
  const auto avg = benchmark::Counter::kAvgIterations;
  state.counters["sgbm_ms"] = benchmark::Counter(sgbm, avg);
  state.counters["alignment_ms"] = benchmark::Counter(pyramid + reference + lm, avg);
  state.counters["pyramid_ms"] = benchmark::Counter(pyramid, avg);
  state.counters["reference_ms"] = benchmark::Counter(reference, avg);
  state.counters["lm_ms"] = benchmark::Counter(lm, avg);
  state.counters["ref_points"] = benchmark::Counter(points, avg);
  // The work of a frame on one core: the stages' times added (two of them overlap in the wall).
  state.counters["one_core_ms"] = benchmark::Counter(pyramid + sgbm + reference + lm, avg);
  errors.report(state);
  state.SetLabel(std::to_string(seq.rig.camera.width) + "x" +
                 std::to_string(seq.rig.camera.height) + ", " + std::to_string(threads) +
                 (threads == 1 ? " thread" : " threads"));
  cv::setNumThreads(1);
}

void BM_DenseVo(benchmark::State& state) { run_vo(state, DenseVoOptions{}); }
BENCHMARK(BM_DenseVo)->Unit(benchmark::kMillisecond);

void BM_DenseVoPaper(benchmark::State& state) { run_vo(state, DenseVoOptions::paper()); }
BENCHMARK(BM_DenseVoPaper)->Unit(benchmark::kMillisecond);

// The whole VO at the Bumblebee2's 1024x768, as in the river scenarios, with OpenCV's pool (the
// VO's loops run on it) at 1 to 16 threads; the defaults, and with sgbm_mode sgbm.
void BM_DenseVo1024(benchmark::State& state) {
  DenseVoOptions o;
  if (state.range(1) == 1) o.sgbm_mode = DenseSgbmMode::kSgbm;
  run_vo(state, o, sequence_1024(), static_cast<int>(state.range(0)));
}
BENCHMARK(BM_DenseVo1024)
    ->ArgsProduct({{1, 2, 4, 8, 16}, {0, 1}})
    ->ArgNames({"threads", "sgbm"})
    ->Unit(benchmark::kMillisecond);

void run_disparity(benchmark::State& state, const dense::DisparityOptions& options) {
  cv::setNumThreads(1);
  const test::Sequence& seq = sequence();
  dense::DisparityEstimator est(options);
  cv::Mat left_f, disparity;
  std::size_t i = 0;
  for (auto _ : state) {
    const StereoFrame& f = seq.frames[ping_pong(i++)];
    f.left.convertTo(left_f, CV_32F);
    est.compute(f.left, f.right, left_f, &disparity);
    benchmark::DoNotOptimize(disparity.data);
  }
  state.SetLabel("640x480");
}
// SGBM on the full pair, no refinement (the paper's method)
void BM_Sgbm(benchmark::State& state) {
  run_disparity(state, dense::disparity_options(DenseVoOptions::paper()));
}
BENCHMARK(BM_Sgbm)->Unit(benchmark::kMillisecond);
// SGBM on the pair shrunk by the default sgbm_downsample, no refinement
void BM_SgbmShrunk(benchmark::State& state) {
  dense::DisparityOptions o = dense::disparity_options(DenseVoOptions{});
  o.refine_iterations = 0;
  run_disparity(state, o);
}
BENCHMARK(BM_SgbmShrunk)->Unit(benchmark::kMillisecond);
// The default: SGBM on the shrunk pair and the refinement at full resolution
void BM_SgbmRefined(benchmark::State& state) {
  run_disparity(state, dense::disparity_options(DenseVoOptions{}));
}
BENCHMARK(BM_SgbmRefined)->Unit(benchmark::kMillisecond);

// The refined disparity of every frame, and the depth (CV_32F [m], NaN: none) RgbdOdometry takes.
struct Depths {
  std::vector<cv::Mat> disparity, depth;
};
const Depths& depths() {
  static const Depths d = [] {
    cv::setNumThreads(1);
    const test::Sequence& seq = sequence();
    dense::DisparityEstimator est(dense::disparity_options(DenseVoOptions{}));
    const double min_d = DenseVoOptions{}.min_disparity_px;
    const double fB = seq.rig.camera.fx * seq.rig.baseline_m;
    Depths out;
    for (const StereoFrame& f : seq.frames) {
      cv::Mat left_f, disparity;
      f.left.convertTo(left_f, CV_32F);
      est.compute(f.left, f.right, left_f, &disparity);
      cv::Mat depth(disparity.size(), CV_32FC1);
      for (int v = 0; v < depth.rows; ++v)
        for (int u = 0; u < depth.cols; ++u) {
          const float dd = disparity.at<float>(v, u);
          depth.at<float>(v, u) =
              dd >= min_d ? static_cast<float>(fB / dd) : std::numeric_limits<float>::quiet_NaN();
        }
      out.disparity.push_back(disparity);
      out.depth.push_back(depth);
    }
    return out;
  }();
  return d;
}

void BM_DenseAlignment(benchmark::State& state) {
  cv::setNumThreads(1);
  const test::Sequence& seq = sequence();
  const Depths& dep = depths();
  const DenseVoOptions o;
  dense::Pyramid pyr[2];
  dense::Reference ref[2];
  for (auto& p : pyr) p.configure(seq.rig.camera, o.pyramid_scales);
  const dense::RefSelection sel = dense::ref_selection(o);
  const dense::AlignOptions ao = dense::align_options(o);
  dense::Aligner aligner;
  const double fB = seq.rig.camera.fx * seq.rig.baseline_m;
  pyr[0].build(seq.frames[0].left, o.pyramid_blur_sigma_px);
  dense::build_reference(pyr[0], dep.disparity[0], fB, sel, &ref[0]);
  std::size_t i = 1;
  ErrorCounters errors{.seq = seq};
  SE3 velocity;  // constant-velocity guess, as the VO does
  for (auto _ : state) {
    const std::size_t from = ping_pong(i - 1), to = ping_pong(i);
    dense::Pyramid& cur = pyr[i % 2];
    dense::Reference& cur_ref = ref[i % 2];
    const dense::Reference& prev_ref = ref[(i + 1) % 2];
    ++i;
    cur.build(seq.frames[to].left, o.pyramid_blur_sigma_px);
    dense::build_reference(cur, dep.disparity[to], fB, sel, &cur_ref);
    SE3 T = velocity;
    const dense::AlignSummary s = aligner.align(prev_ref, cur, ao, &T);
    velocity = s.ok ? T : SE3();
    errors.add(s.ok, T.inverse(), from, to);
  }
  errors.report(state);
  state.SetLabel("640x480");
}
BENCHMARK(BM_DenseAlignment)->Unit(benchmark::kMillisecond);

void BM_RgbdOdometry(benchmark::State& state) {
  cv::setNumThreads(1);
  const test::Sequence& seq = sequence();
  const Depths& dep = depths();
  const PinholeCamera& c = seq.rig.camera;
  const cv::Mat K = (cv::Mat_<float>(3, 3) << c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1);
  cv::Ptr<cv::rgbd::RgbdOdometry> odo;
  if (state.range(0) == 0) {
    odo = cv::rgbd::RgbdOdometry::create(K, /*minDepth=*/0.1f, /*maxDepth=*/100.0f);
  } else {
    // SGBM depths at 10-40 m are uncertain by metres: 3 m was the best of 0.07 (default), 0.3,
    // 1 and 3 m. Iteration counts (also 40/20/3/1, 10/10/20/40) and using all pixels instead of
    // its 7% sample changed neither the errors nor the time by more than a few percent.
    odo = cv::rgbd::RgbdOdometry::create(K, 0.1f, 100.0f, /*maxDepthDiff=*/3.0f);
  }
  odo->setMaxTranslation(1.0);
  odo->setMaxRotation(15.0);
  auto frame = [&](std::size_t k) {
    return cv::rgbd::OdometryFrame::create(seq.frames[k].left, dep.depth[k]);
  };
  cv::Ptr<cv::rgbd::OdometryFrame> prev = frame(0);
  odo->prepareFrameCache(prev, cv::rgbd::OdometryFrame::CACHE_ALL);
  std::size_t i = 1;
  ErrorCounters errors{.seq = seq};
  double cache_ms = 0, compute_ms = 0;
  for (auto _ : state) {
    const std::size_t from = ping_pong(i - 1), to = ping_pong(i);
    ++i;
    auto t = SteadyClock::now();
    cv::Ptr<cv::rgbd::OdometryFrame> cur = frame(to);
    odo->prepareFrameCache(cur, cv::rgbd::OdometryFrame::CACHE_ALL);
    cache_ms += ms_since(t);
    t = SteadyClock::now();
    cv::Mat Rt;
    const bool ok = odo->compute(prev, cur, Rt);
    compute_ms += ms_since(t);
    // Rt maps source (previous) points into the destination (current) frame: T_curr_prev.
    SE3 T_prev_curr;
    if (ok) {
      Mat4 M;
      for (int r = 0; r < 4; ++r)
        for (int k = 0; k < 4; ++k) M(r, k) = Rt.at<double>(r, k);
      T_prev_curr = SE3(M).inverse();
    }
    errors.add(ok, T_prev_curr, from, to);
    prev = cur;
  }
  const auto avg = benchmark::Counter::kAvgIterations;
  state.counters["cache_ms"] = benchmark::Counter(cache_ms, avg);
  state.counters["compute_ms"] = benchmark::Counter(compute_ms, avg);
  errors.report(state);
  state.SetLabel(state.range(0) == 0 ? "640x480, defaults" : "640x480, maxDepthDiff 3 m");
}
BENCHMARK(BM_RgbdOdometry)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
