#include "vo/dense/disparity.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <opencv2/imgproc.hpp>

#include "core/error.hpp"
#include "vo/dense/pieces.hpp"

namespace driftlab::vo::dense {

namespace {

// cv::boxFilter with zeros beyond the image, in pieces of rows. Its running column sums start
// afresh in each piece; the pieces are the same at any thread count.
void box_filter(const cv::Mat& src, cv::Mat* dst, int window, bool normalize) {
  filter_in_row_pieces(src, dst, CV_32FC1, [&](const cv::Mat& in, cv::Mat& out) {
    cv::boxFilter(in, out, CV_32F, cv::Size(window, window), cv::Point(-1, -1), normalize,
                  cv::BORDER_CONSTANT);
  });
}

}  // namespace

int searched_disparities(const DisparityOptions& options) {
  const int per_level = (options.num_disparities + options.downsample - 1) / options.downsample;
  return (per_level + 15) / 16 * 16;
}

DisparityEstimator::DisparityEstimator(const DisparityOptions& options) : options_(options) {
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

void DisparityEstimator::linearise(const cv::Mat& left_f32, const cv::Mat& disparity) {
  const int W = disparity.cols, H = disparity.rows;
  ge_.create(H, W, CV_32FC1);
  gg_.create(H, W, CV_32FC1);
  ee_.create(H, W, CV_32FC1);
  for_each_row(H, [&](int v) {
    const float* d = disparity.ptr<float>(v);
    const float* L = left_f32.ptr<float>(v);
    const float* R = right_f32_.ptr<float>(v);
    const float* G = right_dx_.ptr<float>(v);
    float* ge = ge_.ptr<float>(v);
    float* gg = gg_.ptr<float>(v);
    float* ee = ee_.ptr<float>(v);
    for (int u = 0; u < W; ++u) {
      const float x = static_cast<float>(u) - d[u];
      if (!(d[u] > 0.0f) || !(x >= 0.0f) || !(x < static_cast<float>(W - 1))) {
        ge[u] = gg[u] = ee[u] = 0.0f;
        continue;
      }
      const int x0 = static_cast<int>(x);
      const float a = x - static_cast<float>(x0);
      const float rw = (1.0f - a) * R[x0] + a * R[x0 + 1];
      const float g = (1.0f - a) * G[x0] + a * G[x0 + 1];
      const float e = L[u] - rw;
      ge[u] = g * e;
      gg[u] = g * g;
      ee[u] = e * e;
    }
  });
}

void DisparityEstimator::refine(const cv::Mat& left_f32, cv::Mat* disparity) {
  const int W = disparity->cols, H = disparity->rows;
  // Windows with less gradient energy than 1 grey/px on every pixel keep SGBM's value.
  const float min_energy = static_cast<float>(options_.refine_window * options_.refine_window);
  for (int it = 0; it < options_.refine_iterations; ++it) {
    linearise(left_f32, *disparity);
    box_filter(ge_, &ge_sum_, options_.refine_window, false);
    box_filter(gg_, &gg_sum_, options_.refine_window, false);
    for_each_row(H, [&](int v) {
      float* d = disparity->ptr<float>(v);
      const float* sge = ge_sum_.ptr<float>(v);
      const float* sgg = gg_sum_.ptr<float>(v);
      for (int u = 0; u < W; ++u) {
        if (!(d[u] > 0.0f) || !(sgg[u] > min_energy)) continue;
        d[u] += std::clamp(-sge[u] / sgg[u], -0.5f, 0.5f);
      }
    });
  }
  // A match is kept when the refinement moved it little and the refined disparity brings the
  // window's right-image pixels onto the left ones (RMS residual within max_residual).
  linearise(left_f32, *disparity);
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
