#include "vo/dense/disparity.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <opencv2/core/hal/intrin.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.hpp"
#include "vo/dense/box_filter.hpp"
#include "vo/dense/pieces.hpp"

namespace driftlab::vo::dense {

namespace {

// cv::boxFilter's sums with zeros beyond the image (box_filter_rows), in pieces of rows. The
// running column sums start afresh in each piece; the pieces are the same at any thread count.
void box_filter(const cv::Mat& src, cv::Mat* dst, int window, bool normalize) {
  dst->create(src.size(), CV_32FC1);
  for_each_piece(static_cast<std::size_t>(src.rows), kRowPieces,
                 [&](std::size_t, std::size_t v0, std::size_t v1) {
                   box_filter_rows(src, static_cast<int>(v0), static_cast<int>(v1), window,
                                   normalize, dst);
                 });
}

}  // namespace

int searched_disparities(const DisparityOptions& options) {
  const int per_level = (options.num_disparities + options.downsample - 1) / options.downsample;
  return (per_level + 15) / 16 * 16;
}

DisparityEstimator::DisparityEstimator(const DisparityOptions& options, Lanes lanes)
    : options_(options), simd_(lanes == Lanes::kSimd) {
  if (options.downsample < 1)
    throw InternalError("DisparityEstimator: downsample must be at least 1");
  sgbm_ = cv::StereoSGBM::create(
      /*minDisparity=*/0, searched_disparities(options), options.block_size, options.p1, options.p2,
      options.disp12_max_diff, options.pre_filter_cap, options.uniqueness_ratio,
      options.speckle_window, options.speckle_range, options.mode);
}

void DisparityEstimator::match(const cv::Mat& left8, const cv::Mat& right8, cv::Mat* disparity) {
  const int f = options_.downsample;
  const bool shrink = f > 1;
  if (shrink) {
    const cv::Size small(left8.cols / f, left8.rows / f);
    cv::resize(left8, small_left_, small, 0.0, 0.0, cv::INTER_AREA);
    cv::resize(right8, small_right_, small, 0.0, 0.0, cv::INTER_AREA);
  }
  sgbm_->compute(shrink ? small_left_ : left8, shrink ? small_right_ : right8, raw_);
  // SGBM writes 16 x disparity, and (minDisparity - 1) * 16 = -16 where it found none. A shrunk
  // pair's disparity is in its own pixels: scale it by the width ratio.
  const float scale = static_cast<float>(left8.cols) / static_cast<float>(raw_.cols) / 16.0f;
  cv::Mat& out = shrink ? small_disparity_ : *disparity;
  out.create(raw_.size(), CV_32FC1);
  for_each_row(raw_.rows, [&](int v) {
    const std::int16_t* r = raw_.ptr<std::int16_t>(v);
    float* d = out.ptr<float>(v);
    for (int u = 0; u < raw_.cols; ++u) d[u] = r[u] > 0 ? r[u] * scale : 0.0f;
  });
  if (shrink) cv::resize(out, *disparity, left8.size(), 0.0, 0.0, cv::INTER_NEAREST);
}

void DisparityEstimator::compute(const cv::Mat& left8, const cv::Mat& right8,
                                 const cv::Mat& left_f32, cv::Mat* disparity) {
  match(left8, right8, disparity);
  if (options_.refine_iterations <= 0) return;
  right8.convertTo(right_f32_, CV_32F);
  // Central differences along the row, as the photometric Jacobians use.
  cv::Sobel(right_f32_, right_dx_, CV_32F, 1, 0, 1, 0.5, 0.0, cv::BORDER_REPLICATE);
  disparity->copyTo(sgbm_disparity_);
  refine(left_f32, disparity);
}

namespace {

// The right image at x = u - d for the pixels u of a row with disparity d: the residual
// e = L(u) - R(x) and the slope g = dR/dx(x), both linear in x; 0 for both without a disparity
// or outside the right image (x is then clamped to 0 to read something).
struct RowSampler {
  const float* L;
  const float* R;
  const float* G;
  int W;
  void operator()(int u, float d, float* e, float* g) const {
    const float x = static_cast<float>(u) - d;
    const bool ok = d > 0.0f && x >= 0.0f && x < static_cast<float>(W - 1);
    const float xs = ok ? x : 0.0f;
    const int x0 = static_cast<int>(xs);
    const float a = xs - static_cast<float>(x0), b = 1.0f - a;
    const float ev = L[u] - (b * R[x0] + a * R[x0 + 1]);
    const float gv = b * G[x0] + a * G[x0 + 1];
    *e = ok ? ev : 0.0f;
    *g = ok ? gv : 0.0f;
  }
};

}  // namespace

#if CV_SIMD128
namespace {

// RowSampler on the four pixels from u (OpenCV's universal intrinsics): the same operations in
// the same order, lane by lane, so the same bytes.
struct RowSampler4 {
  RowSampler s;
  void operator()(int u, const float* d, cv::v_float32x4* e, cv::v_float32x4* g) const {
    const cv::v_float32x4 zero = cv::v_setzero_f32(), one = cv::v_setall_f32(1.0f);
    const cv::v_float32x4 vd = cv::v_load(d + u);
    const cv::v_float32x4 x = cv::v_cvt_f32(cv::v_int32x4(u, u + 1, u + 2, u + 3)) - vd;
    const cv::v_float32x4 ok =
        (vd > zero) & (x >= zero) & (x < cv::v_setall_f32(static_cast<float>(s.W - 1)));
    const cv::v_float32x4 xs = cv::v_select(ok, x, zero);
    const cv::v_int32x4 x0 = cv::v_trunc(xs);
    const cv::v_float32x4 a = xs - cv::v_cvt_f32(x0), b = one - a;
    const cv::v_float32x4 ev =
        cv::v_load(s.L + u) - (b * cv::v_lut(s.R, x0) + a * cv::v_lut(s.R + 1, x0));
    const cv::v_float32x4 gv = b * cv::v_lut(s.G, x0) + a * cv::v_lut(s.G + 1, x0);
    *e = cv::v_select(ok, ev, zero);
    *g = cv::v_select(ok, gv, zero);
  }
};

}  // namespace
#endif

void DisparityEstimator::linearise_row(const cv::Mat& left_f32, const cv::Mat& disparity, int v,
                                       bool slopes) {
  const RowSampler sample{left_f32.ptr<float>(v), right_f32_.ptr<float>(v), right_dx_.ptr<float>(v),
                          disparity.cols};
  const float* d = disparity.ptr<float>(v);
  float* ge = ge_.ptr<float>(v);
  float* gg = gg_.ptr<float>(v);
  float* ee = ee_.ptr<float>(v);
  int u = 0;
#if CV_SIMD128
  const RowSampler4 sample4{sample};
  for (; simd_ && u + 4 <= disparity.cols; u += 4) {
    cv::v_float32x4 e, g;
    sample4(u, d, &e, &g);
    if (slopes) {
      cv::v_store(ge + u, g * e);
      cv::v_store(gg + u, g * g);
    } else {
      cv::v_store(ee + u, e * e);
    }
  }
#endif
  for (; u < disparity.cols; ++u) {
    float e, g;
    sample(u, d[u], &e, &g);
    if (slopes) {
      ge[u] = g * e;
      gg[u] = g * g;
    } else {
      ee[u] = e * e;
    }
  }
}

namespace {

// One Lucas-Kanade step on a row of disparities d from the window sums of g e and g^2: d += the
// clamped correction where d > 0 and the window has gradient energy above min_energy.
void step_row(const float* sge, const float* sgg, float min_energy, int W, bool simd, float* d) {
  static_cast<void>(simd);  // unused without SIMD
  int u = 0;
#if CV_SIMD128
  const cv::v_float32x4 zero = cv::v_setzero_f32(), minus_one = cv::v_setall_f32(-1.0f);
  const cv::v_float32x4 lo = cv::v_setall_f32(-0.5f), hi = cv::v_setall_f32(0.5f);
  const cv::v_float32x4 min_e = cv::v_setall_f32(min_energy);
  for (; simd && u + 4 <= W; u += 4) {
    const cv::v_float32x4 vd = cv::v_load(d + u), vgg = cv::v_load(sgg + u);
    const cv::v_float32x4 ratio = (minus_one * cv::v_load(sge + u)) / vgg;
    const cv::v_float32x4 step = cv::v_min(cv::v_max(ratio, lo), hi);
    cv::v_store(d + u, cv::v_select((vd > zero) & (vgg > min_e), vd + step, vd));
  }
#endif
  for (; u < W; ++u) {
    if (!(d[u] > 0.0f) || !(sgg[u] > min_energy)) continue;
    d[u] += std::clamp(-sge[u] / sgg[u], -0.5f, 0.5f);
  }
}

}  // namespace

void DisparityEstimator::refine(const cv::Mat& left_f32, cv::Mat* disparity) {
  const int W = disparity->cols, H = disparity->rows;
  ge_.create(H, W, CV_32FC1);
  gg_.create(H, W, CV_32FC1);
  ee_.create(H, W, CV_32FC1);
  // Windows with less gradient energy than 1 grey/px on every pixel keep SGBM's value.
  const float min_energy = static_cast<float>(options_.refine_window * options_.refine_window);
  const int iterations = options_.refine_iterations;
  for_each_row(H, [&](int v) { linearise_row(left_f32, *disparity, v, /*slopes=*/true); });
  for (int it = 0; it < iterations; ++it) {
    box_filter(ge_, &ge_sum_, options_.refine_window, false);
    box_filter(gg_, &gg_sum_, options_.refine_window, false);
    // A row's step reads its own sums only: each row is stepped, then linearised at its new
    // disparity for the next iteration (slopes) or the acceptance below (residuals).
    for_each_row(H, [&](int v) {
      step_row(ge_sum_.ptr<float>(v), gg_sum_.ptr<float>(v), min_energy, W, simd_,
               disparity->ptr<float>(v));
      linearise_row(left_f32, *disparity, v, /*slopes=*/it + 1 < iterations);
    });
  }
  // A match is kept when the refinement moved it little and the refined disparity brings the
  // window's right-image pixels onto the left ones (RMS residual within max_residual).
  box_filter(ee_, &ee_mean_, options_.refine_window, true);
  const float max_change = static_cast<float>(options_.refine_max_change);
  const float max_ee =
      static_cast<float>(options_.refine_max_residual * options_.refine_max_residual);
  for_each_row(H, [&](int v) {
    float* d = disparity->ptr<float>(v);
    const float* d0 = sgbm_disparity_.ptr<float>(v);
    const float* mean_ee = ee_mean_.ptr<float>(v);
    for (int u = 0; u < W; ++u)
      if (d[u] > 0.0f && (std::abs(d[u] - d0[u]) > max_change || !(mean_ee[u] <= max_ee)))
        d[u] = 0.0f;
  });
}

}  // namespace driftlab::vo::dense
