#include "vo/dense/disparity.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <opencv2/imgproc.hpp>

#include "core/error.hpp"

namespace driftlab::vo::dense {

DisparityEstimator::DisparityEstimator(const DisparityOptions& options) : options_(options) {
  sgbm_ = cv::StereoSGBM::create(
      /*minDisparity=*/0, options.num_disparities, options.block_size, options.p1, options.p2,
      options.disp12_max_diff, options.pre_filter_cap, options.uniqueness_ratio,
      options.speckle_window, options.speckle_range,
      options.full_dp ? cv::StereoSGBM::MODE_HH : cv::StereoSGBM::MODE_SGBM);
}

void DisparityEstimator::compute(const cv::Mat& left8, const cv::Mat& right8,
                                 const cv::Mat& left_f32, cv::Mat* disparity) {
  sgbm_->compute(left8, right8, raw_);
  // SGBM writes 16 x disparity, and (minDisparity - 1) * 16 = -16 where it found none.
  disparity->create(raw_.size(), CV_32FC1);
  for (int v = 0; v < raw_.rows; ++v) {
    const std::int16_t* r = raw_.ptr<std::int16_t>(v);
    float* d = disparity->ptr<float>(v);
    for (int u = 0; u < raw_.cols; ++u) d[u] = r[u] > 0 ? r[u] * (1.0f / 16.0f) : 0.0f;
  }
  if (options_.refine_iterations <= 0) return;
  right8.convertTo(right_f32_, CV_32F);
  // Central differences along the row, as the photometric Jacobians use.
  cv::Sobel(right_f32_, right_dx_, CV_32F, 1, 0, 1, 0.5, 0.0, cv::BORDER_REPLICATE);
  disparity->copyTo(sgbm_disparity_);
  refine(left_f32, disparity);
}

void DisparityEstimator::refine(const cv::Mat& left_f32, cv::Mat* disparity) {
  const int W = disparity->cols, H = disparity->rows;
  ge_.create(H, W, CV_32FC1);
  gg_.create(H, W, CV_32FC1);
  const cv::Size window(options_.refine_window, options_.refine_window);
  // Windows with less gradient energy than 1 grey/px on every pixel keep SGBM's value.
  const float min_energy = static_cast<float>(options_.refine_window * options_.refine_window);
  for (int it = 0; it < options_.refine_iterations; ++it) {
    for (int v = 0; v < H; ++v) {
      const float* d = disparity->ptr<float>(v);
      const float* L = left_f32.ptr<float>(v);
      const float* R = right_f32_.ptr<float>(v);
      const float* G = right_dx_.ptr<float>(v);
      float* ge = ge_.ptr<float>(v);
      float* gg = gg_.ptr<float>(v);
      for (int u = 0; u < W; ++u) {
        const float x = static_cast<float>(u) - d[u];
        if (!(d[u] > 0.0f) || !(x >= 0.0f) || !(x < static_cast<float>(W - 1))) {
          ge[u] = gg[u] = 0.0f;
          continue;
        }
        const int x0 = static_cast<int>(x);
        const float a = x - static_cast<float>(x0);
        const float rw = (1.0f - a) * R[x0] + a * R[x0 + 1];
        const float g = (1.0f - a) * G[x0] + a * G[x0 + 1];
        const float e = L[u] - rw;
        ge[u] = g * e;
        gg[u] = g * g;
      }
    }
    cv::boxFilter(ge_, ge_sum_, CV_32F, window, cv::Point(-1, -1), false, cv::BORDER_CONSTANT);
    cv::boxFilter(gg_, gg_sum_, CV_32F, window, cv::Point(-1, -1), false, cv::BORDER_CONSTANT);
    for (int v = 0; v < H; ++v) {
      float* d = disparity->ptr<float>(v);
      const float* sge = ge_sum_.ptr<float>(v);
      const float* sgg = gg_sum_.ptr<float>(v);
      for (int u = 0; u < W; ++u) {
        if (!(d[u] > 0.0f) || !(sgg[u] > min_energy)) continue;
        d[u] += std::clamp(-sge[u] / sgg[u], -0.5f, 0.5f);
      }
    }
  }
  const float max_change = static_cast<float>(options_.refine_max_change);
  for (int v = 0; v < H; ++v) {
    float* d = disparity->ptr<float>(v);
    const float* d0 = sgbm_disparity_.ptr<float>(v);
    for (int u = 0; u < W; ++u)
      if (d[u] > 0.0f && std::abs(d[u] - d0[u]) > max_change) d[u] = 0.0f;
  }
}

}  // namespace driftlab::vo::dense
